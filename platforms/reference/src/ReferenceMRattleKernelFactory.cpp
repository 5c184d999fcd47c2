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

KernelImpl* ReferenceMRattleKernelFactory::createKernelImpl(std::string name, const Platform& platform,
                                                            ContextImpl& context) const {
    if (name == IntegrateMRattleStepKernel::Name())
        return new ReferenceIntegrateMRattleStepKernel(name, platform);
    if (name == IntegrateRigidSplittingStepKernel::Name())
        return new ReferenceIntegrateRigidSplittingStepKernel(name, platform);
    if (name == IntegrateMRattleLangevinStepKernel::Name())
        return new ReferenceIntegrateMRattleLangevinStepKernel(name, platform);
    if (name == IntegrateMRattleNoseHooverStepKernel::Name())
        return new ReferenceIntegrateMRattleNoseHooverStepKernel(name, platform);
    if (name == IntegrateMRattleBussiStepKernel::Name())
        return new ReferenceIntegrateMRattleBussiStepKernel(name, platform);
    throw OpenMMException("ReferenceMRattleKernelFactory: no kernel named '" + name + "'");
}

namespace {

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
            platform.registerKernelFactory(IntegrateMRattleStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateRigidSplittingStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateMRattleLangevinStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateMRattleNoseHooverStepKernel::Name(), factory);
            platform.registerKernelFactory(IntegrateMRattleBussiStepKernel::Name(), factory);
        }
    }
}

} // namespace

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
