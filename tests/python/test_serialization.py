"""XmlSerializer, copy and pickle of the plugin's integrators from Python."""
import copy
import pickle

import numpy as np
import openmm
import pytest
from openmm import unit

import mrattle


@pytest.mark.parametrize('cls', [mrattle.MRattleIntegrator, mrattle.RigidSplittingIntegrator])
def test_round_trips_give_the_plugin_class(cls):
    original = cls(1.5*unit.femtoseconds)
    original.addRigidBody([0, 1, 2])
    original.addRigidBody([3, 4])
    original.setConstraintTolerance(1e-9)
    original.setIntegrationForceGroups(0b11)
    copies = [openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(original)),
              openmm.XmlSerializer.clone(original), copy.deepcopy(original), copy.copy(original),
              pickle.loads(pickle.dumps(original))]
    for duplicate in copies:
        assert type(duplicate) is cls
        assert duplicate.getStepSize().value_in_unit(unit.femtoseconds) == pytest.approx(1.5, rel=1e-12)
        assert duplicate.getConstraintTolerance() == 1e-9
        assert duplicate.getIntegrationForceGroups() == 0b11
        assert [duplicate.getRigidBodyParticles(i) for i in range(duplicate.getNumRigidBodies())] == [[0, 1, 2], [3, 4]]
    # Other integrators are left alone.
    assert type(openmm.XmlSerializer.clone(openmm.VerletIntegrator(0.001))) is openmm.VerletIntegrator
    assert mrattle.asPluginIntegrator(5) == 5


def test_deserialized_integrator_runs_the_same_trajectory():
    model = mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)
    reference = openmm.Platform.getPlatformByName('Reference')
    results = []
    for integrator in (mrattle.MRattleIntegrator(0.002),
                       openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(mrattle.MRattleIntegrator(0.002)))):
        context = openmm.Context(model.system, integrator, reference)
        context.setPositions(model.positions)
        context.setVelocitiesToTemperature(300, 3)
        integrator.step(20)
        assert integrator.getNumBodiesInEffect() == 27
        results.append(context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometers))
    assert np.array_equal(results[0], results[1])


def test_simulation_checkpoint_file(tmp_path):
    model = mrattle.models.benzeneCluster()
    from openmm import app
    reference = openmm.Platform.getPlatformByName('Reference')
    simulation = app.Simulation(model.topology, model.system, mrattle.MRattleIntegrator(0.002), reference)
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocities(model.velocities)
    simulation.step(5)
    path = str(tmp_path/'state.chk')
    simulation.saveCheckpoint(path)
    simulation.step(10)
    first = simulation.context.getState(getPositions=True).getPositions(asNumpy=True)
    restarted = app.Simulation(model.topology, model.system, mrattle.MRattleIntegrator(0.002), reference)
    restarted.loadCheckpoint(path)
    restarted.step(10)
    assert np.array_equal(restarted.context.getState(getPositions=True).getPositions(asNumpy=True), first)


def test_truncated_integrator_documents_raise_instead_of_crashing():
    # OpenMM 7.7's own XML reader can crash on a document cut inside a tag; after
    # 'import mrattle' every cut is refused with a Python exception before it gets there.
    integrator = mrattle.MRattleIntegrator(0.002)
    integrator.addRigidBody([0, 1, 2])
    integrator.addRigidBody([3, 4, 5])
    document = openmm.XmlSerializer.serialize(integrator)
    end = document.rindex('>')
    for length in range(1, end):
        # OpenMM's own front end raises ValueError when no element name is left at all.
        with pytest.raises((ValueError, openmm.OpenMMException)):
            openmm.XmlSerializer.deserialize(document[:length])
    assert openmm.XmlSerializer.deserialize(document).getNumRigidBodies() == 2


def test_simulation_reads_the_integrator_from_an_xml_file(tmp_path):
    model = mrattle.models.benzeneCluster()
    integrator = mrattle.MRattleIntegrator(0.002)
    integrator.setConstraintTolerance(1e-7)
    path = tmp_path/'integrator.xml'
    path.write_text(openmm.XmlSerializer.serialize(integrator))
    simulation = openmm.app.Simulation(model.topology, model.system, str(path),
                                       openmm.Platform.getPlatformByName('Reference'))
    assert isinstance(simulation.integrator, mrattle.MRattleIntegrator)
    assert simulation.integrator.getConstraintTolerance() == 1e-7
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocities(model.velocities)
    simulation.step(5)
    assert simulation.currentStep == 5
    assert simulation.integrator.getNumDegreesOfFreedom() == 27*6


def test_duplicated_elements_and_non_decimal_numbers_are_refused():
    integrator = mrattle.MRattleIntegrator(0.002)
    integrator.addRigidBody([0, 1, 2])
    xml = openmm.XmlSerializer.serialize(integrator)
    start, end = xml.index('<RigidBodies'), xml.index('</RigidBodies>') + len('</RigidBodies>')
    with pytest.raises(openmm.OpenMMException, match='2 <RigidBodies> elements'):
        openmm.XmlSerializer.deserialize(xml[:end] + xml[start:end] + xml[end:])
    for bad in ('0', '0x10', 'inf'):
        with pytest.raises(openmm.OpenMMException, match='step size must be nonzero|finite decimal number'):
            openmm.XmlSerializer.deserialize(xml.replace('stepSize=".002"', 'stepSize="%s"' % bad))


def test_setters_refuse_values_that_are_not_finite():
    integrator = mrattle.MRattleIntegrator(0.002)
    with pytest.raises(openmm.OpenMMException, match='finite positive'):
        integrator.setConstraintTolerance(float('nan'))
    with pytest.raises(openmm.OpenMMException, match='finite'):
        integrator.setStepSize(float('inf'))
    assert integrator.getConstraintTolerance() == 1e-5


def test_hooks_wrap_only_what_this_openmm_has(monkeypatch):
    """The two private XmlSerializer functions are wrapped once; an OpenMM without one of
    them gets a warning, not a failed import."""
    for name in ('_deserializeIntegrator', '_cloneIntegrator'):
        assert getattr(openmm.XmlSerializer, name)._mrattleWrapped
    wrapped = openmm.XmlSerializer._deserializeIntegrator
    mrattle._installXmlSerializerHooks()
    assert openmm.XmlSerializer._deserializeIntegrator is wrapped  # idempotent
    monkeypatch.delattr(openmm.XmlSerializer, '_cloneIntegrator')
    with pytest.warns(UserWarning, match='has no XmlSerializer._cloneIntegrator'):
        mrattle._installXmlSerializerHooks()
