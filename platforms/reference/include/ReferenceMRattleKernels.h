#ifndef MRATTLE_REFERENCE_KERNELS_H_
#define MRATTLE_REFERENCE_KERNELS_H_

#include "MRattleIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/** M-RATTLE on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateMRattleStepKernel : public ReferenceRigidBodyStepKernel<IntegrateMRattleStepKernel> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;

protected:
    void integratePositions(OpenMM::ContextImpl& context, const MRattleIntegrator& integrator) override;
};

} // namespace MRattlePlugin

#endif
