"""Checkpoints of the previous format still load: format 3 (written by a837ed2 on OpenMM 7.7's
Reference platform, tests/python/data/format3-*; the Reference kernel framed its random state
a second time in it) restores the run bit for bit, and a format the plugin does not know is
refused saying which it reads."""
import os

import numpy as np
import openmm
import pytest
from openmm import unit

import mrattle

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'data')
WRITTEN_WITH = '7.7'  # OpenMM's own part of a checkpoint is in its version's layout


def langevinContext():
    model = mrattle.models.benzeneCluster()
    integrator = mrattle.MRattleLangevinIntegrator(300, 1.0, 0.002)
    integrator.setRandomNumberSeed(2024)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocities(model.velocities)
    return context, integrator


def readFile(name):
    with open(os.path.join(DATA, name), 'rb') as f:
        return f.read()


@pytest.mark.skipif(not openmm.__version__.startswith(WRITTEN_WITH),
                    reason='the format-3 checkpoint holds OpenMM %s Reference data' % WRITTEN_WITH)
def test_format3_checkpoint_continues_the_run_bit_for_bit():
    context, integrator = langevinContext()
    context.loadCheckpoint(readFile('format3-langevin-reference.chk'))
    integrator.step(5)  # the noise comes from the restored random stream
    state = context.getState(getPositions=True, getVelocities=True)
    found = np.concatenate([state.getPositions(asNumpy=True).value_in_unit(unit.nanometers),
                            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers/unit.picoseconds)])
    expected = np.load(os.path.join(DATA, 'format3-langevin-reference-after5.npy'))
    assert np.array_equal(expected, found), 'differs by up to %g' % np.abs(expected - found).max()


def test_checkpoint_of_this_format_round_trips_and_an_unknown_one_is_refused():
    context, integrator = langevinContext()
    checkpoint = context.createCheckpoint()
    integrator.step(3)
    straight = context.getState(getVelocities=True).getVelocities(asNumpy=True)
    context.loadCheckpoint(checkpoint)
    integrator.step(3)
    assert np.array_equal(straight, context.getState(getVelocities=True).getVelocities(asNumpy=True))
    # The plugin's part starts with its magic, then the format version (int32).
    offset = checkpoint.rindex(b'MRattleC') + 8
    version = int.from_bytes(checkpoint[offset:offset + 4], 'little')
    assert version == 4
    damaged = checkpoint[:offset] + (99).to_bytes(4, 'little') + checkpoint[offset + 4:]
    with pytest.raises(openmm.OpenMMException, match='format version 99.*reads versions 3 to 4'):
        context.loadCheckpoint(damaged)
