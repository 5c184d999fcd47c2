"""openmmtools MCMC moves that run rigid-body dynamics with the plugin's thermostatted integrators.

One move per thermostat, each an ``openmmtools.mcmc.BaseIntegratorMove`` with openmmtools'
settings (``timestep``, ``collision_rate``, ``n_steps``, ``reassign_velocities``, with units)::

    import mrattle.mcmc
    from openmmtools import multistate
    move = mrattle.mcmc.MRattleLangevinDynamicsMove(timestep=2*unit.femtoseconds,
                                                    collision_rate=1/unit.picoseconds, n_steps=500)
    sampler = multistate.ReplicaExchangeSampler(mcmc_moves=move, number_of_iterations=100)

openmmtools stores a move by its module and class name, so a stored run resumes in a new
process that can import this module (``mrattle.mcmc``). The integrator is made at the
thermodynamic state's temperature, so openmmtools' ContextCache sees a thermostatted
integrator and keeps one Context for every temperature (it sets the temperature).

openmmtools 0.26.0's SamplerState carries positions, velocities and box vectors but no
integrator parameters: a Nose-Hoover chain (or CSVR's accumulated work) is the Context's,
handed from one replica to the next on that Context (docs/usage.md, "Replica exchange").

This module imports openmmtools; ``import mrattle`` never imports it.
"""
from openmm import unit
from openmmtools import mcmc as _mcmc

from . import MRattleBussiIntegrator, MRattleLangevinIntegrator, MRattleNoseHooverIntegrator

__all__ = ['MRattleLangevinDynamicsMove', 'MRattleNoseHooverDynamicsMove', 'MRattleBussiDynamicsMove']


class _RigidBodyDynamicsMove(_mcmc.BaseIntegratorMove):
    """Rigid-body dynamics at the thermodynamic state's temperature (the subclass's integrator).

    Parameters
    ----------
    timestep : Quantity (time)
        The step size (default 2 fs: the bodies are rigid).
    collision_rate : Quantity (1/time)
        The thermostat's coupling: Langevin friction, the Nose-Hoover chain's or CSVR's
        collision frequency.
    n_steps : int
        Steps per application of the move.
    reassign_velocities : bool
        Draw rigid-body velocities at the state's temperature before each application.
    rigid_bodies : list of lists of int, optional
        The particles of each rigid body to declare (every other particle is free); None (the
        default): every molecule is a rigid body.
    constraint_tolerance : float, optional
        The integrator's tolerance for free particles' constraints; None keeps its default.
    random_seed : int
        The random stream's seed where the integrator has one (0: a new seed per Context).
    """

    def __init__(self, timestep=2.0*unit.femtosecond, collision_rate=1.0/unit.picosecond, n_steps=1000,
                 reassign_velocities=False, rigid_bodies=None, constraint_tolerance=None, random_seed=0, **kwargs):
        super().__init__(n_steps=n_steps, reassign_velocities=reassign_velocities, **kwargs)
        self.timestep = timestep
        self.collision_rate = collision_rate
        self.rigid_bodies = None if rigid_bodies is None else [[int(i) for i in body] for body in rigid_bodies]
        self.constraint_tolerance = constraint_tolerance
        self.random_seed = random_seed

    def _make_integrator(self, temperature):
        """The subclass's integrator at this temperature."""
        raise NotImplementedError

    def _get_integrator(self, thermodynamic_state):
        """Implement BaseIntegratorMove._get_integrator()."""
        integrator = self._make_integrator(thermodynamic_state.temperature)
        for body in self.rigid_bodies or []:
            integrator.addRigidBody(body)
        if self.constraint_tolerance is not None:
            integrator.setConstraintTolerance(self.constraint_tolerance)
        if hasattr(integrator, 'setRandomNumberSeed'):
            integrator.setRandomNumberSeed(self.random_seed)
        return integrator

    #: The settings stored with the move, besides BaseIntegratorMove's (a subclass adds its own).
    _settings = ('timestep', 'collision_rate', 'rigid_bodies', 'constraint_tolerance', 'random_seed')

    def __getstate__(self):
        serialization = super().__getstate__()
        serialization.update((name, getattr(self, name)) for name in self._settings)
        return serialization

    def __setstate__(self, serialization):
        super().__setstate__(serialization)
        for name in self._settings:
            setattr(self, name, serialization[name])


class MRattleLangevinDynamicsMove(_RigidBodyDynamicsMove):
    """Langevin dynamics of rigid bodies (MRattleLangevinIntegrator; collision_rate is its friction)."""

    def _make_integrator(self, temperature):
        return MRattleLangevinIntegrator(temperature, self.collision_rate, self.timestep)


class MRattleNoseHooverDynamicsMove(_RigidBodyDynamicsMove):
    """Rigid bodies with a Nose-Hoover chain (MRattleNoseHooverIntegrator; collision_rate is its
    collision frequency); chain_length, num_mts and num_yoshida_suzuki as its constructor's."""

    def __init__(self, timestep=2.0*unit.femtosecond, collision_rate=1.0/unit.picosecond, n_steps=1000,
                 reassign_velocities=False, chain_length=3, num_mts=3, num_yoshida_suzuki=7, **kwargs):
        super().__init__(timestep=timestep, collision_rate=collision_rate, n_steps=n_steps,
                         reassign_velocities=reassign_velocities, **kwargs)
        self.chain_length = chain_length
        self.num_mts = num_mts
        self.num_yoshida_suzuki = num_yoshida_suzuki

    _settings = _RigidBodyDynamicsMove._settings + ('chain_length', 'num_mts', 'num_yoshida_suzuki')

    def _make_integrator(self, temperature):
        return MRattleNoseHooverIntegrator(temperature, self.collision_rate, self.timestep, self.chain_length,
                                           self.num_mts, self.num_yoshida_suzuki)


class MRattleBussiDynamicsMove(_RigidBodyDynamicsMove):
    """Rigid bodies with stochastic velocity rescaling (MRattleBussiIntegrator; collision_rate is
    its collision frequency, 1/tau)."""

    def _make_integrator(self, temperature):
        return MRattleBussiIntegrator(temperature, self.collision_rate, self.timestep)
