#ifndef MRATTLE_RIGID_BODY_INTEGRATOR_H_
#define MRATTLE_RIGID_BODY_INTEGRATOR_H_

#include "RigidBodyTopology.h"
#include "openmm/Integrator.h"
#include "openmm/Kernel.h"
#include "internal/RigidBodyState.h"
#include "internal/RigidBodyStepState.h"
#include "internal/windowsExportMRattle.h"
#include <string>
#include <vector>

namespace MRattlePlugin {

struct RigidBodyIntegratorName;
class RigidBodyStepKernel;

/**
 * Base of the plugin's rigid-body integrators: the declared bodies, the body topology in
 * effect once bound to a Context, and the glue to the step kernel, which does all the
 * per-particle work (the step, velocity projection, kinetic energy, temperatures,
 * thermostat collisions). A subclass names itself and its step kernel (IntegratorNames).
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
    /**
     * With no body declared every molecule is rigid, a protein too: the bodies in effect
     * that were made rigid that way and have more than LargeBodyAtoms atoms (empty when
     * bodies were declared). Python's mrattle warns once when it is not empty.
     */
    std::vector<int> getLargeDefaultBodies() const;
    /** More atoms than this in a body nobody declared is worth a warning. */
    static constexpr int LargeBodyAtoms = 30;
    /** Degrees of freedom of the bound Context's System under this integrator. */
    int getNumDegreesOfFreedom() const;
    /**
     * The instantaneous temperature 2 KE / (DOF k_B) with this integrator's degrees of
     * freedom, in Kelvin. OpenMM 8's StateDataReporter uses it when an integrator has it, so
     * it then reports the right temperature for rigid bodies (OpenMM 7.7's counts 3 per
     * particle minus constraints: use mrattle.StateDataReporter there).
     */
    double computeSystemTemperature();
    /**
     * The kinetic energy of the bodies' centre-of-mass motion, sum M V^2 / 2 (kJ/mol), from
     * the Context's velocities: those the integrator keeps, so for MRattleLangevinIntegrator
     * those of the middle of the last step, half a step behind the positions, as its kinetic
     * energy (the same convention as LangevinMiddleIntegrator's). Computed by the kernel on
     * every platform. The translational, rotational and free kinetic energies add up to the
     * State's kinetic energy to round-off.
     */
    double computeTranslationalKineticEnergy();
    /** The kinetic energy of the bodies' rotation about their centres of mass, sum over bodies of m |v - V|^2 / 2 (kJ/mol). */
    double computeRotationalKineticEnergy();
    /** The kinetic energy of the free particles (massive particles in no body), sum m v^2 / 2 (kJ/mol). */
    double computeFreeKineticEnergy();
    /**
     * Translational degrees of freedom of the bodies: 3 each, minus their share of a
     * CMMotionRemover's 3, the bodies' fraction of the mass of bodies and free particles
     * (so all 3 when every massive particle is in a body; not an integer in general). The
     * translational, rotational and free degrees of freedom add up to getNumDegreesOfFreedom().
     */
    double getTranslationalDegreesOfFreedom() const;
    /** Rotational degrees of freedom of the bodies: 3 each, 2 for a linear body, 0 for one whose atoms coincide (at the last positions set). */
    int getRotationalDegreesOfFreedom() const;
    /** Degrees of freedom of the free particles: 3 each, minus constraints among them, minus their mass share of a CMMotionRemover's 3. */
    double getFreeDegreesOfFreedom() const;
    /** 2 computeTranslationalKineticEnergy() / (getTranslationalDegreesOfFreedom() k_B), in Kelvin (0 without such degrees of freedom). */
    double computeTranslationalTemperature();
    /** 2 computeRotationalKineticEnergy() / (getRotationalDegreesOfFreedom() k_B), in Kelvin (0 without such degrees of freedom). */
    double computeRotationalTemperature();
    /** 2 computeFreeKineticEnergy() / (getFreeDegreesOfFreedom() k_B), in Kelvin (0 without such degrees of freedom). */
    double computeFreeTemperature();
    /** The body topology in effect (throws if not bound). */
    const RigidBodyTopology& getTopology() const;
    /**
     * Set the step size in picoseconds. Refuses a number that is not finite; zero can be
     * set (as the constructor's argument), but step() refuses it.
     */
    void setStepSize(double size) override;
    /** Set the constraint tolerance (free-particle constraints); refuses anything but a finite positive number. */
    void setConstraintTolerance(double tolerance) override;
    /**
     * Advance the simulation: every step updates the Context's state (CMMotionRemover,
     * thermostats, barostats), then the kernel takes the step.
     *
     * @param steps  the number of time steps to take
     */
    void step(int steps) override;

protected:
    /** @param names  the subclass's entry of IntegratorNames (internal/RigidBodyKernels.h) */
    explicit RigidBodyIntegrator(const RigidBodyIntegratorName& names);
    /** The class name messages use, from IntegratorNames. */
    const char* getIntegratorName() const;
    /** The step kernel of the bound Context, for a subclass's own queries (throws if not bound). */
    RigidBodyStepKernel& getStepKernel() const;
    /**
     * A setting's check: throw an OpenMMException "<integrator>: the <what> must be a finite
     * number >= 0 <unit>, got <value>" (> 0 if zero is not allowed) unless it is one.
     */
    static void requireNonNegativeSetting(const char* integrator, const char* what, const char* unit, double value,
                                          bool zeroAllowed = true);

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
     * Writes a header (format version, kernel name, a signature of the bodies in effect),
     * then the kernel's own state. OpenMM calls it after writing the Context's own data
     * (time, positions, velocities, box, parameters, random state).
     */
    void createCheckpoint(std::ostream& stream) const override;
    /**
     * Checks the header written by createCheckpoint() and loads the kernel's state. OpenMM
     * has already overwritten the Context's data when this is called (unchecked: a damaged
     * checkpoint can leave garbage in its random state, box and parameters); on any
     * mismatch (other bodies, another integrator, unknown format, truncated stream) it
     * throws an OpenMMException saying what is wrong, has the kernel make the platform's
     * unchecked state safe, and refuses to step until Context::reinitialize() is called
     * (then the state is set again) or a checkpoint that fits is loaded.
     */
    void loadCheckpoint(std::istream& stream) override;
    /**
     * Writes the integrator's class name, a format version and the kernel's time-varying
     * state (a thermostat's: the Nose-Hoover chain, CSVR's accumulated work; none for the
     * others), so that Context::setState() of a State taken with the integrator's parameters
     * restores it bit for bit (replica exchange on one Context). A random stream is not
     * included: it stays the Context's.
     */
    void serializeParameters(OpenMM::SerializationNode& node) const override;
    /**
     * Restores what serializeParameters() wrote. Throws an OpenMMException saying what is
     * wrong for parameters of another integrator class, another format, other names or sizes
     * (another chain length) or values that are not finite; empty parameters (an integrator
     * that writes none, as OpenMM's own) only an integrator without such state accepts.
     * Context::setState() has set the positions and velocities before this is called.
     */
    void deserializeParameters(const OpenMM::SerializationNode& node) override;

private:
    friend class RigidBodyMinimizer;
    /**
     * Set by RigidBodyMinimizer during its search, whose setPositions() are exact rigid images
     * of the bodies' shapes: they only invalidate the forces. Its last setPositions(), made
     * with this cleared, checks the shapes and projects the velocities as any other.
     */
    bool minimizing = false;
    /** Throw unless bound to a Context. */
    void requireContext() const;
    /** step()'s steps; step() then has the kernel check those it did not yet (finishSteps()). */
    void stepLoop(int steps);
    /** The kernel's translational, rotational and free kinetic energies (index 0, 1, 2). */
    double kineticEnergyPart(int part);
    /** Whether this integrator is the one that steps the Context (it may be a member of a CompoundIntegrator). */
    bool isCurrentIntegrator() const;
    /** stateChanged(Positions): the kernel takes the new shapes of the bodies (refused if not finite). */
    void useNewPositions();
    /** stateChanged(Positions or Velocities): make the Context's velocities rigid now, later, or keep them. */
    void useNewVelocities(bool byPositions);
    /** The step kernel's state: everything but the step. */
    RigidBodyState& state() const;
    const RigidBodyIntegratorName* names;
    mutable OpenMM::Kernel kernel;
    std::vector<std::vector<int> > declaredBodies;
    RigidBodyTopology topology;
    /** Flags of the Context's state between calls (forces valid, positions set, checkpoint refused, ...). */
    RigidBodyStepState stepState;
};

} // namespace MRattlePlugin

#endif
