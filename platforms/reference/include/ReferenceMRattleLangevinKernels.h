#ifndef MRATTLE_REFERENCE_LANGEVIN_KERNELS_H_
#define MRATTLE_REFERENCE_LANGEVIN_KERNELS_H_

#include "MRattleLangevinIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/**
 * Langevin dynamics with M-RATTLE on the Reference platform, also registered on the CPU
 * platform. Leapfrog like LangevinMiddleIntegrator: the velocities it keeps are those of
 * the middle of the step (after the noise), so its step is a full kick and there is no
 * closing half kick.
 */
class ReferenceIntegrateMRattleLangevinStepKernel : public ReferenceRigidBodyStepKernel<IntegrateMRattleLangevinStepKernel> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;
    /** The shared set-up, then the noise's stream seeded now (so a checkpoint before the first step holds it). */
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;

protected:
    void finishStep(OpenMM::ContextImpl& context, const MRattleLangevinIntegrator& integrator) override;
    void integratePositions(OpenMM::ContextImpl& context, const MRattleLangevinIntegrator& integrator) override;

private:
    std::vector<OpenMM::Vec3> kicked, middlePositions, middleVelocities;  // step buffers
};

} // namespace MRattlePlugin

#endif
