#include "internal/RigidBodyCheckpointHeader.h"
#include "openmm/OpenMMException.h"
#include <algorithm>
#include <cstdint>
#include <istream>
#include <ostream>
#include <sstream>

using namespace MRattlePlugin;
using OpenMM::OpenMMException;

namespace {

// The integrator's part of a checkpoint (OpenMM writes it after the Context's own data):
// magic, format version, the step kernel's name, the number of bodies in effect and their
// signature, then the kernel's own state. Numbers are native-endian, like the rest of an
// OpenMM checkpoint. Version 2: the kernel's state follows the header. Version 3: the
// kernel's state is framed by its length, and an FNV-1a checksum of everything closes it.
// Version 4: the same layout; the frame here is the kernel state's only one (in version 3
// the Reference kernel framed its state again, which it still reads).
const char CheckpointMagic[8] = {'M', 'R', 'a', 't', 't', 'l', 'e', 'C'};
const int32_t CheckpointVersion = 4;
const int32_t OldestReadableVersion = 3;
const int32_t MaxKernelNameLength = 1024;
const int64_t MaxKernelStateLength = 1 << 24;

uint64_t checksum(const std::string& bytes) {
    uint64_t hash = 14695981039346656037ULL;
    for (unsigned char c : bytes) {
        hash ^= c;
        hash *= 1099511628211ULL;
    }
    return hash;
}

/** Reads from a stream and keeps a copy of every byte read, for the checksum. */
struct RecordingReader {
    std::istream& stream;
    std::string bytes;
    void read(char* data, std::streamsize count) {
        stream.read(data, count);
        bytes.append(data, stream.gcount());
    }
    std::streamsize gcount() const {
        return stream.gcount();
    }
    explicit operator bool() const {
        return (bool) stream;
    }
};

template <class T>
void writeValue(std::ostream& stream, T value) {
    stream.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
T readValue(RecordingReader& stream, const char* what) {
    T value;
    stream.read(reinterpret_cast<char*>(&value), sizeof(T));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(T))
        throw OpenMMException(std::string("the checkpoint is truncated (it ends before the ") + what + ")");
    return value;
}

std::string hex(uint64_t value) {
    std::ostringstream text;
    text << "0x" << std::hex << value;
    return text.str();
}

/** The header's kernel name, printable whatever bytes a damaged checkpoint holds. */
std::string printable(const std::string& name) {
    std::string text;
    for (unsigned char c : name)
        text += (c >= 32 && c < 127 ? std::string(1, (char) c) : "\\x" + hex(c).substr(2));
    return text;
}

} // namespace

void RigidBodyCheckpointHeader::write(std::ostream& out, const std::string& kernelName,
                                      const RigidBodyTopology& topology, const std::string& kernelState) {
    std::ostringstream stream;
    stream.write(CheckpointMagic, sizeof(CheckpointMagic));
    writeValue<int32_t>(stream, CheckpointVersion);
    writeValue<int32_t>(stream, kernelName.size());
    stream.write(kernelName.data(), kernelName.size());
    writeValue<int32_t>(stream, topology.getNumBodies());
    writeValue<uint64_t>(stream, topology.getSignature());
    writeValue<int64_t>(stream, kernelState.size());
    stream.write(kernelState.data(), kernelState.size());
    const std::string bytes = stream.str();
    out.write(bytes.data(), bytes.size());
    writeValue<uint64_t>(out, checksum(bytes));
}

std::string RigidBodyCheckpointHeader::read(std::istream& input, const std::string& kernelName,
                                            const RigidBodyTopology& topology) {
    RecordingReader stream{input, std::string()};
    char magic[sizeof(CheckpointMagic)];
    stream.read(magic, sizeof(magic));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(magic))
        throw OpenMMException("the checkpoint holds no rigid-body integrator data: it is truncated, or it was "
                              "written by a Context with a different integrator");
    if (!std::equal(magic, magic + sizeof(magic), CheckpointMagic))
        throw OpenMMException("the checkpoint's integrator data is not a rigid-body integrator's: it is malformed, "
                              "or it was written by a Context with a different integrator");
    int32_t version = readValue<int32_t>(stream, "format version");
    if (version < OldestReadableVersion || version > CheckpointVersion)
        throw OpenMMException("the checkpoint's rigid-body integrator data has format version " +
                              std::to_string(version) + ", and this build of the plugin reads versions " +
                              std::to_string(OldestReadableVersion) + " to " + std::to_string(CheckpointVersion));
    int32_t nameLength = readValue<int32_t>(stream, "integrator name");
    if (nameLength < 0 || nameLength > MaxKernelNameLength)
        throw OpenMMException("the checkpoint's rigid-body integrator data is malformed (integrator name of length " +
                              std::to_string(nameLength) + ")");
    std::string name(nameLength, ' ');
    stream.read(&name[0], nameLength);
    if (!stream || stream.gcount() != nameLength)
        throw OpenMMException("the checkpoint is truncated (it ends in the integrator name)");
    if (name != kernelName)
        throw OpenMMException("the checkpoint was written by an integrator using kernel '" + printable(name) +
                              "', and this one uses '" + kernelName +
                              "': use saveState()/loadState() to change integrators");
    int32_t numBodies = readValue<int32_t>(stream, "number of rigid bodies");
    uint64_t signature = readValue<uint64_t>(stream, "rigid-body signature");
    if (numBodies != topology.getNumBodies() || signature != topology.getSignature())
        throw OpenMMException("the checkpoint was written with " + std::to_string(numBodies) +
                              " rigid bodies in effect (signature " + hex(signature) + "), and this Context has " +
                              std::to_string(topology.getNumBodies()) + " (signature " + hex(topology.getSignature()) +
                              "): the bodies differ, so the System or the bodies declared with addRigidBody() are not "
                              "those the checkpoint was written with");
    int64_t stateLength = readValue<int64_t>(stream, "kernel's state");
    if (stateLength < 0 || stateLength > MaxKernelStateLength)
        throw OpenMMException("the checkpoint's rigid-body integrator data is malformed (kernel state of length " +
                              std::to_string(stateLength) + ")");
    std::string state(stateLength, ' ');
    stream.read(&state[0], stateLength);
    if (!stream || stream.gcount() != stateLength)
        throw OpenMMException("the checkpoint is truncated (it ends in the kernel's state)");
    const uint64_t expectedChecksum = checksum(stream.bytes);
    const uint64_t found = readValue<uint64_t>(stream, "checksum");
    if (found != expectedChecksum)
        throw OpenMMException("the checkpoint's rigid-body integrator data is damaged (its checksum is " + hex(found) +
                              ", and its contents give " + hex(expectedChecksum) + ")");
    return state;
}
