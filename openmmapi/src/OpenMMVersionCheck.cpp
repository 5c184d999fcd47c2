#include "internal/OpenMMVersionCheck.h"
#include "MRattleBuildInfo.h"
#include "openmm/OpenMMException.h"

std::string MRattlePlugin::getBuiltAgainstOpenMMVersion() {
    return MRATTLE_OPENMM_VERSION;
}

void MRattlePlugin::checkOpenMMVersion(const std::string& runningVersion) {
    if (runningVersion != MRATTLE_OPENMM_VERSION)
        throw OpenMM::OpenMMException(std::string("The M-RATTLE plugin was built against OpenMM ") +
                                      MRATTLE_OPENMM_VERSION + ", and this process runs OpenMM " + runningVersion +
                                      ": rebuild the plugin against this OpenMM (cmake -DOPENMM_DIR=<its install folder>)");
}
