#!/usr/bin/env bash
# Installs every Debian 12 package slam_mms needs to build, test and run, when missing.
# Safe to run repeatedly; does nothing (no apt-get at all) when everything is present.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git clang-format
  libeigen3-dev libceres-dev libsuitesparse-dev libgoogle-glog-dev libgflags-dev
  libnanoflann-dev libopencv-dev libgeographiclib-dev libembree-dev
  libgtest-dev libgmock-dev libbenchmark-dev libyaml-cpp-dev
  libegl-dev libgl-dev libgl1-mesa-dev libegl-mesa0 libgl1-mesa-dri libgbm1
  libcli11-dev nlohmann-json3-dev libproj-dev proj-data libpng-dev
  librosbag-storage-dev libsensor-msgs-dev python3-rosbag python3-sensor-msgs python3-geometry-msgs
  python3-dev pybind11-dev python3-numpy python3-pytest python3-venv python3-matplotlib
  python3-setuptools python3-wheel python3-pip python3-distributed python3-fsspec
)
if [[ "${SLAM_MMS_WITH_CLANG:-0}" == "1" ]]; then
  PACKAGES+=(clang libclang-rt-14-dev)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "[install_deps] all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "[install_deps] installing: ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "[install_deps] done"
