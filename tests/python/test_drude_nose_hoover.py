"""MRattleDrudeNoseHooverIntegrator from Python: OpenMM's DrudeNoseHooverIntegrator's units and
settings, XML, and SWM4-NDP water (swm4ndp.xml) as rigid bodies with free Drude particles:
rigid, both chains in the heat-bath energy, a checkpoint continuing bit for bit."""
import numpy as np
import openmm
import pytest
from openmm import unit

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


def test_swm4ndp_rigid_with_both_chains_and_a_checkpoint_bit_for_bit():
    system, positions, bodies = swm4ndp(8)
    integrator = mrattle.MRattleDrudeNoseHooverIntegrator(300*unit.kelvin, 10/unit.picosecond, 1*unit.kelvin,
                                                          20/unit.picosecond, 0.5*unit.femtoseconds)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))
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
                assert abs(np.linalg.norm(again[i] - again[j]) - np.linalg.norm(start[i] - start[j])) < 1e-10
    assert integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) >= 0
    assert integrator.computeBodyTemperature().value_in_unit(unit.kelvin) > 0
