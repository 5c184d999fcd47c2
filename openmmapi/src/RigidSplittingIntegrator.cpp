#include "RigidSplittingIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

RigidSplittingIntegrator::RigidSplittingIntegrator(double stepSize) {
    setStepSize(stepSize);
}

std::string RigidSplittingIntegrator::getStepKernelName() const {
    return IntegrateRigidSplittingStepKernel::Name();
}

void RigidSplittingIntegrator::step(int steps) {
    requireContext();
    IntegrateRigidSplittingStepKernel& stepKernel = kernel.getAs<IntegrateRigidSplittingStepKernel>();
    for (int i = 0; i < steps; i++) {
        beginStep();
        ensureForces();
        stepKernel.integratePositions(*context, *this);
        computeForces();
        stepKernel.integrateVelocities(*context, *this);
    }
    endSteps();
}
