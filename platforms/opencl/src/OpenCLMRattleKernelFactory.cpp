/*
 * The plugin's kernels on OpenMM's OpenCL platform: the common kernels
 * (platforms/common) over the Context's OpenCL context.
 */
#include "CommonMRattleKernelFactory.h"
#include "internal/OpenMMVersionCheck.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/opencl/OpenCLPlatform.h"

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/**
 * The device context of an OpenCL Context. OpenCLContext derives from ComputeContext alone
 * (public, single inheritance), so the base is at the same address; the conversion is done
 * without OpenCLContext.h because Debian's OpenMM headers lack the Lepton headers it
 * includes. The atom count checks that the object is what it should be.
 */
ComputeContext& computeContext(ContextImpl& context) {
    OpenCLPlatform::PlatformData& data = *static_cast<OpenCLPlatform::PlatformData*>(context.getPlatformData());
    if (data.contexts.size() != 1)
        throw OpenMMException("The M-RATTLE integrators on OpenCL run on one device; this Context uses " +
                              std::to_string(data.contexts.size()) + " (set the DeviceIndex property to one device)");
    ComputeContext& cc = *reinterpret_cast<ComputeContext*>(data.contexts[0]);
    if (cc.getNumAtoms() != context.getSystem().getNumParticles())
        throw OpenMMException("The M-RATTLE plugin: OpenMM's OpenCL context does not have the expected layout (this "
                              "plugin was built against another OpenMM)");
    return cc;
}

class OpenCLMRattleKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(std::string name, const Platform& platform, ContextImpl& context) const override {
        return createCommonKernel(name, platform, computeContext(context));
    }
};

/**
 * Register the kernels on the OpenCL platform, if present. File-local: every plugin exports
 * a registerKernelFactories(), and a call to that name could bind to another plugin's.
 */
void registerOnOpenCL() {
    checkOpenMMVersion(Platform::getOpenMMVersion());
    for (int i = 0; i < Platform::getNumPlatforms(); i++)
        if (Platform::getPlatform(i).getName() == "OpenCL")
            registerCommonKernels(Platform::getPlatform(i), new OpenCLMRattleKernelFactory());
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
