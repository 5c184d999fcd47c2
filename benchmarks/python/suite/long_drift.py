"""Long-run energy drift: NVE of the 27-benzene cluster from equilibrated starts, both methods."""
import numpy as np
import openmm
from openmm import unit

import mrattle
from . import common, sampling, stats
from .common import KB
METHODS = ("M-RATTLE", "splitting")


def equilibrated_start(temperature, seed, equilibrate_ps, log):
    """The cluster's lattice start (orientations and velocities from `seed`), equilibrated with
    M-RATTLE and an Andersen thermostat at `temperature` (K, 5/ps, seeded by `seed`; 200 steps of 1 fs,
    then 4 fs); returns (system, positions, velocities, bodies)."""
    model = mrattle.models.benzeneCluster(temperature=temperature * unit.kelvin, seed=seed)
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(model.system))
    thermostat = openmm.AndersenThermostat(temperature * unit.kelvin, 5 / unit.picosecond)
    thermostat.setRandomNumberSeed(seed)
    system.addForce(thermostat)
    integrator = mrattle.MRattleIntegrator(1 * unit.femtosecond)
    context = common.context(system, integrator, model.positions, (temperature * unit.kelvin, seed), "CPU", 1)
    integrator.step(200)
    integrator.setStepSize(4 * unit.femtosecond)
    integrator.step(int(equilibrate_ps / 0.004))
    state = context.getState(getPositions=True, getVelocities=True)
    x = np.array(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer))
    v = np.array(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond))
    bodies = mrattle.rigidBodies(model.topology, model.system, 'BNZ')
    return model.system, x, without_net_motion(x, v, common.masses(model.system)), bodies


def without_net_motion(x, v, masses):
    """Velocities less the whole system's centre-of-mass velocity and rigid rotation (both rigid motions, so every
    body stays rigid)."""
    mass = masses.sum()
    c = masses.dot(x) / mass
    v = v - masses.dot(v) / mass
    r = x - c
    L = (masses[:, None] * np.cross(r, v)).sum(0)
    return v - np.cross(np.linalg.solve(sampling._inertia(r, masses), L), r)


def molecule_centres(positions, system, bodies):
    masses = common.masses(system)
    return np.array([masses[b].dot(positions[b]) / masses[b].sum() for b in bodies])


def departed(centres, radius):
    """How many molecules are farther than `radius` (nm) from the centre of those that remain (from the centres'
    median, which far-away molecules cannot drag, as they drag the mean, until that set settles), and the
    farthest remaining one's distance."""
    centres = np.asarray(centres, float)
    centre = np.median(centres, axis=0)
    inside = None
    for _ in range(len(centres) + 1):
        distance = np.sqrt(((centres - centre) ** 2).sum(1))
        now = distance <= radius
        if not now.any():  # nothing within the radius of the centre: the cluster has dispersed
            return len(centres), float("nan")
        if inside is not None and (now == inside).all():
            break
        inside = now
        centre = centres[inside].mean(0)
    return int((~inside).sum()), float(distance[inside].max())


def run_one(system, positions, velocities, bodies, method, step_fs, total_ps, sample_ps, radius):
    """One long NVE run; drift with its standard error, fluctuation, departed molecules, rigidity."""
    r = common.nve_run(system, positions, velocities, method, step_fs * common.FS, total_ps, sample_ps, "CPU",
                       bodies, threads=1)
    t, e = r["time"], r["total"]
    ok = r["failure"] is None and len(e) > 3
    drift, error = stats.drift_with_error(t, e) if ok else (float("nan"), float("nan"))
    final = r["context"].getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    gone, farthest = departed(molecule_centres(np.array(final), system, bodies), radius)
    return {"method": method, "step_fs": step_fs, "length_ps": float(t[-1] - t[0]) if len(t) else 0.0,
            "temperature_K": float(np.mean(2 * r["kinetic"] / (r["dof"] * KB))),
            "fluctuation": float(np.std(e)) if len(e) else float("nan"), "drift_per_ns": drift,
            "drift_error_per_ns": error, "verdict": verdict(drift, error), "departed": gone, "farthest_nm": farthest,
            "rigidity_nm": float(r["rigidity"].max()) if r["rigidity"].size else float("nan"), "wall_s": r["wall"],
            "failure": r["failure"] or "", "series_time": t - t[0] if len(t) else t,
            "series_energy": e - e[0] if len(e) else e}


def within_se(drift, error, sigmas=2.0):
    return abs(drift) <= sigmas * error


def verdict(drift, error, sigmas=2.0):
    """Whether a drift differs from zero by more than `sigmas` standard errors, in words."""
    if not (np.isfinite(drift) and np.isfinite(error)):
        return "no fit"
    if within_se(drift, error, sigmas):
        return "consistent with zero within %g SE" % sigmas
    return "nonzero (%s, beyond %g SE)" % ("gain" if drift > 0 else "loss", sigmas)


def run(temperature, plan, equilibrate_ps, sample_ps, radius, log):
    """For each seed one equilibrated start, from it each method at each step size whose plan lists the seed
    (plan: {step_fs: (ps per run, [seeds])}): a row per run, with its E(t) - E(0) (series_time, series_energy)."""
    rows = []
    seeds = sorted({s for _, ss in plan.values() for s in ss})
    for seed in seeds:
        system, x, v, bodies = equilibrated_start(temperature, seed, equilibrate_ps, log)
        gone, farthest = departed(molecule_centres(x, system, bodies), radius)
        log("  drift: seed %d equilibrated (%g ps at %g K): %d molecules beyond %g nm, farthest %.2f nm" % (
            seed, equilibrate_ps, temperature, gone, radius, farthest))
        for step_fs in sorted(plan, reverse=True):
            total_ps, step_seeds = plan[step_fs]
            if seed not in step_seeds:
                continue
            for method in METHODS:
                row = run_one(system, x, v, bodies, method, step_fs, total_ps, sample_ps, radius)
                row.update(seed=seed, departed_at_start=gone)
                rows.append(row)
                log("  drift %-9s %g fs seed %d: %+.4f +- %.4f kJ/mol/ns, std E %.3g, T %.1f K, %d departed, %.0f s %s"
                    % (method, step_fs, seed, row["drift_per_ns"], row["drift_error_per_ns"], row["fluctuation"],
                       row["temperature_K"], row["departed"], row["wall_s"], row["failure"]))
    return rows


def summary(rows):
    """Per step size and method: the runs' mean drift, their spread, and the largest |drift| + 2 SE."""
    out = []
    for step_fs in sorted({r["step_fs"] for r in rows}):
        for method in METHODS:
            runs = [r for r in rows if r["step_fs"] == step_fs and r["method"] == method and np.isfinite(r["drift_per_ns"])]
            if not runs:
                continue
            d = np.array([r["drift_per_ns"] for r in runs])
            se = np.array([r["drift_error_per_ns"] for r in runs])
            out.append({"step_fs": step_fs, "method": method, "runs": len(runs), "mean_drift": float(d.mean()),
                        "spread": float(d.std(ddof=1)) if len(d) > 1 else float("nan"),
                        "bound": float(np.max(np.abs(d) + 2 * se)),
                        "zero_within_2se": int(sum(within_se(a, b) for a, b in zip(d, se)))})
    return out


def plot(rows, path, block_ps=5.0):
    """E(t) - E(0) per start and step size: every sample (faint), block means (bold) and the fitted line."""
    panels = sorted({(r["step_fs"], r["seed"]) for r in rows}, key=lambda k: (-k[0], k[1]))
    fig, axes = common.panels(len(panels))
    colours = {"M-RATTLE": "C0", "splitting": "C3"}
    for ax, (step_fs, seed) in zip(axes, panels):
        for r in rows:
            t, e = r["series_time"], r["series_energy"]
            if (r["step_fs"], r["seed"]) != (step_fs, seed) or len(t) < 4:
                continue
            c = colours[r["method"]]
            ax.plot(t, e, color=c, lw=0.4, alpha=0.25)
            per = max(1, int(round(block_ps / (t[1] - t[0]))))
            n = len(e) // per
            ax.plot(t[:n * per].reshape(n, per).mean(1), e[:n * per].reshape(n, per).mean(1), "o-", color=c, ms=2.5,
                    lw=1.2, label="%s, %g ps means" % (r["method"], block_ps))
            slope, intercept = np.polyfit(t, e, 1)
            ax.plot(t[[0, -1]], intercept + slope * t[[0, -1]], "--", color=c, lw=1.2,
                    label="fit: %+.4f +- %.4f kJ/mol/ns" % (r["drift_per_ns"], r["drift_error_per_ns"]))
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_title("%g fs, seed %d" % (step_fs, seed))
        ax.set_xlabel("time (ps)")
        ax.set_ylabel("E(t) - E(0) (kJ/mol)")
        ax.legend(fontsize=7)
    common.save_figure(fig, path, "27 rigid benzene molecules, NVE from equilibrated starts (faint: every sample)")
