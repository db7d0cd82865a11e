"""Fault campaign, run folders (issue 18 item 5): two runs started in the same second get two folders.

The default folder was ``runs/<scenario>_<YYYYmmdd_HHMMSS>``, created with ``exist_ok``: a second run in
the same second shared it (its bag refused as "already exists", or, with ``--no-record``, ``domain_id``
of one run beside ``params.yaml`` of the other). The clock is pinned to one second here, so the
collision is certain rather than a race.
"""

from __future__ import annotations

import re
import threading
import time
from pathlib import Path

import pytest
from acds_runtime.run_folder import create_run_folder


@pytest.fixture
def one_second(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every ``time.strftime`` answers the same second."""
    monkeypatch.setattr(time, 'strftime', lambda *_: '20261202_060000')


def test_the_folder_function_called_twice_in_one_second_gives_two_new_folders(tmp_path: Path, one_second: None) -> None:
    first, second = create_run_folder(tmp_path, 'heao_b_acquisition'), create_run_folder(tmp_path, 'heao_b_acquisition')
    assert first != second and first.is_dir() and second.is_dir()
    assert (first.name, second.name) == ('heao_b_acquisition_20261202_060000', 'heao_b_acquisition_20261202_060000_2')


def test_concurrent_callers_each_get_their_own_folder(tmp_path: Path, one_second: None) -> None:
    got: list[Path] = []
    start = threading.Barrier(8)

    def make() -> None:
        start.wait(timeout=30)
        got.append(create_run_folder(tmp_path, 's'))

    threads = [threading.Thread(target=make) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=30)
    assert len(got) == 8 and len(set(got)) == 8


def test_two_runs_in_the_same_second_use_two_run_folders(tmp_path: Path, one_second: None,
                                                         monkeypatch: pytest.MonkeyPatch,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    from acds_cli import __main__ as cli

    monkeypatch.setattr(cli, 'ROOT', tmp_path)
    folders = []
    for _ in range(2):
        assert cli.main(['run', 'heao_b_acquisition_short', '--engine', 'direct', '--no-record', '--steps', '3',
                         '--quiet']) == 0
        folders += re.findall(r'run folder (\S+)', capsys.readouterr().err)
    assert len(folders) == 2 and folders[0] != folders[1], folders
    assert sorted(p.name for p in (tmp_path / 'runs').iterdir()) == ['heao_b_acquisition_short_20261202_060000',
                                                                     'heao_b_acquisition_short_20261202_060000_2']
