#ifndef MRATTLE_COMMON_LANGEVIN_KERNELS_H_
#define MRATTLE_COMMON_LANGEVIN_KERNELS_H_

#include "CommonRigidBodyStepKernel.h"
#include "MRattleLangevinIntegrator.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/**
 * MRattleLangevinIntegrator on the common compute platforms: LangevinMiddle's splitting
 * with each drift reset by M-RATTLE and the velocities projected after the kick and after
 * the noise (OpenMM's device random numbers, which its checkpoints hold): two fused passes
 * per step (CommonRigidBodyDynamics::advance).
 */
class CommonIntegrateMRattleLangevinStepKernel : public CommonRigidBodyStepKernel<MRattleLangevinIntegrator> {
public:
    CommonIntegrateMRattleLangevinStepKernel(const std::string& name, const OpenMM::Platform& platform,
                                             OpenMM::ComputeContext& cc)
        : CommonRigidBodyStepKernel(name, platform, cc) {
    }
    void execute(OpenMM::ContextImpl& context, const MRattleLangevinIntegrator& integrator, bool& forcesAreValid) override;

protected:
    void initializeIntegrator(const OpenMM::System& system, const MRattleLangevinIntegrator& integrator) override;

};

} // namespace MRattlePlugin

#endif
