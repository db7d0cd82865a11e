"""The controller nodes, as the acds_controller package declares them to the graph (spec §7, §10; issue 19).

``acds_controller``: the HEAO transfer assembly and DPA (spec §7), or the AAP Workshop computer
(seed 000) with the CMGs; ``formation_controller``: one formation vehicle's controller (seed 004).
Named in the entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import topics
from acds_common import units as u
from acds_common.frames import BODY
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import ANGLE, DEG, DUMP_GAIN, MOMENT_OF_INERTIA, MOMENTUM, RATE, TIME, Field, quantity

VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'
#: The scenario section this package defines.
SECTIONS: dict[str, dict[str, Field]] = {
    'controller': {
        'acquisition_law': Field('str', 'Mode 1A magnetic law (b_cross_omega: the CubeSat detumble law '
                                 'M = −(k_ω/|B|)(B̂ × ω) of seed 003)', 'bxh', choices=('bxh', 'bdot', 'b_cross_omega')),
        'unloading_law': Field('str', 'Mode 1B/cruise unloading law (b_cross_h: seed 003 dumping form '
                               'M = −(k_h/|B|)(B̂ × h))', 'bxh', choices=('bxh', 'lead', 'none', 'b_cross_h')),
        'acquisition_gain_per_s_g2': Field('float', 'B×H acquisition gain G, (s·G²)⁻¹', 0.05, lo=0.0, hi=10.0),
        'bdot_gain_ft_lb_s_per_g2': Field('float', 'B-dot gain K_D, ft-lb-s/G²', 1.0, lo=0.0, hi=1e4),
        'unloading_gain_mode_1b_per_s_g2': Field('float', 'unloading gain in Mode 1B', 0.05, lo=0.0, hi=10.0),
        'unloading_gain_scan_per_s_g2': Field('float', 'unloading gain, celestial scan', 0.01, lo=0.0, hi=10.0),
        'unloading_gain_point_per_s_g2': Field('float', 'unloading gain, celestial point', 0.02, lo=0.0, hi=10.0),
        'max_moment_am2': Field('float', 'per-axis moment command saturation', 2000.0, lo=1e-3, hi=1e6),
        # seed 003 gain design, k_ω = (4π/T_orb)(sin ξ + 1) J_min: the on-board design values (defaults: the seed's)
        'detumble_orbit_period': quantity('b_cross_omega gain: orbit period T_orb (seed 003: ISS, 5560.8 s)', 5560.8, 's',
                                    TIME, lo=1e3, hi=1e6),
        'magnetic_inclination': quantity('ξ, inclination of the orbit to the geomagnetic equator, for the b_cross_omega '
                                   'and b_cross_h gains (seed 003: 0.90129 rad, the ISS inclination)', 0.90129,
                                   'rad', ANGLE, lo=1e-3, hi=math.pi / 2),
        'detumble_j_min': quantity('b_cross_omega gain: smallest principal moment of inertia J_min (seed 003: '
                             '5,094,047.43 g·mm²)', 5094047.43 * u.G_MM2_KG_M2, 'kg_m2', MOMENT_OF_INERTIA,
                             lo=1e-6, hi=1e9),
        'dump_time': quantity('b_cross_h gain: dump the slowest momentum mode to dump_residual_fraction within this time '
                        '(seed 003: "say, 1 orbit of 90 minutes")', 5400.0, 's', TIME, lo=1.0, hi=1e7),
        'dump_residual_fraction': Field('float', 'b_cross_h gain: momentum left of the slowest mode after dump_time',
                                        0.1, lo=1e-6, hi=0.999),
        'coupling_compensation': Field('bool', 'subtract the known Δ·M from the sensed field', False),
        'wheel_gains': Field('str', 'acquisition wheel-law gains (Table 4-2)', 'heao_b',
                             choices=('heao_a', 'heao_b', 'heao_b_preliminary')),
        'scan_rate': quantity('celestial scan rate about z', 0.03 * 2 * math.pi / 60, 'rad_s', RATE, lo=0.0, hi=0.1),
        'target_quaternion_xyzw': Field('floats', 'cruise target attitude q body→ECI', [0.0, 0.0, 0.0, 1.0],
                                        length=4, lo=-1.0, hi=1.0, quaternion=True),
        'lead_time_s': Field('float', 'lead law: wheel command → momentum lead time, s', 500.0, lo=0.0, hi=1e5),
        'adc_bits': Field('int', 'transfer assembly ADC width, bits', 10, lo=8, hi=24),
        'telemetry_every': Field('int', 'DPA/TA telemetry on diagnostics every N steps (and at every event)',
                                 20, lo=1, hi=10**6),
        'dump_law': Field('str', 'Workshop dump law: khb (M = k H_s × B), khb_shifted (k (H_s − H_0) × B), '
                          'min_energy (eq. 3 on the predicted field), none (CMG hold only)', 'khb',
                          choices=('khb', 'khb_shifted', 'min_energy', 'none')),
        'dump_gain': quantity('dump gain k (seed 000 §5: "k = 4 × 10⁶", read as amp-turn-ft² per ft-lb-sec per Wb/m², '
                              'the reading its stated range 3–5 × 10⁶ fits; 3.716e5 amp-turn-m² per ft-lb-sec per Wb/m²)',
                              u.dump_gain_seed_to_si(4e6 * u.FOOT_M ** 2), 'per_s_t2', DUMP_GAIN, lo=0.0, hi=1e12),
        'dump_gain_rule': Field('str', 'k of the khb laws: stated (dump_gain_* as given; the memo\'s 4e6 read in '
                                'amp-turn-ft² gives loop gains 0.37–1.51, read in amp-turn-m² 4–16, which diverge) or '
                                'loop_gain (k such that the largest eigenvalue of k·W over '
                                'one day of predicted orbits is dump_loop_gain)', 'stated', choices=('stated', 'loop_gain')),
        'dump_loop_gain': Field('float', 'dump_gain_rule loop_gain: the largest loop gain (eigenvalue of k·W) over the '
                                'predicted orbits; the loop converges for gains in (0, 2)', 1.0, lo=1e-6, hi=2.0),
        'dump_moment_limit_fraction': Field('float', 'seed 000 §9: |M| limited (direction kept) to this fraction of the '
                                            'predicted unconstrained M_m (seed: 0.85); 0: no limit', 0.0, lo=0.0, hi=10.0),
        'dump_day_only': Field('bool', 'seed 000 §10: dump only in orbital daylight (sun sensor), at the constant '
                               '|M| = dump_day_moment_factor × the predicted unconstrained M_m', False),
        'dump_day_moment_factor': Field('float', 'seed 000 §10: day-only constant |M| over the day-and-night M_m (seed: '
                                        '1.3)', 1.3, lo=1e-3, hi=100.0),
        'dump_h_0': quantity('khb_shifted: the shift H_0 of the region H_s settles in (§3)', [0.0, 0.0, 0.0], 'nms',
                       MOMENTUM, length=3, lo=-1e5, hi=1e5),
        'dump_bias_momentum': quantity('bias momentum H_b per orbit known on board (§3): what min_energy dumps and the '
                                 '§5 initialisation uses', [0.0, 0.0, 0.0], 'nms', MOMENTUM, length=3,
                                 lo=-1e6, hi=1e6),
        'dump_h_s_init': Field('str', 'first H_s sample: measured (the CMG momentum as it is) or min_energy '
                               '(§5: k H_s of the first orbit set to eq. 3\'s bracket, kept as an offset)',
                               'measured', choices=('measured', 'min_energy')),
        'cmg_hold_bandwidth': quantity('CMG attitude-hold closed-loop bandwidth ω_n (not in the seed)', 0.05, 'rad_s',
                                 RATE, lo=1e-6, hi=10.0),
        'cmg_hold_damping': Field('float', 'CMG attitude-hold damping ratio ζ (not in the seed)', 0.7,
                                  lo=0.0, hi=10.0),
        # ---- cold-gas acquisition law (seed 002 §3.1; acds_controller.cold_gas_law), with node cold_gas
        'gas_rate_deadband': quantity('gas law: no pulse while every |ω_i − ω_ref,i| is within this (half the hand-over '
                                      'rate, modes.gas_handover_rate: the rates settle inside the capture test; '
                                      'acds_controller.cold_gas_law)', 0.005 * DEG,
                                      'rad_s', RATE, lo=0.0, hi=0.1),
        'gas_position_gain': quantity('gas law: rate reference per radian of sun-line error, ω_ref = −K·θ', 0.02,
                                      'per_s', {'per_s': 1.0}, lo=0.0, hi=10.0),
        'gas_slew_rate': quantity('gas law: limit of |ω_ref| (the sun acquisition slew rate)', 0.5 * DEG, 'rad_s', RATE,
                                  lo=1e-5, hi=0.2),
    },
}


def _acds_controller(params: dict[str, Any]) -> Ports:
    """The HEAO transfer assembly + DPA driving wheels (spec §7), or with the CMGs (``wheels.kind: cmg``) the AAP
    Workshop's computer (seed 000), or with node ``cold_gas`` in the graph the DPA that also flies the cold-gas
    acquisition (seed 002 §3.1; it asks the thrusters for valve on-times): the same inputs (the wheel ones are
    then the CMGs'), each its own outputs."""
    if params['wheels_kind'] == 'cmg':
        stepper = 'workshop_step:WorkshopComputerStep'
        store = (Output('cmg_torque', topics.CMG_TORQUE, BODY), Output('sampled_momentum', topics.SAMPLED_MOMENTUM, BODY))
    elif 'cold_gas' in params['graph_nodes']:
        stepper = 'cold_gas_controller_step:ColdGasControllerStep'
        store = (Output('volts', topics.WHEEL_VOLTS, BODY), Output('gas_on_time', topics.GAS_ON_TIME, BODY))
    else:  # the wheel volts only to wheels (a graph without them, OreSat's, has no reader and no such topic)
        stepper = 'controller_step:DpaStep'
        store = (Output('volts', topics.WHEEL_VOLTS, BODY),) if 'reaction_wheels' in params['graph_nodes'] else ()
    return Ports(
        f'acds_controller.{stepper}',
        (Stage('control', (
            Input('mag_volts', topics.MAG_VOLTS, 'magnetometer_sim'),
            Input('mag_bias', topics.MAG_BIAS_VOLTS, 'magnetometer_sim'),
            Input('gyro', topics.GYRO, 'rigid_body'),
            Input('sun', topics.SUN_SENSOR, 'rigid_body'),
            Input('odometry', topics.TRUTH_ODOMETRY, 'rigid_body'),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, 'reaction_wheels', lag=1),
            Input('wheel_hdot', topics.WHEEL_TORQUE, 'reaction_wheels', lag=1),
            Input('coil_current', topics.COIL_CURRENT, 'em_driver', lag=1),
        )),),
        (Output('moment', topics.MOMENT_COMMAND, BODY),
         *store,
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


#: The formation controller's stepper for each ``formation.law`` (seed 004): each law its own variant.
FORMATION_LAWS = {
    'hold': 'acds_controller.formation_controller_step:FormationControllerStep',
    'spin_up': 'acds_controller.formation_controller_step:FormationControllerStep',
    'array_spin': 'acds_controller.formation_array_step:FormationArrayStep',
    'lqr': 'acds_controller.formation_lqr_step:FormationLqrStep',
    'airtrack_open_loop': 'acds_controller.airtrack_step:AirtrackOpenLoopStep',
    'airtrack_lqr': 'acds_controller.airtrack_step:AirtrackLqrStep',
}


def _formation_controller(params: dict[str, Any]) -> Ports:
    """One vehicle's formation controller: every vehicle's truth of step k and wheel momentum of step k − 1
    (the RF link of seed 004 slide 70); it returns its own vehicle's dipole and wheel torque commands."""
    inputs: list[Input] = []
    for w in params['formation_vehicles']:
        ns = f'{topics.NAMESPACE}/{w}'
        inputs += [Input(f'{w}/odometry', f'{ns}/{topics.TRUTH_ODOMETRY}', 'formation_dynamics'),
                   Input(f'{w}/gyro', f'{ns}/{topics.GYRO}', 'formation_dynamics'),
                   Input(f'{w}/b_body', f'{ns}/{topics.TRUTH_B_BODY}', 'formation_dynamics'),
                   Input(f'{w}/wheel_h', f'{ns}/{topics.WHEEL_MOMENTUM}', f'{w}/reaction_wheels', lag=1),
                   Input(f'{w}/wheel_hdot', f'{ns}/{topics.WHEEL_TORQUE}', f'{w}/reaction_wheels', lag=1)]
    return Ports(FORMATION_LAWS[params['formation_law']], (Stage('control', tuple(inputs)),),
                 (Output('moment', topics.MOMENT_COMMAND, BODY),
                  Output('wheel_torque', topics.WHEEL_TORQUE_COMMAND, BODY),
                  Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def check_airtrack(sc: Any) -> str:
    """The airtrack laws' formation: the electromagnet (fixed, coils, runs the controller) and the slider (free,
    a permanent magnet, on the +x side), a track that holds the slider (magnet along the track, a tilt), positive
    LQR scales ('' when so; seed 004 slides 52–55)."""
    if not sc.formation or not sc.values['formation']['law'].startswith('airtrack_'):
        return ''
    from acds_controller.airtrack_step import airtrack_plant, bryson_scales
    from acds_controller.magnetic_laws import ControllerError
    f, vehicles = sc.values['formation'], sc.values['vehicles']
    magnets = [v for v in vehicles if v['vehicle']['fixed'] and v['vehicle']['magnet'] == 'coils'
               and 'formation_controller' in v['nodes']]
    sliders = [v for v in vehicles if not v['vehicle']['fixed'] and v['vehicle']['magnet'] == 'permanent'
               and not v['nodes']]
    if len(vehicles) != 2 or len(magnets) != 1 or len(sliders) != 1:
        return (f'vehicles: law {f["law"]} flies the airtrack: one fixed electromagnet (vehicle.fixed: true, magnet: '
                'coils, nodes [em_driver, formation_controller]) and one free slider (magnet: permanent, no nodes)')
    magnet, slider = magnets[0], sliders[0]
    if not slider['vehicle']['initial_position'][0] > magnet['vehicle']['initial_position'][0]:
        return (f'vehicles.{slider["name"]}.vehicle.initial_position_m: the slider starts on the +x side of the '
                'electromagnet (the airtrack\'s separation is x_slider − x_magnet > 0)')
    try:
        airtrack_plant(f, slider['vehicle'], slider['spacecraft'])
        if f['law'] == 'airtrack_lqr':
            bryson_scales(f)
    except (ValueError, ControllerError) as exc:
        return str(exc)
    return ''


#: What the acds_controller package adds to the graph.
PACKAGE = Package(
    'acds_controller',
    nodes=(
        # The cold_gas section only with node cold_gas in the graph: the variant that flies the gas reads it.
        Node('acds_controller', ('spacecraft', 'controller', 'magnetometer', 'wheels', 'orbit', 'earth'),
             _acds_controller, sections_with=(('cold_gas', 'cold_gas'),)),
        Node('formation_controller', ('orbit', 'formation'), _formation_controller, in_graph=False, in_vehicle=True,
             every_vehicle=('spacecraft', 'vehicle', 'em_driver', 'wheels')),
    ),
    sections=SECTIONS,
    checks=(check_airtrack,),
    topics=(
        Topic(topics.MOMENT_COMMAND, VECTOR3, 'A·m²', 'commanded dipole, body'),
        Topic(topics.WHEEL_VOLTS, VECTOR3, 'V', 'wheel drive volts per body axis'),
        Topic(topics.WHEEL_TORQUE_COMMAND, VECTOR3, 'N·m', 'wanted ḣ of torque-driven wheels, body'),
        Topic(topics.CMG_TORQUE, VECTOR3, 'N·m', 'commanded CMG momentum rate ḣ, body'),
        Topic(topics.SAMPLED_MOMENTUM, VECTOR3, 'N·m·s', 'H_s the dump law uses (step k), body'),
        Topic(topics.GAS_ON_TIME, VECTOR3, 's', 'cold-gas valve on-time per body axis (sign: torque direction)'),
    ),
)
