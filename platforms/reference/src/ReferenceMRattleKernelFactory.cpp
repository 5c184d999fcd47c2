#include "ReferenceMRattleKernelFactory.h"
#include "ReferenceRigidBodyKernels.h"
#include "MRattlePlatforms.h"
#include "internal/OpenMMVersionCheck.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include "openmm/internal/windowsExport.h"

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** How to make a kernel of this platform. */
typedef KernelImpl* (*ReferenceKernelMaker)(const std::string& name, const Platform& platform);

template <class Kernel>
KernelImpl* make(const std::string& name, const Platform& platform) {
    return new Kernel(name, platform);
}

/** The makers of the Reference and CPU platforms' kernels, in the order of IntegratorNames::All. */
const ReferenceKernelMaker Makers[] = {
    make<ReferenceIntegrateMRattleStepKernel>,
    make<ReferenceIntegrateMRattleLangevinStepKernel>,
    make<ReferenceIntegrateMRattleNoseHooverStepKernel>,
    make<ReferenceIntegrateMRattleBussiStepKernel>,
    make<ReferenceIntegrateRigidSplittingStepKernel>,
    make<ReferenceIntegrateMRattleDrudeLangevinStepKernel>,
    make<ReferenceIntegrateMRattleDrudeNoseHooverStepKernel>,
};
static_assert(sizeof(Makers) / sizeof(Makers[0]) == sizeof(IntegratorNames::All) / sizeof(IntegratorNames::All[0]),
              "one maker per integrator of IntegratorNames::All");

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
            for (const RigidBodyIntegratorName& names : IntegratorNames::All)
                platform.registerKernelFactory(names.stepKernel, factory);
        }
    }
}

} // namespace

KernelImpl* ReferenceMRattleKernelFactory::createKernelImpl(std::string name, const Platform& platform,
                                                            ContextImpl& context) const {
    return Makers[IntegratorNames::indexOfStepKernel(name)](name, platform);
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
