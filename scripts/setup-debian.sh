#!/usr/bin/env bash
# Installs everything iphong needs to build, test and benchmark on Debian 12 (run as root).
# Only Debian's own packages: no pip, no downloads from other hosts.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libceres-dev
  libopencv-dev libopenimageio-dev openimageio-tools libmatio-dev
  # A PNG's embedded colour profile (iCCP) is zlib-compressed; OpenImageIO 2.4 does not report it.
  zlib1g-dev
  libcli11-dev nlohmann-json3-dev libopenmesh-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
  # The test command runs pytest's files on both cores (pytest -n 2).
  python3-pytest-xdist
  # iphong.dask: normals on chunked arrays and many captures, locally or on a cluster.
  python3-dask python3-distributed
  # The relighting viewer's test renders its WebGL page headless (SwiftShader, no GPU needed).
  chromium
  # pip install . into a virtual environment (pyproject.toml builds with setuptools and CMake).
  python3-pip python3-venv python3-setuptools
  # The documentation site (docs/, built by the test command with warnings as errors).
  python3-sphinx python3-myst-parser python3-sphinx-rtd-theme
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  SUDO=""
  [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update
  $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi
