/*
 * The part of OpenMM's own Python module (openmm.openmm) that this module builds on.
 * Debian ships no OpenMM SWIG interface files, so the classes are declared here; the
 * declarations only have to be enough for SWIG to know the base classes: wrappers for
 * them are not generated here, and the Python classes are OpenMM's own.
 */
%module(package="openmm") openmm

namespace OpenMM {

class Context;  /* passed through by pointer: the Python class is openmm.Context */

class Integrator {
public:
    virtual ~Integrator();
    virtual double getStepSize() const;
    virtual void setStepSize(double size);
    virtual double getConstraintTolerance() const;
    virtual void setConstraintTolerance(double tol);
    virtual void step(int steps) = 0;
    virtual int getIntegrationForceGroups() const;
    virtual void setIntegrationForceGroups(int groups);
};

} // namespace OpenMM
