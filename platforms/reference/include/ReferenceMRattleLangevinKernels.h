#ifndef MRATTLE_REFERENCE_LANGEVIN_KERNELS_H_
#define MRATTLE_REFERENCE_LANGEVIN_KERNELS_H_

#include "MRattleLangevinIntegrator.h"
#include "ReferenceRigidBodyStepKernel.h"
#include "internal/RigidBodyKernels.h"

namespace MRattlePlugin {

/**
 * MRattleLangevinIntegrator on the Reference platform, also registered on the CPU platform:
 * LangevinMiddle's splitting with each drift reset by M-RATTLE and the velocities projected
 * after the kick and after the noise (the kernel's random stream, which checkpoints hold).
 * Leapfrog: the velocities it keeps are those of the middle of the step.
 */
class ReferenceIntegrateMRattleLangevinStepKernel : public ReferenceRigidBodyStepKernel<MRattleLangevinIntegrator> {
public:
    using ReferenceRigidBodyStepKernel::ReferenceRigidBodyStepKernel;
    void execute(OpenMM::ContextImpl& context, const MRattleLangevinIntegrator& integrator, bool& forcesAreValid) override;

protected:
    /** The noise's stream seeded now (so a checkpoint before the first step holds it). */
    void initializeIntegrator(const OpenMM::System& system, const MRattleLangevinIntegrator& integrator) override;

private:
    /** Ornstein-Uhlenbeck over time h on every massive particle's velocity. */
    void addNoise(double friction, double temperature, double h);
};

} // namespace MRattlePlugin

#endif
