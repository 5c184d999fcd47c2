"""Cost: time per step with forces excluded, from the C++ program benchmarks/cpp/step_cost."""
import csv
import io
import subprocess

from . import common


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
    plt = common.pyplot()
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
    common.save_figure(fig, path)


def _time_key(timings):
    for key in timings[0]:
        if key.startswith("median") or key.startswith("time"):
            return key
    raise KeyError("step_cost output has no timing column: %s" % list(timings[0]))
