#ifndef MRATTLE_REFERENCE_KERNEL_FACTORY_H_
#define MRATTLE_REFERENCE_KERNEL_FACTORY_H_

#include "openmm/KernelFactory.h"

namespace MRattlePlugin {

/** Creates the plugin's reference kernels; registered on the Reference and CPU platforms. */
class ReferenceMRattleKernelFactory : public OpenMM::KernelFactory {
public:
    OpenMM::KernelImpl* createKernelImpl(std::string name, const OpenMM::Platform& platform,
                                         OpenMM::ContextImpl& context) const override;
};

} // namespace MRattlePlugin

#endif
