#!/usr/bin/env bash
# Installs everything clutterseg needs to build, test and benchmark, from Debian 12's packages only.
# Safe to run again; needs root (or sudo).
set -euo pipefail
SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  build-essential cmake ninja-build pkg-config \
  libopencv-dev libeigen3-dev libcli11-dev nlohmann-json3-dev \
  libgtest-dev libgmock-dev libbenchmark-dev \
  libpcl-dev \
  chromium fonts-dejavu-core \
  python3 python3-numpy python3-matplotlib python3-opencv \
  pybind11-dev python3-dev python3-pytest python3-venv python3-build python3-setuptools python3-wheel >/dev/null
