#include "HostRigidBodyRules.h"
#include "openmm/OpenMMException.h"
#include <cstdint>
#include <istream>
#include <ostream>

using namespace MRattlePlugin;
using namespace OpenMM;

void HostRigidBodyRules::writeKernelState(std::ostream& stream, const std::string& state) {
    const int32_t length = state.size();
    stream.write(reinterpret_cast<const char*>(&length), sizeof(length));
    stream.write(state.data(), length);
}

std::string HostRigidBodyRules::readKernelState(std::istream& stream) {
    int32_t length = -1;
    stream.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(length))
        throw OpenMMException("the checkpoint is truncated (it ends before the kernel's state)");
    if (length < 0 || length > (1 << 20))
        throw OpenMMException("the checkpoint's kernel data is malformed (a state of length " + std::to_string(length) +
                              ")");
    std::string state(length, ' ');
    stream.read(&state[0], length);
    if (!stream || stream.gcount() != length)
        throw OpenMMException("the checkpoint is truncated (it ends in the kernel's state)");
    return state;
}
