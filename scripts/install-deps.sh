#!/usr/bin/env bash
# Installs every build and run-time dependency of paco from Debian 12's own packages.
# Idempotent: packages already present are left alone; safe to run again.
# Run as root (or with sudo). Nothing is downloaded from anywhere but Debian's mirrors.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libpcl-dev libflann-dev libeigen3-dev
  libtorch-dev libgloo-dev
  libcgal-dev libgmp-dev libmpfr-dev
  libboost-dev libboost-graph-dev libboost-program-options-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libglpk-dev coinor-libcbc-dev coinor-libclp-dev coinor-libcgl-dev coinor-libosi-dev coinor-libcoinutils-dev
  libopenblas0-openmp libopenblas-openmp-dev
  zlib1g-dev
)

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -gt 0 ]; then
  echo "paco: installing ${#missing[@]} missing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "paco: all Debian packages already installed"
fi

# LibTorch calls BLAS through the Debian alternatives system. The OpenMP build of OpenBLAS is
# 2.5x faster than the pthread build and ~19x faster than the reference BLAS for our
# transformer, so pin it for both the BLAS and the LAPACK alternative.
arch=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)
for alt in "libblas.so.3-${arch}" "liblapack.so.3-${arch}"; do
  lib="${alt%%-${arch}}"
  target="/usr/lib/${arch}/openblas-openmp/${lib}"
  if [ -e "$target" ]; then
    $SUDO update-alternatives --set "$alt" "$target" >/dev/null
  fi
done
echo "paco: BLAS in use: $(readlink -f /usr/lib/${arch}/libblas.so.3)"
