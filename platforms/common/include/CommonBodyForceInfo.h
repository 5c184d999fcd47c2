#ifndef MRATTLE_COMMON_BODY_FORCE_INFO_H_
#define MRATTLE_COMMON_BODY_FORCE_INFO_H_

#include "openmm/common/ComputeForceInfo.h"
#include <vector>

namespace MRattlePlugin {

/**
 * The rigid bodies as OpenMM's device platforms see particle groups: joined like the atoms
 * of a bond, so that OpenMM's reordering (which wraps each molecule into the periodic box on
 * its own) keeps a body made of several molecules whole. Without it a body straddling the
 * box's edge was torn apart silently by the first reordering (issue 31). Registered with
 * ComputeContext::addForce before the first reordering, which builds the molecules.
 */
class CommonBodyForceInfo : public OpenMM::ComputeForceInfo {
public:
    explicit CommonBodyForceInfo(const std::vector<std::vector<int> >& bodies) : bodies(bodies) {
    }
    int getNumParticleGroups() override {
        return bodies.size();
    }
    void getParticlesInGroup(int index, std::vector<int>& particles) override {
        particles = bodies[index];
    }
    /** Bodies of the same size may be swapped (OpenMM asks every force too); the kernels map atoms anew after a reorder. */
    bool areGroupsIdentical(int group1, int group2) override {
        return bodies[group1].size() == bodies[group2].size();
    }

private:
    std::vector<std::vector<int> > bodies;
};

} // namespace MRattlePlugin

#endif
