#ifndef MRATTLE_REFERENCE_RIGID_BODY_DYNAMICS_H_
#define MRATTLE_REFERENCE_RIGID_BODY_DYNAMICS_H_

#include "RigidBodySet.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/ReferenceConstraints.h"
#include <memory>
#include <vector>

namespace MRattlePlugin {

/**
 * What every rigid-body integrator does the same way on the Reference and CPU platforms:
 * access to the Context's arrays, RATTLE for constraints among free particles (OpenMM's
 * own ReferenceConstraints), velocity projection and kinetic energy.
 */
class ReferenceRigidBodyDynamics {
public:
    ReferenceRigidBodyDynamics(const OpenMM::System& system, const RigidBodySet& bodies);

    static std::vector<OpenMM::Vec3>& positions(OpenMM::ContextImpl& context);
    static std::vector<OpenMM::Vec3>& velocities(OpenMM::ContextImpl& context);
    static std::vector<OpenMM::Vec3>& forces(OpenMM::ContextImpl& context);
    /** Advance the Context's time and step count by one step. */
    static void advanceClock(OpenMM::ContextImpl& context, double stepSize);

    /** RATTLE position step for free-particle constraints: moves newPositions onto the constraints. */
    void constrainFreePositions(std::vector<OpenMM::Vec3>& oldPositions, std::vector<OpenMM::Vec3>& newPositions,
                                double tolerance);
    /** Rigid-body projection of velocities at the given positions, and free constraints. */
    void projectVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double tolerance);
    double kineticEnergy(const std::vector<OpenMM::Vec3>& velocities) const;
    /**
     * The second half of every rigid-body step, with the forces at the new positions: half
     * kick, then the velocity reset (free constraints and rigid-body projection, which for
     * a rigid body is exactly a half kick of its momentum and angular momentum); advances
     * the clock.
     */
    void kickAndProject(OpenMM::ContextImpl& context, double stepSize, double tolerance);

    const RigidBodySet& bodies() const {
        return *bodySet;
    }
    const OpenMM::System& system() const {
        return *systemRef;
    }
    std::vector<double>& inverseMasses() {
        return inverseMass;
    }

private:
    const OpenMM::System* systemRef;
    const RigidBodySet* bodySet;
    std::vector<double> inverseMass;
    std::unique_ptr<OpenMM::ReferenceConstraints> freeConstraints;
};

/** Raw 3N-double view of a Vec3 array, for the numerical core. */
inline double* coordinates(std::vector<OpenMM::Vec3>& v) {
    static_assert(sizeof(OpenMM::Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");
    return reinterpret_cast<double*>(v.data());
}

} // namespace MRattlePlugin

#endif
