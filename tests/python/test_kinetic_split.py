"""The rigid bodies' translational and rotational kinetic energy and temperature from Python: units,
equipartition by construction, StateDataReporter columns, and the benchmark suite's formula."""
import io
import os
import sys

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import meanAndError, platformProperties

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def waterSimulation(platform, integrator=None, numMolecules=64):
    model = mrattle.models.waterBox(numMolecules=numMolecules, cutoff=0.6*unit.nanometers,
                                    nonbondedMethod=app.CutoffPeriodic)
    model.system.addForce(openmm.CMMotionRemover())
    integrator = integrator or mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    return simulation


def test_methods_have_units_and_parts_add_up(platform):
    simulation = waterSimulation(platform)
    integrator = simulation.integrator
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 4)
    simulation.step(5)
    translational = integrator.computeTranslationalKineticEnergy()
    rotational = integrator.computeRotationalKineticEnergy()
    free = integrator.computeFreeKineticEnergy()
    assert translational.unit == unit.kilojoules_per_mole and free.unit == unit.kilojoules_per_mole
    total = simulation.context.getState(getEnergy=True).getKineticEnergy()
    assert abs((translational + rotational + free - total)/total) < 1e-10
    assert free.value_in_unit(unit.kilojoules_per_mole) == pytest.approx(0, abs=1e-9)
    # 64 waters and a CMMotionRemover: 3*64 - 3 translational, 3*64 rotational.
    assert integrator.getTranslationalDegreesOfFreedom() == pytest.approx(3*64 - 3)
    assert integrator.getRotationalDegreesOfFreedom() == 3*64
    assert integrator.getFreeDegreesOfFreedom() == pytest.approx(0)
    boltzmann = unit.MOLAR_GAS_CONSTANT_R
    expected = (2*rotational/(3*64*boltzmann)).value_in_unit(unit.kelvin)
    assert integrator.computeRotationalTemperature().value_in_unit(unit.kelvin) == pytest.approx(expected, rel=1e-12)
    assert integrator.computeTranslationalTemperature().unit == unit.kelvin


def test_equipartition_by_construction_within_error_bars():
    simulation = waterSimulation(openmm.Platform.getPlatformByName('Reference'))
    integrator = simulation.integrator
    translational, rotational = [], []
    for seed in range(1, 13):
        simulation.context.setVelocitiesToTemperature(300*unit.kelvin, seed)
        translational.append(integrator.computeTranslationalTemperature().value_in_unit(unit.kelvin))
        rotational.append(integrator.computeRotationalTemperature().value_in_unit(unit.kelvin))
    for series in (translational, rotational):
        mean, error = meanAndError(series)
        assert 0.5 < error < 15
        assert abs(mean - 300) < 4*error


def test_reporter_columns_follow_temperature(platform):
    simulation = waterSimulation(platform)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 5)
    log = io.StringIO()
    simulation.reporters.append(mrattle.StateDataReporter(log, 2, step=True, temperature=True, speed=True,
                                                          translationalTemperature=True, rotationalTemperature=True))
    simulation.step(4)
    lines = log.getvalue().splitlines()
    headers = lines[0].lstrip('#').replace('"', '').split(',')
    assert headers[:4] == ['Step', 'Temperature (K)', 'Translational Temperature (K)', 'Rotational Temperature (K)']
    assert headers[4] == 'Speed (ns/day)'
    last = [float(value) for value in lines[-1].split(',')[:4]]
    integrator = simulation.integrator
    assert last[2] == pytest.approx(integrator.computeTranslationalTemperature().value_in_unit(unit.kelvin), rel=1e-12)
    assert last[3] == pytest.approx(integrator.computeRotationalTemperature().value_in_unit(unit.kelvin), rel=1e-12)
    # The two parts weigh into the total by their degrees of freedom.
    dof = integrator.getNumDegreesOfFreedom()
    combined = (last[2]*integrator.getTranslationalDegreesOfFreedom() +
                last[3]*integrator.getRotationalDegreesOfFreedom())/dof
    assert combined == pytest.approx(last[1], rel=1e-9)


def test_reporter_columns_without_temperature_and_with_other_integrators():
    simulation = waterSimulation(openmm.Platform.getPlatformByName('Reference'))
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 6)
    log = io.StringIO()
    simulation.reporters.append(mrattle.StateDataReporter(log, 1, step=True, rotationalTemperature=True,
                                                          potentialEnergy=True))
    simulation.step(1)
    headers = log.getvalue().splitlines()[0].lstrip('#').replace('"', '').split(',')
    assert headers == ['Step', 'Potential Energy (kJ/mole)', 'Rotational Temperature (K)']
    verlet = waterSimulation(openmm.Platform.getPlatformByName('Reference'), openmm.VerletIntegrator(0.001))
    verlet.reporters.append(mrattle.StateDataReporter(io.StringIO(), 1, translationalTemperature=True))
    with pytest.raises(ValueError, match='need a RigidBodyIntegrator'):
        verlet.step(1)


def test_langevin_parts_use_its_half_step_velocities():
    simulation = waterSimulation(openmm.Platform.getPlatformByName('Reference'),
                                 mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtoseconds))
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 7)
    simulation.step(10)
    integrator = simulation.integrator
    total = simulation.context.getState(getEnergy=True).getKineticEnergy()
    parts = (integrator.computeTranslationalKineticEnergy() + integrator.computeRotationalKineticEnergy() +
             integrator.computeFreeKineticEnergy())
    assert abs((parts - total)/total) < 1e-10


def test_benchmark_suite_formula_is_the_integrators():
    """The benchmark suite (benchmarks/python/suite/common.py) splits every integrator's velocities itself: on
    M-RATTLE's (rigid) velocities it gives the integrator's own numbers; on velocities that are
    not rigid it first projects them, which keeps the translational part."""
    sys.path.insert(0, os.path.join(ROOT, 'benchmarks', 'python'))
    from suite import common
    simulation = waterSimulation(openmm.Platform.getPlatformByName('Reference'))
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 8)
    simulation.step(3)
    state = simulation.context.getState(getVelocities=True, getPositions=True)
    system = simulation.system
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    bodies = simulation.integrator.getBodiesInEffect()
    v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picosecond)
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    translational, rotational = common.rigid_split(v, masses, bodies, x)
    integrator = simulation.integrator
    assert translational == pytest.approx(integrator.computeTranslationalKineticEnergy().value_in_unit(
        unit.kilojoules_per_mole), rel=1e-10)
    assert rotational == pytest.approx(integrator.computeRotationalKineticEnergy().value_in_unit(
        unit.kilojoules_per_mole), rel=1e-8)
    noisy = v + np.random.default_rng(1).normal(0, 0.3, v.shape)
    assert common.rigid_split(noisy, masses, bodies)[0] == pytest.approx(
        common.rigid_split(noisy, masses, bodies, x)[0], rel=1e-12)
    assert common.rigid_split(noisy, masses, bodies, x)[1] < common.rigid_split(
        noisy, masses, bodies)[1]
