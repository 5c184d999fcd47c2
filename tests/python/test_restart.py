"""Saving and restarting from Python: Simulation.saveCheckpoint/loadCheckpoint (bit for bit,
also in a new process; refused when the bodies differ, after which stepping waits for reinitialize() and new
positions and velocities), saveState/loadState (bit for bit), and malformed integrator XML. (XmlSerializer round trips: test_serialization.py.)"""
import os
import subprocess
import sys
import textwrap

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from conftest import platformProperties

STEPS_BEFORE, STEPS_AFTER = 20, 30


# Models restarted in a new process: the builder call, evaluated here and in the script.
MODELS = {
    # 27 rigid waters in a periodic box with a cutoff. The CPU platform keeps a neighbour list,
    # built anew after a restart, so its forces can differ at round-off: OpenMM's own
    # VerletIntegrator with SETTLE restarts 2.8e-8 nm off on OpenMM 7.7's CPU platform and
    # 7.1e-8 nm on 8.1.2's (measured, 30 steps after a checkpoint of this box), and so does
    # M-RATTLE on 8.1.2. Bit-for-bit checks on CPU therefore use the cluster in vacuum.
    'water': 'mrattle.models.waterBox(numMolecules=27, cutoff=0.45*unit.nanometers)',
    # the 27-benzene cluster in vacuum
    'benzene': 'mrattle.models.benzeneCluster()',
}


def exactModel(platform):
    """The model whose restarts are exact on this platform: see MODELS."""
    return 'benzene' if platform.getName() == 'CPU' else 'water'


def waterSimulation(platform, integrator=None, modelName='water'):
    """A Simulation of one of MODELS, velocities at 300 K."""
    model = eval(MODELS[modelName])
    if integrator is None:
        integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    simulation = app.Simulation(model.topology, model.system, integrator, platform, platformProperties(platform))
    simulation.context.setPositions(model.positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 5)
    return simulation


def stateArrays(simulation):
    state = simulation.context.getState(getPositions=True, getVelocities=True)
    return (state.getPositions(asNumpy=True).value_in_unit(unit.nanometers),
            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds),
            state.getTime().value_in_unit(unit.picoseconds), state.getStepCount())


def assertIdentical(expected, actual):
    """Positions and velocities equal to the last bit, same time and step count."""
    for e, a in zip(expected[:2], actual[:2]):
        assert np.array_equal(e, a), 'differ by up to %g' % np.abs(e - a).max()
    assert expected[2:] == actual[2:]


def test_checkpoint_continues_bit_for_bit(platform, tmp_path):
    simulation = waterSimulation(platform, modelName=exactModel(platform))
    simulation.step(STEPS_BEFORE)
    path = str(tmp_path/'run.chk')
    simulation.saveCheckpoint(path)
    simulation.step(STEPS_AFTER)
    uninterrupted = stateArrays(simulation)
    simulation.loadCheckpoint(path)
    assert simulation.currentStep == STEPS_BEFORE
    simulation.step(STEPS_AFTER)
    assertIdentical(uninterrupted, stateArrays(simulation))
    assert uninterrupted[3] == STEPS_BEFORE + STEPS_AFTER


RESTART_SCRIPT = textwrap.dedent('''
    import sys
    import numpy as np
    import openmm
    from openmm import app, unit
    import mrattle
    platformName, checkpoint, output, steps, builder = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), sys.argv[5]
    model = eval(builder)
    platform = openmm.Platform.getPlatformByName(platformName)
    properties = {'Threads': '1'} if platformName == 'CPU' else {}
    simulation = app.Simulation(model.topology, model.system, mrattle.MRattleIntegrator(2*unit.femtoseconds),
                                platform, properties)
    simulation.loadCheckpoint(checkpoint)
    simulation.step(steps)
    state = simulation.context.getState(getPositions=True, getVelocities=True)
    np.savez(output, positions=state.getPositions(asNumpy=True).value_in_unit(unit.nanometers),
             velocities=state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds),
             time=state.getTime().value_in_unit(unit.picoseconds), step=state.getStepCount())
''')


@pytest.mark.parametrize('modelName', sorted(MODELS))
def test_checkpoint_restart_in_new_process_is_bit_for_bit(platform, tmp_path, modelName):
    if platform.getName() == 'CPU' and modelName != exactModel(platform):
        pytest.skip('OpenMM %s\'s neighbour list is rebuilt after a restart: its own forces differ at round-off '
                    '(see MODELS)' % platform.getName())
    simulation = waterSimulation(platform, modelName=modelName)
    simulation.step(STEPS_BEFORE)
    checkpoint = str(tmp_path/'run.chk')
    simulation.saveCheckpoint(checkpoint)
    simulation.step(STEPS_AFTER)
    uninterrupted = stateArrays(simulation)

    script, output = tmp_path/'restart.py', str(tmp_path/'restarted.npz')
    script.write_text(RESTART_SCRIPT)
    result = subprocess.run([sys.executable, str(script), platform.getName(), checkpoint, output, str(STEPS_AFTER),
                             MODELS[modelName]],
                            capture_output=True, text=True, env=dict(os.environ), timeout=300)
    assert result.returncode == 0, result.stderr
    restarted = np.load(output)
    assertIdentical(uninterrupted, (restarted['positions'], restarted['velocities'], float(restarted['time']),
                                    int(restarted['step'])))


def test_checkpoint_with_other_bodies_is_refused_and_stepping_waits(tmp_path):
    platform = openmm.Platform.getPlatformByName('Reference')
    simulation = waterSimulation(platform)
    simulation.step(5)
    # Only the first 26 molecules rigid: the checkpoint's bodies differ from this Context's.
    other = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    for molecule in range(26):
        other.addRigidBody([3*molecule, 3*molecule + 1, 3*molecule + 2])
    otherSimulation = waterSimulation(platform, other)
    otherSimulation.step(3)
    path, statePath = str(tmp_path/'other.chk'), str(tmp_path/'state.xml')
    otherSimulation.saveCheckpoint(path)
    simulation.saveState(statePath)
    with pytest.raises(openmm.OpenMMException, match='27 rigid bodies in effect.*has 26|26 rigid bodies in effect.*has 27'):
        simulation.loadCheckpoint(path)
    # OpenMM has read the checkpoint's positions and velocities before the integrator refused it.
    with pytest.raises(openmm.OpenMMException, match='loadCheckpoint.. was refused.*reinitialize'):
        simulation.step(1)
    simulation.loadState(statePath)
    with pytest.raises(openmm.OpenMMException, match='loadCheckpoint.. was refused'):
        simulation.step(1)  # until reinitialize(): OpenMM's part of the checkpoint may be damaged
    simulation.context.reinitialize()
    simulation.loadState(statePath)
    simulation.step(5)
    with pytest.raises(openmm.OpenMMException, match='truncated'):
        simulation.context.loadCheckpoint(simulation.context.createCheckpoint()[:-5])
    with pytest.raises(openmm.OpenMMException, match='refused'):
        simulation.step(1)


def test_saved_state_continues_with_rigid_bodies(platform, tmp_path):
    simulation = waterSimulation(platform, modelName=exactModel(platform))
    simulation.step(STEPS_BEFORE)
    path = str(tmp_path/'state.xml')
    simulation.saveState(path)
    saved = stateArrays(simulation)
    simulation.step(STEPS_AFTER)
    uninterrupted = stateArrays(simulation)

    integrator = mrattle.MRattleIntegrator(2*unit.femtoseconds)
    restored = waterSimulation(platform, integrator, modelName=exactModel(platform))
    restored.loadState(path)
    loaded = stateArrays(restored)
    # Rigid velocities are given back as saved, bit for bit.
    assertIdentical(saved, loaded)
    assert loaded[3] == STEPS_BEFORE
    restored.step(STEPS_AFTER)
    continued = stateArrays(restored)
    positions = continued[0]
    for body in integrator.getBodiesInEffect():
        for i in range(3):
            for j in range(i + 1, 3):
                d0 = np.linalg.norm(saved[0][body[i]] - saved[0][body[j]])
                d1 = np.linalg.norm(positions[body[i]] - positions[body[j]])
                assert abs(d1 - d0) < 1e-10
    assert integrator.getNumDegreesOfFreedom() == 27*6
    # The same trajectory, bit for bit.
    assertIdentical(uninterrupted, continued)


def test_malformed_integrator_xml_is_refused():
    xml = openmm.XmlSerializer.serialize(mrattle.MRattleIntegrator(0.002))
    with pytest.raises(openmm.OpenMMException, match='unsupported version 7'):
        openmm.XmlSerializer.deserialize(xml.replace('version="1"', 'version="7"'))
    with pytest.raises(openmm.OpenMMException, match="'stepSize'.*fast"):
        openmm.XmlSerializer.deserialize(xml.replace('stepSize=".002"', 'stepSize="fast"'))
    withBody = xml.replace('<RigidBodies count="0"/>',
                           '<RigidBodies count="1"><Body size="2"><Particle index="1"/><Particle index="-2"/>'
                           '</Body></RigidBodies>')
    assert withBody != xml
    with pytest.raises(openmm.OpenMMException, match='Rigid body 0 lists particle -2'):
        openmm.XmlSerializer.deserialize(withBody)
    with pytest.raises(openmm.OpenMMException):
        openmm.XmlSerializer.deserialize(xml[:len(xml)//2])
