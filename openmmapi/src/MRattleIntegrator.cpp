#include "MRattleIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

MRattleIntegrator::MRattleIntegrator(double stepSize) {
    setStepSize(stepSize);
}

std::string MRattleIntegrator::getStepKernelName() const {
    return IntegrateMRattleStepKernel::Name();
}

void MRattleIntegrator::step(int steps) {
    requireContext();
    IntegrateMRattleStepKernel& stepKernel = kernel.getAs<IntegrateMRattleStepKernel>();
    for (int i = 0; i < steps; i++) {
        beginStep();
        ensureForces();
        stepKernel.integratePositions(*context, *this);
        computeForces();
        stepKernel.integrateVelocities(*context, *this);
    }
    endSteps();
}
