#include "RigidBodyIntegratorSerialization.h"
#include "openmm/OpenMMException.h"
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <vector>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::string;

namespace {

void fail(const string& typeName, const string& message) {
    throw OpenMMException(typeName + " XML: " + message);
}

/** The element's name for messages: OpenMM hands proxies the root element without its name. */
string elementName(const SerializationNode& node) {
    return "<" + (node.getName().empty() ? string("Integrator") : node.getName()) + ">";
}

const string& requireProperty(const SerializationNode& node, const string& name, const string& typeName) {
    if (!node.hasProperty(name))
        fail(typeName, "the " + elementName(node) + " element has no '" + name + "' attribute");
    return node.getStringProperty(name);
}

// SerializationNode's own getters turn text that is not a number into 0; these reject it.
long long parseInteger(const SerializationNode& node, const string& name, const string& typeName) {
    const string& text = requireProperty(node, name, typeName);
    char* end = nullptr;
    errno = 0;
    long long value = std::strtoll(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno == ERANGE || value < INT32_MIN || value > INT32_MAX)
        fail(typeName, "the '" + name + "' attribute of " + elementName(node) + " must be an integer, found \"" + text +
                           "\"");
    return value;
}

double parseDouble(const SerializationNode& node, const string& name, const string& typeName) {
    const string& text = requireProperty(node, name, typeName);
    // Decimal notation only: strtod also reads hexadecimal ("0x10" is 16), "inf" and "nan".
    const bool decimal = !text.empty() && text.find_first_not_of("0123456789+-.eE") == string::npos;
    char* end = nullptr;
    double value = std::strtod(text.c_str(), &end);
    if (!decimal || *end != '\0' || !std::isfinite(value))
        fail(typeName, "the '" + name + "' attribute of " + elementName(node) + " must be a finite decimal number, found \"" +
                           text + "\"");
    return value;
}

} // namespace

void RigidBodyIntegratorSerialization::serialize(const RigidBodyIntegrator& integrator, SerializationNode& node) {
    node.setDoubleProperty("stepSize", integrator.getStepSize());
    node.setDoubleProperty("constraintTolerance", integrator.getConstraintTolerance());
    node.setIntProperty("integrationForceGroups", integrator.getIntegrationForceGroups());
    // The counts let a document cut short inside the list be told from a shorter list
    // (OpenMM's XML reader accepts a document whose closing tags are missing).
    SerializationNode& bodies = node.createChildNode("RigidBodies");
    bodies.setIntProperty("count", integrator.getNumRigidBodies());
    for (int b = 0; b < integrator.getNumRigidBodies(); b++) {
        SerializationNode& body = bodies.createChildNode("Body");
        body.setIntProperty("size", integrator.getRigidBodyParticles(b).size());
        for (int particle : integrator.getRigidBodyParticles(b))
            body.createChildNode("Particle").setIntProperty("index", particle);
    }
}

int RigidBodyIntegratorSerialization::checkVersion(const SerializationNode& node, const string& typeName,
                                                   int latestVersion) {
    int version = parseInteger(node, "version", typeName);
    if (version < 1 || version > latestVersion)
        fail(typeName, "unsupported version " + std::to_string(version) + " (this build of the plugin reads versions 1 to " +
                           std::to_string(latestVersion) + ")");
    return version;
}

double RigidBodyIntegratorSerialization::getStepSize(const SerializationNode& node, const string& typeName) {
    double stepSize = parseDouble(node, "stepSize", typeName);
    if (stepSize == 0)
        fail(typeName, "the step size must be nonzero, found \"" + node.getStringProperty("stepSize") + "\"");
    return stepSize;
}

double RigidBodyIntegratorSerialization::getDouble(const SerializationNode& node, const string& name,
                                                  const string& typeName) {
    return parseDouble(node, name, typeName);
}

int RigidBodyIntegratorSerialization::getInteger(const SerializationNode& node, const string& name,
                                                 const string& typeName) {
    return parseInteger(node, name, typeName);
}

void RigidBodyIntegratorSerialization::deserialize(const SerializationNode& node, const string& typeName,
                                                   RigidBodyIntegrator& integrator) {
    integrator.setStepSize(getStepSize(node, typeName));
    double tolerance = parseDouble(node, "constraintTolerance", typeName);
    if (!(tolerance > 0))
        fail(typeName, "the constraint tolerance must be positive, found " + node.getStringProperty("constraintTolerance"));
    integrator.setConstraintTolerance(tolerance);
    integrator.setIntegrationForceGroups(parseInteger(node, "integrationForceGroups", typeName));
    const std::vector<SerializationNode>& children = node.getChildren();
    for (const SerializationNode& child : children)
        if (child.getName() != "RigidBodies")
            fail(typeName, "unexpected element <" + child.getName() + "> in " + elementName(node));
    if (children.empty())
        fail(typeName, "the " + elementName(node) + " element has no <RigidBodies> element");
    if (children.size() > 1)
        fail(typeName, "the " + elementName(node) + " element has " + std::to_string(children.size()) +
                           " <RigidBodies> elements; it must have one");
    const SerializationNode& bodies = node.getChildNode("RigidBodies");
    const long long numBodies = parseInteger(bodies, "count", typeName);
    if (numBodies != (long long) bodies.getChildren().size())
        fail(typeName, "<RigidBodies> declares " + std::to_string(numBodies) + " bodies and holds " +
                           std::to_string(bodies.getChildren().size()) + ": the document is truncated or was edited");
    for (const SerializationNode& body : bodies.getChildren()) {
        if (body.getName() != "Body")
            fail(typeName, "unexpected element <" + body.getName() + "> in <RigidBodies>");
        const long long size = parseInteger(body, "size", typeName);
        if (size != (long long) body.getChildren().size())
            fail(typeName, "a <Body> declares " + std::to_string(size) + " particles and holds " +
                               std::to_string(body.getChildren().size()) + ": the document is truncated or was edited");
        std::vector<int> particles;
        for (const SerializationNode& particle : body.getChildren()) {
            if (particle.getName() != "Particle")
                fail(typeName, "unexpected element <" + particle.getName() + "> in <Body>");
            particles.push_back(parseInteger(particle, "index", typeName));
            if (!particle.getChildren().empty())
                fail(typeName, "unexpected element <" + particle.getChildren()[0].getName() + "> in <Particle>");
        }
        try {
            integrator.addRigidBody(particles);
        } catch (const OpenMMException& e) {
            fail(typeName, e.what());
        }
    }
}
