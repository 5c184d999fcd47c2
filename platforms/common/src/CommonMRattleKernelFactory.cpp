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

/** A kernel of the device platforms: its name (the interface's Name()) and how to make it. */
struct CommonKernel {
    std::string (*name)();
    KernelImpl* (*create)(const std::string& name, const Platform& platform, ComputeContext& cc);
};

template <class Kernel>
KernelImpl* make(const std::string& name, const Platform& platform, ComputeContext& cc) {
    return new Kernel(name, platform, cc);
}

/** The splitting baseline has no device kernel: refused naming the platforms that run it. */
KernelImpl* refuseRigidSplitting(const std::string& name, const Platform& platform, ComputeContext& cc) {
    throw OpenMMException(IntegrateRigidSplittingStepKernel::IntegratorName() + " (the paper's baseline) runs on the " +
                          hostPlatformNames() + " platforms only, not on " + platform.getName() +
                          "; the plugin's other integrators run there. Create its Context on one of those "
                          "(Platform::getPlatformByName).");
}

/** The kernels of the device platforms (OpenCL, CUDA): registered and created from this list alone. */
const CommonKernel Kernels[] = {
    {IntegrateMRattleStepKernel::Name, make<CommonIntegrateMRattleStepKernel>},
    {IntegrateMRattleLangevinStepKernel::Name, make<CommonIntegrateMRattleLangevinStepKernel>},
    {IntegrateMRattleNoseHooverStepKernel::Name, make<CommonIntegrateMRattleNoseHooverStepKernel>},
    {IntegrateMRattleBussiStepKernel::Name, make<CommonIntegrateMRattleBussiStepKernel>},
    {IntegrateRigidSplittingStepKernel::Name, refuseRigidSplitting},
};

} // namespace

KernelImpl* MRattlePlugin::createCommonKernel(const std::string& name, const Platform& platform, ComputeContext& cc) {
    for (const CommonKernel& kernel : Kernels)
        if (name == kernel.name())
            return kernel.create(name, platform, cc);
    throw OpenMMException("The M-RATTLE plugin has no kernel named '" + name + "' on " + platform.getName());
}

void MRattlePlugin::registerCommonKernels(Platform& platform, KernelFactory* factory) {
    for (const CommonKernel& kernel : Kernels)
        platform.registerKernelFactory(kernel.name(), factory);
}
