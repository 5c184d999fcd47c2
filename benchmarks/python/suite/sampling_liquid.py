"""Sampling in a periodic liquid: NVE runs of liquid benzene (PME) with M-RATTLE and splitting.

The vacuum cluster of sampling.py evaporates and settles at a different temperature in each
run; a periodic liquid cannot evaporate, and all runs start from one equilibrated state.
"""
import numpy as np
import openmm
from openmm import unit

import mrattle
from . import common, gains, sampling, stats

LABELS = {"temperature": "temperature (K)", "translational": "translational KE per molecule",
          "rotational": "rotational KE per molecule", "potential": "potential energy per molecule"}


def equilibrated(num_molecules, equilibrate_ps, log):
    """Rigid liquid benzene (intra-body interactions removed) and one state equilibrated at 300 K."""
    model = mrattle.models.benzeneLiquid(numMolecules=num_molecules)
    state = gains.equilibrate(model, equilibrate_ps, log)
    system = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    return system, state


def run(system, state, method, velocities, total_ps, step_fs):
    """One NVE run from the equilibrated positions with the given rigid velocities; a frame every 100 fs."""
    n_mol = system.getNumParticles() // 12
    bodies = common.benzene_bodies(system.getNumParticles())
    integrator = common.make_integrator(method, step_fs * common.FS, bodies=bodies)
    plat, props = common.platform("CPU")
    context = openmm.Context(system, integrator, plat, props)
    context.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
    context.setPositions(state.getPositions())
    context.setVelocities(velocities)
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(12)])
    dof = integrator.getNumDegreesOfFreedom()
    stride = max(1, int(round(0.1 / (step_fs * common.FS))))
    frames = int(round(total_ps / (stride * step_fs * common.FS)))
    out = {"temperature": [], "translational": [], "rotational": [], "potential": [], "energy": [], "time": []}
    for _ in range(frames):
        integrator.step(stride)
        s = context.getState(getVelocities=True, getEnergy=True)
        ke = s.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        pe = s.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        v = s.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond).reshape(n_mol, 12, 3)
        # Fresh random velocities carry a conserved total momentum: translation is taken relative to it.
        ke_trans, ke_rot = sampling.kinetic_energy_per_molecule(v, masses, relative_to_system=True)
        out["temperature"].append(2 * ke / (dof * sampling.KB))
        out["translational"].append(ke_trans)
        out["rotational"].append(ke_rot)
        out["potential"].append(pe / n_mol)
        out["energy"].append(ke + pe)
        out["time"].append(s.getTime().value_in_unit(unit.picosecond))
    result = {k: np.array(v) for k, v in out.items()}
    result["dof"] = dof
    return result


def run_many(num_molecules, seeds, equilibrate_ps, total_ps, drop_ps, step_fs, log):
    """Both methods from one equilibrated state, with the same fresh 300 K rigid velocities per seed."""
    system, state = equilibrated(num_molecules, equilibrate_ps, log)
    bodies = common.benzene_bodies(12 * num_molecules)
    results = {m: {k: [] for k in ("temperature", "translational", "rotational", "potential")}
               for m in ("M-RATTLE", "splitting")}
    drifts = {m: [] for m in results}
    skip = int(round(drop_ps / 0.1))
    for seed in seeds:
        velocities = common.rigid_velocities(system, state.getPositions(), bodies, 300.0, seed,
                                             box=state.getPeriodicBoxVectors())
        for method in results:
            r = run(system, state, method, velocities, total_ps, step_fs)
            for k in results[method]:
                results[method][k].append(r[k][skip:])
            drifts[method].append(stats.drift_with_error(r["time"][skip:], r["energy"][skip:]))
            log("  liquid sampling %-9s seed %d  T=%.1f K  drift %+.2f +- %.2f kJ/mol/ns" % (
                method, seed, r["temperature"][skip:].mean(), drifts[method][-1][0], drifts[method][-1][1]))
        dof = r["dof"]
    return results, drifts, dof


def compare(results, drifts, num_molecules):
    """Means with the spread of run means, KS tests on decorrelated pooled samples, equipartition, drift."""
    rows = sampling.scalar_rows(results, LABELS)
    ratios = {m: [rot.mean() / tr.mean() for rot, tr in zip(r["rotational"], r["translational"])]
              for m, r in results.items()}
    rows.append({"quantity": "rotational / translational KE", "M-RATTLE mean": float(np.mean(ratios["M-RATTLE"])),
                 "splitting mean": float(np.mean(ratios["splitting"])),
                 "spread of run means": float(np.std(ratios["M-RATTLE"] + ratios["splitting"], ddof=1)),
                 "KS D": "", "KS p": "", "independent samples": ""})
    # Periodic with PME: total momentum is conserved (3 translational DOF fewer), angular momentum is not.
    target = num_molecules / (num_molecules - 1.0)
    rows.append({"quantity": "equipartition target for that ratio (P conserved)", "M-RATTLE mean": target,
                 "splitting mean": target, "KS D": "", "KS p": "", "independent samples": ""})
    for method in drifts:
        values = np.array([d for d, _ in drifts[method]])
        rows.append({"quantity": "energy drift, kJ/mol/ns (mean of runs; spread)",
                     "M-RATTLE mean": float(values.mean()) if method == "M-RATTLE" else "",
                     "splitting mean": float(values.mean()) if method == "splitting" else "",
                     "spread of run means": float(values.std(ddof=1)) if len(values) > 1 else float("nan"),
                     "KS D": "", "KS p": "", "independent samples": ""})
    return rows
