"""The magnetometer_sim node, as its package declares it to the graph (spec §5).

The fluxgate magnetometer assemblies: the true field of step k (rigid_body), the coils' achieved
dipole of step k − 1 (the coupling Δ) and the mode of step k − 1 → output volts, bias volts and the
field they mean. Named in the entry-point group ``acds.nodes`` (setup.py).
"""

from __future__ import annotations

from typing import Any

from acds_common import topics
from acds_common.frames import MAGNETOMETER
from acds_common.graph import Input, Node, Output, Package, Ports, Stage, Topic
from acds_common.schema import COUPLING, FIELD, TIME, Field, quantity

VECTOR3 = 'geometry_msgs/msg/Vector3Stamped'
#: The scenario section this package defines.
SECTIONS: dict[str, dict[str, Field]] = {
    'magnetometer': {
        'active_unit': Field('str', 'active magnetometer assembly', 'A', choices=('A', 'B')),
        'residual_field': quantity('residual body-fixed field seen by the sensor (study: 1 % of max Earth field)',
                             [0.0, 0.0, 0.0], 't', FIELD, length=3, lo=-1e-4, hi=1e-4),
        'coupling_preset': Field('str', 'coupling Δ from the electromagnets: none, cruise (8.75e-6 G/(A·m²) '
                                 'per axis), acquisition (5 % of max field at 2000 A·m² on the other axes), '
                                 'custom (coupling matrix)', 'none',
                                 choices=('none', 'cruise', 'acquisition', 'custom')),
        'coupling': quantity('custom coupling Δ, row-major 3×3 (sensor axis i, magnet j)', [0.0] * 9, 't_per_am2',
                       COUPLING, length=9, lo=-1e-6, hi=1e-6),
        'coupling_signs': Field('floats', 'acquisition preset: sign pattern, row-major 3×3 (±1)',
                                [1.0] * 9, length=9, lo=-1.0, hi=1.0),
        'noise_std': quantity('seeded white noise per axis (0: off)', 0.0, 't', FIELD, lo=0.0, hi=1e-5),
        'accuracy_error': Field('bool', 'apply a seeded ±0.1 %-of-full-scale unit error', False),
        'fault': Field('str', 'fault injected at fault_time: none, bias_shift, stuck_axis, dead_unit', 'none',
                       choices=('none', 'bias_shift', 'stuck_axis', 'dead_unit')),
        'fault_unit': Field('str', 'assembly the fault hits', 'A', choices=('A', 'B')),
        'fault_axis': Field('int', 'axis for stuck_axis/bias_shift (−1: all)', -1, lo=-1, hi=2),
        'fault_value_v': Field('float', 'bias_shift size, V', 0.0, lo=-5.0, hi=5.0),
        'fault_time': quantity('when the fault appears', 0.0, 's', TIME, lo=0.0, hi=1e7),
        'telemetry_every': Field('int', 'diagnostics telemetry every N steps (and at every event)', 10,
                                 lo=1, hi=10**6),
    },
}

PORTS = Ports(
    'magnetometer_sim.magnetometer_step:MagnetometerStep',
    (Stage('sample', (
        Input('b_true', topics.TRUTH_B_BODY, 'rigid_body'),
        Input('dipole', topics.DIPOLE_AVG, 'em_driver', lag=1),
        Input('mode', topics.MODE, 'ascs_mode_manager', lag=1),
    )),),
    (Output('volts', topics.MAG_VOLTS, MAGNETOMETER),
     Output('bias_volts', topics.MAG_BIAS_VOLTS, MAGNETOMETER),
     Output('field', topics.MAG_FIELD, MAGNETOMETER),
     Output('diagnostics', topics.DIAGNOSTICS, every_step=False)))

def _volts_transfer(params: dict[str, Any]) -> list[str]:
    """The output volts' transfer to field, from the node's parameters (the contract's)."""
    from acds_common.parameters import section

    from magnetometer_sim.configuration import volts_transfer
    return volts_transfer(section(params, 'magnetometer'))


def _bias_transfer(params: dict[str, Any]) -> list[str]:
    """What the bias channel means (the contract's)."""
    from acds_common.parameters import section

    from magnetometer_sim.configuration import axis_params
    a = axis_params(section(params, 'magnetometer'))
    return [f'per axis the active assembly\'s zero-field reference voltage, {a.bias_v:g} V nominal, quantised like '
            f'the field channels ({a.step_v:g} V); it is the V_bias of {topics.NAMESPACE}/{topics.MAG_VOLTS}\'s '
            'transfer, and moves only with a bias-shift fault']


#: What the magnetometer_sim package adds to the graph.
PACKAGE = Package(
    'magnetometer_sim',
    nodes=(Node('magnetometer_sim', ('magnetometer',), PORTS),),
    sections=SECTIONS,
    topics=(
        Topic(topics.MAG_FIELD, 'sensor_msgs/msg/MagneticField', 'T', 'the field the volts mean, body',
              realism='calibrated: the simulated sensor\'s own inversion of its volts about the nominal bias, '
                      'no A/D of yours in between; a flight computer on board reads the volts and the bias '
                      'channel (raw, realistic), this topic is the shortcut'),
        Topic(topics.MAG_VOLTS, VECTOR3, 'V', 'per-axis output volts (0…5 V)', transfer=_volts_transfer),
        Topic(topics.MAG_BIAS_VOLTS, VECTOR3, 'V', 'per-axis bias reference volts (2.5 V nominal)',
              transfer=_bias_transfer),
    ),
)
