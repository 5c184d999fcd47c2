/*
 * The body rules for Python: RigidBodyTopology, the C++ class every rigid-body integrator
 * resolves its bodies with (mrattle.integrators.RigidBodyTopology). Python code that needs
 * to know which particles form which body, or the degrees of freedom, asks it instead of
 * re-deriving the rules (mrattle.interactions, mrattle.reporters). Included from
 * integrators.i, so its typemaps (particle lists in and out, numbers) apply here.
 */

namespace OpenMM {
class System;  /* passed through by reference: the Python class is openmm.System (shared SWIG type table) */
}

/*
 * Particle lists from Python: any iterable of integers (anything with __index__), for one
 * list; any iterable of such iterables, for a list of lists (bodies, molecules). False with
 * a Python exception set on anything else.
 */
%fragment("mrattle_particleListFromPython", "header") {
static bool particleListFromPython(PyObject* input, std::vector<int>& values) {
    PyObject* iterator = PyObject_GetIter(input);
    if (iterator == NULL) {
        PyErr_SetString(PyExc_TypeError, "expected a sequence of particle indices");
        return false;
    }
    PyObject* item;
    while ((item = PyIter_Next(iterator)) != NULL) {
        PyObject* index = PyNumber_Index(item);
        Py_DECREF(item);
        long value = index != NULL ? PyLong_AsLong(index) : -1;
        Py_XDECREF(index);
        if (value == -1 && PyErr_Occurred()) {
            Py_DECREF(iterator);
            PyErr_SetString(PyExc_TypeError, "particle indices must be integers");
            return false;
        }
        if (value < INT_MIN || value > INT_MAX) {
            Py_DECREF(iterator);
            PyErr_SetString(PyExc_OverflowError, "particle index out of range of int");
            return false;
        }
        values.push_back((int) value);
    }
    Py_DECREF(iterator);
    return !PyErr_Occurred();
}
}

%fragment("mrattle_particleListsFromPython", "header", fragment="mrattle_particleListFromPython") {
static bool particleListsFromPython(PyObject* input, std::vector<std::vector<int> >& lists) {
    PyObject* iterator = PyObject_GetIter(input);
    if (iterator == NULL) {
        PyErr_SetString(PyExc_TypeError, "expected a sequence of lists of particle indices");
        return false;
    }
    PyObject* row;
    while ((row = PyIter_Next(iterator)) != NULL) {
        lists.emplace_back();
        bool converted = particleListFromPython(row, lists.back());
        Py_DECREF(row);
        if (!converted) {
            Py_DECREF(iterator);
            return false;
        }
    }
    Py_DECREF(iterator);
    return !PyErr_Occurred();
}
}

%typemap(in, fragment="mrattle_particleListsFromPython") const std::vector<std::vector<int> >& (std::vector<std::vector<int> > lists) {
    if (!particleListsFromPython($input, lists))
        SWIG_fail;
    $1 = &lists;
}
%typemap(typecheck) const std::vector<std::vector<int> >& {
    $1 = PyObject_HasAttrString($input, "__iter__") ? 1 : 0;
}
%typemap(doctype) const std::vector<std::vector<int> >& "list of list of int"

%{
#include "RigidBodyTopology.h"
%}

/* Indexed accessors that do not check the index (the C++ callers know it is in range): Python gets whole lists. */
%ignore MRattlePlugin::RigidBodyTopology::getBodyParticles;
%ignore MRattlePlugin::RigidBodyTopology::getBodyOfParticle;
%ignore MRattlePlugin::RigidBodyTopology::getBodyMass;
/* Checkpoint bookkeeping and raw masses: C++ only. */
%ignore MRattlePlugin::RigidBodyTopology::getSignature;
%ignore MRattlePlugin::RigidBodyTopology::getMasses;

%extend MRattlePlugin::RigidBodyTopology {
    /** The body of each particle of the System (RigidBodyTopology::getBodyOfParticle): -1 for a free particle, massless particle or virtual site. */
    std::vector<int> getBodyOfParticles() const {
        std::vector<int> owners($self->getMasses().size());
        for (int i = 0; i < (int) owners.size(); i++)
            owners[i] = $self->getBodyOfParticle(i);
        return owners;
    }
}

%include "RigidBodyTopology.h"
