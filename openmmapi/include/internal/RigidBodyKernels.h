#ifndef MRATTLE_RIGID_BODY_KERNELS_H_
#define MRATTLE_RIGID_BODY_KERNELS_H_

#include "RigidBodyTopology.h"
#include "openmm/KernelImpl.h"
#include "openmm/Platform.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyIntegrator;
class MRattleIntegrator;
class MRattleLangevinIntegrator;
class MRattleNoseHooverIntegrator;
class MRattleBussiIntegrator;
class RigidSplittingIntegrator;

/**
 * An integrator's time-varying state as a State carries it (Context::getState() with the
 * integrator's parameters): named lists of numbers, e.g. a Nose-Hoover chain's positions.
 */
typedef std::map<std::string, std::vector<double> > IntegratorParameterValues;

/**
 * What every rigid-body integrator needs from its platform. The kernel owns the step and
 * all per-particle and per-body work (the API class does O(1) work per step); it keeps its
 * own copy of the body topology and the state that depends on the configuration (which
 * bodies are linear) or on the run (random streams), and writes that state into
 * checkpoints. Each integrator has its own kernel (a subclass below, with its own name and
 * an execute() that takes that integrator), so that a platform can implement each one. A
 * subclass gives Name() (the kernel's), IntegratorName() (the class name failures are
 * reported by on every platform), IntegratorType and execute(); its destructor, the key
 * function, is defined in its integrator's .cpp (docs/contributing.md).
 */
class OPENMM_EXPORT_MRATTLE RigidBodyKernel : public OpenMM::KernelImpl {
public:
    RigidBodyKernel(const std::string& name, const OpenMM::Platform& platform) : OpenMM::KernelImpl(name, platform) {
    }
    ~RigidBodyKernel() override;
    /**
     * @param topology    the bodies in effect; the kernel keeps a copy
     * @param integrator  the integrator (its settings at this point, e.g. a random seed)
     */
    virtual void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                            const RigidBodyIntegrator& integrator) = 0;
    /*
     * The step contract of each subclass's execute(): one step of its integrator, written on
     * every platform as the same list of phases (ReferenceRigidBodyDynamics,
     * CommonRigidBodyDynamics: beginStep, then kicks, drifts with resets, projections and the
     * forces in the integrator's order, then endStep). beginStep does, with an
     * AndersenThermostat in the System, the collisions of whole bodies (a body with a collided
     * atom gets fresh thermal velocities as a whole), then the forces unless forcesAreValid.
     * endStep advances time and step count. A step that fails throws an OpenMMException
     * naming the integrator (IntegratorName()), from this execute(), a later one of the same
     * step(n) call, or finishSteps() (the device platforms find a failure lazily), and
     * leaves positions, velocities, box, time and step count as they were before that step.
     *
     * forcesAreValid -- in: the Context's forces are those at the current positions for the
     * integration force groups; out: true after a step.
     */
    /**
     * The Context's positions were set: classify the bodies' shapes (linear or not) from
     * them. Throws an OpenMMException naming a particle whose position is not finite.
     */
    virtual void updateShapes(OpenMM::ContextImpl& context) = 0;
    /**
     * Make the Context's velocities rigid: each body whose velocities are not rigid-body
     * motion at the current positions is replaced by its mass-weighted projection;
     * velocities along free-particle constraints are removed to the given tolerance.
     * Velocities that are already rigid (to round-off) are left bit for bit as they are.
     * Throws an OpenMMException naming a particle whose velocity is not finite.
     */
    virtual void projectVelocities(OpenMM::ContextImpl& context, double tolerance) = 0;
    /**
     * Maxwell-Boltzmann velocities projected onto the rigid degrees of freedom, rescaled to
     * exactly the given temperature with the rigid-body degrees of freedom (and without
     * centre-of-mass motion if the System has a CMMotionRemover).
     */
    virtual std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                                  int randomSeed, double tolerance) = 0;
    /** Sum of m v^2 / 2 over the Context's velocities. */
    virtual double computeKineticEnergy(OpenMM::ContextImpl& context) = 0;
    /**
     * computeKineticEnergy() split three ways, from the same velocities: translational, the
     * sum of M V^2 / 2 over the bodies (M a body's mass, V its centre-of-mass velocity);
     * rotational, the sum over the bodies of m |v - V|^2 / 2 over their atoms; free, the sum
     * of m v^2 / 2 over the massive particles of no body. The three add up to
     * computeKineticEnergy() to round-off.
     */
    virtual void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                        double& free) = 0;
    /**
     * The end of a step(n) call (or of one a step of which threw): a platform that finds a
     * failed step late (the device platforms) checks every step not yet checked now, puts
     * back the state from before a failed one and throws. Default: nothing (each step was
     * checked as it ended).
     */
    virtual void finishSteps(OpenMM::ContextImpl& context) {
    }
    /** Whether body number index is linear (collinear atoms, 5 degrees of freedom) at the last positions set. */
    virtual bool isBodyLinear(int index) const = 0;
    /** The bodies' degrees of freedom at the last positions set: 6 each, 5 if linear, 3 if its atoms coincide. */
    virtual int getBodyDegreesOfFreedom() const = 0;
    /**
     * Write the kernel's own state (e.g. its random stream) into a checkpoint, unframed: the
     * checkpoint header (RigidBodyCheckpointHeader) frames it.
     */
    virtual void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const = 0;
    /**
     * Read what createCheckpoint() wrote (the stream holds exactly that); throw an
     * OpenMMException saying what is wrong if it does not fit.
     */
    virtual void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) = 0;
    /**
     * A checkpoint was refused after OpenMM had read its own part of it unchecked: make the
     * platform state OpenMM read that a later step could crash on (e.g. a random generator's)
     * valid again. The integrator refuses to step until Context::reinitialize() in any case.
     * Default: nothing.
     */
    virtual void discardRefusedCheckpoint(OpenMM::ContextImpl& context) {
    }
    /** The integrator's class name (the subclass's IntegratorName()), which messages use. */
    virtual std::string integratorName() const = 0;
    /**
     * The integrator's time-varying state that a State carries (a thermostat's variables, not
     * its random stream: replicas sharing one Context must not share one). Default: none.
     */
    virtual IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) {
        return {};
    }
    /** Set what getIntegratorParameters() returns (the integrator has checked the names and sizes). */
    virtual void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) {
    }
};

/** M-RATTLE: the position update resets each body with the 3 + 3 conditions. */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleStep";
    }
    /** The integrator's class name, which messages name it by on every platform. */
    static std::string IntegratorName() {
        return "MRattleIntegrator";
    }
    IntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform) : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleStepKernel() override;
    /** The integrator that execute() takes. */
    typedef MRattleIntegrator IntegratorType;
    /** One step of this integrator: see RigidBodyKernel's step contract. */
    virtual void execute(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator, bool& forcesAreValid) = 0;
};

/** Langevin dynamics with M-RATTLE (MRattleLangevinIntegrator). */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleLangevinStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleLangevinStep";
    }
    /** The integrator's class name, which messages name it by on every platform. */
    static std::string IntegratorName() {
        return "MRattleLangevinIntegrator";
    }
    IntegrateMRattleLangevinStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleLangevinStepKernel() override;
    /** The integrator that execute() takes. */
    typedef MRattleLangevinIntegrator IntegratorType;
    /** One step of this integrator: see RigidBodyKernel's step contract. */
    virtual void execute(OpenMM::ContextImpl& context, const MRattleLangevinIntegrator& integrator, bool& forcesAreValid) = 0;
};

/** Velocity Verlet with M-RATTLE between two half steps of a Nose-Hoover chain (MRattleNoseHooverIntegrator). */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleNoseHooverStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleNoseHooverStep";
    }
    /** The integrator's class name, which messages name it by on every platform. */
    static std::string IntegratorName() {
        return "MRattleNoseHooverIntegrator";
    }
    IntegrateMRattleNoseHooverStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleNoseHooverStepKernel() override;
    /** The integrator that execute() takes. */
    typedef MRattleNoseHooverIntegrator IntegratorType;
    /** One step of this integrator: see RigidBodyKernel's step contract (a failed step leaves the chain as it was). */
    virtual void execute(OpenMM::ContextImpl& context, const MRattleNoseHooverIntegrator& integrator, bool& forcesAreValid) = 0;
    /** The chain's energy with the integrator's temperature and frequency (MRattleNoseHooverIntegrator::computeHeatBathEnergy). */
    virtual double computeHeatBathEnergy(OpenMM::ContextImpl& context, const MRattleNoseHooverIntegrator& integrator) = 0;
};

/** Velocity Verlet with M-RATTLE between two stochastic velocity rescalings (MRattleBussiIntegrator). */
class OPENMM_EXPORT_MRATTLE IntegrateMRattleBussiStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateMRattleBussiStep";
    }
    /** The integrator's class name, which messages name it by on every platform. */
    static std::string IntegratorName() {
        return "MRattleBussiIntegrator";
    }
    IntegrateMRattleBussiStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateMRattleBussiStepKernel() override;
    /** The integrator that execute() takes. */
    typedef MRattleBussiIntegrator IntegratorType;
    /** One step of this integrator: see RigidBodyKernel's step contract (a failed step leaves the stream and work as they were). */
    virtual void execute(OpenMM::ContextImpl& context, const MRattleBussiIntegrator& integrator, bool& forcesAreValid) = 0;
    /** Minus the accumulated work of the rescalings (MRattleBussiIntegrator::computeHeatBathEnergy). */
    virtual double computeHeatBathEnergy(OpenMM::ContextImpl& context) = 0;
};

/** The symplectic splitting baseline: the position update is a free-rotor splitting per body. */
class OPENMM_EXPORT_MRATTLE IntegrateRigidSplittingStepKernel : public RigidBodyKernel {
public:
    static std::string Name() {
        return "IntegrateRigidSplittingStep";
    }
    /** The integrator's class name, which messages name it by on every platform. */
    static std::string IntegratorName() {
        return "RigidSplittingIntegrator";
    }
    IntegrateRigidSplittingStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : RigidBodyKernel(name, platform) {
    }
    ~IntegrateRigidSplittingStepKernel() override;
    /** The integrator that execute() takes. */
    typedef RigidSplittingIntegrator IntegratorType;
    /** One step of this integrator: see RigidBodyKernel's step contract. */
    virtual void execute(OpenMM::ContextImpl& context, const RigidSplittingIntegrator& integrator, bool& forcesAreValid) = 0;
};

} // namespace MRattlePlugin

#endif
