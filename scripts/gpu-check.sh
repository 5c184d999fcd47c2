#!/usr/bin/env bash
# The GPU check (docs/cuda.md, "The GPU check"), in two steps:
#
#   scripts/gpu-check.sh stage [BUILD_DIR]   here, after building against an OpenMM with CUDA
#       (BUILD_DIR default ./build-cuda): copies what the GPU machine needs into ./.gpu/
#       (ignored by git): OpenMM's libraries and CUDA platform plugin, the plugin's libraries,
#       the C++ test programs and benchmarks/cpp/device_speed; refuses if that is over 60 MiB.
#   scripts/gpu-check.sh run                 on the GPU machine, from the repository root with
#       .gpu/ carried, within 8 minutes: the device test first (120 s), then device_speed
#       (mixed precision, TIP3P boxes of 24,000, 98,304 and 985,527 atoms, bare and PME; the
#       thermostats and ten large bodies bare at the first two sizes), one process per group
#       under a hard limit, then the other tests' CUDA cases with what is
#       left. Writes two files to $OUT (the device tool's output folder), else .gpu/out:
#       gpu-check.tar.gz (everything) and gpu-check-summary.txt. Where there is no CUDA device
#       (no driver, or none that nvidia-smi sees) it says so in both, runs nothing and exits 3.
#
# Nothing in .gpu/ is built there: the machine has CUDA 13 and its driver, no Python OpenMM,
# no network. OpenMM's CUDA platform needs libcuda (the driver), libnvrtc and libcufft from
# that machine, found wherever it has them (cuda_library_dirs).
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
    # Stripped, OpenMM's own libraries too (symbol tables are most of their size).
    find "$stage" -type f \( -name '*.so*' -o -path "$stage/bin/*" \) -exec strip --strip-unneeded {} + 2>/dev/null || true
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

# Directories holding a CUDA library (libnvrtc, libcufft, libcuda) wherever this machine has
# it: the loader's cache, every CUDA toolkit folder, the usual library folders; never the
# toolkit's driver stubs (a stub libcuda loads and then fails every call).
cuda_library_dirs() {
    local name found=()
    for name in libnvrtc.so libcufft.so libcuda.so.1; do
        {
            { ldconfig -p 2>/dev/null || true; } | awk -v n="$name" '$1 ~ "^"n {print $NF}'
            find /usr/local/cuda* /usr/lib/x86_64-linux-gnu /usr/lib64 /opt /usr/lib/wsl \
                -maxdepth 6 -name "$name*" \( -type f -o -type l \) 2>/dev/null || true
        } | { grep -v '/stubs/' || true; } | while read -r lib; do dirname "$lib"; done
    done | awk '!seen[$0]++'
}

# Why CUDA cannot run here, or nothing: no driver (libcuda.so.1, a stub not counting) in the
# folders found, or a driver whose nvidia-smi lists no GPU.
no_cuda_device() {
    local dirs="$1" dir
    for dir in ${dirs//:/ }; do
        if [ -e "$dir/libcuda.so.1" ]; then
            if command -v nvidia-smi > /dev/null && ! nvidia-smi -L 2>/dev/null | grep -q '^GPU '; then
                echo "the CUDA driver is here ($dir/libcuda.so.1) but nvidia-smi lists no GPU"
            fi
            return 0
        fi
    done
    echo "no CUDA driver (libcuda.so.1) on this machine, only what a toolkit has (its stubs/ do not count)"
}

run_check() {
    [ -f "$stage/MANIFEST" ] || { echo "gpu-check: no $stage (run 'scripts/gpu-check.sh stage' where it was built, carry .gpu)"; exit 1; }
    # At most 8 result files come back: everything goes into one archive, plus a summary.
    local out="${OUT:-$stage/out}"
    local work
    work="$(mktemp -d)"
    mkdir -p "$out"
    local start=$SECONDS deadline=440  # of the 480 s: 40 s to spare for the archive and the copy back
    left() { echo $((deadline - (SECONDS - start))); }
    export OPENMM_PLUGIN_DIR="$stage/openmm-plugins"  # OpenMM's platforms, for the tests and device_speed
    export MRATTLE_PLUGIN_DIR="$stage/lib"             # the plugin's device kernels, for the tests
    local dirs
    dirs="$(cuda_library_dirs | paste -sd: -)"
    export LD_LIBRARY_PATH="$stage/lib:$stage/openmm-plugins${dirs:+:$dirs}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    {
        head -4 "$stage/MANIFEST"
        echo "run: $(date -u '+%Y-%m-%d %H:%M UTC') on $(hostname)"
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1 || echo "nvidia-smi failed"
        echo "CUDA library folders found: ${dirs:-none}"
        echo "libOpenMMCUDA needs:"
        ldd "$OPENMM_PLUGIN_DIR/libOpenMMCUDA.so" | grep -E "not found|cuda|nvrtc|cufft" || true
    } > "$work/environment.txt" 2>&1
    cat "$work/environment.txt"
    local problem
    problem="$(no_cuda_device "$dirs")"
    if [ -n "$problem" ]; then
        # Nothing can run: say why in both result files rather than let every program fail.
        echo "gpu-check: no CUDA device: $problem; nothing was run" | tee "$work/summary.txt"
        tar -czf "$out/gpu-check.tar.gz" -C "$work" .
        cp "$work/summary.txt" "$out/gpu-check-summary.txt"
        rm -rf "$work"
        exit 3
    fi

    # 1. The device test first (agreement, rigidity, failures), at most 120 s.
    echo "== TestDevicePlatforms (CUDA) =="
    local status=0
    timeout 120 "$stage/bin/TestDevicePlatforms" --gtest_filter='*CUDA*' > "$work/TestDevicePlatforms.txt" 2>&1 || status=$?
    echo "TestDevicePlatforms: exit $status$([ "$status" = 124 ] && echo ' (cut at 120 s)')" | tee "$work/summary.txt"

    # 2. device_speed, one process per (size, System, integrators) group under a hard limit, so
    #    that every group writes its rows or is named as cut: first the integration alone (bare)
    #    of all eight (the thermostats against NoseHoover + SETTLE, ten large bodies against the
    #    same atoms as waters) at 24,000 and 98,304 atoms, 60 s each; then Verlet, LangevinMiddle
    #    and their M-RATTLE counterparts with PME there (45 s each) and at 985,527 atoms (75 s
    #    each), while time is left.
    echo "== device_speed (mixed precision) =="
    local n system integrators limit group
    local base=verlet_settle,mrattle,langevin_settle,mrattle_langevin
    for group in "20 bare all 60" "32 bare all 60" "20 pme $base 45" "32 pme $base 45" "69 bare $base 75" \
                 "69 pme $base 75"; do
        read -r n system integrators limit <<< "$group"
        [ "$integrators" = all ] && integrators=""
        if [ "$(left)" -lt $((limit + 60)) ]; then
            echo "device_speed $n^3 waters $system: not started, $(left) s left" | tee -a "$work/summary.txt"
            continue
        fi
        status=0
        timeout "$limit" "$stage/bin/device_speed" --platform CUDA --precision mixed \
            --plugins "$stage/lib/libMRattlePluginCUDA.so" --waters-per-side "$n" --systems "$system" \
            ${integrators:+--integrators "$integrators"} \
            --out "$work/device_speed-$n-$system.csv" --ratios "$work/device_speed-$n-$system-ratios.csv" \
            2> "$work/device_speed-$n-$system.log" || status=$?
        echo "device_speed $n^3 waters $system: exit $status$([ "$status" = 124 ] && echo " (cut at $limit s)")" \
            | tee -a "$work/summary.txt"
        cat "$work/device_speed-$n-$system-ratios.csv" 2>/dev/null | tail -n +2 | tee -a "$work/summary.txt" || true
    done

    # 3. The other test programs' CUDA cases with what is left, four at a time.
    echo "== other tests (CUDA cases, $(left) s left) =="
    local programs=() program
    for program in "$stage"/bin/Test*; do
        [ "$(basename "$program")" = TestDevicePlatforms ] || programs+=("$program")
    done
    if [ "$(left)" -gt 20 ]; then
        status=0
        printf '%s\n' "${programs[@]}" | timeout "$(left)" xargs -P 4 -I{} sh -c \
            'name=$(basename "{}"); "{}" --gtest_filter="*CUDA*" > "'"$work"'/$name.txt" 2>&1; echo "$name: exit $?"' \
            >> "$work/summary.txt" || status=$?
        [ "$status" = 124 ] && echo "other tests: cut; the programs not listed did not finish" >> "$work/summary.txt"
    else
        echo "other tests: not started, $(left) s left" >> "$work/summary.txt"
    fi
    grep -H -E "^\[  (PASSED|SKIPPED|FAILED) +\] [0-9]+ test" "$work"/Test*.txt | sed "s|^$work/||" >> "$work/summary.txt" || true
    grep -h -E "^\[  FAILED  \] .*\(" "$work"/Test*.txt | head -40 >> "$work/summary.txt" || true
    echo "gpu-check: done in $((SECONDS - start)) s" >> "$work/summary.txt"
    tar -czf "$out/gpu-check.tar.gz" -C "$work" .
    cp "$work/summary.txt" "$out/gpu-check-summary.txt"
    cat "$out/gpu-check-summary.txt"
    echo "gpu-check: results in $out/gpu-check.tar.gz and $out/gpu-check-summary.txt"
    rm -rf "$work"
}

case "$mode" in
    stage) stage_files "${2:-}" ;;
    run) run_check ;;
    *) echo "usage: scripts/gpu-check.sh stage [BUILD_DIR] | run"; exit 1 ;;
esac
