"""Scenario sections → the transfer assembly and DPA cores, or the Workshop computer (pure, no rclpy).

The controller stepper receives the ``spacecraft``, ``controller``, ``magnetometer``,
``wheels``, ``orbit`` and ``earth`` scenario sections as SI values ({field: value}, see
``acds_common.scenario.SCHEMA``) and builds its cores here; the launcher's
pre-flight builds the same stepper before any process starts. With ``wheels.kind``
cmg it builds the AAP Workshop computer (:func:`build_workshop`, seed 000) instead of
the HEAO DPA.

The seed-003 gains are design values the scenario states, as a flight program would carry
them, not quantities taken from the simulated orbit or body: k_ω = (4π/T_orb)(sin ξ + 1)J_min
from ``controller.detumble_orbit_period``, ``magnetic_inclination`` (ξ) and ``detumble_j_min``
(:func:`~acds_controller.b_cross_omega.detumble_gain`), and the dumping gain k_h from
``dump_time``, ξ and ``dump_residual_fraction``
(:func:`~acds_controller.b_cross_omega.dump_gain_per_s`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from acds_common.coupling import coupling_from_section
from acds_common.environment import EnvironmentModelError, field_from_section, orbit_from_section
from acds_common.inertia import inertia_tensor
from acds_common.units import dump_gain_si_to_seed
from acds_common.validation import scenario_key

from acds_controller.b_cross_omega import detumble_gain, dump_gain_per_s
from acds_controller.cmg_dump import DumpLawConfig, OrbitClock
from acds_controller.cmg_hold import HoldGains
from acds_controller.dpa import Dpa, DpaConfig
from acds_controller.magnetic_laws import ControllerError
from acds_controller.transfer_assembly import TransferAssembly
from acds_controller.wheel_laws import HEAO_A_ACQUISITION, HEAO_B_ACQUISITION, HEAO_B_ACQUISITION_PRELIMINARY
from acds_controller.workshop import FieldPrediction, WorkshopComputer, WorkshopConfig, design_dump

__all__ = ['WHEEL_GAIN_SETS', 'build_dpa', 'build_workshop', 'dump_law_config']

#: Scenario ``controller.wheel_gains`` → Table 4-2 acquisition gain set.
WHEEL_GAIN_SETS = {'heao_a': HEAO_A_ACQUISITION, 'heao_b': HEAO_B_ACQUISITION,
                   'heao_b_preliminary': HEAO_B_ACQUISITION_PRELIMINARY}


def build_dpa(sc: dict[str, Any], c: dict[str, Any], mag: dict[str, Any]) -> tuple[TransferAssembly, Dpa]:
    """Transfer assembly and DPA from the scenario's spacecraft, controller and magnetometer sections (SI).

    The coupling compensation subtracts exactly the Δ the magnetometer is built with
    (:func:`acds_common.coupling.coupling_from_section`). A core's refusal names the section.
    """
    with scenario_key('controller', ControllerError):
        return _build(sc, c, mag)


def _build(sc: dict[str, Any], c: dict[str, Any], mag: dict[str, Any]) -> tuple[TransferAssembly, Dpa]:
    ta = TransferAssembly(adc_bits=c['adc_bits'])
    dpa = Dpa(DpaConfig(
        inertia_kg_m2=inertia_tensor(*sc['inertia']) * sc['inertia_scale'],
        acquisition_law=c['acquisition_law'], unloading_law=c['unloading_law'],
        acquisition_gain_study=c['acquisition_gain_per_s_g2'],
        bdot_gain_study=c['bdot_gain_ft_lb_s_per_g2'],
        unloading_gain_mode_1b_study=c['unloading_gain_mode_1b_per_s_g2'],
        unloading_gain_scan_study=c['unloading_gain_scan_per_s_g2'],
        unloading_gain_point_study=c['unloading_gain_point_per_s_g2'],
        max_moment_am2=c['max_moment_am2'],
        coupling_compensation=c['coupling_compensation'],
        coupling_delta_t_per_am2=coupling_from_section(mag),
        wheel_gains_acquisition=WHEEL_GAIN_SETS[c['wheel_gains']],
        scan_rate_rad_s=c['scan_rate'],
        target_q_body_to_eci=np.array(c['target_quaternion_xyzw']),
        lead_time_s=c['lead_time_s'],
        detumble_gain_kg_m2_s=detumble_gain(c['detumble_orbit_period'], c['magnetic_inclination'],
                                            c['detumble_j_min']),
        dump_gain_per_s=dump_gain_per_s(c['dump_time'], c['magnetic_inclination'], c['dump_residual_fraction'])))
    return ta, dpa


def dump_law_config(c: dict[str, Any]) -> DumpLawConfig | None:
    """The dump law of the ``controller`` section (None for ``dump_law: none``), k back in the seed's units."""
    if c['dump_law'] == 'none':
        return None
    return DumpLawConfig(law=c['dump_law'], k_seed=dump_gain_si_to_seed(c['dump_gain']),
                         h_0_nms=tuple(c['dump_h_0']), max_moment_am2=c['max_moment_am2'],
                         h_b_nms=tuple(c['dump_bias_momentum']))


def build_workshop(sc: dict[str, Any], c: dict[str, Any], orbit: dict[str, Any],
                   earth: dict[str, Any]) -> tuple[TransferAssembly, WorkshopComputer]:
    """Transfer assembly and the AAP Workshop computer (seed 000) from the spacecraft, controller, orbit and earth
    sections (SI). The on-board field prediction flies the controller's own copy of the orbit and field models;
    orbits are counted from the ascending node (:meth:`acds_common.environment.Orbit.node_time_s`). The flown
    dump law (k from the loop-gain condition, the §9 |M| limit, §10 day-only dumping) is designed on that
    prediction (:func:`~acds_controller.workshop.design_dump`)."""
    with scenario_key('orbit', EnvironmentModelError):
        orbit_model = orbit_from_section(orbit)
    with scenario_key('earth', EnvironmentModelError):
        field = field_from_section(earth)
    with scenario_key('controller', ControllerError):
        clock = OrbitClock(orbit_model.period_s, orbit_model.node_time_s())
        prediction = FieldPrediction(orbit_model, field, np.array(c['target_quaternion_xyzw']))
        dump, design = dump_law_config(c), None
        if dump is not None:
            dump, design = design_dump(
                dump, prediction, clock, gain_rule=c['dump_gain_rule'], largest_gain=c['dump_loop_gain'],
                moment_limit_fraction=c['dump_moment_limit_fraction'] or None,
                day_moment_factor=c['dump_day_moment_factor'] if c['dump_day_only'] else None)
        cfg = WorkshopConfig(
            inertia_kg_m2=inertia_tensor(*sc['inertia']) * sc['inertia_scale'],
            target_q_body_to_eci=np.array(c['target_quaternion_xyzw']), dump=dump,
            hold=HoldGains(c['cmg_hold_bandwidth'], c['cmg_hold_damping']), h_s_init=c['dump_h_s_init'])
        computer = WorkshopComputer(cfg, clock, prediction, design)
        return TransferAssembly(adc_bits=c['adc_bits']), computer
