"""openmm.XmlSerializer, copy and pickle give back the plugin's integrator classes."""
import openmm

from . import integrators


def asPluginIntegrator(integrator):
    """The same integrator as its mrattle class (MRattleIntegrator, RigidSplittingIntegrator).

    openmm.XmlSerializer creates the C++ object of the right class but wraps it as a plain
    openmm.Integrator; after ``import mrattle`` XmlSerializer.deserialize and clone call this
    themselves. Anything else is returned unchanged.
    """
    if isinstance(integrator, integrators.RigidBodyIntegrator) or not isinstance(integrator, openmm.Integrator):
        return integrator
    proxy = integrators._pluginIntegratorProxy(integrator)
    if proxy is None:
        return integrator
    # One owner of the C++ object: the new proxy takes over from the plain one.
    proxy.thisown = integrator.thisown
    integrator.thisown = False
    return proxy


def _checkWellFormed(document):
    """OpenMM 7.7's XML reader (irrXML) reads past the end of a truncated document and
    overflows its stack on deeply nested ones, crashing the process: refuse anything the
    plugin's check (C++ checkWellFormedXml) does not pass before it gets there."""
    try:
        integrators._checkWellFormedXml(document)
    except openmm.OpenMMException as error:
        raise openmm.OpenMMException('XmlSerializer.deserialize: %s; the file may be truncated or corrupted'
                                     % error) from None


def _returningPluginIntegrators(function, checkDocument=False):
    def wrapper(*arguments):
        if checkDocument and arguments and isinstance(arguments[0], str):
            _checkWellFormed(arguments[0])
        return asPluginIntegrator(function(*arguments))
    wrapper.__doc__ = function.__doc__
    wrapper._mrattleWrapped = True
    return staticmethod(wrapper)


def installXmlSerializerHooks():
    """Make XmlSerializer.deserialize/clone (and so copy.deepcopy and pickle) of the plugin's
    integrators return mrattle classes. Idempotent."""
    for name in ('_deserializeIntegrator', '_cloneIntegrator'):
        function = getattr(openmm.XmlSerializer, name)
        if not getattr(function, '_mrattleWrapped', False):
            setattr(openmm.XmlSerializer, name,
                    _returningPluginIntegrators(function, checkDocument=(name == '_deserializeIntegrator')))
