#!/usr/bin/env bash
# The GPU check (docs/platforms.md, "Running the GPU check"), in two steps:
#
#   scripts/gpu-check.sh stage [BUILD_DIR]   here, after building against an OpenMM with CUDA
#       (BUILD_DIR default ./build-cuda): copies what the GPU machine needs into ./.gpu/
#       (ignored by git): OpenMM's libraries and CUDA platform plugin, the plugin's libraries,
#       the C++ test programs and benchmarks/cpp/device_speed; refuses if that is over 60 MiB.
#   scripts/gpu-check.sh run                 on the GPU machine, from the repository root with
#       .gpu/ carried: the C++ tests' CUDA cases, then device_speed (mixed precision, TIP3P
#       boxes of 24,000, 98,304 and 985,527 atoms), within 8 minutes. Writes to $OUT (the
#       device tool's output folder), else .gpu/out.
#
# Nothing in .gpu/ is built there: the machine has CUDA 13 and its driver, no Python OpenMM,
# no network. OpenMM's CUDA platform needs libcuda (the driver), libnvrtc.so.13 and
# libcufft.so.12 (CUDA 13) from that machine.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
stage="$root/.gpu"
mode="${1:-}"

stage_files() {
    local build="${1:-$root/build-cuda}"
    build="$(cd "$build" && pwd)"
    local cache="$build/CMakeCache.txt"
    [ -f "$cache" ] || { echo "gpu-check: no CMake build in $build"; exit 1; }
    cached() { sed -n "s/^$1:[A-Z]*=//p" "$cache" | head -1; }
    local openmm_lib plugin_dir cuda_plugin
    openmm_lib="$(cached OPENMM_LIBRARY)"
    plugin_dir="$(cached OPENMM_PLUGIN_DIR)"
    cuda_plugin="$(find "$build/platforms/cuda" -name 'libMRattlePluginCUDA.so' 2>/dev/null | head -1)"
    [ -n "$cuda_plugin" ] || { echo "gpu-check: $build has no libMRattlePluginCUDA.so (configure with -DOPENMM_DIR=<an OpenMM built with CUDA> and build)"; exit 1; }
    [ -f "$build/benchmarks/cpp/device_speed" ] || { echo "gpu-check: $build has no benchmarks/cpp/device_speed"; exit 1; }
    rm -rf "$stage"
    mkdir -p "$stage/lib" "$stage/openmm-plugins" "$stage/bin"
    # OpenMM's core library (with its soname links) and its CUDA platform.
    cp -a "$(dirname "$openmm_lib")"/libOpenMM.so* "$stage/lib/"
    cp -a "$plugin_dir/libOpenMMCUDA.so" "$stage/openmm-plugins/"
    # The plugin's libraries: the API, the Reference/CPU kernels the tests link, the device kernels.
    find "$build" -name 'libMRattlePlugin*.so*' -not -path '*/CMakeFiles/*' -exec cp -a {} "$stage/lib/" \;
    # The test programs (the generic suites name their CUDA cases *CUDA*) and the benchmark.
    local program
    for program in "$build"/tests/Test* "$build/benchmarks/cpp/device_speed"; do
        if [ -f "$program" ] && [ -x "$program" ]; then
            cp "$program" "$stage/bin/"
        fi
    done
    strip --strip-unneeded "$stage"/bin/* "$stage"/lib/libMRattlePlugin*.so* 2>/dev/null || true
    {
        echo "staged: $(date -u '+%Y-%m-%d %H:%M UTC') from $build"
        echo "plugin: $(git -C "$root" describe --always --dirty)"
        echo "OpenMM: $(cached OPENMM_VERSION_STRING) ($openmm_lib)"
        local nvcc
        nvcc="$(cached CUDAToolkit_NVCC_EXECUTABLE)"
        echo "CUDA toolkit: $("${nvcc:-nvcc}" --version 2>/dev/null | grep -o "release.*") (${nvcc:-nvcc})"
    } > "$stage/MANIFEST"
    (cd "$stage" && find . -type f | sort | xargs ls -l | awk '{print $5, $9}') >> "$stage/MANIFEST"
    local bytes limit=$((60 * 1024 * 1024))
    bytes="$(du -sb "$stage" | cut -f1)"
    echo "gpu-check: staged $(find "$stage" -type f | wc -l) files, $((bytes / 1024 / 1024)) MiB ($bytes bytes) in $stage"
    cat "$stage/MANIFEST" | head -4
    if [ "$bytes" -gt "$limit" ]; then
        echo "gpu-check: over 60 MiB: the device tool carries 64 MiB with the working tree"; exit 1
    fi
}

run_check() {
    [ -f "$stage/MANIFEST" ] || { echo "gpu-check: no $stage (run 'scripts/gpu-check.sh stage' where it was built, carry .gpu)"; exit 1; }
    local out="${OUT:-$stage/out}/gpu-check"
    mkdir -p "$out"
    local start=$SECONDS
    export OPENMM_PLUGIN_DIR="$stage/openmm-plugins"  # OpenMM's platforms, for the tests and device_speed
    export MRATTLE_PLUGIN_DIR="$stage/lib"             # the plugin's device kernels, for the tests
    export LD_LIBRARY_PATH="$stage/lib:$stage/openmm-plugins${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    local cuda
    for cuda in /usr/local/cuda/lib64 /usr/local/cuda/lib /usr/local/cuda/targets/x86_64-linux/lib; do
        [ -d "$cuda" ] && LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$cuda"
    done
    {
        cat "$stage/MANIFEST" | head -4
        echo "run: $(date -u '+%Y-%m-%d %H:%M UTC') on $(hostname)"
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1 || echo "nvidia-smi failed"
        nvcc --version 2>&1 | tail -2 || true
        echo "libOpenMMCUDA needs:"
        ldd "$OPENMM_PLUGIN_DIR/libOpenMMCUDA.so" | grep -E "not found|cuda|nvrtc|cufft" || true
    } > "$out/environment.txt" 2>&1
    cat "$out/environment.txt"

    # 1. The tests' CUDA cases, four programs at a time, at most 150 s in all.
    echo "== tests (CUDA cases) =="
    local programs=()
    local program
    for program in "$stage"/bin/Test*; do
        programs+=("$program")
    done
    local tests_status=0
    printf '%s\n' "${programs[@]}" | timeout 150 xargs -P 4 -I{} sh -c \
        'name=$(basename "{}"); "{}" --gtest_filter="*CUDA*" > "'"$out"'/$name.txt" 2>&1; echo "$name: exit $?"' \
        > "$out/tests-summary.txt" || tests_status=$?
    if [ "$tests_status" = 124 ]; then
        echo "tests: stopped at 150 s; the programs not listed did not finish" >> "$out/tests-summary.txt"
    fi
    sort "$out/tests-summary.txt"
    # Each program's totals, then every failure and the distinct reasons for skipping.
    grep -H -E "^\[  (PASSED|SKIPPED|FAILED) +\] [0-9]+ test" "$out"/Test*.txt | sed "s|^$out/||" || true
    grep -h -E "^\[  FAILED  \] .*\(" "$out"/Test*.txt | head -40 || true
    grep -h -A1 ": Skipped$" "$out"/Test*.txt | grep -v -E ": Skipped$|^--$" | sort | uniq -c | head -10 || true

    # 2. The benchmark: whatever of the 8 minutes is left, less a margin for writing back.
    local left=$((450 - (SECONDS - start)))
    echo "== device_speed (${left} s left) =="
    local status=0 budget=$((left - 120))
    [ "$budget" -ge 30 ] || budget=30
    timeout "$left" "$stage/bin/device_speed" --platform CUDA --precision mixed --plugins "$stage/lib/libMRattlePluginCUDA.so" \
        --budget "$budget" --out "$out/device_speed.csv" --ratios "$out/device_speed_ratios.csv" \
        2> "$out/device_speed.log" || status=$?
    echo "device_speed: exit $status"
    cat "$out/device_speed.log" | tail -30
    local table
    for table in "$out/device_speed.csv" "$out/device_speed_ratios.csv"; do
        [ -f "$table" ] && { column -s, -t < "$table" 2>/dev/null || cat "$table"; }
    done
    echo "gpu-check: done in $((SECONDS - start)) s; results in $out"
}

case "$mode" in
    stage) stage_files "${2:-}" ;;
    run) run_check ;;
    *) echo "usage: scripts/gpu-check.sh stage [BUILD_DIR] | run"; exit 1 ;;
esac
