"""The em_driver node, as its package declares it to the graph (spec §6; seed 003; issue 19).

The electromagnet drive electronics (bridge-switch or constant-level drivers and their coils), or
the CubeSat torque rods: the moment command of step k from its command source → the achieved
dipole. Named in the entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

from typing import Any

from acds_common import topics
from acds_common.frames import BODY
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import TIME, Field, quantity

VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'
#: The scenario section this package defines.
SECTIONS: dict[str, dict[str, Field]] = {
    'em_driver': {
        'command_source': Field('str', 'node whose moment commands drive the coils', 'acds_controller',
                                choices=('acds_controller', 'ascs_mode_manager', 'formation_controller',
                                         'canopen_cards')),
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
        'failure_time': quantity('when the failure appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'mismatch_settle': quantity('how long the mismatch must persist before the alarm', 3.0, 's', TIME,
                              lo=0.0, hi=1e4),
        'bench_command': quantity('fixed moment command applied when the command source is not in the graph',
                            [0.0, 0.0, 0.0], 'am2', {'am2': 1.0}, length=3, lo=-1e5, hi=1e5),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 10,
                                 lo=1, hi=10**6),
    },
}


def _em_driver(params: dict[str, Any]) -> Ports:
    rods = params['em_driver_driver_kind'] == 'torque_rod'
    # The torque rods' bus power and duty every step: the CubeSat summary's energy and duty (seed 003).
    electrical = (Output('power', topics.COIL_POWER, BODY), Output('duty', topics.COIL_DUTY, BODY)) if rods else ()
    return Ports(
        'em_driver.em_driver_step:EmDriverStep',
        (Stage('drive', (
            Input('command', topics.MOMENT_COMMAND, params['em_driver_command_source']),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
        )),),
        (Output('dipole_avg', topics.DIPOLE_AVG, BODY),
         Output('dipole_end', topics.DIPOLE_END, BODY),
         Output('coil_current', topics.COIL_CURRENT, BODY),
         Output('e_ft', topics.E_FT, BODY),
         *electrical,
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


#: What the em_driver package adds to the graph.
PACKAGE = Package(
    'em_driver',
    nodes=(Node('em_driver', ('em_driver',), _em_driver, in_vehicle=True),),
    sections=SECTIONS,
    vehicle_sections=('em_driver',),
    topics=(
        Topic(topics.DIPOLE_AVG, VECTOR3, 'A·m²', 'achieved dipole averaged over the step'),
        Topic(topics.DIPOLE_END, VECTOR3, 'A·m²', 'achieved dipole at t_k+1'),
        Topic(topics.COIL_CURRENT, VECTOR3, 'A', 'coil current at t_k+1 (signed)'),
        Topic(topics.E_FT, VECTOR3, 'V', 'current-sensor telemetry voltage e_ft'),
        Topic(topics.COIL_POWER, VECTOR3, 'W', 'torque rods: net bus power per axis, step average'),
        Topic(topics.COIL_DUTY, VECTOR3, '', 'torque rods: |PWM duty| of the active winding per axis'),
    ),
)
