"""The benchmark suite's --quick mode: it runs end to end and its numbers make sense."""
import csv
import os
import subprocess
import sys

import mrattle

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The build tree's package lives in <build>/python/mrattle.
BUILD = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(mrattle.__file__))))
SUITE = os.path.join(ROOT, "benchmarks", "python")
sys.path.insert(0, SUITE)  # run_suite, report and the suite package


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def test_quick_suite_writes_every_section(tmp_path):
    # The cost section needs the C++ step_cost program, built unless MRATTLE_BUILD_BENCHMARKS=OFF.
    has_step_cost = os.path.exists(os.path.join(BUILD, "benchmarks", "cpp", "step_cost"))
    parts = "accuracy,cost,sampling,gains" if has_step_cost else "accuracy,sampling,gains"
    subprocess.run([sys.executable, os.path.join(SUITE, "run_suite.py"), "--quick", "--build", BUILD,
                    "--out", str(tmp_path), "--only", parts], check=True, timeout=600)
    text = (tmp_path / "results.md").read_text()
    for heading in ("## Accuracy", "## Sampling", "## What a user gains") + (("## Cost per step",) if has_step_cost else ()):
        assert heading in text
    results = tmp_path / "results"
    for png in ("accuracy_isolated_benzene.png", "accuracy_energy_vs_step.png", "sampling_histograms.png") + \
            (("cost_step_times.png",) if has_step_cost else ()):
        assert (results / png).stat().st_size > 1000

    # M-RATTLE is RATTLE: on the non-planar cluster the energy fluctuations agree.
    rows = read(results / "accuracy_energy_vs_step.csv")
    for h in ("1", "2"):
        m = [r for r in rows if r["system"].startswith("27 tetrahedral") and r["method"] == "M-RATTLE"
             and float(r["step_fs"]) == float(h)][0]
        r = [r for r in rows if r["system"].startswith("27 tetrahedral") and r["method"].startswith("RATTLE")
             and float(r["step_fs"]) == float(h)][0]
        assert abs(float(m["fluctuation"]) - float(r["fluctuation"])) < 1e-3 * float(r["fluctuation"])
        assert float(m["rigidity_nm"]) < 1e-10

    # The free benzene conserves energy and angular momentum to round-off under M-RATTLE.
    for r in read(results / "accuracy_isolated_benzene.csv"):
        if r["method"] == "M-RATTLE":
            assert float(r["energy_rel_error"]) < 1e-11
            assert float(r["angmom_rel_error"]) < 1e-11

    # The constraint set the non-planar runs use is one CCMA converges on.
    ccma = {r["omitted pair"]: r for r in read(results / "accuracy_ccma_subsets.csv")}
    assert ccma["0-1"]["converged"] == "True"

    # Planar benzene: M-RATTLE keeps every distance.
    for r in read(results / "accuracy_planar_constraints.csv"):
        if r["method"] == "M-RATTLE":
            assert r["failure"] == ""
            assert float(r["rigidity_nm"]) < 1e-10

    # Steady-state sampling of liquid benzene: physical numbers, the P-conserved equipartition target.
    liquid = {r["quantity"]: r for r in read(results / "sampling_liquid_comparison.csv")}
    assert 200 < float(liquid["temperature (K)"]["M-RATTLE mean"]) < 450
    assert abs(float(liquid["equipartition target for that ratio (P conserved)"]["M-RATTLE mean"]) - 64 / 63) < 1e-12

    if has_step_cost:
        # The cost part: issue 11's targets in one table; SETTLE water and 2 threads were timed.
        assert "### Speed targets (issue 11)" in text
        ratios = {r["ratio"] for r in read(results / "cost_ratios.csv")}
        assert {"mrattle/verlet", "mrattle/verlet_settle", "verlet_ccma/mrattle", "mrattle threads 1/2"} <= ratios
        paper = read(results / "cost_paper_systems.csv")
        assert {r["method"] for r in paper} == {"M-RATTLE", "splitting"}
        assert all(float(r["us_per_step"]) > 0 for r in paper)

    # Reversibility: the rigid-body methods return to round-off, OpenMM's constrained ones to their tolerance.
    assert "### Time reversibility" in text
    for r in read(results / "accuracy_reversibility.csv"):
        if r["method"] in ("M-RATTLE", "splitting"):
            assert float(r["error_after_10"]) < 1e-13, r
        elif "tolerance 1e-08" in r["method"]:
            assert float(r["error_after_10"]) > 1e-11, r


def test_a_partial_run_replaces_only_its_own_sections():
    import report
    existing = "# Results\n\nintro\n\n## Cost\n\nold cost\n\n## Accuracy\n\nold accuracy\n### Sub\nold\n" \
               "\n## Sampling\n\nold sampling\n\nTotal wall time of this run: 3.0 minutes.\n"
    merged = report.splice_sections(existing, "\n## Accuracy\n\nnew accuracy\n\n## Extra\n\nnew extra\n", "*stamp*\n")
    assert "old accuracy" not in merged and "### Sub" not in merged and "new accuracy" in merged
    assert merged.index("## Cost") < merged.index("## Accuracy") < merged.index("## Sampling") < merged.index("## Extra")
    assert "old cost" in merged and "old sampling" in merged and merged.startswith("# Results\n\nintro")
    assert merged.count("*stamp*") == 2 and merged.index("*stamp*") > merged.index("## Accuracy")
    assert merged.rstrip().endswith("Total wall time of this run: 3.0 minutes.")


def test_quick_langevin_validation_writes_its_section(tmp_path):
    subprocess.run([sys.executable, os.path.join(SUITE, "run_suite.py"), "--quick", "--build", BUILD,
                    "--out", str(tmp_path), "--only", "langevin"], check=True, timeout=600)
    text = (tmp_path / "results.md").read_text()
    assert "## Langevin dynamics with M-RATTLE" in text and "density at 1 bar" in text and "liquid benzene" in text
    rows = {r["quantity"]: r for r in read(tmp_path / "results" / "langevin.csv")}
    # Short runs conclude nothing, but the numbers are physical.
    assert 200 < float(rows["T"]["mrattle"]) < 400 and 200 < float(rows["T"]["settle"]) < 400
    assert 0.8 < float(rows["density"]["mrattle"]) < 1.2
    assert 1.5 < float(rows["gOO_peak"]["mrattle"]) < 4


def test_drift_standard_error_covers_the_true_slope():
    import numpy as np
    from suite import stats
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 10.0, 2001)  # ps
    errors = []
    for _ in range(200):
        # Correlated noise (AR(1), correlation time 20 samples): the naive error would be ~6x too small.
        noise = np.zeros(t.size)
        for i in range(1, t.size):
            noise[i] = 0.95 * noise[i - 1] + rng.normal()
        slope, se = stats.drift_with_error(t, 0.002 * t + 0.1 * noise)
        errors.append((slope - 2.0) / se)
    errors = np.array(errors)
    # Standardised errors: about unit spread, so the reported error bars are honest (not 6x small).
    assert 0.7 < errors.std() < 1.4, errors.std()
    assert abs(errors.mean()) < 0.3


def test_a_rigid_step_counts_as_stable_only_within_its_error_bars():
    from suite import gains

    def row(step, drift, error):
        return {"integrator": "MRattleIntegrator", "failure": None, "step_fs": step, "dof": 100,
                "drift_per_ns": drift, "drift_error_per_ns": error}
    rows = [row(4, 0.5, 0.1), row(6, 0.1, 1.0), row(8, float("nan"), float("nan"))]
    # 6 fs has the smaller drift but error bars too wide to show it meets 0.01 per DOF; 8 fs has none.
    assert gains.largest_stable(rows, 0.01)["step_fs"] == 4
    assert gains.largest_stable(rows, 0.001) is None


def test_quick_long_drift_gives_finite_drifts_with_error_bars(tmp_path):
    subprocess.run([sys.executable, os.path.join(SUITE, "run_suite.py"), "--quick", "--build", BUILD,
                    "--out", str(tmp_path), "--only", "drift"], check=True, timeout=300)
    text = (tmp_path / "results.md").read_text()
    assert "## Long-run energy drift" in text and "consistent with zero within 2 standard errors" in text
    assert (tmp_path / "results" / "long_drift.png").stat().st_size > 1000
    rows = read(tmp_path / "results" / "long_drift.csv")
    assert {r["method"] for r in rows} == {"M-RATTLE", "splitting"}
    import math
    for r in rows:
        assert r["failure"] == ""
        assert math.isfinite(float(r["drift_per_ns"])) and float(r["drift_error_per_ns"]) > 0, r
        assert float(r["rigidity_nm"]) < 1e-10
        assert 100 < float(r["temperature_K"]) < 400


def test_departed_molecules_are_counted_around_the_cluster_that_remains():
    import numpy as np
    from suite import long_drift
    grid = np.array([(i, j, k) for i in range(3) for j in range(3) for k in range(3)], float) * 0.5
    grid -= grid.mean(0)
    assert long_drift.departed(grid, 2.0)[0] == 0
    # One molecule 100 nm away drags the plain centre of mass 3.7 nm off the other 26: counting
    # around that centre would call all 27 departed. Around the cluster that remains, just one.
    far = grid.copy()
    far[0] = [100.0, 0.0, 0.0]
    gone, farthest = long_drift.departed(far, 2.0)
    assert gone == 1 and farthest < 1.0
    far[26] = [0.0, -30.0, 5.0]
    assert long_drift.departed(far, 2.0)[0] == 2


def test_net_motion_removal_zeroes_momentum_and_angular_momentum_and_keeps_bodies_rigid():
    import numpy as np
    from suite import long_drift
    rng = np.random.default_rng(3)
    x = rng.normal(size=(12, 3))
    m = rng.uniform(1.0, 16.0, size=12)
    # Two rigid bodies of 6 atoms each: v = V + w x r within each.
    v = np.concatenate([rng.normal(size=3) + np.cross(rng.normal(size=3), x[b] - x[b].mean(0))
                        for b in (slice(0, 6), slice(6, 12))])
    u = long_drift.without_net_motion(x, v, m)
    c = m.dot(x) / m.sum()
    assert np.abs(m.dot(u)).max() < 1e-12
    assert np.abs((m[:, None] * np.cross(x - c, u)).sum(0)).max() < 1e-12
    # Rigid: the rate of change of every intra-body distance is still zero.
    for b in (range(0, 6), range(6, 12)):
        for i in b:
            for j in b:
                assert abs(np.dot(x[i] - x[j], u[i] - u[j])) < 1e-12


def test_drift_verdicts_follow_the_error_bars():
    import report
    from suite import long_drift
    assert long_drift.verdict(0.03, 0.02) == "consistent with zero within 2 SE"
    assert long_drift.verdict(-0.05, 0.02).startswith("nonzero (loss")
    assert long_drift.verdict(float("nan"), 0.02) == "no fit"

    def row(method, drift, error, seed=1):
        return {"method": method, "step_fs": 4.0, "seed": seed, "drift_per_ns": drift, "drift_error_per_ns": error,
                "departed": 0}
    small = [row("M-RATTLE", 0.004, 0.005), row("splitting", -0.002, 0.004)]
    text = "".join(report.long_drift_reading(small))
    assert "2 of 2 runs have a drift consistent with zero" in text and "agree with the independent" in text
    large = [row("M-RATTLE", 0.004, 0.02), row("splitting", 0.1, 0.01)]
    text = "".join(report.long_drift_reading(large))
    assert "1 of 2 runs" in text and "cannot confirm" in text and "in 1 of 1 cases" in text
    assert "splitting 4 fs seed 1 is 10.0 SE from zero" in text and "exceeds it by more than 2 SE" in text


def test_speed_target_rows_count_what_was_met():
    from suite import cost

    def ratio(platform, k, bodies, name, value, met):
        return {"platform": platform, "atoms_per_body": str(k), "bodies": str(bodies), "ratio": name,
                "value": str(value), "target": "", "met": met}
    ratios = [ratio("Reference", 3, 3000, "mrattle/verlet", 3.2, "no"),
              ratio("Reference", 30, 3000, "mrattle/verlet", 1.4, "yes"),
              ratio("Reference", 3, 100, "mrattle/verlet", 9.0, "no"),   # below 1000 bodies: not counted
              ratio("CPU", 3, 3000, "mrattle threads 1/2", 1.8, "yes"),
              ratio("CPU", 3, 1000, "mrattle threads 1/2", 1.2, "-")]   # below 3000 bodies: not counted
    micro = [{"benchmark": "SolveResetRotation", "atoms_per_body": k, "ns_per_body": ns} for k, ns in ((3, 70), (5, 90))]
    micro.append({"benchmark": "ProjectBodyVelocities", "atoms_per_body": 5, "ns_per_body": 35.0})
    rows = cost.target_rows(ratios, micro, villin_ratio=0.97)
    by_start = lambda start: [r for r in rows if r["target"].startswith(start)]
    assert by_start("rotation solve")[0]["met"] == "no"          # 90 ns > 80
    assert by_start("rotation solve")[0]["measured"] == "70 to 90 ns"
    assert by_start("velocity projection")[0]["met"] == "yes"
    reference = [r for r in by_start("M-RATTLE <= 1.5x") if "Reference" in r["target"]][0]
    assert reference["met"] == "1 of 2" and reference["measured"] == "1.40 to 3.20"
    assert by_start("CPU Threads=2")[0]["met"] == "yes" and by_start("CPU Threads=2")[0]["measured"] == "1.80"
    assert by_start("villin")[0]["met"] == "no"
    assert [r for r in by_start("rigid water") if "Reference" in r["target"]][0]["measured"] == "not run"


def test_sampling_verdict_counts_standard_errors_of_the_difference():
    import report
    rows = [{"quantity": "a", "M-RATTLE mean": 1.0, "splitting mean": 1.5, "spread of run means": 0.5},
            {"quantity": "b", "M-RATTLE mean": 1.0, "splitting mean": 2.0, "spread of run means": 0.5}]
    text = "".join(report.sampling_verdict(rows, 8))   # SE = 0.5 * sqrt(2/8) = 0.25
    assert "- a: difference 0.5, standard error 0.25: 2.0 SE, within 2 SE" in text
    assert "- b: difference 1, standard error 0.25: 4.0 SE, beyond 2 SE" in text


def test_every_method_counts_degrees_of_freedom_with_the_package():
    """One count for the four methods the suite compares: the plugin's from the integrator,
    the constrained baselines' as OpenMM counts them (9 independent constraints per 5-site
    molecule: 6 left each, as for the rigid body)."""
    from suite import common
    system, positions, bodies = common.tetrahedral_cluster(num_per_side=2, constraints=9)
    velocities = common.rigid_velocities(system, positions, bodies, 200.0)
    for method in ("M-RATTLE", "splitting", "RATTLE (CustomIntegrator)", "Verlet + CCMA"):
        run = common.nve_run(system, positions, velocities, method, 0.001, 0.002, 0.001, "Reference", bodies)
        assert run["failure"] is None
        assert run["dof"] == 6*8 == mrattle.degreesOfFreedom(run["context"])


def test_minimization_starts_runs_both_minimizers_from_each_start(tmp_path):
    # Two starts at a loose tolerance: every number of the docs' table comes out and makes sense.
    out, plot = tmp_path / "starts.csv", tmp_path / "starts.png"
    subprocess.run([sys.executable, os.path.join(SUITE, "minimization_starts.py"), "--build", BUILD, "--starts", "2",
                    "--tolerances", "40", "--out", str(out), "--plot", str(plot)], check=True, timeout=600)
    rows = read(out)
    assert [int(r["start"]) for r in rows] == [0, 1]
    start_energy = -36024.6  # tip3p.pdb with exact waters (docs/minimization.md); moved waters start higher
    for r in rows:
        assert float(r["rigid_rms_force"]) <= 40
        assert float(r["rigid_energy"]) < start_energy - 1000
        assert float(r["openmm_energy"]) < start_energy - 1000
        assert abs(float(r["gap"]) - (float(r["rigid_energy"]) - float(r["openmm_energy"]))) < 1e-6
        assert float(r["matched_rigid_energy"]) < start_energy - 1000
        assert abs(float(r["matched_gap"]) - (float(r["matched_rigid_energy"]) - float(r["openmm_energy"]))) < 1e-6
        assert (r["openmm_end_passes_rigid_test"] == "True") == (float(r["openmm_rms_force"]) <= 40)
    assert plot.stat().st_size > 1000
