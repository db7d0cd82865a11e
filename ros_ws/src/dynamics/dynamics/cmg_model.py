"""Control moment gyros as an ideal momentum-exchange store with a spherical capacity (seed 000 §1, §5).

Seed: ``000_aap_cmg_dump_levidow.txt``: the Workshop's attitude is held by "the momentum exchange
action of the control moment gyros"; "the present CMG system has a |ΔH_CMG| capacity of nearly
12000 ft-lb-sec" (§5 footnote). The seed states the capacity as the magnitude of the momentum
vector, not per axis, so the store here is a sphere: |h| ≤ capacity in any direction (gimbal
steering, singularities and torque limits are not modelled; the seed gives none).

Same conventions and step shape as :class:`dynamics.wheels_model.ReactionWheels`: h (body axes,
N·m·s) is the CMGs' momentum, ``step`` takes the commanded momentum rate ḣ (N·m, what the attitude
loop asks of the CMGs) and returns (h at step start, step-mean ḣ); the body feels −ḣ. At capacity
no momentum is taken beyond the sphere: the end-of-step momentum is brought back onto it along the
radius, so the outward (saturating) part of the command is lost while its tangential part and any
inward command still act.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from acds_common import units

from dynamics.errors import DynamicsError, finite_float, finite_vector3

#: |ΔH_CMG| capacity of the present CMG system, N·m·s (§5 footnote: "nearly 12000 ft-lb-sec").
SEED_CAPACITY_NMS = units.ftlbs_to_nms(12000.0)


@dataclass(frozen=True)
class CmgConfig:
    """``capacity_nms``: radius of the spherical momentum envelope, N·m·s (seed ≈ 12,000 ft-lb-sec)."""

    capacity_nms: float = SEED_CAPACITY_NMS

    def __post_init__(self) -> None:
        if finite_float('CmgConfig.capacity_nms', self.capacity_nms) <= 0.0:
            raise DynamicsError(f'CmgConfig.capacity_nms must be > 0 N·m·s, got {self.capacity_nms}')


class ControlMomentGyros:
    """Ideal CMG momentum store: ḣ as commanded, |h| limited to the capacity sphere."""

    def __init__(self, cfg: CmgConfig, h0_body_nms: np.ndarray | None = None) -> None:
        self.cfg = cfg
        h0 = np.zeros(3) if h0_body_nms is None else finite_vector3('h0_body_nms', h0_body_nms)
        if np.linalg.norm(h0) > cfg.capacity_nms * (1.0 + 1e-12):
            raise DynamicsError(f'h0_body_nms {h0.tolist()} N·m·s has magnitude {np.linalg.norm(h0):.6g}, beyond '
                                f'the CMG capacity {cfg.capacity_nms:.6g} N·m·s')
        self._h = h0

    def momentum_body_nms(self) -> np.ndarray:
        """CMG momentum in body axes, N·m·s."""
        return self._h.copy()

    def saturated(self) -> bool:
        """True when |h| is at the capacity."""
        return bool(np.linalg.norm(self._h) >= self.cfg.capacity_nms * (1.0 - 1e-12))

    def step(self, hdot_command_body_nm: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Apply the commanded ḣ (N·m, body) for ``dt_s`` s; return (h at step start N·m·s, mean ḣ N·m)."""
        hdot = finite_vector3('hdot_command_body_nm', hdot_command_body_nm)
        dt = finite_float('dt_s', dt_s)
        if dt <= 0.0:
            raise DynamicsError(f'dt_s must be > 0 s, got {dt}')
        h_start = self._h
        h_end = h_start + hdot * dt
        norm = float(np.linalg.norm(h_end))
        if norm > self.cfg.capacity_nms:
            h_end = h_end * (self.cfg.capacity_nms / norm)
        self._h = h_end
        return h_start.copy(), (h_end - h_start) / dt
