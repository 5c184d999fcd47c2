#ifndef MRATTLE_TEST_SUPPORT_H_
#define MRATTLE_TEST_SUPPORT_H_

#include "MRattleIntegrator.h"
#include "OpenMM.h"
#include <memory>
#include <string>
#include <vector>

namespace MRattleTest {

/** Load OpenMM's plugins (for the CPU platform) and register this plugin's kernels. Idempotent. */
void loadPlugins();
OpenMM::Platform& platform(const std::string& name);

/** A rigid molecule: site positions (nm) about its centre, masses, LJ and charges. */
struct Molecule {
    std::vector<OpenMM::Vec3> sites;
    std::vector<double> masses, charges, sigmas, epsilons;
    /** Pairs joined by bonds (these make OpenMM see one molecule). */
    std::vector<std::pair<int, int> > bonds;
};

/** Benzene: 12 sites, C-C 0.1397 nm, C-H 0.1084 nm, OPLS-AA-like C and H. Planar. */
Molecule benzene();

/** Largest change of any intra-body distance between two configurations. */
double maxDistanceChange(const std::vector<OpenMM::Vec3>& a, const std::vector<OpenMM::Vec3>& b,
                         const std::vector<std::vector<int> >& bodies);

} // namespace MRattleTest

#endif
