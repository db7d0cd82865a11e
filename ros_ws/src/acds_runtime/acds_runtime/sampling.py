"""Monte Carlo samples of a scenario's open conditions (seed 002 §4.3.1; issue 11).

The study leaves the conditions at separation open and says why they matter: "The momentum/field
relative orientation may be considered a random phenomenon" (§4.3.1, Initial Field/Momentum
Orientation). A *sample* is a complete scenario derived from a base scenario: the base's merged
keys with each drawn key replaced (in the unit the key names), named ``<base>_s<seed>k<index>``.

Reproducibility. Sample ``index`` of ``seed`` depends only on the base scenario, the seed, the index
and the distributions. Each drawn key has its own stream,
``numpy.random.SeedSequence(seed, spawn_key=(index, crc32(section.field)))`` — the child, keyed by
the scenario field, of ``SeedSequence(seed).spawn(n)[index]`` — so a sample is the same whatever the
number of samples, the worker that builds it, the order of the ``--vary`` options or the other keys
drawn; and scenarios drawn with the same seed (the cases of a paired sweep) get the same value of
every key they share: common random numbers.

Default draws (the open conditions of §4.3.1; overridden by a ``--vary`` of the same key):

- ``spacecraft.initial_quaternion_xyzw``: ``so3()``, uniform on SO(3) by Shoemake's method (K.
  Shoemake, "Uniform random rotations", Graphics Gems III, 1992): u1, u2, u3 ~ U[0, 1),
  q = (√(1−u1) sin 2πu2, √(1−u1) cos 2πu2, √u1 sin 2πu3, √u1 cos 2πu3), a uniform point on S³;
- ``orbit.raan_deg``, ``earth.greenwich_angle0_deg`` and the orbit phase at t0
  (``orbit.arg_latitude0_deg`` on a circular orbit, ``orbit.mean_anomaly0_deg`` on an elliptical
  one): ``uniform(0, 360)``;
- ``seed`` (the sample's noise streams): ``integers(0, 2³¹ − 1)``.

Distributions (``KEY=DIST``, KEY as in a scenario file, ``section.key_unit`` or a top-level key):

- ``uniform(a, b)``, ``normal(mu, sigma)``: numbers in the key's unit; a vector key draws each
  component independently (``spacecraft.initial_rates_deg_s=uniform(0.5, 1.0)``);
- ``choice(v1, v2, ...)``: one of the values, per component of a vector key
  (``magnetometer.coupling_signs=choice(1, -1)``), or one of whole vectors given as lists;
- ``integers(a, b)``: a whole number in [a, b] (integer keys);
- ``fixed(v)``: always ``v`` (a number for every component, or a whole list);
- ``so3()``: a uniform attitude (quaternion keys);
- ``h_parallel_b()``: the ``so3()`` draw turned by the smallest rotation that puts the body momentum
  I·ω0 along the Earth field at t0 (Table 4-7 case 4, "adverse initial alignment (B × H) t = t0 = 0",
  on the sample's own orbit and field geometry).

Derived geometry (:func:`initial_geometry`), from the dynamics' own model of the sample at t0: the
orbit's inclination to the dipole axis (angle between the orbit normal and the dipole axis; 22.5° ±
11° on the baseline orbit, depending on node RA, Greenwich angle and the pole's longitude), the angle
between the body momentum and B, and the z-body-to-sun angle.
"""

from __future__ import annotations

import array
import ast
import copy
import json
import math
import re
import tempfile
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import yaml
from acds_common import units
from acds_common.attitude import dcm_to_quat, quat_to_dcm, rotation_between
from acds_common.scenario import SAFE_NAME, SCHEMA, Field, Scenario, scenario_from_text  # noqa: F401 (the samples' loader)


class SamplingError(ValueError):
    """A ``--vary`` option, a sample reference or a drawn sample is not valid (the message names it)."""


#: Keys a distribution may not replace (the sampler sets them).
RESERVED = ('name', 'description')
#: Distribution names and what they take.
DISTRIBUTIONS = {
    'uniform': 'uniform(a, b): a ≤ b, numbers in the key\'s unit',
    'normal': 'normal(mu, sigma): sigma ≥ 0, numbers in the key\'s unit',
    'integers': 'integers(a, b): a whole number a ≤ n ≤ b, integer keys only',
    'choice': 'choice(v1, v2, ...): values (or whole lists) the key accepts',
    'fixed': 'fixed(v): one value (or a whole list)',
    'so3': 'so3(): uniform attitude, quaternion keys only',
    'h_parallel_b': 'h_parallel_b(): so3() turned to put I·ω0 along B at t0, quaternion keys only',
}
_DIST = re.compile(r'^\s*([a-z_0-9]+)\s*\((.*)\)\s*$', re.S)
#: libyaml's emitter when present (the same text as PyYAML's, faster).
_DUMPER = getattr(yaml, 'CSafeDumper', yaml.SafeDumper)
#: Largest seed (the schema's bound on the scenario's ``seed``; also the largest study seed).
MAX_SEED = 2**31 - 1


# ------------------------------------------------------------------------------------------ keys


def _resolve(section: str, key: str) -> tuple[str, str | None] | None:
    """(field name, unit) that the scenario key ``key`` of ``section`` sets, or None."""
    for name, f in SCHEMA[section].items():
        if not f.units and key == name:
            return name, None
        for unit in f.units:
            if key == f'{name}_{unit}':
                return name, unit
    return None


def _allowed(section: str) -> list[str]:
    return sorted(f'{n}_{u}' if u else n for n, f in SCHEMA[section].items() for u in (f.units or [None]))


@dataclass(frozen=True)
class Key:
    """A scenario key as a user writes it (``section.key_unit``), resolved against the schema."""

    section: str
    key: str
    name: str
    unit: str | None
    field: Field

    @property
    def label(self) -> str:
        """How the key is written (``orbit.raan_deg``; a top-level key bare)."""
        return f'{self.section}.{self.key}' if self.section else self.key

    @property
    def stream(self) -> str:
        """The key's random-stream name: the scenario field, whatever its unit (``orbit.raan``)."""
        return f'{self.section}.{self.name}' if self.section else self.name

    @property
    def length(self) -> int | None:
        """Components of a vector key, None for a scalar."""
        return self.field.length if self.field.kind in ('floats', 'strs') else None


def parse_key(text: str) -> Key:
    """``section.key_unit`` (or a top-level key) → :class:`Key`; SamplingError naming what is unknown."""
    section, dot, key = text.strip().rpartition('.')
    if not dot:
        section, key = '', text.strip()
    if section not in SCHEMA:
        raise SamplingError(f'{text!r}: unknown section {section!r} (sections: {", ".join(s for s in SCHEMA if s)})')
    found = _resolve(section, key)
    where = f'section {section!r}' if section else 'the top level'
    if found is None:
        raise SamplingError(f'{text!r}: unknown key {key!r} in {where} (allowed: {", ".join(_allowed(section))})')
    if not section and found[0] in RESERVED:
        raise SamplingError(f'{text!r}: {found[0]} is set by the sampler (each sample is named after its index)')
    return Key(section, key, found[0], found[1], SCHEMA[section][found[0]])


# -------------------------------------------------------------------------------- distributions


def uniform_quaternions(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` attitudes uniform on SO(3) as unit quaternions (x, y, z, w), Shoemake's method (module doc)."""
    u1, u2, u3 = rng.random((3, n))
    a, b = np.sqrt(1.0 - u1), np.sqrt(u1)
    return np.stack([a * np.sin(2 * np.pi * u2), a * np.cos(2 * np.pi * u2),
                     b * np.sin(2 * np.pi * u3), b * np.cos(2 * np.pi * u3)], axis=1)


@dataclass(frozen=True)
class Distribution:
    """One distribution over one key's values (module doc); ``text`` as the user wrote it."""

    kind: str
    args: tuple[Any, ...]
    text: str

    def draw(self, rng: np.random.Generator, key: Key) -> Any:
        """A value of ``key`` (a list for a vector key), in the key's unit. ``h_parallel_b`` draws its
        ``so3`` attitude here; :class:`Sampler` turns it once the rest of the sample is known."""
        if self.kind in ('so3', 'h_parallel_b'):
            return [float(c) for c in uniform_quaternions(rng, 1)[0]]
        if self.kind == 'integers':
            return int(rng.integers(self.args[0], self.args[1], endpoint=True))
        if self.kind == 'fixed':
            value = self.args[0]
            return list(value) if isinstance(value, list) else [value] * key.length if key.length else value
        if self.kind == 'choice' and all(isinstance(a, list) for a in self.args):
            return list(self.args[int(rng.integers(len(self.args)))])
        n = key.length or 1
        if self.kind == 'choice':
            values = [self.args[int(i)] for i in rng.integers(len(self.args), size=n)]
        elif self.kind == 'uniform':
            values = [float(v) for v in rng.uniform(self.args[0], self.args[1], size=n)]
        else:
            values = [float(v) for v in rng.normal(self.args[0], self.args[1], size=n)]
        return values if key.length else values[0]


def _literal(inner: str) -> list[Any]:
    """The arguments of ``name(...)``: Python literals, or bare words (``choice(bxh, bdot)``)."""
    if not inner.strip():
        return []
    try:
        value = ast.literal_eval(f'[{inner}]')
    except (ValueError, SyntaxError):
        if '[' in inner or '(' in inner:
            raise SamplingError(f'cannot read the arguments {inner!r}') from None
        return [w.strip() for w in inner.split(',')]
    return value


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


#: What one component of a key of each schema kind must be.
_COMPONENT = {'float': (_is_number, 'a finite number'), 'floats': (_is_number, 'finite numbers'),
              'int': (_is_int, 'an integer'), 'bool': (lambda v: isinstance(v, bool), 'true or false'),
              'str': (lambda v: isinstance(v, str), 'a string'), 'strs': (lambda v: isinstance(v, str), 'strings')}


def _check_value(key: Key, value: Any, what: str) -> None:
    """``value`` is of the kind ``key`` holds: one component, or a whole list of the right length."""
    if isinstance(value, list):
        if not key.length:
            raise SamplingError(f'{what}: {key.label} is a single value, got the list {value}')
        if len(value) != key.length:
            raise SamplingError(f'{what}: {key.label} has {key.length} components, got {len(value)}')
    ok, expect = _COMPONENT[key.field.kind]
    for v in value if isinstance(value, list) else [value]:
        if not ok(v):
            raise SamplingError(f'{what}: {key.label} takes {expect}, got {v!r}')


def parse_distribution(text: str, key: Key) -> Distribution:
    """``uniform(0.5, 1.0)`` etc. for ``key`` → :class:`Distribution`; SamplingError naming what is wrong."""
    m = _DIST.match(text)
    what = f'{key.label}={text}'
    if m is None:
        raise SamplingError(f'{what}: expected a distribution NAME(ARGS), one of {", ".join(DISTRIBUTIONS)}')
    kind = m.group(1)
    if kind not in DISTRIBUTIONS:
        raise SamplingError(f'{what}: unknown distribution {kind!r} (known: {"; ".join(DISTRIBUTIONS.values())})')
    try:
        args = _literal(m.group(2))
    except SamplingError as exc:
        raise SamplingError(f'{what}: {exc}') from None
    args = [list(a) if isinstance(a, tuple) else a for a in args]
    usage = DISTRIBUTIONS[kind]
    if kind in ('so3', 'h_parallel_b'):
        if args:
            raise SamplingError(f'{what}: {kind}() takes no arguments')
        if not key.field.quaternion:
            raise SamplingError(f'{what}: {kind}() draws an attitude: only for a quaternion key '
                                '(spacecraft.initial_quaternion_xyzw)')
    elif kind in ('uniform', 'normal'):
        if key.field.kind not in ('float', 'floats') or key.field.quaternion:
            raise SamplingError(f'{what}: {kind}() draws numbers; {key.label} is not a number key '
                                f'(use choice(...) or fixed(...){", or so3()" if key.field.quaternion else ""})')
        if len(args) != 2 or not all(_is_number(a) for a in args):
            raise SamplingError(f'{what}: expected {usage}')
        if kind == 'uniform' and args[0] > args[1]:
            raise SamplingError(f'{what}: uniform(a, b) needs a ≤ b')
        if kind == 'normal' and args[1] < 0:
            raise SamplingError(f'{what}: normal(mu, sigma) needs sigma ≥ 0')
        args = [float(a) for a in args]
    elif kind == 'integers':
        if key.field.kind != 'int':
            raise SamplingError(f'{what}: integers() draws whole numbers; {key.label} is not an integer key')
        if len(args) != 2 or not all(_is_int(a) for a in args) or args[0] > args[1]:
            raise SamplingError(f'{what}: expected {usage}')
    elif kind == 'fixed':
        if len(args) != 1:
            raise SamplingError(f'{what}: expected {usage}')
        _check_value(key, args[0], what)
    else:
        if not args:
            raise SamplingError(f'{what}: expected {usage}')
        whole = [isinstance(a, list) for a in args]
        if any(whole) and not all(whole):
            raise SamplingError(f'{what}: choice(...) takes either values or whole lists, not both')
        if key.field.quaternion and not all(whole):
            raise SamplingError(f'{what}: choose among whole quaternions ([x, y, z, w], ...)')
        for a in args:
            _check_value(key, a, what)
    return Distribution(kind, tuple(args), text.strip())


@dataclass(frozen=True)
class Variable:
    """A drawn key and its distribution."""

    key: Key
    dist: Distribution

    @property
    def text(self) -> str:
        """``KEY=DIST`` as on the command line."""
        return f'{self.key.label}={self.dist.text}'


def parse_vary(text: str) -> Variable:
    """``KEY=DIST`` → :class:`Variable`; SamplingError naming the bad key or distribution."""
    key, eq, dist = text.partition('=')
    if not eq or not key.strip() or not dist.strip():
        raise SamplingError(f'{text!r}: expected KEY=DIST, e.g. spacecraft.initial_rates_deg_s=uniform(0.5,1.0)')
    parsed = parse_key(key)
    return Variable(parsed, parse_distribution(dist, parsed))


def default_variables(base: Scenario) -> list[Variable]:
    """The open conditions of §4.3.1 drawn by default (module doc), for ``base``'s orbit kind."""
    phase = 'orbit.arg_latitude0_deg' if base.get('orbit', 'kind') == 'circular' else 'orbit.mean_anomaly0_deg'
    return [parse_vary(t) for t in ('spacecraft.initial_quaternion_xyzw=so3()', 'orbit.raan_deg=uniform(0, 360)',
                                    f'{phase}=uniform(0, 360)', 'earth.greenwich_angle0_deg=uniform(0, 360)',
                                    f'seed=integers(0, {MAX_SEED})')]


def stream(seed: int, index: int, key: Key) -> np.random.Generator:
    """The random stream of ``key`` in sample ``index`` of ``seed`` (module doc)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index, zlib.crc32(key.stream.encode()))))


# ---------------------------------------------------------------------------------------- samples


def parse_sample_ref(text: str) -> tuple[int, int]:
    """``S:K`` (seed S, sample index K) → (S, K)."""
    seed, colon, index = text.partition(':')
    try:
        s, k = int(seed), int(index)
    except ValueError:
        s = k = -1
    if not colon or s < 0 or k < 0:
        raise SamplingError(f'--sample {text!r}: expected SEED:INDEX, two whole numbers ≥ 0 (e.g. 1:17)')
    return s, k


def _set(raw: dict[str, Any], key: Key, value: Any) -> None:
    """Set ``key`` in the merged scenario data, replacing the same field given in any unit."""
    section = raw if not key.section else raw.setdefault(key.section, {})
    for old in list(section):
        if isinstance(section[old], dict) and not key.section:
            continue
        found = _resolve(key.section, old)
        if found is not None and found[0] == key.name:
            del section[old]
    section[key.key] = value


def _model(scenario: Scenario) -> Any:
    """The dynamics' rigid body of ``scenario`` at t0 (the very model its run starts from)."""
    from dynamics.configuration import RIGID_BODY_SECTIONS, build_rigid_body

    return build_rigid_body(*(scenario.values[s] for s in RIGID_BODY_SECTIONS))


def h_parallel_b_attitude(scenario: Scenario) -> list[float]:
    """``scenario``'s attitude turned by the smallest rotation that puts I·ω0 along B at t0 (case 4)."""
    model = _model(scenario)
    h_body = model.inertia_kg_m2 @ model.omega_body_rad_s
    if not np.linalg.norm(h_body) > 0.0:
        raise SamplingError(f'{scenario.name}: h_parallel_b(): the initial body momentum I·ω0 is zero')
    truth = model.truth(np.zeros(3))
    r_body_to_eci = quat_to_dcm(model.q_body_to_eci)
    turned = rotation_between(r_body_to_eci @ h_body, truth.b_eci_t) @ r_body_to_eci
    return [float(c) for c in dcm_to_quat(turned)]


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float | None:
    na, nb = float(np.linalg.norm(a)), float(np.linalg.norm(b))
    if not (na > 0.0 and nb > 0.0):
        return None
    return units.deg(math.acos(max(-1.0, min(1.0, float(a @ b) / (na * nb)))))


def initial_geometry(scenario: Scenario) -> dict[str, float | None]:
    """The sample's geometry at t0 (degrees), from the dynamics' own model (module doc)."""
    model = _model(scenario)
    truth = model.truth(np.asarray(scenario.get('wheels', 'initial_momentum'), dtype=float))
    normal = np.cross(truth.r_eci_m, truth.v_eci_m_s)
    return {
        'orbit_dipole_inclination_deg': _angle_deg(normal, model.field.dipole_axis_eci(truth.t_s)),
        'initial_h_b_angle_deg': _angle_deg(truth.h_total_body_nms, truth.b_body_t),
        'initial_sun_angle_deg': float(truth.attitude_to_sun_deg),
    }


@dataclass(frozen=True)
class Sample:
    """One drawn scenario: its index, the values drawn (in the keys' units), its YAML text and scenario."""

    seed: int
    index: int
    drawn: dict[str, Any]
    text: str
    scenario: Scenario

    def geometry(self) -> dict[str, float | None]:
        """:func:`initial_geometry` of the sample."""
        return initial_geometry(self.scenario)

    def kept(self) -> KeptSample:
        """What a study keeps of this sample while its samples run (:class:`KeptSample`)."""
        sc = self.scenario
        return KeptSample(self.seed, self.index, self.drawn, self.text, sc.name, self.geometry(),
                          (sc.total_steps(), sc.control_period_s))


@dataclass(frozen=True)
class KeptSample:
    """A drawn sample as a study keeps it: index, drawn values, YAML text, name, geometry at t0 and run length
    (steps, control period s). About 4 kB, where a :class:`Sample` holds its validated Scenario (about 27 kB): a
    study of N samples holds N of these, so its memory grows by that much a sample, not by the Scenario."""

    seed: int
    index: int
    drawn: dict[str, Any]
    text: str
    name: str
    geometry_t0: dict[str, float | None]
    length: tuple[int, float]

    def geometry(self) -> dict[str, float | None]:
        """:func:`initial_geometry` of the sample, computed when it was drawn."""
        return self.geometry_t0


class SpooledSamples(Sequence[KeptSample]):
    """A study's drawn samples as it keeps them (:class:`KeptSample`, appended in index order), each one JSON line
    in an anonymous temporary file (gone when the process ends, however it ends), read back when asked: in memory
    is only where each line is (16 bytes a sample), so a study's memory does not grow by ~4 kB a sample."""

    def __init__(self) -> None:
        self._file = tempfile.TemporaryFile(prefix='acds_samples_')  # noqa: SIM115 (lives as long as the study)
        self._where = array.array('q')

    def append(self, sample: KeptSample) -> None:
        """Keep ``sample`` (the next index)."""
        line = json.dumps([sample.seed, sample.index, sample.drawn, sample.text, sample.name, sample.geometry_t0,
                           list(sample.length)]).encode() + b'\n'
        self._file.seek(0, 2)
        self._where.extend((self._file.tell(), len(line)))
        self._file.write(line)

    def __len__(self) -> int:
        return len(self._where) // 2

    def __getitem__(self, i: int) -> KeptSample:  # type: ignore[override]
        if not -len(self) <= i < len(self):
            raise IndexError(i)
        i %= len(self)
        self._file.seek(self._where[2 * i])
        seed, index, drawn, text, name, geometry, (steps, period) = json.loads(self._file.read(self._where[2 * i + 1]))
        return KeptSample(seed, index, drawn, text, name, geometry, (steps, period))


def _name(base: str, seed: int, index: int) -> str:
    suffix = f'_s{seed}k{index}'
    name = base[:100 - len(suffix)] + suffix
    if not SAFE_NAME.fullmatch(name):
        raise SamplingError(f'cannot name sample {index} of {base!r} ({name!r} is not a safe folder name)')
    return name


class Sampler:
    """Samples of ``base``: the default draws, replaced or extended by ``vary`` (``KEY=DIST`` or
    :class:`Variable`); ``defaults=False`` draws only ``vary``."""

    def __init__(self, base: Scenario, seed: int, vary: Sequence[str | Variable] = (), *, defaults: bool = True,
                 command: str = '') -> None:
        if not 0 <= seed <= MAX_SEED:
            raise SamplingError(f'--seed {seed}: must be in [0, {MAX_SEED}]')
        self.base, self.seed, self.command = base, seed, command
        given = [v if isinstance(v, Variable) else parse_vary(v) for v in vary]
        streams = [v.key.stream for v in given]
        twice = sorted({s for s in streams if streams.count(s) > 1})
        if twice:
            raise SamplingError(f'--vary: {", ".join(twice)} given more than once')
        chosen = {v.key.stream: v for v in (default_variables(base) if defaults else [])}
        chosen.update({v.key.stream: v for v in given})
        #: Drawn keys in a fixed order: the defaults first, then the others as given.
        self.variables = list(chosen.values())

    def draw(self, index: int) -> Sample:
        """Sample ``index`` (≥ 0): a validated scenario."""
        if index < 0:
            raise SamplingError(f'sample index {index}: must be ≥ 0')
        raw = copy.deepcopy(self.base.raw)
        drawn: dict[str, Any] = {}
        for var in self.variables:
            rng = stream(self.seed, index, var.key)
            value = var.dist.draw(rng, var.key)
            drawn[var.key.label] = value
            _set(raw, var.key, value)
        name = _name(self.base.name, self.seed, index)
        raw['name'] = name
        raw['description'] = f'Monte Carlo sample {index} of seed {self.seed} of {self.base.name}'
        label = f'{self.base.name} sample {self.seed}:{index}'
        text = self._text(raw, index)
        scenario = scenario_from_text(text, label)
        for var in self.variables:
            if var.dist.kind == 'h_parallel_b':  # once the rest of the sample is known
                drawn[var.key.label] = h_parallel_b_attitude(scenario)
                _set(raw, var.key, drawn[var.key.label])
                text = self._text(raw, index)
                scenario = scenario_from_text(text, label)
        return Sample(self.seed, index, drawn, text, scenario)

    def _text(self, raw: dict[str, Any], index: int) -> str:
        head = [f'# Monte Carlo sample {index} of seed {self.seed}, derived from {self.base.name} ({self.base.path}).',
                '# Drawn: ' + '; '.join(f'{v.text}' for v in self.variables) + '.']
        if self.command:
            head.append(f'# Rerun through the full graph: {self.command}')
        return '\n'.join(head) + '\n' + yaml.dump(raw, Dumper=_DUMPER, sort_keys=False)


# ------------------------------------------------------------------------------ drawing a study's samples

#: A study draws its samples in parallel processes when it has at least this many (below, a process's start, ~0.4 s,
#: costs more than it saves: a draw is ~2-3 ms) ...
PARALLEL_DRAW_MIN = 2000
#: ... this many samples a task, at most two tasks a process ahead of the samples kept (the study's memory stays flat).
DRAW_CHUNK = 250
#: The sampler of a drawing process (:func:`_start_drawing`).
_drawing: Sampler | None = None


def kept_samples(sampler: Sampler, start: int, stop: int, processes: int, *, minimum: int = PARALLEL_DRAW_MIN,
                 chunk: int = DRAW_CHUNK) -> Iterator[KeptSample]:
    """Samples ``start`` … ``stop − 1`` of ``sampler`` as a study keeps them, in index order: drawn here, or, with
    ``processes`` > 1 and at least ``minimum`` of them, in that many processes (spawned: they inherit nothing of
    the study's process but the sampler) ``chunk`` at a time. The same samples either way: sample K depends only
    on the base, the seed, K and the distributions (module doc). Drawn here, a study's first seconds had one core
    working (10,000 samples: 24.4 s on the slower host of Measurements; 13.8 s in two processes). A drawing process
    ignores Ctrl-C (the study's process answers it, and stops them) and is killed with the study's process
    (:mod:`acds_common.parent_death`). A bad draw in a drawing process raises here the error the same draw raises
    here (:class:`SamplingError`, a scenario error); a drawing process that dies is a :class:`SamplingError`
    naming its samples."""
    if processes < 2 or stop - start < max(minimum, 2):
        for index in range(start, stop):
            yield sampler.draw(index).kept()
        return
    import multiprocessing
    import os
    from collections import deque
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    from .montecarlo import quiet_resource_tracker

    quiet_resource_tracker()  # the pool's queues' semaphores: unlinked by the tracker, without a report, if killed
    ranges = deque((a, min(a + chunk, stop)) for a in range(start, stop, chunk))
    pool = ProcessPoolExecutor(max_workers=processes, mp_context=multiprocessing.get_context('spawn'),
                               initializer=_start_drawing, initargs=(os.getpid(), sampler))
    try:
        ahead: deque[tuple[tuple[int, int], Any]] = deque()
        while ranges or ahead:
            while ranges and len(ahead) < 2 * processes:
                span = ranges.popleft()
                ahead.append((span, pool.submit(_draw_range, *span)))
            (first, last), future = ahead.popleft()
            try:
                drawn = future.result()
            except BrokenProcessPool as exc:
                raise SamplingError(f'a process drawing samples {first}–{last - 1} ended before it had drawn them '
                                    f'({exc})') from None
            yield from drawn
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _start_drawing(parent: int, sampler: Sampler) -> None:
    """A drawing process's start: killed with the study's process (gone already: leave), deaf to Ctrl-C."""
    import os
    import signal

    from acds_common.parent_death import die_with

    if not die_with(parent):
        os._exit(1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    global _drawing
    _drawing = sampler


def _draw_range(start: int, stop: int) -> list[KeptSample]:
    """Samples ``start`` … ``stop − 1``, in a drawing process, as a study keeps them."""
    assert _drawing is not None, 'a drawing process starts with its sampler'
    return [_drawing.draw(index).kept() for index in range(start, stop)]
