"""CMG attitude hold of the Workshop: the commanded CMG momentum rate that holds an inertial attitude (seed 000 §1, §4).

Seed: ``000_aap_cmg_dump_levidow.txt``: the external torques "are counteracted by the momentum exchange action of
the control moment gyros (CMGs) used for attitude control" (§1), so the CMG momentum takes up whatever external
torque acts and its bias accumulates until dumped; the magnetic dump adds only software to the digital computer
that already has the CMG momentum (§4, Fig. 2). The seed does not give the attitude loop; this is a standard
computed-torque PD hold with its bandwidth and damping as parameters (assumed, stated in :class:`HoldGains`).

Signs as in :mod:`acds_controller.wheel_laws`: θ is the body's rotation beyond the reference (e.g.
``wheel_laws.inertial_hold_error``), ω the body rate, h the CMG momentum; the body obeys
I ω̇ = −ω × (I ω + h) − ḣ + T_ext (spec §3, CMGs in place of wheels). The command

    ḣ = I (ω_n² θ + 2 ζ ω_n ω) − ω × (I ω + h) + T_ff

makes I ω̇ = −I (ω_n² θ + 2 ζ ω_n ω) + (T_ext − T_ff): with the feedforward T_ff equal to the external torque
the error obeys θ̈ + 2ζω_n θ̇ + ω_n² θ = 0, and the CMGs absorb T_ext exactly. On board T_ff is what the
computer knows of the external torque: the magnetic torque M × B it commands itself (M known, B measured)
and, in the Workshop computer (:mod:`acds_controller.workshop`), the gravity-gradient torque of its orbit
model; what it does not know (the aerodynamic torque) is left to the feedback, which holds it with a
steady error I⁻¹ T / ω_n².
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from acds_controller.magnetic_laws import as_matrix3, as_vector3, check_gain


@dataclass(frozen=True)
class HoldGains:
    """Closed-loop attitude bandwidth ω_n (rad/s) and damping ratio ζ of the hold (not in the seed).

    Default ω_n = 0.05 rad/s (a 2-minute period: fast against the orbital-rate disturbances, slow against
    a control period of a few seconds; keep ω_n·Δt ≲ 0.2), ζ = 0.7.
    """

    bandwidth_rad_s: float = 0.05
    damping: float = 0.7

    def __post_init__(self) -> None:
        check_gain(self.bandwidth_rad_s, 'HoldGains.bandwidth_rad_s', 1e-6, 10.0)
        check_gain(self.damping, 'HoldGains.damping', 0.0, 10.0)


def cmg_hold_rate(theta_err_rad: np.ndarray, omega_rad_s: np.ndarray, inertia_kg_m2: np.ndarray,
                  h_cmg_nms: np.ndarray, feedforward_torque_nm: np.ndarray, gains: HoldGains = HoldGains()) -> np.ndarray:
    """Commanded CMG momentum rate ḣ, N·m (body axes), holding the attitude (see the module docstring).

    ``theta_err_rad``: attitude error (rad); ``omega_rad_s``: body rate (rad/s); ``inertia_kg_m2``: 3×3;
    ``h_cmg_nms``: CMG momentum (N·m·s); ``feedforward_torque_nm``: the external torque known on board (N·m).
    """
    theta = as_vector3(theta_err_rad, 'theta_err_rad')
    omega = as_vector3(omega_rad_s, 'omega_rad_s')
    inertia = as_matrix3(inertia_kg_m2, 'inertia_kg_m2')
    h = as_vector3(h_cmg_nms, 'h_cmg_nms')
    t_ff = as_vector3(feedforward_torque_nm, 'feedforward_torque_nm')
    wn, zeta = gains.bandwidth_rad_s, gains.damping
    return inertia @ (wn * wn * theta + 2.0 * zeta * wn * omega) - np.cross(omega, inertia @ omega + h) + t_ff
