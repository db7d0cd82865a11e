"""The detumbled run end (``dynamics.stop_when_detumbled``): the time owner ends the run once the spacecraft is detumbled.

Detumbled (seed 003 "Purpose": detumbling after deployment; the torque-rod summary's definition,
``em_driver.oresat_summary``): the norm of the true body rate |ω| below ``dynamics.detumbled_rate`` (0.1°/s), and
staying there. A run cannot know "to the end of the run" before it ends, so the rule asks it for
``dynamics.detumbled_hold`` (whole steps, rounded up): the run ends at step k when |ω(t_j)| is below the rate at every
step j from the first step of the current stretch below it, k − H, through k. The summary's detumble time (the first
t from which |ω| stays below to the end of the run) is then t_(k − H) whenever the run ends so.

Decided from the truth the time owner publishes (the state at t_k), never from a controller's telemetry: the same
for the built-in law and a user's own node, on every engine (the rule is part of the time owner's stepper).
"""

from __future__ import annotations

import math


class DetumbledStop:
    """Counts the steps since |ω| last was at or above the threshold; :meth:`done` says when the hold is reached."""

    def __init__(self, rate_rad_s: float, hold_s: float, dt_s: float) -> None:
        self.rate_rad_s = rate_rad_s
        #: Whole steps |ω| must stay below (rounded up; a hold of 0 ends the run at the first step below).
        self.hold_steps = math.ceil(hold_s / dt_s - 1e-9)
        self._below_since: int | None = None

    def observe(self, k: int, omega_rad_s: float) -> None:
        """|ω| of the truth of step k (the state at t_k), in step order."""
        if omega_rad_s >= self.rate_rad_s:
            self._below_since = None
        elif self._below_since is None:
            self._below_since = k

    def done(self, k: int) -> bool:
        """Whether the run ends at step k: |ω| below the rate at every step from k − hold_steps through k."""
        return self._below_since is not None and k - self._below_since >= self.hold_steps


def detumbled_stop(dynamics: dict[str, object], dt_s: float) -> DetumbledStop | None:
    """The rule of the scenario's ``dynamics`` section (SI values), or None when ``stop_when_detumbled`` is off."""
    if not dynamics['stop_when_detumbled']:
        return None
    return DetumbledStop(float(dynamics['detumbled_rate']), float(dynamics['detumbled_hold']), dt_s)
