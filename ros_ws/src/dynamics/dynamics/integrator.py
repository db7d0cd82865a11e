"""The dynamics' one integrator: a classical fourth-order Runge–Kutta step (spec §3, §10).

The state ``y`` is a tuple of components that add and scale: plain floats or numpy arrays (a
formation's positions, velocities, quaternions and rates). ``rate(y, c)`` returns the derivative of
every component at the stage that lies the fraction ``c`` (0, ½, ½, 1) into the step, and may append
extra items after the derivatives (the torques the stage saw, for their step averages): they are
returned with the stages and never integrated (``zip(..., strict=False)`` stops at the state's last
component). The operations and their order are fixed, so a state gives the same bits on every run.

The rigid body's kernel (:meth:`dynamics.rigid_body_model.RigidBodyModel.advance`) writes this step
out on its seven floats, the same operations in the same order (so the same bits): the generic
step's per-stage lists cost that kernel a fifth of its time, and it runs once per control step of
every single-vehicle run.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any


def rk4_step(y: tuple[Any, ...], rate: Callable[[Sequence[Any], float], Sequence[Any]],
             h: float) -> tuple[tuple[Any, ...], tuple[Sequence[Any], ...]]:
    """(y after one RK4 step of length ``h``, the four stages' ``rate`` results k1…k4)."""
    half = 0.5 * h
    k1 = rate(y, 0.0)
    k2 = rate([a + half * d for a, d in zip(y, k1, strict=False)], 0.5)
    k3 = rate([a + half * d for a, d in zip(y, k2, strict=False)], 0.5)
    k4 = rate([a + h * d for a, d in zip(y, k3, strict=False)], 1.0)
    sixth = h / 6.0
    y1 = [a + sixth * (d1 + 2.0 * d2 + 2.0 * d3 + d4) for a, d1, d2, d3, d4 in zip(y, k1, k2, k3, k4, strict=False)]
    return tuple(y1), (k1, k2, k3, k4)
