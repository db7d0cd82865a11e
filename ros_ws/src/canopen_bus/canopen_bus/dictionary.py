"""Object dictionaries and their PDOs: an OreSat card from ``oresat-configs`` or any device from an EDS/DCF (spec §13).

``load_dictionary('oresat1/adcs')`` is ``OreSatConfig('oresat1').od_db['adcs']``; a path ending in ``.eds``
or ``.dcf`` is read with ``canopen.import_od``. :func:`pdos` reads the TPDO/RPDO communication and mapping
parameters (0x1800/0x1A00, 0x1400/0x1600) from the dictionary itself: COB-ID, transmission type, event
timer and the mapped objects, each checked to fit the 8 bytes of a classic CAN frame.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import canopen
from canopen import objectdictionary as odict


class DictionaryError(ValueError):
    """An object dictionary or a mapping that does not fit (the message names the device and the object)."""


@dataclasses.dataclass(frozen=True)
class Pdo:
    """One PDO: number (1-based), COB-ID, transmission type, event timer (ms, 0: none) and mapped
    (index, subindex, bits)."""

    number: int
    cob_id: int
    transmission_type: int
    event_timer_ms: int
    mapped: tuple[tuple[int, int, int], ...]

    @property
    def bits(self) -> int:
        return sum(b for _i, _s, b in self.mapped)


@functools.lru_cache(maxsize=4)
def _oresat_config(mission: str):
    """oresat-configs' mission configuration (seconds to build: kept for the process)."""
    from oresat_configs import OreSatConfig
    return OreSatConfig(mission)


def load_dictionary(source: str, base: Path | None = None) -> odict.ObjectDictionary:
    """``MISSION/CARD`` (oresat-configs) or an EDS/DCF path (relative to ``base``) → the object dictionary."""
    if source.lower().endswith(('.eds', '.dcf')):
        path = Path(source) if base is None or Path(source).is_absolute() else base / source
        if not path.is_file():
            raise DictionaryError(f'object dictionary {source}: no such file ({path})')
        try:
            return canopen.import_od(str(path))
        except Exception as exc:  # canopen raises what its parser meets; name the file
            raise DictionaryError(f'object dictionary {path}: not a readable EDS/DCF ({exc})') from None
    mission, sep, card = source.partition('/')
    if not sep:
        raise DictionaryError(f'object dictionary {source!r}: expected MISSION/CARD (e.g. oresat1/adcs) or an .eds/.dcf')
    try:
        config = _oresat_config(mission)
    except Exception as exc:  # oresat-configs raises ValueError/KeyError for an unknown mission
        raise DictionaryError(f'object dictionary {source!r}: oresat-configs has no mission {mission!r} ({exc})') from None
    if card not in config.od_db:
        raise DictionaryError(f'object dictionary {source!r}: mission {mission} has no card {card!r} '
                              f'(cards: {", ".join(config.od_db)})')
    return config.od_db[card]


def variable(od: odict.ObjectDictionary, index: int, subindex: int, device: str) -> odict.ODVariable:
    """The OD variable at index:subindex, or DictionaryError naming what is missing."""
    if index not in od:
        raise DictionaryError(f'device {device}: object 0x{index:04X} not in its object dictionary')
    obj = od[index]
    if isinstance(obj, odict.ODVariable):
        if subindex:
            raise DictionaryError(f'device {device}: object 0x{index:04X} is a variable (no subindex {subindex})')
        return obj
    if subindex not in obj:
        raise DictionaryError(f'device {device}: object 0x{index:04X} ({obj.name}) has no subindex {subindex}')
    return obj[subindex]


def _default(od: odict.ObjectDictionary, index: int, sub: int) -> int:
    var = od[index][sub] if not isinstance(od[index], odict.ODVariable) else od[index]
    return int(var.default or 0)


def pdos(od: odict.ObjectDictionary, device: str, kind: str) -> list[Pdo]:
    """The device's TPDOs (``kind='tpdo'``) or RPDOs (``'rpdo'``) as its dictionary declares them; a mapped object
    missing from the dictionary or a PDO longer than 8 bytes raises DictionaryError."""
    comm0, map0 = (0x1800, 0x1A00) if kind == 'tpdo' else (0x1400, 0x1600)
    out = []
    for n in range(512):
        comm, mapping = comm0 + n, map0 + n
        if comm not in od or mapping not in od:
            continue
        count = _default(od, mapping, 0)
        mapped = []
        for sub in range(1, count + 1):
            word = _default(od, mapping, sub)
            index, subindex, bits = word >> 16, (word >> 8) & 0xFF, word & 0xFF
            var = variable(od, index, subindex, device)
            if len(var) != bits:
                raise DictionaryError(f'device {device}: {kind.upper()} {n + 1} maps 0x{index:04X}:{subindex} with '
                                      f'{bits} bits, the object has {len(var)}')
            mapped.append((index, subindex, bits))
        pdo = Pdo(n + 1, _default(od, comm, 1) & 0x7FF, _default(od, comm, 2),
                  _default(od, comm, 5) if kind == 'tpdo' and 5 in od[comm] else 0, tuple(mapped))
        if pdo.bits > 64:
            raise DictionaryError(f'device {device}: {kind.upper()} {pdo.number} (COB-ID 0x{pdo.cob_id:03X}) maps '
                                  f'{pdo.bits} bits, more than the 64 of a CAN frame')
        out.append(pdo)
    return out


def type_limits(var: odict.ODVariable) -> tuple[int, int]:
    """(min, max) an integer object can hold: the dictionary's own LowLimit/HighLimit where it gives them, else the
    data type's."""
    if var.data_type not in odict.INTEGER_TYPES:
        raise DictionaryError(f'object {var.name}: not an integer type (0x{var.data_type:X})')
    bits = len(var)
    signed = var.data_type in odict.SIGNED_TYPES
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    if var.min is not None:
        lo = max(lo, int(var.min))
    if var.max is not None:
        hi = min(hi, int(var.max))
    return lo, hi


def encode(var: odict.ODVariable, raw: int) -> bytes:
    """An integer object's bytes (little-endian, its own width)."""
    return var.encode_raw(raw)


def decode(var: odict.ODVariable, data: bytes) -> int:
    return int(var.decode_raw(data))


def pack_pdo(od: odict.ObjectDictionary, pdo: Pdo, values: dict[tuple[int, int], bytes]) -> bytes:
    """The PDO's payload from the objects' current bytes (whole-byte mappings, as every OreSat PDO is)."""
    out = b''
    for index, sub, bits in pdo.mapped:
        data = values[(index, sub)]
        out += data[: bits // 8]
    return out

