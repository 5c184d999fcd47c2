#ifndef MRATTLE_REFERENCE_RIGID_BODY_DYNAMICS_H_
#define MRATTLE_REFERENCE_RIGID_BODY_DYNAMICS_H_

#include "internal/BodyShapeConstraints.h"
#include "ReferenceRigidBodyOperations.h"
#include "RigidBodyTopology.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

class RigidBodyIntegrator;

/**
 * What every rigid-body integrator does the same way on the Reference and CPU platforms,
 * as CommonRigidBodyDynamics does on the device platforms and with the same phases: the
 * phases of a step (kicks, drift and reset, projection, forces), the failure handling of
 * every step (a failed phase puts back the state from the step's start and throws), shapes,
 * temperature velocities, kinetic energy and checkpoints. An integrator's kernel
 * (ReferenceMRattleKernels.cpp, ...) sequences the phases in its execute(); the arithmetic
 * on arrays is ReferenceRigidBodyOperations'.
 */
class ReferenceRigidBodyDynamics {
public:
    /** @param integratorName  what failures are reported as ("MRattleIntegrator") */
    explicit ReferenceRigidBodyDynamics(const std::string& integratorName);
    ReferenceRigidBodyDynamics(const ReferenceRigidBodyDynamics&) = delete;
    ReferenceRigidBodyDynamics& operator=(const ReferenceRigidBodyDynamics&) = delete;

    /** Take the bodies and free constraints of the System. */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology);
    /** The arithmetic on arrays and the random stream, for an integrator's own phases. */
    ReferenceRigidBodyOperations& operations() {
        return *ops;
    }

    /**
     * The start of every step: the CPU platform's threads (at the first step), the Andersen
     * collisions of whole bodies, the forces unless they are valid, then a copy of the state
     * (a failed phase puts it back).
     */
    void beginStep(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /** A kick over kickTime (0: none), a drift over h, the bodies' resets and the free constraints. */
    void driftAndReset(double kickTime, double h, double tolerance);
    /** A kick of the Context's velocities over this time with its forces. */
    void kick(double time);
    /** RATTLE's velocity step: bodies onto rigid-body motion (only those not rigid, if asked), free constraints. */
    void project(double tolerance, bool onlyIfNotRigid);
    /** Virtual sites at the new positions, then the forces there. */
    void computeForces(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid);
    /**
     * The end of every step: if a massive particle's position, velocity or force is not
     * finite, put the state back and throw (time and step count unchanged); else advance
     * the clock.
     */
    void endStep(double stepSize, bool& forcesAreValid);
    /**
     * An integrator's own phase, with the step's failure handling: an OpenMMException from
     * work puts back the state from the step's start and is thrown again naming the integrator.
     */
    void ownPhase(const std::function<void()>& work);
    /** The Context's arrays, between beginStep() and endStep(). */
    std::vector<OpenMM::Vec3>& positions();
    std::vector<OpenMM::Vec3>& velocities();
    const std::vector<OpenMM::Vec3>& forces();
    /**
     * Buffers of the Context's size for a phase that writes the new state beside the
     * current one (every particle's); acceptNewState() makes them the Context's.
     */
    std::vector<OpenMM::Vec3>& newPositions() {
        return nextPositions;
    }
    std::vector<OpenMM::Vec3>& newVelocities() {
        return nextVelocities;
    }
    void acceptNewState();

    /** RigidBodyState's work, the same for every integrator. */
    void updateShapes(OpenMM::ContextImpl& context);
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance);
    std::vector<OpenMM::Vec3> velocitiesForTemperature(OpenMM::ContextImpl& context, double temperature, int randomSeed,
                                                       double tolerance);
    double kineticEnergy(OpenMM::ContextImpl& context);
    /** The kinetic energy of the bodies' translation, their rotation, and the free particles. */
    void kineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational, double& free);
    bool isLinear(int body) const {
        return ops->isLinear(body);
    }
    int bodyDegreesOfFreedom() const {
        return ops->getBodyDegreesOfFreedom();
    }
    void createCheckpoint(std::ostream& stream) const;
    void loadCheckpoint(std::istream& stream);
    /** OpenMM read its part of a refused checkpoint unchecked: reseed its host random generator. */
    void discardRefusedCheckpoint(OpenMM::ContextImpl& context);

private:
    /** Put back the state from the step's start and throw what failed, naming the integrator. */
    [[noreturn]] void failStep(const std::string& what);
    /** Throw naming the first massive particle whose position, velocity or force is not finite. */
    void requireFiniteStepResult();

    const std::string integratorName;
    std::unique_ptr<ReferenceRigidBodyOperations> ops;
    std::unique_ptr<BodyShapeConstraints> shapes;
    bool hasVirtualSites = false, threadsChecked = false;
    OpenMM::ContextImpl* stepContext = nullptr;  // the Context of the step under way
    std::vector<OpenMM::Vec3> startPositions, startVelocities;  // the state at the step's start
    std::vector<OpenMM::Vec3> nextPositions, nextVelocities;   // step buffers
};

} // namespace MRattlePlugin

#endif
