"""MRattleLangevinIntegrator from Python: units as OpenMM's LangevinMiddleIntegrator, a
Simulation with reporters at constant temperature, constant pressure with a barostat,
serialization and checkpoints."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties


def test_units_like_langevin_middle():
    integrator = mrattle.MRattleLangevinIntegrator(310*unit.kelvin, 2/unit.picosecond, 2*unit.femtoseconds)
    assert integrator.getTemperature() == 310*unit.kelvin
    assert integrator.getFriction() == 2/unit.picosecond
    assert integrator.getStepSize() == 0.002*unit.picoseconds
    integrator.setTemperature(300*unit.kelvin)
    integrator.setFriction(0.5/unit.femtosecond)
    assert integrator.getFriction().value_in_unit(unit.picosecond**-1) == pytest.approx(500)
    plain = mrattle.MRattleLangevinIntegrator(300, 1, 0.002)  # numbers in K, 1/ps, ps
    assert plain.getTemperature() == 300*unit.kelvin
    with pytest.raises(openmm.OpenMMException, match='friction'):
        plain.setFriction(-1)
    with pytest.raises(openmm.OpenMMException, match='temperature'):
        mrattle.MRattleLangevinIntegrator(-5*unit.kelvin, 1/unit.picosecond, 0.002)
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, mrattle.MRattleLangevinIntegrator)
    assert copy.getTemperature() == 300*unit.kelvin


def test_simulation_at_constant_temperature_and_pressure(platform):
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    barostat = openmm.MonteCarloBarostat(1*unit.bar, 300*unit.kelvin, 10)
    barostat.setRandomNumberSeed(5)
    model.system.addForce(barostat)
    integrator = mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 2*unit.femtoseconds)
    integrator.setRandomNumberSeed(3)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    log = io.StringIO()
    simulation.reporters.append(mrattle.StateDataReporter(log, 20, step=True, temperature=True, density=True))
    simulation.step(400)
    rows = [line.split(',') for line in log.getvalue().splitlines()[1:]]
    assert len(rows) == 20
    temperatures = np.array([float(row[1]) for row in rows])
    densities = np.array([float(row[2]) for row in rows])
    # A smoke test of Simulation + barostat + reporter (the thermostat's and the density's
    # statistics: validate-langevin, docs/results.md): sane values, and the box did change.
    assert 200 < temperatures.mean() < 400
    assert np.all((densities > 0.5) & (densities < 1.5))
    assert np.ptp(densities) > 0
    # The barostat scaled the box without deforming a water.
    state = simulation.context.getState(getPositions=True)
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    for body in integrator.getBodiesInEffect():
        assert abs(np.linalg.norm(positions[body[0]] - positions[body[1]]) - 0.09572) < 1e-6


def test_checkpoint_continues_bit_for_bit(platform, tmp_path):
    # Without a barostat: OpenMM 7.7's checkpoints do not hold a MonteCarloBarostat's own
    # random generator, so with one a continued run differs for any integrator.
    model = mrattle.models.waterBox(numMolecules=64, cutoff=0.45*unit.nanometers)
    integrator = mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    simulation.step(10)
    path = str(tmp_path/'run.chk')
    simulation.saveCheckpoint(path)
    simulation.step(20)
    uninterrupted = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    simulation.loadCheckpoint(path)
    simulation.step(20)
    continued = simulation.context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    if platform.getName() == 'Reference':
        assert np.array_equal(uninterrupted, continued)
    else:  # the CPU neighbour list: round-off (docs/serialization.md)
        assert np.abs(uninterrupted - continued).max() < 1e-4


def test_compute_system_temperature_is_what_openmm8_reporters_use():
    model = mrattle.models.benzeneCluster()
    integrator = mrattle.MRattleLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtoseconds)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(250*unit.kelvin, 1)
    temperature = integrator.computeSystemTemperature()
    assert unit.is_quantity(temperature)
    assert temperature.value_in_unit(unit.kelvin) == pytest.approx(mrattle.kineticTemperature(context).value_in_unit(unit.kelvin))
    # 27 rigid benzenes: 162 degrees of freedom, where OpenMM's count would be 3 per atom.
    assert integrator.getNumDegreesOfFreedom() == 162
