"""The report writer of the benchmark suite: docs/results.md from the rows that run_suite.py's
parts return (tables, the reading of each result, the splice of a partial run)."""
import datetime
import math
import os
import platform as pyplatform

import mrattle
from suite import common


def header(quick):
    """The title and the line naming the run, its machine, the plugin's version and Python."""
    return ["# Benchmark results\n",
            "Written by `./benchmarks/run.sh`'s targets (`docs/benchmarks.md`)%s: each section is stamped with the run "
            "its numbers come from (command, date, commit, machine). Timings on these shared machines are noisy, so "
            "compare ratios taken within a run. Python %s.\n"
            % (" (**quick** smoke runs: they show nothing)" if quick else "", pyplatform.python_version())]


def write(path, md, command, minutes):
    """Write results.md: the run's own sections, stamped with the run, replace theirs in the file (or
    start it); the other sections keep their runs' numbers and stamps. md begins with header()."""
    started = datetime.datetime.utcnow() - datetime.timedelta(minutes=minutes)
    stamp = "*From `./benchmarks/run.sh %s`, %s UTC (%.1f minutes), commit %s, %s; M-RATTLE plugin %s.*\n" % (
        command, started.strftime("%Y-%m-%d %H:%M"), minutes, common.git_commit(),
        common.machine_description(), mrattle.__version__)
    existing = ""
    if os.path.exists(path):
        with open(path) as f:
            existing = f.read()
    heading = len(header(False))
    text = splice_sections(existing, "\n".join(md[:heading]), "\n".join(md[heading:]), stamp)
    with open(path, "w") as f:
        f.write(text)


def _sections(text):
    """Split markdown into (preamble, [(level-2 heading, text)]) ."""
    chunks = ("\n" + text).split("\n## ")
    return chunks[0], [(c.split("\n", 1)[0], "\n## " + c) for c in chunks[1:]]


def splice_sections(existing, preamble, regenerated, stamp):
    """The preamble, then the level-2 sections of `existing` with those `regenerated` has (by heading)
    replaced, stamped, and new ones appended."""
    _, old = _sections(existing)
    _, new = _sections(regenerated)
    new = [(title, _stamped(body, stamp)) for title, body in new]
    titles = [t for t, _ in old]
    merged = [dict(new).get(t, body) for t, body in old] + [body for t, body in new if t not in titles]
    # One blank line before every heading, whatever the spliced section ended with.
    return preamble.strip("\n") + "\n" + "\n".join(body.rstrip("\n") for body in merged) + "\n"


def _stamped(body, stamp):
    heading, rest = body.lstrip("\n").split("\n", 1)
    return "\n" + heading + "\n\n" + stamp + rest


def table(rows, columns, formats=None):
    """A markdown table: columns [(title, row key or function of the row)], formats {title: %-format of numbers}."""
    def cell(r, title, key):
        value = r.get(key, "") if isinstance(key, str) else key(r)
        fmt = (formats or {}).get(title)
        ok = fmt and isinstance(value, (int, float)) and not (isinstance(value, float) and math.isnan(value))
        return str(fmt % value if ok else value)
    lines = ["| " + " | ".join(c for c, _ in columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    lines += ["| " + " | ".join(cell(r, title, key) for title, key in columns) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def method(section, detail=""):
    """The line pointing at the section's method in docs/benchmarks.md, with the run's own settings."""
    return "%sThe method: `docs/benchmarks.md`, \"%s\".\n" % (detail + " " if detail else "", section)


def accuracy_section(iso, rows, order_rows, planar, quick):
    md = ["\n## Accuracy\n", "### Isolated rigid benzene (free rotor)\n", method("Accuracy")]
    md.append(table(iso, [("method", "method"), ("step (fs)", "step_fs"), ("max abs(E-E0)/E0", "energy_rel_error"),
                          ("abs(L-L0)/abs(L0)", "angmom_rel_error"), ("position error (nm)", "position_error_nm"),
                          ("rigidity (nm)", "rigidity_nm")],
                    {"max abs(E-E0)/E0": "%.2e", "abs(L-L0)/abs(L0)": "%.2e", "position error (nm)": "%.2e",
                     "rigidity (nm)": "%.1e"}))
    md.append("![isolated benzene](results/accuracy_isolated_benzene.png)\n")
    md.append("### Energy error against step size\n")
    md.append(table(rows, [("system", "system"), ("method", "method"), ("step (fs)", "step_fs"),
                           ("std E (kJ/mol)", "fluctuation"),
                           ("drift (kJ/mol/ns)", lambda r: "%+.2g +- %.1g" % (r["drift_per_ns"], r["drift_error_per_ns"])
                            if math.isfinite(r["drift_per_ns"]) else "nan"),
                           ("rigidity (nm)", "rigidity_nm"), ("failure", "failure")],
                    {"std E (kJ/mol)": "%.3e", "rigidity (nm)": "%.1e"}))
    md.append("Fitted order of the energy fluctuation (log-log slope over the three smallest steps that ran):\n")
    md.append(table(order_rows, [("system", "system"), ("method", "method"), ("order", "order")], {"order": "%.2f"}))
    md.append("![energy vs step](results/accuracy_energy_vs_step.png)\n")
    md.append("### Planar benzene under OpenMM's distance constraints\n")
    md.append(table(planar, [("constraints per molecule", "constraints"), ("method", "method"),
                             ("steps run", "steps_run"), ("rigidity (nm)", "rigidity_nm"),
                             ("energy change (kJ/mol)", "energy_change"), ("wall (s)", "wall_s"), ("failure", "failure")],
                    {"rigidity (nm)": "%.2e", "energy change (kJ/mol)": "%+.3e", "wall (s)": "%.1f"}))
    return md


def reversibility_section(rows, step_counts):
    md = ["### Time reversibility\n"]
    md.append(table(rows, [("system", "system"), ("method", "method")] +
                    [("after %d steps (nm)" % n, "error_after_%d" % n) for n in step_counts],
                    {"after %d steps (nm)" % n: "%.2e" for n in step_counts}))
    if rows:
        first = "error_after_%d" % step_counts[0]
        rigid = [r[first] for r in rows if r["method"] in ("M-RATTLE", "splitting")]
        constrained = [r[first] for r in rows if r["method"] not in ("M-RATTLE", "splitting")]
        md.append("After %d steps M-RATTLE and the splitting method are back within %.1e nm (round-off); OpenMM's "
                  "RATTLE and CCMA within %.1e to %.1e nm, set by their constraint tolerance.\n" % (
                      step_counts[0], max(rigid), min(constrained), max(constrained)))
    return md


def cost_section(timings, ratios, paper_rows):
    md = ["\n## Cost per step, forces excluded\n", method("Cost per step")]
    md.append("Every ratio, against its target where it has one (`met` is `-` where it has none):\n")
    md.append(table(ratios, [(k, k) for k in ratios[0].keys()]) if ratios else "(no ratios)\n")
    md.append("All timings (microseconds per step):\n")
    keep = [k for k in timings[0].keys() if k in ("platform", "integrator", "threads", "atoms_per_body", "bodies",
                                                   "constraints_per_body", "median_us_per_step")]
    md.append(table(timings, [(k, k) for k in keep]))
    md.append("![cost](results/cost_step_times.png)\n")
    if paper_rows:
        md.append("### The paper's systems, forces included\n")
        md.append(table(paper_rows, [("system", "system"), ("platform", "platform"), ("method", "method"),
                                     ("us per step", "us_per_step")], {"us per step": "%.1f"}))
    return md


def sampling_section(rows, runs, per_run, eq, step, quick):
    md = ["\n## Sampling\n", method("Sampling", "%d runs per method of %g ps at %g fs, the first %g ps dropped." % (
        runs, per_run, step, eq))]
    md.append(table(rows, [("quantity", "quantity"), ("M-RATTLE mean", "M-RATTLE mean"),
                           ("splitting mean", "splitting mean"),
                           ("spread of run means", lambda r: r.get("spread of run means", "")),
                           ("KS D", "KS D"), ("KS p", "KS p"), ("independent samples", "independent samples")],
                    {"M-RATTLE mean": "%.4g", "splitting mean": "%.4g", "spread of run means": "%.3g",
                     "KS D": "%.3f", "KS p": "%.3f"}))
    md += sampling_verdict(rows, runs)
    md.append("![sampling](results/sampling_histograms.png)\n")
    return md


def sampling_verdict(rows, runs_per_method):
    """One line per quantity: the methods' difference in standard errors of the difference of two
    means of runs_per_method run means each, the standard error taken from the spread of run means."""
    scale = math.sqrt(2.0 / runs_per_method)
    lines = []
    for r in rows:
        spread = r.get("spread of run means")
        a, b = r.get("M-RATTLE mean"), r.get("splitting mean")
        if not all(isinstance(v, float) and math.isfinite(v) for v in (spread, a, b)) or spread <= 0:
            continue
        error = spread * scale
        lines.append("- %s: difference %.3g, standard error %.3g: %.1f SE, %s.\n" % (
            r["quantity"], abs(a - b), error, abs(a - b) / error,
            "beyond 2 SE" if abs(a - b) > 2 * error else "within 2 SE (no detectable difference)"))
    if not lines:
        return []
    return ["\nThe methods' difference against its standard error (the spread of run means times sqrt(2/%d), "
            "%d runs per method). With %d quantities, one of them beyond 2 SE is expected about %.0f%% of the time "
            "even if the methods sample alike, so a single such line is not evidence of a difference:\n\n" % (
                runs_per_method, runs_per_method, len(lines), 100 * (1 - 0.9545 ** len(lines))) + "".join(lines)]


def long_drift_section(rows, temperature, equilibrate_ps, sample_ps, radius):
    """Long NVE runs from equilibrated starts: drift with standard error per run, and what they show."""
    from suite import long_drift
    lengths = ", ".join("%g ps at %g fs" % (length, step) for step, length in sorted(
        {(r["step_fs"], round(r["length_ps"], 1)) for r in rows}, reverse=True))
    md = ["\n## Long-run energy drift\n", method("Long-run energy drift", "Starts equilibrated %g ps at %g K; NVE %s, energy every %g ps; departed: "
                     "beyond %g nm." % (equilibrate_ps, temperature, lengths, sample_ps, radius))]
    ordered = sorted(rows, key=lambda r: (-r["step_fs"], r["seed"], r["method"]))
    md.append(table(ordered, [("step (fs)", "step_fs"), ("seed", "seed"), ("method", "method"),
                              ("length (ps)", "length_ps"), ("T (K)", "temperature_K"),
                              ("std E (kJ/mol)", "fluctuation"),
                              ("drift (kJ/mol/ns)", lambda r: "%+.4f +- %.4f" % (r["drift_per_ns"], r["drift_error_per_ns"])
                               if math.isfinite(r["drift_per_ns"]) else "nan"),
                              ("verdict", "verdict"), ("departed", "departed"), ("farthest (nm)", "farthest_nm"),
                              ("rigidity (nm)", "rigidity_nm"), ("wall (s)", "wall_s"), ("failure", "failure")],
                    {"step (fs)": "%g", "length (ps)": "%.1f", "T (K)": "%.1f", "std E (kJ/mol)": "%.3g", "farthest (nm)": "%.2f",
                     "rigidity (nm)": "%.1e", "wall (s)": "%.0f"}))
    md.append("![E(t) - E(0)](results/long_drift.png)\n")
    lines = ["- %g fs, %s: %d run%s, mean drift %+.4f kJ/mol/ns%s; %d of %d consistent with zero within 2 SE; largest "
             "|drift| + 2 SE %.4f kJ/mol/ns.\n" % (
                 s["step_fs"], s["method"], s["runs"], "" if s["runs"] == 1 else "s", s["mean_drift"],
                 (", spread (standard deviation) over runs %.4f" % s["spread"]) if math.isfinite(s["spread"]) else "",
                 s["zero_within_2se"], s["runs"], s["bound"]) for s in long_drift.summary(rows)]
    if lines:
        md.append("Per step size and method:\n\n" + "".join(lines))
    md += long_drift_reading(rows)
    return md


def long_drift_reading(rows, claim=0.03):
    """What the long runs show and cannot show, worded from their numbers."""
    from suite import long_drift
    finite = [r for r in rows if math.isfinite(r["drift_per_ns"]) and math.isfinite(r["drift_error_per_ns"])]
    if not finite:
        return ["No run gave a drift fit.\n"]
    name = lambda r: "%s %g fs seed %d" % (r["method"], r["step_fs"], r["seed"])  # noqa: E731
    zero = [r for r in finite if long_drift.within_se(r["drift_per_ns"], r["drift_error_per_ns"])]
    beyond = [r for r in finite if r not in zero]
    text = "\n%d of %d runs have a drift consistent with zero within 2 standard errors" % (len(zero), len(finite))
    if beyond:
        def chance(r):  # at least one of all runs beyond this run's z (two-sided normal tails)
            p = math.erfc(abs(r["drift_per_ns"]) / r["drift_error_per_ns"] / math.sqrt(2))
            return 1 - (1 - p) ** len(finite)
        text += "; %s. " % "; ".join(
            "%s is %.1f SE from zero, with %d molecule%s departed (were every drift zero and the standard errors "
            "right, at least one of %d runs would land that far from zero with probability %.2g%%)" % (
                name(r), abs(r["drift_per_ns"]) / r["drift_error_per_ns"], r["departed"],
                "" if r["departed"] == 1 else "s", len(finite), 100 * chance(r)) for r in beyond)
    else:
        text += ". "
    bounds = {name(r): abs(r["drift_per_ns"]) + 2 * r["drift_error_per_ns"] for r in finite}
    over = [n for n, b in bounds.items() if b >= claim]
    above = [name(r) for r in finite if abs(r["drift_per_ns"]) - 2 * r["drift_error_per_ns"] > claim]
    largest = max(abs(r["drift_per_ns"]) for r in finite)
    if not over:
        text += ("Every run's |drift| + 2 SE is below %g kJ/mol/ns (largest %.4f): these runs agree with the "
                 "independent measurement that both methods drift by less than %g kJ/mol/ns over 200-400 ps from "
                 "an equilibrated start. " % (claim, max(bounds.values()), claim))
    else:
        text += ("Against the independent measurement that both methods drift by less than %g kJ/mol/ns over "
                 "200-400 ps from an equilibrated start: %d of %d runs bound |drift| + 2 SE below it; in %s it "
                 "reaches %.4f, so %s cannot confirm that bound%s. The largest drift estimate itself is %.4f "
                 "kJ/mol/ns in magnitude. " % (
                     claim, len(finite) - len(over), len(finite), ", ".join(over), max(bounds.values()),
                     "that run" if len(over) == 1 else "those runs",
                     ("; in %s the drift exceeds it by more than 2 SE" % ", ".join(above)) if above else "",
                     largest))
    pairs = {}
    for r in finite:
        pairs.setdefault((r["step_fs"], r["seed"]), {})[r["method"]] = r
    differ = [(k, p) for k, p in pairs.items() if len(p) == 2 and abs(p["M-RATTLE"]["drift_per_ns"] -
              p["splitting"]["drift_per_ns"]) > 2 * math.hypot(p["M-RATTLE"]["drift_error_per_ns"],
                                                                  p["splitting"]["drift_error_per_ns"])]
    both = [k for k, p in pairs.items() if len(p) == 2]
    if both:
        text += ("From the same start, the two methods' drifts differ by more than 2 combined standard errors "
                 "(the root sum of squares of the two) in %d of %d cases%s. " % (len(differ), len(both), (" (%s)" % ", ".join(
                     "%g fs seed %d" % k for k, _ in differ)) if differ else ""))
    gone = sum(r["departed"] for r in rows)
    text += ("%s. " % ("No molecule left the cluster in any run" if gone == 0 else
                       "Molecules left the cluster in %d of %d runs (%d in all)" % (
                           sum(1 for r in rows if r["departed"]), len(rows), gone)))
    return [text.rstrip() + "\n"]
