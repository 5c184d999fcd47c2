#ifndef MRATTLE_RIGID_BODY_CHECKPOINT_HEADER_H_
#define MRATTLE_RIGID_BODY_CHECKPOINT_HEADER_H_

#include "RigidBodyTopology.h"
#include <iosfwd>
#include <string>

namespace MRattlePlugin {

/**
 * The head of a rigid-body integrator's part of a checkpoint (OpenMM writes it after the
 * Context's own data): magic, format version, the step kernel's name, the number of
 * bodies in effect and their signature. The kernel's own state follows it.
 */
namespace RigidBodyCheckpointHeader {

void write(std::ostream& stream, const std::string& kernelName, const RigidBodyTopology& topology);
/** Throws an OpenMMException saying what differs unless the header fits this kernel and these bodies. */
void check(std::istream& stream, const std::string& kernelName, const RigidBodyTopology& topology);

} // namespace RigidBodyCheckpointHeader
} // namespace MRattlePlugin

#endif
