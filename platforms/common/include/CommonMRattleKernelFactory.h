#ifndef MRATTLE_COMMON_KERNEL_FACTORY_H_
#define MRATTLE_COMMON_KERNEL_FACTORY_H_

#include "openmm/KernelFactory.h"
#include "openmm/KernelImpl.h"
#include "openmm/Platform.h"
#include "openmm/common/ComputeContext.h"
#include <string>

namespace MRattlePlugin {

/**
 * What a device platform's kernel factory (OpenCL, CUDA) does once it has the Context's
 * ComputeContext: make the plugin's kernel of that name over the common kernels. The
 * splitting baseline (RigidSplittingIntegrator) has no device kernel: its name is refused
 * with an OpenMMException naming the platforms that run it.
 */
OpenMM::KernelImpl* createCommonKernel(const std::string& name, const OpenMM::Platform& platform,
                                       OpenMM::ComputeContext& cc);

/**
 * Register the factory on the platform for every kernel name of the plugin (the splitting
 * baseline's too, so that it is refused with createCommonKernel's message rather than
 * OpenMM's generic one). The platform takes ownership of the factory.
 */
void registerCommonKernels(OpenMM::Platform& platform, OpenMM::KernelFactory* factory);

} // namespace MRattlePlugin

#endif
