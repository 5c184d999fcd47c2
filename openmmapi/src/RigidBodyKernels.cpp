#include "internal/RigidBodyKernels.h"

// Key functions: the kernel interfaces' vtables and type information live in this
// library only, so Kernel::getAs<> casts agree across the plugin's shared libraries.
MRattlePlugin::RigidBodyKernel::~RigidBodyKernel() {
}

MRattlePlugin::IntegrateMRattleStepKernel::~IntegrateMRattleStepKernel() {
}

MRattlePlugin::IntegrateRigidSplittingStepKernel::~IntegrateRigidSplittingStepKernel() {
}

MRattlePlugin::IntegrateMRattleLangevinStepKernel::~IntegrateMRattleLangevinStepKernel() {
}

MRattlePlugin::IntegrateMRattleNoseHooverStepKernel::~IntegrateMRattleNoseHooverStepKernel() {
}

MRattlePlugin::IntegrateMRattleBussiStepKernel::~IntegrateMRattleBussiStepKernel() {
}
