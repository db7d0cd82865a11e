"""The HEAO mode logic as a kernel: the compiled step gives the Python core's states and says when it cannot.

:func:`~ascs_mode_manager.heao_modes.heao_advance` (seed 002 §4.3.1: Mode 1A → 1B on the rate thresholds and the
sun, capture in Mode 1B within 10° of the sun line with the rates nulled, the automatic cruise transfer) is checked

* compiled (numba) against plain, bit for bit, and the Python :meth:`HeaoModeManager.advance` that calls it against
  the logic as it was written before it became a kernel (:func:`_reference_advance`: the same transitions, causes
  and attributes), step by step over the recorded inputs of direct-engine runs (Mode 1A → 1B → capture, a run
  started in Mode 1B, ground commands, auto cruise) and over random states and inputs on every threshold;
* for its contract: quiet exactly when advance returns no transition and the status is unchanged, and then
  :meth:`HeaoModeManager.set_kernel_state` of the kernel's state leaves the core exactly as advance does;
* through :class:`~ascs_mode_manager.heao_part.HeaoPart`'s fused protocol (:meth:`fused_inputs`,
  :meth:`fused_quiet`): a direct run whose quiet steps are the compiled kernel's gives every step's output and the
  truth digest of the run in Python.
"""

from __future__ import annotations

import copy
import math
import random

import pytest
from acds_common.commands import AXES
from acds_common.modes import HEAO_CRUISE_MODES, HEAO_MODES
from acds_common.scenario import load_scenario
from acds_common.units import deg, rad
from acds_runtime.direct import DirectRun
from ascs_mode_manager.ground_commands import DUE_SLACK_S
from ascs_mode_manager.heao_modes import (
    BASELINE_RATE_THRESHOLDS_DEG_S,
    CAPTURE_CONE_DEG,
    CAPTURE_RATE_DEG_S,
    CASE_5_RATE_THRESHOLDS_DEG_S,
    HeaoModeConfig,
    HeaoModeManager,
    Transition,
    heao_advance,
    heao_logic,
)
from ascs_mode_manager.heao_part import HeaoPart
from ascs_mode_manager.mode_manager_step import ModeManagerStep

ZERO = (0.0, 0.0, 0.0)


def _reference_advance(core: HeaoModeManager, t: float, omega: tuple, sun: tuple, sun_present: bool) -> list:
    """The HEAO on-board logic on the core's attributes as the Python core wrote it before the kernel (the oracle)."""
    core._last_t_s = t
    norm = math.sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2])
    present = sun_present and norm > 0.0

    def enter(to_mode: str, cause: str) -> Transition:
        from_mode, core.mode = core.mode, to_mode
        if to_mode not in HEAO_CRUISE_MODES:
            core.captured, core._capture_since_t_s = False, None
        if to_mode == 'mode_1b':
            core.mode_1b_entry_t_s = t
        return Transition(t, from_mode, to_mode, cause)

    out = [enter(to, f"ground command '{text}' accepted at t={t_acc:.3f} s") for to, t_acc, text in core._pending]
    core._pending.clear()
    cfg = core.config
    thr = cfg.rate_thresholds_rad_s
    if core.mode == 'mode_1a' and present and all(abs(omega[i]) <= thr[i] for i in range(3)):
        rates = ', '.join(f'|ω{a}|={deg(abs(omega[i])):.4f}≤{deg(thr[i]):.4f}' for i, a in enumerate(AXES))
        out.append(enter('mode_1b', f'rates below thresholds ({rates} deg/s) and sun present'))
    if core.mode != 'mode_1b':
        return out
    if core.mode_1b_entry_t_s is None:
        core.mode_1b_entry_t_s = t
    if core.captured:
        return out
    angle = math.acos(max(-1.0, min(1.0, sun[2] / norm))) if present else math.pi
    if angle > cfg.capture_cone_rad or not all(abs(w) <= cfg.capture_rate_rad_s for w in omega):
        core._capture_since_t_s = None
        return out
    if core._capture_since_t_s is None:
        core._capture_since_t_s = t
    if t - core._capture_since_t_s < cfg.capture_dwell_s:
        return out
    core.captured, core.capture_t_s = True, t
    out.append(Transition(t, 'mode_1b', 'mode_1b', f'acquisition capture: z {deg(angle):.2f}° from the sun line, '
                          f'rates nulled (max |ω| {deg(max(abs(w) for w in omega)):.4f} deg/s)', kind='capture'))
    if cfg.auto_cruise:
        out.append(enter(cfg.cruise_target, 'automatic transfer to cruise at acquisition capture'))
    return out


def _clone(core: HeaoModeManager) -> HeaoModeManager:
    """A copy of ``core`` (its attributes are immutable values but the queue)."""
    out = copy.copy(core)
    out._pending = list(core._pending)
    return out


@pytest.fixture
def check_step(compile_kernels, ieee_bits):
    """``check_step(core, t, omega, sun, sun_present)``: one step of ``core`` (advanced in place) checked against
    the oracle, the compiled kernel against the plain one, and the quiet contract (finite inputs: the stepper holds
    the logic on others, :func:`test_non_finite_inputs_are_not_quiet`); returns (quiet, transitions)."""
    fast_advance, fast_logic = compile_kernels(heao_advance), compile_kernels(heao_logic)

    def check(core: HeaoModeManager, t: float, omega: tuple, sun: tuple, sun_present: bool = True):
        before, oracle = _clone(core), _clone(core)
        params, state, status = core.kernel_params(), core.kernel_state(), core.status_state()
        kernel_sun = sun if sun_present else ZERO
        quiet, new = heao_advance(params, state, t, omega, kernel_sun)
        where = f'{state} t={t!r} ω={omega!r} sun={sun!r} present={sun_present}'
        assert ieee_bits(fast_advance(params, state, t, omega, kernel_sun)) == ieee_bits((quiet, new)), where
        assert ieee_bits(fast_logic(params, state, t, omega, kernel_sun)) == ieee_bits(
            heao_logic(params, state, t, omega, kernel_sun)), where
        transitions = core.advance(t, omega, sun, sun_present)
        assert transitions == _reference_advance(oracle, t, omega, sun, sun_present), where
        assert vars(core) == vars(oracle), where
        assert quiet == (not transitions and core.status_state() == status), where
        if quiet:
            assert (core.mode, core.captured) == (before.mode, before.captured), where
            before.set_kernel_state(new)
            assert vars(before) == vars(core), where
        return quiet, transitions

    return check


# ----------------------------------------------------------------------------------------------- random inputs
def _near(rng: random.Random, x: float) -> float:
    """``x``, a double next to it, or a value a little off, with either sign."""
    v = rng.choice([x, x, math.nextafter(x, math.inf), math.nextafter(x, -math.inf), x * (1 + 1e-9), x * (1 - 1e-9)])
    return v if rng.random() < 0.5 else -v


def _omega(rng: random.Random, thr: tuple[float, float, float]) -> tuple[float, float, float]:
    """Rates on the 1A → 1B thresholds, on the capture rate (0.01 deg/s), zero or anywhere."""
    capture = rad(CAPTURE_RATE_DEG_S)
    kind = rng.random()
    if kind < 0.4:
        return tuple(_near(rng, thr[i]) if rng.random() < 0.7 else rng.uniform(-thr[i], thr[i]) for i in range(3))
    if kind < 0.8:
        return tuple(_near(rng, capture) if rng.random() < 0.6 else rng.uniform(-capture, capture) for _ in range(3))
    if kind < 0.9:
        return rng.choice([ZERO, (-0.0, 0.0, -0.0)])
    return tuple(rng.uniform(-0.05, 0.05) for _ in range(3))


def _sun(rng: random.Random, cone: float) -> tuple[float, float, float]:
    """A sun vector at the capture cone's edge (10°, the double each side), inside or outside it, absent (zero),
    unnormalised, tiny (its norm's squares underflow) or huge."""
    kind = rng.random()
    if kind < 0.1:
        return ZERO
    theta = (rng.choice([cone, math.nextafter(cone, 0.0), math.nextafter(cone, 4.0), cone * (1 + 1e-12)])
             if kind < 0.6 else rng.uniform(0.0, math.pi))
    phi = rng.uniform(-math.pi, math.pi)
    scale = rng.choice([1.0, 1.0, 1.0, 0.3, 7.0, 1e-170, 1e-300, 1e150])
    return (scale * math.sin(theta) * math.cos(phi), scale * math.sin(theta) * math.sin(phi), scale * math.cos(theta))


def _random_core(rng: random.Random) -> tuple[HeaoModeManager, float]:
    """A core in any state (any mode, captured or not, every time set or None, commands queued) and a step time."""
    dwell = rng.choice([0.0, 0.0, 4.0, 30.0])
    thresholds = rng.choice([BASELINE_RATE_THRESHOLDS_DEG_S, CASE_5_RATE_THRESHOLDS_DEG_S])
    core = HeaoModeManager(HeaoModeConfig(
        rate_thresholds_rad_s=tuple(rad(x) for x in thresholds), capture_dwell_s=dwell,
        cruise_target=rng.choice(HEAO_CRUISE_MODES), auto_cruise=rng.random() < 0.5))
    last = rng.choice([None, rng.uniform(0.0, 2e4)])
    t = (last or 0.0) + rng.choice([0.0, 0.5, 2.0, rng.uniform(0.0, 100.0)])
    core._last_t_s = last
    core.mode = rng.choice(HEAO_MODES)
    core.captured = rng.random() < 0.3
    core.mode_1b_entry_t_s = rng.choice([None, rng.uniform(0.0, t)])
    core.capture_t_s = rng.choice([None, None, rng.uniform(0.0, t)])
    core._capture_since_t_s = rng.choice([None, t, t - dwell, math.nextafter(t - dwell, math.inf),
                                          math.nextafter(t - dwell, -math.inf), rng.uniform(0.0, t)])
    if rng.random() < 0.05:
        core._pending.append((rng.choice(HEAO_MODES), t, 'mode <target>'))
    return core, t


def test_random_states_and_inputs_on_every_threshold(check_step):
    """20,000 steps from random states with rates on the 0.573/0.115 (and case 5) deg/s thresholds and the
    0.01 deg/s capture rate, the sun at the 10° cone's edge, absent or of any scale, the dwell's edge, queued
    commands; every kind of step occurs."""
    rng = random.Random(3636)
    cone = rad(CAPTURE_CONE_DEG)
    seen: set[str] = set()
    for _ in range(20000):
        core, t = _random_core(rng)
        omega, sun = _omega(rng, core.config.rate_thresholds_rad_s), _sun(rng, cone)
        quiet, transitions = check_step(core, t, omega, sun, rng.random() < 0.9)
        seen.update(f'{tr.kind}:{tr.from_mode}->{tr.to_mode}' for tr in transitions)
        seen.add('quiet' if quiet else 'not quiet')
    assert {'quiet', 'not quiet', 'mode:mode_1a->mode_1b', 'capture:mode_1b->mode_1b',
            'mode:mode_1b->celestial_point', 'mode:mode_1b->celestial_scan'} <= seen


def test_non_finite_inputs_are_not_quiet(compile_kernels):
    """A non-finite rate, sun component or time: the compiled step is not quiet and keeps the state (the stepper
    holds the logic and warns)."""
    fast = compile_kernels(heao_advance)
    core = HeaoModeManager(HeaoModeConfig())
    params, state = core.kernel_params(), core.kernel_state()
    for bad in (math.nan, math.inf, -math.inf):
        for i in range(7):
            args = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
            args[i] = bad
            for kernel in (heao_advance, fast):
                quiet, new = kernel(params, state, args[0], tuple(args[1:4]), tuple(args[4:]))
                assert not quiet and new[0] == state[0] and math.isnan(new[5]), (kernel, args)


# ------------------------------------------------------------------------------------------ recorded runs
@pytest.fixture
def python_steps(monkeypatch):
    """The direct engine runs every step of the mode manager through its Python stage: the stepper offers no fused
    form (``ModeManagerStep.fused``, where the engine has one, returns None), so the runs below see each step."""
    monkeypatch.setattr(ModeManagerStep, 'fused', lambda self, stage, held: None, raising=False)


def _recorded_steps(monkeypatch, scenario) -> tuple[HeaoModeManager, list]:
    """The HEAO core as a direct run built it and the inputs of each of its steps: (queued commands, t, ω, sun,
    sun present); the run's own advance is the one under test here, so the record is of its inputs only."""
    record: list = []
    first: list[HeaoModeManager] = []
    advance = HeaoModeManager.advance

    def recording(self, t, omega, sun, sun_present):
        if not first:
            first.append(_clone(self))
        record.append((list(self._pending), t, tuple(omega), tuple(sun), sun_present))
        return advance(self, t, omega, sun, sun_present)

    with monkeypatch.context() as patch:
        patch.setattr(HeaoModeManager, 'advance', recording)
        DirectRun(scenario).run()
    return first[0], record


#: heao_b_acquisition_fast_geometry past its capture (about t = 5,200 s) with the automatic cruise transfer and
#: ground commands: a cruise refused before capture, then from cruise a restart of acquisition (Mode 1A, again 1B
#: and capture and cruise), standby and Mode 1B by command (its entry; no capture in the 26 minutes left).
COMMANDS = ('duration_min: 160\nmodes:\n  auto_cruise: true\n  stop_at_capture: false\n  ground_commands: '
            '["30: mode celestial_point", "6000: mode mode_1a", "8000: mode standby", "8000.5: mode mode_1b"]\n')


def _commands_variant(tmp_path):
    path = tmp_path / 'heao_b_acquisition_commands.yaml'
    path.write_text(f'extends: heao_b_acquisition_fast_geometry\nname: heao_b_acquisition_commands\n{COMMANDS}')
    return load_scenario(str(path))


@pytest.mark.parametrize('case', ['acquisition', 'wheels_on', 'commands_auto_cruise'])
def test_recorded_runs_step_by_step(monkeypatch, python_steps, tmp_path, check_step, case):
    """The inputs of direct runs, step by step: heao_b_acquisition (Mode 1A → 1B → capture, where it stops),
    Table 4-7 case 6 (wheels on from separation: the Mode 1B entry stamp), and the acquisition with ground
    commands (a refused cruise before capture, a restart of acquisition) and the automatic cruise transfer."""
    scenario = {'acquisition': lambda: load_scenario('heao_b_acquisition'),
                'wheels_on': lambda: load_scenario('heao_b_case6'),
                'commands_auto_cruise': lambda: _commands_variant(tmp_path)}[case]()
    core, record = _recorded_steps(monkeypatch, scenario)
    kinds = {'quiet': 0, 'not quiet': 0}
    seen = []
    for pending, t, omega, sun, present in record:
        core._pending[:] = pending
        quiet, transitions = check_step(core, t, omega, sun, present)
        kinds['quiet' if quiet else 'not quiet'] += 1
        seen.extend(f'{tr.kind}:{tr.from_mode}->{tr.to_mode}' for tr in transitions)
    assert kinds['quiet'] > 0.9 * len(record) and kinds['not quiet'] >= 1, kinds
    assert seen == {'acquisition': ['mode:mode_1a->mode_1b', 'capture:mode_1b->mode_1b'],
                    'wheels_on': ['capture:mode_1b->mode_1b'],
                    'commands_auto_cruise': ['mode:mode_1a->mode_1b', 'capture:mode_1b->mode_1b',
                                             'mode:mode_1b->celestial_point', 'mode:celestial_point->mode_1a',
                                             'mode:mode_1a->mode_1b', 'capture:mode_1b->mode_1b',
                                             'mode:mode_1b->celestial_point', 'mode:celestial_point->standby',
                                             'mode:standby->mode_1b']}[case]


# ------------------------------------------------------------------------------------------ fused protocol
def _fused_step(compiled):
    """HeaoPart.step as a fused caller runs it: the compiled kernel on a quiet step, Python on any other."""
    step = HeaoPart.step

    def fused(self: HeaoPart, k, t, inp):
        given = self.fused_inputs()
        if given is not None and not given[2] <= t + DUE_SLACK_S:
            gyro, sun = inp['gyro'], inp['sun']
            quiet, state = compiled(given[0], given[1], t, ZERO if gyro is None else gyro[0],
                                    ZERO if sun is None else sun)
            if quiet:
                self.fused_quiet_steps = getattr(self, 'fused_quiet_steps', 0) + 1
                return self.fused_quiet(state)
        return step(self, k, t, inp)

    return fused


def test_fused_protocol_gives_the_python_steps(monkeypatch, python_steps, tmp_path, compile_kernels):
    """A direct run whose quiet mode-logic steps are the compiled kernel's (through :meth:`HeaoPart.fused_inputs` and
    :meth:`HeaoPart.fused_quiet`) gives every step's mode-logic output (the same ``mode`` object as the last step's
    on a quiet step) and the truth digest of the Python run, with ground commands and the auto cruise."""
    scenario = _commands_variant(tmp_path)
    steps = scenario.total_steps()
    outputs: dict[str, list] = {'python': [], 'fused': []}
    digests = {}
    parts: list[HeaoPart] = []
    for run in ('python', 'fused'):
        step = _fused_step(compile_kernels(heao_advance)) if run == 'fused' else HeaoPart.step

        def recording(self, k, t, inp, step=step, out=outputs[run]):
            if not parts or parts[-1] is not self:
                parts.append(self)
            result = step(self, k, t, inp)
            out.append(result)
            return result

        with monkeypatch.context() as patch:
            patch.setattr(HeaoPart, 'step', recording)
            digests[run] = DirectRun(scenario, steps=steps).run().summary['truth_digest']
    assert digests['fused'] == digests['python']
    assert len(outputs['fused']) > steps
    assert outputs['fused'] == outputs['python']
    quiet = parts[-1].fused_quiet_steps
    assert 0.9 * steps < quiet < steps
    for k in range(1, steps):  # a quiet step's report is the last step's object
        if outputs['python'][k]['mode'] is outputs['python'][k - 1]['mode']:
            assert outputs['fused'][k]['mode'] is outputs['fused'][k - 1]['mode'], k
