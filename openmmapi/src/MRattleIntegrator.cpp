#include "MRattleIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

// The kernel interface's key function: its vtable and type information live in this
// library only, so Kernel::getAs<> casts agree across the plugin's shared libraries.
IntegrateMRattleStepKernel::~IntegrateMRattleStepKernel() {
}

MRattleIntegrator::MRattleIntegrator(double stepSize) {
    setStepSize(stepSize);
}

std::string MRattleIntegrator::getStepKernelName() const {
    return IntegrateMRattleStepKernel::Name();
}

void MRattleIntegrator::executeStep(Kernel& kernel, ContextImpl& context, bool& forcesAreValid) {
    kernel.getAs<IntegrateMRattleStepKernel>().execute(context, *this, forcesAreValid);
}
