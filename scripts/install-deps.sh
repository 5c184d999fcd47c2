#!/usr/bin/env bash
# Install the Debian packages the project needs, only for what is missing. Each need is
# checked by what the package provides (a command, a header, a library, a module that the
# Python interpreter CMake will choose can import), not by the package's name, so a machine
# that has everything runs no apt at all, whichever package brought it (on Debian 13
# python3-simtk is only a virtual package that python3-openmm provides).
# Where a package's name differs between releases the names are listed by preference
# ("python3-openmm|python3-simtk"): the first one this release's apt sources have is used.
set -euo pipefail

# The interpreter CMake chooses (python/CMakeLists.txt): 'python3' on PATH if it can
# import openmm, else Debian's /usr/bin/python3.
python=/usr/bin/python3
if command -v python3 >/dev/null 2>&1 && python3 -c 'import openmm' >/dev/null 2>&1; then
    python="$(command -v python3)"
fi

exists() { local f; for f in "$@"; do [ -e "$f" ] && return 0; done; return 1; }  # any of (globs)
runs() { command -v "$1" >/dev/null 2>&1; }
imports() { [ -x "$python" ] && "$python" -c "import $1" >/dev/null 2>&1; }
has_python_headers() {
    [ -x "$python" ] && "$python" -c 'import os, sys, sysconfig
sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))' >/dev/null 2>&1
}

# Fills 'missing' with one entry per unmet need: "package[|alternative...]  (what is missing)".
check() {
    missing=()
    need() { local what="$1" packages="$2"; shift 2; "$@" || missing+=("$packages  ($what)"); }
    need "cmake"                           cmake              runs cmake
    need "g++"                             g++                runs g++
    need "make"                            make               runs make
    need "OpenMM.h"                        libopenmm-dev      exists /usr/include/OpenMM.h
    need "libOpenMM.so"                    libopenmm-dev      exists /usr/lib/*/libOpenMM.so /usr/lib/libOpenMM.so
    need "OpenMM's OpenCL headers"         libopenmm-dev      exists /usr/include/openmm/opencl/OpenCLPlatform.h
    need "OpenMM's CPU and OpenCL platforms" libopenmm-plugins \
        exists /usr/lib/*/openmm/plugins/libOpenMMCPU.so
    need "OpenMM's OpenCL platform"        libopenmm-plugins  exists /usr/lib/*/openmm/plugins/libOpenMMOpenCL.so
    need "$python: import openmm"          "python3-openmm|python3-simtk" imports openmm
    need "$python: import numpy"           python3-numpy      imports numpy
    need "$python: import pytest"          python3-pytest     imports pytest
    need "$python: import matplotlib"      python3-matplotlib imports matplotlib
    need "$python: Python.h"               python3-dev        has_python_headers
    need "swig"                            swig               runs swig
    need "Eigen 3 and its CMake config"    libeigen3-dev \
        exists /usr/share/eigen3/cmake/Eigen3Config.cmake /usr/lib/cmake/eigen3/Eigen3Config.cmake
    need "lbfgs.h (the minimizer)"         liblbfgs-dev       exists /usr/include/lbfgs.h
    need "liblbfgs"                        liblbfgs-dev       exists /usr/lib/*/liblbfgs.so
    need "gtest/gtest.h"                   libgtest-dev       exists /usr/include/gtest/gtest.h
    need "libgtest"                        libgtest-dev       exists /usr/lib/*/libgtest.a /usr/lib/*/libgtest.so
    need "CL/cl.h"                         ocl-icd-opencl-dev exists /usr/include/CL/cl.h
    need "libOpenCL.so"                    ocl-icd-opencl-dev exists /usr/lib/*/libOpenCL.so
    # An OpenCL device on the CPU, which the OpenCL tests use.
    need "pocl's OpenCL driver"            pocl-opencl-icd    exists /etc/OpenCL/vendors/pocl.icd
    # Wanted, not needed: what openmmtools (from ../shared/deps) needs for the replica-exchange
    # tests (tests/python/replica_exchange), which skip, saying why, without it. A package this
    # release's apt sources lack, or whose install fails, gets a note, not a failure.
    wanted=()
    want() { local what="$1" packages="$2"; shift 2; "$@" || wanted+=("$packages  ($what)"); }
    want "$python: import scipy"           python3-scipy      imports scipy
    want "$python: import yaml"            python3-yaml       imports yaml
    want "$python: import netCDF4"         python3-netcdf4    imports netCDF4
    want "$python: import mdtraj"          python3-mdtraj     imports mdtraj
    want "$python: import pymbar"          python3-pymbar     imports pymbar
    want "$python: import numba"           python3-numba      imports numba
    want "$python: import mpi4py"          python3-mpi4py     imports mpi4py
    want "mpirun"                          openmpi-bin        runs mpirun
}

check
[ ${#missing[@]} -eq 0 ] && [ ${#wanted[@]} -eq 0 ] && exit 0
[ ${#missing[@]} -gt 0 ] && { echo "install-deps.sh: missing:"; printf '  %s\n' "${missing[@]}"; }
[ ${#wanted[@]} -gt 0 ] && { echo "install-deps.sh: wanted (the replica-exchange tests):"; printf '  %s\n' "${wanted[@]}"; }
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
$SUDO apt-get update -qq

# The first of an entry's names that this release's apt sources have ("" if none).
candidate() {
    local name policy
    for name in $(echo "${1%%  (*}" | tr '|' ' '); do
        policy="$(apt-cache policy "$name" 2>/dev/null)"
        if [[ "$policy" =~ Candidate:\ [^\(] ]]; then echo "$name"; return; fi
    done
}

# apt-get install of the packages; returns apt's status, its output in a log.
install() {
    local log
    log="$(mktemp -t mrattle-apt.XXXXXX.log)"
    echo "install-deps.sh: installing $* (apt's output: $log)"
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -q --no-install-recommends \
        "$@" > "$log" 2>&1 || { tail -n 40 "$log" >&2; echo "install-deps.sh: apt-get install failed (log: $log)" >&2; return 1; }
}

packages=()
for entry in "${missing[@]}"; do
    chosen="$(candidate "$entry")"
    [ -n "$chosen" ] || { echo "install-deps.sh: no package ${entry%%  (*} in this system's apt sources" >&2; exit 1; }
    packages+=("$chosen")
done
if [ ${#packages[@]} -gt 0 ]; then
    mapfile -t packages < <(printf '%s\n' "${packages[@]}" | sort -u)
    install "${packages[@]}" || exit 1
fi
extras=()
for entry in "${wanted[@]}"; do
    chosen="$(candidate "$entry")"
    if [ -n "$chosen" ]; then extras+=("$chosen")
    else echo "install-deps.sh: note: no package ${entry%%  (*} in this system's apt sources; the replica-exchange tests will say what they lack"
    fi
done
if [ ${#extras[@]} -gt 0 ]; then
    mapfile -t extras < <(printf '%s\n' "${extras[@]}" | sort -u)
    install "${extras[@]}" || echo "install-deps.sh: note: the replica-exchange tests' packages did not install; those tests will skip, saying why"
fi
check
if [ ${#missing[@]} -gt 0 ]; then
    echo "install-deps.sh: still missing after installing (is $python the interpreter you meant?):" >&2
    printf '  %s\n' "${missing[@]}" >&2
    exit 1
fi
if [ ${#wanted[@]} -gt 0 ]; then
    echo "install-deps.sh: note: still missing for the replica-exchange tests (they will skip, saying why):"
    printf '  %s\n' "${wanted[@]}"
fi
