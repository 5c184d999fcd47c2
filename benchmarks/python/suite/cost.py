"""Cost: time per step with forces excluded, from the C++ program benchmarks/cpp/step_cost."""
import csv
import io
import subprocess



def run_step_cost(binary, platforms, bodies, atoms, repeats, batch_seconds, log, threads=(1,)):
    """Run step_cost; returns (timing rows, ratio rows) parsed from its CSV output.
    threads: CPU thread counts (the first for every integrator, the others for verlet, mrattle, splitting)."""
    cmd = [binary, "--platforms", ",".join(platforms), "--bodies", ",".join(map(str, bodies)),
           "--atoms", ",".join(map(str, atoms)), "--repeats", str(repeats),
           "--batch-seconds", str(batch_seconds), "--threads", ",".join(map(str, threads)),
           "--out", "/dev/stdout", "--ratios", "/dev/stderr"]
    log("  " + " ".join(cmd))
    done = subprocess.run(cmd, check=True, capture_output=True, text=True)
    timings = list(csv.DictReader(io.StringIO(done.stdout)))
    ratios = list(csv.DictReader(io.StringIO(_csv_part(done.stderr))))
    return timings, ratios


def _csv_part(text):
    """step_cost may print progress lines on stderr; keep the CSV block (header onward)."""
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if "," in line and not line.startswith("#"):
            return "\n".join(lines[i:])
    return ""


def plot(timings, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    key_time = _time_key(timings)
    platforms = sorted({r["platform"] for r in timings})
    fig, axes = plt.subplots(1, len(platforms), figsize=(5.5 * len(platforms), 4.2), squeeze=False)
    atoms_for_n = 5 if any(int(r["atoms_per_body"]) == 5 for r in timings) else int(timings[0]["atoms_per_body"])
    for ax, platform in zip(axes[0], platforms):
        rows = [r for r in timings if r["platform"] == platform and int(r["atoms_per_body"]) == atoms_for_n]
        for integrator, threads in sorted({(r["integrator"], r.get("threads", "1")) for r in rows}):
            pts = sorted((int(r["bodies"]), float(r[key_time])) for r in rows
                         if r["integrator"] == integrator and r.get("threads", "1") == threads)
            label = integrator if threads == "1" else "%s (%s threads)" % (integrator, threads)
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o--" if threads != "1" else "o-", label=label)
        ax.set_xlabel("number of rigid bodies (k = %d atoms each)" % atoms_for_n)
        ax.set_ylabel("time per step (microseconds, median)")
        ax.set_title(platform)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _time_key(timings):
    for key in timings[0]:
        if key.startswith("median") or key.startswith("time"):
            return key
    raise KeyError("step_cost output has no timing column: %s" % list(timings[0]))


def micro_benchmarks(binary, log):
    """Google Benchmark timings of the numerical core: ns per body (and Newton iterations)."""
    import json
    done = subprocess.run([binary, "--benchmark_format=json", "--benchmark_min_time=0.2"], check=True,
                          capture_output=True, text=True)
    rows = []
    for b in json.loads(done.stdout)["benchmarks"]:
        name, _, k = b["name"].partition("/k:")
        row = {"benchmark": name, "atoms_per_body": int(k) if k else "", "ns_per_body": b["per_body"] * 1e9}
        if "newton_iterations" in b:
            row["newton_iterations"] = b["newton_iterations"]
        rows.append(row)
        log("  %-26s k=%-3s %8.1f ns per body" % (name, k, row["ns_per_body"]))
    return rows


def _perf_report(step_cost, step_args, sort, log):
    """perf record step_cost with step_args, then perf report sorted by `sort`: [(share %, name)]."""
    import os
    import shutil
    import tempfile
    if shutil.which("perf") is None:
        log("  perf is not installed (Debian: linux-perf): no profile")
        return []
    with tempfile.TemporaryDirectory() as scratch:
        data = os.path.join(scratch, "perf.data")
        record = subprocess.run(["perf", "record", "-q", "-o", data, "--", step_cost] + step_args +
                                ["--out", os.devnull, "--ratios", os.devnull], capture_output=True, text=True)
        if record.returncode != 0:
            log("  perf record failed: %s" % record.stderr.strip().splitlines()[-1:])
            return []
        report = subprocess.run(["perf", "report", "-i", data, "--stdio", "--no-children", "--sort", sort,
                                 "--percent-limit", "0.1"], capture_output=True, text=True)
    shares = []
    for line in report.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 2 and parts[0].endswith("%") and not line.lstrip().startswith("#"):
            name = " ".join(p for p in parts[1:] if p not in ("-", "[.]", "[k]"))
            shares.append((float(parts[0][:-1]), name))
    return shares


def profile(step_cost, atoms, log):
    """Where an M-RATTLE step spends its time (perf, if installed): symbol and share."""
    shares = _perf_report(step_cost, ["--platforms", "Reference", "--bodies", "1000", "--atoms", str(atoms),
                                      "--integrators", "mrattle", "--repeats", "5", "--batch-seconds", "0.2"],
                          "symbol", log)
    rows = [{"share_percent": share, "function": name} for share, name in shares if share >= 1]
    for r in rows[:6]:
        log("  %5.1f%%  %s" % (r["share_percent"], r["function"]))
    return rows


def thread_profile(step_cost, atoms_list, bodies, log):
    """Amdahl's bound on the 2-thread speed-up of an M-RATTLE step on the CPU platform.

    perf profiles a 1-thread run by library: the plugin's per-body work is split over the
    threads, OpenMM's own part of the step (its force call: clearing and summing force
    buffers, virtual-site passes) is not. With s the share of the plugin's work,
    a second thread can at best make the step 1 / (1 - s / 2) times faster."""
    rows = []
    for k in atoms_list:
        shares = _perf_report(step_cost, ["--platforms", "CPU", "--threads", "1", "--bodies", str(bodies), "--atoms",
                                          str(k), "--integrators", "mrattle", "--repeats", "5",
                                          "--batch-seconds", "0.2"], "dso", log)
        if not shares:
            return []
        plugin = sum(share for share, name in shares if name.startswith("libMRattle"))
        openmm = sum(share for share, name in shares if name.startswith("libOpenMM"))
        split = plugin / (plugin + openmm)
        rows.append({"atoms_per_body": k, "bodies": bodies, "plugin_percent": plugin, "openmm_percent": openmm,
                     "amdahl_bound": 1.0 / (1.0 - split / 2.0)})
        log("  k=%-3d plugin %.1f%%, OpenMM %.1f%% of samples: 2 threads at most %.2fx" % (
            k, plugin, openmm, rows[-1]["amdahl_bound"]))
    return rows


def _range_text(values, fmt="%.2f"):
    values = sorted(values)
    if not values:
        return "not run"
    return (fmt % values[0]) if len(values) == 1 else (fmt + " to " + fmt) % (values[0], values[-1])


def target_rows(ratios, micro, villin_ratio=None):
    """Issue 11's speed targets against this run's numbers: one row (target, measured, met) each.

    ratios: step_cost's ratio rows; micro: RigidBodyMathBenchmarks rows; villin_ratio: M-RATTLE's
    ns/day over Verlet's on the villin headpiece (None if not run)."""
    rows = []

    def add(target, values, met, fmt="%.2f", where=""):
        measured = _range_text(values, fmt) + (where if values else "")
        rows.append({"target": target, "measured": measured,
                     "met": "-" if not values else ("%d of %d" % (sum(met), len(met)) if len(met) > 1 else
                                                    ("yes" if met[0] else "no"))})

    def ratio_values(name, platform=None, atoms=None, min_bodies=1000):
        chosen = [r for r in ratios if r["ratio"] == name and int(r["bodies"]) >= min_bodies and
                  (platform is None or r["platform"] == platform) and
                  (atoms is None or int(r["atoms_per_body"]) == atoms)]
        return [float(r["value"]) for r in chosen], [r["met"] == "yes" for r in chosen]

    def micro_values(name, atoms=None):
        return [r["ns_per_body"] for r in micro if r["benchmark"] == name and
                (atoms is None or r["atoms_per_body"] == atoms)]

    solve = micro_values("SolveResetRotation")
    add("rotation solve <= 80 ns per body (k = 3 to 30)", solve, [max(solve) <= 80] if solve else [], "%.0f", " ns")
    projection = micro_values("ProjectBodyVelocities", 5)
    add("velocity projection <= 40 ns per 5-atom body", projection, [v <= 40 for v in projection], "%.0f", " ns")
    for platform in ("Reference", "CPU"):
        values, met = ratio_values("mrattle/verlet", platform)
        add("M-RATTLE <= 1.5x VerletIntegrator, %s, 1000 and 3000 bodies of 3-30 atoms" % platform, values, met)
    for platform in ("Reference", "CPU"):
        values, met = ratio_values("mrattle/verlet_settle", platform, 3)
        add("rigid water: M-RATTLE <= 1.0x Verlet + SETTLE, %s" % platform, values, met)
    values, met = ratio_values("verlet_ccma/mrattle", None, 5)
    add("5-atom bodies: Verlet + CCMA >= 2x M-RATTLE's time", values, met)
    values, met = ratio_values("mrattle threads 1/2", "CPU", None, 3000)
    add("CPU Threads=2 >= 1.7x faster than Threads=1, 3000 bodies", values, met)
    if villin_ratio is not None:
        add("villin in water, CPU, 2 threads: ns/day >= Verlet + SETTLE + CCMA", [villin_ratio],
            [villin_ratio >= 1.0], "%.3f", " x Verlet's ns/day")
    values, met = ratio_values("mrattle/splitting")
    add("M-RATTLE no slower than the splitting method", values, met)
    return rows
