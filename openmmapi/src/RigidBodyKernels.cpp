#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"

using namespace MRattlePlugin;

// Key functions: the interfaces' vtables and type information live in this library only,
// so Kernel::getAs<> casts agree across the plugin's shared libraries.
RigidBodyState::~RigidBodyState() {
}

RigidBodyStepKernel::RigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform)
    : OpenMM::KernelImpl(name, platform) {
}

RigidBodyStepKernel::~RigidBodyStepKernel() {
}

int IntegratorNames::indexOfStepKernel(const std::string& stepKernelName) {
    for (int i = 0; i < (int) (sizeof(All) / sizeof(All[0])); i++)
        if (stepKernelName == All[i].stepKernel)
            return i;
    throw OpenMM::OpenMMException("The M-RATTLE plugin has no kernel named '" + stepKernelName + "'");
}
