#ifndef MRATTLE_COMMON_KERNELS_H_
#define MRATTLE_COMMON_KERNELS_H_

#include "CommonRigidBodyStepKernel.h"
#include "MRattleIntegrator.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/** MRattleIntegrator on the common compute platforms: velocity Verlet with M-RATTLE's resets. */
class CommonIntegrateMRattleStepKernel : public CommonRigidBodyStepKernel<MRattleIntegrator> {
public:
    CommonIntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : CommonRigidBodyStepKernel(name, platform, cc) {
    }
    void execute(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator, bool& forcesAreValid) override;
};

} // namespace MRattlePlugin

#endif
