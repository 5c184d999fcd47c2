#include "RigidSplittingIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

// The kernel interface's key function: its vtable and type information live in this
// library only, so Kernel::getAs<> casts agree across the plugin's shared libraries.
IntegrateRigidSplittingStepKernel::~IntegrateRigidSplittingStepKernel() {
}

RigidSplittingIntegrator::RigidSplittingIntegrator(double stepSize) {
    setStepSize(stepSize);
}

std::string RigidSplittingIntegrator::getStepKernelName() const {
    return IntegrateRigidSplittingStepKernel::Name();
}

void RigidSplittingIntegrator::executeStep(Kernel& kernel, ContextImpl& context, bool& forcesAreValid) {
    kernel.getAs<IntegrateRigidSplittingStepKernel>().execute(context, *this, forcesAreValid);
}
