"""MRattleDrudeLangevinIntegrator from Python: OpenMM's DrudeLangevinIntegrator's units and
settings, XML, and SWM4-NDP water (swm4ndp.xml, Modeller.addExtraParticles) as rigid bodies
with their Drude particles free."""

import numpy as np
import openmm
import pytest
from openmm import unit

import mrattle


def test_units_like_drude_langevin():
    integrator = mrattle.MRattleDrudeLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 1*unit.kelvin,
                                                        20/unit.picosecond, 1*unit.femtoseconds)
    assert integrator.getTemperature() == 300*unit.kelvin
    assert integrator.getFriction() == 5/unit.picosecond
    assert integrator.getDrudeTemperature() == 1*unit.kelvin
    assert integrator.getDrudeFriction() == 20/unit.picosecond
    assert integrator.getStepSize() == 0.001*unit.picoseconds
    assert integrator.getMaxDrudeDistance() == 0*unit.nanometer
    integrator.setMaxDrudeDistance(0.2*unit.angstroms)
    assert integrator.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.02)
    integrator.setDrudeTemperature(2*unit.kelvin)
    integrator.setDrudeFriction(0.01/unit.femtosecond)
    assert integrator.getDrudeFriction().value_in_unit(unit.picosecond**-1) == pytest.approx(10)
    with pytest.raises(openmm.OpenMMException, match='Drude temperature'):
        integrator.setDrudeTemperature(-1)
    with pytest.raises(openmm.OpenMMException, match='maximum Drude distance'):
        integrator.setMaxDrudeDistance(float('nan'))
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, mrattle.MRattleDrudeLangevinIntegrator)
    assert copy.getDrudeTemperature() == 2*unit.kelvin
    assert copy.getMaxDrudeDistance().value_in_unit(unit.nanometer) == pytest.approx(0.02)


def swm4ndp(numMolecules):
    """numMolecules SWM4-NDP waters in vacuum, and their O-H-H bodies (rigidBodies leaves the Drude particles out)."""
    model = mrattle.models.swm4ndpWater(numMolecules)
    bodies = mrattle.rigidBodies(model.topology, model.system)
    assert all(len(body) == 3 for body in bodies)
    return model.system, model.positions, bodies


def test_swm4ndp_bodies_stay_rigid_with_free_drude_particles():
    system, positions, bodies = swm4ndp(8)
    integrator = mrattle.MRattleDrudeLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 1*unit.kelvin,
                                                        20/unit.picosecond, 1*unit.femtoseconds)
    integrator.setRandomNumberSeed(4)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 2)
    # 6 per body and 3 per Drude particle, less the CMMotionRemover's 3.
    assert integrator.getNumDegreesOfFreedom() == 8*6 + 8*3 - 3
    start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    integrator.step(300)
    end = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    for body in bodies:
        for i in body:
            for j in body:
                assert abs(np.linalg.norm(end[i] - end[j]) - np.linalg.norm(start[i] - start[j])) < 1e-10
    assert integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) >= 0
    assert integrator.computeBodyTemperature().value_in_unit(unit.kelvin) > 0


def test_drude_particles_in_default_bodies_are_refused():
    system, positions, bodies = swm4ndp(2)
    integrator = mrattle.MRattleDrudeLangevinIntegrator(300, 5, 1, 20, 0.001)
    with pytest.raises(openmm.OpenMMException, match='Drude particle 4'):
        openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))


def test_swm4ndp_on_the_device_in_single_precision(devicePlatform):
    """OpenMM's SWM4-NDP water (its M sites virtual) in the device's default precision: the
    bodies stay rigid to float's round-off, the hard wall holds the Drude particles, and the
    two temperatures are finite and of the right size."""
    system, positions, bodies = swm4ndp(8)
    integrator = mrattle.MRattleDrudeLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 1*unit.kelvin,
                                                        20/unit.picosecond, 1*unit.femtoseconds)
    integrator.setMaxDrudeDistance(0.02*unit.nanometer)
    integrator.setRandomNumberSeed(4)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, devicePlatform, {'Precision': 'single'})
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 2)
    start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    integrator.step(300)
    end = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    for body in bodies:
        for i in body:
            for j in body:
                assert abs(np.linalg.norm(end[i] - end[j]) - np.linalg.norm(start[i] - start[j])) < 1e-5
    drude = [f for f in system.getForces() if isinstance(f, openmm.DrudeForce)][0]
    for k in range(drude.getNumParticles()):
        particle, core = drude.getParticleParameters(k)[:2]
        assert np.linalg.norm(end[particle] - end[core]) <= 0.02*(1 + 1e-5)
    assert 100 < integrator.computeBodyTemperature().value_in_unit(unit.kelvin) < 600
    assert 0 <= integrator.computeDrudeTemperature().value_in_unit(unit.kelvin) < 100
