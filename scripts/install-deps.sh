#!/usr/bin/env bash
# Installs the Debian packages voxmesh builds and tests with; does nothing when they are present.
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  ocl-icd-opencl-dev opencl-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  catch2 libcli11-dev zlib1g-dev
  python3 python3-numpy python3-venv python3-pip python3-setuptools python3-wheel python3-build
  clang libclang-rt-14-dev
  locales
)
if [[ "${VOXMESH_PEERS:-0}" == 1 ]]; then
  packages+=(python3-vtk9 python3-skimage python3-matplotlib)
fi
# VOXMESH_ORACLES=1 (CI sets it): scikit-image, which tests/test_python_skimage.py compares
# voxmesh.marching_cubes with (those cases skip without it).
if [[ "${VOXMESH_ORACLES:-0}" == 1 ]]; then
  packages+=(python3-skimage)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}" >&2
  sudo=""
  [[ $(id -u) == 0 ]] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
