"""Shared fixtures of the Python tests. Run through ctest (Python.<file>), which puts the
build tree's package on PYTHONPATH."""
import math
import os

import numpy as np
import openmm
import pytest

import mrattle


def pytest_sessionstart(session):
    # Under ctest the package must be the build tree's, not some installed copy.
    expected = os.environ.get('MRATTLE_EXPECT_PACKAGE_DIR')
    if expected and os.path.realpath(os.path.dirname(mrattle.__file__)) != os.path.realpath(expected):
        raise pytest.UsageError('imported mrattle from %s, expected %s' % (mrattle.__file__, expected))


def pytest_collection_finish(session):
    # An empty collection (pytest's exit code 5) must never pass for a green suite.
    if not session.items:
        raise pytest.UsageError('no Python tests were collected from %s' % os.path.dirname(__file__))


#: The host platforms of the build's list (Reference, CPU): every integrator runs there.
HOST_PLATFORMS = [name for name in mrattle.PLATFORMS if name not in mrattle.DEVICE_PLATFORMS]


@pytest.fixture(params=HOST_PLATFORMS)
def platform(request):
    """Each host platform the plugin's kernels run on (the device platforms have their own
    tests: a device Context is slow to make through pocl)."""
    return openmm.Platform.getPlatformByName(request.param)


@pytest.fixture(params=mrattle.DEVICE_PLATFORMS or [pytest.param(None, marks=pytest.mark.skip(
    reason='no device platform (OpenCL, CUDA) with the plugin\'s kernels in this OpenMM'))])
def devicePlatform(request):
    """Each device platform (OpenCL, CUDA) the plugin's kernels run on here; skipped, saying
    why, where the platform has no device (CUDA without a GPU)."""
    problem = _deviceProblem(request.param)
    if problem:
        pytest.skip(problem)
    return openmm.Platform.getPlatformByName(request.param)


_deviceProblems = {}


def _deviceProblem(name):
    """Why a device platform cannot make a Context here (e.g. no CUDA device), or None: once per session."""
    if name not in _deviceProblems:
        _deviceProblems[name] = None
        system = openmm.System()
        system.addParticle(1.0)
        try:
            openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName(name))
        except Exception as error:
            _deviceProblems[name] = 'no %s device: %s' % (name, error)
    return _deviceProblems[name]


def platformProperties(platform):
    """One CPU thread (deterministic sums, and the machine is shared); double precision on a device."""
    if platform.getName() == 'CPU':
        return {'Threads': '1'}
    return {'Precision': 'double'} if platform.getName() in mrattle.DEVICE_PLATFORMS else {}


def meanAndError(values):
    """The mean of independent values and its standard error."""
    return np.mean(values), np.std(values, ddof=1)/math.sqrt(len(values))


def makeContext(system, integrator, platform, positions, velocities=None):
    context = openmm.Context(system, integrator, platform, platformProperties(platform))
    context.setPositions(positions)
    if velocities is not None:
        context.setVelocities(velocities)
    return context
