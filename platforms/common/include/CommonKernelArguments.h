#ifndef MRATTLE_COMMON_KERNEL_ARGUMENTS_H_
#define MRATTLE_COMMON_KERNEL_ARGUMENTS_H_

#include "openmm/common/ArrayInterface.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeKernel.h"

namespace MRattlePlugin {

/**
 * A device kernel's arguments as they are added, in the order of its signature: each add
 * returns the argument's index, kept by name for the setArg of each launch.
 */
class CommonKernelArguments {
public:
    /** @param doubleMixed  the integration arithmetic ('mixed') is double (mixed and double precision) */
    CommonKernelArguments(OpenMM::ComputeKernel& kernel, bool doubleMixed) : kernel(kernel), doubleMixed(doubleMixed) {
    }
    template <class T>
    int add(const T& value) {
        kernel->addArg(value);
        return count++;
    }
    int add(OpenMM::ArrayInterface& array) {
        kernel->addArg(array);
        return count++;
    }
    int add(OpenMM::ComputeArray& array) {
        kernel->addArg(array);
        return count++;
    }
    /** A number in the integration arithmetic's precision. */
    int addMixed(double value) {
        if (doubleMixed)
            kernel->addArg(value);
        else
            kernel->addArg((float) value);
        return count++;
    }

private:
    OpenMM::ComputeKernel& kernel;
    bool doubleMixed;
    int count = 0;
};

} // namespace MRattlePlugin

#endif
