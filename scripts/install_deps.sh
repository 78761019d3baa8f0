#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs the Debian 12 packages nfield builds and tests with. Idempotent: prints nothing
# and exits 0 when everything is present. Set NFIELD_WITH_TORCH=1 to add the PyTorch peer
# benchmark's packages.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libceres-dev libvtk9-dev libhdf5-dev libyaml-cpp-dev
  libgtest-dev libgmock-dev libbenchmark-dev libmuparser-dev libomp-dev libcli11-dev nlohmann-json3-dev
  python3-h5py python3-dev python3-numpy python3-pybind11 python3-scipy python3-skimage
  libboost-dev libsndfile1-dev libwebp-dev libopenblas-openmp-dev
  libopenmpi-dev openmpi-bin
  gnome-backgrounds  # data: the 4096² picture of configs/fit_image_acorn.yaml (data/SOURCES.md)
)
if [[ "${NFIELD_WITH_TORCH:-0}" == 1 ]]; then
  packages+=(python3 python3-torch python3-numpy python3-pil libopenblas0-openmp)
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "nfield: installing missing Debian packages: ${missing[*]}"
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    SUDO=(sudo -n)
  else
    echo "nfield: cannot install (not root and no password-less sudo)." >&2
    echo "nfield: as root, run: apt-get update && apt-get install -y ${missing[*]}" >&2
    exit 1
  fi
else
  SUDO=()
fi
export DEBIAN_FRONTEND=noninteractive
# A fresh machine has no package lists yet; update once when the install cannot find a package.
if ! "${SUDO[@]}" apt-get install -y -qq "${missing[@]}" >/tmp/nfield-apt.log 2>&1; then
  if ! "${SUDO[@]}" apt-get update -qq >>/tmp/nfield-apt.log 2>&1; then
    echo "nfield: 'apt-get update' failed (no network to the Debian archive?). Log: /tmp/nfield-apt.log" >&2
    exit 1
  fi
  if ! "${SUDO[@]}" apt-get install -y -qq "${missing[@]}" >>/tmp/nfield-apt.log 2>&1; then
    echo "nfield: 'apt-get install' failed. Log: /tmp/nfield-apt.log" >&2
    tail -n 5 /tmp/nfield-apt.log >&2
    exit 1
  fi
fi
echo "nfield: packages installed."
