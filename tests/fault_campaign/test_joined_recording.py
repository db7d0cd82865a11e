"""Fault campaign, joined recordings (issue 18 item 6): a bag of ``acds record`` holds every step or says so.

Under load a recorder joining a running graph missed 867–953 of ~8,800 steps in the middle of its
bag, exited 0 with WARNING lines only, and ``acds info`` showed no gap. The gap is induced
deterministically here: the recorder's subscription callback (:class:`JoinedRecording`, what
``acds record`` subscribes every topic with) is fed the stamped messages of a real run folder's
per-step topics with a hole, as a recorder that fell behind its history depth receives them; the
bag, its metadata, ``acds info`` and the exit status are then checked.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from acds_cli.bag.info import bag_info
from acds_cli.bag.recorder import JoinedRecording, report_recording, step_coverage
from acds_common import topics
from acds_common.cdr import Codec
from acds_common.parameters import node_parameters, parameters_yaml
from acds_common.scenario import load_scenario
from acds_runtime.bag.coverage import StepCoverage
from acds_runtime.bag.reader import open_bag
from acds_runtime.bag.writer import BagWriter

WHEELS = topics.resolve(topics.WHEEL_MOMENTUM)
DT_NS = 1_000_000_000  # heao_b_acquisition_short: 1 s control period


def _run_folder(tmp_path: Path) -> Path:
    """A run folder as the launcher writes it (its params.yaml gives the graph and the control period)."""
    run = tmp_path / 'run'
    run.mkdir()
    run.joinpath('params.yaml').write_text(parameters_yaml(node_parameters(load_scenario('heao_b_acquisition_short'),
                                                                             200)))
    return run


def _record(tmp_path: Path, steps: list[int]) -> JoinedRecording:
    """Feed the recorder's callback /clock and wheel momentum of ``steps`` (arrival order), then close the bag."""
    recording = JoinedRecording(BagWriter(tmp_path / 'bag'), None, step_coverage(_run_folder(tmp_path)))
    clock, wheels = Codec(topics.TYPES[topics.CLOCK]), Codec(topics.type_of(topics.WHEEL_MOMENTUM), 'body')
    for k in steps:
        recording(topics.CLOCK, clock.encode(k * DT_NS))
        recording(WHEELS, wheels.encode(k * DT_NS, (0.1 * k, 0.0, 0.0)))
    recording.close()
    return recording


def test_a_joined_recording_with_a_hole_says_so_in_its_metadata_info_and_exit_status(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    history = list(range(100, 140))  # the transient-local history on joining
    recording = _record(tmp_path, [*history, *range(140, 160), *range(181, 230)])  # steps 160–180 never arrived
    assert recording.gaps == {topics.CLOCK: [(160, 180)], WHEELS: [(160, 180)]}
    bag = open_bag(tmp_path / 'bag')
    assert yaml.safe_load(bag.info['gaps']) == {topics.CLOCK: [[160, 180]], WHEELS: [[160, 180]]}
    text = bag_info(tmp_path / 'bag')
    assert 'gaps:       2 topic(s) miss steps' in text and f'{WHEELS} misses 21 step(s) (160–180)' in text
    assert report_recording(recording, allow_gaps=False) == 1
    err = capsys.readouterr().err
    assert 'acds record:' in err and '--allow-gaps' in err and f'{WHEELS}: 21 step(s) missing' in err
    assert report_recording(recording, allow_gaps=True) == 0


def test_a_complete_joined_recording_exits_0_and_info_says_no_gaps(tmp_path: Path) -> None:
    # Out of order and repeated (history replayed after live messages) is not a gap.
    recording = _record(tmp_path, [*range(50, 80), *range(40, 55), *range(80, 120)])
    assert recording.gaps == {}
    assert report_recording(recording, allow_gaps=False) == 0
    assert 'gaps:       none' in bag_info(tmp_path / 'bag')


def test_without_a_run_folder_the_gaps_are_not_checked_and_info_says_so(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    recording = JoinedRecording(BagWriter(tmp_path / 'bag'), None, None)
    recording(topics.CLOCK, Codec(topics.TYPES[topics.CLOCK]).encode(0))
    recording.close()
    assert report_recording(recording, allow_gaps=False) == 0
    assert 'steps not checked for gaps' in capsys.readouterr().err
    assert 'gaps:       not checked' in bag_info(tmp_path / 'bag')


def test_step_coverage_keeps_runs_and_finds_every_hole() -> None:
    cov = StepCoverage(10, ['/a', '/b'])
    for step in (5, 6, 7, 12, 13, 9, 20, 8, 7, 30, 31, 29):
        cov.add('/a', step * 10 + 3)
    cov.add('/c', 0)  # not a per-step topic: ignored
    assert cov.gaps() == {'/a': [(10, 11), (14, 19), (21, 28)]}
    for step in (10, 11, *range(14, 20), *range(21, 29)):
        cov.add('/a', step * 10)
    assert cov.gaps() == {} and cov._runs['/a'] == [[5, 31]]
