#!/usr/bin/env bash
# The device step before and after a change, through pocl, in one run (issue 31, item 3):
# two builds' device_speed, alternating for each precision: 512 and 4,096 rigid TIP3P
# waters (8 and 16 per side) bare (the integration's own cost, forces excluded), and 512
# with PME (ns/day). device_speed times its four integrators in interleaved batches; this
# script interleaves the builds, so both see the same machine within minutes. With PME the
# integration is under 1% of a step through pocl, so its ns/day ratios are the machine's
# noise: about 7% from batch to batch, and 2% from one Context to another of the same
# integrator. So PME runs in three processes (fresh Contexts) of 7 batches each, whose
# ratios are pooled (geometric mean) into *-pme-ratios.csv; the bare systems in one of 9.
#
# Usage: benchmarks/device_speed_pocl.sh BEFORE_DEVICE_SPEED AFTER_DEVICE_SPEED OUTDIR [BEFORE_PLUGIN AFTER_PLUGIN]
#   e.g. build-before/obj/benchmarks/cpp/device_speed build/benchmarks/cpp/device_speed docs/results/pocl
# The plugins (libMRattlePluginOpenCL.so) default to each build's own; give copies to keep
# building while it runs. Writes OUTDIR/{before,after}-{single,double}.csv (bare timings),
# ...-pme-{1,2,3}.csv (PME) and *-ratios.csv (device_speed's GPU targets, with each ratio's
# paired 95% interval; issue 31's pocl targets are in docs/platforms.md).
set -euo pipefail
if [ $# -ne 3 ] && [ $# -ne 5 ]; then
    sed -n '2,17p' "$0"
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
        echo "$(date -u +%H:%M:%S) $build $precision bare" >&2
        # shellcheck disable=SC2086
        "${binary[$build]}" ${plugins[$build]} --platform OpenCL --precision "$precision" --waters-per-side 8,16 \
            --systems bare --repeats 9 --batch-seconds 0.5 --warmup 20 --out "$out/$build-$precision.csv" \
            --ratios "$out/$build-$precision-ratios.csv"
    done
    for process in 1 2 3; do
        for build in before after; do
            echo "$(date -u +%H:%M:%S) $build $precision pme $process" >&2
            # shellcheck disable=SC2086
            "${binary[$build]}" ${plugins[$build]} --platform OpenCL --precision "$precision" --waters-per-side 8 \
                --systems pme --repeats 7 --batch-seconds 0.5 --warmup 20 --out "$out/$build-$precision-pme-$process.csv" \
                --ratios "$out/$build-$precision-pme-$process-ratios.csv"
        done
    done
    for build in before after; do
        # The three processes' ratios of medians, pooled: geometric mean, lowest, highest.
        awk -F, 'FNR > 1 { n[$3]++; sum[$3] += log($4); if (!($3 in low) || $4 < low[$3]) low[$3] = $4;
                           if ($4 > high[$3]) high[$3] = $4; key[$3] = $1 "," $2 }
                 END { print "system,atoms,measure,value,target,processes,lowest,highest";
                       for (m in n) printf "%s,%s,%.3f,>= 0.97,%d,%s,%s\n", key[m], m, exp(sum[m] / n[m]), n[m], low[m], high[m] }' \
            "$out/$build-$precision"-pme-[123]-ratios.csv > "$out/$build-$precision-pme-ratios.csv"
    done
done
