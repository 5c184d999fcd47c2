#!/usr/bin/env bash
# Install the Debian packages the project needs, only if some are missing.
set -euo pipefail
packages=(cmake g++ make libopenmm-dev libopenmm-plugins python3-simtk libeigen3-dev liblbfgs-dev libgtest-dev
          libbenchmark-dev swig python3-dev python3-pytest python3-numpy python3-matplotlib
          pocl-opencl-icd ocl-icd-opencl-dev)  # an OpenCL device on the CPU, and the headers: the OpenCL kernels
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "Installing missing packages: ${missing[*]}"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
