#!/usr/bin/env bash
# Set up drakedeburr on a fresh Debian/Ubuntu machine:
#   1. system libraries open3d's wheel links against (libusb-1.0, libGL, libEGL), and
#      headless Chromium + its driver for the verification report's browser test,
#   2. a virtual environment .venv with drakedeburr and its dependencies (editable install).
# Usage: bash install.sh [--no-system] [--no-browser] [--venv DIR]
set -euo pipefail
cd "$(dirname "$0")"

VENV=.venv
SYSTEM=1
BROWSER=1
while [ $# -gt 0 ]; do
  case "$1" in
    --no-system) SYSTEM=0 ;;
    --no-browser) BROWSER=0 ;;
    --venv) VENV="$2"; shift ;;
    *) echo "install.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done

if [ "$SYSTEM" = 1 ]; then
  pkgs="libusb-1.0-0 libgl1 libegl1"
  [ "$BROWSER" = 1 ] && pkgs="$pkgs chromium chromium-driver"
  missing=""
  for p in $pkgs; do dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"; done
  if [ -n "$missing" ]; then
    if command -v apt-get >/dev/null 2>&1; then
      SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
      echo "install.sh: installing system libraries:$missing"
      $SUDO apt-get update -q
      DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q $missing
    else
      echo "install.sh: please install the system libraries$missing (open3d needs them)" >&2
    fi
  fi
fi

PY=${PYTHON:-python3}
"$PY" -c 'import sys; assert sys.version_info >= (3, 11), "drakedeburr needs Python >= 3.11"'
"$PY" -m venv "$VENV"
"$VENV/bin/python" -m pip install -q --upgrade pip
"$VENV/bin/python" -m pip install -q -e ".[dev,dask]"
"$VENV/bin/python" -c "import drakedeburr, pydrake, open3d; print('drakedeburr', drakedeburr.__version__, 'installed in $VENV')"
