// RigidBodyIntegrator's integrator parameters: the state's time-varying variables in a State.
#include "RigidBodyIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include "openmm/serialization/SerializationNode.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {
const int ParametersVersion = 1;

/** "a, b" */
std::string namesOf(const IntegratorParameterValues& values) {
    std::string names;
    for (const auto& entry : values)
        names += (names.empty() ? "" : ", ") + entry.first;
    return names;
}
} // namespace

void RigidBodyIntegrator::serializeParameters(SerializationNode& node) const {
    requireContext();
    node.setIntProperty("version", ParametersVersion);
    node.setStringProperty("integrator", getIntegratorName());
    for (const auto& entry : state().getIntegratorParameters(*context)) {
        SerializationNode& list = node.createChildNode(entry.first);
        for (double value : entry.second)
            list.createChildNode("Value").setDoubleProperty("v", value);
    }
}

void RigidBodyIntegrator::deserializeParameters(const SerializationNode& node) {
    requireContext();
    RigidBodyState& bound = state();
    const std::string self = getIntegratorName(), prefix = self + ": the State's integrator parameters ";
    IntegratorParameterValues values = bound.getIntegratorParameters(*context);  // the names and sizes expected
    if (node.getProperties().empty() && node.getChildren().empty()) {
        // Written by an integrator that has none (OpenMM's own, or one of this plugin's).
        if (values.empty())
            return;
        throw OpenMMException(prefix + "are empty, from an integrator without state of its own; they must hold " +
                              namesOf(values) + ": take the State from a " + self +
                              "'s Context with getIntegratorParameters");
    }
    if (!node.hasProperty("integrator"))
        throw OpenMMException(prefix + "were not written by one of this plugin's integrators (no 'integrator' "
                              "property): they belong to another integrator class");
    const std::string writer = node.getStringProperty("integrator");
    if (writer != self)
        throw OpenMMException(prefix + "are those of a " + writer + ", not of a " + self +
                              ": a State's integrator parameters are set back only into the class that wrote them");
    if (node.getIntProperty("version", -1) != ParametersVersion)
        throw OpenMMException(prefix + "have format version " + node.getStringProperty("version", "(none)") +
                              "; this build reads version " + std::to_string(ParametersVersion));
    if (node.getChildren().size() != values.size())
        throw OpenMMException(prefix + "hold " + std::to_string(node.getChildren().size()) + " lists; a " + self +
                              " has " + std::to_string(values.size()) + " (" + namesOf(values) + ")");
    for (const SerializationNode& list : node.getChildren()) {
        auto expected = values.find(list.getName());
        if (expected == values.end())
            throw OpenMMException(prefix + "hold '" + list.getName() + "', which a " + self + " does not have (" +
                                  namesOf(values) + ")");
        if (list.getChildren().size() != expected->second.size())
            throw OpenMMException(prefix + "hold " + std::to_string(list.getChildren().size()) + " values of " +
                                  list.getName() + "; this " + self + " has " +
                                  std::to_string(expected->second.size()) + " (another chain length?)");
        for (size_t i = 0; i < expected->second.size(); i++) {
            const double value = list.getChildren()[i].getDoubleProperty("v");
            if (!std::isfinite(value))
                throw OpenMMException(prefix + "hold a value of " + list.getName() + " that is not finite (number " +
                                      std::to_string(i) + ")");
            expected->second[i] = value;
        }
    }
    bound.setIntegratorParameters(*context, values);
}
