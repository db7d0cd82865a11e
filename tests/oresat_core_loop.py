"""Test-only composition of the OreSat detumble cores in one process (seed 003; no ROS).

Step k, in the graph's order: rigid_body's truth(t_k) → the law (ideal gyro and
magnetometer: true ω and B in body axes) M_k = sat(−(k_ω/|B|)(B̂ × ω)) at the rods' full-duty
moment → the torque-rod assembly drives [t_k, t_k+1] → rigid_body integrates with the
step-average dipole. The cores are the ones the nodes will host; the scenario schema and the
node wiring come later.

OreSat-like CubeSat (the seed gives only J_min): a 2U body, 10 × 10 × 22.7 cm, as a uniform
box whose long-axis moment equals the seed's J_min = 5.094e-3 kg·m² (m = 3.06 kg), so
J = diag(15.67, 15.67, 5.094) × 1e-3 kg·m², principal axes = body axes, no products of
inertia. Orbit: circular, period 5560.8 s (altitude 405.8 km), inclination 51.6° (ISS-like),
tilted-dipole field of the dynamics package, gravity gradient on. Initial rates 5°/s per axis
(the seed's worst deployment case). Rods: the design routine's minimum-mass rod for the seed's
constraints with AWG 35 (AWG 36 cannot reach 0.1552 A·m² with two windings, see
``acds design-torque-rod``), one per body axis; PWM drive of ``em_driver.torque_rod``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from acds_common import units
from acds_common.environment import EarthFieldConfig, Orbit, OrbitConfig, Sun, SunConfig, TiltedDipoleField
from acds_controller.b_cross_omega import detumble_gain, detumble_moment
from acds_controller.magnetic_laws import saturate
from dynamics.rigid_body_model import RigidBodyModel, inertia_tensor
from em_driver.torque_rod import TorqueRodAssembly
from em_driver.torque_rod_design import DesignRequest, design_torque_rod

T_ORB_S = 5560.8
XI_RAD = 0.90129
INCLINATION_RAD = math.radians(51.6)
J_MIN_KG_M2 = 5_094_047.43 * units.G_MM2_KG_M2
_BOX_M = (0.10, 0.10, 0.227)
MASS_KG = 12.0 * J_MIN_KG_M2 / (_BOX_M[0] ** 2 + _BOX_M[1] ** 2)
INERTIA_KG_M2 = inertia_tensor(MASS_KG * (_BOX_M[1] ** 2 + _BOX_M[2] ** 2) / 12.0,
                               MASS_KG * (_BOX_M[0] ** 2 + _BOX_M[2] ** 2) / 12.0, J_MIN_KG_M2, 0.0, 0.0, 0.0)
OMEGA0_RAD_S = np.full(3, math.radians(5.0))
ROD_REQUEST = DesignRequest(awg=35)


def altitude_for_period_m(period_s: float) -> float:
    """Circular-orbit altitude with the given period, m."""
    a = (units.EARTH_MU_M3_S2 * (period_s / (2.0 * math.pi)) ** 2) ** (1.0 / 3.0)
    return a - units.EARTH_RADIUS_M


@dataclass
class DetumbleRun:
    """Records every ``record_every`` steps (SI), totals over the run, and the rod used."""

    t_s: list[float] = field(default_factory=list)
    omega_rad_s: list[np.ndarray] = field(default_factory=list)
    energy_j: float = 0.0
    peak_current_a: float = 0.0
    mean_duty: np.ndarray = field(default_factory=lambda: np.zeros(3))
    design_summary: str = ''


def run(steps: int, dt_s: float = 1.0, record_every: int = 1, substeps: int = 2) -> DetumbleRun:
    """Run ``steps`` control periods of ``dt_s`` s through the cores."""
    model = RigidBodyModel(
        INERTIA_KG_M2,
        Orbit(OrbitConfig(kind='circular', inclination_rad=INCLINATION_RAD,
                          altitude_m=altitude_for_period_m(T_ORB_S))),
        TiltedDipoleField(EarthFieldConfig()), Sun(SunConfig()), gravity_gradient=True, substeps=substeps,
        omega0_body_rad_s=OMEGA0_RAD_S)
    design = design_torque_rod(ROD_REQUEST)
    rods = TorqueRodAssembly([design.rod] * 3)
    limit = float(rods.max_moment_am2().min())
    k_omega = detumble_gain(T_ORB_S, XI_RAD, float(np.linalg.eigvalsh(INERTIA_KG_M2)[0]))
    out = DetumbleRun(design_summary=f'{design.mass_kg * 1e3:.1f} g, {design.moment_am2:.4f} A·m², '
                                     f'l_c {design.rod.core_length_m * 1e3:.2f} mm, r_c {design.rod.core_radius_m * 1e3:.3f} mm')
    zero = np.zeros(3)
    duty_sum = np.zeros(3)
    for k in range(steps):
        truth = model.truth(zero)
        if k % record_every == 0:
            out.t_s.append(truth.t_s)
            out.omega_rad_s.append(truth.omega_body_rad_s)
        command = saturate(detumble_moment(truth.b_body_t, truth.omega_body_rad_s, k_omega), limit)
        result = rods.step(command, dt_s)
        out.energy_j += float(np.sum(result.power_w)) * dt_s
        out.peak_current_a = max(out.peak_current_a, float(np.max(np.abs(result.coil_current_a))))
        duty_sum += result.duty
        model.advance(dt_s, result.avg_dipole_am2, zero, zero)
    out.t_s.append(model.t_s)
    out.omega_rad_s.append(model.omega_body_rad_s)
    out.mean_duty = duty_sum / max(steps, 1)
    return out
