#ifndef MRATTLE_NOSE_HOOVER_INTEGRATOR_PROXY_H_
#define MRATTLE_NOSE_HOOVER_INTEGRATOR_PROXY_H_

#include "MRattleNoseHooverIntegrator.h"
#include "RigidBodyIntegratorProxy.h"

namespace MRattlePlugin {

// MRattleNoseHooverIntegrator's own settings in its XML (MRattleNoseHooverIntegratorProxy.cpp): temperature, collision frequency, chain length, multiple time steps and Yoshida-Suzuki order;
// declared wherever its proxy is made, so that the template's defaults are not used there.
template <>
OPENMM_EXPORT_MRATTLE void RigidBodyIntegratorProxy<MRattleNoseHooverIntegrator>::writeOwnSettings(
    const MRattleNoseHooverIntegrator& integrator, OpenMM::SerializationNode& node);
template <>
OPENMM_EXPORT_MRATTLE MRattleNoseHooverIntegrator* RigidBodyIntegratorProxy<MRattleNoseHooverIntegrator>::create(
    const OpenMM::SerializationNode& node, const std::string& typeName);

} // namespace MRattlePlugin

#endif
