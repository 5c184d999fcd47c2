"""openmmtools 0.26.0's ReplicaExchangeSampler with mrattle.mcmc's moves (issue 43), on 64
rigid waters (CPU platform, one thread): a temperature exchange of 4 states at 300-360 K with
each thermostatted integrator, a Hamiltonian exchange with the Nose-Hoover chain, a stored
run resumed in a new process, and the run over two MPI processes. Skipped, saying why, where
openmmtools (../shared/deps) or its Debian dependencies cannot be imported.
"""
import json
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rex  # noqa: E402

PROBLEM = rex.importProblem()
if PROBLEM:
    pytest.skip(PROBLEM, allow_module_level=True)

import numpy as np  # noqa: E402
import openmm  # noqa: E402
from openmm import unit  # noqa: E402
from openmmtools import multistate, states  # noqa: E402

import mrattle  # noqa: E402
import mrattle.mcmc  # noqa: E402

MOVES = list(rex.COUPLING)
ITERATIONS = 110  # 0.2 ps each: 10 of equilibration, then 100 samples of each state
BURN_IN = 10
SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'rex.py')


def runScript(arguments, launcher=()):
    """rex.py in a new process (under the launcher, e.g. mpirun): its JSON line."""
    environment = dict(os.environ)
    environment['PYTHONPATH'] = os.pathsep.join([str(rex.DEPENDENCIES / f) for f in rex.FOLDERS] +
                                                [os.path.dirname(os.path.dirname(mrattle.__file__))] +
                                                [environment.get('PYTHONPATH', '')])
    result = subprocess.run(list(launcher) + [sys.executable, SCRIPT] + list(arguments), env=environment,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=600)
    lines = [line for line in result.stdout.splitlines() if line.startswith('REX ')]
    assert result.returncode == 0 and lines, result.stdout[-4000:]
    return json.loads(lines[-1][4:])


@pytest.fixture(scope='module')
def temperatureRuns(tmp_path_factory):
    """Each move's temperature exchange, stored: {move: (summary, storage)}."""
    runs = {}
    for name in MOVES:
        storage = tmp_path_factory.mktemp(name) / 'rex.nc'
        sampler, record = rex.temperatureExchange(name, ITERATIONS, storage)
        sampler._reporter.close()
        summary = record.summary(BURN_IN)
        print('%s: %d of %d swaps accepted (neighbours %s of %s); kinetic T %s K; rigid to %.1e nm; %.1f s'
              % (name, summary['accepted'], summary['proposed'], summary['neighbourAccepted'],
                 summary['neighbourProposed'], ', '.join('%.1f +- %.1f' % s for s in summary['states']),
                 summary['rigidity'], summary['seconds']))
        runs[name] = (summary, storage)
    return runs


@pytest.mark.parametrize('name', MOVES)
def test_temperature_exchange(temperatureRuns, name):
    summary, _ = temperatureRuns[name]
    assert all(n > 0 for n in summary['neighbourAccepted']), summary
    for target, (mean, error) in zip(rex.TEMPERATURES, summary['states']):
        assert abs(mean - target) < 3*error, (target, mean, error)
        assert error < 0.03*target  # the test can fail: the error bar is not vacuous
    assert summary['rigidity'] < 1e-6
    # One Context for every temperature, whose integrator is the move's and never replaced.
    assert len(summary['contexts']) == 1, summary['contexts']
    assert summary['contexts'][0][2] == name.replace('DynamicsMove', 'Integrator')


def test_stored_runs_resume_in_a_new_process(temperatureRuns):
    results = runScript(['extend', '3'] + [str(temperatureRuns[name][1]) for name in MOVES])
    for name, result in zip(MOVES, results):
        assert (result['before'], result['after']) == (ITERATIONS, ITERATIONS + 3)
        assert result['moves'] == ['mrattle.mcmc.' + name]
        assert result['rigidity'] < 1e-6


def test_moves_settings_round_trip():
    move = mrattle.mcmc.MRattleNoseHooverDynamicsMove(timestep=1.5*unit.femtoseconds,
                                                      collision_rate=5/unit.picoseconds, n_steps=7,
                                                      reassign_velocities=True, chain_length=4,
                                                      rigid_bodies=[[0, 1, 2]])
    copy = mrattle.mcmc.MRattleNoseHooverDynamicsMove.__new__(mrattle.mcmc.MRattleNoseHooverDynamicsMove)
    copy.__setstate__(move.__getstate__())
    thermodynamicState = states.ThermodynamicState(rex.water()[0].system, 310*unit.kelvin)
    integrator = copy._get_integrator(thermodynamicState)
    assert isinstance(integrator, mrattle.MRattleNoseHooverIntegrator)
    assert integrator.getTemperature() == 310*unit.kelvin
    assert integrator.getCollisionFrequency() == 5/unit.picoseconds
    assert integrator.getChainLength() == 4 and integrator.getNumRigidBodies() == 1
    assert (copy.n_steps, copy.reassign_velocities) == (7, True)


class _RecordingNoseHooverMove(mrattle.mcmc.MRattleNoseHooverDynamicsMove):
    """Records the Context's heat bath before and after each application (the chain's hand-over)."""
    log = []

    def _before_integration(self, context, thermodynamic_state):
        self.log.append(('before', context.getIntegrator().computeHeatBathEnergy()))

    def _after_integration(self, context, thermodynamic_state):
        self.log.append(('after', context.getIntegrator().computeHeatBathEnergy()))


def test_hamiltonian_exchange_hands_the_chain_on(tmp_path):
    """Two states differing in a restraint's strength (a global parameter, so one Context).
    openmmtools 0.26.0's SamplerState carries no integrator parameters, so the chain is the
    Context's: each application starts from the chain the previous one (another replica's) left."""
    model, bodies = rex.water()
    restraint = openmm.CustomExternalForce('lambda_restraint*0.5*20*periodicdistance(x, y, z, x0, y0, z0)^2')
    restraint.addGlobalParameter('lambda_restraint', 1.0)
    for name in ('x0', 'y0', 'z0'):
        restraint.addPerParticleParameter(name)
    for i, body in enumerate(bodies):
        restraint.addParticle(body[0], model.positions[body[0]].value_in_unit(unit.nanometers))
    model.system.addForce(restraint)

    class RestraintState(states.GlobalParameterState):
        lambda_restraint = states.GlobalParameterState.GlobalParameter('lambda_restraint', standard_value=1.0)

    thermodynamicStates = [states.CompoundThermodynamicState(states.ThermodynamicState(model.system, 300*unit.kelvin),
                                                             [RestraintState(lambda_restraint=value)])
                           for value in (1.0, 0.0)]
    velocities, dof = rex.rigidVelocities(model, 300, 2)
    rex.seedEverything(2)
    move = _RecordingNoseHooverMove(timestep=2*unit.femtoseconds, collision_rate=20/unit.picoseconds,
                                    n_steps=rex.STEPS_PER_ITERATION)
    sampler = multistate.ReplicaExchangeSampler(mcmc_moves=move, number_of_iterations=20)
    rex.useCPU(sampler)
    sampler.create(thermodynamicStates, states.SamplerState(model.positions, velocities=velocities,
                                                            box_vectors=model.system.getDefaultPeriodicBoxVectors()),
                   multistate.MultiStateReporter(str(tmp_path / 'hrex.nc'), checkpoint_interval=1))
    record = rex.Record(2)
    rex.runIterations(sampler, 20, record, model, bodies, dof)
    sampler._reporter.close()
    print('Hamiltonian exchange: %d of %d swaps accepted; rigid to %.1e nm; %.1f s'
          % (record.accepted, record.proposed, record.rigidity, record.seconds))
    assert record.accepted > 0
    assert record.rigidity < 1e-6
    assert len(record.contexts) == 1
    log = _RecordingNoseHooverMove.log  # the moves are copies per state: the class keeps one log
    assert len(log) == 2*2*20
    for (previous, energy), (kind, start) in zip(log[1::2], log[2::2]):
        assert (previous, kind) == ('after', 'before')
        assert start == energy  # the next replica starts from the chain this one left


@pytest.mark.skipif(shutil.which('mpirun') is None, reason='no mpirun (Debian\'s openmpi-bin)')
def test_two_mpi_processes_give_the_acceptance_of_one(temperatureRuns, tmp_path):
    """The Langevin move's exchange over 2 processes (mpiplus gives each 2 replicas) against
    the one-process run from the same seeds: the same number of proposals, and each neighbour
    pair's acceptance fraction within 3 combined standard errors (over iterations; the runs
    differ: each process has its own Context and random stream)."""
    try:
        import mpi4py  # noqa: F401
    except ImportError as error:
        pytest.skip('mpi4py cannot be imported (%s): Debian\'s python3-mpi4py' % error)
    name = 'MRattleLangevinDynamicsMove'
    launcher = ['mpirun', '-np', '2', '--oversubscribe']
    if os.geteuid() == 0:
        launcher.append('--allow-run-as-root')
    two = runScript(['temperature', name, str(ITERATIONS), str(tmp_path / 'mpi.nc')], launcher)
    one, _ = temperatureRuns[name]
    assert two['ranks'] == 2
    assert two['proposed'] == one['proposed']
    for k in range(len(rex.TEMPERATURES) - 1):
        (p1, e1), (p2, e2) = one['neighbourFractions'][k], two['neighbourFractions'][k]
        print('pair %d-%d accepted: one process %.3f +- %.3f, two %.3f +- %.3f' % (k, k + 1, p1, e1, p2, e2))
        assert p2 > 0 and abs(p1 - p2) < 3*np.hypot(e1, e2)
    assert two['rigidity'] < 1e-6
    print('two processes: %.1f s (one: %.1f s)' % (two['seconds'], one['seconds']))
