"""'cmake --install' into a temporary prefix gives a package that imports and runs by itself."""
import os
import subprocess
import sys

import pytest

import mrattle

# Under ctest the package is <build>/python/mrattle.
BUILD_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(mrattle.__file__))))

CHECK = """
import os, sys, openmm, mrattle
prefix = sys.argv[1]
assert os.path.realpath(mrattle.__file__).startswith(prefix), mrattle.__file__
assert os.path.realpath(mrattle.PLUGIN_PATH).startswith(prefix), mrattle.PLUGIN_PATH
model = mrattle.models.benzene()
for name in ('Reference', 'CPU'):
    integrator = mrattle.MRattleIntegrator(0.002)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName(name))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(300)
    integrator.step(5)
    print(name, integrator.getNumDegreesOfFreedom())
"""


@pytest.mark.skipif(not os.path.isfile(os.path.join(BUILD_DIR, 'CMakeCache.txt')),
                    reason='mrattle is not imported from a CMake build tree, so there is nothing to install')
def test_install_into_prefix_imports(tmp_path):
    prefix = str(tmp_path/'prefix')
    install = subprocess.run(['cmake', '--install', BUILD_DIR, '--prefix', prefix], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, universal_newlines=True, timeout=120)
    assert install.returncode == 0, install.stdout
    packages = [os.path.join(root) for root, dirs, files in os.walk(prefix) if 'mrattle' in dirs and
                os.path.isfile(os.path.join(root, 'mrattle', '__init__.py'))]
    assert len(packages) == 1
    # Only the installed package on the path: no build tree, no environment variables for the plugin.
    environment = {key: value for key, value in os.environ.items() if not key.startswith(('PYTHON', 'OPENMM', 'LD_'))}
    environment['PYTHONPATH'] = packages[0]
    result = subprocess.run([sys.executable, '-c', CHECK, os.path.realpath(prefix)], cwd=str(tmp_path),
                            env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            universal_newlines=True, timeout=120)
    assert result.returncode == 0, result.stdout
    assert result.stdout.split() == ['Reference', '6', 'CPU', '6']
