"""M-RATTLE rigid-body integrators for OpenMM.

``import mrattle`` registers the plugin's kernels with every platform of its build that
OpenMM has (Reference and CPU; OpenCL and CUDA where their kernels were built and OpenMM
has that platform: ``mrattle.PLATFORMS`` lists them), so ``mrattle.MRattleIntegrator``
can be used anywhere an OpenMM integrator can::

    import mrattle
    from openmm.unit import femtoseconds
    integrator = mrattle.MRattleIntegrator(2*femtoseconds)
    simulation = openmm.app.Simulation(topology, system, integrator)

The package also holds a StateDataReporter that reports the rigid-body temperature,
a helper that removes interactions inside rigid bodies, builders of test systems, and the
OpenMM-only RATTLE integrator the plugin is compared with (mrattle.baselines).
"""
import os as _os

import openmm as _openmm

from . import _plugin_location
from ._version import __version__  # the release, generated from CMakeLists.txt's project version


def _loadKernelPlugin(platform, relativePath, required):
    """Load a kernel plugin unless OpenMM already did (an install into its plugin folder)."""
    path = _os.path.normpath(_os.path.join(_os.path.dirname(_os.path.abspath(__file__)), relativePath))
    # Installed into OpenMM's own plugin folder, 'import openmm' has loaded it already:
    # registering the kernels twice would be harmless but wasteful.
    loaded = getattr(_openmm, 'pluginLoadedLibNames', [])
    if any(_os.path.realpath(name) == _os.path.realpath(path) for name in loaded):
        return path
    if not _os.path.isfile(path):
        if not required:
            return None
        raise ImportError("mrattle: the kernel plugin is missing: expected %s" % path)
    try:
        _openmm.Platform.loadPluginLibrary(path)
    except Exception as error:
        if not required:
            import warnings
            warnings.warn("mrattle: OpenMM could not load the %s kernels %s (%s); the M-RATTLE integrators do "
                          "not run on %s" % (platform, path, error, platform))
            return None
        raise ImportError("mrattle: OpenMM could not load the kernel plugin %s: %s" % (path, error)) from error
    return path


def _hasPlatform(name):
    return any(_openmm.Platform.getPlatform(i).getName() == name for i in range(_openmm.Platform.getNumPlatforms()))


# The SWIG module first: it loads libMRattlePlugin.so, which the kernel plugin needs.
from .integrators import RigidBodyIntegrator, INTEGRATOR_CLASSES

# INTEGRATOR_CLASSES: the integrator classes (MRattleIntegrator, ...), one registered by each
# MRATTLE_INTEGRATOR line of the SWIG module; the package exports each by its name.
globals().update((_class.__name__, _class) for _class in INTEGRATOR_CLASSES)

def _loadKernelPlugins():
    """{platform: kernel plugin path} for the build's platforms (_plugin_location.PLATFORMS) that OpenMM has."""
    paths, loaded = {}, {}
    for platform, kind, relativePath in _plugin_location.PLATFORMS:
        if not _hasPlatform(platform):
            continue
        if relativePath not in loaded:  # Reference and CPU share one plugin
            loaded[relativePath] = _loadKernelPlugin(platform, relativePath, required=(kind == 'host'))
        if loaded[relativePath] is not None:
            paths[platform] = loaded[relativePath]
    return paths


#: The kernel plugin serving each platform: {platform name: path}.
PLUGIN_PATHS = _loadKernelPlugins()
#: The platforms the plugin's kernels run on here, in the build's order (Reference, CPU, then the device platforms).
PLATFORMS = list(PLUGIN_PATHS)
#: The device platforms among them (OpenCL, CUDA): they run every integrator but RigidSplittingIntegrator.
DEVICE_PLATFORMS = [platform for platform, kind, path in _plugin_location.PLATFORMS
                    if kind == 'device' and platform in PLUGIN_PATHS]
#: The Reference and CPU kernel plugin.
PLUGIN_PATH = PLUGIN_PATHS['Reference']

from .reporters import StateDataReporter, degreesOfFreedom, kineticTemperature
from .interactions import removeIntraBodyInteractions
from .topology import rigidBodies, declareRigidBodies
from .drude import setDrudeMass
from . import models, baselines
from .serialization import asPluginIntegrator, installXmlSerializerHooks as _installXmlSerializerHooks
from .minimize import minimizeEnergy, RigidBodyMinimizer, installLocalEnergyMinimizerHook as _installMinimizerHook

_installXmlSerializerHooks()
_installMinimizerHook()


__all__ = ['RigidBodyIntegrator', 'INTEGRATOR_CLASSES'] + [_class.__name__ for _class in INTEGRATOR_CLASSES] + [
    'StateDataReporter', 'degreesOfFreedom', 'kineticTemperature', 'removeIntraBodyInteractions', 'rigidBodies',
    'declareRigidBodies', 'setDrudeMass', 'asPluginIntegrator', 'minimizeEnergy', 'RigidBodyMinimizer', 'models', 'baselines',
    'PLUGIN_PATH', 'PLUGIN_PATHS', 'PLATFORMS', 'DEVICE_PLATFORMS']
