#!/usr/bin/env bash
# Install the build into a temporary prefix, compile the C++ example against the installed
# headers (include/mrattle) and OpenMM's alone, link it to the installed libraries and run
# a few steps. Fails if a public header needs Eigen or anything else from the source tree.
# Usage: check_installed_headers.sh BUILD_DIR EXAMPLE_CPP OPENMM_INCLUDE OPENMM_LIBDIR OPENMM_PLUGIN_DIR CXX
set -euo pipefail
build="$1" example="$2" openmm_include="$3" openmm_lib="$4" openmm_plugins="$5" cxx="$6"
prefix="$(mktemp -d)"
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build" --prefix "$prefix" > "$prefix/install.log"
libdir="$(dirname "$(find "$prefix" -name 'libMRattlePlugin.so' | head -1)")"
plugin="$(find "$prefix" -name 'libMRattlePluginReference.so' | head -1)"
[ -f "$prefix/include/mrattle/MRattleIntegrator.h" ] || { echo "include/mrattle/MRattleIntegrator.h not installed"; exit 1; }
if grep -rl "Eigen" "$prefix/include/mrattle"; then echo "an installed header mentions Eigen"; exit 1; fi
"$cxx" -std=c++11 -O1 -I"$prefix/include/mrattle" -I"$openmm_include" -I"$(dirname "$openmm_include")" \
    "$example" -o "$prefix/example" -L"$libdir" -L"$openmm_lib" \
    "$plugin" -lMRattlePlugin -lOpenMM -Wl,-rpath,"$libdir:$(dirname "$plugin"):$openmm_lib"
OPENMM_PLUGIN_DIR="$openmm_plugins" "$prefix/example" 50 2 Reference
echo "compiled against $prefix/include/mrattle and $openmm_include only, and ran"
