"""Scenario files: schema, unit conversion, and the node parameters they become.

A scenario is a YAML file (``scenarios/<name>.yaml``). Quantities carry their
unit in the key, e.g. ``altitude_nmi: 225`` or ``inertia_slug_ft2: [...]``;
each field accepts a small set of units and is converted to SI here, the one
place where seed units meet SI (spec header "Units"). ``extends: <name>``
starts from another scenario and overrides keys (deep merge); a relative
``extends`` (a bare name or a path) is looked up first beside the extending
file, then among the shipped scenarios. A key naming a file (``Field.path``, e.g.
``em_driver.torque_rod_design``) is relative to the scenario file that gives it
(also through ``extends``) and becomes an absolute path.

Reading is strict, and every problem is one :class:`ScenarioError` line naming
the file and the key: the file must be UTF-8 YAML text; a key given twice in
one mapping (at any level) is refused; exponent floats without a dot
(``2.25e2``, ``1e5``, ``-3E-2``) are numbers, as in YAML 1.2; every number has
a physical range; ``name`` becomes a folder name, so it is limited to letters,
digits, ``_ - .`` (not starting with ``.``); quaternions must be normalisable;
``nodes`` must hold the time owner ``rigid_body`` and no node twice; a run has
at most :data:`MAX_STEPS` steps. A model's own checks (inertia positive
definite, apogee above perigee, ...) are the cores' and run in the launcher
before any process starts (``scripts/acds_cli/preflight.py``).

The schema is the single source of truth: node parameter names
(``<section>_<field>_<si unit>``), types, defaults, ranges and descriptions
all come from :data:`SCHEMA`; nodes declare their parameters from it, and the
launcher passes each node exactly the sections it owns (:data:`NODE_SECTIONS`).
"""

from __future__ import annotations

import datetime
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from acds_common import units as u
from acds_common.environment import IGRF_LAST_YEAR, decimal_year_datetime
from acds_common.graph import TIME_OWNER
from acds_common.thrusters import COLD_GAS_FAULTS, GAS_MODES, HEAO_B_DIRECTIONS, HEAO_B_POSITIONS_M, MAX_CROSS_COUPLING


class ScenarioError(ValueError):
    """A scenario file is malformed: the message names the file and the key."""


REQUIRED = object()
_DEG = math.pi / 180.0
#: Most control steps one run may have (the time owner's ``total_steps`` bound).
MAX_STEPS = 10**9
#: A scenario file larger than this is not a scenario (guards against reading a device or a data file).
MAX_SCENARIO_BYTES = 1 << 20
#: A quaternion shorter than this cannot be normalised to an attitude (the rigid body's own limit).
MIN_QUATERNION_NORM = 1e-6
#: ``name`` is used as a run-folder name: letters, digits, ``_ - .``, not starting with ``.``, ≤ 100 characters.
SAFE_NAME = re.compile(r'[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}')


@dataclass(frozen=True)
class Field:
    """One scenario key: type, SI unit suffix, accepted units → SI factor, default, range, meaning."""

    kind: str  # 'float' | 'int' | 'bool' | 'str' | 'floats' | 'strs'
    doc: str
    default: Any = REQUIRED
    si: str = ''
    units: dict[str, float] = field(default_factory=dict)
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    length: int | None = None
    pattern: re.Pattern[str] | None = None  # 'str': the whole value must match
    unique: bool = False  # 'strs': no entry twice
    quaternion: bool = False  # 'floats' (x, y, z, w): must be normalisable
    path: bool = False  # 'str': a file name, resolved relative to the scenario file that gives it ('' = none)

    def param_name(self, section: str, name: str) -> str:
        """The ROS parameter name this key becomes."""
        base = f'{section}_{name}' if section else name
        return f'{base}_{self.si}' if self.si else base


def _q(doc: str, default: Any, si: str, units: dict[str, float], **kw: Any) -> Field:
    kind = 'floats' if isinstance(default, list) or kw.get('length') else 'float'
    return Field(kind, doc, default, si, units, **kw)


ANGLE = {'deg': _DEG, 'rad': 1.0}
RATE = {'deg_s': _DEG, 'rad_s': 1.0, 'rpm': 2 * math.pi / 60}
LENGTH = {'nmi': u.NMI_M, 'km': 1e3, 'm': 1.0}
RADIUS = {**LENGTH, 'earth_radii': u.EARTH_RADIUS_M}
INERTIA = {'slug_ft2': u.SLUG_FT2_KG_M2, 'kg_m2': 1.0}
MOMENTUM = {'ft_lb_s': u.FT_LB_S_NMS, 'nms': 1.0}
FIELD = {'gauss': u.GAUSS_T, 't': 1.0}
COUPLING = {'g_per_am2': u.GAUSS_T, 't_per_am2': 1.0}
TIME = {'s': 1.0, 'min': 60.0}
MOMENT_OF_INERTIA = {**INERTIA, 'g_mm2': u.G_MM2_KG_M2}
TORQUE = {'ft_lb': u.FT_LB_NM, 'nm': 1.0}
#: The seed-000 dump gain k: amp-turn-m² per (ft-lb-sec · Wb/m²), or SI A·m²/(N·m·s·T) = 1/(s·T²).
DUMP_GAIN = {'am2_per_ftlbs_t': u.dump_gain_seed_to_si(1.0), 'per_s_t2': 1.0}

#: Every key a scenario may hold, by section ('' is the top level).
SCHEMA: dict[str, dict[str, Field]] = {
    '': {
        'name': Field('str', 'scenario name (the file stem; names the run folder)', pattern=SAFE_NAME),
        'description': Field('str', 'one line: what this scenario shows'),
        'seed': Field('int', 'random seed for every noise stream', 1, lo=0, hi=2**31 - 1),
        'control_period': _q('lockstep control period Δt (the DPA cycle)', 0.5, 's', TIME, lo=1e-3, hi=60.0),
        'duration': _q('run length (or duration_orbits)', REQUIRED, 's',
                       {**TIME, 'orbits': float('nan')}, lo=0.0, hi=30 * 86400.0),
        'nodes': Field('strs', 'nodes of the graph (a formation: its time owner formation_dynamics; each '
                       "vehicle's nodes are listed under vehicles)", ['rigid_body', 'reaction_wheels'],
                       choices=('rigid_body', 'reaction_wheels', 'magnetometer_sim', 'em_driver',
                                'acds_controller', 'ascs_mode_manager', 'formation_dynamics', 'cold_gas'), unique=True),
        'input_timeout': _q('wall time a node may wait for an input', 30.0, 's', TIME, lo=0.5, hi=3600.0),
    },
    'spacecraft': {
        'inertia': _q('inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (Table 4-1; products Ixy = ∫xy dm, '
                      'tensor I = [[Ixx,−Ixy,−Ixz],…]; |each| ≤ 1e9 kg·m², the ISS is ~1e8)', REQUIRED, 'kg_m2',
                      INERTIA, length=6, lo=-1e9, hi=1e9),
        'inertia_scale': Field('float', 'multiplies the whole tensor (Table 4-7 case 3: 2/3)', 1.0,
                               lo=0.01, hi=100.0),
        'initial_rates': _q('initial body rates ω0 (x, y, z)', [0.0, 0.0, 0.0], 'rad_s', RATE, length=3,
                            lo=-1.0, hi=1.0),
        'initial_quaternion_xyzw': Field('floats', 'initial attitude q body→ECI, scalar last',
                                         [0.0, 0.0, 0.0, 1.0], length=4, lo=-1.0, hi=1.0, quaternion=True),
    },
    'orbit': {
        'kind': Field('str', 'circular or elliptical (Kepler)', 'circular', choices=('circular', 'elliptical')),
        'altitude': _q('circular orbit altitude', 225 * u.NMI_M, 'm', LENGTH, lo=100e3, hi=1e8),
        'perigee_altitude': _q('elliptical: perigee altitude', 120 * u.NMI_M, 'm', LENGTH, lo=100e3, hi=1e8),
        'apogee_radius': _q('elliptical: apogee radius, geocentric', 5.2 * u.EARTH_RADIUS_M, 'm', RADIUS,
                            lo=6.4e6, hi=1e9),
        'inclination': _q('orbit inclination', 22.5 * _DEG, 'rad', ANGLE, lo=0.0, hi=math.pi),
        'raan': _q('right ascension of the ascending node', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'arg_latitude0': _q('circular: argument of latitude at t0', 0.0, 'rad', ANGLE,
                            lo=-2 * math.pi, hi=2 * math.pi),
        'arg_perigee': _q('elliptical: argument of perigee', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'mean_anomaly0': _q('elliptical: mean anomaly at t0', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
    },
    'earth': {
        'model': Field('str', 'Earth field: dipole (the study\'s tilted dipole, default) or igrf (IGRF-14 to degree 13, '
                       'ppigrf, at the epoch date; the dipole_* keys are then unused)', 'dipole',
                       choices=('dipole', 'igrf')),
        'epoch': _q('igrf: date at t0, decimal year (2025.5 = 2 July 2025; IGRF-14 spans 1900–2030)', 2025.0, 'year',
                    {'year': 1.0}, lo=1900.0, hi=2030.0),
        'greenwich_angle0': _q('Greenwich meridian from the vernal equinox at t0', 0.0, 'rad', ANGLE,
                               lo=-2 * math.pi, hi=2 * math.pi),
        'dipole_tilt': _q('dipole axis tilt from the spin axis (study: 11°)', 11 * _DEG, 'rad', ANGLE,
                          lo=0.0, hi=math.pi),
        'dipole_longitude': _q('dipole axis longitude offset from Greenwich (study: 20°)', 20 * _DEG, 'rad',
                               ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'dipole_moment': _q('Earth dipole moment', 7.94e22, 'am2', {'am2': 1.0}, lo=1e20, hi=1e24),
    },
    'sun': {
        'right_ascension': _q('sun right ascension (ECI)', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'declination': _q('sun declination (ECI)', 0.0, 'rad', ANGLE, lo=-math.pi / 2, hi=math.pi / 2),
        'eclipse': Field('bool', 'model the Earth shadow (cylindrical)', False),
    },
    'dynamics': {
        'gravity_gradient': Field('bool', 'apply the gravity-gradient torque', True),
        'substeps': Field('int', 'RK4 substeps per control period. Default 1, from the accuracy study '
                          '(tests/substep_study.py, HEAO-B at 0.5 s, against 100 substeps): after one orbit of '
                          'the 1 deg/s tumble the attitude is off by 6.7e-7 deg and the rates by 3.0e-9 deg/s '
                          '(torque-free and with gravity gradient; 2 substeps: 4.0e-8 deg, 5: 1.2e-9 deg, '
                          '10 and more: rounding, 3e-10 deg); Basilisk 2.12.1 at the same 0.5 s step differs '
                          'from 1 substep by 1e-7 deg and from its own 0.05 s run by 5.8e-7 deg. Closed loop '
                          '(heao_b_acquisition_fast_geometry, direct engine), 1, 2, 5, 10, 20 and 100 substeps '
                          'reach Mode 1B '
                          '(56.59 min) and capture (86.32 min) at the same step, final wheel momentum within '
                          '9e-6 ft-lb-s. Raise it for faster bodies or longer control periods', 1, lo=1, hi=10000),
    },
    'wheels': {
        'kind': Field('str', 'momentum store: wheels (square-law reaction wheels, spec §4) or cmg (ideal control '
                      'moment gyros, seed 000: the momentum rate the attitude loop asks, spherical capacity)',
                      'wheels', choices=('wheels', 'cmg')),
        'drive': Field('str', 'kind wheels: volts, square-law drive from the controller\'s volts (HEAO, spec §4); '
                       'torque, torque-commanded wheels (EMFFORCE, seed 004 slide 74) along torque_axes', 'volts',
                       choices=('volts', 'torque')),
        'layout': Field('str', 'volts drive: three_orthogonal or four_cant20 (spec §4)', 'three_orthogonal',
                        choices=('three_orthogonal', 'four_cant20')),
        'torque_axes': Field('floats', 'torque drive: unit wheel axes, body axes, one (x, y, z) triple per wheel '
                             '(EMFFORCE: one wheel about z)', [0.0, 0.0, 1.0], lo=-1.0, hi=1.0),
        'max_torque': _q('torque drive: torque limit of each wheel (EMFFORCE: 0.1 N·m)', 0.1, 'nm', {'nm': 1.0},
                         lo=1e-6, hi=1e4),
        'capacity': _q('torque drive: momentum capacity of each wheel (0: not given, unlimited)', 0.0, 'nms',
                       MOMENTUM, lo=0.0, hi=1e6),
        'failed_wheel': Field('int', 'index of a failed wheel of the 4-wheel cluster, −1 for none', -1,
                              lo=-1, hi=3),
        'initial_momentum': _q('initial wheel (or CMG) momentum, body axes', [0.0, 0.0, 0.0], 'nms', MOMENTUM,
                               length=3, lo=-1e5, hi=1e5),
        'cmg_capacity': _q('kind cmg: |h| capacity of the CMG momentum envelope (seed 000 §5: nearly 12,000 '
                           'ft-lb-sec)', 12000.0 * u.FT_LB_S_NMS, 'nms', MOMENTUM, lo=1.0, hi=1e6),
    },
    'disturbance': {
        'bias_momentum_per_orbit': _q('body-fixed disturbance: the bias momentum it delivers per orbit (a constant '
                                      'torque = this / orbit period), body axes; the gravity gradient is the '
                                      "rigid body's own (dynamics.gravity_gradient)", [0.0, 0.0, 0.0], 'nms',
                                      MOMENTUM, length=3, lo=-1e6, hi=1e6),
        'once_per_orbit_cos': _q('body-fixed cyclic torque, once per orbit: the cos u part (u = argument of '
                                 'latitude)', [0.0, 0.0, 0.0], 'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
        'once_per_orbit_sin': _q('body-fixed cyclic torque, once per orbit: the sin u part', [0.0, 0.0, 0.0], 'nm',
                                 TORQUE, length=3, lo=-1e3, hi=1e3),
        'twice_per_orbit_cos': _q('body-fixed cyclic torque, twice per orbit: the cos 2u part', [0.0, 0.0, 0.0],
                                  'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
        'twice_per_orbit_sin': _q('body-fixed cyclic torque, twice per orbit: the sin 2u part', [0.0, 0.0, 0.0],
                                  'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
    },
    # ---- magnetics hardware (spec §5, §6) -------------------------------------------------------
    'magnetometer': {
        'active_unit': Field('str', 'active magnetometer assembly', 'A', choices=('A', 'B')),
        'residual_field': _q('residual body-fixed field seen by the sensor (study: 1 % of max Earth field)',
                             [0.0, 0.0, 0.0], 't', FIELD, length=3, lo=-1e-4, hi=1e-4),
        'coupling_preset': Field('str', 'coupling Δ from the electromagnets: none, cruise (8.75e-6 G/(A·m²) '
                                 'per axis), acquisition (5 % of max field at 2000 A·m² on the other axes), '
                                 'custom (coupling matrix)', 'none',
                                 choices=('none', 'cruise', 'acquisition', 'custom')),
        'coupling': _q('custom coupling Δ, row-major 3×3 (sensor axis i, magnet j)', [0.0] * 9, 't_per_am2',
                       COUPLING, length=9, lo=-1e-6, hi=1e-6),
        'coupling_signs': Field('floats', 'acquisition preset: sign pattern, row-major 3×3 (±1)',
                                [1.0] * 9, length=9, lo=-1.0, hi=1.0),
        'noise_std': _q('seeded white noise per axis (0: off)', 0.0, 't', FIELD, lo=0.0, hi=1e-5),
        'accuracy_error': Field('bool', 'apply a seeded ±0.1 %-of-full-scale unit error', False),
        'fault': Field('str', 'fault injected at fault_time: none, bias_shift, stuck_axis, dead_unit', 'none',
                       choices=('none', 'bias_shift', 'stuck_axis', 'dead_unit')),
        'fault_unit': Field('str', 'assembly the fault hits', 'A', choices=('A', 'B')),
        'fault_axis': Field('int', 'axis for stuck_axis/bias_shift (−1: all)', -1, lo=-1, hi=2),
        'fault_value_v': Field('float', 'bias_shift size, V', 0.0, lo=-5.0, hi=5.0),
        'fault_time': _q('when the fault appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 10,
                                 lo=1, hi=10**6),
    },
    'em_driver': {
        'command_source': Field('str', 'node whose moment commands drive the coils', 'acds_controller',
                                choices=('acds_controller', 'ascs_mode_manager', 'formation_controller')),
        'driver_kind': Field('str', 'coil hardware: electromagnet (HEAO/SSS coils, drive_types and coil_* keys) '
                             'or torque_rod (CubeSat rods of seed 003 from torque_rod_design, PWM from supply_v)',
                             'electromagnet', choices=('electromagnet', 'torque_rod')),
        'torque_rod_design': Field('str', 'torque_rod: the rod of every axis, a `acds design-torque-rod --json` '
                                   'file (relative to the scenario file that names it)', '', path=True),
        'drive_types': Field('strs', 'electromagnet: per-axis drive, bridge_switch (HEAO) or constant_level (SSS), '
                             'or none (no coil on that axis)',
                             ['bridge_switch'] * 3, choices=('bridge_switch', 'constant_level', 'none'), length=3),
        'coil_resistance_ohm': Field('floats', 'per-axis winding resistance (Table 4-3: 30.3 Ω)', [30.3] * 3,
                                     length=3, lo=1e-3, hi=1e4),
        'coil_inductance_h': Field('floats', 'per-axis winding inductance (Table 4-3: 20.3 H)', [20.3] * 3,
                                   length=3, lo=1e-6, hi=1e3),
        'coil_moment_per_amp_am2': Field('floats', 'per-axis dipole per ampere (Table 4-3: 2062/0.727)',
                                         [2062 / 0.727] * 3, length=3, lo=1e-3, hi=1e5),
        'coil_max_moment_am2': Field('floats', 'per-axis saturation of the commanded dipole', [2062.0] * 3,
                                     length=3, lo=1e-3, hi=1e6),
        'supply_v': Field('float', 'power bus, V', 28.0, lo=1.0, hi=100.0),
        'epsilon': Field('float', 'hysteresis half-band ε (fraction of I_c)', 0.01, lo=1e-4, hi=0.5),
        'band_floor_a': Field('float', 'absolute floor of the band half-width (comparator offset), A', 4e-4,
                              lo=0.0, hi=0.1),
        'auto_switch_to_standby': Field('bool', 'switch an alarmed axis to its standby driver/winding', False),
        'mismatch_tolerance_frac': Field('float', 'e_ft vs command mismatch alarm, fraction of full scale',
                                         0.1, lo=0.001, hi=1.0),
        'failure': Field('str', 'failure injected at failure_time', 'none',
                         choices=('none', 'open_winding', 'stuck_on_bridge', 'dead_driver')),
        'failure_axis': Field('int', 'axis of the injected failure', 0, lo=0, hi=2),
        'failure_unit': Field('str', 'unit of the injected failure', 'A', choices=('A', 'B')),
        'failure_time': _q('when the failure appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'mismatch_settle': _q('how long the mismatch must persist before the alarm', 3.0, 's', TIME,
                              lo=0.0, hi=1e4),
        'bench_command': _q('fixed moment command applied when the command source is not in the graph',
                            [0.0, 0.0, 0.0], 'am2', {'am2': 1.0}, length=3, lo=-1e5, hi=1e5),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 10,
                                 lo=1, hi=10**6),
    },
    # ---- cold-gas reaction control subsystem (seed 002 §3.2, §5; cold_gas.rcs) -----------------------------
    'cold_gas': {
        'thrust': _q('thrust of each thruster at the regulator set point (§3.2: "nominal thrust in the 0.1 to 1 pound '
                     'range"; 0.5 lbf taken)', 0.5 * u.LBF_N, 'n', {'lbf': u.LBF_N, 'n': 1.0}, lo=1e-4, hi=1e3),
        'isp': _q('cold-nitrogen specific impulse (Table 5-3: every tank\'s impulse over its gas capacity is 65 s)',
                  65.0, 's', {'s': 1.0}, lo=1.0, hi=400.0),
        'valve_open_delay': _q('thruster valve opening delay (command to thrust; not in the seed)', 0.005, 's',
                               {'ms': 1e-3, 's': 1.0}, lo=0.0, hi=0.1),
        'valve_close_delay': _q('thruster valve closing delay (command end to thrust end; not in the seed)', 0.003,
                                's', {'ms': 1e-3, 's': 1.0}, lo=0.0, hi=0.1),
        'min_on_time': _q('minimum valve on-time: the minimum impulse bit (not in the seed)', 0.020, 's',
                          {'ms': 1e-3, 's': 1.0}, lo=1e-4, hi=1.0),
        'max_open_valves': Field('int', 'valves powered at once (Table 5-2: "maximum of two valves operating at one '
                                 'time", 12 W each)', 2, lo=1, hi=6),
        'tank_diameter': _q('inner diameter of each spherical tank (§3.2: 7.6 in)', 7.6 * u.INCH_M, 'm',
                            {'in': u.INCH_M, 'm': 1.0}, lo=0.01, hi=3.0),
        'tank_count': Field('int', 'tanks (§3.2: two)', 2, lo=1, hi=8),
        'load_mass': _q('GN₂ loaded in all tanks (§3.2: 4.6 lb)', 4.6 * u.LB_KG, 'kg', {'lb': u.LB_KG, 'kg': 1.0},
                        lo=1e-4, hi=1e3),
        'gas_temperature': _q('gas temperature (isothermal blowdown)', 293.0, 'k', {'k': 1.0}, lo=50.0, hi=500.0),
        'regulator_set_pressure': _q('regulator set point, absolute (not in the seed)', 150 * u.PSI_PA, 'pa',
                                     {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'pressure_switch_pressure': _q('over-pressure switch set point, absolute (not in the seed)', 200 * u.PSI_PA,
                                       'pa', {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'relief_pressure': _q('relief valve crack pressure, absolute (not in the seed)', 250 * u.PSI_PA, 'pa',
                              {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'manifold_volume': _q('low-pressure manifold volume, regulators to thruster valves', 50e-6, 'm3',
                              {'cm3': 1e-6, 'm3': 1.0}, lo=1e-7, hi=1e-2),
        'regulator_seat_area': _q('flow area of a failed-open regulator seat (fault regulator_fail_open)', 0.05e-6,
                                  'm2', {'mm2': 1e-6, 'm2': 1.0}, lo=0.0, hi=1e-3),
        'isolation_close_delay': _q('latching isolation valve closing time after the pressure switch trips', 0.030,
                                    's', {'ms': 1e-3, 's': 1.0}, lo=0.0, hi=1.0),
        'thruster_positions': _q('T1…T6 positions from the centre of mass, body axes, (x, y, z) each (default: the '
                                 'HEAO-B arrangement of acds_common.thrusters)', list(HEAO_B_POSITIONS_M), 'm',
                                 {'m': 1.0, 'ft': u.FOOT_M}, length=18, lo=-100.0, hi=100.0),
        'thruster_directions': Field('floats', 'T1…T6 thrust directions (force on the spacecraft), body axes',
                                     list(HEAO_B_DIRECTIONS), length=18, lo=-1.0, hi=1.0),
        'max_cross_coupling': Field('float', 'largest off-axis torque of a thruster, fraction of its on-axis torque',
                                    MAX_CROSS_COUPLING, lo=0.0, hi=1.0),
        'isolation_valves_open': Field('bool', 'both isolation valves open at t0', True),
        'bank_power': Field('bool', 'thruster bank power on at t0', True),
        'fault': Field('str', 'fault injected at fault_time', 'none', choices=COLD_GAS_FAULTS),
        'fault_index': Field('int', 'the thruster (1–6) or regulator (1–2) the fault hits', 1, lo=1, hi=6),
        'fault_time': _q('when the fault appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 20, lo=1, hi=10**6),
    },
    # ---- flight laws and modes (spec §7, §8) ----------------------------------------------------
    'controller': {
        'acquisition_law': Field('str', 'Mode 1A magnetic law (b_cross_omega: the CubeSat detumble law '
                                 'M = −(k_ω/|B|)(B̂ × ω) of seed 003)', 'bxh', choices=('bxh', 'bdot', 'b_cross_omega')),
        'unloading_law': Field('str', 'Mode 1B/cruise unloading law (b_cross_h: seed 003 dumping form '
                               'M = −(k_h/|B|)(B̂ × h))', 'bxh', choices=('bxh', 'lead', 'none', 'b_cross_h')),
        'acquisition_gain_per_s_g2': Field('float', 'B×H acquisition gain G, (s·G²)⁻¹', 0.05, lo=0.0, hi=10.0),
        'bdot_gain_ft_lb_s_per_g2': Field('float', 'B-dot gain K_D, ft-lb-s/G²', 1.0, lo=0.0, hi=1e4),
        'unloading_gain_mode_1b_per_s_g2': Field('float', 'unloading gain in Mode 1B', 0.05, lo=0.0, hi=10.0),
        'unloading_gain_scan_per_s_g2': Field('float', 'unloading gain, celestial scan', 0.01, lo=0.0, hi=10.0),
        'unloading_gain_point_per_s_g2': Field('float', 'unloading gain, celestial point', 0.02, lo=0.0, hi=10.0),
        'max_moment_am2': Field('float', 'per-axis moment command saturation', 2000.0, lo=1e-3, hi=1e6),
        # seed 003 gain design, k_ω = (4π/T_orb)(sin ξ + 1) J_min: the on-board design values (defaults: the seed's)
        'detumble_orbit_period': _q('b_cross_omega gain: orbit period T_orb (seed 003: ISS, 5560.8 s)', 5560.8, 's',
                                    TIME, lo=1e3, hi=1e6),
        'magnetic_inclination': _q('ξ, inclination of the orbit to the geomagnetic equator, for the b_cross_omega '
                                   'and b_cross_h gains (seed 003: 0.90129 rad, the ISS inclination)', 0.90129,
                                   'rad', ANGLE, lo=1e-3, hi=math.pi / 2),
        'detumble_j_min': _q('b_cross_omega gain: smallest principal moment of inertia J_min (seed 003: '
                             '5,094,047.43 g·mm²)', 5094047.43 * u.G_MM2_KG_M2, 'kg_m2', MOMENT_OF_INERTIA,
                             lo=1e-6, hi=1e9),
        'dump_time': _q('b_cross_h gain: dump the slowest momentum mode to dump_residual_fraction within this time '
                        '(seed 003: "say, 1 orbit of 90 minutes")', 5400.0, 's', TIME, lo=1.0, hi=1e7),
        'dump_residual_fraction': Field('float', 'b_cross_h gain: momentum left of the slowest mode after dump_time',
                                        0.1, lo=1e-6, hi=0.999),
        'coupling_compensation': Field('bool', 'subtract the known Δ·M from the sensed field', False),
        'wheel_gains': Field('str', 'acquisition wheel-law gains (Table 4-2)', 'heao_b',
                             choices=('heao_a', 'heao_b', 'heao_b_preliminary')),
        'scan_rate': _q('celestial scan rate about z', 0.03 * 2 * math.pi / 60, 'rad_s', RATE, lo=0.0, hi=0.1),
        'target_quaternion_xyzw': Field('floats', 'cruise target attitude q body→ECI', [0.0, 0.0, 0.0, 1.0],
                                        length=4, lo=-1.0, hi=1.0, quaternion=True),
        'lead_time_s': Field('float', 'lead law: wheel command → momentum lead time, s', 500.0, lo=0.0, hi=1e5),
        'adc_bits': Field('int', 'transfer assembly ADC width, bits', 10, lo=8, hi=24),
        'telemetry_every': Field('int', 'DPA/TA telemetry on diagnostics every N steps (and at every event)',
                                 20, lo=1, hi=10**6),
        # ---- AAP Workshop CMG momentum dump (seed 000), with wheels.kind cmg
        'dump_law': Field('str', 'Workshop dump law: khb (M = k H_s × B), khb_shifted (k (H_s − H_0) × B), '
                          'min_energy (eq. 3 on the predicted field), none (CMG hold only)', 'khb',
                          choices=('khb', 'khb_shifted', 'min_energy', 'none')),
        'dump_gain': _q('dump gain k (seed 000 §5: 4e6 amp-turn-m² per ft-lb-sec per Wb/m²)',
                        u.dump_gain_seed_to_si(4e6), 'per_s_t2', DUMP_GAIN, lo=0.0, hi=1e12),
        'dump_h_0': _q('khb_shifted: the shift H_0 of the region H_s settles in (§3)', [0.0, 0.0, 0.0], 'nms',
                       MOMENTUM, length=3, lo=-1e5, hi=1e5),
        'dump_bias_momentum': _q('bias momentum H_b per orbit known on board (§3): what min_energy dumps and the '
                                 '§5 initialisation uses', [0.0, 0.0, 0.0], 'nms', MOMENTUM, length=3,
                                 lo=-1e6, hi=1e6),
        'dump_h_s_init': Field('str', 'first H_s sample: measured (the CMG momentum as it is) or min_energy '
                               '(§5: k H_s of the first orbit set to eq. 3\'s bracket, kept as an offset)',
                               'measured', choices=('measured', 'min_energy')),
        'cmg_hold_bandwidth': _q('CMG attitude-hold closed-loop bandwidth ω_n (not in the seed)', 0.05, 'rad_s',
                                 RATE, lo=1e-6, hi=10.0),
        'cmg_hold_damping': Field('float', 'CMG attitude-hold damping ratio ζ (not in the seed)', 0.7,
                                  lo=0.0, hi=10.0),
        # ---- cold-gas acquisition law (seed 002 §3.1; acds_controller.cold_gas_law), with node cold_gas
        'gas_rate_deadband': _q('gas law: no pulse while every |ω_i − ω_ref,i| is within this', 0.02 * _DEG, 'rad_s',
                                RATE, lo=0.0, hi=0.1),
        'gas_position_gain': _q('gas law: rate reference per radian of sun-line error, ω_ref = −K·θ', 0.02, 'per_s',
                                {'per_s': 1.0}, lo=0.0, hi=10.0),
        'gas_slew_rate': _q('gas law: limit of |ω_ref| (the sun acquisition slew rate)', 0.5 * _DEG, 'rad_s', RATE,
                            lo=1e-5, hi=0.2),
    },
    'modes': {
        'system': Field('str', 'which mode logic runs: heao, heao_cold_gas (the study\'s recommended design: cold-gas '
                        'acquisition, wheels + magnetics cruise, seed 002 §3.1), sss or aap (the AAP Workshop CMG hold '
                        'and magnetic dump, seed 000)', 'heao', choices=('heao', 'heao_cold_gas', 'sss', 'aap')),
        'initial_mode': Field('str', 'mode at separation (aap: cmg_hold or cmg_dump; heao_cold_gas: a gas mode)',
                              'mode_1a', choices=('standby', 'mode_1a', 'mode_1b', 'celestial_scan', 'celestial_point',
                                                  'cmg_hold', 'cmg_dump', *GAS_MODES)),
        'rate_thresholds': _q('Mode 1A→1B body-rate thresholds |ω_x|, |ω_y|, |ω_z|',
                              [0.573 * _DEG, 0.115 * _DEG, 0.115 * _DEG], 'rad_s', RATE, length=3, lo=0.0, hi=1.0),
        'capture_cone': _q('acquisition capture: z within this angle of the sun', 10 * _DEG, 'rad', ANGLE,
                           lo=0.0, hi=math.pi),
        'capture_rate': _q('acquisition capture: every rate below this ("nulled")', 0.01 * _DEG, 'rad_s', RATE,
                           lo=0.0, hi=0.1),
        'cruise_target': Field('str', 'cruise mode after capture', 'celestial_point',
                               choices=('celestial_scan', 'celestial_point')),
        'auto_cruise': Field('bool', 'enter cruise automatically at capture (else by ground command)', False),
        'stop_at_capture': Field('bool', 'end the run at acquisition capture', False),
        'ground_commands': Field('strs', 'scheduled ground commands, "T_S: command"', []),
        'gas_damped_rate': _q('heao_cold_gas: gas rate damping → gas sun acquisition when every |ω_i| is below this',
                              0.05 * _DEG, 'rad_s', RATE, lo=0.0, hi=0.1),
        'gas_handover_cone': _q('heao_cold_gas: gas sun acquisition → Mode 1B (wheels) when z is within this of the '
                                'sun line …', 5 * _DEG, 'rad', ANGLE, lo=0.0, hi=math.pi),
        'gas_handover_rate': _q('heao_cold_gas: … and every |ω_i| is below this', 0.05 * _DEG, 'rad_s', RATE,
                                lo=0.0, hi=0.1),
    },
    'sss': {
        'polarity_level': _q('polarity-sensing level of the spin-plane magnetometer channel', 0.075 * u.GAUSS_T,
                             't', FIELD, lo=0.0, hi=1e-4),
        'hold_time_constant_s': Field('float', 'attitude/pass hold circuit RC time constant, s', 30.0,
                                      lo=0.1, hi=1e4),
        'mechanization': Field('str', 'spin-mode mechanization', 'one_channel_constant',
                               choices=('two_channel_sine', 'two_channel_constant', 'one_channel_sine',
                                        'one_channel_constant')),
        'hold_release_fraction': Field('float', 'hold circuit releases when its capacitor voltage falls below '
                                       'this fraction (hold time = RC·ln(1/fraction))', 0.5, lo=0.01, hi=0.99),
        'magnetometer_scale_v_per_g': Field('float', 'scale of the spin-plane magnetometer channel (body y) '
                                            'read against its bias reference, V/G (Table 4-5: 2.5)', 2.5,
                                            lo=0.01, hi=100.0),
        'bus_v': Field('float', 'main bus feeding the coils (seed 001: 28 V); sets the commanded dipoles',
                       28.0, lo=1.0, hi=100.0),
    },
    # ---- electromagnetic formation flight (spec §10; seed 004) ----------------------------------
    'formation': {
        'frame': Field('str', 'planar: the EMFFORCE air-bearing testbed (x, y, yaw); free_space: 3-D, no field; '
                       'hill: relative motion about a circular LEO orbit (Clohessy–Wiltshire)', 'planar',
                       choices=('planar', 'free_space', 'hill')),
        'em_model': Field('str', 'inter-vehicle wrench: far_field (exact dipole–dipole) or near_field (Biot–Savart '
                          'of the coils)', 'far_field', choices=('far_field', 'near_field')),
        'segments': Field('int', 'near field: straight segments per coil loop', 64, lo=3, hi=4096),
        'earth_field': Field('bool', 'hill: the Earth field\'s torque and force on every dipole (orbit, earth '
                             'sections)', True),
        'law': Field('str', 'hold: keep the second vehicle at relative_position from the first; spin_up: spin '
                     'the pair about the frame z axis', 'hold', choices=('hold', 'spin_up')),
        'relative_position': _q('hold: the second vehicle\'s position relative to the first, formation frame',
                                [2.5, 0.0, 0.0], 'm', LENGTH, length=3, lo=-1e5, hi=1e5),
        'hold_natural_frequency': _q('hold: PD natural frequency', 0.1, 'rad_s', {'rad_s': 1.0}, lo=1e-4, hi=10.0),
        'hold_damping_ratio': Field('float', 'hold: PD damping ratio', 0.9, lo=0.05, hi=5.0),
        'spin_rate': _q('spin_up: commanded rate of the array about the frame z axis', 0.05, 'rad_s', RATE,
                        lo=-1.0, hi=1.0),
        'spin_ramp': _q('spin_up: rate reference ramp', 1e-3, 'rad_s2', {'rad_s2': 1.0, 'deg_s2': _DEG},
                        lo=1e-7, hi=1.0),
        'spin_separation': _q('spin_up: separation held while spinning', 2.5, 'm', LENGTH, lo=0.01, hi=1e5),
        'spin_start': _q('spin_up: when the rate reference starts', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'radial_natural_frequency': _q('spin_up: radial PD natural frequency', 0.2, 'rad_s', {'rad_s': 1.0},
                                       lo=1e-4, hi=10.0),
        'radial_damping_ratio': Field('float', 'spin_up: radial PD damping ratio', 0.9, lo=0.05, hi=5.0),
        'rate_gain_per_s': Field('float', 'spin_up: rate loop gain, 1/s', 0.2, lo=0.0, hi=100.0),
        'attitude_natural_frequency': _q('attitude hold by the wheels: PD natural frequency', 0.5, 'rad_s',
                                         {'rad_s': 1.0}, lo=1e-4, hi=100.0),
        'attitude_damping_ratio': Field('float', 'attitude hold: PD damping ratio', 0.8, lo=0.05, hi=5.0),
        'max_force': _q('limit of the commanded relative force', 0.5, 'n', {'n': 1.0}, lo=0.0, hi=1e4),
        'dump': Field('bool', 'hill with the Earth field: Earth as a momentum dump (slides 31–33)', False),
        'dump_start': _q('dump: start dumping the vehicle whose wheels hold more than this', 0.5, 'nms', MOMENTUM,
                         lo=0.0, hi=1e6),
        'dump_done': _q('dump: stop (and pick again) below this', 0.05, 'nms', MOMENTUM, lo=0.0, hi=1e6),
    },
    'vehicle': {
        'mass': _q('vehicle mass', REQUIRED, 'kg', {'kg': 1.0, 'lb': u.LB_KG}, lo=1e-3, hi=1e7),
        'initial_position': _q('initial position, formation frame (hill: relative to the reference orbit)',
                               [0.0, 0.0, 0.0], 'm', LENGTH, length=3, lo=-1e7, hi=1e7),
        'initial_velocity': _q('initial velocity, formation frame', [0.0, 0.0, 0.0], 'm_s', {'m_s': 1.0},
                               length=3, lo=-1e4, hi=1e4),
        'coil_axes': Field('floats', 'unit axes of the coils in body axes, one (x, y, z) triple per coil, '
                           'orthonormal (EMFFORCE: two vertical coils along x and y)', [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                           lo=-1.0, hi=1.0),
        'coil_radii': _q('coil radii (EMFFORCE: 0.375 m outer, 0.345 m inner)', [0.375, 0.345], 'm', LENGTH,
                         lo=1e-3, hi=100.0),
        'coil_turns': Field('floats', 'turns of each coil (EMFFORCE: 100 wraps)', [100.0, 100.0], lo=1.0, hi=1e6),
        'coil_max_current': _q('current limit of each coil (EMFFORCE: ~100 A)', [100.0, 100.0], 'a', {'a': 1.0},
                               lo=1e-6, hi=1e5),
    },
}

#: Which scenario sections each node receives as parameters.
NODE_SECTIONS: dict[str, tuple[str, ...]] = {
    'rigid_body': ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics', 'em_driver', 'wheels', 'disturbance'),
    'reaction_wheels': ('wheels',),
    'magnetometer_sim': ('magnetometer',),
    'em_driver': ('em_driver',),
    'acds_controller': ('spacecraft', 'controller', 'magnetometer', 'wheels', 'orbit', 'earth', 'cold_gas'),
    'ascs_mode_manager': ('modes', 'sss'),
    'formation_dynamics': ('orbit', 'earth', 'sun', 'dynamics', 'formation'),
    'formation_controller': ('orbit', 'formation'),
    'cold_gas': ('cold_gas',),
}
#: Sections every vehicle of a formation has of its own (given under ``vehicles:``; a top-level
#: section of the same name gives the defaults all vehicles share).
VEHICLE_SECTIONS = ('spacecraft', 'vehicle', 'em_driver', 'wheels')
#: Per-vehicle sections the formation-wide nodes (time owner, controllers) receive for *every* vehicle,
#: named ``<vehicle>.<parameter>``.
FORMATION_VEHICLE_SECTIONS = ('spacecraft', 'vehicle', 'em_driver')
#: Nodes a vehicle of a formation may run (each in its namespace /acds/<vehicle>).
VEHICLE_NODES = ('em_driver', 'reaction_wheels', 'formation_controller')

#: Where shipped scenarios live (override with ACDS_SCENARIO_DIR).
SCENARIO_DIR = Path(os.environ.get('ACDS_SCENARIO_DIR', Path(__file__).resolve().parents[4] / 'scenarios'))


@dataclass(frozen=True)
class Scenario:
    """A validated scenario: SI values by section, plus where it came from."""

    name: str
    path: Path
    values: dict[str, dict[str, Any]]
    raw: dict[str, Any]

    def get(self, section: str, name: str) -> Any:
        """SI value of ``section.name``."""
        return self.values[section][name]

    @property
    def control_period_s(self) -> float:
        """Lockstep Δt, s."""
        return self.values['']['control_period']

    def orbit_period_s(self) -> float:
        """Orbital period from the orbit section (circular or Kepler)."""
        o = self.values['orbit']
        if o['kind'] == 'circular':
            a = u.EARTH_RADIUS_M + o['altitude']
        else:
            a = (u.EARTH_RADIUS_M + o['perigee_altitude'] + o['apogee_radius']) / 2.0
        return 2 * math.pi * math.sqrt(a**3 / u.EARTH_MU_M3_S2)

    def duration_s(self) -> float:
        """Run length, s (``duration_orbits`` × the orbit period when given in orbits)."""
        top = self.values['']
        if 'duration_orbits' in top:
            return top['duration_orbits'] * self.orbit_period_s()
        return top['duration']

    def total_steps(self) -> int:
        """Number of control steps in the run."""
        return max(1, round(self.duration_s() / self.control_period_s))

    @property
    def formation(self) -> bool:
        """Whether this is a formation of several vehicles (spec §10)."""
        return 'vehicles' in self.values

    def vehicle(self, name: str) -> dict[str, Any]:
        """One vehicle of a formation: {name, nodes, section: {field: SI value}}."""
        for v in self.values.get('vehicles', []):
            if v['name'] == name:
                return v
        raise KeyError(f'scenario {self.name} has no vehicle {name!r}')

    def node_parameters(self, node: str, vehicle: str = '') -> dict[str, Any]:
        """ROS parameters (SI, unit in the name) for ``node`` from its sections (a vehicle's node: its own).

        The formation-wide nodes (:data:`FORMATION_VEHICLE_SECTIONS`) also get every vehicle's sections,
        named ``<vehicle>.<parameter>``.
        """
        own = self.vehicle(vehicle) if vehicle else {}
        params: dict[str, Any] = {}
        for section in NODE_SECTIONS[node]:
            values = own.get(section, self.values.get(section))
            for name, f in SCHEMA[section].items():
                params[f.param_name(section, name)] = values[name]
        if node in ('formation_dynamics', 'formation_controller'):
            for v in self.values['vehicles']:
                for section in FORMATION_VEHICLE_SECTIONS:
                    for name, f in SCHEMA[section].items():
                        params[f'{v["name"]}.{f.param_name(section, name)}'] = v[section][name]
        return params


def scenario_path(name_or_path: str) -> Path:
    """Resolve a shipped scenario name or a path to a YAML file."""
    p = Path(name_or_path)
    if p.suffix in ('.yaml', '.yml') or p.exists():
        return p
    return SCENARIO_DIR / f'{name_or_path}.yaml'


def list_scenarios() -> list[tuple[str, str]]:
    """(name, description) of every shipped scenario."""
    out = []
    for p in sorted(SCENARIO_DIR.glob('*.yaml')):
        try:
            out.append((p.stem, load_scenario(str(p)).values['']['description']))
        except ScenarioError as exc:
            out.append((p.stem, f'INVALID: {exc}'))
    return out


class _ScenarioLoader(yaml.SafeLoader):
    """PyYAML's safe loader, strict where a scenario needs it.

    A key given twice in one mapping (at any level) is an error, not a silent
    override. Exponent floats without a dot (``2.25e2``, ``1e5``, ``-3E-2``) are
    floats, as in YAML 1.2 (PyYAML's YAML 1.1 rule needs a dot and a signed
    exponent); anything else that is not a number stays a string.
    """

    def construct_mapping(self, node: yaml.Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, yaml.Mark] = {}
            for key_node, _ in node.value:
                if key_node.tag == 'tag:yaml.org,2002:merge':
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    seen = first.get(key)
                except TypeError:  # unhashable: the base constructor says so
                    continue
                if seen is not None:
                    raise yaml.constructor.ConstructorError(
                        None, None, f'duplicate key {key!r} (first given on line {seen.line + 1})',
                        key_node.start_mark)
                first[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)


_ScenarioLoader.add_implicit_resolver(
    'tag:yaml.org,2002:float', re.compile(r'^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$'),
    list('-+0123456789.'))


def _read_text(path: Path) -> str:
    """The text of a scenario file, or one ScenarioError saying why it is not one."""
    if not path.exists():
        known = ', '.join(p.stem for p in sorted(SCENARIO_DIR.glob('*.yaml')))
        raise ScenarioError(f'scenario {path} not found (shipped: {known})')
    if path.is_dir():
        raise ScenarioError(f'{path}: is a directory, not a scenario file (give a YAML file or a shipped name)')
    if not path.is_file():
        raise ScenarioError(f'{path}: is not a regular file (a scenario is a YAML text file)')
    try:
        size = path.stat().st_size
        if size > MAX_SCENARIO_BYTES:
            raise ScenarioError(f'{path}: {size} bytes is too large for a scenario (limit {MAX_SCENARIO_BYTES})')
        data = path.read_bytes()
    except OSError as exc:
        raise ScenarioError(f'{path}: cannot be read: {exc.strerror or exc}') from None
    if b'\0' in data:
        raise ScenarioError(f'{path}: is a binary file, not YAML text (NUL byte at offset {data.index(0)})')
    try:
        return data.decode('utf-8-sig')
    except UnicodeDecodeError as exc:
        raise ScenarioError(f'{path}: is not UTF-8 text (byte 0x{data[exc.start]:02x} at offset {exc.start}); '
                            'a scenario is a UTF-8 YAML file') from None


def _extends_path(base: Any, child: Path) -> Path:
    """Where ``extends: base`` of ``child`` points: an absolute path as given; a relative path or a bare
    name first beside ``child``, then among the shipped scenarios."""
    if not isinstance(base, str) or not base.strip():
        raise ScenarioError(f'{child}: extends: expected a scenario name or a path, got {base!r}')
    rel = Path(base if Path(base).suffix in ('.yaml', '.yml') else f'{base}.yaml')
    candidates = [rel] if rel.is_absolute() else [child.parent / rel, SCENARIO_DIR / rel]
    for candidate in candidates:
        if candidate.exists():
            return candidate
    raise ScenarioError(f'{child}: extends: {base!r} not found (looked for {" and ".join(map(str, candidates))})')


def _read_yaml(path: Path, chain: tuple[Path, ...] = ()) -> dict[str, Any]:
    text = _read_text(path)
    if path.resolve() in chain:
        raise ScenarioError(f'{path}: "extends" loops back on itself')
    try:
        data = yaml.load(text, Loader=_ScenarioLoader)  # a SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        raise ScenarioError(f'{path}:{where} is not valid YAML: {getattr(exc, "problem", exc)}') from None
    if not isinstance(data, dict):
        raise ScenarioError(f'{path}: a scenario is a mapping of keys, got {type(data).__name__}')
    _resolve_paths(data, path)
    if 'extends' not in data:
        return data
    base = _read_yaml(_extends_path(data.pop('extends'), path), (*chain, path.resolve()))
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            merged = dict(base[key])
            for sub, v in value.items():  # a key given in another unit replaces the base's
                stem = _stem(key, sub)
                for old in [o for o in merged if _stem(key, o) == stem]:
                    del merged[old]
                merged[sub] = v
            base[key] = merged
        else:  # top level: a key given in another unit (duration_min vs duration_orbits) replaces the base's
            for old in [o for o in base if not isinstance(base[o], dict) and _stem('', o) == _stem('', key)]:
                del base[old]
            base[key] = value
    return base


def _resolve_paths(data: dict[str, Any], path: Path) -> None:
    """Make every file-name key (``Field.path``) this file gives absolute, relative to this file's folder.

    Done per file before ``extends`` merges them, so a base scenario's file names stay relative to the base.
    """
    for section, fields in SCHEMA.items():
        given = data if not section else data.get(section)
        if not isinstance(given, dict):
            continue
        for name, f in fields.items():
            value = given.get(name)
            if f.path and isinstance(value, str) and value and not Path(value).is_absolute():
                given[name] = str((path.parent / value).resolve())


def _stem(section: str, key: str) -> str:
    schema = SCHEMA.get(section, {})
    for name, f in schema.items():
        if key == name or any(key == f'{name}_{unit}' for unit in f.units):
            return name
    return key


def _show(v: Any) -> str:
    """``repr(v)``, shortened when huge (a 400-digit integer is named by its length)."""
    text = repr(v)
    if len(text) <= 40:
        return text
    if isinstance(v, int):
        return f'an integer with {len(str(abs(v)))} digits ({text[:8]}…)'
    return f'{text[:36]}…'


def _check_value(where: str, f: Field, value: Any, factor: float) -> Any:
    def out_of_range(v: Any) -> ScenarioError:
        def bound(b: float | None, none: str) -> str:
            return none if b is None else str(int(b)) if f.kind == 'int' else f'{b / factor:g}'
        lo, hi = bound(f.lo, '-inf'), bound(f.hi, 'inf')
        return ScenarioError(f'{where}: {_show(v)} is out of range [{lo}, {hi}]')

    def number(v: Any) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ScenarioError(f'{where}: expected a number, got {_show(v)}')
        try:
            x = float(v) * factor
        except OverflowError:  # an integer beyond any float
            raise out_of_range(v) from None
        if not math.isfinite(x):
            raise ScenarioError(f'{where}: {_show(v)} is not a finite number')
        if (f.lo is not None and x < f.lo) or (f.hi is not None and x > f.hi):
            raise out_of_range(v)
        return x

    if f.kind == 'float':
        return number(value)
    if f.kind == 'int':
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(f'{where}: expected an integer, got {_show(value)}')
        if (f.lo is not None and value < f.lo) or (f.hi is not None and value > f.hi):
            raise out_of_range(value)
        return value
    if f.kind == 'bool':
        if not isinstance(value, bool):
            raise ScenarioError(f'{where}: expected true or false, got {_show(value)}')
        return value
    if f.kind == 'str':
        if not isinstance(value, str):
            raise ScenarioError(f'{where}: expected a string, got {_show(value)}')
        if f.choices and value not in f.choices:
            raise ScenarioError(f'{where}: {_show(value)} is not one of {", ".join(f.choices)}')
        if f.pattern is not None and not f.pattern.fullmatch(value):
            raise ScenarioError(f'{where}: {_show(value)} is not a safe folder name (letters, digits, _ - . only, '
                                'not starting with ".", at most 100 characters)')
        return value
    if not isinstance(value, list):
        raise ScenarioError(f'{where}: expected a list, got {_show(value)}')
    if f.length is not None and len(value) != f.length:
        raise ScenarioError(f'{where}: expected {f.length} values, got {len(value)}')
    if f.kind == 'strs':
        bad = [v for v in value if not isinstance(v, str) or (f.choices and v not in f.choices)]
        if bad and not f.choices:
            raise ScenarioError(f'{where}: expected strings, got {_show(bad[0])}')
        if bad:
            raise ScenarioError(f'{where}: unknown {", ".join(map(_show, bad))} (known: {", ".join(f.choices)})')
        twice = sorted({v for v in value if value.count(v) > 1})
        if f.unique and twice:
            raise ScenarioError(f'{where}: {", ".join(twice)} listed more than once')
        return list(value)
    numbers = [number(v) for v in value]
    if f.quaternion:
        norm = math.sqrt(sum(x * x for x in numbers))
        if norm < MIN_QUATERNION_NORM:
            raise ScenarioError(f'{where}: {_show(value)} has norm {norm:g}: not an attitude quaternion '
                                f'(it cannot be normalised; |q| must be at least {MIN_QUATERNION_NORM:g})')
    return numbers


def _validate_section(path: Path, section: str, given: dict[str, Any], label: str | None = None) -> dict[str, Any]:
    schema = SCHEMA[section]
    prefix = f'{label if label is not None else section}.' if section else ''
    allowed: dict[str, tuple[str, str | None]] = {}
    for name, f in schema.items():
        if f.units:
            for unit in f.units:
                allowed[f'{name}_{unit}'] = (name, unit)
        else:
            allowed[name] = (name, None)
    out: dict[str, Any] = {}
    for key, value in given.items():
        if key not in allowed:
            hint = ', '.join(sorted(allowed))
            raise ScenarioError(f'{path}: unknown key "{prefix}{key}" (allowed here: {hint})')
        name, unit = allowed[key]
        if name in out or (name == 'duration' and 'duration_orbits' in out):
            raise ScenarioError(f'{path}: "{prefix}{name}" is given twice (in two units?)')
        f = schema[name]
        where = f'{path}: {prefix}{key}'
        if unit == 'orbits':
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= 1000:
                raise ScenarioError(f'{where}: expected a number of orbits in (0, 1000], got {value!r}')
            out['duration_orbits'] = float(value)
            continue
        out[name] = _check_value(where, f, value, f.units[unit] if unit else 1.0)
    for name, f in schema.items():
        if name not in out and not (name == 'duration' and 'duration_orbits' in out):
            if f.default is REQUIRED:
                units = ', '.join(f'{name}_{x}' for x in f.units) if f.units else name
                raise ScenarioError(f'{path}: missing required key "{prefix}{name}" (as {units})')
            out[name] = f.default
    return out


def _check_graph(path: Path, sc: Scenario) -> None:
    """Checks across keys: the node list can run, and the run has a bounded number of steps."""
    owner = 'formation_dynamics' if sc.formation else TIME_OWNER
    if owner not in sc.get('', 'nodes'):
        what = 'a formation\'s time owner' if sc.formation else 'it owns sim time; every graph has it'
        raise ScenarioError(f'{path}: nodes: {owner} is missing ({what})')
    if sc.formation and set(sc.get('', 'nodes')) != {owner}:
        raise ScenarioError(f'{path}: nodes: a formation lists only formation_dynamics at the top level; each '
                            'vehicle lists its own nodes (vehicles[].nodes)')
    if not sc.formation and 'formation_dynamics' in sc.get('', 'nodes'):
        raise ScenarioError(f'{path}: nodes: formation_dynamics needs a vehicles list')
    if not sc.formation:
        _check_workshop(path, sc)
        nodes = sc.get('', 'nodes')
        if 'ascs_mode_manager' in nodes and ('cold_gas' in nodes) != (sc.get('modes', 'system') == 'heao_cold_gas'):
            raise ScenarioError(f'{path}: modes.system: {sc.get("modes", "system")!r} with node cold_gas '
                                f'{"in" if "cold_gas" in nodes else "not in"} the graph (the heao_cold_gas mode logic '
                                'acquires on the cold-gas thrusters, and only it flies them)')
    if sc.get('earth', 'model') == 'igrf':
        end = decimal_year_datetime(sc.get('earth', 'epoch')) + datetime.timedelta(seconds=sc.duration_s())
        if end > decimal_year_datetime(IGRF_LAST_YEAR):
            raise ScenarioError(f'{path}: earth.epoch_year {sc.get("earth", "epoch"):g} + the run\'s duration ends '
                                f'{end:%Y-%m-%d}, after the IGRF-14 coefficients end ({IGRF_LAST_YEAR:g})')
    steps = round(sc.duration_s() / sc.control_period_s)
    if steps > MAX_STEPS:
        raise ScenarioError(f'{path}: duration / control_period give {steps:,} steps, more than the {MAX_STEPS:,} '
                            'a run may have (shorten duration_* or lengthen control_period_*)')


def _merge_units(section: str, base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over``'s keys over ``base``'s; a key given in another unit replaces the base's (as ``extends`` does)."""
    merged = dict(base)
    for key, value in over.items():
        stem = _stem(section, key)
        for old in [o for o in merged if _stem(section, o) == stem]:
            del merged[old]
        merged[key] = value
    return merged


def _validate_vehicles(path: Path, data: dict[str, Any]) -> list[dict[str, Any]]:
    """The ``vehicles`` of a formation: each a name, its nodes and its sections (over the top-level defaults)."""
    given = data['vehicles']
    if not isinstance(given, list) or len(given) < 2 or not all(isinstance(v, dict) for v in given):
        raise ScenarioError(f'{path}: vehicles: expected a list of at least two vehicles (mappings), got {_show(given)}')
    out: list[dict[str, Any]] = []
    for i, item in enumerate(given):
        where = f'vehicles[{i}]'
        unknown = sorted(set(item) - {'name', 'nodes', *VEHICLE_SECTIONS})
        if unknown:
            raise ScenarioError(f'{path}: {where}: unknown key "{unknown[0]}" (a vehicle has: name, nodes, '
                                f'{", ".join(VEHICLE_SECTIONS)})')
        name = item.get('name')
        if not isinstance(name, str) or not SAFE_NAME.fullmatch(name) or '.' in name:
            raise ScenarioError(f'{path}: {where}.name: {_show(name)} is not a vehicle name (letters, digits, _ -)')
        if any(v['name'] == name for v in out):
            raise ScenarioError(f'{path}: {where}.name: vehicle {name!r} is listed twice')
        nodes = item.get('nodes', list(VEHICLE_NODES))
        if not isinstance(nodes, list) or any(n not in VEHICLE_NODES for n in nodes) or len(set(nodes)) != len(nodes):
            raise ScenarioError(f'{path}: {where}.nodes: {_show(nodes)}: a vehicle runs distinct nodes of '
                                f'{", ".join(VEHICLE_NODES)}')
        vehicle: dict[str, Any] = {'name': name, 'nodes': list(nodes)}
        for section in VEHICLE_SECTIONS:
            own = item.get(section, {})
            if not isinstance(own, dict):
                raise ScenarioError(f'{path}: {where}.{section}: must be a mapping of keys, got {_show(own)}')
            vehicle[section] = _validate_section(path, section, _merge_units(section, data.get(section, {}), own),
                                                 label=f'vehicles.{name}.{section}')
        out.append(vehicle)
    return out

#: Mode names of the AAP Workshop (``modes.system: aap``, seed 000).
WORKSHOP_MODES = ('cmg_hold', 'cmg_dump')


def _check_workshop(path: Path, sc: Scenario) -> None:
    """The Workshop mode logic drives CMGs, and only it does; its modes are its own."""
    system, initial, kind = sc.get('modes', 'system'), sc.get('modes', 'initial_mode'), sc.get('wheels', 'kind')
    if (system == 'aap') != (initial in WORKSHOP_MODES):
        raise ScenarioError(f'{path}: modes.initial_mode: {initial!r} with modes.system {system!r} (the Workshop '
                            f'modes {", ".join(WORKSHOP_MODES)} belong to system aap, and only they)')
    if 'ascs_mode_manager' in sc.get('', 'nodes') and (system == 'aap') != (kind == 'cmg'):
        raise ScenarioError(f'{path}: wheels.kind: {kind!r} with modes.system {system!r} (the aap mode logic holds '
                            'the attitude with CMGs, wheels.kind cmg; the heao and sss logic drive wheels)')


def load_scenario(name_or_path: str) -> Scenario:
    """Read, merge (``extends``), validate and convert a scenario; raise ScenarioError on any problem.

    A formation (a ``vehicles`` list) validates each vehicle's :data:`VEHICLE_SECTIONS` from the
    vehicle's own keys over the top-level section of the same name (the shared defaults); its values
    are ``values['vehicles']``, a list of {name, nodes, section: {field: SI value}}.
    """
    path = scenario_path(name_or_path)
    data = _read_yaml(path)
    sections = [s for s in SCHEMA if s]
    formation = 'vehicles' in data
    for key, value in data.items():
        if isinstance(value, dict) and key not in SCHEMA:
            raise ScenarioError(f'{path}: unknown section "{key}" (sections: {", ".join(sections)})')
        if key in sections and not isinstance(value, dict):
            raise ScenarioError(f'{path}: "{key}" must be a mapping of keys, got {_show(value)}')
    if 'vehicle' in data and not formation:
        raise ScenarioError(f'{path}: "vehicle": a section of a formation\'s vehicles (give a vehicles list)')
    values: dict[str, Any] = {'': _validate_section(
        path, '', {k: v for k, v in data.items() if k not in sections and k != 'vehicles'})}
    for section in sections:
        if section in VEHICLE_SECTIONS and (formation or section == 'vehicle'):
            continue  # per vehicle (a formation's top-level section is the vehicles' shared defaults)
        values[section] = _validate_section(path, section, data.get(section, {}))
    if formation:
        values['vehicles'] = _validate_vehicles(path, data)
    sc = Scenario(values['']['name'], path, values, data)
    if path.parent == SCENARIO_DIR and sc.name != path.stem:
        raise ScenarioError(f'{path}: name "{sc.name}" differs from the file name "{path.stem}"')
    _check_graph(path, sc)
    return sc
