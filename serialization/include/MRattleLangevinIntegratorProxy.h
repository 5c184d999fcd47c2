#ifndef MRATTLE_LANGEVIN_INTEGRATOR_PROXY_H_
#define MRATTLE_LANGEVIN_INTEGRATOR_PROXY_H_

#include "openmm/serialization/SerializationProxy.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * XmlSerializer support for MRattleLangevinIntegrator (type name "MRattleLangevinIntegrator"), with
 * temperature, friction and random seed. It is
 * registered when libMRattlePlugin is loaded.
 */
class OPENMM_EXPORT_MRATTLE MRattleLangevinIntegratorProxy : public OpenMM::SerializationProxy {
public:
    /** The version written; deserialize() reads versions 1 to this. */
    static const int Version = 1;
    MRattleLangevinIntegratorProxy();
    void serialize(const void* object, OpenMM::SerializationNode& node) const override;
    void* deserialize(const OpenMM::SerializationNode& node) const override;
};

} // namespace MRattlePlugin

#endif
