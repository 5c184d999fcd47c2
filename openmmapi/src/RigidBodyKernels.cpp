#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <cstdint>
#include <istream>
#include <ostream>

using namespace MRattlePlugin;

// Key functions: the interfaces' vtables and type information live in this library only,
// so Kernel::getAs<> casts agree across the plugin's shared libraries.
RigidBodyState::~RigidBodyState() {
}

RigidBodyStepKernel::RigidBodyStepKernel(const std::string& name, const OpenMM::Platform& platform)
    : OpenMM::KernelImpl(name, platform) {
}

RigidBodyStepKernel::~RigidBodyStepKernel() {
}

int IntegratorNames::indexOfStepKernel(const std::string& stepKernelName) {
    for (int i = 0; i < (int) (sizeof(All) / sizeof(All[0])); i++)
        if (stepKernelName == All[i].stepKernel)
            return i;
    throw OpenMM::OpenMMException("The M-RATTLE plugin has no kernel named '" + stepKernelName + "'");
}

void MRattlePlugin::writeIntegratorVariables(std::ostream& stream, const std::vector<const std::vector<double>*>& values,
                                             bool lengthFirst) {
    if (lengthFirst) {
        const int32_t length = values[0]->size();
        stream.write(reinterpret_cast<const char*>(&length), sizeof(length));
    }
    for (const std::vector<double>* variable : values)
        stream.write(reinterpret_cast<const char*>(variable->data()), variable->size() * sizeof(double));
}

void MRattlePlugin::readIntegratorVariables(std::istream& stream, const std::string& names,
                                            const std::vector<std::vector<double>*>& values, bool lengthFirst) {
    using OpenMM::OpenMMException;
    if (lengthFirst) {
        int32_t length = -1;
        stream.read(reinterpret_cast<char*>(&length), sizeof(length));
        if (!stream)
            throw OpenMMException("the checkpoint is truncated (it ends before the " + names + ")");
        if (length != (int32_t) values[0]->size())
            throw OpenMMException("the checkpoint's " + names + " has " + std::to_string(length) +
                                  " values, this integrator's " + std::to_string(values[0]->size()));
    }
    std::vector<std::vector<double> > read(values.size());
    for (size_t i = 0; i < values.size(); i++) {
        read[i].resize(values[i]->size());
        stream.read(reinterpret_cast<char*>(read[i].data()), read[i].size() * sizeof(double));
        if (!stream)
            throw OpenMMException("the checkpoint is truncated (it ends in the " + names + ")");
        for (double value : read[i])
            if (!std::isfinite(value))
                throw OpenMMException("the checkpoint's kernel data is malformed (the " + names +
                                      " holds a value that is not finite)");
    }
    for (size_t i = 0; i < values.size(); i++)
        values[i]->swap(read[i]);
}
