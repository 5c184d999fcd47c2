"""Temperatures with the rigid-body degrees of freedom."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties


def openmmVersion():
    """(major, minor) of the OpenMM this runs with."""
    return tuple(int(part) for part in openmm.version.short_version.split('.')[:2])


def reportedRows(simulation, reporter, log, steps):
    simulation.reporters.append(reporter)
    simulation.step(steps)
    return np.array([[float(value) for value in line.split(',')] for line in log.getvalue().splitlines()[1:]])


@pytest.mark.parametrize('removeMotion', [False, True])
def test_reporter_temperature_is_2ke_over_dof_kb(platform, removeMotion):
    model = mrattle.models.benzeneCluster(temperature=200*unit.kelvin)
    system = model.system
    if removeMotion:
        system.addForce(openmm.CMMotionRemover())
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocities(model.velocities)
    log = io.StringIO()
    rows = reportedRows(simulation, mrattle.StateDataReporter(log, 4, kineticEnergy=True, temperature=True), log, 12)
    assert len(rows) == 3
    dof = 6*27 - (3 if removeMotion else 0)
    assert integrator.getNumDegreesOfFreedom() == dof
    assert mrattle.degreesOfFreedom(simulation) == dof
    boltzmann = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoules_per_mole/unit.kelvin)
    np.testing.assert_allclose(rows[:, 1], 2*rows[:, 0]/(dof*boltzmann), rtol=1e-12)
    # Depends on OpenMM's version. From 8.0 OpenMM's own reporter asks the integrator
    # (computeSystemTemperature(), with the rigid-body count); 7.x counts 3 per atom minus
    # constraints (324 atoms here), which mrattle.StateDataReporter corrects.
    if openmmVersion() >= (8, 0):
        openmmDof = dof
    else:
        openmmDof = 3*324 - (3 if removeMotion else 0)
    openmmLog = io.StringIO()
    openmmRows = reportedRows(simulation, app.StateDataReporter(openmmLog, 4, kineticEnergy=True, temperature=True),
                              openmmLog, 4)
    np.testing.assert_allclose(openmmRows[:, 1], 2*openmmRows[:, 0]/(openmmDof*boltzmann), rtol=1e-12)
    kinetic = simulation.context.getState(getEnergy=True).getKineticEnergy()
    assert mrattle.kineticTemperature(simulation).value_in_unit(unit.kelvin) == \
        pytest.approx(2*kinetic.value_in_unit(unit.kilojoules_per_mole)/(dof*boltzmann), rel=1e-12)


def test_builder_velocities_are_at_the_temperature():
    model = mrattle.models.benzeneCluster(temperature=123*unit.kelvin, seed=4)
    integrator = mrattle.MRattleIntegrator(0.002)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocities(model.velocities)
    assert mrattle.kineticTemperature(context).value_in_unit(unit.kelvin) == pytest.approx(123, rel=1e-10)


def test_temperature_fix_only_where_openmm_needs_it():
    """OpenMM 8's own StateDataReporter asks the integrator (computeSystemTemperature()), so
    mrattle's then only adds its columns; only on 7.x does it replace the count."""
    stock = app.StateDataReporter
    overriding = [cls for cls in mrattle.StateDataReporter.__mro__ if cls is not stock and '_initializeConstants' in vars(cls)]
    assert mrattle.reporters.STOCK_REPORTER_ASKS_INTEGRATOR == (openmmVersion() >= (8, 0))
    if openmmVersion() >= (8, 0):
        assert mrattle.reporters._TemperatureReporter is stock
        assert overriding == []
    else:
        assert overriding == [mrattle.reporters._TemperatureReporter]
    assert issubclass(mrattle.StateDataReporter, stock)


@pytest.mark.parametrize('makeIntegrator', [lambda: openmm.VerletIntegrator(0.001),
                                            lambda: mrattle.baselines.rattleVerletIntegrator(0.001)],
                         ids=['Verlet+CCMA', 'RATTLE CustomIntegrator'])
@pytest.mark.parametrize('removeMotion', [False, True])
def test_constrained_baselines_count_as_openmm_reports(makeIntegrator, removeMotion):
    """The benchmark suite's constrained baselines: degreesOfFreedom is what OpenMM's own
    StateDataReporter divides by (3 per particle, minus constraints, minus 3 with a CMMotionRemover)."""
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    system = model.system
    if removeMotion:
        system.addForce(openmm.CMMotionRemover())
    simulation = app.Simulation(model.topology, system, makeIntegrator(), openmm.Platform.getPlatformByName('Reference'))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    dof = mrattle.degreesOfFreedom(simulation)
    assert dof == 3*81 - 81 - (3 if removeMotion else 0)
    log = io.StringIO()
    rows = reportedRows(simulation, app.StateDataReporter(log, 2, kineticEnergy=True, temperature=True), log, 4)
    boltzmann = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoules_per_mole/unit.kelvin)
    np.testing.assert_allclose(2*rows[:, 0]/(rows[:, 1]*boltzmann), dof, rtol=1e-9)


def test_other_integrators_use_openmm_count():
    system = openmm.System()
    for i in range(3):
        system.addParticle(1.0)
    system.addConstraint(0, 1, 0.1)
    # A constraint between two massless particles takes nothing (OpenMM's count; the
    # benchmark suite's own count, now gone, subtracted it).
    system.addParticle(0.0)
    system.addParticle(0.0)
    system.addConstraint(3, 4, 0.1)
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName('Reference'))
    assert mrattle.degreesOfFreedom(context) == 8
