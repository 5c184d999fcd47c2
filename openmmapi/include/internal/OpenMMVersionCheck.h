#ifndef MRATTLE_OPENMM_VERSION_CHECK_H_
#define MRATTLE_OPENMM_VERSION_CHECK_H_

#include "internal/windowsExportMRattle.h"
#include <string>

namespace MRattlePlugin {

/** The OpenMM version (OpenMM::Platform::getOpenMMVersion()) this build of the plugin was configured against. */
OPENMM_EXPORT_MRATTLE std::string getBuiltAgainstOpenMMVersion();

/**
 * Throws an OpenMMException saying what to do unless runningVersion is the version the
 * plugin was built against: OpenMM's platform data differ between versions (7.7 and 8.x
 * lay out ReferencePlatform::PlatformData differently), so kernels built against one must
 * not run in another. Called when the kernel plugin registers and when an integrator is
 * bound to a Context.
 */
OPENMM_EXPORT_MRATTLE void checkOpenMMVersion(const std::string& runningVersion);

} // namespace MRattlePlugin

#endif
