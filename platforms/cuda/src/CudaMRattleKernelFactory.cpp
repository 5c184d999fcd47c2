// The plugin's kernels on OpenMM's CUDA platform: the common kernels over the Context's CudaContext.
#include "CommonKernelFactory.h"
#include "CommonRigidBodyState.h"
#include "openmm/cuda/CudaPlatform.h"
#include "openmm/internal/windowsExport.h"
#include <cuda.h>

using namespace MRattlePlugin;

namespace {

/** Page-locked host memory: CUDA copies asynchronously only into it (the failure flag's lazy copy). */
void* allocatePageLocked(size_t bytes) {
    void* memory = nullptr;
    return cuMemHostAlloc(&memory, bytes, CU_MEMHOSTALLOC_PORTABLE) == CUDA_SUCCESS ? memory : nullptr;
}

void releasePageLocked(void* memory) {
    cuMemFreeHost(memory);
}

// File-local: every plugin exports a registerKernelFactories(), and a call to that name could bind to another's.
void registerOnCuda() {
    CommonRigidBodyState::setHostMemory({allocatePageLocked, releasePageLocked});
    registerDeviceKernels("CUDA", computeContextOf<OpenMM::CudaPlatform::PlatformData>);
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
