"""Scenario files: schema, unit conversion, and the node parameters they become.

A scenario is a YAML file (``scenarios/<name>.yaml``). Quantities carry their
unit in the key, e.g. ``altitude_nmi: 225`` or ``inertia_slug_ft2: [...]``;
each field accepts a small set of units and is converted to SI here, the one
place where seed units meet SI (spec header "Units"). ``extends: <name>``
starts from another scenario and overrides keys (deep merge).

The schema is the single source of truth: node parameter names
(``<section>_<field>_<si unit>``), types, defaults, ranges and descriptions
all come from :data:`SCHEMA`; nodes declare their parameters from it, and the
launcher passes each node exactly the sections it owns (:data:`NODE_SECTIONS`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from acds_common import units as u


class ScenarioError(ValueError):
    """A scenario file is malformed: the message names the file and the key."""


REQUIRED = object()
_DEG = math.pi / 180.0


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

#: Every key a scenario may hold, by section ('' is the top level).
SCHEMA: dict[str, dict[str, Field]] = {
    '': {
        'name': Field('str', 'scenario name (the file stem)'),
        'description': Field('str', 'one line: what this scenario shows'),
        'seed': Field('int', 'random seed for every noise stream', 1, lo=0, hi=2**31 - 1),
        'control_period': _q('lockstep control period Δt (the DPA cycle)', 0.5, 's', TIME, lo=1e-3, hi=60.0),
        'duration': _q('run length (or duration_orbits)', REQUIRED, 's',
                       {**TIME, 'orbits': float('nan')}, lo=0.0, hi=30 * 86400.0),
        'nodes': Field('strs', 'nodes of the graph', ['rigid_body', 'reaction_wheels'],
                       choices=('rigid_body', 'reaction_wheels', 'magnetometer_sim', 'em_driver',
                                'acds_controller', 'ascs_mode_manager')),
        'input_timeout': _q('wall time a node may wait for an input', 30.0, 's', TIME, lo=0.5, hi=3600.0),
    },
    'spacecraft': {
        'inertia': _q('inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (Table 4-1; products Ixy = ∫xy dm, '
                      'tensor I = [[Ixx,−Ixy,−Ixz],…])', REQUIRED, 'kg_m2', INERTIA, length=6),
        'inertia_scale': Field('float', 'multiplies the whole tensor (Table 4-7 case 3: 2/3)', 1.0,
                               lo=0.01, hi=100.0),
        'initial_rates': _q('initial body rates ω0 (x, y, z)', [0.0, 0.0, 0.0], 'rad_s', RATE, length=3,
                            lo=-1.0, hi=1.0),
        'initial_quaternion_xyzw': Field('floats', 'initial attitude q body→ECI, scalar last',
                                         [0.0, 0.0, 0.0, 1.0], length=4, lo=-1.0, hi=1.0),
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
        'substeps': Field('int', 'RK4 substeps per control period', 10, lo=1, hi=10000),
    },
    'wheels': {
        'layout': Field('str', 'three_orthogonal or four_cant20 (spec §4)', 'three_orthogonal',
                        choices=('three_orthogonal', 'four_cant20')),
        'failed_wheel': Field('int', 'index of a failed wheel of the 4-wheel cluster, −1 for none', -1,
                              lo=-1, hi=3),
        'initial_momentum': _q('initial wheel momentum, body axes', [0.0, 0.0, 0.0], 'nms', MOMENTUM,
                               length=3, lo=-1e3, hi=1e3),
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
                                choices=('acds_controller', 'ascs_mode_manager')),
        'drive_types': Field('strs', 'per-axis drive: bridge_switch (HEAO) or constant_level (SSS)',
                             ['bridge_switch'] * 3, choices=('bridge_switch', 'constant_level'), length=3),
        'coil_resistance_ohm': Field('floats', 'per-axis winding resistance (Table 4-3: 30.3 Ω)', [30.3] * 3,
                                     length=3, lo=0.1, hi=1e4),
        'coil_inductance_h': Field('floats', 'per-axis winding inductance (Table 4-3: 20.3 H)', [20.3] * 3,
                                   length=3, lo=1e-6, hi=1e3),
        'coil_moment_per_amp_am2': Field('floats', 'per-axis dipole per ampere (Table 4-3: 2062/0.727)',
                                         [2062 / 0.727] * 3, length=3, lo=1e-3, hi=1e5),
        'coil_max_moment_am2': Field('floats', 'per-axis saturation of the commanded dipole', [2062.0] * 3,
                                     length=3, lo=1e-3, hi=1e5),
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
    # ---- flight laws and modes (spec §7, §8) ----------------------------------------------------
    'controller': {
        'acquisition_law': Field('str', 'Mode 1A magnetic law', 'bxh', choices=('bxh', 'bdot')),
        'unloading_law': Field('str', 'Mode 1B/cruise unloading law', 'bxh', choices=('bxh', 'lead', 'none')),
        'acquisition_gain_per_s_g2': Field('float', 'B×H acquisition gain G, (s·G²)⁻¹', 0.05, lo=0.0, hi=10.0),
        'bdot_gain_ft_lb_s_per_g2': Field('float', 'B-dot gain K_D, ft-lb-s/G²', 1.0, lo=0.0, hi=1e4),
        'unloading_gain_mode_1b_per_s_g2': Field('float', 'unloading gain in Mode 1B', 0.05, lo=0.0, hi=10.0),
        'unloading_gain_scan_per_s_g2': Field('float', 'unloading gain, celestial scan', 0.01, lo=0.0, hi=10.0),
        'unloading_gain_point_per_s_g2': Field('float', 'unloading gain, celestial point', 0.02, lo=0.0, hi=10.0),
        'max_moment_am2': Field('float', 'per-axis moment command saturation', 2000.0, lo=1.0, hi=1e5),
        'coupling_compensation': Field('bool', 'subtract the known Δ·M from the sensed field', False),
        'wheel_gains': Field('str', 'acquisition wheel-law gains (Table 4-2)', 'heao_b',
                             choices=('heao_a', 'heao_b', 'heao_b_preliminary')),
        'scan_rate': _q('celestial scan rate about z', 0.03 * 2 * math.pi / 60, 'rad_s', RATE, lo=0.0, hi=0.1),
        'target_quaternion_xyzw': Field('floats', 'cruise target attitude q body→ECI', [0.0, 0.0, 0.0, 1.0],
                                        length=4, lo=-1.0, hi=1.0),
        'lead_time_s': Field('float', 'lead law: wheel command → momentum lead time, s', 500.0, lo=0.0, hi=1e5),
        'adc_bits': Field('int', 'transfer assembly ADC width, bits', 10, lo=8, hi=24),
        'telemetry_every': Field('int', 'DPA/TA telemetry on diagnostics every N steps (and at every event)',
                                 20, lo=1, hi=10**6),
    },
    'modes': {
        'system': Field('str', 'which mode logic runs: heao or sss', 'heao', choices=('heao', 'sss')),
        'initial_mode': Field('str', 'mode at separation', 'mode_1a',
                              choices=('standby', 'mode_1a', 'mode_1b', 'celestial_scan', 'celestial_point')),
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
}

#: Which scenario sections each node receives as parameters.
NODE_SECTIONS: dict[str, tuple[str, ...]] = {
    'rigid_body': ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics'),
    'reaction_wheels': ('wheels',),
    'magnetometer_sim': ('magnetometer',),
    'em_driver': ('em_driver',),
    'acds_controller': ('spacecraft', 'controller', 'magnetometer', 'wheels'),
    'ascs_mode_manager': ('modes', 'sss'),
}

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

    def node_parameters(self, node: str) -> dict[str, Any]:
        """ROS parameters (SI, unit in the name) for ``node`` from its sections."""
        params: dict[str, Any] = {}
        for section in NODE_SECTIONS[node]:
            for name, f in SCHEMA[section].items():
                params[f.param_name(section, name)] = self.values[section][name]
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


def _read_yaml(path: Path, chain: tuple[Path, ...] = ()) -> dict[str, Any]:
    if not path.exists():
        known = ', '.join(n for n, _ in ((p.stem, '') for p in sorted(SCENARIO_DIR.glob('*.yaml'))))
        raise ScenarioError(f'scenario {path} not found (shipped: {known})')
    if path in chain:
        raise ScenarioError(f'{path}: "extends" loops back on itself')
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        mark = getattr(exc, 'problem_mark', None)
        where = f' line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        raise ScenarioError(f'{path}:{where} is not valid YAML: {getattr(exc, "problem", exc)}') from None
    if not isinstance(data, dict):
        raise ScenarioError(f'{path}: a scenario is a mapping of keys, got {type(data).__name__}')
    base_name = data.pop('extends', None)
    if base_name is None:
        return data
    base = _read_yaml(scenario_path(str(base_name)), (*chain, path))
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


def _stem(section: str, key: str) -> str:
    schema = SCHEMA.get(section, {})
    for name, f in schema.items():
        if key == name or any(key == f'{name}_{unit}' for unit in f.units):
            return name
    return key


def _check_value(where: str, f: Field, value: Any, factor: float) -> Any:
    def number(v: Any) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise ScenarioError(f'{where}: expected a number, got {v!r}')
        x = float(v) * factor
        if not math.isfinite(x):
            raise ScenarioError(f'{where}: {v!r} is not a finite number')
        if (f.lo is not None and x < f.lo) or (f.hi is not None and x > f.hi):
            lo = f.lo / factor if f.lo is not None else None
            hi = f.hi / factor if f.hi is not None else None
            raise ScenarioError(f'{where}: {v!r} is out of range [{lo:g}, {hi:g}]')
        return x

    if f.kind == 'float':
        return number(value)
    if f.kind == 'int':
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(f'{where}: expected an integer, got {value!r}')
        return int(number(value))
    if f.kind == 'bool':
        if not isinstance(value, bool):
            raise ScenarioError(f'{where}: expected true or false, got {value!r}')
        return value
    if f.kind == 'str':
        if not isinstance(value, str):
            raise ScenarioError(f'{where}: expected a string, got {value!r}')
        if f.choices and value not in f.choices:
            raise ScenarioError(f'{where}: {value!r} is not one of {", ".join(f.choices)}')
        return value
    if not isinstance(value, list):
        raise ScenarioError(f'{where}: expected a list, got {value!r}')
    if f.length is not None and len(value) != f.length:
        raise ScenarioError(f'{where}: expected {f.length} values, got {len(value)}')
    if f.kind == 'strs':
        if not f.choices:
            bad = [v for v in value if not isinstance(v, str)]
            if bad:
                raise ScenarioError(f'{where}: expected strings, got {bad[0]!r}')
            return list(value)
        bad = [v for v in value if v not in f.choices]
        if bad:
            raise ScenarioError(f'{where}: unknown {", ".join(map(str, bad))} (known: {", ".join(f.choices)})')
        return list(value)
    return [number(v) for v in value]


def _validate_section(path: Path, section: str, given: dict[str, Any]) -> dict[str, Any]:
    schema = SCHEMA[section]
    prefix = f'{section}.' if section else ''
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


def load_scenario(name_or_path: str) -> Scenario:
    """Read, merge (``extends``), validate and convert a scenario; raise ScenarioError on any problem."""
    path = scenario_path(name_or_path)
    data = _read_yaml(path)
    unknown = sorted(k for k, v in data.items() if isinstance(v, dict) and k not in SCHEMA)
    if unknown:
        raise ScenarioError(f'{path}: unknown section "{unknown[0]}" (sections: {", ".join(s for s in SCHEMA if s)})')
    values = {'': _validate_section(path, '', {k: v for k, v in data.items() if not isinstance(v, dict)})}
    for section in SCHEMA:
        if section:
            given = data.get(section, {})
            if not isinstance(given, dict):
                raise ScenarioError(f'{path}: "{section}" must be a mapping')
            values[section] = _validate_section(path, section, given)
    sc = Scenario(values['']['name'], path, values, data)
    if path.parent == SCENARIO_DIR and sc.name != path.stem:
        raise ScenarioError(f'{path}: name "{sc.name}" differs from the file name "{path.stem}"')
    return sc
