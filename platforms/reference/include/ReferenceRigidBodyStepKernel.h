#ifndef MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_
#define MRATTLE_REFERENCE_RIGID_BODY_STEP_KERNEL_H_

#include "ReferenceRigidBodyDynamics.h"
#include "RigidBodyIntegrator.h"
#include <memory>
#include <string>
#include <vector>

namespace MRattlePlugin {

/**
 * The part of a rigid-body step kernel that is the same for every integrator on the
 * Reference and CPU platforms: set-up, velocity projection, kinetic energy and the second
 * half of the step (half kick, then RATTLE's velocity step, the rigid-body projection).
 * A kernel derives from it with its interface (e.g. IntegrateMRattleStepKernel) and
 * supplies integratePositions().
 */
template <class StepKernel>
class ReferenceRigidBodyStepKernel : public StepKernel {
public:
    ReferenceRigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform) : StepKernel(name, platform) {
    }
    void initialize(const OpenMM::System& system, const RigidBodySet& bodies) override {
        dynamics.reset(new ReferenceRigidBodyDynamics(system, bodies));
        newPositions.resize(system.getNumParticles());
        newVelocities.resize(system.getNumParticles());
    }
    void projectVelocities(OpenMM::ContextImpl& context, std::vector<OpenMM::Vec3>& velocities, double tolerance) override {
        dynamics->projectVelocities(ReferenceRigidBodyDynamics::positions(context), velocities, tolerance);
    }
    void projectContextVelocities(OpenMM::ContextImpl& context, double tolerance) override {
        projectVelocities(context, ReferenceRigidBodyDynamics::velocities(context), tolerance);
    }
    double computeKineticEnergy(OpenMM::ContextImpl& context) override {
        return dynamics->kineticEnergy(ReferenceRigidBodyDynamics::velocities(context));
    }
    void integrateVelocities(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) override {
        dynamics->kickAndProject(context, integrator.getStepSize(), integrator.getConstraintTolerance());
    }

protected:
    std::unique_ptr<ReferenceRigidBodyDynamics> dynamics;
    std::vector<OpenMM::Vec3> newPositions, newVelocities;  // step buffers
};

} // namespace MRattlePlugin

#endif
