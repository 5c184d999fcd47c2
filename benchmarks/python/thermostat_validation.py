#!/usr/bin/env python3
"""Validation of MRattleNoseHooverIntegrator and MRattleBussiIntegrator (issue 33) on rigid
TIP3P water (openmm/app/data/tip3p.pdb, amber14/tip3p.xml, PME 0.9 nm, 895 waters, CPU platform).

From one start (LangevinMiddle + SETTLE at 300 K), each method runs at 300 K:
1. production at 2 fs with M-RATTLE NVE, the Nose-Hoover chain (10/ps), CSVR (10/ps) and
   LangevinMiddleIntegrator + SETTLE (1/ps): the kinetic energy's mean and variance against the
   canonical values for N = 6 * 895 - 3 degrees of freedom (mean N kT/2, variance N (kT)^2/2),
   the potential energy per molecule, the translational and rotational temperatures, and the
   self-diffusion coefficient (oxygen mean-squared displacement);
2. short runs at 0.5, 1, 3, 4 and 5 fs (2 fs from 1.) of the three M-RATTLE methods: the
   conserved quantity's drift (kinetic + potential + the heat bath's energy; NVE's total
   energy) and the translational and rotational temperatures (on-step velocities).
Means carry standard errors from 10 block averages; a variance's error comes from the block
variances. Writes a CSV and prints a markdown table.
Usage: scripts/python.sh benchmarks/python/thermostat_validation.py [--production-ps 20] [--short-ps 2]
"""
import argparse
import csv
import math
import os
import sys
import time

import numpy as np
import openmm
from openmm import app, unit

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mrattle  # noqa: E402
from suite import langevin  # noqa: E402
from suite.stats import drift_with_error  # noqa: E402

TEMPERATURE = 300.0
FREQUENCY = 10.0  # 1/ps, both thermostats
METHODS = ('M-RATTLE NVE', 'M-RATTLE Nose-Hoover chain', 'M-RATTLE CSVR', 'LangevinMiddle + SETTLE')
BLOCKS = 10


def make_integrator(method, step_fs):
    step = step_fs * unit.femtoseconds
    if method == 'M-RATTLE NVE':
        return mrattle.MRattleIntegrator(step)
    if method == 'M-RATTLE Nose-Hoover chain':
        return mrattle.MRattleNoseHooverIntegrator(TEMPERATURE, FREQUENCY, step)
    if method == 'M-RATTLE CSVR':
        integrator = mrattle.MRattleBussiIntegrator(TEMPERATURE, FREQUENCY, step)
        integrator.setRandomNumberSeed(5)
        return integrator
    if method == 'LangevinMiddle + SETTLE':
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, 1.0, step)
        integrator.setRandomNumberSeed(5)
        return integrator
    raise ValueError(method)


def platform(threads):
    return openmm.Platform.getPlatformByName('CPU'), {'Threads': str(threads)}


def block_variance(values, blocks=BLOCKS):
    """The variance of a series and its standard error from the blocks' variances."""
    values = np.asarray(values, float)
    n = len(values) // blocks
    variances = values[:n * blocks].reshape(blocks, n).var(axis=1, ddof=1)
    return variances.mean(), variances.std(ddof=1) / math.sqrt(blocks)


def diffusion(times, oxygens, groups=5):
    """D (1e-5 cm^2/s) from the oxygens' mean-squared displacement, slope over lags of 20-60 % of
    the run (all time origins); mean and standard error over groups of molecules."""
    t = np.asarray(times) - times[0]
    x = np.asarray(oxygens)  # frames x molecules x 3, unwrapped
    lags = [k for k in range(1, len(t)) if 0.2 * t[-1] <= t[k] <= 0.6 * t[-1]]
    values = []
    for g in np.array_split(np.arange(x.shape[1]), groups):
        msd = [np.mean(np.sum((x[k:, g] - x[:-k, g]) ** 2, axis=2)) for k in lags]
        slope = np.polyfit(t[lags], msd, 1)[0]  # nm^2/ps
        values.append(slope / 6 * 1e-2 / 1e-5)  # nm^2/ps = 1e-2 cm^2/s
    return np.mean(values), np.std(values, ddof=1) / math.sqrt(groups)


def run(method, step_fs, ps, start, system, bodies, threads, sample_fs=10.0, keep_oxygens=False):
    integrator = make_integrator(method, step_fs)
    context = openmm.Context(system, integrator, *platform(threads))
    context.setPositions(start[0])
    context.setVelocities(start[1])
    rigid = isinstance(integrator, mrattle.RigidBodyIntegrator)
    bath = getattr(integrator, 'computeHeatBathEnergy', None)
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    oxygen = [body[0] for body in bodies]
    stride = max(1, int(round(sample_fs / step_fs)))
    series = {key: [] for key in ('time', 'kinetic', 'potential', 'conserved', 'Ttrans', 'Trot')}
    oxygens = []
    began = time.time()
    for _ in range(int(round(ps * 1000 / (stride * step_fs)))):
        integrator.step(stride)
        state = context.getState(getEnergy=True, getVelocities=not rigid, getPositions=keep_oxygens)
        kinetic = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        potential = state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        series['time'].append(state.getTime().value_in_unit(unit.picosecond))
        series['kinetic'].append(kinetic)
        series['potential'].append(potential)
        series['conserved'].append(kinetic + potential + (bath().value_in_unit(unit.kilojoule_per_mole) if bath else 0))
        if rigid:
            series['Ttrans'].append(integrator.computeTranslationalTemperature().value_in_unit(unit.kelvin))
            series['Trot'].append(integrator.computeRotationalTemperature().value_in_unit(unit.kelvin))
        else:  # its half-step velocities, as LangevinMiddle reports them
            v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
            _, ttrans, trot = langevin.temperatures(v, masses, bodies, 6 * len(bodies) - 3, True)
            series['Ttrans'].append(ttrans)
            series['Trot'].append(trot)
        if keep_oxygens:
            oxygens.append(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[oxygen])
        if not math.isfinite(series['conserved'][-1]):
            raise ArithmeticError('%s at %g fs: energy not finite' % (method, step_fs))
    return series, oxygens, time.time() - began


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--production-ps', type=float, default=20.0)
    parser.add_argument('--short-ps', type=float, default=2.0)
    parser.add_argument('--equilibrate-ps', type=float, default=2.0)
    parser.add_argument('--threads', type=int, default=1)
    parser.add_argument('--out', default='docs/results/thermostats.csv')
    parser.add_argument('--methods', default=','.join(METHODS))
    args = parser.parse_args()
    methods = args.methods.split(',')
    pdb, system = langevin.water_system()
    positions = langevin.exact_geometry(system, pdb.positions)
    bodies = mrattle.rigidBodies(pdb.topology, system)
    dof = 6 * len(bodies) - 3
    kT = langevin.KB * TEMPERATURE
    print('equilibrating %g ps (LangevinMiddle + SETTLE, 2 fs)' % args.equilibrate_ps, flush=True)
    equilibration = openmm.LangevinMiddleIntegrator(TEMPERATURE, 1.0, 0.002)
    equilibration.setRandomNumberSeed(11)
    context = openmm.Context(system, equilibration, *platform(args.threads))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(TEMPERATURE, 11)
    equilibration.step(int(round(args.equilibrate_ps / 0.002)))
    state = context.getState(getPositions=True, getVelocities=True)
    start = (state.getPositions(), state.getVelocities())
    del context
    rows = []
    for method in methods:
        for step_fs in (2, 0.5, 1, 3, 4, 5):
            if method == 'LangevinMiddle + SETTLE' and step_fs != 2:
                continue
            production = step_fs == 2
            ps = args.production_ps if production else args.short_ps
            try:
                series, oxygens, wall = run(method, step_fs, ps, start, system, bodies, args.threads,
                                            keep_oxygens=production)
            except Exception as error:  # a blow-up is a result
                rows.append(dict(method=method, step_fs=step_fs, ps=ps, failure=str(error).splitlines()[0]))
                print(rows[-1], flush=True)
                continue
            row = dict(method=method, step_fs=step_fs, ps=ps, wall_s=round(wall))
            if method != 'LangevinMiddle + SETTLE':  # it conserves nothing
                drift, drift_se = drift_with_error(series['time'], series['conserved'])
                row['drift_kJ_per_mol_ns_per_molecule'], row['drift_se'] = drift / len(bodies), drift_se / len(bodies)
            for key in ('Ttrans', 'Trot'):
                row[key], row[key + '_se'] = langevin.block_mean(series[key], BLOCKS)
            if production:
                row['kinetic_mean'], row['kinetic_mean_se'] = langevin.block_mean(series['kinetic'], BLOCKS)
                row['kinetic_variance'], row['kinetic_variance_se'] = block_variance(series['kinetic'])
                mean_potential, se_potential = langevin.block_mean(series['potential'], BLOCKS)
                row['potential_per_molecule'], row['potential_per_molecule_se'] = (
                    mean_potential / len(bodies), se_potential / len(bodies))
                row['D_1e-5_cm2_per_s'], row['D_se'] = diffusion(series['time'], oxygens)
            rows.append(row)
            print(row, flush=True)
    columns = ['method', 'step_fs', 'ps', 'kinetic_mean', 'kinetic_mean_se', 'kinetic_variance', 'kinetic_variance_se',
               'potential_per_molecule', 'potential_per_molecule_se', 'Ttrans', 'Ttrans_se', 'Trot', 'Trot_se',
               'D_1e-5_cm2_per_s', 'D_se', 'drift_kJ_per_mol_ns_per_molecule', 'drift_se', 'failure', 'wall_s']
    with open(args.out, 'w', newline='') as stream:
        writer = csv.DictWriter(stream, columns)
        writer.writeheader()
        for row in rows:
            writer.writerow(row)
    print('canonical kinetic energy: mean %.1f, variance %.1f kJ^2/mol^2 (N = %d, T = %g K)'
          % (0.5 * dof * kT, 0.5 * dof * kT * kT, dof, TEMPERATURE))


if __name__ == '__main__':
    main()
