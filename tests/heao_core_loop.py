"""Test-only composition of the HEAO cores in one process, in the graph's lockstep order.

Step k, exactly as the six nodes do it: rigid_body's truth(t_k) → magnetometer (B_true k,
achieved dipole k−1) → mode manager (gyro, sun k) → controller (TA + DPA; wheel momentum
h(t_k) = h_{k−1} + ḣ_{k−1}·Δt) → em_driver (moment command k) and wheels (volts k) →
rigid_body integrates t_k → t_k+1 with the step-average dipole and ḣ. Every core is built
from the scenario by the same functions the nodes use, so a scenario means the same thing
here and in the graph; only the ROS transport is missing. Used where the graph would be too
slow for a test (two orbits of normal mode).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
from acds_common.scenario import Scenario
from acds_controller.configuration import build_dpa
from ascs_mode_manager.heao_part import build_core
from dynamics.rigid_body_model import RigidBodyModel, inertia_tensor
from dynamics.wheels_model import ReactionWheels, WheelsConfig
from em_driver.configuration import build_assembly
from magnetometer_sim.configuration import build_magnetometer


@dataclass
class CoreRun:
    """Per-step records of a core loop run (SI)."""

    t_s: list[float] = field(default_factory=list)
    mode: list[str] = field(default_factory=list)
    wheel_h_nms: list[np.ndarray] = field(default_factory=list)
    moment_am2: list[np.ndarray] = field(default_factory=list)
    omega_rad_s: list[np.ndarray] = field(default_factory=list)
    transitions: list[Any] = field(default_factory=list)


def rigid_body(sc: Scenario) -> RigidBodyModel:
    """The rigid_body node's model for the scenario."""
    s, o, e, sun, d = (sc.values[x] for x in ('spacecraft', 'orbit', 'earth', 'sun', 'dynamics'))
    return RigidBodyModel(
        inertia_tensor(*s['inertia']) * s['inertia_scale'],
        Orbit(OrbitConfig(kind=o['kind'], inclination_rad=o['inclination'], raan_rad=o['raan'],
                          altitude_m=o['altitude'], arg_latitude0_rad=o['arg_latitude0'],
                          perigee_altitude_m=o['perigee_altitude'], apogee_radius_m=o['apogee_radius'],
                          arg_perigee_rad=o['arg_perigee'], mean_anomaly0_rad=o['mean_anomaly0'])),
        TiltedDipoleField(EarthFieldConfig(dipole_moment_am2=e['dipole_moment'], tilt_rad=e['dipole_tilt'],
                                           dipole_longitude_rad=e['dipole_longitude'],
                                           greenwich_angle0_rad=e['greenwich_angle0'])),
        Sun(SunConfig(right_ascension_rad=sun['right_ascension'], declination_rad=sun['declination'],
                      eclipse=sun['eclipse'])),
        gravity_gradient=d['gravity_gradient'], substeps=d['substeps'],
        q0_body_to_eci=s['initial_quaternion_xyzw'], omega0_body_rad_s=s['initial_rates'])


def run_cores(sc: Scenario, steps: int, dt_s: float | None = None) -> CoreRun:
    """Run ``steps`` control periods of ``dt_s`` (default: the scenario's Δt) through the cores."""
    dt = sc.control_period_s if dt_s is None else dt_s
    v = sc.values
    model = rigid_body(sc)
    w = v['wheels']
    wheels = ReactionWheels(WheelsConfig(layout=w['layout'],
                                         failed_wheel=w['failed_wheel'] if w['failed_wheel'] >= 0 else None),
                            h0_body_nms=np.array(w['initial_momentum']))
    mag = build_magnetometer(v['magnetometer'], v['']['seed'])
    assembly = build_assembly(v['em_driver'])
    ta, dpa = build_dpa(v['spacecraft'], v['controller'], v['magnetometer'])
    modes = build_core(v['modes'])
    out = CoreRun()
    h_wheel = wheels.momentum_body_nms()
    dipole_prev = np.zeros(3)
    for k in range(steps):
        t = k * dt
        truth = model.truth(h_wheel)
        reading = mag.read(truth.b_body_t, dipole_prev)
        sun = truth.sun_body_unit if truth.sun_present else np.zeros(3)
        out.transitions.extend(modes.step(t, truth.omega_body_rad_s, sun, bool(np.linalg.norm(sun) > 0.0)))
        b = ta.sense(reading.volts, reading.bias_volts)
        cmd = dpa.step(modes.mode, b, truth.omega_body_rad_s, sun, h_wheel, truth.q_body_to_eci, dt)
        result = assembly.step(cmd.moment_command_am2, dt)
        h_start, hdot = wheels.step(cmd.wheel_volts_v, dt)
        model.advance(dt, result.avg_dipole_am2, h_start, hdot)
        h_wheel = h_start + hdot * dt
        dipole_prev = result.avg_dipole_am2
        out.t_s.append(t)
        out.mode.append(modes.mode)
        out.wheel_h_nms.append(h_start)
        out.moment_am2.append(cmd.moment_command_am2)
        out.omega_rad_s.append(truth.omega_body_rad_s)
    return out
