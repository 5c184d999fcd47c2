"""A State's integrator parameters (getState(getIntegratorParameters=True), setState) and
OpenMM 8.6's ReplicaExchangeSampler loop written with the OpenMM 7.7/8.1.2 API (issue 43).

The loop: one Context; each iteration, for each replica, set its State (with the
integrator's parameters), rescale its velocities by sqrt(T_new/T_old) if its temperature
changed, set the integrator's temperature, step, and take its State back; then exchange
temperatures between random pairs (Metropolis). Each replica's run must be the one it has
alone in a Context of its own: bit for bit with the Nose-Hoover chain, whose variables the
State carries. A stochastic integrator's random stream is the Context's (a State does not
carry it, so that replicas never draw the same numbers): there the test checks that every
replica gets its own heat bath back, exactly, at each turn.
"""
import math
import pickle
import random

import numpy as np
import openmm
import pytest
from openmm import app, unit

import mrattle
from mrattle.reporters import DRUDE_INTEGRATORS, HEAT_BATH_INTEGRATORS

# The thermostats constructed as (temperature, collisionFrequency, stepSize): the Drude ones
# (OpenMM's Drude integrators' constructors) have tests of their own.
HEAT_BATH_INTEGRATORS = [cls for cls in HEAT_BATH_INTEGRATORS if cls not in DRUDE_INTEGRATORS]

THERMOSTATS = [mrattle.MRattleLangevinIntegrator] + list(HEAT_BATH_INTEGRATORS)
STEP = 0.002


def waterModel():
    """64 rigid TIP3P waters, cut off at 0.6 nm (cheap on Reference)."""
    return mrattle.models.waterBox(64, cutoff=0.6*unit.nanometers, nonbondedMethod=app.CutoffPeriodic)


def makeIntegrator(cls, temperature=300):
    if cls is mrattle.MRattleLangevinIntegrator:
        integrator = cls(temperature, 1.0, STEP)
    else:
        integrator = cls(temperature, 10.0, STEP)
    if hasattr(integrator, 'setRandomNumberSeed'):
        integrator.setRandomNumberSeed(5)
    return integrator


def heatBath(integrator):
    return integrator.computeHeatBathEnergy().value_in_unit(unit.kilojoules_per_mole)


def withParameters(context):
    return context.getState(getPositions=True, getVelocities=True, getParameters=True, getIntegratorParameters=True)


@pytest.mark.parametrize('cls', HEAT_BATH_INTEGRATORS, ids=lambda c: c.__name__)
def test_a_state_restores_the_heat_bath_also_pickled(platform, cls):
    model = waterModel()
    integrator = makeIntegrator(cls)
    context = openmm.Context(model.system, integrator, platform)
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(200*unit.kelvin, 3)
    integrator.step(20)
    state = withParameters(context)
    saved = heatBath(integrator)
    pickled = pickle.loads(pickle.dumps(state))
    integrator.step(20)
    assert heatBath(integrator) != saved
    for each in (state, pickled):
        context.setState(each)
        assert heatBath(integrator) == saved

    # Parameters of another class are refused, naming both.
    other = [c for c in HEAT_BATH_INTEGRATORS if c is not cls][0]
    otherIntegrator = makeIntegrator(other)
    otherContext = openmm.Context(model.system, otherIntegrator, openmm.Platform.getPlatformByName('Reference'))
    otherContext.setPositions(model.positions)
    with pytest.raises(Exception, match='are those of a %s, not of a %s' % (other.__name__, cls.__name__)):
        context.setState(withParameters(otherContext))


def test_states_with_or_without_parameters_set_into_integrators_without_variables():
    model = waterModel()
    for cls in (mrattle.MRattleIntegrator, mrattle.RigidSplittingIntegrator, mrattle.MRattleLangevinIntegrator):
        integrator = cls(300, 1.0, STEP) if cls is mrattle.MRattleLangevinIntegrator else cls(STEP)
        context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
        context.setPositions(model.positions)
        context.setVelocitiesToTemperature(300)
        integrator.step(2)
        verlet = openmm.Context(model.system, openmm.VerletIntegrator(STEP),
                                openmm.Platform.getPlatformByName('Reference'))
        verlet.setPositions(model.positions)
        for state in (withParameters(context), context.getState(getPositions=True, getVelocities=True),
                      withParameters(verlet)):
            context.setState(state)
            # Taken as given: a State's bodies are rigid (the Verlet Context's positions are the
            # model's, its velocities zero), so positions and velocities are kept bit for bit.
            now = context.getState(getPositions=True, getVelocities=True)
            for get in ('getPositions', 'getVelocities'):
                assert np.array_equal(getattr(now, get)(asNumpy=True), getattr(state, get)(asNumpy=True)), (cls, get)
            assert now.getStepCount() == state.getStepCount()
            integrator.step(2)
            assert context.getState().getStepCount() == state.getStepCount() + 2
            assert np.all(np.isfinite(context.getState(getPositions=True).getPositions(asNumpy=True)))


def runReplicaExchange(cls, temperatures, iterations, stepsPerIteration, seed):
    """OpenMM 8.6's ReplicaExchangeSampler loop (simulate(), simulateReplica(), exchangeReplicas())
    with temperatures, without reinitialising velocities. Returns the initial State, each
    replica's final State and heat bath, each replica's history [(temperature, scale)] and the
    number of accepted exchanges."""
    model = waterModel()
    integrator = makeIntegrator(cls, temperatures[0])
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(temperatures[0]*unit.kelvin, 11)
    n = len(temperatures)
    kT = [(unit.MOLAR_GAS_CONSTANT_R*t*unit.kelvin).value_in_unit(unit.kilojoules_per_mole) for t in temperatures]
    initial = withParameters(context)
    conformation = [initial]*n
    baths = [heatBath(integrator) if cls in HEAT_BATH_INTEGRATORS else 0.0]*n
    stateIndex, previous = list(range(n)), list(range(n))
    history = [[] for _ in range(n)]
    accepted = 0
    generator = random.Random(seed)
    for _ in range(iterations):
        energies = []
        for i in range(n):
            context.setState(conformation[i])
            if cls in HEAT_BATH_INTEGRATORS:  # at the temperature its bath was read at (the chain's energy depends on it)
                integrator.setTemperature(temperatures[previous[i]]*unit.kelvin)
                assert heatBath(integrator) == baths[i], 'replica %d did not get its heat bath back' % i
            scale = None
            if previous[i] != stateIndex[i]:
                scale = math.sqrt(kT[stateIndex[i]]/kT[previous[i]])
                context.setVelocities(conformation[i].getVelocities(asNumpy=True)*scale)
            previous[i] = stateIndex[i]
            integrator.setTemperature(temperatures[stateIndex[i]]*unit.kelvin)
            integrator.step(stepsPerIteration)
            history[i].append((temperatures[stateIndex[i]], scale))
            conformation[i] = withParameters(context)
            if cls in HEAT_BATH_INTEGRATORS:
                baths[i] = heatBath(integrator)
            energies.append(context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(
                unit.kilojoules_per_mole))
        for _ in range(n*n):
            i, j = generator.sample(range(n), 2)
            si, sj = stateIndex[i], stateIndex[j]
            exponent = (energies[i] - energies[j])/kT[si] + (energies[j] - energies[i])/kT[sj]
            if generator.random() <= min(1.0, math.exp(min(exponent, 0.0))):
                stateIndex[i], stateIndex[j] = sj, si
                accepted += 1
    return model, initial, conformation, baths, history, accepted


def runAlone(cls, model, initial, history, stepsPerIteration):
    """One replica's run in a Context of its own, with the same temperatures and rescalings: its final State and heat bath."""
    integrator = makeIntegrator(cls, history[0][0])
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setState(initial)
    for temperature, scale in history:
        if scale is not None:
            context.setVelocities(context.getState(getVelocities=True).getVelocities(asNumpy=True)*scale)
        integrator.setTemperature(temperature*unit.kelvin)
        integrator.step(stepsPerIteration)
    return context.getState(getPositions=True, getVelocities=True), heatBath(integrator)


@pytest.mark.parametrize('cls', THERMOSTATS, ids=lambda c: c.__name__)
def test_openmm_8_6_replica_exchange_loop_keeps_each_replicas_thermostat(cls):
    temperatures = [300, 320, 340, 360]
    stepsPerIteration = 20
    model, initial, final, baths, history, accepted = runReplicaExchange(cls, temperatures, 6, stepsPerIteration, 7)
    print('%s: %d exchanges accepted of %d' % (cls.__name__, accepted, 6*len(temperatures)**2))
    assert accepted > 0, 'no exchange: the rescaling path was not exercised'
    assert any(scale is not None for replica in history for _, scale in replica)
    if cls in HEAT_BATH_INTEGRATORS:
        assert len(set(baths)) == len(baths), 'the replicas\' heat baths are not their own'
    if cls is not mrattle.MRattleNoseHooverIntegrator:
        return  # the random stream is the Context's: a replica's run is not its run alone
    for i, replica in enumerate(history):
        alone, aloneBath = runAlone(cls, model, initial, replica, stepsPerIteration)
        assert np.array_equal(alone.getPositions(asNumpy=True), final[i].getPositions(asNumpy=True)), i
        assert np.array_equal(alone.getVelocities(asNumpy=True), final[i].getVelocities(asNumpy=True)), i
        assert aloneBath == baths[i], i
