/*
 * SWIG interface of the plugin's integrators (Python module mrattle.integrators).
 *
 * The classes derive from OpenMM's Python class openmm.Integrator: SWIG's shared runtime
 * type table (do not define SWIG_TYPE_TABLE) lets openmm.Context accept them, and the
 * inherited getStepSize()/setStepSize() handle units as for OpenMM's integrators.
 * To wrap another RigidBodyIntegrator subclass: include its header below, add a
 * MRATTLE_INTEGRATOR line and a dynamic_cast line in _pluginIntegratorProxy.
 */
%module(package="mrattle", docstring="SWIG wrappers of the M-RATTLE plugin's integrators.") integrators

%pythonbegin %{
from openmm import unit
%}

%import(module="openmm") "openmm_base.i"

%{
#include "MRattleIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "RigidSplittingIntegrator.h"
#include "RigidBodyMinimizer.h"
#include <climits>
#include <exception>
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
 * Wrap one concrete integrator class whose constructor takes the step size: a Quantity
 * of time or a number of picoseconds, as for openmm.VerletIntegrator.
 */
%define MRATTLE_INTEGRATOR(CLASS, HEADER)
%typemap(doctype) double stepSize "float or Quantity (time)"
%feature("pythonprepend") MRattlePlugin::CLASS::CLASS %{
    if unit.is_quantity(stepSize):
        stepSize = stepSize.value_in_unit(unit.picosecond)
%}
%include HEADER
%enddef

MRATTLE_INTEGRATOR(MRattleIntegrator, "MRattleIntegrator.h")
MRATTLE_INTEGRATOR(RigidSplittingIntegrator, "RigidSplittingIntegrator.h")

/* The Langevin integrator: temperature, friction and step size with units, as OpenMM's LangevinMiddleIntegrator. */
%typemap(doctype) double temperature "float or Quantity (temperature)"
%typemap(doctype) double frictionCoeff "float or Quantity (1/time)"
%feature("pythonprepend") MRattlePlugin::MRattleLangevinIntegrator::MRattleLangevinIntegrator %{
    if unit.is_quantity(temperature):
        temperature = temperature.value_in_unit(unit.kelvin)
    if unit.is_quantity(frictionCoeff):
        frictionCoeff = frictionCoeff.value_in_unit(unit.picosecond**-1)
    if unit.is_quantity(stepSize):
        stepSize = stepSize.value_in_unit(unit.picosecond)
%}
%feature("pythonprepend") MRattlePlugin::MRattleLangevinIntegrator::setTemperature %{
    if unit.is_quantity(temperature):
        temperature = temperature.value_in_unit(unit.kelvin)
%}
%feature("pythonprepend") MRattlePlugin::MRattleLangevinIntegrator::setFriction %{
    if unit.is_quantity(coeff):
        coeff = coeff.value_in_unit(unit.picosecond**-1)
%}
%feature("pythonappend") MRattlePlugin::MRattleLangevinIntegrator::getTemperature %{
    val = val*unit.kelvin
%}
%feature("pythonappend") MRattlePlugin::MRattleLangevinIntegrator::getFriction %{
    val = val/unit.picosecond
%}
%include "MRattleLangevinIntegrator.h"

/* The plugin's XML check (the rule lives in C++): the package runs it before OpenMM's reader. */
%{
#include "MRattleXml.h"
%}
%inline %{
void _checkWellFormedXml(const char* document) {
    MRattlePlugin::checkWellFormedXml(document);
}
%}

/* The rigid-body minimizer; mrattle.minimizeEnergy (minimize.py) adds units. */
%include "RigidBodyMinimizer.h"

/*
 * OpenMM's XmlSerializer returns deserialized integrators as plain openmm.Integrator
 * proxies: this gives a new, non-owning proxy of the plugin's class for the same object
 * (None for other integrators). The package moves the ownership over.
 */
%inline %{
PyObject* _pluginIntegratorProxy(OpenMM::Integrator* integrator) {
    if (MRattlePlugin::MRattleIntegrator* cast = dynamic_cast<MRattlePlugin::MRattleIntegrator*>(integrator))
        return SWIG_NewPointerObj(SWIG_as_voidptr(cast), SWIGTYPE_p_MRattlePlugin__MRattleIntegrator, 0);
    if (MRattlePlugin::RigidSplittingIntegrator* cast = dynamic_cast<MRattlePlugin::RigidSplittingIntegrator*>(integrator))
        return SWIG_NewPointerObj(SWIG_as_voidptr(cast), SWIGTYPE_p_MRattlePlugin__RigidSplittingIntegrator, 0);
    if (MRattlePlugin::MRattleLangevinIntegrator* cast = dynamic_cast<MRattlePlugin::MRattleLangevinIntegrator*>(integrator))
        return SWIG_NewPointerObj(SWIG_as_voidptr(cast), SWIGTYPE_p_MRattlePlugin__MRattleLangevinIntegrator, 0);
    Py_RETURN_NONE;
}
%}

%include "topology.i"
