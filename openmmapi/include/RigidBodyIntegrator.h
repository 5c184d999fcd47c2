#ifndef MRATTLE_RIGID_BODY_INTEGRATOR_H_
#define MRATTLE_RIGID_BODY_INTEGRATOR_H_

#include "RigidBodySet.h"
#include "openmm/Integrator.h"
#include "openmm/Kernel.h"
#include "internal/windowsExportMRattle.h"
#include <string>
#include <vector>

namespace MRattlePlugin {

/**
 * Base of the plugin's rigid-body integrators: the body definitions, the bookkeeping in
 * effect once bound to a Context, velocity projection when the user sets velocities,
 * temperature-correct velocity generation, kinetic energy and force caching. A subclass
 * supplies its kernel name and its step.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyIntegrator : public OpenMM::Integrator {
public:
    /**
     * Declare a rigid body. Once any body is added, only declared bodies are rigid and
     * every other particle is free; with none, every molecule is a rigid body.
     * Must be called before the integrator is bound to a Context.
     *
     * @param particles  the indices of the body's particles
     * @return the index of the body
     */
    int addRigidBody(const std::vector<int>& particles);
    /** Number of bodies declared with addRigidBody(). */
    int getNumRigidBodies() const;
    /** Particles of a body declared with addRigidBody(). */
    const std::vector<int>& getRigidBodyParticles(int index) const;

    /** Rigid bodies in effect in the bound Context (declared bodies of 2+ particles, or the molecules). */
    const std::vector<std::vector<int> >& getBodiesInEffect() const;
    /** Number of rigid bodies in effect in the bound Context. */
    int getNumBodiesInEffect() const;
    /** True if body (in effect) number index is linear: its atoms are collinear (5 degrees of freedom). */
    bool isBodyLinear(int index) const;
    /** Massive particles that belong to no body in the bound Context. */
    const std::vector<int>& getFreeParticles() const;
    /** Degrees of freedom of the bound Context's System under this integrator. */
    int getNumDegreesOfFreedom() const;
    /** The body bookkeeping in effect (throws if not bound). */
    const RigidBodySet& getRigidBodySet() const;
    /**
     * Advance the simulation: every step updates the Context's state (CMMotionRemover,
     * thermostats, barostats), then runs the kernel's two halves around one evaluation of
     * the integration force groups at the new positions.
     *
     * @param steps  the number of time steps to take
     */
    void step(int steps) override;

protected:
    RigidBodyIntegrator();
    /** The kernel's name; the kernel must derive from RigidBodyKernel. */
    virtual std::string getStepKernelName() const = 0;

    void initialize(OpenMM::ContextImpl& context) override;
    void cleanup() override;
    std::vector<std::string> getKernelNames() override;
    void stateChanged(OpenMM::State::DataType changed) override;
    double computeKineticEnergy() override;
    bool kineticEnergyRequiresForce() const override {
        return false;
    }
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(const OpenMM::System& system, double temperature,
                                                          int randomSeed) const override;
    /**
     * Writes a header (format version, integrator kind, a signature of the bodies in
     * effect) and then writeCheckpointState(). OpenMM calls it after writing the Context's
     * own data (time, positions, velocities, box, random state). The next step first
     * refreshes the platform's force caches (as loading does), so that this run and one
     * continued from the checkpoint stay identical bit for bit.
     */
    void createCheckpoint(std::ostream& stream) const override;
    /**
     * Checks the header written by createCheckpoint(). OpenMM has already overwritten the
     * Context's data when this is called, so on any mismatch (other bodies, another
     * integrator, unknown format, truncated stream) the Context is put back as it was
     * before loadCheckpoint() and an OpenMMException explains what is wrong.
     */
    void loadCheckpoint(std::istream& stream) override;
    /** State of a subclass to put in checkpoints, after the base class's header; none by default. */
    virtual void writeCheckpointState(std::ostream& /*stream*/) const {
    }
    /** Read what writeCheckpointState() wrote; throw OpenMMException if it is malformed. */
    virtual void readCheckpointState(std::istream& /*stream*/) {
    }

    /** Throw unless bound to a Context. */
    void requireContext() const;

    mutable OpenMM::Kernel kernel;
    RigidBodySet bodySet;

private:
    /** Start of a step: let forces update the state; make velocities rigid if something changed them. */
    void beginStep();
    /** Compute forces at the current positions unless the cached ones are valid. */
    void ensureForces();
    /** Compute forces at the current positions (after the positions moved). */
    void computeForces();
    /** At the end of step(): remember the Context's state, which a failed loadCheckpoint() puts back. */
    void endSteps();
    std::vector<std::vector<int> > declaredBodies;
    bool forcesAreValid = false;
    bool restoringCheckpoint = false;
    bool hasVelocityChangingForce = false;
    bool inProjection = false;

    /** Recompute forces after making the platform rebuild what it caches from earlier positions. */
    void refreshForceCaches();
    /** After a thermostat collision hit part of a body, give the whole body fresh thermal velocities. */
    void thermalizeCollidedBodies();
    /** A checkpoint of the whole Context at the last point it was known to be consistent. */
    void saveRollbackState();
    /** Load the rollback checkpoint; true on success. */
    bool restoreRollbackState();
    std::vector<char> rollbackState;
    std::vector<std::string> rollbackParameterNames;
    bool rollbackStateIsCurrent = false;
    bool rollingBack = false;
    bool takingRollbackState = false;
    mutable bool refreshCachesBeforeStep = false;
};

} // namespace MRattlePlugin

#endif
