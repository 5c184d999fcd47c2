#!/usr/bin/env bash
# The device step before and after a change, through pocl, in one run (issue 31, item 3):
# two builds' device_speed, alternating for each precision: 512 and 4,096 rigid TIP3P
# waters (8 and 16 per side) bare (the integration's own cost, forces excluded), and 512
# with PME (ns/day). device_speed times its four integrators in interleaved batches; this
# script interleaves the builds, so both see the same machine within minutes.
#
# Usage: benchmarks/device_speed_pocl.sh BEFORE_DEVICE_SPEED AFTER_DEVICE_SPEED OUTDIR [BEFORE_PLUGIN AFTER_PLUGIN]
#   e.g. build-before/obj/benchmarks/cpp/device_speed build/benchmarks/cpp/device_speed docs/results/pocl
# The plugins (libMRattlePluginOpenCL.so) default to each build's own; give copies to keep
# building while it runs. Writes OUTDIR/{before,after}-{single,double}.csv (timings) and
# *-ratios.csv (device_speed's GPU targets; issue 31's pocl targets are in docs/platforms.md).
set -euo pipefail
if [ $# -ne 3 ] && [ $# -ne 5 ]; then
    sed -n '2,15p' "$0"
    exit 1
fi
declare -A binary=([before]="$1" [after]="$2") plugins=([before]="" [after]="")
out="$3"
if [ $# -eq 5 ]; then
    plugins=([before]="--plugins $4" [after]="--plugins $5")
fi
mkdir -p "$out"
for precision in single double; do
    for build in before after; do
        echo "$(date -u +%H:%M:%S) $build $precision" >&2
        # shellcheck disable=SC2086
        "${binary[$build]}" ${plugins[$build]} --platform OpenCL --precision "$precision" --waters-per-side 8,16 \
            --systems bare --repeats 5 --batch-seconds 0.5 --warmup 20 --out "$out/$build-$precision.csv" \
            --ratios "$out/$build-$precision-ratios.csv"
        # shellcheck disable=SC2086
        "${binary[$build]}" ${plugins[$build]} --platform OpenCL --precision "$precision" --waters-per-side 8 \
            --systems pme --repeats 5 --batch-seconds 0.5 --warmup 20 --out "$out/$build-$precision-pme.csv" \
            --ratios "$out/$build-$precision-pme-ratios.csv"
    done
done
