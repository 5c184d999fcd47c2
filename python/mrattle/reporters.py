"""Temperatures with the rigid-body degrees of freedom, and StateDataReporter columns for them."""
import openmm
from openmm import app, unit

from .integrators import INTEGRATOR_CLASSES, RigidBodyIntegrator, RigidBodyTopology

#: The plugin's integrator classes with a heat bath (computeHeatBathEnergy()), which the reporter's energy columns need.
HEAT_BATH_INTEGRATORS = [cls for cls in INTEGRATOR_CLASSES if hasattr(cls, 'computeHeatBathEnergy')]
#: The plugin's Drude integrator classes (computeDrudeTemperature(), computeBodyTemperature()),
#: constructed as OpenMM's Drude integrators, with a temperature and coupling for the Drude particles too.
DRUDE_INTEGRATORS = [cls for cls in INTEGRATOR_CLASSES if hasattr(cls, 'computeDrudeTemperature')]


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


#: Whether OpenMM's own StateDataReporter takes the temperature from the integrator's
#: computeSystemTemperature() when it has one (OpenMM 8.0 on, openmm/openmm#3486), as the
#: plugin's integrators do, so that it reports the rigid-body temperature. OpenMM 7.7's
#: divides by 3 per particle minus constraints instead, 6 times too many for a rigid benzene.
STOCK_REPORTER_ASKS_INTEGRATOR = int(openmm.version.short_version.split('.')[0]) >= 8

if STOCK_REPORTER_ASKS_INTEGRATOR:
    _TemperatureReporter = app.StateDataReporter
else:
    class _TemperatureReporter(app.StateDataReporter):
        """OpenMM 7.7's StateDataReporter with the degrees of freedom of a RigidBodyIntegrator."""

        def _initializeConstants(self, simulation):
            # OpenMM 7.7 counts the degrees of freedom here, into self._dof, which its
            # _constructReportValues divides by; it has no public way to be given them.
            super()._initializeConstants(simulation)
            if self._temperature and isinstance(simulation.integrator, RigidBodyIntegrator):
                self._dof = simulation.integrator.getNumDegreesOfFreedom()


class StateDataReporter(_TemperatureReporter):
    """openmm.app.StateDataReporter reporting the rigid-body temperature, with columns for
    the rigid bodies' translational and rotational temperatures and for a thermostat's
    heat-bath energy.

    On OpenMM 8 and later this is OpenMM's reporter with only the columns added: OpenMM's
    own reports the rigid-body temperature (it asks the integrator's
    computeSystemTemperature()). On OpenMM 7.7, whose reporter counts 3 degrees of freedom
    per particle minus constraints (a rigid benzene has 6, not 36), it also takes the count
    from a RigidBodyIntegrator (such as MRattleIntegrator). With any other integrator it
    behaves exactly like OpenMM's. It takes the same arguments, and:

    translationalTemperature : bool=False
        write the bodies' translational temperature (RigidBodyIntegrator.computeTranslationalTemperature())
    rotationalTemperature : bool=False
        write the bodies' rotational temperature (RigidBodyIntegrator.computeRotationalTemperature())
    heatBathEnergy : bool=False
        write the thermostat's heat-bath energy (computeHeatBathEnergy() of an integrator of
        HEAT_BATH_INTEGRATORS, MRattleNoseHooverIntegrator say, or of OpenMM's NoseHooverIntegrator)
    conservedEnergy : bool=False
        write kinetic + potential + heat-bath energy, the quantity those thermostats conserve
    bodyTemperature : bool=False
        write the temperature of the bodies and free particles without the Drude particles'
        relative motion (computeBodyTemperature() of an integrator of DRUDE_INTEGRATORS)
    drudeTemperature : bool=False
        write the temperature of the Drude particles' motion relative to their cores
        (computeDrudeTemperature() of an integrator of DRUDE_INTEGRATORS)

    The new columns follow the Temperature column (or where it would be). The temperature
    columns need a RigidBodyIntegrator; with MRattleLangevinIntegrator they use its half-step
    velocities, as its kinetic energy does. The energy columns need an integrator with
    computeHeatBathEnergy(), the Drude columns one of DRUDE_INTEGRATORS.
    """

    def __init__(self, file, reportInterval, *args, translationalTemperature=False, rotationalTemperature=False,
                 heatBathEnergy=False, conservedEnergy=False, bodyTemperature=False, drudeTemperature=False,
                 **kwargs):
        super().__init__(file, reportInterval, *args, **kwargs)
        kelvin, energy = unit.kelvin, unit.kilojoules_per_mole
        bath = lambda simulation: simulation.integrator.computeHeatBathEnergy()
        self._bodyColumns = [(name, needs, value) for flag, name, needs, value in (
            (translationalTemperature, 'Translational Temperature (K)', 'computeTranslationalTemperature',
             lambda simulation, state: simulation.integrator.computeTranslationalTemperature().value_in_unit(kelvin)),
            (rotationalTemperature, 'Rotational Temperature (K)', 'computeRotationalTemperature',
             lambda simulation, state: simulation.integrator.computeRotationalTemperature().value_in_unit(kelvin)),
            (heatBathEnergy, 'Heat Bath Energy (kJ/mole)', 'computeHeatBathEnergy',
             lambda simulation, state: bath(simulation).value_in_unit(energy)),
            (conservedEnergy, 'Conserved Energy (kJ/mole)', 'computeHeatBathEnergy',
             lambda simulation, state: (state.getKineticEnergy() + state.getPotentialEnergy() +
                                        bath(simulation)).value_in_unit(energy)),
            (bodyTemperature, 'Body Temperature (K)', 'computeDrudeTemperature',
             lambda simulation, state: simulation.integrator.computeBodyTemperature().value_in_unit(kelvin)),
            (drudeTemperature, 'Drude Temperature (K)', 'computeDrudeTemperature',
             lambda simulation, state: simulation.integrator.computeDrudeTemperature().value_in_unit(kelvin))) if flag]
        if conservedEnergy:
            self._needEnergy = True

    def report(self, simulation, state):
        needs = {needed for _, needed, _ in self._bodyColumns}
        if needs & {'computeTranslationalTemperature', 'computeRotationalTemperature'} and \
                not isinstance(simulation.integrator, RigidBodyIntegrator):
            raise ValueError('StateDataReporter: the translationalTemperature and rotationalTemperature columns need a '
                             'RigidBodyIntegrator (such as mrattle.MRattleIntegrator); the Simulation has a %s'
                             % type(simulation.integrator).__name__)
        if 'computeHeatBathEnergy' in needs and not hasattr(simulation.integrator, 'computeHeatBathEnergy'):
            raise ValueError('StateDataReporter: the heatBathEnergy and conservedEnergy columns need an integrator with '
                             'computeHeatBathEnergy() (%s); the Simulation has a %s'
                             % (', '.join('mrattle.' + cls.__name__ for cls in HEAT_BATH_INTEGRATORS),
                                type(simulation.integrator).__name__))
        if 'computeDrudeTemperature' in needs and not hasattr(simulation.integrator, 'computeDrudeTemperature'):
            raise ValueError('StateDataReporter: the bodyTemperature and drudeTemperature columns need a Drude '
                             'integrator (%s); the Simulation has a %s'
                             % (', '.join('mrattle.' + cls.__name__ for cls in DRUDE_INTEGRATORS),
                                type(simulation.integrator).__name__))
        super().report(simulation, state)

    # OpenMM's StateDataReporter has no public way to add columns: the two below extend the
    # methods that make its header and its rows.

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
        return headers[:index] + [name for name, _, _ in self._bodyColumns] + headers[index:]

    def _constructReportValues(self, simulation, state):
        values = super()._constructReportValues(simulation, state)
        if not self._bodyColumns:
            return values
        index = self._bodyIndex
        extra = [value(simulation, state) for _, _, value in self._bodyColumns]
        return values[:index] + extra + values[index:]
