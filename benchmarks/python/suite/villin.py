"""Speed on a real solvated protein: OpenMM's villin headpiece in 2761 TIP3P waters
(openmm/app/data/test.pdb, 8867 atoms), amber14-all.xml + amber14/tip3p.xml, PME, bonds to
hydrogen constrained in the protein, 2 fs, CPU platform: ns/day of OpenMM's VerletIntegrator
(SETTLE for the waters, CCMA for the protein's constraints) against MRattleIntegrator with
the waters declared rigid bodies (RATTLE for the protein's constraints)."""
import math
import os

import openmm
from openmm import app, unit

import mrattle
from . import common

STEP_FS = 2.0


def _setup():
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    forcefield = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    system = forcefield.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9 * unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True)
    return pdb, system


def _contexts(threads):
    """Both integrators on the same minimised start with the same velocities."""
    pdb, system = _setup()
    plat, props = common.platform("CPU", threads)
    verlet = openmm.VerletIntegrator(STEP_FS * unit.femtosecond)
    verlet_context = openmm.Context(system, verlet, plat, props)
    verlet_context.setPositions(pdb.positions)
    # The crystal start has close contacts that NVE at 2 fs would feel: relax them first.
    openmm.LocalEnergyMinimizer.minimize(verlet_context, 10.0, 200)
    verlet_context.setVelocitiesToTemperature(300 * unit.kelvin, 1)
    state = verlet_context.getState(getPositions=True, getVelocities=True)
    rigid = mrattle.MRattleIntegrator(STEP_FS * unit.femtosecond)
    waters = mrattle.declareRigidBodies(rigid, pdb.topology, system, "water")
    rigid_context = openmm.Context(system, rigid, plat, props)
    rigid_context.setPositions(state.getPositions())
    rigid_context.setVelocities(state.getVelocities())
    return {"Verlet + SETTLE + CCMA": (verlet, verlet_context), "M-RATTLE (rigid waters)": (rigid, rigid_context)}, \
        system.getNumParticles(), waters


def compare(threads, steps_per_batch, batches, log):
    """ns/day of each integrator, median of interleaved batches; one row per integrator."""
    runs, atoms, waters = _contexts(threads)
    log("  villin: %d atoms, %d rigid waters, CPU platform with %d threads" % (atoms, waters, threads))
    for integrator, _ in runs.values():
        integrator.step(10)  # warm-up: first forces, neighbour lists, kernels
    seconds = common.interleaved_median({name: pair[0] for name, pair in runs.items()},
                                        {name: steps_per_batch for name in runs}, batches)
    rows = []
    for name, (integrator, context) in runs.items():
        per_step = seconds[name]
        state = context.getState(getEnergy=True)
        finite = math.isfinite(state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole) +
                               state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole))
        rows.append({"integrator": name, "threads": threads, "atoms": atoms, "step_fs": STEP_FS,
                     "batches": batches, "steps_per_batch": steps_per_batch,
                     "ms_per_step": per_step * 1e3, "ns_per_day": STEP_FS * 1e-6 / per_step * 86400,
                     "finite": "yes" if finite else "no"})
        log("  %-26s %.2f ms/step, %.2f ns/day" % (name, rows[-1]["ms_per_step"], rows[-1]["ns_per_day"]))
    return rows


def ratio(rows):
    """M-RATTLE's ns/day over Verlet's (target >= 1)."""
    speed = {r["integrator"]: r["ns_per_day"] for r in rows}
    return speed["M-RATTLE (rigid waters)"] / speed["Verlet + SETTLE + CCMA"]
