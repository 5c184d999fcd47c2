"""What keeps the benchmark suite's figures honest: its error bars and verdicts (drift standard errors), its
degree-of-freedom count, every configuration of the cost part running and staying finite, and one quick run of
the paper's accuracy part, whose numbers must say that M-RATTLE is RATTLE."""
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


def test_quick_accuracy_part_finds_m_rattle_is_rattle(tmp_path):
    subprocess.run([sys.executable, os.path.join(SUITE, "run_suite.py"), "paper", "--quick", "--build", BUILD,
                    "--out", str(tmp_path), "--only", "accuracy"], check=True, timeout=600)
    text = (tmp_path / "results.md").read_text()
    assert "## Accuracy" in text and "M-RATTLE plugin %s" % mrattle.__version__ in text
    results = tmp_path / "results"

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
    assert all(r["failure"] == "" for r in rows if r["system"].startswith("27 tetrahedral")
               and r["method"] == "Verlet + CCMA")

    # Planar benzene: M-RATTLE keeps every distance.
    for r in read(results / "accuracy_planar_constraints.csv"):
        if r["method"] == "M-RATTLE":
            assert r["failure"] == ""
            assert float(r["rigidity_nm"]) < 1e-10

    # Reversibility: the rigid-body methods return to round-off, OpenMM's constrained ones to their tolerance.
    assert "### Time reversibility" in text
    for r in read(results / "accuracy_reversibility.csv"):
        if r["method"] in ("M-RATTLE", "splitting"):
            assert float(r["error_after_10"]) < 1e-13, r
        elif "tolerance 1e-08" in r["method"]:
            assert float(r["error_after_10"]) > 1e-11, r


def test_every_cost_configuration_runs_and_stays_finite():
    from suite import cost
    timings, _ = cost.run(["Reference", "CPU"], [8], [3, 5], 1, 0.001, lambda message: None, threads=[1, 2])
    assert {r["integrator"] for r in timings} == {"verlet", "mrattle", "splitting", "mrattle_allpairs", "verlet_ccma",
                                                  "verlet_settle"}
    assert all(r["finite"] == "yes" for r in timings)


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


def test_stamps_name_the_commit_or_unknown_without_git(monkeypatch):
    # OpenMM 8's leg tests a `git archive` copy in a root without git: the stamp says "unknown", the run goes on.
    from suite import common
    common.git_commit.cache_clear()
    monkeypatch.setenv("PATH", "/nonexistent")
    assert common.git_commit() == "unknown"
    common.git_commit.cache_clear()
