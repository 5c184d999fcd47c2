"""Replica exchange of 64 rigid TIP3P waters with openmmtools 0.26.0 and mrattle.mcmc's moves:
the runs of test_openmmtools.py, which also runs this file as a script (a resumed run in a
new process, the run under mpirun).

openmmtools and mpiplus are imported from ../shared/deps beside the repository (their
folders there; docs/usage.md, "Replica exchange") when they are not installed.

As a script (prints one JSON line on rank 0):
  rex.py temperature MOVE ITERATIONS STORAGE   a new run (under mpirun: replicas over ranks)
  rex.py extend ITERATIONS STORAGE...          resume each stored run and extend it
"""
import json
import math
import pathlib
import sys
import time

REPOSITORY = pathlib.Path(__file__).resolve().parents[3]
DEPENDENCIES = REPOSITORY.parent / 'shared' / 'deps'
FOLDERS = ('openmmtools-0.26.0', 'mpiplus-0.0.2')

#: The states of the temperature exchange (K), and each move's coupling (1/ps).
TEMPERATURES = [300.0, 320.0, 340.0, 360.0]
COUPLING = {'MRattleLangevinDynamicsMove': 10.0, 'MRattleNoseHooverDynamicsMove': 20.0,
            'MRattleBussiDynamicsMove': 20.0}
STEPS_PER_ITERATION = 100  # of 2 fs: 0.2 ps, several thermostat times (a swapped replica's velocities relax)


def addDependencies():
    """Put ../shared/deps's openmmtools and mpiplus on sys.path (if there)."""
    for folder in FOLDERS:
        path = DEPENDENCIES / folder
        if path.is_dir() and str(path) not in sys.path:
            sys.path.insert(0, str(path))


def importProblem():
    """Why openmmtools' replica exchange cannot run here, or None."""
    addDependencies()
    try:
        import openmmtools.multistate  # noqa: F401 (pulls in netCDF4, mdtraj, pymbar, numba, mpiplus)
        import mrattle.mcmc  # noqa: F401
    except Exception as error:  # ImportError, or a package that fails as it loads
        return ('openmmtools 0.26.0 cannot be imported (%s: %s): it is looked for in %s, with Debian\'s '
                'python3-netcdf4, python3-mdtraj, python3-pymbar, python3-numba (scripts/install-deps.sh)'
                % (type(error).__name__, error, DEPENDENCIES))
    return None


def seedEverything(seed):
    """numpy's and numba's generators (openmmtools mixes replicas with numba's)."""
    import numba
    import numpy as np

    @numba.njit
    def seedNumba(value):
        np.random.seed(value)

    np.random.seed(seed)
    seedNumba(seed)


def water():
    """64 rigid TIP3P waters cut off at 0.6 nm (mrattle.models.waterBox), and their bodies."""
    import mrattle
    from openmm import app, unit
    model = mrattle.models.waterBox(64, cutoff=0.6*unit.nanometers, nonbondedMethod=app.CutoffPeriodic)
    return model, [[3*i, 3*i + 1, 3*i + 2] for i in range(64)]


def useCPU(sampler):
    """One CPU thread for the sampler's and the energies' Contexts, each its own cache."""
    import openmm
    from openmmtools import cache
    cpu = openmm.Platform.getPlatformByName('CPU')
    sampler.sampler_context_cache = cache.ContextCache(platform=cpu, platform_properties={'Threads': '1'})
    sampler.energy_context_cache = cache.ContextCache(platform=cpu, platform_properties={'Threads': '1'})


def rigidVelocities(model, temperature, seed):
    """Rigid-body velocities at the temperature (a throwaway Context)."""
    import mrattle
    import openmm
    integrator = mrattle.MRattleIntegrator(0.002)
    context = openmm.Context(model.system, integrator, openmm.Platform.getPlatformByName('Reference'))
    context.setPositions(model.positions)
    context.setVelocitiesToTemperature(temperature, seed)
    return context.getState(getVelocities=True).getVelocities(asNumpy=True), integrator.getNumDegreesOfFreedom()


class Record:
    """What the tests check, per iteration: each state's kinetic temperature, the swaps, rigidity."""

    def __init__(self, numStates):
        self.temperatures = [[] for _ in range(numStates)]
        self.accepted = 0
        self.proposed = 0
        self.neighbourAccepted = [0]*(numStates - 1)
        self.neighbourProposed = [0]*(numStates - 1)
        self.neighbourFractions = [[] for _ in range(numStates - 1)]  # per iteration
        self.rigidity = 0.0
        self.contexts = set()
        self.seconds = 0.0

    def take(self, sampler, masses, dof, shapes, bodies):
        import numpy as np
        from openmm import unit
        boltzmann = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoules_per_mole/unit.kelvin)
        for replica, state in enumerate(sampler._replica_thermodynamic_states):  # those of this propagation
            sampler_state = sampler.sampler_states[replica]
            v = sampler_state.velocities.value_in_unit(unit.nanometers/unit.picoseconds)
            self.temperatures[state].append(float((masses[:, None]*v*v).sum()/(dof*boltzmann)))
            x = sampler_state.positions.value_in_unit(unit.nanometers)
            self.rigidity = max(self.rigidity, float(np.abs(bodyShapes(x, bodies) - shapes).max()))
        accepted, proposed = sampler._n_accepted_matrix, sampler._n_proposed_matrix
        self.accepted += int(accepted.sum())//2  # each swap counts (i, j) and (j, i)
        self.proposed += int(proposed.sum())//2
        for k in range(len(self.neighbourAccepted)):
            self.neighbourAccepted[k] += int(accepted[k, k + 1])
            self.neighbourProposed[k] += int(proposed[k, k + 1])
            self.neighbourFractions[k].append(float(accepted[k, k + 1])/max(int(proposed[k, k + 1]), 1))
        # The sampler's Contexts (an integrator replaced would add one), by the SWIG pointer.
        for key in list(sampler.sampler_context_cache._lru):
            context = sampler.sampler_context_cache._lru[key]
            self.contexts.add((int(context.this), int(context.getIntegrator().this),
                               type(context.getIntegrator()).__name__))

    def summary(self, burnIn):
        """Per state, the mean kinetic temperature, and per neighbour pair, the acceptance
        fraction of an iteration's swap attempts (correlated within an iteration): each with
        its standard error over iterations (blockEstimate; the temperatures after burnIn iterations)."""
        return dict(states=[blockEstimate(series[burnIn:]) for series in self.temperatures],
                    neighbourFractions=[blockEstimate(series) for series in self.neighbourFractions],
                    accepted=self.accepted, proposed=self.proposed, neighbourAccepted=self.neighbourAccepted,
                    neighbourProposed=self.neighbourProposed, rigidity=self.rigidity,
                    contexts=sorted(self.contexts), seconds=self.seconds)


def blockEstimate(series, numBlocks=10):
    """Mean of a series and its standard error: the larger of the estimate from numBlocks
    block means (correlation between samples) and that of independent samples (so a block
    estimate that is low by chance, as one from 10 blocks can be, does not understate it)."""
    n = len(series)
    mean = sum(series)/n
    if n < 2:
        return mean, float('nan')
    numBlocks = min(numBlocks, n)
    length = n//numBlocks
    blocks = [sum(series[b*length:(b + 1)*length])/length for b in range(numBlocks)]
    blockMean = sum(blocks)/numBlocks
    blocked = math.sqrt(sum((b - blockMean)**2 for b in blocks)/numBlocks/(numBlocks - 1))
    independent = math.sqrt(sum((x - mean)**2 for x in series)/(n - 1)/n)
    return mean, max(blocked, independent)


def bodyShapes(x, bodies):
    """Every intra-body distance (O-H, O-H, H-H per water)."""
    import numpy as np
    b = np.array(bodies)
    return np.concatenate([np.linalg.norm(x[b[:, i]] - x[b[:, j]], axis=1) for i, j in ((0, 1), (0, 2), (1, 2))])


def runIterations(sampler, iterations, record, model, bodies, dof):
    import numpy as np
    from openmm import unit
    masses = np.array([model.system.getParticleMass(i).value_in_unit(unit.dalton)
                       for i in range(model.system.getNumParticles())])
    shapes = bodyShapes(np.array(model.positions.value_in_unit(unit.nanometers)), bodies)
    start = time.time()
    for _ in range(iterations):
        sampler.extend(1)
        if record is not None:
            record.take(sampler, masses, dof, shapes, bodies)
    if record is not None:
        record.seconds += time.time() - start


def temperatureExchange(moveName, iterations, storage, seed=1):
    """A new temperature replica exchange of 4 states at 300-360 K: the sampler and its Record."""
    import mpiplus
    import mrattle.mcmc
    from openmm import unit
    from openmmtools import multistate, states
    seedEverything(seed)
    communicator = mpiplus.get_mpicomm()
    streamSeed = seed + 1000*(communicator.rank if communicator else 0)  # each process's Context its own stream
    model, bodies = water()
    velocities, dof = rigidVelocities(model, TEMPERATURES[0], seed)
    thermodynamicStates = [states.ThermodynamicState(model.system, t*unit.kelvin) for t in TEMPERATURES]
    samplerState = states.SamplerState(model.positions, velocities=velocities,
                                       box_vectors=model.system.getDefaultPeriodicBoxVectors())
    move = getattr(mrattle.mcmc, moveName)(timestep=2.0*unit.femtoseconds,
                                           collision_rate=COUPLING[moveName]/unit.picoseconds,
                                           n_steps=STEPS_PER_ITERATION, random_seed=streamSeed)
    sampler = multistate.ReplicaExchangeSampler(mcmc_moves=move, number_of_iterations=iterations)
    reporter = multistate.MultiStateReporter(str(storage), checkpoint_interval=1)
    useCPU(sampler)
    sampler.create(thermodynamicStates, samplerState, reporter)
    record = Record(len(TEMPERATURES))
    runIterations(sampler, iterations, record, model, bodies, dof)
    return sampler, record


def extendStored(storage, iterations):
    """Resume a stored run (as a new process would) and extend it: iterations before and after, the move's class."""
    from openmmtools import multistate
    sampler = multistate.ReplicaExchangeSampler.from_storage(str(storage))
    useCPU(sampler)
    before = sampler.iteration
    model, bodies = water()
    record = Record(sampler.n_states)
    runIterations(sampler, iterations, record, model, bodies, 6*len(bodies))
    moves = sorted({type(move).__module__ + '.' + type(move).__name__ for move in sampler.mcmc_moves})
    after = sampler.iteration
    sampler._reporter.close()
    return dict(before=before, after=after, moves=moves, accepted=record.accepted, rigidity=record.rigidity)


def main(arguments):
    addDependencies()
    import mpiplus
    problem = importProblem()
    if problem:
        raise SystemExit(problem)
    if arguments[0] == 'temperature':
        moveName, iterations, storage = arguments[1], int(arguments[2]), arguments[3]
        sampler, record = temperatureExchange(moveName, iterations, storage)
        result = record.summary(burnIn=0)
        result['ranks'] = mpiplus.get_mpicomm().size if mpiplus.get_mpicomm() else 1
    elif arguments[0] == 'extend':
        result = [extendStored(path, int(arguments[1])) for path in arguments[2:]]
    else:
        raise SystemExit(__doc__)
    if mpiplus.get_mpicomm() is None or mpiplus.get_mpicomm().rank == 0:
        print('REX ' + json.dumps(result))


if __name__ == '__main__':
    main(sys.argv[1:])
