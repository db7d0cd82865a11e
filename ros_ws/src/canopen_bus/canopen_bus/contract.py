"""The CANopen side of the canopen_cards node's contract, and each device's EDS (spec §13).

Declared in the entry-point group ``acds.contract``: ``acds contract SCENARIO --node canopen_cards`` (every
device) or ``--node DEVICE`` (one device of the mapping, e.g. ``adcs``) adds, from the same mapping and object
dictionaries the cards run: node id, the heartbeat and SDO COB-IDs, each TPDO (COB-ID, period, mapped
objects) and RPDO, and each mapped object (index:sub, name, type, access, the dictionary's unit and scale, the
mapping's SI per count, quantity, limits). ``--format eds`` writes the device's EDS (``canopen.export_od`` of
the dictionary the device serves, with its node id).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from canopen import objectdictionary as odict

from canopen_bus.dictionary import pdos

NODE = 'canopen_cards'
#: The formats this plug-in writes, beyond the contract's own.
FORMATS = {'eds': "the device's Electronic Data Sheet (one device: --node DEVICE)"}
TYPE_NAMES = {odict.BOOLEAN: 'BOOLEAN', odict.INTEGER8: 'INTEGER8', odict.INTEGER16: 'INTEGER16',
              odict.INTEGER32: 'INTEGER32', odict.INTEGER64: 'INTEGER64', odict.UNSIGNED8: 'UNSIGNED8',
              odict.UNSIGNED16: 'UNSIGNED16', odict.UNSIGNED32: 'UNSIGNED32', odict.UNSIGNED64: 'UNSIGNED64',
              odict.REAL32: 'REAL32', odict.REAL64: 'REAL64', odict.VISIBLE_STRING: 'VISIBLE_STRING',
              odict.OCTET_STRING: 'OCTET_STRING', odict.DOMAIN: 'DOMAIN'}


def _maps(scenario: Any) -> tuple:
    from canopen_bus.mapping import load_mapping
    return load_mapping(Path(scenario.get('can_bus', 'mapping')))


def resolve(scenario: Any, name: str) -> tuple[str, str] | None:
    """(graph node, device or '') when ``name`` is the cards node or one of its devices; None otherwise."""
    if NODE not in scenario.get('', 'nodes'):
        return None
    if name == NODE:
        return NODE, ''
    return (NODE, name) if any(m.name == name for m in _maps(scenario)) else None


def _var(od: odict.ObjectDictionary, index: int, sub: int) -> odict.ODVariable:
    obj = od[index]
    return obj if isinstance(obj, odict.ODVariable) else obj[sub]


def _device(m: Any, rate_of: dict[int, float]) -> dict[str, Any]:
    objects = []
    for o in m.objects:
        for sub, (lo, hi) in zip(o.subs, o.limits, strict=True):
            var = _var(m.od, o.index, sub)
            objects.append({'object': f'0x{o.index:04X}:{sub}', 'name': f'{o.name}.{var.name}',
                            'type': TYPE_NAMES.get(var.data_type, hex(var.data_type)), 'access': var.access_type,
                            'od_unit': var.unit or None, 'od_scale': var.factor, 'quantity': o.quantity,
                            'si_unit': o.unit, 'si_per_count': o.si_per_count, 'limits': [lo, hi],
                            'direction': 'flight computer → card (SDO/RPDO)' if o.command else 'card → bus (TPDO/SDO)'})
    tpdos = [{'number': p.number, 'cob_id': f'0x{p.cob_id:03X}', 'period_s': rate_of.get(p.number, p.event_timer_ms / 1e3),
              'mapped': [f'0x{i:04X}:{s} ({_var(m.od, i, s).name}, {b} bits)' for i, s, b in p.mapped]}
             for p in pdos(m.od, m.name, 'tpdo')]
    rpdos = [{'number': p.number, 'cob_id': f'0x{p.cob_id:03X}',
              'mapped': [f'0x{i:04X}:{s} ({_var(m.od, i, s).name}, {b} bits)' for i, s, b in p.mapped]}
             for p in pdos(m.od, m.name, 'rpdo')]
    hb = int(m.od[0x1017].default or 0) if 0x1017 in m.od else 0
    return {'device': m.name, 'dictionary': m.dictionary, 'node_id': f'0x{m.node_id:02X}',
            'heartbeat': {'cob_id': f'0x{0x700 + m.node_id:03X}', 'period_ms': hb},
            'sdo': {'request_cob_id': f'0x{0x600 + m.node_id:03X}', 'reply_cob_id': f'0x{0x580 + m.node_id:03X}'},
            'nmt_cob_id': '0x000', 'tpdos': tpdos, 'rpdos': rpdos, 'objects': objects}


def extend(scenario: Any, contract: dict[str, Any], device: str) -> None:
    """Add ``canopen``: the CANopen side of the devices (one when ``device`` names it)."""
    c = scenario.values['can_bus']
    contract['canopen'] = {
        'bus': 'socketcand protocol over TCP (acds run prints HOST:PORT; default 127.0.0.1:29536), channel vcan0',
        'flight_computer': {'node_id': f'0x{c["flight_computer_node_id"]:02X}',
                            'heartbeat_cob_id': f'0x{0x700 + c["flight_computer_node_id"]:03X}',
                            'heartbeat_timeout_s': c['heartbeat_timeout'], 'on_loss': c['on_heartbeat_loss']},
        'sample_and_hold': 'a frame is taken in at the first step sampled after it arrives; sensors of step k go out '
                           'at the step\'s wall time t_wall(0) + t_k / R',
        'devices': [_device(m, m.tpdo_period_s) for m in _maps(scenario) if device in ('', m.name)],
    }


def markdown(contract: dict[str, Any]) -> list[str]:
    """The CANopen side as Markdown lines ([] when the contract has none)."""
    cn = contract.get('canopen')
    if cn is None:
        return []
    fc = cn['flight_computer']
    lines = ['## CANopen side', '', f'Bus: {cn["bus"]}. Flight computer: node {fc["node_id"]}, heartbeat '
             f'{fc["heartbeat_cob_id"]} (lost after {fc["heartbeat_timeout_s"]:g} s: {fc["on_loss"]}). '
             f'Sample and hold: {cn["sample_and_hold"]}.', '']
    for d in cn['devices']:
        lines += [f'### Device `{d["device"]}` ({d["dictionary"]}), node id {d["node_id"]}', '',
                  f'Heartbeat {d["heartbeat"]["cob_id"]} every {d["heartbeat"]["period_ms"]} ms; SDO request '
                  f'{d["sdo"]["request_cob_id"]}, reply {d["sdo"]["reply_cob_id"]}; NMT {d["nmt_cob_id"]}.', '',
                  '| TPDO | COB-ID | period s | mapped |', '| --- | --- | --- | --- |']
        lines += [f'| {p["number"]} | {p["cob_id"]} | {p["period_s"]:g} | {"; ".join(p["mapped"])} |' for p in d['tpdos']]
        if d['rpdos']:
            lines += ['', '| RPDO | COB-ID | mapped |', '| --- | --- | --- |']
            lines += [f'| {p["number"]} | {p["cob_id"]} | {"; ".join(p["mapped"])} |' for p in d['rpdos']]
        lines += ['', '| object | name | type | access | OD unit (scale) | quantity | SI per count | limits | direction |',
                  '| --- | --- | --- | --- | --- | --- | --- | --- | --- |']
        lines += [f'| {o["object"]} | {o["name"]} | {o["type"]} | {o["access"]} | {o["od_unit"] or "—"} ({o["od_scale"]:g}) | '
                  f'{o["quantity"]} | {o["si_per_count"]:g} {o["si_unit"]} | {o["limits"][0]}..{o["limits"][1]} | '
                  f'{o["direction"]} |' for o in d['objects']]
        lines.append('')
    return lines


def write(fmt: str, scenario: Any, device: str) -> str:
    """The document of ``fmt`` (``eds``) for one device; ValueError (one line) when the device is not named."""
    maps = _maps(scenario)
    if not device:
        raise ValueError(f'--format {fmt}: name one device with --node ({", ".join(m.name for m in maps)})')
    import canopen
    m = next(m for m in maps if m.name == device)
    m.od.node_id = m.node_id
    buf = io.StringIO()
    canopen.export_od(m.od, buf, doc_type=fmt)
    return buf.getvalue()
