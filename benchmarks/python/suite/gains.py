"""What a user gains: liquid benzene with PME on the CPU platform, rigid versus flexible."""
import time

import numpy as np
import openmm
from openmm import unit

import mrattle
from . import common, stats


def _copy(system):
    return openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))


def flexible_with_hbonds(system):
    """The all-atom flexible model with bonds to hydrogen constrained (as createSystem(constraints=HBonds))."""
    flexible = _copy(system)
    for force in flexible.getForces():
        if isinstance(force, openmm.HarmonicBondForce):
            for b in range(force.getNumBonds()):
                p1, p2, r0, k = force.getBondParameters(b)
                m1 = flexible.getParticleMass(p1).value_in_unit(unit.dalton)
                m2 = flexible.getParticleMass(p2).value_in_unit(unit.dalton)
                if min(m1, m2) < 1.5:
                    flexible.addConstraint(p1, p2, r0)
                    force.setBondParameters(b, p1, p2, r0, 0.0)
    return flexible


def equilibrate(model, picoseconds, log, temperature=300.0, seed=1, threads=None, thermostat_seed=0):
    """Rigid M-RATTLE with an Andersen thermostat at `temperature` (K) from the lattice start:
    200 steps of 1 fs, then `picoseconds` at 4 fs. seed: the starting velocities' random seed;
    thermostat_seed: the thermostat's (0: OpenMM picks a new one each time, so runs differ)."""
    system = _copy(model.system)
    thermostat = openmm.AndersenThermostat(temperature * unit.kelvin, 5 / unit.picosecond)
    thermostat.setRandomNumberSeed(thermostat_seed)
    system.addForce(thermostat)
    integrator = mrattle.MRattleIntegrator(1 * unit.femtosecond)
    plat, props = common.platform("CPU", threads)
    context = openmm.Context(system, integrator, plat, props)
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(temperature * unit.kelvin, seed)
    integrator.step(200)
    integrator.setStepSize(4 * unit.femtosecond)
    integrator.step(int(picoseconds / 0.004))
    state = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    log("  equilibrated %g ps: T = %.1f K" % (picoseconds, mrattle.kineticTemperature(context, state).value_in_unit(unit.kelvin)))
    return state


def nve(system, state, integrator, picoseconds, sample_every_ps=0.05):
    """NVE from an equilibrated state; energies and wall-clock speed."""
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("CPU"))
    context.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
    context.setPositions(state.getPositions())
    context.setVelocities(state.getVelocities())
    h = integrator.getStepSize().value_in_unit(unit.picosecond)
    stride = max(1, int(round(sample_every_ps / h)))
    samples = max(2, int(round(picoseconds / (stride * h))))
    integrator.step(stride)  # warm-up: first force evaluation, neighbour lists
    times, energies = [], []
    failure = None
    wall = 0.0
    for k in range(samples):
        start = time.perf_counter()
        try:
            integrator.step(stride)
        except Exception as error:
            failure = str(error).splitlines()[0]
            break
        wall += time.perf_counter() - start
        s = context.getState(getEnergy=True)
        e = (s.getKineticEnergy() + s.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole)
        if not np.isfinite(e):
            failure = "energy became non-finite"
            break
        times.append(s.getTime().value_in_unit(unit.picosecond))
        energies.append(e)
    steps = len(times) * stride
    ns_per_day = (steps * h * 1e-3) / (wall / 86400.0) if wall > 0 else float("nan")
    drift, drift_error = stats.drift_with_error(times, energies) if len(times) > 2 else (float("nan"), float("nan"))
    return {"ns_per_day": ns_per_day, "drift_per_ns": drift, "drift_error_per_ns": drift_error, "failure": failure,
            "fluctuation": float(np.std(energies)) if energies else float("nan")}


def compare(num_molecules, rigid_steps_fs, nve_ps, equilibrate_ps, log):
    model = mrattle.models.benzeneLiquid(numMolecules=num_molecules)
    state = equilibrate(model, equilibrate_ps, log)
    rows = []
    flexible = flexible_with_hbonds(model.system)
    dof_flexible = 3 * flexible.getNumParticles() - flexible.getNumConstraints()
    r = nve(flexible, state, openmm.VerletIntegrator(2 * unit.femtosecond), nve_ps)
    rows.append(dict(model="flexible all-atom, H-bond constraints", integrator="VerletIntegrator", step_fs=2.0,
                     dof=dof_flexible, **r))
    log("  flexible 2 fs: %.2f ns/day, drift %+.3g kJ/mol/ns %s" % (r["ns_per_day"], r["drift_per_ns"], r["failure"] or ""))
    rigid = mrattle.removeIntraBodyInteractions(model.system, model.positions, 'molecules')
    for h in rigid_steps_fs:
        integrator = mrattle.MRattleIntegrator(h * unit.femtosecond)
        r = nve(rigid, state, integrator, nve_ps)
        rows.append(dict(model="rigid, intra-body interactions removed", integrator="MRattleIntegrator", step_fs=h,
                         dof=6 * num_molecules, **r))
        log("  rigid %g fs: %.2f ns/day, drift %+.3g kJ/mol/ns %s" % (h, r["ns_per_day"], r["drift_per_ns"], r["failure"] or ""))
    return rows


def largest_stable(rows, tolerance_per_dof):
    """Largest rigid step whose |drift| per degree of freedom, plus two standard errors, is within
    the tolerance (kJ/mol/ns): a step counts only if its error bars show it meets the criterion."""
    best = None
    for r in rows:
        bound = abs(r["drift_per_ns"]) + 2 * r.get("drift_error_per_ns", 0.0)
        if r["integrator"] == "MRattleIntegrator" and r["failure"] is None and bound / r["dof"] <= tolerance_per_dof:
            if best is None or r["step_fs"] > best["step_fs"]:
                best = r
    return best
