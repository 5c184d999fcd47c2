"""The wrapped integrators inside OpenMM's Python API: Context, Simulation, units, errors."""
import io
import math
import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import makeContext, platformProperties


def rigidWater():
    """One water molecule (O, H, H) held by three constraints, with nonzero positions."""
    system = openmm.System()
    for mass in (15.999, 1.008, 1.008):
        system.addParticle(mass)
    sites = mrattle.models.waterSites() + np.array([0.1, 0.2, 0.3])
    for i, j in ((0, 1), (0, 2), (1, 2)):
        system.addConstraint(i, j, float(np.linalg.norm(sites[i] - sites[j])))
    return system, [openmm.Vec3(*x) for x in sites]


def test_is_an_openmm_integrator():
    integrator = mrattle.MRattleIntegrator(0.002)
    assert isinstance(integrator, openmm.Integrator)
    assert isinstance(integrator, mrattle.RigidBodyIntegrator)
    assert isinstance(mrattle.RigidSplittingIntegrator(0.002), mrattle.RigidBodyIntegrator)
    with pytest.raises(AttributeError):
        mrattle.RigidBodyIntegrator()  # abstract


def test_package_exports_every_wrapped_integrator_class():
    """Each MRATTLE_INTEGRATOR line registers its class (INTEGRATOR_CLASSES), and the package
    exports exactly the registered classes, by name and through 'from mrattle import *'."""
    wrapped = [cls for cls in vars(mrattle.integrators).values()
               if isinstance(cls, type) and issubclass(cls, mrattle.RigidBodyIntegrator)
               and cls is not mrattle.RigidBodyIntegrator]
    assert 'MRattleIntegrator' in [cls.__name__ for cls in wrapped]
    assert sorted(mrattle.INTEGRATOR_CLASSES, key=lambda cls: cls.__name__) == sorted(wrapped, key=lambda cls: cls.__name__)
    exported = {}
    exec('from mrattle import *', exported)
    for cls in wrapped:
        assert getattr(mrattle, cls.__name__) is cls
        assert exported[cls.__name__] is cls
    # The reporter's energy columns and the thermostat tests take theirs from the registry.
    assert mrattle.reporters.HEAT_BATH_INTEGRATORS, 'no registered integrator has computeHeatBathEnergy()'


@pytest.mark.parametrize('cls', [mrattle.MRattleIntegrator, mrattle.RigidSplittingIntegrator])
def test_step_size_units(cls):
    fromQuantity = cls(2*unit.femtoseconds)
    assert unit.is_quantity(fromQuantity.getStepSize())
    assert fromQuantity.getStepSize().value_in_unit(unit.picoseconds) == pytest.approx(0.002, rel=1e-15)
    fromFloat = cls(0.003)
    assert fromFloat.getStepSize() == 0.003*unit.picoseconds
    fromFloat.setStepSize(0.5*unit.femtoseconds)
    assert fromFloat.getStepSize().value_in_unit(unit.femtoseconds) == pytest.approx(0.5, rel=1e-12)
    fromFloat.setStepSize(0.004)
    assert fromFloat.getStepSize() == 0.004*unit.picoseconds
    with pytest.raises(TypeError):
        cls(2*unit.nanometers)  # not a time


def test_integrator_settings():
    integrator = mrattle.MRattleIntegrator(0.001)
    integrator.setConstraintTolerance(1e-9)
    assert integrator.getConstraintTolerance() == 1e-9
    integrator.setIntegrationForceGroups({0, 2})
    assert integrator.getIntegrationForceGroups() == 0b101


def test_context_on_each_platform(platform):
    system, positions = rigidWater()
    integrator = mrattle.MRattleIntegrator(1*unit.femtoseconds)
    integrator.setConstraintTolerance(1e-10)
    context = makeContext(system, integrator, platform, positions)
    assert context.getPlatform().getName() == platform.getName()
    assert context.getIntegrator() is integrator
    context.setVelocitiesToTemperature(300*unit.kelvin, 5)
    assert integrator.getBodiesInEffect() == [[0, 1, 2]]
    assert integrator.getNumBodiesInEffect() == 1
    assert integrator.getFreeParticles() == []
    assert integrator.isBodyLinear(0) is False
    assert integrator.getNumDegreesOfFreedom() == 6
    # setVelocitiesToTemperature is exact with the rigid-body degrees of freedom.
    kinetic = context.getState(getEnergy=True).getKineticEnergy()
    assert (2*kinetic/(6*unit.MOLAR_GAS_CONSTANT_R)).value_in_unit(unit.kelvin) == pytest.approx(300, rel=1e-9)
    integrator.step(50)
    state = context.getState(getPositions=True, getEnergy=True)
    assert state.getTime().value_in_unit(unit.picoseconds) == pytest.approx(0.05)
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        assert np.linalg.norm(x[i] - x[j]) == pytest.approx(system.getConstraintParameters(i + j - 1)[2]
                                                            .value_in_unit(unit.nanometers), abs=1e-9)
    # A free rigid body keeps its kinetic energy.
    assert state.getKineticEnergy().value_in_unit(unit.kilojoules_per_mole) == \
        pytest.approx(kinetic.value_in_unit(unit.kilojoules_per_mole), rel=1e-8)


def test_explicit_bodies_and_free_particles():
    system, positions = rigidWater()
    system.addParticle(4.0)
    positions.append(openmm.Vec3(1, 1, 1))
    integrator = mrattle.MRattleIntegrator(0.001)
    assert integrator.addRigidBody([0, 1, 2]) == 0
    assert integrator.getNumRigidBodies() == 1
    assert integrator.getRigidBodyParticles(0) == [0, 1, 2]
    assert integrator.addRigidBody(np.array([3])) == 1  # any sequence of integers, a 1-particle body is free
    context = makeContext(system, integrator, openmm.Platform.getPlatformByName('Reference'), positions)
    assert integrator.getBodiesInEffect() == [[0, 1, 2]]
    assert integrator.getFreeParticles() == [3]
    assert integrator.getNumDegreesOfFreedom() == 9
    del context


def test_linear_body():
    system = openmm.System()
    for mass in (12.0, 16.0, 16.0):
        system.addParticle(mass)
    system.addConstraint(0, 1, 0.116)
    system.addConstraint(0, 2, 0.116)
    positions = [openmm.Vec3(0, 0, 0), openmm.Vec3(0.116, 0, 0), openmm.Vec3(-0.116, 0, 0)]
    integrator = mrattle.MRattleIntegrator(0.001)
    context = makeContext(system, integrator, openmm.Platform.getPlatformByName('Reference'), positions)
    assert integrator.isBodyLinear(0) is True
    assert integrator.getNumDegreesOfFreedom() == 5
    del context


def test_errors_are_python_exceptions():
    integrator = mrattle.MRattleIntegrator(0.001)
    with pytest.raises(openmm.OpenMMException, match='not bound'):
        integrator.getNumDegreesOfFreedom()
    with pytest.raises(openmm.OpenMMException, match='not bound'):
        integrator.step(1)
    with pytest.raises(openmm.OpenMMException, match='twice'):
        integrator.addRigidBody([0, 1, 0])
    with pytest.raises(openmm.OpenMMException, match='out of range'):
        integrator.getRigidBodyParticles(3)
    with pytest.raises(TypeError):
        integrator.addRigidBody([0, 1.5])
    with pytest.raises(TypeError):
        integrator.addRigidBody(7)
    # Errors found when the Context is created: a body naming a particle the System lacks.
    system, positions = rigidWater()
    integrator.addRigidBody([0, 1, 5])
    with pytest.raises(openmm.OpenMMException, match='5'):
        openmm.Context(system, integrator, openmm.Platform.getPlatformByName('Reference'))
    # And once bound: bad body index, late addRigidBody, bad step size.
    integrator = mrattle.MRattleIntegrator(0.001)
    context = makeContext(system, integrator, openmm.Platform.getPlatformByName('Reference'), positions)
    with pytest.raises(openmm.OpenMMException, match='out of range'):
        integrator.isBodyLinear(1)
    with pytest.raises(openmm.OpenMMException, match='bound'):
        integrator.addRigidBody([0, 1])
    with pytest.raises(openmm.OpenMMException, match='step size must be a finite'):
        integrator.setStepSize(float('nan'))  # refused when set (issue 13), not at the next step
    integrator.setStepSize(0)
    with pytest.raises(openmm.OpenMMException, match='step size'):
        integrator.step(1)
    with pytest.raises(openmm.OpenMMException, match='temperature'):
        context.setVelocitiesToTemperature(-5)
    del context


def test_simulation_with_reporters(platform, tmp_path):
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 11)
    dcdPath, pdbPath = str(tmp_path/'water.dcd'), str(tmp_path/'water.pdb')
    log = io.StringIO()
    simulation.reporters.append(app.DCDReporter(dcdPath, 5))
    simulation.reporters.append(app.PDBReporter(pdbPath, 10))
    simulation.reporters.append(mrattle.StateDataReporter(log, 5, step=True, temperature=True))
    simulation.step(20)
    assert simulation.currentStep == 20
    assert integrator.getNumBodiesInEffect() == 27
    assert os.path.getsize(dcdPath) > 0
    models = app.PDBFile(pdbPath)
    assert models.getNumFrames() == 2 and models.topology.getNumAtoms() == 81
    rows = [line.split(',') for line in log.getvalue().splitlines()[1:]]
    assert [int(row[0]) for row in rows] == [5, 10, 15, 20]
    assert all(math.isfinite(float(row[1])) and float(row[1]) > 0 for row in rows)
    # A checkpoint through the Context restores a state that continues identically.
    checkpoint = simulation.context.createCheckpoint()
    simulation.step(5)
    first = simulation.context.getState(getPositions=True).getPositions(asNumpy=True)
    simulation.context.loadCheckpoint(checkpoint)
    simulation.step(5)
    second = simulation.context.getState(getPositions=True).getPositions(asNumpy=True)
    if platform.getName() == 'Reference':
        assert np.array_equal(first, second)
    else:
        # The CPU platform rebuilds its neighbour list on a restore, which reorders its
        # single-precision sums: OpenMM's own VerletIntegrator differs by ~1e-9 nm here too.
        assert np.abs((first - second).value_in_unit(unit.nanometers)).max() < 1e-6
