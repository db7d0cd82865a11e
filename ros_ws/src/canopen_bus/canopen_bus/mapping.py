"""The mapping file: graph quantities ↔ device objects, with the unit and scale of each object (spec §13).

A YAML file::

    devices:
      adcs:                                  # the device's name (its card)
        dictionary: oresat1/adcs             # MISSION/CARD of oresat-configs, or an .eds/.dcf path
        node_id: 0x38                        # optional: the dictionary's own by default
        tpdo_period_s: {1: 0.5}              # optional: PDO number → period, over the dictionary's event timer
        objects:
          - {index: 0x4000, subs: [1, 2, 3], quantity: body_rate, si_per_count: 0.001, unit: rad/s,
             full_scale: 8.73, noise_std: 0.0}
          - {index: 0x4007, subs: [4, 5, 6], quantity: coil_current_setpoint, si_per_count: 1.0e-6, unit: A}

Each object is three subindices of one record, a body-axis (or ECEF) vector. ``si_per_count``: the SI value of
one count (the firmware's scale: a count is rounded to the nearest and saturates at the object's limits,
the dictionary's LowLimit/HighLimit or its type's). ``magnetic_field`` is the truth field at the spacecraft;
``sensed_magnetic_field`` the field magnetometer_sim reports (with its faults: a stuck axis, a dead unit), when
that node is in the graph. Quantities (:data:`SENSORS`: the device sends them;
:data:`COMMANDS`: the flight computer writes them) and their SI units are fixed here; ``unit`` must name
that unit, so a file cannot scale a value it means in another. ``full_scale``: the largest |SI value| the
object must carry; a type that cannot hold it (full_scale / si_per_count beyond its limits) is refused.
``mounting``: a 3×3 rotation from the body axes to the sensor's (rows), ``noise_std``: the sensor's white
noise, SI, seeded per object from the scenario seed.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import yaml
from canopen import objectdictionary as odict

from canopen_bus.dictionary import DictionaryError, load_dictionary, pdos, type_limits, variable

#: Quantities a device sends (from the graph), by SI unit.
SENSORS = {'body_rate': 'rad/s', 'magnetic_field': 'T', 'sensed_magnetic_field': 'T', 'ecef_position': 'm',
           'ecef_velocity': 'm/s', 'coil_current': 'A', 'coil_duty': '1'}
#: Quantities the flight computer writes (to the graph), by SI unit.
COMMANDS = {'coil_current_setpoint': 'A'}
IDENTITY = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@dataclasses.dataclass(frozen=True)
class ObjectMap:
    """Three subindices of one record ↔ one vector quantity."""

    index: int
    subs: tuple[int, int, int]
    quantity: str
    si_per_count: float
    unit: str
    limits: tuple[tuple[int, int], ...]
    full_scale: float | None = None
    noise_std: float = 0.0
    mounting: tuple[tuple[float, float, float], ...] = IDENTITY
    name: str = ''

    @property
    def command(self) -> bool:
        return self.quantity in COMMANDS


@dataclasses.dataclass(frozen=True)
class DeviceMap:
    name: str
    dictionary: str
    od: odict.ObjectDictionary
    node_id: int
    tpdo_period_s: dict[int, float]
    objects: tuple[ObjectMap, ...]


def _need(entry: dict, key: str, where: str):
    if key not in entry:
        raise DictionaryError(f'{where}: missing key "{key}"')
    return entry[key]


def _object(device: str, od: odict.ObjectDictionary, i: int, entry: dict) -> ObjectMap:
    where = f'device {device} object {i + 1}'
    if not isinstance(entry, dict):
        raise DictionaryError(f'{where}: expected a mapping of keys, got {entry!r}')
    unknown = set(entry) - {'index', 'subs', 'quantity', 'si_per_count', 'unit', 'full_scale', 'noise_std', 'mounting'}
    if unknown:
        raise DictionaryError(f'{where}: unknown key "{sorted(unknown)[0]}"')
    index, quantity = _need(entry, 'index', where), _need(entry, 'quantity', where)
    units = {**SENSORS, **COMMANDS}
    if quantity not in units:
        raise DictionaryError(f'{where}: quantity "{quantity}" is none of {", ".join(units)}')
    unit = str(_need(entry, 'unit', where))
    if unit != units[quantity]:
        raise DictionaryError(f'{where}: {quantity} is in {units[quantity]}, the file says {unit}')
    subs = tuple(_need(entry, 'subs', where))
    if len(subs) != 3 or not all(isinstance(s, int) for s in subs):
        raise DictionaryError(f'{where}: subs must be three subindices, got {list(subs)}')
    scale = float(_need(entry, 'si_per_count', where))
    if not scale > 0:
        raise DictionaryError(f'{where}: si_per_count must be > 0, got {scale}')
    limits, names = [], []
    for s in subs:
        var = variable(od, index, s, device)
        try:
            limits.append(type_limits(var))
        except DictionaryError as exc:
            raise DictionaryError(f'{where}: 0x{index:04X}:{s} {exc}') from None
        names.append(var.name)
        writable = var.writable and quantity in COMMANDS
        if quantity in COMMANDS and not writable:
            raise DictionaryError(f'{where}: 0x{index:04X}:{s} ({var.name}) is read-only; the flight computer '
                                  f'cannot write {quantity}')
    full_scale = entry.get('full_scale')
    if full_scale is not None:
        counts = abs(float(full_scale)) / scale
        for s, (lo, hi) in zip(subs, limits, strict=True):
            if counts > hi or (lo < 0 and -counts < lo):
                raise DictionaryError(f'{where}: 0x{index:04X}:{s} holds {lo}..{hi} counts; full_scale {full_scale} '
                                      f'{unit} at {scale} {unit}/count needs ±{counts:.0f}')
    mounting = tuple(tuple(float(v) for v in row) for row in entry.get('mounting', IDENTITY))
    mounting = IDENTITY if mounting == IDENTITY else mounting
    if len(mounting) != 3 or any(len(r) != 3 for r in mounting):
        raise DictionaryError(f'{where}: mounting must be a 3×3 matrix (rows)')
    return ObjectMap(index, subs, quantity, scale, unit, tuple(limits), None if full_scale is None else float(full_scale),
                     float(entry.get('noise_std', 0.0)), mounting, od[index].name)


def load_mapping(path: Path) -> tuple[DeviceMap, ...]:
    """Read and check a mapping file against the devices' dictionaries; DictionaryError (one line) on any misfit."""
    try:
        data = yaml.safe_load(Path(path).read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise DictionaryError(f'mapping {path}: {exc}') from None
    if not isinstance(data, dict) or not isinstance(data.get('devices'), dict) or not data['devices']:
        raise DictionaryError(f'mapping {path}: expected a "devices" mapping of one or more devices')
    out, ids = [], {}
    for name, dev in data['devices'].items():
        if not isinstance(dev, dict):
            raise DictionaryError(f'mapping {path}: device {name}: expected a mapping of keys')
        try:
            source = str(_need(dev, 'dictionary', f'device {name}'))
            od = load_dictionary(source, Path(path).parent)
            node_id = int(dev.get('node_id', od.node_id or 0))
            if not 1 <= node_id <= 127:
                raise DictionaryError(f'device {name}: node id {node_id} outside 1..127')
            if node_id in ids:
                raise DictionaryError(f'device {name}: node id 0x{node_id:02X} is also device {ids[node_id]}\'s')
            ids[node_id] = name
            numbers = {p.number for p in pdos(od, name, 'tpdo')}
            periods = {int(k): float(v) for k, v in (dev.get('tpdo_period_s') or {}).items()}
            for number in periods:
                if number not in numbers:
                    raise DictionaryError(f'device {name}: tpdo_period_s names TPDO {number}; the dictionary has '
                                          f'{sorted(numbers)}')
            pdos(od, name, 'rpdo')
            objects = tuple(_object(name, od, i, e) for i, e in enumerate(dev.get('objects') or ()))
        except DictionaryError as exc:
            raise DictionaryError(f'mapping {path}: {exc}') from None
        out.append(DeviceMap(name, source, od, node_id, periods, objects))
    return tuple(out)
