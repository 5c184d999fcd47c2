#ifndef MRATTLE_LANGEVIN_INTEGRATOR_PROXY_H_
#define MRATTLE_LANGEVIN_INTEGRATOR_PROXY_H_

#include "MRattleLangevinIntegrator.h"
#include "RigidBodyIntegratorProxy.h"

namespace MRattlePlugin {

// MRattleLangevinIntegrator's own settings in its XML (MRattleLangevinIntegratorProxy.cpp):
// declared wherever its proxy is made, so that the template's defaults are not used there.
template <>
OPENMM_EXPORT_MRATTLE void RigidBodyIntegratorProxy<MRattleLangevinIntegrator>::writeOwnSettings(
    const MRattleLangevinIntegrator& integrator, OpenMM::SerializationNode& node);
template <>
OPENMM_EXPORT_MRATTLE MRattleLangevinIntegrator* RigidBodyIntegratorProxy<MRattleLangevinIntegrator>::create(
    const OpenMM::SerializationNode& node, const std::string& typeName);

} // namespace MRattlePlugin

#endif
