"""The ascs_mode_manager node, as its package declares it to the graph (spec §8; seeds 000, 001; issue 19).

The on-board mode logic: HEAO (Mode 1A → 1B → cruise, on the gyros and the sun sensor; heao_cold_gas: with
the cold-gas acquisition in front, seed 002 §3.1), SSS (the
perigee automatic turn-on, on the spin-plane magnetometer channel; it commands the coils itself) or
the AAP Workshop's (CMG hold and magnetic dump, by ground command only); ``modes.system`` picks it.
Every system takes the ground commands and answers them on ``ground/ack``. Named in the
entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import topics
from acds_common import units as u
from acds_common.frames import BODY
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.modes import GAS_MODES, HEAO_CRUISE_MODES, INITIAL_MODES, WORKSHOP_INITIAL_MODES
from acds_common.schema import ANGLE, DEG, FIELD, RATE, Field, quantity

#: The scenario sections this package defines.
SECTIONS: dict[str, dict[str, Field]] = {
    'modes': {
        'system': Field('str', 'which mode logic runs: heao, heao_cold_gas (the study\'s recommended design: cold-gas '
                        'acquisition, wheels + magnetics cruise, seed 002 §3.1), sss or aap (the AAP Workshop CMG hold '
                        'and magnetic dump, seed 000)', 'heao', choices=('heao', 'heao_cold_gas', 'sss', 'aap')),
        'initial_mode': Field('str', 'mode at separation (aap: cmg_hold or cmg_dump; heao_cold_gas: a gas mode)',
                              'mode_1a', choices=INITIAL_MODES),
        'rate_thresholds': quantity('Mode 1A→1B body-rate thresholds |ω_x|, |ω_y|, |ω_z|',
                              [0.573 * DEG, 0.115 * DEG, 0.115 * DEG], 'rad_s', RATE, length=3, lo=0.0, hi=1.0),
        'capture_cone': quantity('acquisition capture: z within this angle of the sun', 10 * DEG, 'rad', ANGLE,
                           lo=0.0, hi=math.pi),
        'capture_rate': quantity('acquisition capture: every rate below this ("nulled")', 0.01 * DEG, 'rad_s', RATE,
                           lo=0.0, hi=0.1),
        'cruise_target': Field('str', 'cruise mode after capture', 'celestial_point', choices=HEAO_CRUISE_MODES),
        'auto_cruise': Field('bool', 'enter cruise automatically at capture (else by ground command)', False),
        'stop_at_capture': Field('bool', 'end the run at acquisition capture', False),
        'ground_commands': Field('strs', 'scheduled ground commands, "T_S: command"', []),
        'gas_damped_rate': quantity('heao_cold_gas: gas rate damping → gas sun acquisition when every |ω_i| is below '
                                    'this', 0.05 * DEG, 'rad_s', RATE, lo=0.0, hi=0.1),
        'gas_handover_cone': quantity('heao_cold_gas: gas sun acquisition → Mode 1B (wheels) when z is within this of '
                                      'the sun line …', 5 * DEG, 'rad', ANGLE, lo=0.0, hi=math.pi),
        'gas_handover_rate': quantity('heao_cold_gas: … and every |ω_i| is below this (the capture test\'s rate, '
                                      'capture_rate: the gas finishes the acquisition, seed 002 §2 "within ten minutes")',
                                      0.01 * DEG, 'rad_s', RATE,
                                      lo=0.0, hi=0.1),
    },
    'sss': {
        'polarity_level': quantity('polarity-sensing level of the spin-plane magnetometer channel', 0.075 * u.GAUSS_T,
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


_HEAO_INPUTS = (Input('gyro', topics.GYRO, 'rigid_body'), Input('sun', topics.SUN_SENSOR, 'rigid_body'))
#: Each system's stepper and the inputs of its stage ``mode_logic``.
_SYSTEMS = {
    'heao': ('HeaoModeManagerStep', _HEAO_INPUTS),
    'heao_cold_gas': ('ColdGasModeManagerStep', _HEAO_INPUTS),
    'sss': ('SssModeManagerStep', (Input('volts', topics.MAG_VOLTS, 'magnetometer_sim'),
                                   Input('bias', topics.MAG_BIAS_VOLTS, 'magnetometer_sim'))),
    'aap': ('AapModeManagerStep', ()),  # paced by /clock: the Workshop's modes change by ground command only
}


def _ascs_mode_manager(params: dict[str, Any]) -> Ports:
    """The variant ``modes.system`` names; the SSS logic also commands the coils itself."""
    system = params['modes_system']
    stepper, inputs = _SYSTEMS[system]
    outputs = (Output('mode', topics.MODE),
               *((Output('moment', topics.MOMENT_COMMAND, BODY),) if system == 'sss' else ()),
               Output('events', topics.EVENTS, every_step=False, many=True),
               Output('diagnostics', topics.DIAGNOSTICS, every_step=False),
               Output('ack', topics.GROUND_ACK, every_step=False, lockstep=False, many=True))
    return Ports(f'ascs_mode_manager.mode_manager_step:{stepper}', (Stage('mode_logic', inputs),), outputs,
                 ground_commands=True)


def check_workshop(sc: Any) -> str:
    """The Workshop mode logic drives CMGs, and only it does; its modes are its own ('' when so)."""
    if sc.formation:
        return ''
    system, initial, kind = sc.get('modes', 'system'), sc.get('modes', 'initial_mode'), sc.get('wheels', 'kind')
    if (system == 'aap') != (initial in WORKSHOP_INITIAL_MODES):
        return (f'modes.initial_mode: {initial!r} with modes.system {system!r} (a run of system aap starts in a '
                f'Workshop mode, {" or ".join(WORKSHOP_INITIAL_MODES)}, and only it does)')
    if 'ascs_mode_manager' in sc.get('', 'nodes') and (system == 'aap') != (kind == 'cmg'):
        return (f'wheels.kind: {kind!r} with modes.system {system!r} (the aap mode logic holds '
                'the attitude with CMGs, wheels.kind cmg; the heao and sss logic drive wheels)')
    return ''


def check_gas_modes(sc: Any) -> str:
    """The gas modes start, and only start, a heao_cold_gas acquisition ('' when so; seed 002 §3.1)."""
    if sc.formation:
        return ''
    system, initial = sc.get('modes', 'system'), sc.get('modes', 'initial_mode')
    if (system == 'heao_cold_gas') != (initial in GAS_MODES):
        return (f'modes.initial_mode: {initial!r} with modes.system {system!r} (the gas modes, '
                f'{" or ".join(GAS_MODES)}, start a heao_cold_gas acquisition, and only they do)')
    return ''


#: What the ascs_mode_manager package adds to the graph.
PACKAGE = Package(
    'ascs_mode_manager',
    nodes=(Node('ascs_mode_manager', ('modes', 'sss'), _ascs_mode_manager),),
    sections=SECTIONS,
    topics=(
        Topic(topics.MODE, 'diagnostic_msgs/msg/DiagnosticArray', '', 'current mode (step k), transition cause'),
        Topic(topics.GROUND_ACK, 'std_msgs/msg/String', '', 'acknowledgements and refusals with reasons'),
        Topic(topics.EVENTS, 'std_msgs/msg/String', '', 'mode transitions, automatic turn-on/off, with sim time'),
    ),
    checks=(check_workshop, check_gas_modes),
)
