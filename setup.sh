#!/usr/bin/env bash
# Install what stickslip needs on a Debian machine, if missing: gfortran, LAPACK/BLAS, FFTW3,
# MINPACK, gnuplot for the plots (Debian packages) and fpm (PyPI). Idempotent; prints nothing when all is there.
# Usage: ./setup.sh                 install only
#        ./setup.sh --run           install, build, run the seed example (examples/seed.nml:
#                                   the three methods side by side), draw out/seed/figure3.png
#        ./setup.sh --install DIR   install, then install the library for other build systems
#                                   (doc/library.md): a release build's DIR/lib/libstickslip.a,
#                                   DIR/include/*.mod (the library's modules only),
#                                   DIR/bin/stickslip, DIR/lib/pkgconfig/stickslip.pc and
#                                   DIR/lib/cmake/stickslip/ (find_package(stickslip))
set -euo pipefail
cd "$(dirname "$0")"

pkgs=(gfortran liblapack-dev libfftw3-dev minpack-dev libopenblas0-pthread libopenblas-pthread-dev libopenblas-dev libsuitesparse-dev libarpack2-dev gnuplot-nox cmake pkgconf)
missing=()
for p in "${pkgs[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "setup: installing ${missing[*]}" >&2
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    export DEBIAN_FRONTEND=noninteractive
    log=$(mktemp)
    if ! { $sudo apt-get update -qq && \
           $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
        cat "$log" >&2
        echo "setup: apt-get failed" >&2
        exit 1
    fi
    rm -f "$log"
fi
if ! command -v fpm >/dev/null 2>&1; then
    echo "setup: installing fpm from PyPI" >&2
    if ! python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore fpm \
            >/dev/null 2>&1; then
        python3 -m pip install --disable-pip-version-check fpm >&2 || exit 1
    fi
    hash -r
    if ! command -v fpm >/dev/null 2>&1 && command -v pyenv >/dev/null 2>&1; then
        pyenv rehash || true
        hash -r
    fi
    command -v fpm >/dev/null 2>&1 || { echo "setup: fpm installed but not on PATH (add $(python3 -m site --user-base)/bin)" >&2; exit 1; }
fi

if [ "${1:-}" = "--run" ]; then
    fpm run --profile release -- examples/seed.nml
    gnuplot -e "dir='out/seed'" examples/figure3.gp
    echo "setup: drew out/seed/figure3.png"
fi

if [ "${1:-}" = "--install" ]; then
    prefix=${2:-}
    [ -n "$prefix" ] || { echo "setup: --install needs a directory: ./setup.sh --install DIR" >&2; exit 1; }
    mkdir -p "$prefix"
    prefix=$(cd "$prefix" && pwd)
    log=$(mktemp)
    # --no-prune: every library module, also those no program of this tree uses (stickslip_io)
    if ! fpm install --profile release --no-prune --prefix "$prefix" >"$log" 2>&1; then
        cat "$log" >&2
        echo "setup: fpm install failed" >&2
        exit 1
    fi
    rm -f "$log"
    # fpm installs the .mod file of every module it compiled, the program's (app/) and the
    # benchmarks' (bench/) too: remove those, the library's (src/) stay
    for f in app/*.f90 bench/*.f90; do
        sed -n 's/^[[:space:]]*module[[:space:]]\{1,\}\([A-Za-z0-9_]\{1,\}\)[[:space:]]*$/\1/Ip' "$f"
    done | tr 'A-Z' 'a-z' | while read -r m; do
        [ "$m" = "procedure" ] || rm -f "$prefix/include/$m.mod"
    done
    version=$(sed -n 's/^version[[:space:]]*=[[:space:]]*"\(.*\)"/\1/p' fpm.toml)
    gfortran_major=$(gfortran -dumpversion | cut -d. -f1)
    # the libraries libstickslip.a needs, in link order (fpm.toml [build] link), and OpenMP
    deps=$(sed -n 's/^link[[:space:]]*=[[:space:]]*\[\(.*\)\]/\1/p' fpm.toml | tr -d '" ' | tr ',' ' ')
    mkdir -p "$prefix/lib/pkgconfig" "$prefix/lib/cmake/stickslip"
    libs=""
    for d in $deps; do libs="$libs -l$d"; done
    cat >"$prefix/lib/pkgconfig/stickslip.pc.tmp" <<PC
# stickslip $version, built with gfortran $gfortran_major and OpenMP: its .mod files need
# gfortran $gfortran_major (Fortran modules are compiler-specific).
prefix=\${pcfiledir}/../..
libdir=\${prefix}/lib
includedir=\${prefix}/include
fortran_compiler=GNU
fortran_compiler_major=$gfortran_major

Name: stickslip
Description: Periodic vibration of structures with Coulomb dry friction (Fortran library)
Version: $version
Cflags: -I\${includedir}
Libs: -L\${libdir} -lstickslip$libs -fopenmp
PC
    mv "$prefix/lib/pkgconfig/stickslip.pc.tmp" "$prefix/lib/pkgconfig/stickslip.pc"
    cat >"$prefix/lib/cmake/stickslip/stickslip-config.cmake.tmp" <<CMAKE
# stickslip $version: find_package(stickslip) defines the imported target stickslip::stickslip
# (libstickslip.a, its module directory and the libraries it needs). Relocatable: the paths
# are found from this file's place, <prefix>/lib/cmake/stickslip.
get_filename_component(_stickslip_prefix "\${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)
set(stickslip_VERSION $version)
set(stickslip_Fortran_COMPILER_ID GNU)
set(stickslip_Fortran_COMPILER_MAJOR $gfortran_major)
# the .mod files are read by gfortran $gfortran_major only
if(NOT CMAKE_Fortran_COMPILER_ID STREQUAL "GNU" OR
   NOT CMAKE_Fortran_COMPILER_VERSION MATCHES "^$gfortran_major\\.")
  set(stickslip_FOUND FALSE)
  set(stickslip_NOT_FOUND_MESSAGE "stickslip's .mod files were written by gfortran $gfortran_major; this project's Fortran compiler is \${CMAKE_Fortran_COMPILER_ID} \${CMAKE_Fortran_COMPILER_VERSION} (enable_language(Fortran) with gfortran $gfortran_major first)")
  return()
endif()
include(CMakeFindDependencyMacro)
find_dependency(OpenMP COMPONENTS Fortran)
set(_stickslip_libs)
foreach(_lib $deps)
  find_library(stickslip_\${_lib}_LIBRARY NAMES \${_lib})
  if(NOT stickslip_\${_lib}_LIBRARY)
    set(stickslip_FOUND FALSE)
    set(stickslip_NOT_FOUND_MESSAGE "stickslip needs the library '\${_lib}' (Debian: ./setup.sh in stickslip's source tree installs it)")
    return()
  endif()
  list(APPEND _stickslip_libs "\${stickslip_\${_lib}_LIBRARY}")
endforeach()
if(NOT TARGET stickslip::stickslip)
  add_library(stickslip::stickslip STATIC IMPORTED)
  set_target_properties(stickslip::stickslip PROPERTIES
    IMPORTED_LOCATION "\${_stickslip_prefix}/lib/libstickslip.a"
    IMPORTED_LINK_INTERFACE_LANGUAGES "Fortran"
    INTERFACE_INCLUDE_DIRECTORIES "\${_stickslip_prefix}/include"
    INTERFACE_LINK_LIBRARIES "\${_stickslip_libs};OpenMP::OpenMP_Fortran")
endif()
CMAKE
    mv "$prefix/lib/cmake/stickslip/stickslip-config.cmake.tmp" "$prefix/lib/cmake/stickslip/stickslip-config.cmake"
    cat >"$prefix/lib/cmake/stickslip/stickslip-config-version.cmake.tmp" <<CMAKE
# stickslip $version: compatible with a request of the same major version, not newer
set(PACKAGE_VERSION $version)
if(PACKAGE_FIND_VERSION VERSION_GREATER PACKAGE_VERSION OR
   NOT PACKAGE_FIND_VERSION_MAJOR STREQUAL "$(echo "$version" | cut -d. -f1)")
  set(PACKAGE_VERSION_COMPATIBLE FALSE)
else()
  set(PACKAGE_VERSION_COMPATIBLE TRUE)
  if(PACKAGE_FIND_VERSION STREQUAL PACKAGE_VERSION)
    set(PACKAGE_VERSION_EXACT TRUE)
  endif()
endif()
CMAKE
    mv "$prefix/lib/cmake/stickslip/stickslip-config-version.cmake.tmp" "$prefix/lib/cmake/stickslip/stickslip-config-version.cmake"
    echo "setup: installed stickslip $version into $prefix (lib/libstickslip.a, include/, bin/stickslip, lib/pkgconfig/stickslip.pc, lib/cmake/stickslip/)"
fi
