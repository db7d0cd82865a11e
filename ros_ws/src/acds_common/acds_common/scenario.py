"""Scenario files: schema, unit conversion, and the node parameters they become.

A scenario is a YAML file (``scenarios/<name>.yaml``; the shipped ones are found through the
``acds.scenarios`` entry point, :data:`SCENARIO_DIR`). Quantities carry their
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
``nodes`` must hold the declared time owner and no node twice; a run has
at most :data:`MAX_STEPS` steps; the packages' own checks across keys
(:attr:`acds_common.graph.Package.checks`) hold. A model's own checks (inertia positive
definite, apogee above perigee, ...) are the cores' and run in the launcher
before any process starts (:mod:`acds_runtime.preflight`).

The schema is the single source of truth: node parameter names
(``<section>_<field>_<si unit>``), types, defaults, ranges and descriptions
all come from :data:`SCHEMA`: the world's sections (:data:`WORLD`) and every
installed package's (:func:`acds_common.graph.declared_sections`); nodes declare
their parameters from it, and the launcher passes each node exactly the sections
its package declares it reads (:attr:`acds_common.graph.Node.sections`).
"""

from __future__ import annotations

import datetime
import functools
import json
import math
import os
import re
from collections.abc import Iterable
from dataclasses import dataclass
from importlib.metadata import entry_points
from importlib.resources import files
from pathlib import Path
from typing import Any

import yaml

from acds_common import units as u
from acds_common.environment import IGRF_LAST_YEAR, decimal_year_datetime
from acds_common.graph import (
    declared_node,
    declared_nodes,
    declared_sections,
    external_nodes,
    packages,
    time_owner_name,
)
from acds_common.schema import ANGLE, DEG, INERTIA, LENGTH, RADIUS, RATE, REQUIRED, TIME, Field, quantity


class ScenarioError(ValueError):
    """A scenario file is malformed: the message names the file and the key."""


#: Most control steps one run may have (the time owner's ``total_steps`` bound).
MAX_STEPS = 10**9
#: A scenario file larger than this is not a scenario (guards against reading a device or a data file).
MAX_SCENARIO_BYTES = 1 << 20
#: A quaternion shorter than this cannot be normalised to an attitude (the rigid body's own limit).
MIN_QUATERNION_NORM = 1e-6
#: ``name`` is used as a run-folder name: letters, digits, ``_ - .``, not starting with ``.``, ≤ 100 characters.
SAFE_NAME = re.compile(r'[A-Za-z0-9_-][A-Za-z0-9_.-]{0,99}')


#: The world's sections (the top level '' and the spacecraft, its orbit, the Earth, the sun), which the
#: scenario itself reads (the run length in orbits, the IGRF epoch); every other section is declared by
#: the package whose nodes read it (:class:`acds_common.graph.Package`).
WORLD: dict[str, dict[str, Field]] = {
    '': {
        'name': Field('str', 'scenario name (the file stem; names the run folder)', pattern=SAFE_NAME),
        'description': Field('str', 'one line: what this scenario shows'),
        'seed': Field('int', 'random seed for every noise stream', 1, lo=0, hi=2**31 - 1),
        'control_period': quantity('lockstep control period Δt (the DPA cycle)', 0.5, 's', TIME, lo=1e-3, hi=60.0),
        'duration': quantity('run length (or duration_orbits)', REQUIRED, 's',
                       {**TIME, 'orbits': float('nan')}, lo=0.0, hi=30 * 86400.0),
        'nodes': Field('strs', 'nodes of the graph (a formation: its time owner formation_dynamics; each '
                       "vehicle's nodes are listed under vehicles)", ['rigid_body', 'reaction_wheels'],
                       choices=tuple(n for n, (_pkg, node) in declared_nodes().items() if node.in_graph),
                       unique=True),
        'input_timeout': quantity('wall time a node may wait for an input (and the graph for its start, external '
                                  'nodes included)', 30.0, 's', TIME, lo=0.5, hi=3600.0),
        'external': Field('strs', 'nodes the user runs, "NODE" or "NODE=ROS_NODE_NAME" (issue 20; the launcher '
                          'starts the others and waits for these; acds run --external adds to them)', [], unique=True),
        'fsw_command': Field('str', 'montecarlo: the command that starts the external node for each sample, with '
                             'placeholders {domain}, {params}, {run_dir} (acds montecarlo --fsw-command gives the same)',
                             ''),
    },
    'spacecraft': {
        'inertia': quantity('inertia [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (Table 4-1; products Ixy = ∫xy dm, '
                      'tensor I = [[Ixx,−Ixy,−Ixz],…]; |each| ≤ 1e9 kg·m², the ISS is ~1e8)', REQUIRED, 'kg_m2',
                      INERTIA, length=6, lo=-1e9, hi=1e9),
        'inertia_scale': Field('float', 'multiplies the whole tensor (Table 4-7 case 3: 2/3)', 1.0,
                               lo=0.01, hi=100.0),
        'initial_rates': quantity('initial body rates ω0 (x, y, z)', [0.0, 0.0, 0.0], 'rad_s', RATE, length=3,
                            lo=-1.0, hi=1.0),
        'initial_quaternion_xyzw': Field('floats', 'initial attitude q body→ECI, scalar last',
                                         [0.0, 0.0, 0.0, 1.0], length=4, lo=-1.0, hi=1.0, quaternion=True),
    },
    'orbit': {
        'kind': Field('str', 'circular or elliptical (Kepler)', 'circular', choices=('circular', 'elliptical')),
        'altitude': quantity('circular orbit altitude', 225 * u.NMI_M, 'm', LENGTH, lo=100e3, hi=1e8),
        'perigee_altitude': quantity('elliptical: perigee altitude', 120 * u.NMI_M, 'm', LENGTH, lo=100e3, hi=1e8),
        'apogee_radius': quantity('elliptical: apogee radius, geocentric', 5.2 * u.EARTH_RADIUS_M, 'm', RADIUS,
                            lo=6.4e6, hi=1e9),
        'inclination': quantity('orbit inclination', 22.5 * DEG, 'rad', ANGLE, lo=0.0, hi=math.pi),
        'raan': quantity('right ascension of the ascending node', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'arg_latitude0': quantity('circular: argument of latitude at t0', 0.0, 'rad', ANGLE,
                            lo=-2 * math.pi, hi=2 * math.pi),
        'arg_perigee': quantity('elliptical: argument of perigee', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'mean_anomaly0': quantity('elliptical: mean anomaly at t0', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
    },
    'earth': {
        'model': Field('str', 'Earth field: dipole (the study\'s tilted dipole, default) or igrf (IGRF-14 to degree 13, '
                       'ppigrf, at the epoch date; the dipole_* keys are then unused)', 'dipole',
                       choices=('dipole', 'igrf')),
        'epoch': quantity('igrf: date at t0, decimal year (2025.5 = 2 July 2025; IGRF-14 spans 1900–2030)', 2025.0, 'year',
                    {'year': 1.0}, lo=1900.0, hi=2030.0),
        'greenwich_angle0': quantity('Greenwich meridian from the vernal equinox at t0', 0.0, 'rad', ANGLE,
                               lo=-2 * math.pi, hi=2 * math.pi),
        'dipole_tilt': quantity('dipole axis tilt from the spin axis (study: 11°)', 11 * DEG, 'rad', ANGLE,
                          lo=0.0, hi=math.pi),
        'dipole_longitude': quantity('dipole axis longitude offset from Greenwich (study: 20°)', 20 * DEG, 'rad',
                               ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'dipole_moment': quantity('Earth dipole moment', 7.94e22, 'am2', {'am2': 1.0}, lo=1e20, hi=1e24),
    },
    'sun': {
        'right_ascension': quantity('sun right ascension (ECI)', 0.0, 'rad', ANGLE, lo=-2 * math.pi, hi=2 * math.pi),
        'declination': quantity('sun declination (ECI)', 0.0, 'rad', ANGLE, lo=-math.pi / 2, hi=math.pi / 2),
        'eclipse': Field('bool', 'model the Earth shadow (cylindrical)', False),
    },
}
#: Every key a scenario may hold, by section ('' is the top level): the world's and every package's.
SCHEMA: dict[str, dict[str, Field]] = {**WORLD, **declared_sections()}
#: Sections every vehicle of a formation has of its own (given under ``vehicles:``; a top-level
#: section of the same name gives the defaults all vehicles share).
VEHICLE_SECTIONS = ('spacecraft', *(name for pkg in packages() for name in pkg.vehicle_sections))
#: Nodes a vehicle of a formation may run (each in its namespace /acds/<vehicle>).
VEHICLE_NODES = tuple(n for n, (_pkg, node) in declared_nodes().items() if node.in_vehicle)

#: Entry-point group naming the packages that ship scenarios, each in its ``scenarios`` package-data folder.
SCENARIO_ENTRY_POINTS = 'acds.scenarios'


def _shipped_dir() -> Path:
    """$ACDS_SCENARIO_DIR, else the ``scenarios`` folder of the package the ``shipped`` entry point names
    (``acds_cli``), else ``./scenarios`` (no such package installed: the nodes alone need none)."""
    if os.environ.get('ACDS_SCENARIO_DIR'):
        return Path(os.environ['ACDS_SCENARIO_DIR'])
    for ep in entry_points(group=SCENARIO_ENTRY_POINTS, name='shipped'):
        return Path(str(files(ep.module) / 'scenarios')).resolve()
    return Path('scenarios').resolve()


#: Where shipped scenarios live (override with ACDS_SCENARIO_DIR).
SCENARIO_DIR = _shipped_dir()
#: The file beside the shipped scenarios naming their roles: ``main_job`` (what ``acds run`` runs with no argument),
#: ``bench_flight_software`` (the flight-software sample of ``acds bench``: scenario, node, command),
#: ``sweep_groups`` (``acds sweep``'s group names → scenarios) and ``paired_case_vary`` (a case's own draws in a
#: paired sweep).
ROLES_FILE = 'roles.json'


@functools.cache
def shipped_role(role: str) -> Any:
    """What :data:`ROLES_FILE` gives ``role``: which shipped scenario plays it is data, so the runtime and the CLI name
    no scenario of a mission."""
    path = SCENARIO_DIR / ROLES_FILE
    try:
        return json.loads(path.read_text())[role]
    except (OSError, ValueError, KeyError) as exc:
        raise ScenarioError(f'{path}: no role {role!r} of the shipped scenarios ({exc})') from exc


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

    def instances(self) -> list[tuple[str, str, str]]:
        """(instance, node, vehicle) of every node of the graph: ``<node>`` for the whole graph's,
        ``<vehicle>/<node>`` for a formation vehicle's."""
        out = [(n, n, '') for n in self.get('', 'nodes')]
        for v in self.values.get('vehicles', []):
            out += [(f'{v["name"]}/{n}', n, v['name']) for n in v['nodes']]
        return out

    def external(self, extra: Iterable[str] = ()) -> dict[str, str]:
        """{instance: ROS identity} of the nodes the user runs: the scenario's ``external`` and ``extra`` (``acds run
        --external``); ValueError (one line) as :func:`acds_common.graph.external_nodes` raises it."""
        return external_nodes([*self.get('', 'external'), *extra], [i for i, _n, _v in self.instances()],
                              time_owner_name(self.formation))

    def vehicle(self, name: str) -> dict[str, Any]:
        """One vehicle of a formation: {name, nodes, section: {field: SI value}}."""
        for v in self.values.get('vehicles', []):
            if v['name'] == name:
                return v
        raise KeyError(f'scenario {self.name} has no vehicle {name!r}')

    def node_parameters(self, node: str, vehicle: str = '') -> dict[str, Any]:
        """ROS parameters (SI, unit in the name) for ``node`` from its sections (a vehicle's node: its own).

        A formation-wide node (:attr:`acds_common.graph.Node.every_vehicle`) also gets those sections of every
        vehicle, named ``<vehicle>.<parameter>``.
        """
        own = self.vehicle(vehicle) if vehicle else {}
        params: dict[str, Any] = {}
        _pkg, decl = declared_node(node)
        for section in decl.sections_in(inst for inst, _n, _v in self.instances()):
            values = own.get(section, self.values.get(section))
            for name, f in SCHEMA[section].items():
                params[f.param_name(section, name)] = values[name]
        if decl.every_vehicle:
            for v in self.values['vehicles']:
                for section in decl.every_vehicle:
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


class _WrittenScenarioLoader(yaml.cyaml.CParser, _ScenarioLoader):
    """:class:`_ScenarioLoader` on libyaml's parser (the same constructor, resolvers and duplicate-key rule: the same
    data), about 8× faster, for scenario text the project wrote itself (a drawn sample, :func:`scenario_from_text`):
    its messages on malformed YAML are libyaml's, so a user's file keeps the pure-Python parser's."""

    def __init__(self, stream: str) -> None:
        yaml.cyaml.CParser.__init__(self, stream)
        yaml.constructor.SafeConstructor.__init__(self)
        yaml.resolver.Resolver.__init__(self)


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


def extends_chain(path: Path) -> list[Path]:
    """The scenario file ``path`` and every file its ``extends`` reaches, in order (what its content depends on)."""
    chain = [path]
    while isinstance(data := yaml.load(_read_text(chain[-1]), Loader=_ScenarioLoader), dict) and 'extends' in data:
        chain.append(_extends_path(data['extends'], chain[-1]))
        if chain[-1].resolve() in {c.resolve() for c in chain[:-1]}:
            raise ScenarioError(f'{chain[-1]}: "extends" loops back on itself')
    return chain


def _read_yaml(path: Path, chain: tuple[Path, ...] = (), written: str | None = None) -> dict[str, Any]:
    """The merged data of the scenario file ``path`` (``written``: its text, written by the project, not read)."""
    text = _read_text(path) if written is None else written
    if path.resolve() in chain:
        raise ScenarioError(f'{path}: "extends" loops back on itself')
    try:
        data = yaml.load(text, Loader=_ScenarioLoader if written is None else _WrittenScenarioLoader)
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
    # A key given in another unit replaces the base's, never one the extending file gives itself: its own
    # two units of one key stay both, for the schema to refuse as a key given twice.
    top = {_stem('', key) for key, value in data.items() if not (isinstance(value, dict)
                                                                and isinstance(base.get(key), dict))}
    for old in [o for o in base if not isinstance(base[o], dict) and _stem('', o) in top]:
        del base[old]  # top level: duration_min vs duration_orbits
    for key, value in data.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            base[key] = _merge_units(key, base[key], value)
        else:
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
    owner = time_owner_name(sc.formation)
    if owner not in sc.get('', 'nodes'):
        what = 'a formation\'s time owner' if sc.formation else 'it owns sim time; every graph has it'
        raise ScenarioError(f'{path}: nodes: {owner} is missing ({what})')
    if sc.formation and set(sc.get('', 'nodes')) != {owner}:
        raise ScenarioError(f'{path}: nodes: a formation lists only {owner} at the top level; each '
                            'vehicle lists its own nodes (vehicles[].nodes)')
    formation_owner = time_owner_name(True)
    if not sc.formation and formation_owner in sc.get('', 'nodes'):
        raise ScenarioError(f'{path}: nodes: {formation_owner} needs a vehicles list')
    try:
        sc.external()
    except ValueError as exc:
        raise ScenarioError(f'{path}: external: {exc}') from None
    for pkg in packages():
        for check in pkg.checks:
            problem = check(sc)
            if problem:
                raise ScenarioError(f'{path}: {problem}')
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
    stems = {_stem(section, key) for key in over}
    merged = {key: value for key, value in base.items() if _stem(section, key) not in stems}
    merged.update(over)  # ``over``'s own two units of one key both stay: the schema refuses them as given twice
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

def load_scenario(name_or_path: str) -> Scenario:
    """Read, merge (``extends``), validate and convert a scenario; raise ScenarioError on any problem.

    A formation (a ``vehicles`` list) validates each vehicle's :data:`VEHICLE_SECTIONS` from the
    vehicle's own keys over the top-level section of the same name (the shared defaults); its values
    are ``values['vehicles']``, a list of {name, nodes, section: {field: SI value}}.
    """
    return _load(scenario_path(name_or_path), None)


def scenario_from_text(text: str, label: str = 'sample') -> Scenario:
    """A scenario the project wrote as YAML text (a drawn sample crosses to its worker as text), loaded as
    :func:`load_scenario` loads a file, without a file: its path, in its errors, is ``label``; relative file names
    in it are relative to the working folder. Parsed by libyaml (:class:`_WrittenScenarioLoader`)."""
    return _load(Path(label), text)


def _load(path: Path, written: str | None) -> Scenario:
    data = _read_yaml(path, written=written)
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
