"""Accuracy: energy error against step size for M-RATTLE, splitting and OpenMM's own RATTLE."""
import math

import numpy as np
import openmm
from openmm import unit

import mrattle
from . import common, stats


def _positions(model):
    return np.array(model.positions.value_in_unit(unit.nanometer))


def _bodies(model):
    return mrattle.rigidBodies(model.topology, model.system, 'BNZ')


def _angular_momentum(system, state=None, x=None, v=None):
    if state is not None:
        x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    return (common.masses(system)[:, None] * np.cross(x, v)).sum(0)


def benzene_start():
    """One free benzene with rigid-body velocities at 300 K: (system, positions, velocities, bodies); this and the
    two below build afresh the starts that the energy runs and the reversibility test share."""
    model = mrattle.models.benzene()
    x = _positions(model)
    bodies = _bodies(model)
    return model.system, x, common.rigid_velocities(model.system, x, bodies, 300.0, seed=3), bodies


def cluster_start():
    """The 27-benzene cluster at 250 K (seed 1) with its own velocities: (system, positions, velocities, bodies)."""
    cluster = mrattle.models.benzeneCluster(temperature=250 * unit.kelvin, seed=1)
    v = np.array(cluster.velocities.value_in_unit(unit.nanometer / unit.picosecond))
    return cluster.system, _positions(cluster), v, _bodies(cluster)


def tetrahedral_start():
    """27 non-planar 5-site bodies with 9 constraints each, at 200 K: (system, positions, velocities, bodies)."""
    system, x, bodies = common.tetrahedral_cluster(constraints=9)
    return system, x, common.rigid_velocities(system, x, bodies, 200.0, seed=5), bodies


def isolated_benzene(steps_fs, total_ps, log):
    """Free rigid benzene: energy, angular momentum and trajectory error against a fine-step reference."""
    system, x0, v0, bodies = benzene_start()
    reference_step = min(steps_fs) / 16 * common.FS
    # Sample every 32 fs: a whole number of steps for every step size, so all runs end at total_ps.
    total_ps = max(1, round(total_ps / 0.032)) * 0.032
    ref = common.nve_run(system, x0, v0, "M-RATTLE", reference_step, total_ps, total_ps, "Reference", bodies)
    ref_positions = ref["context"].getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    L0 = _angular_momentum(system, x=x0, v=v0)
    rows = []
    for method in ("M-RATTLE", "splitting"):
        for h in steps_fs:
            run = common.nve_run(system, x0, v0, method, h * common.FS, total_ps, 0.032, "Reference", bodies)
            state = run["context"].getState(getPositions=True, getVelocities=True)
            L = _angular_momentum(system, state)
            e = run["total"]
            rows.append({"system": "isolated benzene", "method": method, "step_fs": h,
                         "energy_rel_error": float(np.max(np.abs(e - e[0])) / abs(e[0])),
                         "angmom_rel_error": float(np.linalg.norm(L - L0) / np.linalg.norm(L0)),
                         "position_error_nm": float(np.max(np.linalg.norm(
                             state.getPositions(asNumpy=True).value_in_unit(unit.nanometer) - ref_positions, axis=1))),
                         "rigidity_nm": float(run["rigidity"].max())})
            log("  isolated benzene %-9s h=%4.1f fs  |dE|/E=%.2e  |dL|/L=%.2e  x err=%.2e nm" % (
                method, h, rows[-1]["energy_rel_error"], rows[-1]["angmom_rel_error"], rows[-1]["position_error_nm"]))
    return rows


def energy_vs_step(label, system, positions, velocities, bodies, methods, steps_fs, total_ps, log, platform="CPU"):
    """Total-energy fluctuation (std) and drift per step size and method, one NVE run each."""
    rows = []
    for method in methods:
        for h in steps_fs:
            run = common.nve_run(system, positions, velocities, method, h * common.FS, total_ps, 0.008,
                                 platform, bodies)
            e = run["total"]
            ok = run["failure"] is None and len(e) > 2
            drift, drift_error = stats.drift_with_error(run["time"], e) if ok else (float("nan"), float("nan"))
            rows.append({"system": label, "method": method, "step_fs": h,
                         "fluctuation": float(np.std(e)) if ok else float("nan"),
                         "drift_per_ns": drift, "drift_error_per_ns": drift_error,
                         "rigidity_nm": float(run["rigidity"].max()) if run["rigidity"].size else float("nan"),
                         "failure": run["failure"] or "", "dof": run["dof"]})
            log("  %-22s %-26s h=%4.1f fs  std(E)=%.3e  drift=%+.3e kJ/mol/ns  rigid=%.1e  %s" % (
                label, method, h, rows[-1]["fluctuation"], rows[-1]["drift_per_ns"], rows[-1]["rigidity_nm"],
                rows[-1]["failure"]))
    return rows


def orders(rows):
    """Fitted order of the energy fluctuation per (system, method) over the finite points."""
    out = []
    keys = sorted({(r["system"], r["method"]) for r in rows if "fluctuation" in r})
    for system, method in keys:
        pts = [(r["step_fs"], r["fluctuation"]) for r in rows
               if r["system"] == system and r["method"] == method and math.isfinite(r["fluctuation"])
               and r["fluctuation"] > 0]
        # Fit where the error is asymptotic: the three smallest steps that ran.
        pts = sorted(pts)[:3]
        if len(pts) >= 2:
            out.append({"system": system, "method": method,
                        "order": stats.fitted_order([p[0] for p in pts], [p[1] for p in pts])})
    return out


def planar_benzene_with_constraints(total_ps, log):
    """OpenMM's constraint algorithms on the cluster's benzenes held by their 30 bond and angle distances (3N-6,
    enough for a non-planar molecule, not for planar benzene) or all 66 (redundant), beside M-RATTLE."""
    model = mrattle.models.benzeneCluster(temperature=250 * unit.kelvin, seed=2)
    x0 = _positions(model)
    v0 = np.array(model.velocities.value_in_unit(unit.nanometer / unit.picosecond))
    bodies = _bodies(model)
    sites = mrattle.models.benzeneSites()
    bonded = [(k, (k + 1) % 6) for k in range(6)] + [(k, k + 6) for k in range(6)]
    angles = [(k, (k + 2) % 6) for k in range(6)] + [((k + 1) % 6, k + 6) for k in range(6)] + \
             [((k - 1) % 6, k + 6) for k in range(6)]
    all_pairs = [(i, j) for i in range(12) for j in range(i + 1, 12)]
    rows = []
    for name, pairs in (("30 bond+angle distances", bonded + angles), ("all 66 pair distances", all_pairs)):
        system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(model.system))
        for body in bodies:
            for i, j in pairs:
                system.addConstraint(body[i], body[j], float(np.linalg.norm(sites[i] - sites[j])))
        for method in ("Verlet + CCMA", "RATTLE (CustomIntegrator)", "M-RATTLE"):
            run = common.nve_run(system, x0, v0, method, 1.0 * common.FS, total_ps, 0.01, "Reference", bodies,
                                 tolerance=1e-8)
            e = run["total"]
            rows.append({"constraints": name, "method": method, "steps_run": run["steps"],
                         "rigidity_nm": float(run["rigidity"].max()) if run["rigidity"].size else float("nan"),
                         "energy_change": float(e[-1] - e[0]) if len(e) > 1 else float("nan"),
                         "wall_s": run["wall"], "failure": run["failure"] or ""})
            log("  planar benzene, %-24s %-26s steps=%d rigid=%.2e dE=%.3e %s" % (
                name, method, rows[-1]["steps_run"], rows[-1]["rigidity_nm"], rows[-1]["energy_change"],
                rows[-1]["failure"]))
    return rows


def plot(rows, path, title):
    systems = sorted({r["system"] for r in rows})
    fig, axes = common.panels(len(systems))
    for ax, system in zip(axes, systems):
        for method in sorted({r["method"] for r in rows if r["system"] == system}):
            pts = sorted((r["step_fs"], r["fluctuation"]) for r in rows
                         if r["system"] == system and r["method"] == method and math.isfinite(r["fluctuation"]))
            if pts:
                ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=method)
        hs = np.array(sorted({r["step_fs"] for r in rows}))
        finite = [r["fluctuation"] for r in rows if r["system"] == system and math.isfinite(r["fluctuation"])]
        if finite:
            anchor = min(finite)
            ax.loglog(hs, anchor * (hs / hs[0]) ** 2, "k:", label="slope 2")
        ax.set_xlabel("step size (fs)")
        ax.set_ylabel("std of total energy (kJ/mol)")
        ax.set_title(system)
        ax.legend(fontsize=8)
    common.save_figure(fig, path, title)


def plot_isolated(rows, path):
    fig, axes = common.panels(2, 5, 4)
    for method in ("M-RATTLE", "splitting"):
        pts = sorted((r["step_fs"], r["energy_rel_error"], r["position_error_nm"]) for r in rows if r["method"] == method)
        axes[0].loglog([p[0] for p in pts], [max(p[1], 1e-17) for p in pts], "o-", label=method)
        axes[1].loglog([p[0] for p in pts], [p[2] for p in pts], "o-", label=method)
    axes[0].set_ylabel("max |E - E0| / E0")
    axes[1].set_ylabel("max atom position error at end (nm)")
    for ax in axes:
        ax.set_xlabel("step size (fs)")
        ax.legend()
    common.save_figure(fig, path, "Isolated rigid benzene (free rotor)")


def _forward_and_back(system, positions, velocities, method, step_ps, steps, bodies, tolerance=1e-10):
    """Run `steps` steps, reverse the velocities, run `steps` more (Reference platform): how far from the start it
    ends, the method's own irreversibility plus round-off (and a constrained method's tolerance)."""
    integrator = common.make_integrator(method, step_ps, tolerance, bodies)
    context = common.context(system, integrator, positions, velocities, "Reference")
    context.applyConstraints(tolerance)  # start exactly on the constraint surface for every method
    context.applyVelocityConstraints(tolerance)
    x0 = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    integrator.step(steps)
    state = context.getState(getVelocities=True, getForces=True)
    v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    if method == "Verlet + CCMA":
        # OpenMM's VerletIntegrator is leapfrog: it stores v(t - dt/2), so the reversed run
        # must start from -v(t + dt/2) = -(v(t - dt/2) + dt f(t)/m).
        f = state.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer)
        v = v + step_ps * f / common.masses(system)[:, None]
    context.setVelocities(-v)
    integrator.step(steps)
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    return float(np.max(np.linalg.norm(x - x0, axis=1)))


def reversibility(step_counts, step_fs, log):
    """Time reversibility of each method on the suite's systems (forward, reverse velocities, back)."""
    cases = [("isolated benzene", benzene_start(), ["M-RATTLE", "splitting"]),
             ("27-benzene cluster", cluster_start(), ["M-RATTLE", "splitting"]),
             ("27 tetrahedral 5-site", tetrahedral_start(),
              ["M-RATTLE", "splitting", "RATTLE (CustomIntegrator)", "Verlet + CCMA"])]
    rows = []
    for label, (system, x, v, bodies), methods in cases:
        for method in methods:
            constrained = method in ("Verlet + CCMA", "RATTLE (CustomIntegrator)")
            for tolerance in ([1e-8, 1e-10, 1e-12] if constrained else [None]):
                name = method + (" (tolerance %g)" % tolerance if constrained else "")
                row = {"system": label, "method": name, "step_fs": step_fs}
                for steps in step_counts:
                    row["error_after_%d" % steps] = _forward_and_back(
                        system, x, v, method, step_fs * common.FS, steps, bodies, tolerance or 1e-10)
                rows.append(row)
                log("  reversibility %-22s %-40s %s" % (label, name, "  ".join(
                    "%d: %.2e nm" % (n, row["error_after_%d" % n]) for n in step_counts)))
    return rows
