/*
 * XmlSerializer support for the rigid-body integrators: the proxies are registered when
 * the library loads, a round trip keeps every setting and gives the same trajectory bit
 * for bit, and malformed documents are refused with a clear OpenMMException.
 */
#include "RigidSplittingIntegrator.h"
#include "TestSupport.h"
#include "openmm/serialization/XmlSerializer.h"
#include <gtest/gtest.h>
#include <cstring>
#include <memory>
#include <sstream>

using namespace OpenMM;
using namespace MRattlePlugin;
using namespace MRattleTest;
using std::string;
using std::vector;

namespace {

bool sameBits(double a, double b) {
    return std::memcmp(&a, &b, sizeof(double)) == 0;
}

/** Four benzenes in vacuum, LJ in force group 1 and a weak spring between two rings in group 2. */
struct Benzenes {
    System system;
    vector<Vec3> positions;
    vector<vector<int> > molecules;
};

Benzenes fourBenzenes() {
    Benzenes b;
    Molecule m = benzene();
    NonbondedForce* nonbonded = new NonbondedForce();
    nonbonded->setForceGroup(1);
    HarmonicBondForce* bonds = new HarmonicBondForce();
    const Vec3 centers[4] = {Vec3(0, 0, 0), Vec3(0.75, 0.05, 0), Vec3(0, 0.7, 0.2), Vec3(0.72, 0.75, -0.15)};
    for (int k = 0; k < 4; k++) {
        vector<int> members;
        for (size_t s = 0; s < m.sites.size(); s++) {
            members.push_back(b.system.addParticle(m.masses[s]));
            const Vec3& site = m.sites[s];
            // Alternate the ring's plane so the rings are not parallel.
            b.positions.push_back(centers[k] + (k % 2 == 0 ? site : Vec3(site[0], site[2], site[1])));
            nonbonded->addParticle(0, m.sigmas[s], m.epsilons[s]);
        }
        for (auto& bond : m.bonds)
            bonds->addBond(members[bond.first], members[bond.second], 0.14, 0.0);
        for (size_t i = 0; i < members.size(); i++)
            for (size_t j = i + 1; j < members.size(); j++)
                nonbonded->addException(members[i], members[j], 0, 1, 0);
        b.molecules.push_back(members);
    }
    HarmonicBondForce* spring = new HarmonicBondForce();
    spring->addBond(0, 12, 0.5, 200.0);
    spring->setForceGroup(2);
    b.system.addForce(nonbonded);
    b.system.addForce(bonds);
    b.system.addForce(spring);
    return b;
}

/** An integrator with every setting away from its default. */
template <class IntegratorType>
std::unique_ptr<IntegratorType> configured(const Benzenes& b) {
    std::unique_ptr<IntegratorType> integrator(new IntegratorType(0.0017320508075688772));
    integrator->setConstraintTolerance(3.3e-7);
    integrator->setIntegrationForceGroups((1 << 1) | (1 << 2));
    // Bodies in a scrambled order, members too, and one body of a single particle.
    integrator->addRigidBody({13, 12, 23, 14, 15, 16, 17, 18, 19, 20, 21, 22});
    integrator->addRigidBody(b.molecules[0]);
    integrator->addRigidBody({30, 31, 32, 33, 34, 35, 24, 25, 26, 27, 28, 29});
    integrator->addRigidBody({40});
    return integrator;
}

template <class IntegratorType>
void expectSameSettings(const IntegratorType& expected, const Integrator& actualBase) {
    const IntegratorType* actual = dynamic_cast<const IntegratorType*>(&actualBase);
    ASSERT_NE(nullptr, actual) << "deserialized to the wrong type";
    EXPECT_TRUE(sameBits(expected.getStepSize(), actual->getStepSize()));
    EXPECT_TRUE(sameBits(expected.getConstraintTolerance(), actual->getConstraintTolerance()));
    EXPECT_EQ(expected.getIntegrationForceGroups(), actual->getIntegrationForceGroups());
    ASSERT_EQ(expected.getNumRigidBodies(), actual->getNumRigidBodies());
    for (int i = 0; i < expected.getNumRigidBodies(); i++)
        EXPECT_EQ(expected.getRigidBodyParticles(i), actual->getRigidBodyParticles(i)) << "body " << i;
}

template <class IntegratorType>
void roundTripKeepsEverySetting(const string& typeName) {
    Benzenes b = fourBenzenes();
    std::unique_ptr<IntegratorType> original = configured<IntegratorType>(b);
    string xml = toXml(*original);
    EXPECT_NE(string::npos, xml.find("type=\"" + typeName + "\"")) << xml;
    EXPECT_NE(string::npos, xml.find("version=\"1\"")) << xml;
    std::unique_ptr<Integrator> copy = fromXml(xml);
    expectSameSettings(*original, *copy);
    // Serializing the copy gives the same document.
    EXPECT_EQ(xml, toXml(*copy));
    // XmlSerializer::clone goes through the same proxy without text.
    std::unique_ptr<Integrator> clone(XmlSerializer::clone<Integrator>(*original));
    expectSameSettings(*original, *clone);

    // An integrator with nothing set (molecules as bodies) round-trips too.
    IntegratorType plain(0.002);
    std::unique_ptr<Integrator> plainCopy = fromXml(toXml(plain));
    expectSameSettings(plain, *plainCopy);
}

template <class IntegratorType>
void deserializedIntegratorFollowsTheSameTrajectory() {
    Benzenes b = fourBenzenes();
    std::unique_ptr<IntegratorType> original = configured<IntegratorType>(b);
    std::unique_ptr<Integrator> copy = fromXml(toXml(*original));
    Context first(b.system, *original, platform("Reference"));
    Context second(b.system, *copy, platform("Reference"));
    for (Context* context : {&first, &second}) {
        context->setPositions(b.positions);
        context->setVelocitiesToTemperature(300, 11);
    }
    original->step(200);
    copy->step(200);
    State s1 = first.getState(State::Positions | State::Velocities);
    State s2 = second.getState(State::Positions | State::Velocities);
    int differing = 0;
    for (int i = 0; i < b.system.getNumParticles(); i++)
        for (int d = 0; d < 3; d++) {
            differing += !sameBits(s1.getPositions()[i][d], s2.getPositions()[i][d]);
            differing += !sameBits(s1.getVelocities()[i][d], s2.getVelocities()[i][d]);
        }
    EXPECT_EQ(0, differing);
    // The declared bodies are in effect (body {40} is a free particle) and the run moved.
    const IntegratorType& deserialized = dynamic_cast<const IntegratorType&>(*copy);
    EXPECT_EQ(3, deserialized.getNumBodiesInEffect());
    EXPECT_EQ(3 * 6 + 3 * 12, deserialized.getNumDegreesOfFreedom());
    EXPECT_GT(std::fabs(s1.getPositions()[0][0] - b.positions[0][0]), 1e-4);
}

/** Deserializing xml throws an OpenMMException whose message contains every phrase. */
void expectRefused(const string& xml, const vector<string>& phrases) {
    string message = messageOf([&] { fromXml(xml); });
    for (const string& phrase : phrases)
        EXPECT_NE(string::npos, message.find(phrase)) << "'" << phrase << "' not in: " << message << " (" << xml << ")";
}

const string ValidHeader =
    "<?xml version=\"1.0\" ?>\n<Integrator constraintTolerance=\"1e-05\" integrationForceGroups=\"-1\" "
    "stepSize=\"0.002\" type=\"MRattleIntegrator\" version=\"1\">\n";

/** A document with the given bodies (each a list of particle indices given as text). */
string documentWithBodies(const vector<vector<string> >& bodies) {
    string xml = ValidHeader + "<RigidBodies count=\"" + std::to_string(bodies.size()) + "\">";
    for (const auto& body : bodies) {
        xml += "<Body size=\"" + std::to_string(body.size()) + "\">";
        for (const string& index : body)
            xml += "<Particle index=\"" + index + "\"/>";
        xml += "</Body>";
    }
    return xml + "</RigidBodies>\n</Integrator>\n";
}

} // namespace

TEST(Serialization, ProxiesAreRegisteredWhenTheLibraryLoads) {
    // Nothing in this test registers them: the library's load-time constructor does.
    EXPECT_EQ("MRattleIntegrator", SerializationProxy::getProxy("MRattleIntegrator").getTypeName());
    EXPECT_EQ("RigidSplittingIntegrator", SerializationProxy::getProxy("RigidSplittingIntegrator").getTypeName());
}

TEST(Serialization, MRattleRoundTripKeepsEverySetting) {
    roundTripKeepsEverySetting<MRattleIntegrator>("MRattleIntegrator");
}

TEST(Serialization, RigidSplittingRoundTripKeepsEverySetting) {
    roundTripKeepsEverySetting<RigidSplittingIntegrator>("RigidSplittingIntegrator");
}

TEST(Serialization, MRattleDeserializedFollowsTheSameTrajectory) {
    deserializedIntegratorFollowsTheSameTrajectory<MRattleIntegrator>();
}

TEST(Serialization, RigidSplittingDeserializedFollowsTheSameTrajectory) {
    deserializedIntegratorFollowsTheSameTrajectory<RigidSplittingIntegrator>();
}

TEST(Serialization, HandWrittenDocumentIsRead) {
    std::unique_ptr<Integrator> integrator = fromXml(documentWithBodies({{"3", "1"}}));
    MRattleIntegrator& read = dynamic_cast<MRattleIntegrator&>(*integrator);
    EXPECT_EQ(0.002, read.getStepSize());
    EXPECT_EQ(1e-5, read.getConstraintTolerance());
    EXPECT_EQ(-1, read.getIntegrationForceGroups());
    ASSERT_EQ(1, read.getNumRigidBodies());
    EXPECT_EQ(vector<int>({3, 1}), read.getRigidBodyParticles(0));
}

TEST(Serialization, RefusesUnknownVersion) {
    string xml = documentWithBodies({});
    for (const string& version : {"2", "0", "-1"}) {
        string changed = xml;
        changed.replace(changed.find("version=\"1\""), 11, "version=\"" + version + "\"");
        expectRefused(changed, {"MRattleIntegrator XML", "unsupported version " + version});
    }
    string notNumber = xml;
    notNumber.replace(notNumber.find("version=\"1\""), 11, "version=\"one\"");
    expectRefused(notNumber, {"'version'", "integer", "one"});
    string missing = xml;
    missing.replace(missing.find("version=\"1\""), 11, "");
    expectRefused(missing, {"no 'version' attribute"});
}

TEST(Serialization, RefusesMalformedSettings) {
    string xml = documentWithBodies({});
    auto withAttribute = [&](const string& name, const string& value) {
        string changed = xml;
        size_t start = changed.find(" " + name + "=\"") + 1;
        size_t end = changed.find('"', start + name.size() + 2);
        return changed.replace(start, end + 1 - start, name + "=\"" + value + "\"");
    };
    expectRefused(withAttribute("stepSize", "fast"), {"'stepSize'", "finite decimal number", "fast"});
    expectRefused(withAttribute("stepSize", "nan"), {"'stepSize'", "finite decimal number"});
    expectRefused(withAttribute("stepSize", "0.002ps"), {"'stepSize'"});
    expectRefused(withAttribute("constraintTolerance", "-1e-5"), {"constraint tolerance must be positive"});
    expectRefused(withAttribute("integrationForceGroups", "1.5"), {"'integrationForceGroups'", "integer"});
    expectRefused(withAttribute("integrationForceGroups", "99999999999"), {"'integrationForceGroups'"});
    string noBodies = xml;
    size_t start = noBodies.find("<RigidBodies"), end = noBodies.find("</RigidBodies>") + 14;
    noBodies.erase(start, end - start);
    expectRefused(noBodies, {"no <RigidBodies> element"});
    string extra = xml;
    extra.insert(extra.find("</Integrator>"), "<Thermostat/>");
    expectRefused(extra, {"unexpected element <Thermostat>"});
    string noCount = documentWithBodies({{"0", "1"}});
    noCount.replace(noCount.find(" count=\"1\""), 10, "");
    expectRefused(noCount, {"no 'count' attribute"});
    string wrongSize = documentWithBodies({{"0", "1"}});
    wrongSize.replace(wrongSize.find("size=\"2\""), 8, "size=\"3\"");
    expectRefused(wrongSize, {"declares 3 particles and holds 2"});
}

TEST(Serialization, RefusesBadBodies) {
    expectRefused(documentWithBodies({{"0", "-4"}}), {"MRattleIntegrator XML", "Rigid body 0", "-4", "negative"});
    expectRefused(documentWithBodies({{"2"}, {"5", "5"}}), {"Rigid body 1", "particle 5 twice"});
    expectRefused(documentWithBodies({{}}), {"Rigid body 0", "empty"});
    expectRefused(documentWithBodies({{"x1"}}), {"'index'", "integer", "x1"});
    expectRefused(documentWithBodies({{""}}), {"'index'", "integer"});
    string noIndex = documentWithBodies({{"1"}});
    noIndex.replace(noIndex.find(" index=\"1\""), 10, "");
    expectRefused(noIndex, {"no 'index' attribute"});
    string atom = documentWithBodies({{"1"}});
    atom.replace(atom.find("<Particle"), 9, "<Atom");
    expectRefused(atom, {"unexpected element <Atom> in <Body>"});
    string molecule = documentWithBodies({{"1"}});
    molecule.replace(molecule.find("<Body"), 5, "<Molecule");
    molecule.replace(molecule.find("</Body>"), 7, "</Molecule>");
    expectRefused(molecule, {"unexpected element <Molecule> in <RigidBodies>"});
}

TEST(Serialization, BodiesThatDoNotFitTheSystemAreRefusedByTheContext) {
    // Indices are checked against a System only when there is one: at Context creation.
    Benzenes b = fourBenzenes();
    std::unique_ptr<Integrator> outOfRange = fromXml(documentWithBodies({{"0", "48"}}));
    string message = messageOf([&] { Context context(b.system, *outOfRange, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("only 48 particles")) << message;
    std::unique_ptr<Integrator> shared = fromXml(documentWithBodies({{"0", "1"}, {"1", "2"}}));
    message = messageOf([&] { Context context(b.system, *shared, platform("Reference")); });
    EXPECT_NE(string::npos, message.find("Particle 1 is listed in rigid bodies 0 and 1")) << message;
}

TEST(Serialization, RefusesTruncatedDocuments) {
    Benzenes b = fourBenzenes();
    string xml = toXml(*configured<MRattleIntegrator>(b));
    // OpenMM's XML reader accepts missing closing tags, so a document cut inside the body
    // list reads as a well-formed document with fewer <Body> or <Particle> elements. Each
    // such document (every particle, then every body, dropped from the end) must be
    // refused through the count and size attributes, never read as fewer bodies.
    // (Cutting the raw text instead makes OpenMM 7.7's reader, irrXML, read past the end
    // of its buffer, which can crash before any proxy is called: that is outside the
    // plugin's reach, and Python's XmlSerializer hook checks well-formedness first.)
    const string closing = "</Body>";
    int tried = 0;
    for (size_t cut = xml.rfind("<Particle"); cut != string::npos && cut > xml.find("<RigidBodies");
         cut = xml.rfind("<Particle", cut - 1), tried++) {
        size_t bodyEnd = xml.rfind("<Body", cut);
        string truncated = xml.substr(0, cut) + closing + "</RigidBodies></Integrator>";
        if (bodyEnd == string::npos)
            continue;
        std::stringstream stream(truncated);
        EXPECT_THROW(XmlSerializer::deserialize<Integrator>(stream), OpenMMException) << "cut at " << cut;
    }
    for (size_t cut = xml.rfind("<Body"); cut != string::npos && cut > xml.find("<RigidBodies");
         cut = xml.rfind("<Body", cut - 1), tried++) {
        std::stringstream stream(xml.substr(0, cut) + "</RigidBodies></Integrator>");
        EXPECT_THROW(XmlSerializer::deserialize<Integrator>(stream), OpenMMException) << "cut at " << cut;
    }
    EXPECT_GT(tried, 40);
    expectRefused("<Integrator type=\"NoSuchIntegrator\" version=\"1\"/>", {"NoSuchIntegrator"});
}
