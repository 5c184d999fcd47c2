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

/** How to make a kernel of the device platforms. */
typedef KernelImpl* (*CommonKernelMaker)(const std::string& name, const Platform& platform, ComputeContext& cc);

template <class Kernel>
KernelImpl* make(const std::string& name, const Platform& platform, ComputeContext& cc) {
    return new Kernel(name, platform, cc);
}

/** The splitting baseline has no device kernel: refused naming the platforms that run it. */
KernelImpl* refuseRigidSplitting(const std::string& name, const Platform& platform, ComputeContext& cc) {
    throw OpenMMException(std::string(IntegratorNames::RigidSplitting.integrator) +
                          " (the paper's baseline) runs on the " + hostPlatformNames() + " platforms only, not on " +
                          platform.getName() + "; the plugin's other integrators run there. Create its Context on one of those "
                          "(Platform::getPlatformByName).");
}

/** The makers of the device platforms' kernels (OpenCL, CUDA), in the order of IntegratorNames::All. */
const CommonKernelMaker Makers[] = {
    make<CommonIntegrateMRattleStepKernel>,
    make<CommonIntegrateMRattleLangevinStepKernel>,
    make<CommonIntegrateMRattleNoseHooverStepKernel>,
    make<CommonIntegrateMRattleBussiStepKernel>,
    refuseRigidSplitting,
};
static_assert(sizeof(Makers) / sizeof(Makers[0]) == sizeof(IntegratorNames::All) / sizeof(IntegratorNames::All[0]),
              "one maker per integrator of IntegratorNames::All");

} // namespace

KernelImpl* MRattlePlugin::createCommonKernel(const std::string& name, const Platform& platform, ComputeContext& cc) {
    return Makers[IntegratorNames::indexOfStepKernel(name)](name, platform, cc);
}

void MRattlePlugin::registerCommonKernels(Platform& platform, KernelFactory* factory) {
    for (const RigidBodyIntegratorName& names : IntegratorNames::All)
        platform.registerKernelFactory(names.stepKernel, factory);
}
