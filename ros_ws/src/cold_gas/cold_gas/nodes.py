"""The cold_gas node, as its package declares it to the graph (seed 002 §3.2, §5; issue 22).

``cold_gas``: the HEAO cold-gas reaction control subsystem (two GN₂ tanks, regulators, pressure switch,
isolation valves, six thrusters; core :mod:`cold_gas.rcs`). It takes the controller's valve on-time
requests and the mode (forwarded ground commands) of step k and returns the thrusters' step-average
wrench (to the rigid body), the subsystem state every step and telemetry. Its scenario section
``cold_gas``; its check across keys: the node flies with, and only with, the heao_cold_gas mode logic.
Named in the entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

from typing import Any

from acds_common import topics
from acds_common import units as u
from acds_common.frames import BODY
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import TIME, Field, quantity
from acds_common.thrusters import DEFAULT_LAYOUT, LAYOUT_CHOICES, LAYOUTS, MAX_CROSS_COUPLING

from cold_gas.rcs import COLD_GAS_FAULTS

MS = {'ms': 1e-3, 's': 1.0}
#: The scenario section this package defines (SI inside; the core: cold_gas.configuration).
SECTIONS: dict[str, dict[str, Field]] = {
    'cold_gas': {
        'thrust': quantity('thrust of each thruster at the regulator set point (§3.2: "nominal thrust in the 0.1 to 1 '
                           'pound range"; 0.5 lbf taken)', 0.5 * u.LBF_N, 'n', {'lbf': u.LBF_N, 'n': 1.0},
                           lo=1e-4, hi=1e3),
        'isp': quantity('cold-nitrogen specific impulse (Table 5-3: every tank\'s impulse over its gas capacity is '
                        '65 s)', 65.0, 's', {'s': 1.0}, lo=1.0, hi=400.0),
        'valve_open_delay': quantity('thruster valve opening delay (command to thrust; not in the seed)', 0.005, 's',
                                     MS, lo=0.0, hi=0.1),
        'valve_close_delay': quantity('thruster valve closing delay (command end to thrust end; not in the seed)',
                                      0.003, 's', MS, lo=0.0, hi=0.1),
        'min_on_time': quantity('minimum valve on-time: the minimum impulse bit (not in the seed)', 0.020, 's', MS,
                                lo=1e-4, hi=1.0),
        'max_open_valves': Field('int', 'valves powered at once (Table 5-2: "maximum of two valves operating at one '
                                 'time", 12 W each)', 2, lo=1, hi=6),
        'tank_diameter': quantity('inner diameter of each spherical tank (§3.2: 7.6 in)', 7.6 * u.INCH_M, 'm',
                                  {'in': u.INCH_M, 'm': 1.0}, lo=0.01, hi=3.0),
        'tank_count': Field('int', 'tanks (§3.2: two)', 2, lo=1, hi=8),
        'load_mass': quantity('GN₂ loaded in all tanks (§3.2: 4.6 lb)', 4.6 * u.LB_KG, 'kg',
                              {'lb': u.LB_KG, 'kg': 1.0}, lo=1e-4, hi=1e3),
        'gas_temperature': quantity('gas temperature (isothermal blowdown)', 293.0, 'k', {'k': 1.0}, lo=50.0, hi=500.0),
        'regulator_set_pressure': quantity('regulator set point, absolute (not in the seed)', 150 * u.PSI_PA, 'pa',
                                           {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'pressure_switch_pressure': quantity('over-pressure switch set point, absolute (not in the seed)',
                                             200 * u.PSI_PA, 'pa', {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'relief_pressure': quantity('relief valve crack pressure, absolute (not in the seed)', 250 * u.PSI_PA, 'pa',
                                    {'psia': u.PSI_PA, 'pa': 1.0}, lo=1e3, hi=1e8),
        'manifold_volume': quantity('low-pressure manifold volume, regulators to thruster valves', 50e-6, 'm3',
                                    {'cm3': 1e-6, 'm3': 1.0}, lo=1e-7, hi=1e-2),
        'regulator_seat_area': quantity('flow area of a failed-open regulator seat (fault regulator_fail_open)',
                                        0.05e-6, 'm2', {'mm2': 1e-6, 'm2': 1.0}, lo=0.0, hi=1e-3),
        'isolation_close_delay': quantity('latching isolation valve closing time after the pressure switch trips',
                                          0.030, 's', MS, lo=0.0, hi=1.0),
        'thruster_layout': Field('str', 'thruster layout (acds_common.thrusters): platform, §6.2.5\'s six thrusters on '
                                 'the equipment platform\'s lower surface (default); outriggers, roll thrusters in the '
                                 'centre-of-mass station; custom, thruster_positions and thruster_directions',
                                 DEFAULT_LAYOUT, choices=LAYOUT_CHOICES),
        'thruster_positions': quantity('T1…T6 positions from the centre of mass, body axes, (x, y, z) each (read with '
                                       'thruster_layout custom; default: the platform layout\'s)',
                                       list(LAYOUTS[DEFAULT_LAYOUT][0]), 'm', {'m': 1.0, 'ft': u.FOOT_M, 'in': u.INCH_M},
                                       length=18, lo=-100.0, hi=100.0),
        'thruster_directions': Field('floats', 'T1…T6 thrust directions (force on the spacecraft), body axes (read with '
                                     'thruster_layout custom)', list(LAYOUTS[DEFAULT_LAYOUT][1]), length=18,
                                     lo=-1.0, hi=1.0),
        'max_cross_coupling': Field('float', 'largest off-axis torque of a thruster or couple, fraction of its on-axis torque',
                                    MAX_CROSS_COUPLING, lo=0.0, hi=1.0),
        'isolation_valves_open': Field('bool', 'both isolation valves open at t0', True),
        'bank_power': Field('bool', 'thruster bank power on at t0', True),
        'fault': Field('str', 'fault injected at fault_time', 'none', choices=COLD_GAS_FAULTS),
        'fault_index': Field('int', 'the thruster (1–6) or regulator (1–2) the fault hits', 1, lo=1, hi=6),
        'fault_time': quantity('when the fault appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 20,
                                 lo=1, hi=10**6),
    },
}

#: The node: the controller's on-time requests and the mode (forwarded ground commands) of step k in; the
#: thrusters' step-average wrench (to the rigid body), the subsystem state every step, telemetry out.
PORTS = Ports(
    'cold_gas.cold_gas_step:ColdGasStep',
    (Stage('fire', (Input('pulse', topics.GAS_ON_TIME, 'acds_controller'),
                    Input('mode', topics.MODE, 'ascs_mode_manager'))),),
    (Output('wrench', topics.COLD_GAS_WRENCH, BODY),
     Output('state', topics.COLD_GAS_STATE),
     Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def check_cold_gas(sc: Any) -> str:
    """The thrusters fly with, and only with, the heao_cold_gas mode logic ('' when so; seed 002 §3.1)."""
    if sc.formation:
        return ''
    nodes, system = sc.get('', 'nodes'), sc.get('modes', 'system')
    if 'ascs_mode_manager' in nodes and ('cold_gas' in nodes) != (system == 'heao_cold_gas'):
        return (f'modes.system: {system!r} with node cold_gas {"in" if "cold_gas" in nodes else "not in"} the graph '
                '(the heao_cold_gas mode logic acquires on the cold-gas thrusters, and only it flies them)')
    return ''


#: What the cold_gas package adds to the graph.
PACKAGE = Package(
    'cold_gas',
    nodes=(Node('cold_gas', ('cold_gas',), PORTS),),
    sections=SECTIONS,
    topics=(
        Topic(topics.COLD_GAS_WRENCH, 'geometry_msgs/msg/WrenchStamped', 'N, N·m',
              'thrusters\' force and torque, step average, body'),
        Topic(topics.COLD_GAS_STATE, 'diagnostic_msgs/msg/DiagnosticArray', '',
              'thrust times, gas, pressures, valves, every step'),
    ),
    checks=(check_cold_gas,),
)
