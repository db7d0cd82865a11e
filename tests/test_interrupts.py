"""A stop signal raised inside a C extension (numba's cache loader) still stops a verb with 128 + its number.

CI saw it: SIGHUP landed while a study's first fused block loaded from numba's cache, came out as
``SystemError: ... returned a result with an exception set`` with the stop as its cause, and the study exited 1
with a traceback instead of 129 and its resume line.
"""

from __future__ import annotations

import argparse
import signal
from pathlib import Path

import pytest
from acds_cli.interrupts import interruption
from acds_cli.verbs import montecarlo


def _wrapped(stop: BaseException) -> SystemError:
    """What numba raises when the unpickler it called raised ``stop`` (its __cause__)."""
    try:
        try:
            raise stop
        except BaseException as inner:
            raise SystemError('<function _numba_unpickle> returned a result with an exception set') from inner
    except SystemError as outer:
        return outer


def test_the_stop_is_found_under_the_extension_error():
    stop = KeyboardInterrupt()
    assert interruption(_wrapped(stop)) is stop
    assert interruption(stop) is stop
    assert interruption(ValueError('not a stop')) is None


def test_the_stop_is_found_as_a_context_and_a_cycle_ends_the_walk():
    a, b = ValueError('a'), ValueError('b')
    a.__context__, b.__context__ = b, a
    assert interruption(a) is None
    try:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise RuntimeError('while handling')  # noqa: B904 (the context is what is tested)
    except RuntimeError as exc:
        assert isinstance(interruption(exc), KeyboardInterrupt)


class _Journal:
    def __init__(self, path: Path) -> None:
        self.path, self.done, self.study, self.recorded = path / 'samples.jsonl', {}, {'command': 'acds montecarlo x'}, []

    def record(self, key, summary):
        self.recorded.append(key)

    def kept(self) -> int:
        return len(self.recorded)

    def close(self) -> None:
        pass


class _Sample:
    text = 'scenario: x'


def test_a_study_whose_signal_lands_inside_numba_exits_128_plus_its_number(tmp_path, capsys):
    def task(_text):
        raise _wrapped(montecarlo._Stop('SIGHUP', signal.SIGHUP))
    journal = _Journal(tmp_path)
    args = argparse.Namespace(engine='direct', jobs=1, scheduler=None, quiet=True, allow_mixed_workers=False)
    with pytest.raises(SystemExit) as stopped:
        montecarlo.run_journaled(journal, {('s', 0): _Sample()}, args, lambda _key: 10, 'montecarlo',
                                 task_of=lambda _key, _steps: task)
    assert stopped.value.code == 128 + signal.SIGHUP
    err = capsys.readouterr().err
    assert 'interrupted (SIGHUP)' in err and f'--resume {tmp_path}' in err, err


def test_an_error_that_is_no_stop_is_not_taken_for_one(tmp_path):
    def task(_text):
        raise SystemError('a real engine error')
    args = argparse.Namespace(engine='direct', jobs=1, scheduler=None, quiet=True, allow_mixed_workers=False)
    with pytest.raises(SystemError, match='a real engine error'):
        montecarlo.run_journaled(_Journal(tmp_path), {('s', 0): _Sample()}, args, lambda _key: 10, 'montecarlo',
                                 task_of=lambda _key, _steps: task)
