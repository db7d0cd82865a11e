"""The nodes of the dynamics package, as it declares them to the graph (spec §2, §3, §4, §10; issue 19).

``rigid_body`` owns sim time of a single-vehicle graph (rigid body, orbit, environment);
``reaction_wheels`` is the momentum store (square-law wheels, torque-driven wheels, or the AAP
Workshop's CMGs); ``formation_dynamics`` owns sim time of a formation (every vehicle's translation
and attitude, seed 004). Named in the entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

import math
from typing import Any

from acds_common import topics
from acds_common import units as u
from acds_common.frames import BODY, ECI, FORMATION, vehicle_body
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import (
    ANGLE,
    DEG,
    LENGTH,
    MOMENTUM,
    RATE,
    REQUIRED,
    TIME,
    TORQUE,
    Field,
    quantity,
)

VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'
#: The formation laws of the 1-D airtrack (frame ``line``; acds_controller.airtrack_control).
AIRTRACK_LAWS = ('airtrack_open_loop', 'airtrack_lqr')
#: The scenario sections this package defines.
SECTIONS: dict[str, dict[str, Field]] = {
    'dynamics': {
        'gravity_gradient': Field('bool', 'apply the gravity-gradient torque', True),
        'substeps': Field('int', 'RK4 substeps per control period. Default 1, from the accuracy study '
                          '(tests/substep_study.py, HEAO-B at 0.5 s, against 100 substeps): after one orbit of '
                          'the 1 deg/s tumble the attitude is off by 6.7e-7 deg and the rates by 3.0e-9 deg/s '
                          '(torque-free and with gravity gradient; 2 substeps: 4.0e-8 deg, 5: 1.2e-9 deg, '
                          '10 and more: rounding, 3e-10 deg); Basilisk 2.12.1 at the same 0.5 s step differs '
                          'from 1 substep by 1e-7 deg and from its own 0.05 s run by 5.8e-7 deg. Closed loop '
                          '(heao_b_acquisition_fast_geometry, direct engine), 1, 2, 5, 10, 20 and 100 substeps '
                          'reach Mode 1B '
                          '(56.59 min) and capture (86.32 min) at the same step, final wheel momentum within '
                          '9e-6 ft-lb-s. Raise it for faster bodies or longer control periods', 1, lo=1, hi=10000),
        'stop_when_detumbled': Field('bool', 'rigid_body: end the run once the spacecraft is detumbled, |ω| (the '
                                     'norm of the true body rate) below detumbled_rate at every step for '
                                     'detumbled_hold; decided by the time owner from the truth, so it acts the same '
                                     'whoever flies the spacecraft (the built-in law or your own node) and on every '
                                     'engine. Off: the run lasts its duration', False),
        'detumbled_rate': quantity('the body rate |ω| below which the spacecraft counts as detumbled (seed 003: '
                                   'the torque-rod summary\'s threshold, 0.1 deg/s)', 0.1 * DEG, 'rad_s', RATE,
                                   lo=1e-9, hi=1.0),
        'detumbled_hold': quantity('stop_when_detumbled: how long |ω| must stay below detumbled_rate (whole steps, '
                                   'rounded up) before the run ends', 600.0, 's', TIME, lo=0.0, hi=1e7),
    },
    'wheels': {
        'kind': Field('str', 'momentum store: wheels (square-law reaction wheels, spec §4) or cmg (ideal control '
                      'moment gyros, seed 000: the momentum rate the attitude loop asks, spherical capacity)',
                      'wheels', choices=('wheels', 'cmg')),
        'drive': Field('str', 'kind wheels: volts, square-law drive from the controller\'s volts (HEAO, spec §4); '
                       'torque, torque-commanded wheels (EMFFORCE, seed 004 slide 74) along torque_axes', 'volts',
                       choices=('volts', 'torque')),
        'layout': Field('str', 'volts drive: three_orthogonal or four_cant20 (spec §4)', 'three_orthogonal',
                        choices=('three_orthogonal', 'four_cant20')),
        'torque_axes': Field('floats', 'torque drive: unit wheel axes, body axes, one (x, y, z) triple per wheel '
                             '(EMFFORCE: one wheel about z)', [0.0, 0.0, 1.0], lo=-1.0, hi=1.0),
        'max_torque': quantity('torque drive: torque limit of each wheel (EMFFORCE: 0.1 N·m)', 0.1, 'nm', {'nm': 1.0},
                         lo=1e-6, hi=1e4),
        'capacity': quantity('torque drive: momentum capacity of each wheel (0: not given, unlimited)', 0.0, 'nms',
                       MOMENTUM, lo=0.0, hi=1e6),
        'failed_wheel': Field('int', 'index of a failed wheel of the 4-wheel cluster, −1 for none', -1,
                              lo=-1, hi=3),
        'initial_momentum': quantity('initial wheel (or CMG) momentum, body axes', [0.0, 0.0, 0.0], 'nms', MOMENTUM,
                               length=3, lo=-1e5, hi=1e5),
        'cmg_capacity': quantity('kind cmg: |h| capacity of the CMG momentum envelope (seed 000 §5: nearly 12,000 '
                           'ft-lb-sec)', 12000.0 * u.FT_LB_S_NMS, 'nms', MOMENTUM, lo=1.0, hi=1e6),
    },
    'disturbance': {
        'bias_momentum_per_orbit': quantity('body-fixed disturbance: the bias momentum it delivers per orbit (a constant '
                                      'torque = this / orbit period), body axes; the gravity gradient is the '
                                      "rigid body's own (dynamics.gravity_gradient)", [0.0, 0.0, 0.0], 'nms',
                                      MOMENTUM, length=3, lo=-1e6, hi=1e6),
        'once_per_orbit_cos': quantity('body-fixed cyclic torque, once per orbit: the cos u part (u = argument of '
                                 'latitude)', [0.0, 0.0, 0.0], 'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
        'once_per_orbit_sin': quantity('body-fixed cyclic torque, once per orbit: the sin u part', [0.0, 0.0, 0.0], 'nm',
                                 TORQUE, length=3, lo=-1e3, hi=1e3),
        'twice_per_orbit_cos': quantity('body-fixed cyclic torque, twice per orbit: the cos 2u part', [0.0, 0.0, 0.0],
                                  'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
        'twice_per_orbit_sin': quantity('body-fixed cyclic torque, twice per orbit: the sin 2u part', [0.0, 0.0, 0.0],
                                  'nm', TORQUE, length=3, lo=-1e3, hi=1e3),
    },
    'formation': {
        'frame': Field('str', 'planar: the EMFFORCE air-bearing testbed (x, y, yaw); free_space: 3-D, no field; '
                       'hill: relative motion about a circular LEO orbit (Clohessy–Wiltshire); line: the 1-D airtrack '
                       '(slides 52–55: motion along the frame x axis only, the track holds the rest)', 'planar',
                       choices=('planar', 'free_space', 'hill', 'line')),
        'track_tilt': quantity('line: tilt of the track, > 0 rising along +x (away from an electromagnet at the '
                               'origin): every free vehicle feels gravity −g sin θ along x', 0.0, 'rad', ANGLE,
                               lo=-math.pi / 2, hi=math.pi / 2),
        'em_model': Field('str', 'inter-vehicle wrench: far_field (exact dipole–dipole) or near_field (Biot–Savart '
                          'of the coils)', 'far_field', choices=('far_field', 'near_field')),
        'segments': Field('int', 'near field: straight segments per coil loop', 64, lo=3, hi=4096),
        'earth_field': Field('bool', 'hill: the Earth field\'s torque and force on every dipole (orbit, earth '
                             'sections)', True),
        'law': Field('str', 'hold: keep the second vehicle at relative_position from the first; spin_up: spin '
                     'the pair about the frame z axis; array_spin: spin N vehicles at their array_position about '
                     'the frame z axis (PD); lqr: LQR about the steady spin of the array at spin_rate; '
                     'airtrack_open_loop: the airtrack\'s electromagnet at the constant dipole that holds the slider '
                     'at airtrack_separation; airtrack_lqr: that dipole plus LQR feedback on the separation', 'hold',
                     choices=('hold', 'spin_up', 'array_spin', 'lqr') + AIRTRACK_LAWS),
        'relative_position': quantity('hold: the second vehicle\'s position relative to the first, formation frame',
                                [2.5, 0.0, 0.0], 'm', LENGTH, length=3, lo=-1e5, hi=1e5),
        'hold_natural_frequency': quantity('hold: PD natural frequency', 0.1, 'rad_s', {'rad_s': 1.0}, lo=1e-4, hi=10.0),
        'hold_damping_ratio': Field('float', 'hold: PD damping ratio', 0.9, lo=0.05, hi=5.0),
        'spin_rate': quantity('spin_up: commanded rate of the array about the frame z axis', 0.05, 'rad_s', RATE,
                        lo=-1.0, hi=1.0),
        'spin_ramp': quantity('spin_up: rate reference ramp', 1e-3, 'rad_s2', {'rad_s2': 1.0, 'deg_s2': DEG},
                        lo=1e-7, hi=1.0),
        'spin_separation': quantity('spin_up: separation held while spinning', 2.5, 'm', LENGTH, lo=0.01, hi=1e5),
        'spin_start': quantity('spin_up: when the rate reference starts', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'radial_natural_frequency': quantity('spin_up: radial PD natural frequency', 0.2, 'rad_s', {'rad_s': 1.0},
                                       lo=1e-4, hi=10.0),
        'radial_damping_ratio': Field('float', 'spin_up: radial PD damping ratio', 0.9, lo=0.05, hi=5.0),
        'rate_gain_per_s': Field('float', 'spin_up: rate loop gain, 1/s', 0.2, lo=0.0, hi=100.0),
        'attitude_natural_frequency': quantity('attitude hold by the wheels: PD natural frequency', 0.5, 'rad_s',
                                         {'rad_s': 1.0}, lo=1e-4, hi=100.0),
        'attitude_damping_ratio': Field('float', 'attitude hold: PD damping ratio', 0.8, lo=0.05, hi=5.0),
        'max_force': quantity('limit of the commanded relative force', 0.5, 'n', {'n': 1.0}, lo=0.0, hi=1e4),
        'array_natural_frequency': quantity('array_spin: PD natural frequency of each vehicle on its place', 0.2,
                                            'rad_s', {'rad_s': 1.0}, lo=1e-4, hi=10.0),
        'array_damping_ratio': Field('float', 'array_spin: PD damping ratio', 0.9, lo=0.05, hi=5.0),
        **{f'lqr_{name}_weight': Field('float', f'lqr: dimensionless weight on {what} (normalised by its scale, '
                                       'acds_controller.formation_lqr; > 0)', 1.0, lo=0.0, hi=1e12)
           for name, what in (('radial', 'the relative positions along the nominal baselines (Δr)'),
                              ('tangential', 'the relative positions across them in the spin plane (d·Δφ)'),
                              ('normal', 'the relative positions along the spin axis (d·Δψ)'),
                              ('radial_rate', 'the relative velocities along the baselines (Δṙ)'),
                              ('tangential_rate', 'the relative velocities across them in the spin plane (d·Δφ̇)'),
                              ('normal_rate', 'the relative velocities along the spin axis (d·Δψ̇)'),
                              ('attitude', 'the attitude errors'), ('attitude_rate', 'the body rates'),
                              ('coil', 'the coil moments'), ('wheel', 'the wheel torques'))},
        'airtrack_separation': quantity('airtrack laws: the commanded separation of the slider from the '
                                        'electromagnet (the step\'s target)', 0.5, 'm', LENGTH, lo=1e-3, hi=100.0),
        **{f'airtrack_{name}_scale': quantity(f'airtrack_lqr: Bryson scale of {what}: its weight is 1/scale² '
                                              '(Q = diag(1/Δx², 1/Δv²), R = 1/Δμ²; > 0)', default, si, units,
                                              lo=0.0, hi=1e6)
           for name, what, default, si, units in (
               ('position', 'the separation error Δx', 0.01, 'm', LENGTH),
               ('velocity', 'the slider\'s velocity Δv', 0.01, 'm_s', {'m_s': 1.0}),
               ('dipole', 'the electromagnet\'s dipole Δμ', 100.0, 'am2', {'am2': 1.0}))},
        'dump': Field('bool', 'hill with the Earth field: Earth as a momentum dump (slides 31–33)', False),
        'dump_start': quantity('dump: start dumping the vehicle whose wheels hold more than this', 0.5, 'nms', MOMENTUM,
                         lo=0.0, hi=1e6),
        'dump_done': quantity('dump: stop (and pick again) below this', 0.05, 'nms', MOMENTUM, lo=0.0, hi=1e6),
    },
    'vehicle': {
        'mass': quantity('vehicle mass', REQUIRED, 'kg', {'kg': 1.0, 'lb': u.LB_KG}, lo=1e-3, hi=1e7),
        'initial_position': quantity('initial position, formation frame (hill: relative to the reference orbit)',
                               [0.0, 0.0, 0.0], 'm', LENGTH, length=3, lo=-1e7, hi=1e7),
        'initial_velocity': quantity('initial velocity, formation frame', [0.0, 0.0, 0.0], 'm_s', {'m_s': 1.0},
                               length=3, lo=-1e4, hi=1e4),
        'magnet': Field('str', 'coils: electromagnets (the coil_* keys); permanent: a permanent magnet of '
                        'permanent_dipole and no coil (the airtrack slider, seed 004 slide 52)', 'coils',
                        choices=('coils', 'permanent')),
        'permanent_dipole': quantity('magnet permanent: the magnet\'s constant dipole, body axes', [0.0, 0.0, 0.0],
                                     'am2', {'am2': 1.0}, length=3, lo=-1e6, hi=1e6),
        'fixed': Field('bool', 'frame line: the vehicle is bolted to the track (the airtrack\'s electromagnet): it '
                       'never moves, its mount takes the force on it', False),
        'array_position': quantity('array_spin, lqr: the vehicle\'s place in the spinning array at t = 0, formation '
                                   'frame (about the array\'s centre of mass)', [0.0, 0.0, 0.0], 'm', LENGTH, length=3,
                                   lo=-1e7, hi=1e7),
        'coil_axes': Field('floats', 'unit axes of the coils in body axes, one (x, y, z) triple per coil, '
                           'orthonormal (EMFFORCE: two vertical coils along x and y)', [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                           lo=-1.0, hi=1.0),
        'coil_radii': quantity('coil radii (EMFFORCE: 0.375 m outer, 0.345 m inner)', [0.375, 0.345], 'm', LENGTH,
                         lo=1e-3, hi=100.0),
        'coil_turns': Field('floats', 'turns of each coil (EMFFORCE: 100 wraps)', [100.0, 100.0], lo=1.0, hi=1e6),
        'coil_max_current': quantity('current limit of each coil (EMFFORCE: ~100 A)', [100.0, 100.0], 'a', {'a': 1.0},
                               lo=1e-6, hi=1e5),
    },
}

TOPICS = (
    Topic(topics.TRUTH_ODOMETRY, 'nav_msgs/msg/Odometry', 'm, m/s, rad/s',
          'ECI position/velocity, q body→ECI, ω body (a formation vehicle: formation frame)'),
    Topic(topics.TRUTH_B_BODY, 'sensor_msgs/msg/MagneticField', 'T', 'Earth field at the spacecraft, body axes'),
    Topic(topics.TRUTH_SUN_COSINES, VECTOR3, '', '(B13, B23, B33): the sun frame\'s z in body components'),
    Topic(topics.TRUTH_TORQUE_MAG, VECTOR3, 'N·m', 'M × B_true over the step, body'),
    Topic(topics.TRUTH_TORQUE_GG, VECTOR3, 'N·m', 'gravity-gradient torque, body'),
    Topic(topics.GYRO, 'sensor_msgs/msg/Imu', 'rad/s', 'ideal rate gyros (angular_velocity, body; covariance 0)'),
    Topic(topics.TRUTH_WRENCH, 'geometry_msgs/msg/WrenchStamped', 'N, N·m', 'formation: external force + torque, body'),
    Topic(topics.SUN_SENSOR, VECTOR3, '', 'unit sun vector in body; zero vector = sun absent'),
    Topic(topics.WHEEL_MOMENTUM, VECTOR3, 'N·m·s', 'total wheel (or CMG) momentum h(t_k), body'),
    Topic(topics.WHEEL_TORQUE, VECTOR3, 'N·m', 'ḣ over [t_k, t_k+1], body'),
)


def _rigid_body(_params: dict[str, Any]) -> Ports:
    truth = dict(stamp_offset=1)  # step 0 comes from start(), step k + 1 from the stage of step k
    return Ports(
        'dynamics.rigid_body_step:RigidBodyStep',
        (Stage('integrate', (
            Input('dipole', topics.DIPOLE_AVG, 'em_driver'),
            Input('wheel_h', topics.WHEEL_MOMENTUM, 'reaction_wheels'),
            Input('wheel_hdot', topics.WHEEL_TORQUE, 'reaction_wheels'),
            Input('mode', topics.MODE, 'ascs_mode_manager'),
            Input('gas_wrench', topics.COLD_GAS_WRENCH, 'cold_gas'),  # the cold-gas thrusters (seed 002 §5)
        )),),
        (Output('odometry', topics.TRUTH_ODOMETRY, ECI, BODY, **truth),
         Output('b_body', topics.TRUTH_B_BODY, BODY, **truth),
         Output('sun_cosines', topics.TRUTH_SUN_COSINES, BODY, **truth),  # the sun frame's z in body components
         Output('torque_mag', topics.TRUTH_TORQUE_MAG, BODY, **truth),
         Output('torque_gg', topics.TRUTH_TORQUE_GG, BODY, **truth),
         Output('gyro', topics.GYRO, BODY, **truth),
         Output('sun_sensor', topics.SUN_SENSOR, BODY, **truth),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _reaction_wheels(params: dict[str, Any]) -> Ports:
    """The momentum store the scenario names: the Workshop's CMGs (``wheels.kind: cmg``, the controller's
    momentum-rate command, seed 000), torque-commanded wheels (``wheels.drive: torque``, a formation vehicle,
    seed 004) or square-law wheels driven by the controller's volts (spec §4)."""
    if params['wheels_kind'] == 'cmg':
        stepper, stage = 'cmg_step:CmgStep', Stage('gimbal', (Input('torque', topics.CMG_TORQUE, 'acds_controller'),))
    elif params['wheels_drive'] == 'torque':
        stepper, stage = 'torque_wheels_step:TorqueWheelsStep', Stage(
            'drive', (Input('torque', topics.WHEEL_TORQUE_COMMAND, 'formation_controller'),))
    else:
        stepper, stage = 'reaction_wheels_step:ReactionWheelsStep', Stage(
            'drive', (Input('volts', topics.WHEEL_VOLTS, 'acds_controller'),))
    return Ports(
        f'dynamics.{stepper}',
        (stage,),
        (Output('momentum', topics.WHEEL_MOMENTUM, BODY),
         Output('torque', topics.WHEEL_TORQUE, BODY),
         Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))


def _formation_dynamics(params: dict[str, Any]) -> Ports:
    """The formation's time owner: every vehicle's translation and attitude (spec §10; seed 004).

    Step k takes each vehicle's achieved dipole and wheel momentum/rate of step k (from that vehicle's
    em_driver and reaction_wheels, in its namespace) and returns each vehicle's truth of step k + 1
    under ``/acds/<vehicle>/``: the single-vehicle topic names, so each vehicle's nodes read them as a
    single vehicle's nodes would.
    """
    truth = dict(stamp_offset=1)
    inputs: list[Input] = []
    outputs: list[Output] = []
    for v in params['formation_vehicles']:
        inputs += [Input(f'{v}/dipole', f'{v}/{topics.DIPOLE_AVG}', f'{v}/em_driver'),
                   Input(f'{v}/wheel_h', f'{v}/{topics.WHEEL_MOMENTUM}', f'{v}/reaction_wheels'),
                   Input(f'{v}/wheel_hdot', f'{v}/{topics.WHEEL_TORQUE}', f'{v}/reaction_wheels')]
        body = vehicle_body(v)
        outputs += [Output(f'{v}/odometry', f'{v}/{topics.TRUTH_ODOMETRY}', FORMATION, body, **truth),
                    Output(f'{v}/gyro', f'{v}/{topics.GYRO}', body, **truth),
                    Output(f'{v}/b_body', f'{v}/{topics.TRUTH_B_BODY}', body, **truth),
                    Output(f'{v}/wrench', f'{v}/{topics.TRUTH_WRENCH}', body, **truth)]
    return Ports('dynamics.formation_step:FormationDynamicsStep', (Stage('integrate', tuple(inputs)),), tuple(outputs))


def check_formation(sc: Any) -> str:
    """A formation's vehicles are apart, its law fits their number and frame, its LQR weights are > 0 ('' when
    so; seed 004)."""
    if not sc.formation:
        return ''
    vehicles = sc.values['vehicles']
    f = sc.values['formation']
    keys = [('initial_position', 'start at')] + ([('array_position', 'have their array places at')]
                                                 if f['law'] in ('array_spin', 'lqr') else [])
    for key, what in keys:
        for i, a in enumerate(vehicles):
            for b in vehicles[i + 1:]:
                if a['vehicle'][key] == b['vehicle'][key]:
                    return (f'vehicles.{b["name"]}.vehicle.{key}_m: vehicles {a["name"]} and {b["name"]} {what} the '
                            f'same position {a["vehicle"][key]} m')
    line = f['frame'] == 'line'
    if line != (f['law'] in AIRTRACK_LAWS):
        return (f'formation.law: frame line (the airtrack) flies the laws {", ".join(AIRTRACK_LAWS)} and they fly '
                f'only it, got law {f["law"]!r} in frame {f["frame"]!r}')
    if f['track_tilt'] != 0.0 and not line:
        return f'formation.track_tilt: the airtrack\'s tilt is for frame line, got frame {f["frame"]!r}'
    for v in vehicles:
        vh, where = v['vehicle'], f'vehicles.{v["name"]}.vehicle'
        if vh['fixed'] and not line:
            return f'{where}.fixed: a vehicle bolted to the track is the airtrack\'s (frame line), got {f["frame"]!r}'
        if (vh['magnet'] == 'permanent') != any(vh['permanent_dipole']):
            return (f'{where}.permanent_dipole_am2: a permanent magnet (magnet: permanent) has a non-zero dipole and '
                    f'only it, got magnet {vh["magnet"]} with {vh["permanent_dipole"]} A·m²')
        if line and (any(vh['initial_position'][1:]) or any(vh['initial_velocity'][1:])
                     or (vh['fixed'] and vh['initial_velocity'][0] != 0.0) or any(v['spacecraft']['initial_rates'])):
            return (f'{where}: frame line puts every vehicle on the track (initial_position_m and initial_velocity_m_s '
                    'along x only, spacecraft.initial_rates zero) and a fixed one at rest')
    if line and f['em_model'] != 'far_field':
        return 'formation.em_model: the airtrack\'s permanent magnet is a point dipole (far_field)'
    if f['law'] in ('hold', 'spin_up') and len(vehicles) != 2:
        return f'formation.law: {f["law"]!r} flies a pair of vehicles, got {len(vehicles)} (array_spin or lqr fly N)'
    if f['law'] in ('array_spin', 'lqr') and f['frame'] not in ('planar', 'free_space'):
        return (f'formation.frame: law {f["law"]!r} spins the array about the frame z axis (planar or free_space), '
                f'got {f["frame"]!r}')
    if f['law'] == 'lqr':
        if f['frame'] != 'free_space':
            return f'formation.frame: law lqr is designed on the 3-D linearised array (free_space), got {f["frame"]!r}'
        for key in sorted(k for k in f if k.startswith('lqr_')):
            if not f[key] > 0.0:
                return f'formation.{key}: {f[key]:g} is not a positive LQR weight'
    return ''


#: What the dynamics package adds to the graph.
PACKAGE = Package(
    'dynamics',
    nodes=(
        Node('rigid_body', ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics', 'em_driver', 'wheels', 'disturbance'),
             _rigid_body, time_owner=True),
        Node('reaction_wheels', ('wheels',), _reaction_wheels, in_vehicle=True),
        Node('formation_dynamics', ('orbit', 'earth', 'sun', 'dynamics', 'formation'), _formation_dynamics,
             time_owner=True, every_vehicle=('spacecraft', 'vehicle', 'em_driver')),
    ),
    sections=SECTIONS,
    vehicle_sections=('vehicle', 'wheels'),
    topics=TOPICS,
    checks=(check_formation,),
)
