"""SSS magnetic attitude and spin control subsystem logic (spec §8, SSS part; seed 001).

Hardware model (body axes as in :mod:`spin_mechanizations`: z spin axis, spacecraft spinning in +z):

* One magnetometer axis in the spin plane, along body **y**; its signal ``s = B_y`` is a sinusoid at the
  spin rate whose amplitude is the spin-plane field.  A polarity-sensing comparator with level
  ``L = 0.075 G`` gives +1 when ``s ≥ L``, −1 when ``s ≤ −L``, 0 in between (seed: "by setting the
  polarity sensing level of the magnetometer at 0.075 G, the system is activated ... during the perigee
  pass").  While the spin-plane amplitude is below L the comparator never fires: that *is* the automatic
  turn-off; above L it fires twice per revolution for a pulse width that grows with the field (more than
  80 % of the time at 0.27 G, seed Fig. 12).
* Spin coil: dipole along body **x**, 500 turns, constant level ±V/R.  ``τ_z = M_x B_y``, so
  ``spin_coil = +comparator`` spins up and ``−comparator`` despins (one-channel constant level).
* Time-constant circuit (seed, "The attitude mode": it "keeps the attitude coil constantly energized
  despite the sinusoidal variations in the magnetometer signal"): modelled as an RC envelope/peak
  detector on the comparator output: a capacitor voltage ``v`` (normalised) is charged to 1 whenever the
  comparator fires (diode charge, fast) and otherwise decays as ``exp(−t/RC)``; the output stays on while
  ``v > release_fraction``.  Hold time = RC·ln(1/release_fraction).  The seed gives no value; it must
  outlast the longest gap between comparator pulses: half a spin period (7.5 s at 4 rpm) just above the
  level, a whole period (15 s) when hardware asymmetry gives half-frequency commutation (seed Fig. 11a).
  Default RC = 30 s, release at 0.5 → hold 20.8 s (one revolution down to 2.9 rpm); the turn-off lag is
  negligible against a perigee pass of tens of minutes.
* The same detector-and-hold defines the *pass* (``torquing_active``, events) in both modes; in spin mode
  it gates the spin-coil drive, whose polarity still follows the comparator pulse by pulse, so the coil is
  off inside the dead zone as in the seed (Figs. 9, 10).
* Attitude coil: dipole along body **+z** (or −z by command), 435 turns, on while the hold is on.
* Direct Attitude: the attitude coil straight from the bus regardless of enable and threshold; the spin
  coil is then inhibited (never both coils on one pass).

Command grammar (case-insensitive, whitespace-separated; :class:`SssCommand`, parsed where the text enters the
mode manager, :mod:`ascs_mode_manager.ground_commands`)::

    sss enable | sss disable
    sss mode spin | sss mode attitude
    sss spin_up | sss despin
    sss direct_attitude on | sss direct_attitude off
    sss attitude_polarity plus | sss attitude_polarity minus     (extension: sign of the attitude dipole)

The flight rule (seed 001, "The attitude mode"): "The spin mode and attitude mode will not both be activated
on a single perigee pass." It holds per *perigee pass*, not per activation:

* Perigee pass: the span over which the spin-plane signal keeps reaching the polarity-sensing level. The
  core follows it with a second copy of the time-constant circuit fed by the comparator *whether or not the
  system is enabled* (its state ``perigee_pass``): the pass starts at the first step at which ``|s| ≥ L``
  and ends at the first step at which the comparator has not fired for the hold time RC·ln(1/release_fraction)
  — the same condition that ends a torquing pass ("no polarity detection for … s (hold released)"). So a
  disable/enable cycle, or a turn-off by command, does not end the perigee pass; the signal staying below the
  level for the hold time does. Inside a perigee the gaps between detections are at most one revolution,
  shorter than the hold, so one perigee is one pass; the next perigee, an orbit later, is a new one.
* On a perigee pass the core records the modes that have been active: spin once a spin-mode torquing pass
  has been on, attitude once the attitude coil has been energised (automatic attitude mode or Direct
  Attitude). Then, until that perigee pass ends: ``sss mode <the other one>`` is refused, ``sss
  direct_attitude on`` is refused after spin, and a spin-mode turn-on after the attitude coil (possible only
  through Direct Attitude, which may be switched off mid-pass) is inhibited (event ``inhibited``). Each
  refusal says why and when the perigee pass ends.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from acds_common.commands import CommandError, decode
from acds_common.units import GAUSS_T, nm_to_dyne_cm, rad_s_to_rpm, tesla_to_gauss

from ascs_mode_manager.ground_commands import CommandResult
from ascs_mode_manager.spin_mechanizations import (
    ATTITUDE_COIL,
    BUS_V,
    MECHANIZATIONS,
    SPIN_COIL,
    AscsError,
    Coil,
    polarity,
)

__all__ = ["AscsError", "Event", "PassAccumulator", "SssAscs", "SssAscsConfig", "SssCommand",
           "SssOutput", "build_sss_ascs"]

_MODES = ("spin", "attitude")
_PASS_MODES = ("spin", "attitude", "direct_attitude")


def _finite(name: str, value: float) -> float:
    if not isinstance(value, int | float | np.floating | np.integer) or not math.isfinite(value):
        raise AscsError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _vector3(name: str, value: np.ndarray) -> np.ndarray:
    v = np.asarray(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise AscsError(f"{name} must be 3 finite numbers, got {value!r}")
    return v


@dataclass(frozen=True)
class SssAscsConfig:
    """Parameters of the SSS ASCS (seed 001; spec §8).

    polarity_level_t: comparator level, T (0.075 G); hold_time_constant_s: RC of the time-constant
    circuit, s; hold_release_fraction: fraction of the charged voltage at which the hold releases;
    spin_coil, attitude_coil: coil sizings; bus_v: main bus, V (28 V).
    """

    polarity_level_t: float = 0.075 * GAUSS_T
    hold_time_constant_s: float = 30.0
    hold_release_fraction: float = 0.5
    spin_coil: Coil = SPIN_COIL
    attitude_coil: Coil = ATTITUDE_COIL
    bus_v: float = BUS_V

    def __post_init__(self) -> None:
        if _finite("polarity_level_t", self.polarity_level_t) <= 0.0:
            raise AscsError(f"polarity_level_t must be > 0 T, got {self.polarity_level_t}")
        if _finite("hold_time_constant_s", self.hold_time_constant_s) <= 0.0:
            raise AscsError(f"hold_time_constant_s must be > 0 s, got {self.hold_time_constant_s}")
        if not 0.0 < _finite("hold_release_fraction", self.hold_release_fraction) < 1.0:
            raise AscsError(f"hold_release_fraction must be in (0, 1), got {self.hold_release_fraction}")
        if _finite("bus_v", self.bus_v) <= 0.0:
            raise AscsError(f"bus_v must be > 0 V, got {self.bus_v}")

    @property
    def hold_time_s(self) -> float:
        """Time the hold stays on after the last comparator pulse, s: RC·ln(1/release_fraction)."""
        return self.hold_time_constant_s * math.log(1.0 / self.hold_release_fraction)


def build_sss_ascs(sss: dict[str, Any]) -> SssAscs:
    """The subsystem the scenario's ``sss`` section describes (SI values; the mechanization sets the spin coil).

    The mode-manager node and the launcher's pre-flight both build it here.
    """
    if sss["mechanization"] not in MECHANIZATIONS:
        raise AscsError(f"mechanization {sss['mechanization']!r} unknown; known: {', '.join(MECHANIZATIONS)}")
    return SssAscs(SssAscsConfig(
        polarity_level_t=sss["polarity_level"], hold_time_constant_s=sss["hold_time_constant_s"],
        hold_release_fraction=sss["hold_release_fraction"], spin_coil=MECHANIZATIONS[sss["mechanization"]].coil,
        bus_v=sss["bus_v"]))


#: The SSS command's actions and the argument each takes ('' = none).
_SSS_ACTIONS: dict[str, tuple[str, ...]] = {
    "enable": ("",), "disable": ("",), "mode": _MODES, "spin_up": ("",), "despin": ("",),
    "direct_attitude": ("on", "off"), "attitude_polarity": ("plus", "minus"),
}
_SSS_USAGE = ("usage: sss enable|disable|mode spin|mode attitude|spin_up|despin|direct_attitude on|off|"
              "attitude_polarity plus|minus")


@dataclass(frozen=True)
class SssCommand:
    """``sss <action> [argument]`` (grammar in the module docstring), parsed: an action of :data:`_SSS_ACTIONS`
    and its argument ('' for none). Applied by the ASCS itself."""

    action: str
    argument: str = ""
    verb: ClassVar[str] = "sss"
    route: ClassVar[str] = ""

    @classmethod
    def parse(cls, args: Sequence[str]) -> SssCommand:
        """The words after the verb → the command (:class:`CommandError`: the usage)."""
        words = [w.lower() for w in args]
        action, rest = (words[0], words[1:]) if words else ("", [])
        if action not in _SSS_ACTIONS or len(rest) > 1 or (rest[0] if rest else "") not in _SSS_ACTIONS[action]:
            raise CommandError(_SSS_USAGE)
        return cls(action, rest[0] if rest else "")

    @property
    def text(self) -> str:
        """The normalised command."""
        return " ".join(w for w in ("sss", self.action, self.argument) if w)


@dataclass(frozen=True)
class Event:
    """An automatic turn-on/turn-off (kind 'turn_on' | 'turn_off'), or a spin-mode turn-on withheld by the
    one-mode-per-perigee-pass rule (kind 'inhibited'), at sim time t_s (s)."""

    t_s: float
    kind: str
    detail: str


@dataclass(frozen=True)
class SssOutput:
    """One step of the subsystem: constant-level drive commands −1/0/+1 per coil, the pass state, the
    events of this step (turn_on, turn_off, inhibited), the steady-state dipole in body axes (A·m²), the
    bus power (W) and the pass mode ('spin' | 'attitude' | 'direct_attitude' | 'off')."""

    spin_coil: int
    attitude_coil: int
    torquing_active: bool
    events: list[Event] = field(default_factory=list)
    dipole_body_am2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    power_w: float = 0.0
    mode: str = "off"


class SssAscs:
    """The SSS ASCS logic (spec §8): enable, mode and direction by command; automatic turn-on/turn-off
    at the polarity-sensing level; spin/attitude exclusivity on a pass; Direct Attitude backup."""

    def __init__(self, config: SssAscsConfig | None = None) -> None:
        self.config = config if config is not None else SssAscsConfig()
        self.enabled = False
        self.mode = "spin"
        self.spin_direction = "spin_up"
        self.direct_attitude = False
        self.attitude_polarity = 1
        self.torquing_active = False
        self._hold_v = 0.0
        self._pass_mode = "off"
        #: Whether a perigee pass is in progress (module docstring: the un-gated copy of the hold circuit).
        self.perigee_pass = False
        self._perigee_v = 0.0
        #: Modes active so far on the current perigee pass → sim time each first was (s).
        self._perigee_modes: dict[str, float] = {}
        self._spin_inhibited = False

    def _already_on_this_pass(self, mode: str) -> str:
        """Why ``mode`` having been active on this perigee pass forbids the other one ('' if it was not)."""
        if not self.perigee_pass or mode not in self._perigee_modes:
            return ""
        cfg = self.config
        article = "an" if mode == "attitude" else "a"
        return (f"this perigee pass already had {article} {mode}-mode pass (from t={self._perigee_modes[mode]:.1f} s), and "
                "spin and attitude mode are never both active on one perigee pass; the perigee pass ends once the "
                f"spin-plane signal has stayed below {tesla_to_gauss(cfg.polarity_level_t):.3f} G "
                f"for {cfg.hold_time_s:.1f} s")

    def parse(self, text: str) -> SssCommand:
        """A ground command's text → its command (:class:`CommandError`: the reason it does not parse)."""
        return decode(text, (SssCommand,))

    def apply(self, cmd: SssCommand, t_s: float) -> CommandResult:
        """Apply a parsed ground command at sim time ``t_s`` (s), or refuse it with the reason (module docstring)."""
        _finite("t_s", t_s)
        verb, arg = cmd.action, cmd.argument
        if verb in ("enable", "disable"):
            self.enabled = verb == "enable"
            level_g = tesla_to_gauss(self.config.polarity_level_t)
            return CommandResult(True, f"{verb}d; automatic turn-on at {level_g:.3f} G "
                                       f"{'armed' if self.enabled else 'inhibited'}")
        if verb == "mode":
            other = "spin" if arg == "attitude" else "attitude"
            why = self._already_on_this_pass(other) if arg != self.mode else ""
            if why:
                return CommandResult(False, why)
            self.mode = arg
            return CommandResult(True, f"mode {arg} selected")
        if verb in ("spin_up", "despin"):
            self.spin_direction = verb
            return CommandResult(True, f"spin direction {verb}")
        if verb == "direct_attitude":
            turn_on = arg == "on"
            why = self._already_on_this_pass("spin") if turn_on else ""
            if why:
                return CommandResult(False, why)
            self.direct_attitude = turn_on
            return CommandResult(True, f"direct attitude {arg}: attitude coil "
                                       f"{'on from the main bus' if turn_on else 'back to automatic control'}")
        self.attitude_polarity = 1 if arg == "plus" else -1
        return CommandResult(True, f"attitude dipole along {'+' if self.attitude_polarity > 0 else '-'}z")

    def step(self, t_s: float, dt_s: float, b_sensed_t: np.ndarray) -> SssOutput:
        """Advance the subsystem to ``t_s`` (s) after ``dt_s`` (s) with the sensed field ``b_sensed_t``
        (3,) in body axes, T; return the coil commands for the step starting at ``t_s``."""
        t = _finite("t_s", t_s)
        dt = _finite("dt_s", dt_s)
        if dt <= 0.0:
            raise AscsError(f"dt_s must be > 0 s, got {dt_s}")
        b = _vector3("b_sensed_t", b_sensed_t)
        cfg = self.config
        signal_t = float(b[1])
        detected = polarity(signal_t, cfg.polarity_level_t)
        decay = math.exp(-dt / cfg.hold_time_constant_s)
        self._perigee_v = 1.0 if detected != 0 else self._perigee_v * decay
        self.perigee_pass = self._perigee_v > cfg.hold_release_fraction
        if not self.perigee_pass:
            self._perigee_modes.clear()
            self._spin_inhibited = False
        comparator = detected if self.enabled else 0
        self._hold_v = 1.0 if comparator != 0 else self._hold_v * decay
        if not self.enabled:
            self._hold_v = 0.0
        active = self.enabled and self._hold_v > cfg.hold_release_fraction
        events: list[Event] = []
        if self.direct_attitude and self.perigee_pass:
            self._perigee_modes.setdefault("attitude", t)
        if active and self.mode == "spin" and "attitude" in self._perigee_modes:
            if not self._spin_inhibited:
                events.append(Event(t, "inhibited", f"spin mode not activated: {self._already_on_this_pass('attitude')}"))
                self._spin_inhibited = True
            active = False
        if active and not self.torquing_active:
            self._pass_mode = self.mode
            events.append(Event(t, "turn_on", f"spin-plane magnetometer |B_y| = {abs(tesla_to_gauss(signal_t)):.4f} G"
                                              f" >= {tesla_to_gauss(cfg.polarity_level_t):.3f} G; {self.mode} mode"
                                              + (f" ({self.spin_direction})" if self.mode == "spin" else "")))
        elif self.torquing_active and not active:
            why = ("disabled by command" if not self.enabled else
                   f"no polarity detection for {cfg.hold_time_s:.1f} s (hold released)")
            events.append(Event(t, "turn_off", f"{self._pass_mode} mode: {why}"))
            self._pass_mode = "off"
        self.torquing_active = active
        spin_cmd = 0
        att_cmd = 0
        if self.direct_attitude:
            att_cmd = self.attitude_polarity
        elif active and self._pass_mode == "spin":
            spin_cmd = comparator if self.spin_direction == "spin_up" else -comparator
        elif active:
            att_cmd = self.attitude_polarity
        if self.perigee_pass and active and self._pass_mode == "spin":
            self._perigee_modes.setdefault("spin", t)
        if self.perigee_pass and att_cmd != 0:
            self._perigee_modes.setdefault("attitude", t)
        dipole = np.array([spin_cmd * cfg.spin_coil.peak_moment_am2(cfg.bus_v), 0.0,
                           att_cmd * cfg.attitude_coil.peak_moment_am2(cfg.bus_v)])
        power = cfg.bus_v * (abs(spin_cmd) * cfg.spin_coil.current_a(cfg.bus_v)
                             + abs(att_cmd) * cfg.attitude_coil.current_a(cfg.bus_v))
        mode = "direct_attitude" if self.direct_attitude else (self._pass_mode if active else "off")
        return SssOutput(spin_cmd, att_cmd, active, events, dipole, power, mode)


@dataclass
class _Pass:
    mode: str
    t_start_s: float
    spin_rate_start_rad_s: float
    axis_start: np.ndarray
    on_time_s: float = 0.0
    torque_int: float = 0.0
    torque_sq_int: float = 0.0
    peak_nm: float = 0.0
    energy_j: float = 0.0


class PassAccumulator:
    """Per-pass statistics of the SSS ASCS (spec §8) from a sampled time series.

    Each sample (``add``) holds over [t_k, t_{k+1}) (forward rectangle weights).  A pass is a run of
    samples with the same mode in 'spin' | 'attitude' | 'direct_attitude'; 'off' ends it.  The useful
    torque is the spin-axis (body z) component in spin mode and the magnitude of the transverse
    component (perpendicular to body z) in the attitude modes.  Spin-rate change and precession are
    measured from the pass's first sample to the sample that ends it (the state after the last torquing
    step).
    """

    def __init__(self) -> None:
        self._current: _Pass | None = None
        self._pending: tuple[float, float, float, float, np.ndarray] | None = None
        self.reports: list[dict] = []

    @staticmethod
    def _useful_torque_nm(mode: str, torque_body_nm: np.ndarray) -> float:
        if mode == "spin":
            return float(torque_body_nm[2])
        return float(np.hypot(torque_body_nm[0], torque_body_nm[1]))

    def _accumulate_pending(self, t_s: float) -> None:
        if self._pending is None or self._current is None:
            return
        t_k, torque, power, _rate, _axis = self._pending
        w = t_s - t_k
        if w <= 0.0:
            raise AscsError(f"PassAccumulator samples must be in increasing time: {t_s} after {t_k}")
        cur = self._current
        cur.on_time_s += w
        cur.torque_int += torque * w
        cur.torque_sq_int += torque * torque * w
        cur.peak_nm = max(cur.peak_nm, abs(torque))
        cur.energy_j += power * w
        self._pending = None

    def _close(self, t_end_s: float, spin_rate_rad_s: float, axis: np.ndarray) -> dict:
        cur = self._current
        assert cur is not None
        avg = cur.torque_int / cur.on_time_s if cur.on_time_s > 0.0 else 0.0
        var = max(cur.torque_sq_int / cur.on_time_s - avg * avg, 0.0) if cur.on_time_s > 0.0 else 0.0
        cos_p = float(np.clip(np.dot(cur.axis_start, axis), -1.0, 1.0))
        report = {
            "mode": cur.mode,
            "on_time_min": cur.on_time_s / 60.0,
            "avg_torque_dyne_cm": float(nm_to_dyne_cm(avg)),
            "peak_torque_dyne_cm": float(nm_to_dyne_cm(cur.peak_nm)),
            "ripple_pct": 100.0 * math.sqrt(var) / abs(avg) if avg != 0.0 else math.nan,
            "spin_rate_change_rpm": rad_s_to_rpm(spin_rate_rad_s - cur.spin_rate_start_rad_s),
            "precession_deg": math.degrees(math.acos(cos_p)),
            "energy_j": cur.energy_j,
            "avg_torque_nm": avg,
            "peak_torque_nm": cur.peak_nm,
            "t_start_s": cur.t_start_s,
            "t_end_s": t_end_s,
        }
        self.reports.append(report)
        self._current = None
        return report

    def add(self, t_s: float, torque_body_nm: np.ndarray, spin_rate_rad_s: float,
            spin_axis_inertial: np.ndarray, power_w: float, mode: str) -> dict | None:
        """Add one sample: time (s), magnetic torque in body axes (N·m), spin rate (rad/s), spin-axis unit
        vector in inertial axes, electrical power (W), pass mode.  Returns the report of a pass this sample
        ends, else None."""
        t = _finite("t_s", t_s)
        torque = _vector3("torque_body_nm", torque_body_nm)
        rate = _finite("spin_rate_rad_s", spin_rate_rad_s)
        axis = _vector3("spin_axis_inertial", spin_axis_inertial)
        norm = float(np.linalg.norm(axis))
        if norm == 0.0:
            raise AscsError("spin_axis_inertial must be a non-zero vector")
        axis = axis / norm
        power = _finite("power_w", power_w)
        if mode not in _PASS_MODES and mode != "off":
            raise AscsError(f"mode must be one of {_PASS_MODES + ('off',)}, got {mode!r}")
        self._accumulate_pending(t)
        report = None
        if self._current is not None and mode != self._current.mode:
            report = self._close(t, rate, axis)
        if mode != "off":
            if self._current is None:
                self._current = _Pass(mode, t, rate, axis)
            self._pending = (t, self._useful_torque_nm(mode, torque), power, rate, axis)
        return report

    def close(self, t_s: float) -> dict | None:
        """End an open pass at ``t_s`` (s), the end of the last sample's interval; returns its report."""
        if self._current is None:
            return None
        pending = self._pending
        self._accumulate_pending(_finite("t_s", t_s))
        if pending is None:
            raise AscsError("PassAccumulator.close: an open pass without samples (internal state error)")
        return self._close(t_s, pending[3], pending[4])
