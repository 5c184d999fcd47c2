"""Sampling: long NVE runs of the 27-benzene cluster with M-RATTLE and splitting, compared."""
import numpy as np
from openmm import unit

import mrattle
from . import common, stats
from .common import KB
LABELS = {"temperature": "temperature (6N DOF)", "radius": "farthest molecule from the centre of mass (nm)"}


def run_many(method, seeds, total_ps, equilibrate_ps, step_fs, temperature, log):
    """One run per seed (the same seeds for every method), equilibration dropped: {quantity: one array per run}, so
    that each run's series can be decorrelated on its own before the runs are pooled."""
    runs = [run(method, total_ps, step_fs, temperature, seed, log) for seed in seeds]
    return {key: [r[key][int(round(equilibrate_ps / r["frame_ps"])):] for r in runs]
            for key in ("temperature", "translational", "rotational", "cc", "target", "radius")}


def run(method, total_ps, step_fs, temperature, seed, log):
    """Sample kinetic temperature, per-molecule translational/rotational KE and intermolecular C-C distances."""
    model = mrattle.models.benzeneCluster(temperature=temperature * unit.kelvin, seed=seed)
    integrator = common.make_integrator(method, step_fs * common.FS)
    context = common.context(model.system, integrator, model.positions, model.velocities, "CPU", 1)
    n_mol = model.system.getNumParticles() // 12
    all_masses, bodies = common.masses(model.system), mrattle.rigidBodies(model.topology, model.system, 'BNZ')
    masses = all_masses[:12]
    dof = integrator.getNumDegreesOfFreedom()
    stride = max(1, int(round(0.1 / (step_fs * common.FS))))  # a frame every 100 fs
    frames = int(round(total_ps / (stride * step_fs * common.FS)))
    temps, trans, rot, cc, target, radius = [], [], [], [], [], []
    carbons = np.arange(6)
    for k in range(frames):
        integrator.step(stride)
        state = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
        ke = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        temps.append(2 * ke / (dof * KB))
        x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer).reshape(n_mol, 12, 3)
        ke_trans, ke_rot = common.rigid_split(  # per molecule, kJ/mol
            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond), all_masses, bodies)
        trans.append(ke_trans / n_mol)
        rot.append(ke_rot / n_mol)
        expected, farthest = equipartition_target(x, masses)
        target.append(expected)
        radius.append(farthest)
        c = x[:, carbons, :].reshape(-1, 3)
        mol = np.repeat(np.arange(n_mol), 6)
        d = np.sqrt(((c[:, None, :] - c[None, :, :]) ** 2).sum(-1))
        other = mol[:, None] < mol[None, :]
        cc.append(d[other])
        if k % max(1, frames // 4) == 0:
            log("  sampling %-9s seed %d %5.1f%%  T=%.1f K" % (method, seed, 100.0 * k / frames, temps[-1]))
    return {"temperature": np.array(temps), "translational": np.array(trans), "rotational": np.array(rot),
            "cc": np.array(cc), "target": np.array(target), "radius": np.array(radius),
            "frame_ps": stride * step_fs * common.FS}


def row(label, per_run):
    """One quantity's row from per_run, {method: [one array per run]}: means, the spread of run means, a KS test."""
    a, b = _decorrelated(per_run["M-RATTLE"]), _decorrelated(per_run["splitting"])
    d, p = stats.ks_two_sample(a, b)
    means = [r.mean() for runs in per_run.values() for r in runs]
    return {"quantity": label, "M-RATTLE mean": float(np.concatenate(per_run["M-RATTLE"]).mean()),
            "splitting mean": float(np.concatenate(per_run["splitting"]).mean()),
            "spread of run means": float(np.std(means, ddof=1)) if len(means) > 1 else float("nan"),
            "KS D": d, "KS p": p, "independent samples": (len(a), len(b))}


def _inertia(points, masses):
    """Inertia tensor of point masses about the origin."""
    return (masses * (points ** 2).sum(-1)).sum() * np.eye(3) - np.einsum("i,ij,ik->jk", masses, points, points)


def equipartition_target(x, masses):
    """Expected mean rotational / translational KE per molecule with total momentum P and angular momentum L
    conserved (P = 0 takes 3 translational degrees of freedom; L = 0 the 3 of a global rotation, shared between
    orbital motion and spin as tr(I_total^-1 I_orbital) to 3 - that), and the farthest molecule's distance from
    the centre of mass. x: (molecules, sites, 3) nm; masses: the sites' masses."""
    n = x.shape[0]
    mass = masses.sum()
    centres = (masses[None, :, None] * x).sum(1) / mass
    centres -= centres.mean(0)
    orbital = _inertia(centres, np.full(n, mass))
    spin = sum(_inertia(x[m] - x[m].T.dot(masses) / mass, masses) for m in range(n))
    f = float(np.trace(np.linalg.solve(orbital + spin, orbital)))
    return (3 * n - 3 + f) / (3 * n - 3 - f), float(np.sqrt((centres ** 2).sum(1)).max())


def _decorrelated(runs):
    """Each run's series thinned to roughly independent samples, then pooled."""
    return np.concatenate([stats.decorrelate(r) for r in runs])


def compare(results):
    """Means, KS tests on decorrelated pooled samples, and equipartition per method."""
    rows = [row(LABELS.get(name, name), {m: r[name] for m, r in results.items()})
            for name in ("temperature", "translational", "rotational", "radius")]
    # C-C distances: the per-frame fraction of pairs within the first peak (< 0.6 nm), a scalar series that
    # can be decorrelated; the pooled histograms are in the plot.
    rows.append(row("C-C pairs < 0.6 nm (fraction)",
                    {m: [(c < 0.6).mean(1) for c in r["cc"]] for m, r in results.items()}))
    # Equipartition: rotational over translational kinetic energy per molecule. Conserved P and L
    # take more degrees of freedom from translation than from rotation, so the target is the
    # per-frame expectation from equipartition_target(), not 1.
    ratio = {m: float(np.concatenate(r["rotational"]).mean() / np.concatenate(r["translational"]).mean())
             for m, r in results.items()}
    run_ratios = [rot.mean() / tr.mean() for r in results.values() for rot, tr in zip(r["rotational"], r["translational"])]
    rows.append({"quantity": "rotational / translational KE", "M-RATTLE mean": ratio["M-RATTLE"],
                 "splitting mean": ratio["splitting"],
                 "spread of run means": float(np.std(run_ratios, ddof=1)) if len(run_ratios) > 1 else float("nan"),
                 "KS D": "", "KS p": "", "independent samples": ""})
    target = {m: float(np.concatenate(r["target"]).mean()) for m, r in results.items()}
    rows.append({"quantity": "equipartition target for that ratio (P and L conserved)",
                 "M-RATTLE mean": target["M-RATTLE"], "splitting mean": target["splitting"],
                 "KS D": "", "KS p": "", "independent samples": ""})
    return rows


def plot(results, path):
    fig, axes = common.panels(3, 5)
    for method, r in results.items():
        axes[0].hist(np.concatenate(r["temperature"]), bins=30, density=True, histtype="step", lw=1.5, label=method)
        axes[1].hist(np.concatenate(r["translational"]) / KB, bins=30, density=True, histtype="step", lw=1.5,
                     label=method + " translational")
        axes[1].hist(np.concatenate(r["rotational"]) / KB, bins=30, density=True, histtype="step", lw=1.5, ls="--",
                     label=method + " rotational")
        axes[2].hist(np.concatenate([c.ravel() for c in r["cc"]]), bins=120, range=(0.3, 1.5), density=True,
                     histtype="step", lw=1.2, label=method)
    axes[0].set_xlabel("kinetic temperature (K), rigid-body DOF")
    axes[1].set_xlabel("mean KE per molecule / k_B (K)")
    axes[2].set_xlabel("intermolecular C-C distance (nm)")
    for ax in axes:
        ax.legend(fontsize=8)
    common.save_figure(fig, path, "27 rigid benzene molecules, NVE: M-RATTLE vs splitting")
