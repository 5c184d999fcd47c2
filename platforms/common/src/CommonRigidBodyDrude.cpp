/*
 * CommonRigidBodyState: the Drude integrators' phases (kernels/drude.cc), as
 * ReferenceRigidBodyDrude.cpp on the host: the noise split between each Drude group's rigid
 * motion (each Drude particle at its core) and its Drude particles' motion relative to their cores, the hard wall, the kinetic energy of the
 * relative motion and the scaling of the two parts by two factors. One work item per Drude
 * group (a body with the Drude particles of its cores, or a free core with its own) and per
 * atom in no group; a work group for a group of more than LargeBodyAtoms particles with a body.
 */
#include "CommonRigidBodyState.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void CommonRigidBodyState::setDrudeGroups(const DrudeGroups& groups) {
    vector<int> groupStarts = {0}, rotates, pairStarts = {0}, large;
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
        if (group.rotates && group.particles.size() > LargeBodyAtoms)
            large.push_back(rotates.size() - 1);
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
    numLargeDrudeGroups = large.size();
    large.resize(std::max<size_t>(1, large.size()), 0);
    largeDrudeGroups.initialize<int>(cc, large.size(), "mrattleLargeDrudeGroups");
    largeDrudeGroups.upload(large);
    initializeMixedArray(largeDrudeRelative, vector<double>(large.size(), 0.0), "mrattleLargeDrudeRelative");
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
    drudeNoiseLarge = stepProgram->createKernel("drudeNoiseLargeGroups");
    drudeHardWallLarge = stepProgram->createKernel("drudeHardWallLargeGroups");
    drudeRelativeEnergyLarge = stepProgram->createKernel("drudeRelativeEnergiesLargeGroups");
    drudeScaleLarge = stepProgram->createKernel("scaleDrudeVelocitiesLargeGroups");
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
    // Each *Large kernel takes its small one's arguments (the wall's: the same after the first)
    // and the large groups' list last.
    auto addLargeGroups = [&](Arguments& arguments) {
        arguments.add(largeDrudeGroups);
        arguments.add(numLargeDrudeGroups);
    };
    for (ComputeKernel* kernel : {&drudeNoise, &drudeNoiseLarge}) {
        Arguments noise = integratorArguments(*kernel);
        addDrudeGroupArguments(noise);
        noise.add(drudeNoiseField);
        drudeNoiseArguments = noise.addMixed(1.0);
        noise.addMixed(0.0);
        noise.addMixed(1.0);
        noise.addMixed(0.0);
        noise.add(random);
        drudeNoiseRandomIndex = noise.add(0u);
        if (kernel == &drudeNoiseLarge)
            addLargeGroups(noise);
    }

    for (ComputeKernel* kernel : {&drudeHardWall, &drudeHardWallLarge}) {
        const bool large = kernel == &drudeHardWallLarge;
        Arguments wall = integratorArguments(*kernel);
        if (!large) {
            wall.add(numDrudeGroupsOnDevice);
            wall.add(drudeGroupStart);
        }
        wall.add(drudePairStart);
        wall.add(drudePairAtoms);
        if (!large)
            wall.add(drudeGroupRotates);
        wall.add(drudeFailedPair);
        wall.add(cc.getPosq());
        wall.add(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
        wall.add(cc.getVelm());
        (large ? drudeWallLargeArguments : drudeWallArguments) = wall.addMixed(0.0);
        wall.addMixed(0.0);
        wall.addMixed(0.0);
        if (large)
            addLargeGroups(wall);
    }

    Arguments relative = integratorArguments(drudeRelativeEnergy);
    addDrudeGroupArguments(relative);
    relative.add(drudeRelative);
    relative.add(drudeRelativeCountArray);
    relative.add(largeDrudeRelative);
    relative.add(numLargeDrudeGroups);
    Arguments largeRelative = integratorArguments(drudeRelativeEnergyLarge);
    addDrudeGroupArguments(largeRelative);
    largeRelative.add(largeDrudeRelative);
    addLargeGroups(largeRelative);

    for (ComputeKernel* kernel : {&drudeScale, &drudeScaleLarge}) {
        Arguments scale = integratorArguments(*kernel);
        addDrudeGroupArguments(scale);
        if (kernel == &drudeScaleLarge)
            addLargeGroups(scale);
    }
}

void CommonRigidBodyState::launchOnLargeDrudeGroups(ComputeKernel& kernel) {
    if (numLargeDrudeGroups > 0)
        launch(kernel, numLargeDrudeGroups * LargeBodyThreads, LargeBodyThreads);
}

void CommonRigidBodyState::addDrudeNoise(double friction, double temperature, double drudeFriction,
                                         double drudeTemperature, double h) {
    const double a = std::exp(-friction * h), aDrude = std::exp(-drudeFriction * h);
    const double scale = std::sqrt((1 - a * a) * BOLTZ * temperature);
    const double drudeScaleValue = std::sqrt((1 - aDrude * aDrude) * BOLTZ * drudeTemperature);
    // The large groups' kernel only where there are any: setting arguments costs the host time.
    vector<ComputeKernel*> kernels = {&drudeNoise};
    if (numLargeDrudeGroups > 0)
        kernels.push_back(&drudeNoiseLarge);
    for (ComputeKernel* kernel : kernels) {
        setMixedArg(*kernel, drudeNoiseArguments, a);
        setMixedArg(*kernel, drudeNoiseArguments + 1, scale);
        setMixedArg(*kernel, drudeNoiseArguments + 2, aDrude);
        setMixedArg(*kernel, drudeNoiseArguments + 3, drudeScaleValue);
    }
    flush();  // the random numbers of this launch after those of the queued phases
    if (scale != 0 || drudeScaleValue != 0) {
        const unsigned int randomIndex = cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms());
        for (ComputeKernel* kernel : kernels)
            (*kernel)->setArg(drudeNoiseRandomIndex, randomIndex);
    }
    const int items = numDrudeGroupsOnDevice + numUngrouped;
    if (items > 0)
        launch(drudeNoise, items);
    launchOnLargeDrudeGroups(drudeNoiseLarge);
}

void CommonRigidBodyState::bounceDrudes(double maxDistance, double drudeTemperature, double h) {
    if (maxDistance <= 0 || numDrudeGroupsOnDevice == 0)
        return;
    drudeWallDistance = maxDistance;
    auto setWall = [&](ComputeKernel& kernel, int first) {
        setMixedArg(kernel, first, maxDistance);
        setMixedArg(kernel, first + 1, BOLTZ * drudeTemperature);
        setMixedArg(kernel, first + 2, h);
    };
    setWall(drudeHardWall, drudeWallArguments);
    if (numLargeDrudeGroups > 0)
        setWall(drudeHardWallLarge, drudeWallLargeArguments);
    launch(drudeHardWall, numDrudeGroupsOnDevice);
    launchOnLargeDrudeGroups(drudeHardWallLarge);
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
    launchOnLargeDrudeGroups(drudeRelativeEnergyLarge);  // read by the small groups' sums
    if (numDrudeGroupsOnDevice > 0)
        launch(drudeRelativeEnergy, numDrudeGroupsOnDevice, ReductionThreads);
}

double CommonRigidBodyState::computeDrudeKineticEnergy() {
    synchronize();  // a step not yet checked may have failed
    if (numDrudeGroupsOnDevice == 0)
        return 0;
    if (!argumentsSet)
        setKernelArguments();
    if (numLargeDrudeGroups > 0)
        drudeRelativeEnergyLarge->execute(numLargeDrudeGroups * LargeBodyThreads, LargeBodyThreads);
    drudeRelativeEnergy->execute(numDrudeGroupsOnDevice, ReductionThreads);
    int count;
    drudeRelativeCountArray.download(&count);
    const vector<double> partials = downloadAsDouble(drudeRelative);
    double twice = 0;
    for (int g = 0; g < count; g++)
        twice += partials[g];
    return 0.5 * twice;
}

void CommonRigidBodyState::scaleDrudeVelocities() {
    const int items = numDrudeGroupsOnDevice + numUngrouped;
    if (items > 0)
        launch(drudeScale, items);
    launchOnLargeDrudeGroups(drudeScaleLarge);
}
