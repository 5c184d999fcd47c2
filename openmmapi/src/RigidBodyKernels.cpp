#include "internal/RigidBodyKernels.h"

// Key functions: the kernel interfaces' vtables and type information live in this
// library only, so Kernel::getAs<> casts agree across the plugin's shared libraries. Each
// integrator's own interface has its key function in that integrator's .cpp.
MRattlePlugin::RigidBodyKernel::~RigidBodyKernel() {
}
