#ifndef MRATTLE_REFERENCE_KERNELS_H_
#define MRATTLE_REFERENCE_KERNELS_H_

#include "ReferenceRigidBodyDynamics.h"
#include "internal/RigidBodyKernels.h"
#include <memory>

namespace MRattlePlugin {

/** M-RATTLE on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleStepKernel : public IntegrateMRattleStepKernel {
public:
    ReferenceIntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform)
        : IntegrateMRattleStepKernel(name, platform) {
    }
    void initialize(const OpenMM::System& system, const RigidBodySet& bodies) override;
    void projectVelocities(OpenMM::ContextImpl& context, std::vector<OpenMM::Vec3>& velocities, double tolerance) override;
    void projectContextVelocities(OpenMM::ContextImpl& context, double tolerance) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    void integratePositions(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator) override;
    void integrateVelocities(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator) override;

private:
    std::unique_ptr<ReferenceRigidBodyDynamics> dynamics;
    std::vector<OpenMM::Vec3> newPositions, newVelocities;  // step buffers, swapped with the Context's
};

} // namespace MRattlePlugin

#endif
