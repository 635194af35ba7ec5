#!/usr/bin/env bash
# Install what stickslip needs on a Debian machine, if missing: gfortran, LAPACK/BLAS, FFTW3,
# MINPACK, gnuplot for the plots (Debian packages) and fpm (PyPI). Idempotent; prints nothing when all is there.
# Usage: ./setup.sh            install only
#        ./setup.sh --run      install, build, run the seed example (examples/seed.nml: the
#                              three methods side by side) and draw out/seed/figure3.png
set -euo pipefail
cd "$(dirname "$0")"

pkgs=(gfortran liblapack-dev libfftw3-dev minpack-dev libopenblas0-pthread libopenblas-pthread-dev libopenblas-dev libsuitesparse-dev libarpack2-dev gnuplot-nox)
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
