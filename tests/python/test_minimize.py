"""mrattle.minimizeEnergy and app.Simulation.minimizeEnergy with the plugin's integrators:
the energy goes down, bodies keep their shapes, dynamics follow; other integrators keep
OpenMM's minimizer; arguments take units and numpy values."""
import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties


def maxShapeChange(a, b, bodies):
    a, b = np.asarray(a), np.asarray(b)
    worst = 0.0
    for body in bodies:
        da = np.linalg.norm(a[body][:, None] - a[body][None], axis=2)
        db = np.linalg.norm(b[body][:, None] - b[body][None], axis=2)
        worst = max(worst, np.abs(da - db).max())
    return worst


def positions(context):
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)


def energy(context):
    return context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoules_per_mole)


def simulationOf(model, integrator, platform):
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    return simulation


def test_simulation_minimizes_rigidly_then_steps(platform):
    model = mrattle.models.benzeneCluster()
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = simulationOf(model, integrator, platform)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    start, before = energy(simulation.context), positions(simulation.context)
    # At the default 10 kJ/mol/nm this start is already converged (rms generalized force 4.4).
    simulation.minimizeEnergy(tolerance=0.5*unit.kilojoules_per_mole/unit.nanometer)
    after = positions(simulation.context)
    bodies = integrator.getBodiesInEffect()
    assert energy(simulation.context) < start - 10
    assert maxShapeChange(before, after, bodies) < 1e-12
    assert np.abs(after - before).max() > 1e-3
    simulation.step(10)
    assert maxShapeChange(before, positions(simulation.context), bodies) < 1e-9


def test_other_integrators_keep_openmms_minimizer():
    # OpenMM's minimizer deforms the benzenes of this flexible System; ours never does.
    model = mrattle.models.benzeneCluster()
    reference = openmm.Platform.getPlatformByName('Reference')
    simulation = simulationOf(model, openmm.VerletIntegrator(0.001), reference)
    before = positions(simulation.context)
    simulation.minimizeEnergy(maxIterations=50)
    molecules = [list(range(12*m, 12*m + 12)) for m in range(27)]
    assert maxShapeChange(before, positions(simulation.context), molecules) > 1e-4
    assert not mrattle.RigidBodyMinimizer.appliesTo(simulation.context)


def test_compound_integrator_minimizes_rigidly():
    model = mrattle.models.benzeneCluster()
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(openmm.VerletIntegrator(0.001))
    compound.addIntegrator(mrattle.MRattleIntegrator(0.001))
    simulation = simulationOf(model, compound, openmm.Platform.getPlatformByName('Reference'))
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy(tolerance=1*unit.kilojoules_per_mole/unit.nanometer, maxIterations=np.int64(40))
    molecules = [list(range(12*m, 12*m + 12)) for m in range(27)]
    assert energy(simulation.context) < start
    assert maxShapeChange(before, positions(simulation.context), molecules) < 1e-12


def test_arguments_take_units_and_numpy_and_bad_ones_are_refused():
    model = mrattle.models.benzeneCluster()
    simulation = simulationOf(model, mrattle.MRattleIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    context = simulation.context
    report = mrattle.minimizeEnergy(context, 0.01*unit.kilocalories_per_mole/unit.angstrom, maxIterations=np.int32(3))
    assert report.iterations == 3 and report.finalEnergy < report.initialEnergy
    report = mrattle.minimizeEnergy(context, np.float64(1e9))
    assert report.iterations == 0
    with pytest.raises(TypeError, match='force'):
        mrattle.minimizeEnergy(context, 1*unit.nanometer)
    with pytest.raises(TypeError, match='maxIterations'):
        mrattle.minimizeEnergy(context, 10, 2.5)
    with pytest.raises(openmm.OpenMMException, match='tolerance'):
        mrattle.minimizeEnergy(context, -1)
    with pytest.raises(openmm.OpenMMException, match='maxIterations'):
        mrattle.minimizeEnergy(context, 10, -1)
    with pytest.raises(TypeError, match='reporter'):
        simulation.minimizeEnergy(10, 0, object())
    flexible = openmm.Context(model.system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    flexible.setPositions(model.positions)
    with pytest.raises(openmm.OpenMMException, match='LocalEnergyMinimizer'):
        mrattle.minimizeEnergy(flexible)


def test_tip3p_rigid_water_minimizes_far():
    # The case: OpenMM's minimizer with MRattleIntegrator lowered this by 38 kJ/mol.
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), 'data', 'tip3p.pdb'))
    system = app.ForceField('tip3p.xml').createSystem(pdb.topology, nonbondedMethod=app.PME, rigidWater=True)
    cpu = openmm.Platform.getPlatformByName('CPU')
    integrator = mrattle.MRattleIntegrator(0.002)
    simulation = app.Simulation(pdb.topology, system, integrator, cpu, {'Threads': '1'})
    simulation.context.setPositions(pdb.positions)
    start, before = energy(simulation.context), positions(simulation.context)
    simulation.minimizeEnergy()
    assert energy(simulation.context) < start - 5000
    assert maxShapeChange(before, positions(simulation.context), integrator.getBodiesInEffect()) < 1e-12
