#ifndef MRATTLE_XML_H_
#define MRATTLE_XML_H_

#include "openmm/Integrator.h"
#include "internal/windowsExportMRattle.h"
#include <string>

namespace MRattlePlugin {

/**
 * Read an integrator from XML, as OpenMM::XmlSerializer::deserialize<Integrator> does, but
 * check first that the document is well formed: OpenMM 7.7's XML reader can crash on a
 * document cut inside a start tag, and keeps the last of duplicated attributes. Throws an
 * OpenMMException naming the first problem (an unclosed tag or quote, mismatched or
 * missing end tags, a duplicated attribute, text after the root element, elements nested
 * deeper than MaxXmlDepth) before OpenMM's
 * reader sees the document. The caller owns the result.
 */
OPENMM_EXPORT_MRATTLE OpenMM::Integrator* deserializeIntegratorXml(const std::string& xml);

/**
 * Elements may nest this deep at most: OpenMM's reader recurses once per level and a deep
 * enough document overflows the stack (100,000 levels crash it); the plugin's documents
 * nest 4 deep, OpenMM's own a few more.
 */
constexpr int MaxXmlDepth = 100;

/**
 * The well-formedness check alone (nesting deeper than MaxXmlDepth counts as not well
 * formed): throws an OpenMMException naming the first problem.
 */
OPENMM_EXPORT_MRATTLE void checkWellFormedXml(const std::string& xml);

} // namespace MRattlePlugin

#endif
