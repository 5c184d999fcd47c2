"""Issue 22 from Python: numpy scalars are accepted wherever OpenMM's own integrators accept
them, and a deeply nested document is refused before OpenMM's XML reader sees it."""
import numpy as np
import openmm
import pytest
from openmm import unit

import mrattle

FLOATS = [np.float16, np.float32, np.float64, np.longdouble]
INTS = [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint32]


@pytest.mark.parametrize('kind', FLOATS)
def test_numpy_floats_are_accepted_as_openmm_accepts_them(kind):
    step, temperature, friction = kind(0.002), kind(300), kind(1)
    for integrator, openmmIntegrator in ((mrattle.MRattleIntegrator(step), openmm.VerletIntegrator(step)),
                                         (mrattle.RigidSplittingIntegrator(step), openmm.VerletIntegrator(step)),
                                         (mrattle.MRattleLangevinIntegrator(temperature, friction, step),
                                          openmm.LangevinMiddleIntegrator(temperature, friction, step))):
        assert integrator.getStepSize() == openmmIntegrator.getStepSize()
        integrator.setStepSize(kind(0.001))
        integrator.setConstraintTolerance(kind(1e-4))
        assert integrator.getStepSize() == float(kind(0.001))*unit.picosecond
    langevin = mrattle.MRattleLangevinIntegrator(300, 1, 0.002)
    middle = openmm.LangevinMiddleIntegrator(300, 1, 0.002)
    for target in (langevin, middle):
        target.setTemperature(kind(310))
        target.setFriction(kind(2))
    assert langevin.getTemperature() == middle.getTemperature()
    assert langevin.getFriction() == middle.getFriction()
    # With units, as OpenMM takes them.
    assert mrattle.MRattleIntegrator(kind(2)*unit.femtoseconds).getStepSize() == \
        openmm.VerletIntegrator(kind(2)*unit.femtoseconds).getStepSize()


@pytest.mark.parametrize('kind', INTS)
def test_numpy_integers_are_accepted_as_openmm_accepts_them(kind):
    langevin = mrattle.MRattleLangevinIntegrator(300, 1, 0.002)
    middle = openmm.LangevinMiddleIntegrator(300, 1, 0.002)
    for target in (langevin, middle):
        target.setRandomNumberSeed(kind(7))
        target.setIntegrationForceGroups(kind(3))
    assert langevin.getRandomNumberSeed() == middle.getRandomNumberSeed() == 7
    assert langevin.getIntegrationForceGroups() == 3
    integrator = mrattle.MRattleIntegrator(kind(1))
    assert integrator.getStepSize() == 1*unit.picosecond
    assert integrator.addRigidBody(np.array([0, 1], dtype=kind)) == 0


def test_arguments_that_are_no_numbers_are_still_refused():
    with pytest.raises(TypeError):
        mrattle.MRattleIntegrator('0.002')
    with pytest.raises(TypeError):
        mrattle.MRattleLangevinIntegrator(300, 1, 0.002).setRandomNumberSeed(7.5)
    with pytest.raises(OverflowError):
        mrattle.MRattleLangevinIntegrator(300, 1, 0.002).setRandomNumberSeed(2**40)


def test_numpy_step_counts_and_body_indices(platform):
    system = openmm.System()
    for mass in (16, 1, 1):
        system.addParticle(mass)
    integrator = mrattle.MRattleIntegrator(0.001)
    integrator.addRigidBody([0, 1, 2])
    context = openmm.Context(system, integrator, platform)
    context.setPositions([openmm.Vec3(0, 0, 0), openmm.Vec3(0.1, 0, 0), openmm.Vec3(0, 0.1, 0)])
    integrator.step(np.int64(3))
    assert context.getState().getStepCount() == 3
    assert not integrator.isBodyLinear(np.int32(0))


def test_deeply_nested_xml_is_refused_before_openmm_reads_it():
    document = '<Integrator a="1">'*100000 + '</Integrator>'*100000  # what reaches the plugin's hook
    with pytest.raises(openmm.OpenMMException, match='nest deeper than'):
        openmm.XmlSerializer.deserialize(document)
    # A plugin document still reads.
    xml = openmm.XmlSerializer.serialize(mrattle.MRattleIntegrator(0.002))
    assert isinstance(openmm.XmlSerializer.deserialize(xml), mrattle.MRattleIntegrator)
