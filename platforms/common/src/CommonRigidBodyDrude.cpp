/*
 * CommonRigidBodyState: the Drude integrators' phases (kernels/drude.cc), as
 * ReferenceRigidBodyDrude.cpp on the host: the noise split between each Drude group's rigid
 * motion (each Drude particle at its core) and its Drude particles' motion relative to their cores, the hard wall, the kinetic energy of the
 * relative motion and the scaling of the two parts by two factors. One work item per Drude
 * group (a body with the Drude particles of its cores, or a free core with its own) and per
 * atom in no group.
 */
#include "CommonRigidBodyState.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void CommonRigidBodyState::setDrudeGroups(const DrudeGroups& groups) {
    vector<int> groupStarts = {0}, rotates, pairStarts = {0};
    vector<bool> grouped(cc.getNumAtoms(), false);
    // A group's Drude particles are its last particles, in the DrudeForce's order (DrudeGroups).
    std::map<int, int> coreOf;
    for (const auto& pair : groups.getPairs())
        coreOf[pair.first] = pair.second;
    for (const DrudeGroups::Group& group : groups.getGroups()) {
        systemDrudeGroupPlaces.insert(systemDrudeGroupPlaces.end(), group.places.begin(), group.places.end());
        for (int atom : group.particles) {
            systemDrudeGroupAtoms.push_back(atom);
            grouped[atom] = true;
            if (coreOf.count(atom)) {
                systemDrudePairAtoms.push_back(atom);
                systemDrudePairAtoms.push_back(coreOf[atom]);
            }
        }
        groupStarts.push_back(systemDrudeGroupAtoms.size());
        pairStarts.push_back(systemDrudePairAtoms.size() / 2);
        rotates.push_back(group.rotates ? 1 : 0);
    }
    for (int atom = 0; atom < cc.getNumAtoms(); atom++)
        if (!grouped[atom])
            systemUngroupedAtoms.push_back(atom);
    numDrudeGroupsOnDevice = groups.getGroups().size();
    numUngrouped = systemUngroupedAtoms.size();
    drudeGroupStart.initialize<int>(cc, groupStarts.size(), "mrattleDrudeGroupStart");
    drudeGroupStart.upload(groupStarts);
    drudeGroupAtoms.initialize<int>(cc, std::max<size_t>(1, systemDrudeGroupAtoms.size()), "mrattleDrudeGroupAtoms");
    drudeGroupPlaces.initialize<int>(cc, std::max<size_t>(1, systemDrudeGroupPlaces.size()), "mrattleDrudeGroupPlaces");
    rotates.resize(std::max<size_t>(1, rotates.size()), 0);
    drudeGroupRotates.initialize<int>(cc, rotates.size(), "mrattleDrudeGroupRotates");
    drudeGroupRotates.upload(rotates);
    ungroupedAtoms.initialize<int>(cc, std::max<size_t>(1, systemUngroupedAtoms.size()), "mrattleUngroupedAtoms");
    drudePairStart.initialize<int>(cc, pairStarts.size(), "mrattleDrudePairStart");
    drudePairStart.upload(pairStarts);
    drudePairAtoms.initialize<int>(cc, std::max<size_t>(2, systemDrudePairAtoms.size()), "mrattleDrudePairAtoms");
    drudeFailedPair.initialize<int>(cc, 1, "mrattleDrudeFailedPair");
    drudeFailedPair.upload(vector<int>(1, 0));
    drudeNoiseField.initialize(cc, cc.getPaddedNumAtoms(), doubleMixed() ? sizeof(mm_double4) : sizeof(mm_float4),
                               "mrattleDrudeNoise");
    initializeMixedArray(drudeRelative, vector<double>(cc.getNumThreadBlocks(), 0.0), "mrattleDrudeRelative");
    drudeRelativeCountArray.initialize<int>(cc, 1, "mrattleDrudeRelativeCount");
    drudeRelativeCountArray.upload(vector<int>(1, 0));
    mapAtoms();
    drudeNoise = stepProgram->createKernel("drudeNoise");
    drudeHardWall = stepProgram->createKernel("drudeHardWall");
    drudeRelativeEnergy = stepProgram->createKernel("drudeRelativeEnergies");
    drudeScale = stepProgram->createKernel("scaleDrudeVelocities");
    hasDrudeGroups = true;
}

void CommonRigidBodyState::addDrudeGroupArguments(Arguments& arguments) {
    arguments.add(numDrudeGroupsOnDevice);
    arguments.add(drudeGroupStart);
    arguments.add(drudeGroupAtoms);
    arguments.add(drudeGroupPlaces);
    arguments.add(drudeGroupRotates);
    arguments.add(numUngrouped);
    arguments.add(ungroupedAtoms);
    arguments.add(cc.getPosq());
    arguments.add(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    arguments.add(cc.getVelm());
}

void CommonRigidBodyState::setDrudeKernelArguments() {
    // OpenMM's device random numbers where something made them; else any float4-sized array, unread.
    ArrayInterface& random = hasRandomNumbers ? cc.getIntegrationUtilities().getRandom()
                                              : static_cast<ArrayInterface&>(velmBackup);
    Arguments noise = integratorArguments(drudeNoise);
    addDrudeGroupArguments(noise);
    noise.add(drudeNoiseField);
    drudeNoiseArguments = noise.addMixed(1.0);
    noise.addMixed(0.0);
    noise.addMixed(1.0);
    noise.addMixed(0.0);
    noise.add(random);
    drudeNoiseRandomIndex = noise.add(0u);

    Arguments wall = integratorArguments(drudeHardWall);
    wall.add(numDrudeGroupsOnDevice);
    wall.add(drudePairStart);
    wall.add(drudePairAtoms);
    wall.add(drudeGroupRotates);
    wall.add(drudeFailedPair);
    wall.add(cc.getPosq());
    wall.add(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    wall.add(cc.getVelm());
    drudeWallArguments = wall.addMixed(0.0);
    wall.addMixed(0.0);
    wall.addMixed(0.0);

    Arguments relative = integratorArguments(drudeRelativeEnergy);
    addDrudeGroupArguments(relative);
    relative.add(drudeRelative);
    relative.add(drudeRelativeCountArray);

    Arguments scale = integratorArguments(drudeScale);
    addDrudeGroupArguments(scale);
}

void CommonRigidBodyState::addDrudeNoise(double friction, double temperature, double drudeFriction,
                                         double drudeTemperature, double h) {
    const double a = std::exp(-friction * h), aDrude = std::exp(-drudeFriction * h);
    const double scale = std::sqrt((1 - a * a) * BOLTZ * temperature);
    const double drudeScaleValue = std::sqrt((1 - aDrude * aDrude) * BOLTZ * drudeTemperature);
    setMixedArg(drudeNoise, drudeNoiseArguments, a);
    setMixedArg(drudeNoise, drudeNoiseArguments + 1, scale);
    setMixedArg(drudeNoise, drudeNoiseArguments + 2, aDrude);
    setMixedArg(drudeNoise, drudeNoiseArguments + 3, drudeScaleValue);
    flush();  // the random numbers of this launch after those of the queued phases
    if (scale != 0 || drudeScaleValue != 0)
        drudeNoise->setArg(drudeNoiseRandomIndex,
                           (unsigned int) cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms()));
    const int items = numDrudeGroupsOnDevice + numUngrouped;
    if (items > 0)
        launch(drudeNoise, items);
}

void CommonRigidBodyState::bounceDrudes(double maxDistance, double drudeTemperature, double h) {
    if (maxDistance <= 0 || numDrudeGroupsOnDevice == 0)
        return;
    drudeWallDistance = maxDistance;
    setMixedArg(drudeHardWall, drudeWallArguments, maxDistance);
    setMixedArg(drudeHardWall, drudeWallArguments + 1, BOLTZ * drudeTemperature);
    setMixedArg(drudeHardWall, drudeWallArguments + 2, h);
    launch(drudeHardWall, numDrudeGroupsOnDevice);
}

std::string CommonRigidBodyState::takeDrudeWallFailure() {
    if (!hasDrudeGroups)
        return "";
    int failedPair;
    drudeFailedPair.download(&failedPair);   // only where a failure was found: no read in a step
    if (failedPair <= 0 || 2 * failedPair > (int) systemDrudePairAtoms.size())
        return "";
    drudeFailedPair.upload(vector<int>(1, 0));
    const int drude = systemDrudePairAtoms[2 * (failedPair - 1)], core = systemDrudePairAtoms[2 * failedPair - 1];
    return "Drude particle " + std::to_string(drude) + " went beyond twice the hard wall's maxDrudeDistance (" +
           std::to_string(drudeWallDistance) + " nm) from its core " + std::to_string(core);
}

void CommonRigidBodyState::sumDrudeKineticEnergies() {
    sumKineticEnergy();
    if (numDrudeGroupsOnDevice > 0)
        launch(drudeRelativeEnergy, numDrudeGroupsOnDevice, ReductionThreads);
}

void CommonRigidBodyState::scaleDrudeVelocities() {
    const int items = numDrudeGroupsOnDevice + numUngrouped;
    if (items > 0)
        launch(drudeScale, items);
}
