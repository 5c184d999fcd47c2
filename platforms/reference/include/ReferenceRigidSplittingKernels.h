#ifndef MRATTLE_REFERENCE_RIGID_SPLITTING_KERNELS_H_
#define MRATTLE_REFERENCE_RIGID_SPLITTING_KERNELS_H_

#include "RigidSplittingIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/**
 * RigidSplittingIntegrator (the splitting baseline) on the Reference platform, also
 * registered on the CPU platform: velocity Verlet whose position update is a free-rotor
 * splitting per body.
 */
class ReferenceIntegrateRigidSplittingStepKernel : public ReferenceRigidBodyStepKernel<RigidSplittingIntegrator> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;
    void execute(OpenMM::ContextImpl& context, const RigidSplittingIntegrator& integrator, bool& forcesAreValid) override;

private:
    /**
     * Half kick and drift of the free particles with RATTLE for their constraints, and each
     * body's rotor splitting, into the step buffers, which then become the state.
     */
    void rotorPositionStep(double h, double tolerance);
};

} // namespace MRattlePlugin

#endif
