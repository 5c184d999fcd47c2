#ifndef MRATTLE_RIGID_BODY_CHECKPOINT_HEADER_H_
#define MRATTLE_RIGID_BODY_CHECKPOINT_HEADER_H_

#include "RigidBodyTopology.h"
#include <iosfwd>
#include <string>

namespace MRattlePlugin {

/**
 * A rigid-body integrator's part of a checkpoint (OpenMM writes it after the Context's own
 * data): magic, format version, the step kernel's name, the number of bodies in effect
 * and their signature, the kernel's own state (length and bytes: the only frame it has),
 * and a checksum of all of it, so that damage anywhere in it is refused rather than loaded.
 */
namespace RigidBodyCheckpointHeader {

/** Write the integrator's part, with kernelState (what the kernel's createCheckpoint() wrote). */
void write(std::ostream& stream, const std::string& kernelName, const RigidBodyTopology& topology,
           const std::string& kernelState);
/**
 * Read the integrator's part and return the kernel's state. Throws an OpenMMException
 * saying what differs unless it fits this kernel and these bodies and its checksum holds.
 */
std::string read(std::istream& stream, const std::string& kernelName, const RigidBodyTopology& topology);

} // namespace RigidBodyCheckpointHeader
} // namespace MRattlePlugin

#endif
