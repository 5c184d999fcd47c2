#ifndef MRATTLE_COMMON_KERNEL_FACTORY_H_
#define MRATTLE_COMMON_KERNEL_FACTORY_H_

#include "openmm/common/ComputeContext.h"
#include "openmm/internal/ContextImpl.h"
#include <string>

namespace MRattlePlugin {

/** How a device platform's plugin finds a Context's ComputeContext. */
typedef OpenMM::ComputeContext& (*FindComputeContext)(OpenMM::ContextImpl& context);

/**
 * Check OpenMM's version, then register the plugin's kernels on the platform of this name (if
 * OpenMM has it), every integrator of IntegratorNames, each kernel made over the Context's
 * ComputeContext (the splitting baseline's refused, naming the platforms that run it).
 */
void registerDeviceKernels(const std::string& platformName, FindComputeContext find);

/**
 * The one device context of a Context (first of `count`): refused for several devices, or when
 * its atom count shows a layout other than this build's OpenMM's.
 */
OpenMM::ComputeContext& checkedComputeContext(OpenMM::ContextImpl& context, size_t count, OpenMM::ComputeContext* first);

/**
 * FindComputeContext for a platform whose PlatformData lists its device contexts in
 * `contexts`. Each derives from ComputeContext alone, at the same address: converted without
 * the context's header (Debian's OpenMM lacks the Lepton headers OpenCLContext.h includes).
 */
template <class PlatformData>
OpenMM::ComputeContext& computeContextOf(OpenMM::ContextImpl& context) {
    const PlatformData& data = *static_cast<const PlatformData*>(context.getPlatformData());
    return checkedComputeContext(context, data.contexts.size(),
                                 data.contexts.empty() ? nullptr : reinterpret_cast<OpenMM::ComputeContext*>(data.contexts[0]));
}

} // namespace MRattlePlugin

#endif
