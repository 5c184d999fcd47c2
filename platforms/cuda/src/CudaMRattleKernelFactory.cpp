/*
 * The plugin's kernels on OpenMM's CUDA platform: the common kernels (platforms/common) on
 * the Context's CudaContext, which is OpenMM's ComputeContext for CUDA. Which kernels exist,
 * and the refusal of RigidSplittingIntegrator's, are the common factory's (createCommonKernel,
 * registerCommonKernels); this file only finds the device context.
 */
#include "CommonMRattleKernelFactory.h"
#include "CommonStepFailure.h"
#include "internal/OpenMMVersionCheck.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/cuda/CudaContext.h"
#include "openmm/cuda/CudaPlatform.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/internal/windowsExport.h"
#include <string>

using namespace OpenMM;

namespace {

/** Page-locked host memory (as CudaContext's pinned buffer): an asynchronous copy into pageable memory waits for the stream. */
void* allocatePageLocked(size_t bytes) {
    void* memory = nullptr;
    return cuMemHostAlloc(&memory, bytes, CU_MEMHOSTALLOC_PORTABLE) == CUDA_SUCCESS ? memory : nullptr;
}

void releasePageLocked(void* memory) {
    cuMemFreeHost(memory);
}

class CudaMRattleKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(std::string name, const Platform& platform, ContextImpl& context) const override {
        CudaPlatform::PlatformData& data = *static_cast<CudaPlatform::PlatformData*>(context.getPlatformData());
        if (data.contexts.size() != 1)
            throw OpenMMException("MRattleIntegrator on CUDA runs on one device; this Context uses " +
                                  std::to_string(data.contexts.size()) + " (set the DeviceIndex property to one device)");
        ComputeContext& cc = *data.contexts[0];
        return MRattlePlugin::createCommonKernel(name, platform, cc);
    }
};

/**
 * Register the kernels on the CUDA platform, if present. File-local: every plugin exports a
 * registerKernelFactories(), and a call to that name could bind to another plugin's.
 */
void registerOnCuda() {
    MRattlePlugin::checkOpenMMVersion(Platform::getOpenMMVersion());
    MRattlePlugin::CommonStepFailure::setHostMemory({allocatePageLocked, releasePageLocked});
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.getName() == "CUDA")
            MRattlePlugin::registerCommonKernels(platform, new CudaMRattleKernelFactory());
    }
}

} // namespace

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

/** OpenMM's plugin entry point. */
extern "C" OPENMM_EXPORT void registerKernelFactories() {
    registerOnCuda();
}

/** For programs that link the plugin instead of loading it from OpenMM's plugin folder. */
extern "C" OPENMM_EXPORT void registerMRattleCudaKernelFactories() {
    registerOnCuda();
}
