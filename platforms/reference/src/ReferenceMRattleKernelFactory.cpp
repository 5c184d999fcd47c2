#include "ReferenceMRattleKernelFactory.h"
#include "ReferenceMRattleKernels.h"
#include "ReferenceMRattleLangevinKernels.h"
#include "ReferenceRigidSplittingKernels.h"
#include "ReferenceThermostatKernels.h"
#include "MRattlePlatforms.h"
#include "internal/OpenMMVersionCheck.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include "openmm/internal/windowsExport.h"

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** A kernel of this platform: its name (the interface's Name()) and how to make it. */
struct ReferenceKernel {
    std::string (*name)();
    KernelImpl* (*create)(const std::string& name, const Platform& platform);
};

template <class Kernel>
KernelImpl* make(const std::string& name, const Platform& platform) {
    return new Kernel(name, platform);
}

/** The kernels of the Reference and CPU platforms: registered and created from this list alone. */
const ReferenceKernel Kernels[] = {
    {IntegrateMRattleStepKernel::Name, make<ReferenceIntegrateMRattleStepKernel>},
    {IntegrateRigidSplittingStepKernel::Name, make<ReferenceIntegrateRigidSplittingStepKernel>},
    {IntegrateMRattleLangevinStepKernel::Name, make<ReferenceIntegrateMRattleLangevinStepKernel>},
    {IntegrateMRattleNoseHooverStepKernel::Name, make<ReferenceIntegrateMRattleNoseHooverStepKernel>},
    {IntegrateMRattleBussiStepKernel::Name, make<ReferenceIntegrateMRattleBussiStepKernel>},
};

/** A platform of the build's list that this plugin serves (Reference and CPU; the CPU platform derives from Reference). */
bool isHostPlatform(const std::string& name) {
    for (const BuiltPlatform& built : BuiltPlatforms)
        if (!built.device && name == built.name)
            return true;
    return false;
}

/**
 * Register the kernels on every host platform of the build's list that is present. File-local: every
 * plugin exports a registerKernelFactories(), and a call to that name could bind to
 * another plugin's.
 */
void registerOnReferenceAndCpu() {
    checkOpenMMVersion(Platform::getOpenMMVersion());
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (isHostPlatform(platform.getName())) {
            // One factory per platform: each Platform deletes the factories it holds.
            ReferenceMRattleKernelFactory* factory = new ReferenceMRattleKernelFactory();
            for (const ReferenceKernel& kernel : Kernels)
                platform.registerKernelFactory(kernel.name(), factory);
        }
    }
}

} // namespace

KernelImpl* ReferenceMRattleKernelFactory::createKernelImpl(std::string name, const Platform& platform,
                                                            ContextImpl& context) const {
    for (const ReferenceKernel& kernel : Kernels)
        if (name == kernel.name())
            return kernel.create(name, platform);
    throw OpenMMException("ReferenceMRattleKernelFactory: no kernel named '" + name + "'");
}

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

/** OpenMM's plugin entry point. */
extern "C" OPENMM_EXPORT void registerKernelFactories() {
    registerOnReferenceAndCpu();
}

/** For programs that link the plugin instead of loading it from OpenMM's plugin folder. */
extern "C" OPENMM_EXPORT void registerMRattleReferenceKernelFactories() {
    registerOnReferenceAndCpu();
}
