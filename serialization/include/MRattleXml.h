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
 * missing end tags, a duplicated attribute, text after the root element) before OpenMM's
 * reader sees the document. The caller owns the result.
 */
OPENMM_EXPORT_MRATTLE OpenMM::Integrator* deserializeIntegratorXml(const std::string& xml);

/** The well-formedness check alone: throws an OpenMMException naming the first problem. */
OPENMM_EXPORT_MRATTLE void checkWellFormedXml(const std::string& xml);

} // namespace MRattlePlugin

#endif
