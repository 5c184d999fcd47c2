/*
 * SWIG interface of the plugin's integrators (Python module mrattle.integrators).
 *
 * The classes derive from OpenMM's Python class openmm.Integrator: SWIG's shared runtime
 * type table (do not define SWIG_TYPE_TABLE) lets openmm.Context accept them, and the
 * inherited getStepSize()/setStepSize() handle units as for OpenMM's integrators.
 * To wrap another RigidBodyIntegrator subclass: one MRATTLE_INTEGRATOR line (below), after
 * the features of its own methods if it has any; the package 'mrattle' then exports it.
 */
%module(package="mrattle", docstring="SWIG wrappers of the M-RATTLE plugin's integrators.") integrators

%pythonbegin %{
from openmm import unit
%}

%import(module="openmm") "openmm_base.i"

%{
#include "RigidBodyIntegrator.h"
#include "RigidBodyMinimizer.h"
#include <climits>
#include <exception>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

/* C++ exceptions reach Python as openmm.OpenMMException, as with OpenMM's own wrappers. */
static void raiseOpenMMException(const char* message) {
    PyObject* module = PyImport_ImportModule("openmm");
    PyObject* type = module != NULL ? PyObject_GetAttrString(module, "OpenMMException") : NULL;
    Py_XDECREF(module);
    if (type == NULL) {
        PyErr_Clear();
        PyErr_SetString(PyExc_RuntimeError, message);
        return;
    }
    PyErr_SetString(type, message);
    Py_DECREF(type);
}
%}

%exception {
    try {
        $action
    } catch (const std::exception& e) {
        raiseOpenMMException(e.what());
        SWIG_fail;
    } catch (...) {
        raiseOpenMMException("unknown C++ exception");
        SWIG_fail;
    }
}

/*
 * Numbers as OpenMM's own wrappers take them: a double from anything with __float__, an
 * int from anything with __index__ (numpy scalars among them; SWIG's defaults take only
 * Python's float and int).
 */
%typemap(in) double {
    $1 = PyFloat_AsDouble($input);
    if ($1 == -1.0 && PyErr_Occurred())
        SWIG_fail;
}
%typemap(typecheck, precedence=SWIG_TYPECHECK_DOUBLE) double {
    $1 = (PyFloat_Check($input) || PyIndex_Check($input) || PyObject_HasAttrString($input, "__float__")) ? 1 : 0;
}
%typemap(in) int {
    PyObject* index = PyNumber_Index($input);
    if (index == NULL)
        SWIG_fail;
    long value = PyLong_AsLong(index);
    Py_DECREF(index);
    if (value == -1 && PyErr_Occurred())
        SWIG_fail;
    if (value < INT_MIN || value > INT_MAX)
        SWIG_exception_fail(SWIG_OverflowError, "in method '$symname', argument $argnum out of range of int");
    $1 = (int) value;
}
%typemap(typecheck, precedence=SWIG_TYPECHECK_INTEGER) int {
    $1 = PyIndex_Check($input) ? 1 : 0;
}

/* Particle lists: any iterable of integers in, Python lists out. */
%typemap(in) const std::vector<int>& (std::vector<int> values) {
    PyObject* iterator = PyObject_GetIter($input);
    if (iterator == NULL) {
        PyErr_Clear();
        SWIG_exception_fail(SWIG_TypeError, "in method '$symname', expected a sequence of particle indices");
    }
    PyObject* item;
    while ((item = PyIter_Next(iterator)) != NULL) {
        long value = PyLong_AsLong(item);
        Py_DECREF(item);
        if (value == -1 && PyErr_Occurred()) {
            Py_DECREF(iterator);
            PyErr_Clear();
            SWIG_exception_fail(SWIG_TypeError, "in method '$symname', particle indices must be integers");
        }
        if (value < INT_MIN || value > INT_MAX) {
            Py_DECREF(iterator);
            SWIG_exception_fail(SWIG_OverflowError, "in method '$symname', particle index out of range of int");
        }
        values.push_back((int) value);
    }
    Py_DECREF(iterator);
    if (PyErr_Occurred())
        SWIG_fail;
    $1 = &values;
}

%fragment("mrattle_intListToPython", "header") {
static PyObject* intListToPython(const std::vector<int>& values) {
    PyObject* list = PyList_New(values.size());
    for (size_t i = 0; i < values.size(); i++)
        PyList_SET_ITEM(list, i, PyLong_FromLong(values[i]));
    return list;
}
}

%typemap(out, fragment="mrattle_intListToPython") const std::vector<int>& {
    $result = intListToPython(*$1);
}

%typemap(out, fragment="mrattle_intListToPython") std::vector<int> {
    $result = intListToPython($1);
}

%typemap(out, fragment="mrattle_intListToPython") const std::vector<std::vector<int> >& {
    $result = PyList_New($1->size());
    for (size_t i = 0; i < $1->size(); i++)
        PyList_SET_ITEM($result, i, intListToPython((*$1)[i]));
}

/* Types as the Python docstrings name them. */
%typemap(doctype) const std::vector<int>& "list of int"
%typemap(doctype) std::vector<int> "list of int"
%typemap(doctype) const std::vector<std::vector<int> >& "list of list of int"

#define OPENMM_EXPORT_MRATTLE
/* The bookkeeping object is C++-only; its content is exposed by the integrator's queries. */
%ignore MRattlePlugin::RigidBodyIntegrator::getTopology;
/* OpenMM's own Python wrappers of these handle units; they reach the C++ overrides (which validate) virtually. */
%ignore MRattlePlugin::RigidBodyIntegrator::setStepSize;
%ignore MRattlePlugin::RigidBodyIntegrator::setConstraintTolerance;
/* Every molecule rigid by default, a protein too: say so once, at the first step. */
%feature("pythonprepend") MRattlePlugin::RigidBodyIntegrator::step %{
    if not getattr(self, '_checkedDefaultBodies', False):
        self._checkedDefaultBodies = True
        large = self.getLargeDefaultBodies()
        if large:
            import warnings
            bodies = self.getBodiesInEffect()
            sizes = [len(bodies[b]) for b in large]
            warnings.warn('%d molecule(s) of more than %d atoms became rigid bodies because no body was declared '
                          '(the largest has %d atoms). Declare the bodies you want rigid, e.g. '
                          "mrattle.declareRigidBodies(integrator, topology, system, 'water'), to keep the rest flexible."
                          % (len(large), RigidBodyIntegrator.LargeBodyAtoms, max(sizes)), stacklevel=2)
%}
%feature("pythonappend") MRattlePlugin::RigidBodyIntegrator::computeSystemTemperature %{
    val = val*unit.kelvin
%}
/* The kinetic-energy split (kernels on every platform): energies in kJ/mol, temperatures in K. */
%define MRATTLE_UNITS(METHOD, UNIT)
%feature("pythonappend") MRattlePlugin::RigidBodyIntegrator::METHOD %{
    val = val*UNIT
%}
%enddef
MRATTLE_UNITS(computeTranslationalKineticEnergy, unit.kilojoules_per_mole)
MRATTLE_UNITS(computeRotationalKineticEnergy, unit.kilojoules_per_mole)
MRATTLE_UNITS(computeFreeKineticEnergy, unit.kilojoules_per_mole)
MRATTLE_UNITS(computeTranslationalTemperature, unit.kelvin)
MRATTLE_UNITS(computeRotationalTemperature, unit.kelvin)
MRATTLE_UNITS(computeFreeTemperature, unit.kelvin)
%include "RigidBodyIntegrator.h"

/*
 * OpenMM's XmlSerializer returns deserialized integrators as plain openmm.Integrator
 * proxies: _pluginIntegratorProxy (below) gives a new, non-owning proxy of the plugin's
 * class for the same object, trying each wrapped class's cast in turn.
 */
%{
typedef PyObject* (*PluginIntegratorCast)(OpenMM::Integrator* integrator);
static std::vector<PluginIntegratorCast> pluginIntegratorCasts;
%}

/*
 * Wrap one concrete integrator class, declared in CLASS.h: its constructor takes the step
 * size as a Quantity of time or a number of picoseconds, as for openmm.VerletIntegrator
 * (a constructor with more arguments gets its own pythonprepend, with its signature, before
 * this line: that one is the more specific and wins), _pluginIntegratorProxy knows it, and
 * INTEGRATOR_CLASSES lists it (so the package exports it).
 */
%typemap(doctype) double stepSize "float or Quantity (time)"
%pythoncode %{
#: Every integrator class wrapped here, in the order of their MRATTLE_INTEGRATOR lines (each
#: line appends its class): the package imports and exports them from this list.
INTEGRATOR_CLASSES = []


def _inUnit(value, inUnit):
    """A number in the unit the C++ API takes: a Quantity converted, a plain number as it is."""
    return value.value_in_unit(inUnit) if unit.is_quantity(value) else value
%}
%define MRATTLE_INTEGRATOR(CLASS)
%{
#include "CLASS.h"
static PyObject* pluginIntegratorAs##CLASS(OpenMM::Integrator* integrator) {
    MRattlePlugin::CLASS* cast = dynamic_cast<MRattlePlugin::CLASS*>(integrator);
    return cast != NULL ? SWIG_NewPointerObj(SWIG_as_voidptr(cast), SWIGTYPE_p_MRattlePlugin__##CLASS, 0) : NULL;
}
%}
%init %{
    pluginIntegratorCasts.push_back(pluginIntegratorAs##CLASS);
%}
%feature("pythonprepend") MRattlePlugin::CLASS::CLASS %{
    stepSize = _inUnit(stepSize, unit.picosecond)
%}
%include "CLASS.h"
%pythoncode %{
INTEGRATOR_CLASSES.append(CLASS)
%}
%enddef

/*
 * Units as OpenMM's LangevinMiddleIntegrator and NoseHooverIntegrator take them: a bath's
 * temperature (K) and a coupling frequency (1/ps), set and got, for every class with them.
 */
%typemap(doctype) double temperature "float or Quantity (temperature)"
%typemap(doctype) double frictionCoeff "float or Quantity (1/time)"
%typemap(doctype) double collisionFrequency "float or Quantity (1/time)"
%define MRATTLE_BATH_UNITS(CLASS, SET_FREQUENCY, GET_FREQUENCY, FREQUENCY_ARGUMENT)
%feature("pythonprepend") MRattlePlugin::CLASS::setTemperature %{
    temperature = _inUnit(temperature, unit.kelvin)
%}
%feature("pythonappend") MRattlePlugin::CLASS::getTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonprepend") MRattlePlugin::CLASS::SET_FREQUENCY %{
    FREQUENCY_ARGUMENT = _inUnit(FREQUENCY_ARGUMENT, unit.picosecond**-1)
%}
%feature("pythonappend") MRattlePlugin::CLASS::GET_FREQUENCY %{
    val = val/unit.picosecond
%}
%enddef
/* A constructor (temperature, frequency, step size, ...): per signature, so that it wins over MRATTLE_INTEGRATOR's. */
%define MRATTLE_BATH_CONSTRUCTOR(CLASS, FREQUENCY_ARGUMENT, SIGNATURE)
%feature("pythonprepend") MRattlePlugin::CLASS::CLASS SIGNATURE %{
    temperature = _inUnit(temperature, unit.kelvin)
    FREQUENCY_ARGUMENT = _inUnit(FREQUENCY_ARGUMENT, unit.picosecond**-1)
    stepSize = _inUnit(stepSize, unit.picosecond)
%}
%enddef
/* The thermostats' heat-bath energy, in kJ/mol. */
%define MRATTLE_HEAT_BATH_UNITS(CLASS)
%feature("pythonappend") MRattlePlugin::CLASS::computeHeatBathEnergy %{
    val = val*unit.kilojoules_per_mole
%}
%enddef

MRATTLE_INTEGRATOR(MRattleIntegrator)
MRATTLE_INTEGRATOR(RigidSplittingIntegrator)

MRATTLE_BATH_UNITS(MRattleLangevinIntegrator, setFriction, getFriction, coeff)
MRATTLE_BATH_CONSTRUCTOR(MRattleLangevinIntegrator, frictionCoeff, (double temperature, double frictionCoeff, double stepSize))
MRATTLE_INTEGRATOR(MRattleLangevinIntegrator)

/* SWIG's Python constructor (one, with the defaults) takes its prepend from the three-argument form. */
MRATTLE_BATH_UNITS(MRattleNoseHooverIntegrator, setCollisionFrequency, getCollisionFrequency, frequency)
MRATTLE_HEAT_BATH_UNITS(MRattleNoseHooverIntegrator)
MRATTLE_BATH_CONSTRUCTOR(MRattleNoseHooverIntegrator, collisionFrequency, (double temperature, double collisionFrequency, double stepSize))
MRATTLE_BATH_CONSTRUCTOR(MRattleNoseHooverIntegrator, collisionFrequency, (double temperature, double collisionFrequency, double stepSize, int chainLength))
MRATTLE_BATH_CONSTRUCTOR(MRattleNoseHooverIntegrator, collisionFrequency, (double temperature, double collisionFrequency, double stepSize, int chainLength, int numMTS))
MRATTLE_BATH_CONSTRUCTOR(MRattleNoseHooverIntegrator, collisionFrequency, (double temperature, double collisionFrequency, double stepSize, int chainLength, int numMTS, int numYoshidaSuzuki))
MRATTLE_INTEGRATOR(MRattleNoseHooverIntegrator)

MRATTLE_BATH_UNITS(MRattleBussiIntegrator, setCollisionFrequency, getCollisionFrequency, frequency)
MRATTLE_HEAT_BATH_UNITS(MRattleBussiIntegrator)
MRATTLE_BATH_CONSTRUCTOR(MRattleBussiIntegrator, collisionFrequency, (double temperature, double collisionFrequency, double stepSize))
%feature("pythonprepend") MRattlePlugin::MRattleBussiIntegrator::setTimeConstant %{
    tau = _inUnit(tau, unit.picosecond)
%}
%feature("pythonappend") MRattlePlugin::MRattleBussiIntegrator::getTimeConstant %{
    val = val*unit.picosecond
%}
MRATTLE_INTEGRATOR(MRattleBussiIntegrator)

/* OpenMM's DrudeLangevinIntegrator's units: two baths (K, 1/ps), the hard wall in nm. */
MRATTLE_BATH_UNITS(MRattleDrudeLangevinIntegrator, setFriction, getFriction, coeff)
%feature("pythonprepend") MRattlePlugin::MRattleDrudeLangevinIntegrator::MRattleDrudeLangevinIntegrator(double temperature, double frictionCoeff, double drudeTemperature, double drudeFrictionCoeff, double stepSize) %{
    temperature = _inUnit(temperature, unit.kelvin)
    frictionCoeff = _inUnit(frictionCoeff, unit.picosecond**-1)
    drudeTemperature = _inUnit(drudeTemperature, unit.kelvin)
    drudeFrictionCoeff = _inUnit(drudeFrictionCoeff, unit.picosecond**-1)
    stepSize = _inUnit(stepSize, unit.picosecond)
%}
%feature("pythonprepend") MRattlePlugin::MRattleDrudeLangevinIntegrator::setDrudeTemperature %{
    temperature = _inUnit(temperature, unit.kelvin)
%}
%feature("pythonprepend") MRattlePlugin::MRattleDrudeLangevinIntegrator::setDrudeFriction %{
    coeff = _inUnit(coeff, unit.picosecond**-1)
%}
%feature("pythonprepend") MRattlePlugin::MRattleDrudeLangevinIntegrator::setMaxDrudeDistance %{
    distance = _inUnit(distance, unit.nanometer)
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeLangevinIntegrator::getDrudeTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeLangevinIntegrator::getDrudeFriction %{
    val = val/unit.picosecond
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeLangevinIntegrator::getMaxDrudeDistance %{
    val = val*unit.nanometer
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeLangevinIntegrator::computeDrudeTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeLangevinIntegrator::computeBodyTemperature %{
    val = val*unit.kelvin
%}
MRATTLE_INTEGRATOR(MRattleDrudeLangevinIntegrator)

/* OpenMM's DrudeNoseHooverIntegrator's units: two chains (K, 1/ps), the hard wall in nm, the heat baths in kJ/mol. */
MRATTLE_BATH_UNITS(MRattleDrudeNoseHooverIntegrator, setCollisionFrequency, getCollisionFrequency, frequency)
MRATTLE_HEAT_BATH_UNITS(MRattleDrudeNoseHooverIntegrator)
%define MRATTLE_DRUDE_NOSE_HOOVER_CONSTRUCTOR(SIGNATURE)
%feature("pythonprepend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::MRattleDrudeNoseHooverIntegrator SIGNATURE %{
    temperature = _inUnit(temperature, unit.kelvin)
    collisionFrequency = _inUnit(collisionFrequency, unit.picosecond**-1)
    drudeTemperature = _inUnit(drudeTemperature, unit.kelvin)
    drudeCollisionFrequency = _inUnit(drudeCollisionFrequency, unit.picosecond**-1)
    stepSize = _inUnit(stepSize, unit.picosecond)
%}
%enddef
MRATTLE_DRUDE_NOSE_HOOVER_CONSTRUCTOR((double temperature, double collisionFrequency, double drudeTemperature, double drudeCollisionFrequency, double stepSize))
MRATTLE_DRUDE_NOSE_HOOVER_CONSTRUCTOR((double temperature, double collisionFrequency, double drudeTemperature, double drudeCollisionFrequency, double stepSize, int chainLength))
MRATTLE_DRUDE_NOSE_HOOVER_CONSTRUCTOR((double temperature, double collisionFrequency, double drudeTemperature, double drudeCollisionFrequency, double stepSize, int chainLength, int numMTS))
MRATTLE_DRUDE_NOSE_HOOVER_CONSTRUCTOR((double temperature, double collisionFrequency, double drudeTemperature, double drudeCollisionFrequency, double stepSize, int chainLength, int numMTS, int numYoshidaSuzuki))
%typemap(doctype) double drudeTemperature "float or Quantity (temperature)"
%typemap(doctype) double drudeCollisionFrequency "float or Quantity (1/time)"
%feature("pythonprepend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::setDrudeTemperature %{
    temperature = _inUnit(temperature, unit.kelvin)
%}
%feature("pythonprepend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::setDrudeCollisionFrequency %{
    frequency = _inUnit(frequency, unit.picosecond**-1)
%}
%feature("pythonprepend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::setMaxDrudeDistance %{
    distance = _inUnit(distance, unit.nanometer)
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::getDrudeTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::getDrudeCollisionFrequency %{
    val = val/unit.picosecond
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::getMaxDrudeDistance %{
    val = val*unit.nanometer
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::computeDrudeTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonappend") MRattlePlugin::MRattleDrudeNoseHooverIntegrator::computeBodyTemperature %{
    val = val*unit.kelvin
%}
MRATTLE_INTEGRATOR(MRattleDrudeNoseHooverIntegrator)

/* The plugin's XML check (the rule lives in C++): the package runs it before OpenMM's reader. */
%{
#include "MRattleXml.h"
%}
%inline %{
void _checkWellFormedXml(const char* document) {
    MRattlePlugin::checkWellFormedXml(document);
}
%}

/* The rigid-body minimizer; mrattle.minimizeEnergy (minimize.py) adds units and the reporter. */
%ignore MRattlePlugin::ForwardingMinimizationReporter;
%ignore MRattlePlugin::RigidBodyMinimizationReporter;
%include "RigidBodyMinimizer.h"
%{
/*
 * A Python reporter (any object with OpenMM 8's report(iteration, x, grad, args): x and grad
 * tuples of floats, args a dict) for RigidBodyMinimizer::minimize. An exception it raises
 * is kept and raised again by _minimizeReporting, after the Context is left at the best point.
 */
class PythonMinimizationReporter : public MRattlePlugin::RigidBodyMinimizationReporter {
public:
    explicit PythonMinimizationReporter(PyObject* reporter) : reporter(reporter) {
    }
    ~PythonMinimizationReporter() {
        Py_XDECREF(type);
        Py_XDECREF(value);
        Py_XDECREF(traceback);
    }
    bool report(int iteration, const std::vector<double>& x, const std::vector<double>& grad,
                std::map<std::string, double>& args) override {
        PyObject* xs = PyTuple_New(x.size());
        PyObject* grads = PyTuple_New(grad.size());
        PyObject* argDict = PyDict_New();
        for (size_t i = 0; i < x.size(); i++)
            PyTuple_SET_ITEM(xs, i, PyFloat_FromDouble(x[i]));
        for (size_t i = 0; i < grad.size(); i++)
            PyTuple_SET_ITEM(grads, i, PyFloat_FromDouble(grad[i]));
        for (const auto& entry : args) {
            PyObject* number = PyFloat_FromDouble(entry.second);
            PyDict_SetItemString(argDict, entry.first.c_str(), number);
            Py_DECREF(number);
        }
        PyObject* result = PyObject_CallMethod(reporter, "report", "iOOO", iteration, xs, grads, argDict);
        Py_DECREF(xs);
        Py_DECREF(grads);
        Py_DECREF(argDict);
        int stop = result != NULL ? PyObject_IsTrue(result) : -1;
        Py_XDECREF(result);
        if (stop < 0) {
            PyErr_Fetch(&type, &value, &traceback);
            throw std::runtime_error("the Python reporter's report() raised an exception");
        }
        return stop != 0;
    }
    /** Raise the reporter's exception again; false if it raised none. */
    bool restoreError() {
        if (type == NULL)
            return false;
        PyErr_Restore(type, value, traceback);
        type = value = traceback = NULL;
        return true;
    }

private:
    PyObject* reporter;
    PyObject* type = NULL;
    PyObject* value = NULL;
    PyObject* traceback = NULL;
};
%}
%exception _minimizeReporting {
    $action
    if (result == NULL)
        SWIG_fail;
}
%inline %{
/* RigidBodyMinimizer::minimize with a Python reporter: the report, or NULL with the Python error set. */
PyObject* _minimizeReporting(OpenMM::Context& context, double tolerance, int maxIterations, PyObject* reporter) {
    PythonMinimizationReporter forward(reporter);
    MRattlePlugin::RigidBodyMinimizationReport report;
    try {
        report = MRattlePlugin::RigidBodyMinimizer::minimize(context, tolerance, maxIterations, &forward);
    } catch (const std::exception& e) {
        if (!forward.restoreError())
            raiseOpenMMException(e.what());
        return NULL;
    }
    return SWIG_NewPointerObj(new MRattlePlugin::RigidBodyMinimizationReport(report),
                              SWIGTYPE_p_MRattlePlugin__RigidBodyMinimizationReport, SWIG_POINTER_OWN);
}
%}

/* The plugin's class of a deserialized integrator (None for other integrators); the package moves the ownership over. */
%inline %{
PyObject* _pluginIntegratorProxy(OpenMM::Integrator* integrator) {
    for (PluginIntegratorCast cast : pluginIntegratorCasts)
        if (PyObject* proxy = cast(integrator))
            return proxy;
    Py_RETURN_NONE;
}
%}

%include "topology.i"
