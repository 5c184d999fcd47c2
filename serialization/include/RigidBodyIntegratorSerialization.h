#ifndef MRATTLE_RIGID_BODY_INTEGRATOR_SERIALIZATION_H_
#define MRATTLE_RIGID_BODY_INTEGRATOR_SERIALIZATION_H_

#include "RigidBodyIntegrator.h"
#include "openmm/serialization/SerializationNode.h"
#include "internal/windowsExportMRattle.h"
#include <string>

namespace MRattlePlugin {

/**
 * The XML form of what every RigidBodyIntegrator has: step size, constraint tolerance,
 * integration force groups and the bodies declared with addRigidBody(). The family's proxy,
 * RigidBodyIntegratorProxy<T>, writes its version and then calls serialize(); its
 * deserialize() checks the version with checkVersion(), constructs the integrator and
 * calls deserialize(). Properties are parsed strictly: a malformed number or index
 * raises an OpenMMException naming the integrator, the property and the text found.
 *
 *   <Integrator type="MRattleIntegrator" version="1" stepSize="0.002"
 *               constraintTolerance="1e-05" integrationForceGroups="-1">
 *     <RigidBodies count="1">
 *       <Body size="3"><Particle index="0"/><Particle index="1"/><Particle index="2"/></Body>
 *     </RigidBodies>
 *   </Integrator>
 */
class OPENMM_EXPORT_MRATTLE RigidBodyIntegratorSerialization {
public:
    /** Write the shared settings into node. */
    static void serialize(const RigidBodyIntegrator& integrator, OpenMM::SerializationNode& node);
    /**
     * Throw unless node's "version" is an integer from 1 to latestVersion; return it.
     *
     * @param typeName  the integrator's type name, for the message
     */
    static int checkVersion(const OpenMM::SerializationNode& node, const std::string& typeName, int latestVersion);
    /** The step size stored in node (to construct the integrator with). */
    static double getStepSize(const OpenMM::SerializationNode& node, const std::string& typeName);
    /** A property that must be a finite decimal number (strictly parsed). */
    static double getDouble(const OpenMM::SerializationNode& node, const std::string& name, const std::string& typeName);
    /** A property that must be a 32-bit integer (strictly parsed). */
    static int getInteger(const OpenMM::SerializationNode& node, const std::string& name, const std::string& typeName);
    /** Apply the shared settings stored in node to a newly constructed integrator. */
    static void deserialize(const OpenMM::SerializationNode& node, const std::string& typeName,
                            RigidBodyIntegrator& integrator);
};

} // namespace MRattlePlugin

#endif
