#ifndef MRATTLE_BUSSI_INTEGRATOR_PROXY_H_
#define MRATTLE_BUSSI_INTEGRATOR_PROXY_H_

#include "MRattleBussiIntegrator.h"
#include "RigidBodyIntegratorProxy.h"

namespace MRattlePlugin {

// MRattleBussiIntegrator's own settings in its XML (MRattleBussiIntegratorProxy.cpp): temperature, collision frequency and random seed;
// declared wherever its proxy is made, so that the template's defaults are not used there.
template <>
OPENMM_EXPORT_MRATTLE void RigidBodyIntegratorProxy<MRattleBussiIntegrator>::writeOwnSettings(
    const MRattleBussiIntegrator& integrator, OpenMM::SerializationNode& node);
template <>
OPENMM_EXPORT_MRATTLE MRattleBussiIntegrator* RigidBodyIntegratorProxy<MRattleBussiIntegrator>::create(
    const OpenMM::SerializationNode& node, const std::string& typeName);

} // namespace MRattlePlugin

#endif
