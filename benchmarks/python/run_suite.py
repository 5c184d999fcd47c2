#!/usr/bin/env python3
"""The benchmark suite behind docs/results.md, run through its one door, ./benchmarks/run.sh TARGET:

    paper                   M-RATTLE against the splitting method: accuracy, cost, sampling, drift
    validate-langevin       MRattleLangevinIntegrator against LangevinMiddle + SETTLE
    validate-equipartition  rigid water, translational against rotational temperature
    validate-thermostats    Nose-Hoover chain and CSVR on rigid water [--report-from CSV]
    validate-drude          the Drude integrators against OpenMM's + SETTLE on SWM4-NDP (results/drude.md), and
                            the Langevin Drude temperature against the body friction (results/drude-friction.md)
    validate-minimization   RigidBodyMinimizer against LocalEnergyMinimizer (options of its own: --help)

--quick: tiny runs written to a scratch folder (a smoke test); --only: some parts of a target.
Every table and plot in docs/results.md comes from these runs; report.py writes the markdown
(a partial run replaces only its own sections, stamped).
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TARGETS = {"paper": ("accuracy", "cost", "sampling", "drift"),
           "validate-langevin": ("langevin",), "validate-equipartition": ("equipartition",),
           "validate-thermostats": ("thermostats",), "validate-drude": ("drude", "friction")}


def parse(argv):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("target", choices=sorted(TARGETS) + ["validate-minimization"])
    p.add_argument("--quick", action="store_true", help="tiny runs for CI smoke tests")
    p.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build folder")
    p.add_argument("--out", default=None, help="output folder (default docs/, or a scratch folder with --quick)")
    p.add_argument("--only", help="comma-separated parts of the target to run")
    thermostats = p.add_argument_group("validate-thermostats")
    thermostats.add_argument("--report-from", help="report a finished run from its CSV instead of running")
    thermostats.add_argument("--threads", type=int, default=1, help="CPU platform threads")
    return p.parse_args(argv)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv and argv[0] == "validate-minimization":  # every option is suite/minimization.py's own
        build = argv[argv.index("--build") + 1] if "--build" in argv else os.path.join(ROOT, "build")
        sys.path[:0] = [os.path.join(build, "python"), HERE]
        from suite import minimization
        return minimization.compare(argv[1:])
    args = parse(argv)
    sys.path[:0] = [os.path.join(args.build, "python"), HERE]
    from suite import accuracy, cost, langevin, long_drift, sampling
    from suite.common import git_commit, read_csv, write_csv
    import report

    out = args.out or (os.path.join(args.build, "results-quick") if args.quick else os.path.join(ROOT, "docs"))
    results_dir = os.path.join(out, "results")
    # The paper's rows go to the build (docs/results/ holds what the documents cite), or beside the report with --out.
    rows_dir = results_dir if args.out or args.quick else os.path.join(args.build, "results")
    os.makedirs(results_dir, exist_ok=True)
    git_commit()  # the commit the run starts at, for its stamps
    all_parts = TARGETS[args.target]
    parts = set(args.only.split(",")) if args.only else set(all_parts)
    started = time.time()

    def log(message):
        print("[%6.0f s] %s" % (time.time() - started, message), file=sys.stderr, flush=True)

    q = args.quick
    md = report.header(q)

    def rows(name, data):  # a part's rows, as a CSV
        write_csv(os.path.join(rows_dir, name + ".csv"), data)
        return data

    if "cost" in parts:  # first, while the machine is quietest
        log("cost: the integrators' own cost per step (forces excluded), then the paper's systems (forces included)")
        timings, ratios = cost.run(["Reference", "CPU"], [50] if q else [100, 1000, 3000], [3, 5] if q else [3, 5, 12, 30],
                                   2 if q else 7, 0.01 if q else 0.1, log, threads=[1, 2])
        rows("cost_step_times", timings), rows("cost_ratios", ratios)
        cost.plot(timings, os.path.join(results_dir, "cost_step_times.png"))
        prows = rows("cost_paper_systems", cost.paper_systems(["Reference", "CPU"], 1 if q else 7, 0.01 if q else 0.2, log))
        md += report.cost_section(timings, ratios, prows)

    if "accuracy" in parts:
        log("accuracy: isolated benzene, the 27-benzene and 5-site clusters, planar benzene, reversibility")
        steps = [1, 2] if q else [0.5, 1, 2, 4, 8]
        iso = rows("accuracy_isolated_benzene", accuracy.isolated_benzene(steps, 0.064 if q else 2.048, log))
        accuracy.plot_isolated(iso, os.path.join(results_dir, "accuracy_isolated_benzene.png"))
        energy = accuracy.energy_vs_step("27-benzene cluster", *accuracy.cluster_start(), ["M-RATTLE", "splitting"],
                                         steps, 0.1 if q else 4.096, log)
        # Reference platform: OpenMM 7.7's CPU platform turns this constrained system's
        # coordinates to NaN on the first Verlet step, which Reference does not.
        energy += accuracy.energy_vs_step("27 tetrahedral 5-site", *accuracy.tetrahedral_start(),
                                          ["M-RATTLE", "splitting", "RATTLE (CustomIntegrator)", "Verlet + CCMA"],
                                          steps, 0.1 if q else 4.0, log, platform="Reference")
        rows("accuracy_energy_vs_step", energy)
        accuracy.plot(energy, os.path.join(results_dir, "accuracy_energy_vs_step.png"), "Energy fluctuation against step size")
        planar = rows("accuracy_planar_constraints", accuracy.planar_benzene_with_constraints(0.05 if q else 0.5, log))
        rev_steps = [10, 50] if q else [10, 1000]
        rev = rows("accuracy_reversibility", accuracy.reversibility(rev_steps, 2.0, log))
        md += report.accuracy_section(iso, energy, accuracy.orders(energy), planar, q)
        md += report.reversibility_section(rev, rev_steps)

    if "sampling" in parts:
        log("sampling: independent NVE runs of the cluster, both methods")
        seeds = [11, 12] if q else [11, 12, 13, 14, 15, 16]
        per_run, eq, step = (0.8, 0.2, 4.0) if q else (24.0, 4.0, 4.0)
        res = {m: sampling.run_many(m, seeds, per_run, eq, step, 200.0, log) for m in ("M-RATTLE", "splitting")}
        sampling.plot(res, os.path.join(results_dir, "sampling_histograms.png"))
        md += report.sampling_section(rows("sampling_comparison", sampling.compare(res)), len(seeds), per_run, eq, step, q)

    if "drift" in parts:
        log("drift: long NVE of the 27-benzene cluster from equilibrated starts, both methods")
        # {step (fs): (ps per run, seeds)}: 200 ps at 4 fs from two starts, 100 ps at 2 fs from one
        # (a 2 fs run costs twice as much; the whole part takes about 11 minutes on 2 cores).
        dplan, deq, dsample = ({4.0: (0.4, [1])}, 0.4, 0.02) if q else ({4.0: (200.0, [1, 2]), 2.0: (100.0, [1])}, 100.0, 0.1)
        drows = long_drift.run(200.0, dplan, deq, dsample, 2.0, log)
        rows("long_drift", [{k: v for k, v in r.items() if not k.startswith("series_")} for r in drows])
        long_drift.plot(drows, os.path.join(results_dir, "long_drift.png"))
        md += report.long_drift_section(drows, 200.0, deq, dsample, 2.0)

    if "langevin" in parts:
        log("langevin: validation against LangevinMiddle + SETTLE (water NVT, NPT; liquid benzene)")
        md += langevin.run(q, os.path.join(results_dir, "langevin"), log)

    if "equipartition" in parts:
        log("equipartition: rigid TIP3P and SPC/E water, NVE at 0.5-4 fs (translational against rotational T)")
        from suite import equipartition
        md += equipartition.run(q, os.path.join(results_dir, "equipartition"), log)

    if "drude" in parts or "friction" in parts:  # their own tables, cited by docs/usage.md: results.md is left alone
        from suite import drude
        if "drude" in parts:
            drude.run(q, results_dir, log)
        if "friction" in parts:
            drude.friction_scan(q, results_dir, log)
        return 0

    if "thermostats" in parts:
        log("thermostats: Nose-Hoover chain and CSVR on rigid TIP3P water (canonical sampling, drift, diffusion)")
        from suite import thermostats
        if args.report_from:  # the section from a finished run's CSV (its settings: the full run's)
            md += thermostats.report(read_csv(args.report_from), 895, False, 20.0, 2.0, 2.0, 1)
        else:
            md += thermostats.run(q, os.path.join(results_dir, "thermostats"), log, args.threads)

    path = os.path.join(out, "results.md")
    command = [a for i, a in enumerate(argv) if a != "--build" and (i == 0 or argv[i - 1] != "--build")]
    report.write(path, md, " ".join(command), (time.time() - started) / 60)
    log("wrote %s" % path)


if __name__ == "__main__":
    sys.exit(main())
