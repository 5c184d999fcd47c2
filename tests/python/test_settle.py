"""Rigid water: M-RATTLE against SETTLE in OpenMM's velocity-Verlet RATTLE (mrattle.baselines)."""
import numpy as np
import openmm
from openmm import unit

import mrattle


def test_rigid_water_matches_settle():
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    reference = openmm.Platform.getPlatformByName('Reference')
    stepSize = 1*unit.femtoseconds
    rattle = mrattle.MRattleIntegrator(stepSize)
    rattle.setConstraintTolerance(1e-12)
    mrattleContext = openmm.Context(model.system, rattle, reference)
    mrattleContext.setPositions(model.positions)
    # Relax the lattice start first (it heats up fast), so the comparison is not dominated
    # by the chaotic growth of the per-step difference: OpenMM 7.7's Reference SETTLE holds
    # distances only to ~5e-9 nm, M-RATTLE to round-off.
    for seed in range(6):
        mrattleContext.setVelocitiesToTemperature(300*unit.kelvin, seed)
        rattle.step(50)
    mrattleContext.setVelocitiesToTemperature(300*unit.kelvin, 17)
    state = mrattleContext.getState(getPositions=True, getVelocities=True)
    settle = mrattle.baselines.rattleVerletIntegrator(stepSize, 1e-12)  # SETTLE for the waters
    settleContext = openmm.Context(model.system, settle, reference)
    settleContext.setPositions(state.getPositions())
    settleContext.setVelocities(state.getVelocities())

    largest = 0.0
    for block in range(10):
        rattle.step(10)
        settle.step(10)
        a = mrattleContext.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
        b = settleContext.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
        largest = max(largest, np.abs(a - b).max())
    # The molecules moved (so the comparison means something).
    start = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    assert np.abs(a - start).max() > 1e-3
    assert largest < 1e-7
    va = mrattleContext.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds)
    vb = settleContext.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds)
    assert np.abs(va - vb).max() < 1e-5


def test_mrattle_keeps_water_exactly_rigid():
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    integrator.setConstraintTolerance(1e-12)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 2)
    integrator.step(100)
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    errors = [abs(np.linalg.norm(x[i] - x[j]) - d.value_in_unit(unit.nanometers))
              for i, j, d in (model.system.getConstraintParameters(c) for c in range(model.system.getNumConstraints()))]
    assert max(errors) < 1e-12
