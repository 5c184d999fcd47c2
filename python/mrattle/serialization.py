"""openmm.XmlSerializer (and so app.Simulation, copy and pickle) gives back the plugin's integrator classes."""
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
    """Make XmlSerializer.deserialize and clone of the plugin's integrators return mrattle
    classes (so app.Simulation given an integrator's XML file gets one too), and run the XML
    check on integrator documents first (pickle's loads go through it). Idempotent.

    OpenMM has no public mechanism for either. The Python class of an integrator that its
    XmlSerializer makes is chosen inside OpenMM's compiled wrappers, from a fixed list of
    OpenMM's own classes (SWIG %factory) that a plugin cannot extend. Its public deserialize()
    and clone() pick a function per kind of object; the integrators' are _deserializeIntegrator
    and _cloneIntegrator (the same names in OpenMM 7.7 and 8.x), so wrapping those two touches
    integrators only: wrapping the public functions instead would also put the check in front
    of every System, State and Force document. Where an OpenMM lacks one of the two, that one
    is left alone and a warning says what is lost.
    """
    for name in ('_deserializeIntegrator', '_cloneIntegrator'):
        function = getattr(openmm.XmlSerializer, name, None)
        if function is None:
            import warnings
            warnings.warn('mrattle: this OpenMM (%s) has no XmlSerializer.%s: XmlSerializer.deserialize and clone '
                          'return its integrators as plain openmm.Integrator; mrattle.asPluginIntegrator() gives '
                          'the plugin\'s class back' % (openmm.version.version, name))
            continue
        if not getattr(function, '_mrattleWrapped', False):
            setattr(openmm.XmlSerializer, name,
                    _returningPluginIntegrators(function, checkDocument=(name == '_deserializeIntegrator')))
