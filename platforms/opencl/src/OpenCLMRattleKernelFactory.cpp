// The plugin's kernels on OpenMM's OpenCL platform: the common kernels over the Context's OpenCL context.
#include "CommonKernelFactory.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/opencl/OpenCLPlatform.h"

using namespace MRattlePlugin;

namespace {
// File-local: every plugin exports a registerKernelFactories(), and a call to that name could bind to another's.
void registerOnOpenCL() {
    registerDeviceKernels("OpenCL", computeContextOf<OpenMM::OpenCLPlatform::PlatformData>);
}
} // namespace

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

/** OpenMM's plugin entry point. */
extern "C" OPENMM_EXPORT void registerKernelFactories() {
    registerOnOpenCL();
}

/** For programs that link the plugin instead of loading it from OpenMM's plugin folder. */
extern "C" OPENMM_EXPORT void registerMRattleOpenCLKernelFactories() {
    registerOnOpenCL();
}
