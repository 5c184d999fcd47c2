#include "CommonMRattleKernelFactory.h"
#include "CommonMRattleKernels.h"
#include "CommonMRattleLangevinKernels.h"
#include "CommonThermostatKernels.h"
#include "MRattlePlatforms.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** "Reference and CPU": the platforms of this build that run every integrator. */
std::string hostPlatformNames() {
    std::string names;
    const int count = sizeof(BuiltPlatforms) / sizeof(BuiltPlatforms[0]);
    for (int i = 0, listed = 0; i < count; i++)
        if (!BuiltPlatforms[i].device)
            names += std::string(listed++ == 0 ? "" : " and ") + BuiltPlatforms[i].name;
    return names;
}

} // namespace

KernelImpl* MRattlePlugin::createCommonKernel(const std::string& name, const Platform& platform, ComputeContext& cc) {
    if (name == IntegrateMRattleStepKernel::Name())
        return new CommonIntegrateMRattleStepKernel(name, platform, cc);
    if (name == IntegrateMRattleLangevinStepKernel::Name())
        return new CommonIntegrateMRattleLangevinStepKernel(name, platform, cc);
    if (name == IntegrateMRattleNoseHooverStepKernel::Name())
        return new CommonIntegrateMRattleNoseHooverStepKernel(name, platform, cc);
    if (name == IntegrateMRattleBussiStepKernel::Name())
        return new CommonIntegrateMRattleBussiStepKernel(name, platform, cc);
    if (name == IntegrateRigidSplittingStepKernel::Name())
        throw OpenMMException("RigidSplittingIntegrator (the paper's baseline) runs on the " + hostPlatformNames() +
                              " platforms only, not on " + platform.getName() + "; the plugin's other integrators run there. Create its Context on one of those (Platform::getPlatformByName).");
    throw OpenMMException("The M-RATTLE plugin has no kernel named '" + name + "' on " + platform.getName());
}

void MRattlePlugin::registerCommonKernels(Platform& platform, KernelFactory* factory) {
    platform.registerKernelFactory(IntegrateMRattleStepKernel::Name(), factory);
    platform.registerKernelFactory(IntegrateMRattleLangevinStepKernel::Name(), factory);
    platform.registerKernelFactory(IntegrateMRattleNoseHooverStepKernel::Name(), factory);
    platform.registerKernelFactory(IntegrateMRattleBussiStepKernel::Name(), factory);
    platform.registerKernelFactory(IntegrateRigidSplittingStepKernel::Name(), factory);
}
