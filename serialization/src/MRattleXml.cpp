#include "MRattleXml.h"
#include "openmm/OpenMMException.h"
#include "openmm/serialization/XmlSerializer.h"
#include <cctype>
#include <set>
#include <sstream>
#include <vector>

using namespace OpenMM;
using std::string;

namespace {

void problem(const string& what, size_t offset) {
    throw OpenMMException("The XML document is not well formed: " + what + " (at character " + std::to_string(offset) +
                          ")");
}

bool isNameCharacter(char c) {
    return std::isalnum((unsigned char) c) || c == '_' || c == '-' || c == '.' || c == ':';
}

} // namespace

void MRattlePlugin::checkWellFormedXml(const string& xml) {
    std::vector<string> open;  // element names not yet closed
    bool sawRoot = false;
    size_t i = 0;
    const size_t n = xml.size();
    while (i < n) {
        if (xml[i] != '<') {
            if (!std::isspace((unsigned char) xml[i]) && open.empty())
                problem(sawRoot ? "text after the root element" : "text before the root element", i);
            i++;
            continue;
        }
        const size_t start = i;
        if (xml.compare(i, 4, "<!--") == 0) {
            size_t end = xml.find("-->", i + 4);
            if (end == string::npos)
                problem("a comment is not closed", start);
            i = end + 3;
            continue;
        }
        if (xml.compare(i, 2, "<?") == 0) {
            size_t end = xml.find("?>", i + 2);
            if (end == string::npos)
                problem("a processing instruction is not closed", start);
            i = end + 2;
            continue;
        }
        const bool closing = (i + 1 < n && xml[i + 1] == '/');
        i += closing ? 2 : 1;
        size_t nameStart = i;
        while (i < n && isNameCharacter(xml[i]))
            i++;
        const string name = xml.substr(nameStart, i - nameStart);
        if (name.empty())
            problem("a tag has no element name", start);
        std::set<string> attributes;
        bool selfClosing = false;
        while (true) {
            while (i < n && std::isspace((unsigned char) xml[i]))
                i++;
            if (i >= n)
                problem("the tag <" + name + " is not closed", start);
            if (xml[i] == '>') {
                i++;
                break;
            }
            if (xml[i] == '/' && i + 1 < n && xml[i + 1] == '>' && !closing) {
                selfClosing = true;
                i += 2;
                break;
            }
            if (closing)
                problem("the end tag </" + name + "> has more than a name", start);
            size_t attributeStart = i;
            while (i < n && isNameCharacter(xml[i]))
                i++;
            const string attribute = xml.substr(attributeStart, i - attributeStart);
            if (attribute.empty())
                problem("unexpected character '" + string(1, xml[i]) + "' in the tag <" + name + ">", i);
            if (!attributes.insert(attribute).second)
                problem("the attribute '" + attribute + "' appears twice in <" + name + ">", attributeStart);
            while (i < n && std::isspace((unsigned char) xml[i]))
                i++;
            if (i >= n || xml[i] != '=')
                problem("the attribute '" + attribute + "' of <" + name + "> has no value", attributeStart);
            i++;
            while (i < n && std::isspace((unsigned char) xml[i]))
                i++;
            if (i >= n || (xml[i] != '"' && xml[i] != '\''))
                problem("the value of the attribute '" + attribute + "' of <" + name + "> is not quoted", i);
            const char quote = xml[i];
            size_t end = xml.find(quote, i + 1);
            if (end == string::npos)
                problem("the value of the attribute '" + attribute + "' of <" + name + "> is not closed", i);
            if (xml.find('<', i + 1) < end)
                problem("'<' inside the value of the attribute '" + attribute + "' of <" + name + ">", i);
            i = end + 1;
        }
        if (closing) {
            if (open.empty() || open.back() != name)
                problem("the end tag </" + name + "> does not match " +
                            (open.empty() ? string("any open element") : "<" + open.back() + ">"), start);
            open.pop_back();
        }
        else {
            if (open.empty() && sawRoot)
                problem("a second root element <" + name + ">", start);
            sawRoot = true;
            if ((int) open.size() >= MaxXmlDepth)
                problem("elements nest deeper than " + std::to_string(MaxXmlDepth) + " levels", start);
            if (!selfClosing)
                open.push_back(name);
        }
    }
    if (!sawRoot)
        problem("there is no root element", n);
    if (!open.empty())
        problem("the element <" + open.back() + "> is not closed", n);
}

Integrator* MRattlePlugin::deserializeIntegratorXml(const string& xml) {
    checkWellFormedXml(xml);
    std::istringstream stream(xml);
    return XmlSerializer::deserialize<Integrator>(stream);
}
