"""MRattleDrudeNoseHooverIntegrator from Python: OpenMM's DrudeNoseHooverIntegrator's units and
settings, XML, and SWM4-NDP water (swm4ndp.xml) as rigid bodies with free Drude particles:
rigid, both chains in the heat-bath energy, a checkpoint continuing bit for bit; the
StateDataReporter's body and Drude temperature columns for both Drude integrators."""
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from mrattle.reporters import DRUDE_INTEGRATORS, HEAT_BATH_INTEGRATORS
from test_drude_langevin import swm4ndp


def test_units_like_drude_nose_hoover():
    integrator = mrattle.MRattleDrudeNoseHooverIntegrator(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin,
                                                          20/unit.picosecond, 1*unit.femtoseconds)
    assert integrator.getTemperature() == 300*unit.kelvin
    assert integrator.getCollisionFrequency() == 10/unit.picosecond
    assert integrator.getDrudeTemperature() == 1*unit.kelvin
    assert integrator.getDrudeCollisionFrequency() == 20/unit.picosecond
    assert integrator.getStepSize() == 0.001*unit.picoseconds
    assert (integrator.getChainLength(), integrator.getNumMultiTimeSteps(),
            integrator.getNumYoshidaSuzukiTimeSteps()) == (3, 3, 7)
    assert integrator.getMaxDrudeDistance() == 0.02*unit.nanometer   # OpenMM's default
    integrator.setMaxDrudeDistance(0.25*unit.angstroms)
    assert integrator.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.025)
    integrator.setDrudeTemperature(2*unit.kelvin)
    integrator.setDrudeCollisionFrequency(0.01/unit.femtosecond)
    assert integrator.getDrudeCollisionFrequency().value_in_unit(unit.picosecond**-1) == pytest.approx(10)
    numbers = mrattle.MRattleDrudeNoseHooverIntegrator(np.float64(300), 10, 1, 20, 0.001, 4, 2, 5)
    assert (numbers.getChainLength(), numbers.getNumMultiTimeSteps(), numbers.getNumYoshidaSuzukiTimeSteps()) == (4, 2, 5)
    with pytest.raises(openmm.OpenMMException, match='Yoshida-Suzuki'):
        mrattle.MRattleDrudeNoseHooverIntegrator(300, 10, 1, 20, 0.001, 3, 3, 4)
    with pytest.raises(openmm.OpenMMException, match='Drude temperature'):
        integrator.setDrudeTemperature(-1)
    with pytest.raises(openmm.OpenMMException, match='maximum Drude distance'):
        integrator.setMaxDrudeDistance(float('nan'))
    with pytest.raises(openmm.OpenMMException, match='not bound'):
        integrator.computeHeatBathEnergy()
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, mrattle.MRattleDrudeNoseHooverIntegrator)
    assert copy.getDrudeTemperature() == 2*unit.kelvin
    assert copy.getDrudeCollisionFrequency().value_in_unit(unit.picosecond**-1) == pytest.approx(10)
    assert copy.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.025)
    assert mrattle.MRattleDrudeNoseHooverIntegrator in HEAT_BATH_INTEGRATORS
    assert mrattle.MRattleDrudeNoseHooverIntegrator in DRUDE_INTEGRATORS


def swm4ndp_rigid_with_both_chains_and_a_checkpoint_bit_for_bit(platform, properties, rigidity):
    system, positions, bodies = swm4ndp(8)
    integrator = mrattle.MRattleDrudeNoseHooverIntegrator(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin,
                                                          20/unit.picosecond, 0.5*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 2)
    start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    integrator.step(100)
    checkpoint = context.createCheckpoint()
    bath = integrator.computeHeatBathEnergy()
    assert bath != 0*unit.kilojoules_per_mole
    integrator.step(100)
    straight = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    straightBath = integrator.computeHeatBathEnergy()
    context.loadCheckpoint(checkpoint)
    assert integrator.computeHeatBathEnergy() == bath
    integrator.step(100)
    again = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    assert np.array_equal(straight, again)
    assert integrator.computeHeatBathEnergy() == straightBath
    for body in bodies:
        for i in body:
            for j in body:
                assert abs(np.linalg.norm(again[i] - again[j]) - np.linalg.norm(start[i] - start[j])) < rigidity
    assert integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) >= 0
    assert integrator.computeBodyTemperature().value_in_unit(unit.kelvin) > 0


def test_swm4ndp_rigid_with_both_chains_and_a_checkpoint_bit_for_bit():
    swm4ndp_rigid_with_both_chains_and_a_checkpoint_bit_for_bit(openmm.Platform.getPlatformByName('Reference'), {},
                                                                1e-10)


def test_swm4ndp_on_the_device_in_single_precision(devicePlatform):
    """OpenMM's SWM4-NDP water (its M sites virtual) in the device's default precision: rigid
    to float's round-off, both chains moving and in the checkpoint."""
    swm4ndp_rigid_with_both_chains_and_a_checkpoint_bit_for_bit(devicePlatform, {'Precision': 'single'}, 1e-5)


@pytest.mark.parametrize('cls', DRUDE_INTEGRATORS, ids=lambda cls: cls.__name__)
def test_reporter_writes_body_and_drude_temperatures(cls):
    system, positions, bodies = swm4ndp(4)
    integrator = cls(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin, 20/unit.picosecond, 0.5*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    simulation = app.Simulation(app.Topology(), system, integrator, openmm.Platform.getPlatformByName('Reference'))
    simulation.context.setPositions(positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    log = io.StringIO()
    heatBath = cls in HEAT_BATH_INTEGRATORS
    simulation.reporters.append(mrattle.StateDataReporter(log, 10, step=True, temperature=True, bodyTemperature=True,
                                                          drudeTemperature=True, conservedEnergy=heatBath))
    simulation.step(30)
    lines = log.getvalue().splitlines()
    header = lines[0].split(',')
    body, drude = header.index('"Body Temperature (K)"'), header.index('"Drude Temperature (K)"')
    assert drude == body + 1 and body > header.index('"Temperature (K)"')
    last = [float(value) for value in lines[-1].split(',')]
    assert len(lines) == 4 and last[0] == 30
    assert last[body] == pytest.approx(integrator.computeBodyTemperature().value_in_unit(unit.kelvin), rel=1e-6)
    assert last[drude] == pytest.approx(integrator.computeDrudeTemperature().value_in_unit(unit.kelvin), rel=1e-6)
    assert last[body] > 0 and last[drude] >= 0
    assert ('"Conserved Energy (kJ/mole)"' in header) == heatBath
    # An integrator without Drude temperatures is refused, naming what the columns need.
    other = app.Simulation(app.Topology(), system, mrattle.MRattleIntegrator(0.0005),
                           openmm.Platform.getPlatformByName('Reference'))
    other.context.setPositions(positions)
    with pytest.raises(ValueError, match='MRattleDrudeNoseHooverIntegrator'):
        other.reporters.append(mrattle.StateDataReporter(io.StringIO(), 1, drudeTemperature=True))
        other.step(1)
