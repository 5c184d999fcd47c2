"""Reporting with the rigid-body degrees of freedom, and a progress bar."""
import sys
import time

import openmm
from openmm import app, unit

from .integrators import RigidBodyIntegrator, RigidBodyTopology


def degreesOfFreedom(simulationOrContext):
    """Degrees of freedom of a Context's System under its integrator.

    For a RigidBodyIntegrator bound to the Context, its own count
    (RigidBodyIntegrator.getNumDegreesOfFreedom()): 6 per rigid body (5 if linear), 3 per
    free particle, minus constraints among free particles, minus 3 with a CMMotionRemover.
    For any other integrator (VerletIntegrator with CCMA, a CustomIntegrator with
    constraints, ...) the same rule with no body, which is OpenMM's count: 3 per massive
    particle, minus each constraint with a massive end, minus 3 with a CMMotionRemover. Both
    come from the C++ RigidBodyTopology, the integrators' one home of the count. Like
    OpenMM's count, the second assumes independent constraints: constraining all 66 pair
    distances of a 12-atom molecule removes 30 degrees of freedom, not 66.
    """
    context = getattr(simulationOrContext, 'context', simulationOrContext)
    integrator = context.getIntegrator()
    if isinstance(integrator, RigidBodyIntegrator):
        return integrator.getNumDegreesOfFreedom()
    return RigidBodyTopology(context.getSystem(), [], []).getNumDegreesOfFreedom(0)


def kineticTemperature(simulationOrContext, state=None):
    """The instantaneous temperature 2 KE / (DOF k_B) with degreesOfFreedom(), as a Quantity in K."""
    context = getattr(simulationOrContext, 'context', simulationOrContext)
    if state is None:
        state = context.getState(getEnergy=True)
    return (2*state.getKineticEnergy()/(degreesOfFreedom(context)*unit.MOLAR_GAS_CONSTANT_R)).in_units_of(unit.kelvin)


class StateDataReporter(app.StateDataReporter):
    """openmm.app.StateDataReporter whose temperature uses the rigid-body degrees of freedom,
    with columns for the rigid bodies' translational and rotational temperatures.

    OpenMM's reporter counts 3 degrees of freedom per particle minus constraints, which is
    wrong for rigid bodies (a rigid benzene has 6, not 36 - 0). With a RigidBodyIntegrator
    (such as MRattleIntegrator) this reporter asks the integrator instead; with any other
    integrator it behaves exactly like OpenMM's. It takes the same arguments, and:

    translationalTemperature : bool=False
        write the bodies' translational temperature (RigidBodyIntegrator.computeTranslationalTemperature())
    rotationalTemperature : bool=False
        write the bodies' rotational temperature (RigidBodyIntegrator.computeRotationalTemperature())

    The two columns follow the Temperature column (or where it would be). They need a
    RigidBodyIntegrator; with MRattleLangevinIntegrator they use its half-step velocities, as
    its kinetic energy does.
    """

    def __init__(self, file, reportInterval, *args, translationalTemperature=False, rotationalTemperature=False,
                 **kwargs):
        super().__init__(file, reportInterval, *args, **kwargs)
        self._bodyColumns = [(name, method) for flag, name, method in (
            (translationalTemperature, 'Translational Temperature (K)', 'computeTranslationalTemperature'),
            (rotationalTemperature, 'Rotational Temperature (K)', 'computeRotationalTemperature')) if flag]

    def _initializeConstants(self, simulation):
        super()._initializeConstants(simulation)
        rigid = isinstance(simulation.integrator, RigidBodyIntegrator)
        if self._temperature and rigid:
            self._dof = simulation.integrator.getNumDegreesOfFreedom()
        if self._bodyColumns and not rigid:
            raise ValueError('StateDataReporter: the translationalTemperature and rotationalTemperature columns need a '
                             'RigidBodyIntegrator (such as mrattle.MRattleIntegrator); the Simulation has a %s'
                             % type(simulation.integrator).__name__)
        self._bodyIntegrator = simulation.integrator

    def _bodyColumnIndex(self, headers):
        """Where the new columns go: after Temperature, or after the energies before it."""
        if 'Temperature (K)' in headers:
            return headers.index('Temperature (K)') + 1
        before = ('Progress (%)', 'Step', 'Time (ps)', 'Potential Energy (kJ/mole)', 'Kinetic Energy (kJ/mole)',
                  'Total Energy (kJ/mole)')
        return sum(1 for header in headers if header in before)

    def _constructHeaders(self):
        headers = super()._constructHeaders()
        self._bodyIndex = self._bodyColumnIndex(headers)
        index = self._bodyIndex
        return headers[:index] + [name for name, _ in self._bodyColumns] + headers[index:]

    def _constructReportValues(self, simulation, state):
        values = super()._constructReportValues(simulation, state)
        if not self._bodyColumns:
            return values
        index = self._bodyIndex
        extra = [getattr(self._bodyIntegrator, method)().value_in_unit(unit.kelvin) for _, method in self._bodyColumns]
        return values[:index] + extra + values[index:]


class ProgressReporter(object):
    """A reporter drawing a progress bar with the time left on stderr (in a log file, one line per 10%)."""

    def __init__(self, totalSteps, interval, stream=sys.stderr, width=40):
        self.totalSteps, self.interval, self.stream, self.width = totalSteps, interval, stream, width
        self.startTime = time.time()
        # Redrawing in place needs a terminal; in a log file, one line per 10%.
        self.interactive = hasattr(stream, 'isatty') and stream.isatty()
        self.lastTenth = -1

    def describeNextReport(self, simulation):
        return (self.interval - simulation.currentStep % self.interval, False, False, False, False)

    def report(self, simulation, state):
        fraction = min(1.0, simulation.currentStep/self.totalSteps)
        filled = int(round(self.width*fraction))
        elapsed = time.time() - self.startTime
        remaining = elapsed*(1 - fraction)/fraction if fraction > 0 else 0
        bar = '[%s%s] %3.0f%%  %5.1f s left ' % ('#'*filled, '.'*(self.width - filled), 100*fraction, remaining)
        if self.interactive:
            self.stream.write('\r' + bar + ('\n' if simulation.currentStep >= self.totalSteps else ''))
        elif int(10*fraction) > self.lastTenth:
            self.lastTenth = int(10*fraction)
            self.stream.write(bar + '\n')
        self.stream.flush()
