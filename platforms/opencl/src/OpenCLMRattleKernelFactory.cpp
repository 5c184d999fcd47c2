/*
 * The plugin's kernels on OpenMM's OpenCL platform. MRattleIntegrator runs there;
 * RigidSplittingIntegrator, the paper's baseline, stays on Reference and CPU: its kernel is
 * registered here only to refuse with a message naming those platforms (so a Context
 * created without naming a platform picks OpenCL for it and is refused with that message).
 */
#include "CommonMRattleKernels.h"
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
ComputeContext& computeContext(OpenCLContext* context, const ContextImpl& contextImpl) {
    ComputeContext& cc = *reinterpret_cast<ComputeContext*>(context);
    if (cc.getNumAtoms() != contextImpl.getSystem().getNumParticles())
        throw OpenMMException("MRattleIntegrator: OpenMM's OpenCL context does not have the expected layout (this "
                              "plugin was built against another OpenMM)");
    return cc;
}

class OpenCLMRattleKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(std::string name, const Platform& platform, ContextImpl& context) const override {
        OpenCLPlatform::PlatformData& data = *static_cast<OpenCLPlatform::PlatformData*>(context.getPlatformData());
        if (data.contexts.size() != 1)
            throw OpenMMException("MRattleIntegrator on OpenCL runs on one device; this Context uses " +
                                  std::to_string(data.contexts.size()) + " (set the DeviceIndex property to one device)");
        if (name == IntegrateMRattleStepKernel::Name() || name == IntegrateMRattleLangevinStepKernel::Name())
            return new CommonIntegrateMRattleStepKernel(name, platform, computeContext(data.contexts[0], context));
        if (name == IntegrateRigidSplittingStepKernel::Name())
            throw OpenMMException("RigidSplittingIntegrator (the paper's baseline) runs on the Reference and CPU "
                                  "platforms only; MRattleIntegrator and MRattleLangevinIntegrator run on Reference, CPU and OpenCL. Create the "
                                  "Context with Platform::getPlatformByName(\"CPU\") or \"Reference\".");
        throw OpenMMException("OpenCLMRattleKernelFactory: no kernel named '" + name + "'");
    }
};

/**
 * Register the kernels on the OpenCL platform, if present. File-local: every plugin exports
 * a registerKernelFactories(), and a call to that name could bind to another plugin's.
 */
void registerOnOpenCL() {
    checkOpenMMVersion(Platform::getOpenMMVersion());
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.getName() == "OpenCL") {
            // One factory per platform, holding both names: the splitting baseline is refused
            // with a message naming its platforms, rather than OpenMM's generic one.
            OpenCLMRattleKernelFactory* factory = new OpenCLMRattleKernelFactory();
            platform.registerKernelFactory(IntegrateMRattleStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateMRattleLangevinStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateRigidSplittingStepKernel::Name(), factory);
        }
    }
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
