#include "CommonKernelFactory.h"
#include "CommonStepKernels.h"
#include "MRattlePlatforms.h"
#include "internal/OpenMMVersionCheck.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

/** "Reference and CPU": the platforms of this build that run every integrator. */
std::string hostPlatformNames() {
    std::string names;
    for (int i = 0, listed = 0; i < (int) (sizeof(BuiltPlatforms) / sizeof(BuiltPlatforms[0])); i++)
        if (!BuiltPlatforms[i].device)
            names += std::string(listed++ == 0 ? "" : " and ") + BuiltPlatforms[i].name;
    return names;
}

class DeviceKernelFactory : public KernelFactory {
public:
    explicit DeviceKernelFactory(FindComputeContext find) : find(find) {
    }
    KernelImpl* createKernelImpl(std::string name, const Platform& platform, ContextImpl& context) const override {
        ComputeContext& cc = find(context);
        if (name == IntegratorNames::MRattle.stepKernel)
            return new CommonIntegrateMRattleStepKernel(name, platform, cc);
        if (name == IntegratorNames::MRattleLangevin.stepKernel)
            return new CommonIntegrateMRattleLangevinStepKernel(name, platform, cc);
        if (name == IntegratorNames::MRattleNoseHoover.stepKernel)
            return new CommonIntegrateMRattleNoseHooverStepKernel(name, platform, cc);
        if (name == IntegratorNames::MRattleBussi.stepKernel)
            return new CommonIntegrateMRattleBussiStepKernel(name, platform, cc);
        if (name == IntegratorNames::MRattleDrudeLangevin.stepKernel)
            return new CommonIntegrateMRattleDrudeLangevinStepKernel(name, platform, cc);
        if (name == IntegratorNames::MRattleDrudeNoseHoover.stepKernel)
            return new CommonIntegrateMRattleDrudeNoseHooverStepKernel(name, platform, cc);
        // An integrator without a device kernel (the splitting baseline) names where it runs.
        const std::string baseline = name == IntegratorNames::RigidSplitting.stepKernel ? " (the paper's baseline)" : "";
        throw OpenMMException(IntegratorNames::ofStepKernel(name).integrator + baseline + " runs on the " +
                              hostPlatformNames() + " platforms only, not on " + platform.getName() + "; the plugin's "
                              "other integrators run there. Create its Context on one of those "
                              "(Platform::getPlatformByName).");
    }

private:
    FindComputeContext find;
};

} // namespace

ComputeContext& MRattlePlugin::checkedComputeContext(ContextImpl& context, size_t count, ComputeContext* first) {
    const std::string platform = context.getPlatform().getName();
    if (count != 1)
        throw OpenMMException("The M-RATTLE integrators on " + platform + " run on one device; this Context uses " +
                              std::to_string(count) + " (set the DeviceIndex property to one device)");
    if (first->getNumAtoms() != context.getSystem().getNumParticles())
        throw OpenMMException("The M-RATTLE plugin: OpenMM's " + platform + " context does not have the expected layout "
                              "(this plugin was built against another OpenMM)");
    return *first;
}

void MRattlePlugin::registerDeviceKernels(const std::string& platformName, FindComputeContext find) {
    checkOpenMMVersion(Platform::getOpenMMVersion());
    for (int i = 0; i < Platform::getNumPlatforms(); i++)
        if (Platform::getPlatform(i).getName() == platformName) {
            DeviceKernelFactory* factory = new DeviceKernelFactory(find);  // the platform owns it
            for (const RigidBodyIntegratorName& names : IntegratorNames::All)
                Platform::getPlatform(i).registerKernelFactory(names.stepKernel, factory);
        }
}
