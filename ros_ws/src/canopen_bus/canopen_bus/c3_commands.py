"""What an operator says to the OreSat C3 over the bus, and what it reads back from the C3's own dictionary (spec §13).

The C3 is CANopen node 0x01; its dictionary is oresat-configs' ``OreSatConfig('oresat1').od_db['c3']``. Its ADCS
manager is object 0x400E ``adcs_manager``: sub 2 ``control_mode`` (uint8: IDLE 0 … DETUMBLE 3,
``oresat_c3/subsystems/adcs/config.py``), sub 4 ``orbital_period`` (float32, s) and sub 5 ``orbital_inclination``
(float32, degrees), both 1.0 by default, from which it computes its detumble gain
(``adcs_manager.py`` ``_update_detumble_gain``). The PDOs it receives from the other cards it stores in its own
dictionary: the ADCS card's in object 0x5038 ``adcs`` (gyro and the four magnetometers as the cards' raw integers),
readable by SDO upload like any object.
"""

from __future__ import annotations

import math

import canopen

from .c3_runner import C3_NODE_ID

#: ``ControlMode.DETUMBLE`` of the C3 (oresat_c3/subsystems/adcs/config.py).
DETUMBLE = 3
#: The C3's stored copies of the ADCS card's sensor PDOs (object 0x5038 ``adcs``), sub names.
GYRO_SUBS = ('gyroscope_pitch_rate', 'gyroscope_yaw_rate', 'gyroscope_roll_rate')
MAGNETOMETER_SUBS = tuple(f'{end}_z_magnetometer_{n}_{axis}' for end in ('pos', 'min') for n in (1, 2)
                          for axis in ('x', 'y', 'z'))


def c3_dictionary() -> canopen.ObjectDictionary:
    """The C3's object dictionary as the mission defines it (oresat-configs, mission ``oresat1``)."""
    from oresat_configs import OreSatConfig

    return OreSatConfig('oresat1').od_db['c3']


#: Seconds this client waits for each SDO answer of the C3 (canopen's default 0.3 s, one retry): the C3 is a Python
#: program answering in its own thread, beside its ADCS loop and the cards' PDOs; on a loaded 2-core machine an upload
#: of its ``adcs`` record went unanswered in 0.3 s twice (a fresh clone's suite, the real-C3 test).
SDO_RESPONSE_TIMEOUT_S = 2.0


def connect(network: canopen.Network) -> canopen.RemoteNode:
    """The C3 as a remote node on ``network`` (SDO client on COB-IDs 0x601/0x581, waiting
    :data:`SDO_RESPONSE_TIMEOUT_S` for each answer)."""
    node = network.add_node(canopen.RemoteNode(C3_NODE_ID, c3_dictionary()))
    node.sdo.RESPONSE_TIMEOUT = SDO_RESPONSE_TIMEOUT_S
    return node


def command_detumble(c3: canopen.RemoteNode, orbit_period_s: float, inclination_rad: float) -> dict[str, float]:
    """Set the orbit the C3's detumble gain needs, then its ADCS manager to DETUMBLE; returns what it reads back."""
    manager = c3.sdo['adcs_manager']
    manager['orbital_period'].raw = float(orbit_period_s)
    manager['orbital_inclination'].raw = math.degrees(inclination_rad)
    manager['control_mode'].raw = DETUMBLE
    return {name: manager[name].raw for name in ('orbital_period', 'orbital_inclination', 'control_mode')}


def stored_adcs(c3: canopen.RemoteNode) -> dict[str, int]:
    """The gyro and magnetometer integers the C3 stored from the ADCS card's PDOs (SDO upload of 0x5038)."""
    record = c3.sdo['adcs']
    return {name: record[name].raw for name in (*GYRO_SUBS, *MAGNETOMETER_SUBS)}
