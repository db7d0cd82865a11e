"""The canopen_cards node, as its package declares it to the graph (spec §13).

The emulated CANopen cards (for OreSat: the ADCS card, node 0x38, and the GPS card, 0x34) between the truth
of step k and the bus: the sensors of step k go out at the step's wall time, the flight computer's setpoints
held until the step that samples them become the rods' moment command of that step. Named in the entry-point
group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from acds_common import topics
from acds_common.frames import BODY
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import TIME, Field, quantity

VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'
SETPOINT = 'cards/current_setpoint'
BODY_RATE = 'cards/body_rate'
MAG = 'cards/magnetic_field'
ECEF = 'cards/ecef_position'
TIMING = 'cards/timing'
CURRENT = {'a': 1.0, 'ma': 1e-3}

SECTIONS: dict[str, dict[str, Field]] = {
    'can_bus': {
        'mapping': Field('str', 'the mapping file: devices (object dictionaries), objects ↔ graph quantities, '
                         'units and scales (relative to the scenario file)', '', path=True),
        'rtf': Field('float', 'real-time factor the cards pace the steps at (acds run --rtf sets it)', 1.0,
                     lo=0.01, hi=1e4),
        'flight_computer_node_id': Field('int', 'node id of the flight computer whose heartbeat the run waits for '
                                         'and watches (OreSat C3: 0x01)', 1, lo=1, hi=127),
        'heartbeat_timeout': quantity('wall time without the flight computer\'s heartbeat that counts as lost',
                                      3.0, 's', TIME, lo=0.1, hi=3600.0),
        'on_heartbeat_loss': Field('str', 'when the heartbeat is lost (or never comes): fail the run, or fly on with '
                                   'the setpoints held', 'fly_on', choices=('fail', 'fly_on')),
        'dipole_per_amp': quantity('per-axis dipole per ampere of the coil a current setpoint drives (x, y, z)',
                                   [1.0, 1.0, 1.0], 'am2_per_a', {'am2_per_a': 1.0}, length=3, lo=1e-6, hi=1e4),
        'setpoint_limit': quantity('per-axis current the driver can deliver; a setpoint beyond it is clamped',
                                   [1.0, 1.0, 1.0], 'a', CURRENT, length=3, lo=0.0, hi=100.0),
        'interface': Field('str', 'the bus: socketcand (the built-in hub over TCP, no kernel CAN needed) or socketcan (a '
                           'kernel CAN interface such as vcan0, where this machine has one)', 'socketcand',
                           choices=('socketcand', 'socketcan')),
        'channel': Field('str', 'socketcan: the kernel interface (e.g. vcan0, can0)', 'vcan0'),
        'endpoint': Field('str', 'socketcand:HOST:PORT or socketcan:CHANNEL (set by acds run; empty: the cards run '
                          'off the bus)', ''),
        'can_log': Field('str', 'CAN log to write (set by acds run: RUN_DIR/can.asc)', ''),
        'replay_can': Field('str', 'CAN log whose frames are applied at their recorded steps instead of a bus '
                            '(acds run --replay-can)', ''),
        'fault': Field('str', 'bus fault injected at fault_time: a card stops its TPDOs (stop_pdos), its SDO replies are '
                       'lost (sdo_lost) or late by fault_delay (sdo_delay), a sensor object reads 0 on fault_axis '
                       '(zero_axis), holds its value (stuck_axis) or reads 0 on every axis (dead_sensor)', 'none',
                       choices=('none', 'stop_pdos', 'sdo_lost', 'sdo_delay', 'zero_axis', 'stuck_axis', 'dead_sensor')),
        'fault_device': Field('str', 'the device of the fault (a mapping device name)', 'adcs'),
        'fault_object': Field('int', 'zero_axis/stuck_axis/dead_sensor: the sensor object (index, e.g. 0x4003)', 0x4003,
                              lo=0, hi=0xFFFF),
        'fault_axis': Field('int', 'zero_axis/stuck_axis: the axis (0, 1, 2 = the object\'s subs in mapping order)', 0,
                            lo=0, hi=2),
        'fault_time': quantity('when the fault appears (sim time)', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'fault_delay': quantity('sdo_delay: how late each SDO reply goes out (wall time)', 0.03, 's', TIME,
                                lo=0.0, hi=60.0),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 10,
                                 lo=1, hi=10**6),
    },
}

PORTS = Ports(
    'canopen_bus.cards_step:CardsStep',
    (Stage('exchange', (
        Input('odometry', topics.TRUTH_ODOMETRY, 'rigid_body'),
        Input('b_true', topics.TRUTH_B_BODY, 'rigid_body'),
        Input('dipole', topics.DIPOLE_END, 'em_driver', lag=1),
        Input('duty', topics.COIL_DUTY, 'em_driver', lag=1),
        Input('sensed_field', topics.MAG_FIELD, 'magnetometer_sim'),
    )),),
    (Output('command', topics.MOMENT_COMMAND, BODY),
     Output('setpoint', SETPOINT, BODY),
     Output('body_rate', BODY_RATE, BODY),
     Output('magnetic_field', MAG, BODY),
     Output('ecef_position', ECEF, 'ecef'),
     Output('timing', TIMING),
     Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def check_mapping(scenario: Any) -> str:
    """'' or the one line saying why the scenario's mapping does not fit its dictionaries (before any process)."""
    if 'canopen_cards' not in scenario.get('', 'nodes'):
        return ''
    from canopen_bus.dictionary import DictionaryError
    from canopen_bus.mapping import load_mapping
    path = scenario.get('can_bus', 'mapping')
    if not path:
        return 'can_bus.mapping: the canopen_cards node needs a mapping file'
    try:
        maps = load_mapping(Path(path))
    except DictionaryError as exc:
        return f'can_bus.mapping: {exc}'
    c = scenario.values['can_bus']
    if c['fault'] != 'none':
        device = next((m for m in maps if m.name == c['fault_device']), None)
        if device is None:
            return f'can_bus.fault_device: {c["fault_device"]!r} is no device of the mapping ({", ".join(m.name for m in maps)})'
        if c['fault'] in ('zero_axis', 'stuck_axis', 'dead_sensor') and not any(
                o.index == c['fault_object'] and not o.command for o in device.objects):
            return (f'can_bus.fault_object: 0x{c["fault_object"]:04X} is no sensor object of device {device.name} '
                    f'(its sensor objects: {", ".join(f"0x{o.index:04X}" for o in device.objects if not o.command)})')
    return ''


#: What the canopen_bus package adds to the graph.
PACKAGE = Package(
    'canopen_bus',
    nodes=(Node('canopen_cards', ('can_bus', 'earth'), PORTS),),
    sections=SECTIONS,
    topics=(
        Topic(SETPOINT, VECTOR3, 'A', 'the flight computer\'s current setpoints applied at step k (held, clamped)'),
        Topic(BODY_RATE, VECTOR3, 'rad/s', 'the gyro rates the ADCS card sent at step k (quantised)'),
        Topic(MAG, VECTOR3, 'T', 'the field the magnetometers sent at step k, mean of the units (quantised)'),
        Topic(ECEF, VECTOR3, 'm', 'the ECEF position the GPS card sent at step k (quantised)'),
        Topic(TIMING, VECTOR3, 's', 'step k: sensor lateness vs the wall schedule, largest SDO request→reply, '
              'largest setpoint age when applied (NaN: none)'),
    ),
    checks=(check_mapping,),
)
