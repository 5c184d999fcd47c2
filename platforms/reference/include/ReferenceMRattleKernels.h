#ifndef MRATTLE_REFERENCE_KERNELS_H_
#define MRATTLE_REFERENCE_KERNELS_H_

#include "MRattleIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/** MRattleIntegrator on the Reference platform, also registered on the CPU platform: velocity Verlet with M-RATTLE's resets. */
class ReferenceIntegrateMRattleStepKernel : public ReferenceRigidBodyStepKernel<MRattleIntegrator> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;
    void execute(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator, bool& forcesAreValid) override;
};

} // namespace MRattlePlugin

#endif
