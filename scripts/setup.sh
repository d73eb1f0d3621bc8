#!/usr/bin/env bash
# Installs everything clutterseg needs to build, test and benchmark, from Debian 12's packages only.
# Safe to run again; needs root (or sudo).
set -euo pipefail
SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
packages=(
  build-essential cmake ninja-build pkg-config
  libopencv-dev libeigen3-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libpcl-dev
  chromium fonts-dejavu-core
  python3 python3-numpy python3-matplotlib python3-opencv
  pybind11-dev python3-dev python3-pytest python3-venv python3-build python3-setuptools python3-wheel
  # Sanitizer builds and fuzzers (scripts/sanitize.sh, scripts/fuzz.sh): clang 14 with its ASan, UBSan,
  # TSan and libFuzzer runtimes, and its OpenMP runtime.
  clang-14 libclang-rt-14-dev libomp-14-dev
  # The ROS 1 node (ros/, docs/ROS.md): Debian's ROS 1 packages, message generation (gencpp, genpy and
  # the .msg files), master, launch, bags and rosrun to run it; rospy, OpenCV and pytest for the bag
  # script and the ROS tests.
  libroscpp-dev libxmlrpcpp-dev libimage-transport-dev libcv-bridge-dev libmessage-filters-dev
  libnodeletlib-dev libnodeletlib-tools pluginlib-dev libtf2-ros-dev libdiagnostic-updater-dev
  libsensor-msgs-dev libgeometry-msgs-dev libvisualization-msgs-dev libstd-msgs-dev libdiagnostic-msgs-dev
  python3-gencpp python3-genpy ros-message-generation ros-std-msgs ros-geometry-msgs
  python3-rosmaster python3-roslaunch python3-rosbag python3-rospy rosbash rosout
  python3-sensor-msgs python3-std-msgs python3-diagnostic-msgs python3-tf2-msgs
)
$SUDO apt-get update -qq
# One install (one dependency resolution, each trigger run once) and no fsync per unpacked file (unsafe
# only if the machine loses power during the install): on a new machine the install is minutes of CI time
# (docs/RELIABILITY.md, "CI time").
$SUDO apt-get install -y -qq --no-install-recommends -o Dpkg::Options::=--force-unsafe-io \
  "${packages[@]}" >/dev/null
