"""Fault campaign, what interruptions leave and what headers say (issue 18 item 8).

- A bag closed on a full disk left ``metadata.yaml.tmp`` beside it (sqlite3): the disk filling while the
  temporary is written is reproduced by making that write fail with ENOSPC after half of it.
- A Ctrl-C in a Monte Carlo study's report phase left samples but no report and no mark: the
  interruption is raised from the report writer, as a Ctrl-C arriving there would.
- The ``montecarlo`` header printed the base scenario's step count when ``control_period_s`` is varied.
- A SIGKILLed ``montecarlo --jobs 2`` printed "There appear to be 12 leaked semaphore objects": the
  resource tracker unlinking the named semaphores of the Dask nannies' worker queues.
"""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from acds_common import topics
from acds_common.cdr import Codec
from acds_common.scenario import load_scenario
from acds_runtime.bag.writer import BagWriter

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize('temporary', ['metadata.yaml.tmp', 'acds_run.yaml.tmp'])
@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_a_bag_closed_on_a_full_disk_leaves_no_temporary_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                              storage: str, temporary: str) -> None:
    writer = BagWriter(tmp_path / 'bag', storage)
    clock = Codec(topics.TYPES[topics.CLOCK])
    for k in range(10):
        writer.write(topics.CLOCK, clock.encode(k * 500_000_000))
    real = Path.write_text

    def disk_full(self: Path, text: str, *args: object, **kwargs: object) -> int:
        if self.name == temporary:
            real(self, text[:len(text) // 2])
            raise OSError(errno.ENOSPC, 'No space left on device')
        return real(self, text, *args, **kwargs)

    monkeypatch.setattr(Path, 'write_text', disk_full)
    writer.close()
    assert writer.error is not None and 'No space left on device' in writer.error
    assert sorted(p.name for p in (tmp_path / 'bag').iterdir() if p.name.endswith('.tmp')) == []


def _montecarlo(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    from acds_cli.__main__ import main

    code = main(list(argv))
    return code, capsys.readouterr().err


def test_a_study_interrupted_in_its_report_phase_says_it_is_incomplete(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from acds_runtime import dispersion_report

    out = tmp_path / 'mc'
    study = ('montecarlo', 'heao_b_acquisition_short', '--runs', '2', '--jobs', '1', '--until-min', '0.5', '--quiet',
             '--out', str(out))

    def ctrl_c(*_args: object) -> None:
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(dispersion_report, 'write_report', ctrl_c)
        code, _ = _montecarlo(capsys, *study)
    assert code == 130
    assert (out / 'samples.json').exists() and not (out / 'report.md').exists()
    assert json.loads((out / 'montecarlo.json').read_text())['complete'] is False
    code, err = _montecarlo(capsys, 'pick-sample', str(out))
    assert code == 2 and 'incomplete' in err
    # The same study left alone is complete.
    code, _ = _montecarlo(capsys, *study[:-1], str(tmp_path / 'mc2'))
    assert code == 0 and json.loads((tmp_path / 'mc2' / 'montecarlo.json').read_text())['complete'] is True


def test_the_montecarlo_header_gives_the_samples_step_counts_when_the_control_period_is_varied() -> None:
    from acds_cli.verbs.montecarlo import _run_length, draw_samples

    base = load_scenario('heao_b_acquisition_short')  # 60 min at 1 s
    _, samples = draw_samples(base, 1, 6, ['control_period_s=choice(0.5, 2.0)'], '')
    assert {s.length[1] for s in samples} == {0.5, 2.0}
    text = _run_length(base, None, samples)
    assert text.startswith('1800–7200 steps of 0.5–2 s (control_period_s varied; 60.0–60.0 min sim)'), text
    assert _run_length(base, None).startswith('3600 steps of 1 s (60.0 min sim)')


@pytest.mark.slow
def test_a_sigkilled_local_cluster_study_reports_no_leaked_semaphores(tmp_path: Path) -> None:
    import psutil

    err = tmp_path / 'stderr'
    with err.open('w') as fh:
        proc = subprocess.Popen([sys.executable, '-m', 'acds_cli', 'montecarlo', 'heao_b_acquisition_short', '--runs',
                                 '6', '--jobs', '2', '--until-min', '30', '--quiet', '--out', str(tmp_path / 'mc')],
                                cwd=ROOT, env=dict(os.environ),
                                stdout=subprocess.DEVNULL, stderr=fh)
    try:
        parent = psutil.Process(proc.pid)
        deadline = time.monotonic() + 180
        while sum('spawn_main' in ' '.join(c.cmdline()) for c in parent.children()) < 2:  # the queues exist by then
            assert proc.poll() is None and time.monotonic() < deadline, (
                f'no 2 Dask worker processes within 180 s: {err.read_text()}')
            time.sleep(0.1)
        children = parent.children(recursive=True)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        _, alive = psutil.wait_procs(children, timeout=120)  # the workers and the tracker end after their parent
        assert alive == [], f'still running 120 s after the SIGKILL: {alive}'
    finally:
        if proc.poll() is None:
            proc.kill()
    assert 'leaked semaphore' not in err.read_text(), err.read_text()
