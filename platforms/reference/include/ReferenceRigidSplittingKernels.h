#ifndef MRATTLE_REFERENCE_RIGID_SPLITTING_KERNELS_H_
#define MRATTLE_REFERENCE_RIGID_SPLITTING_KERNELS_H_

#include "RigidSplittingIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/** The splitting baseline on the Reference platform, also registered on the CPU platform. */
class ReferenceIntegrateRigidSplittingStepKernel : public ReferenceRigidBodyStepKernel<IntegrateRigidSplittingStepKernel> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;

protected:
    void integratePositions(OpenMM::ContextImpl& context, const RigidSplittingIntegrator& integrator) override;
};

} // namespace MRattlePlugin

#endif
