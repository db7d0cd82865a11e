"""Fault campaign, bags (issue 9 §1 and the bag verbs of §6): reading a bag never writes.

Every case runs the user command (``python -m acds_cli VERB``) or the library
call it makes, and compares the folder's listing and file hashes before and
after. Bags are written by a real :class:`~acds_runtime.bag.writer.BagWriter` in a
child process that either closes them or dies without closing (``os._exit``:
what a SIGKILL leaves), except the live-recording case, which records a real
graph run.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tracemalloc
from pathlib import Path

import pytest
import yaml
from acds_common import topics
from acds_runtime.testing import wait_for_messages

ROOT = Path(__file__).resolve().parents[2]
BAG_VERBS = ('info', 'play', 'plot', 'compare')
WHEELS = topics.resolve(topics.WHEEL_MOMENTUM)
EVENTS = topics.resolve(topics.EVENTS)

#: Writes a bag with BagWriter: /clock and wheel momentum per step (+ an events string of PAYLOAD bytes),
#: flushed (chunk closed / transaction committed) every FLUSH_EVERY steps and at the end of the steps.
#: Then optionally: LATE wheel-momentum history messages for steps 0.. arriving last (a late joiner's
#: transient-local history: a chunk whose start time is earlier than the chunks before it); SPILL more steps
#: written without flushing (sqlite3: with a 2-page cache, so the uncommitted pages reach the database file);
#: CHILD: start a sleeping child process (inheriting every inheritable descriptor). CLOSE: close the bag, else
#: die without closing it. COMPRESSION: zstd | none (default: the storage's). Prints {"flushed": {topic: n}, "child": pid}.
WRITER = r'''
import json, os, subprocess, sys
from acds_runtime.bag import writer as bw
from acds_common import topics
from rosbags.typesys.stores.ros2_jazzy import (builtin_interfaces__msg__Time as Time, geometry_msgs__msg__Vector3 as V3,
    geometry_msgs__msg__Vector3Stamped as V3S, rosgraph_msgs__msg__Clock as Clock, std_msgs__msg__Header as Header,
    std_msgs__msg__String as String)
spec = json.loads(sys.argv[1])
bw.FLUSH_MESSAGES = 10**9  # flushes only where the spec says
ts = bw.typestore()
w = bw.BagWriter(spec['path'], spec['storage'], {'scenario_name': 'fault_campaign', 'control_period_s': '0.5',
                                                 'steps': str(spec['steps'])}, flush_period_s=1e9,
                 compression=spec.get('compression'))
w.note_publishers(topics.resolve(topics.WHEEL_MOMENTUM), ['reaction_wheels'])
stamp = lambda k: Time(sec=k // 2, nanosec=(k % 2) * 500_000_000)
clock = lambda k: ts.serialize_cdr(Clock(clock=stamp(k)), 'rosgraph_msgs/msg/Clock')
wheels = lambda k: ts.serialize_cdr(V3S(header=Header(stamp=stamp(k), frame_id='body'), vector=V3(x=0.1 * k, y=-1.0, z=2.0)),
                                    'geometry_msgs/msg/Vector3Stamped')
events = lambda k: ts.serialize_cdr(String(data=f'{k:08d}' + 'e' * spec.get('payload', 0)), 'std_msgs/msg/String')
def step(k):
    w.write(topics.CLOCK, clock(k))
    if spec.get('payload'):
        w.write(topics.resolve(topics.EVENTS), events(k))
    if not spec.get('late'):
        w.write(topics.resolve(topics.WHEEL_MOMENTUM), wheels(k))
for k in range(spec['steps']):
    step(k)
    if (k + 1) % spec.get('flush_every', 50) == 0:
        w.flush()
for k in range(spec.get('late', 0)):
    w.write(topics.resolve(topics.WHEEL_MOMENTUM), wheels(k))
w.flush()
child = None
if spec.get('child'):
    child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(120)'], close_fds=False,
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).pid
if spec.get('spill'):
    if spec['storage'] == 'sqlite3':
        w._writer.storage.conn.execute('PRAGMA cache_size=2')
    for k in range(spec['steps'], spec['steps'] + spec['spill']):
        step(k)
print(json.dumps({'flushed': w.flushed_counts, 'child': child}), flush=True)
if spec.get('close', True):
    w.close()
else:
    os._exit(0)
'''


def _env() -> dict[str, str]:
    return dict(os.environ, ROS_LOG_DIR=os.environ.get('ROS_LOG_DIR', '/tmp/acds_ros_log'))


def make_bag(path: Path, storage: str = 'mcap', steps: int = 120, **spec) -> dict:
    """Write a bag (see WRITER) in a child process; return what it printed."""
    out = subprocess.run([sys.executable, '-c', WRITER, json.dumps({'path': str(path), 'storage': storage,
                                                                    'steps': steps, **spec})],
                         cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def acds(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    """The user command, as ``./scripts/acds`` runs it."""
    return subprocess.run([sys.executable, '-m', 'acds_cli', *args], cwd=ROOT, env=_env(), capture_output=True,
                          text=True, timeout=timeout, check=False)


def verb_args(verb: str, bag: Path, tmp_path: Path, domain: int) -> list[str]:
    """A minimal valid invocation of a bag verb on ``bag``."""
    return {'info': ['info', str(bag)],
            'play': ['play', str(bag), '--domain', str(domain), '--wait', '0'],
            'plot': ['plot', str(bag), '--out', str(tmp_path / 'plots_out')],
            'compare': ['compare', str(bag), '--node', 'reaction_wheels']}[verb]


def one_line(proc: subprocess.CompletedProcess[str]) -> str:
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, f'expected one line on stderr, got:\n{proc.stderr}'
    assert 'Traceback' not in proc.stderr
    return lines[0]


# ---- 4. what is not a bag: one line naming the path and what is wrong; the folder stays as it was ----------

def _random_mcap(d: Path) -> Path:
    (d / 'notes.txt').write_text('keep\n')
    (d / 'x.mcap').write_bytes(os.urandom(5000))
    return d / 'x.mcap'


def _empty_mcap(d: Path) -> Path:
    (d / 'notes.txt').write_text('keep\n')
    (d / 'x.mcap').write_bytes(b'')
    return d / 'x.mcap'


def _empty_folder(d: Path) -> Path:
    (d / 'notes.txt').write_text('keep\n')
    return d


def _not_a_bag(d: Path) -> Path:
    (d / 'notes.txt').write_text('keep\n')
    return d / 'notes.txt'


def _truncated_metadata(d: Path) -> Path:
    bag = d / 'bag'
    make_bag(bag, steps=20)
    meta = bag / 'metadata.yaml'
    text = meta.read_text()
    meta.write_text(text[:len(text) // 2])
    return bag


BAD = {
    'random bytes named .mcap': (_random_mcap, 'x.mcap: not an MCAP file'),
    'empty .mcap': (_empty_mcap, 'x.mcap: empty file (0 bytes)'),
    'folder without storage': (_empty_folder, 'not a bag (no metadata.yaml and no .mcap or .db3 storage file in it)'),
    'not a bag path': (_not_a_bag, 'notes.txt: not a bag (expected a bag folder, or its .mcap or .db3 storage file)'),
    'truncated metadata.yaml': (_truncated_metadata, 'its metadata.yaml'),
}


@pytest.mark.parametrize('case', sorted(BAD))
def test_what_is_not_a_bag_is_one_line_and_nothing_changes(tmp_path, folder_state, play_domain, case):
    make, reason = BAD[case]
    area = tmp_path / 'area'  # the bag's folder and its parent (where plot's default output would go)
    folder = area / 'd'
    folder.mkdir(parents=True)
    target = make(folder)
    before = folder_state(area)
    for verb in BAG_VERBS:
        args = verb_args(verb, target, tmp_path, play_domain)
        if verb == 'plot':
            args = args[:2]  # default output beside the bag: must not be created either
        proc = acds(*args)
        line = one_line(proc)
        assert proc.returncode == 2, f'{verb}: exit {proc.returncode}: {line}'
        assert line.startswith(f'acds {verb}: bag ') and reason in line, f'{verb}: {line}'
        assert str(folder) in line, f'{verb}: the line names the path: {line}'
        assert folder_state(area) == before, f'{verb} on {case} changed {area}'
    assert not (tmp_path / 'plots_out').exists()


def test_truncated_metadata_says_what_is_wrong(tmp_path):
    from acds_runtime.bag.reader import open_bag
    from acds_runtime.bag.writer import BagError

    bag = _truncated_metadata(tmp_path)
    with pytest.raises(BagError) as err:
        open_bag(bag)
    text = str(err.value)
    assert '\n' not in text and text.startswith(f'bag {bag}: its metadata.yaml ')
    assert 'truncated' in text


# ---- 1. unclosed bags are read as they are, never rewritten -------------------------------------------------

@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_every_verb_reads_an_unclosed_bag_without_changing_it(tmp_path, folder_state, play_domain, storage):
    bag = tmp_path / 'area' / 'killed'
    got = make_bag(bag, storage, steps=120, spill=30, close=False)
    assert got['flushed'] == {topics.CLOCK: 120, WHEELS: 120}
    assert {p.name for p in bag.iterdir()} >= {'acds_recording.lock', 'acds_run.yaml'}, \
        'a killed writer leaves its (released) lock file behind'
    before = folder_state(tmp_path / 'area')
    for verb in BAG_VERBS:
        proc = acds(*verb_args(verb, bag, tmp_path, play_domain))
        notes = [line for line in proc.stderr.splitlines() if 'was not closed' in line]
        assert len(notes) == 1, f'{verb}: one line says the bag is unclosed:\n{proc.stderr}'
        last = 'its last complete chunk' if storage == 'mcap' else 'its last committed transaction'
        assert f'bag {bag} was not closed' in notes[0] and last in notes[0] and 'without changing it' in notes[0]
        assert folder_state(tmp_path / 'area') == before, f'{verb} changed the unclosed bag'
        if verb == 'info':
            assert proc.returncode == 0, proc.stderr
            assert 'messages:   240 on 2 topics' in proc.stdout, proc.stdout
        elif verb == 'play':
            assert proc.returncode == 0, proc.stderr
            assert '[play] published 240 messages' in proc.stderr
        elif verb == 'plot':
            assert proc.returncode == 0, proc.stderr
            assert (tmp_path / 'plots_out' / 'fig_4-15_roll_response.png').exists()
        else:  # the bag has no parameters to re-run the node with: a set-up error, after reading
            assert proc.returncode == 2 and 'no recorded parameters or scenario' in proc.stderr, proc.stderr


def test_sqlite_hot_journal_is_rolled_back_in_memory_only(tmp_path, folder_state):
    """A writer killed inside a transaction whose pages already reached the database file: reading gives
    exactly the committed transactions, and the database and its journal stay byte-identical."""
    import sqlite3

    from acds_runtime.bag.reader import open_bag
    from rosbags.rosbag2 import Reader

    bag = tmp_path / 'hot'
    make_bag(bag, 'sqlite3', steps=100, spill=300, close=False)
    db, journal = bag / 'hot.db3', bag / 'hot.db3-journal'
    assert journal.exists() and db.stat().st_size > 0
    before = folder_state(bag)
    with Reader(db) as naive:  # ignoring the journal sees the torn, uncommitted state
        torn = sum(1 for _ in naive.messages())
    read = open_bag(bag)
    msgs = list(read.messages())
    assert folder_state(bag) == before, 'reading rolled back the journal on disk'
    assert read.counts == {topics.CLOCK: 100, WHEELS: 100} and len(msgs) == 200
    assert [t for topic, t, _ in msgs if topic == topics.CLOCK] == [k * 500_000_000 for k in range(100)]
    assert torn != 200, 'the test needs a journal that matters (uncommitted pages in the database file)'
    # what SQLite itself restores (on a copy): the same rows
    copy = tmp_path / 'sqlite_copy'
    copy.mkdir()
    (copy / db.name).write_bytes(db.read_bytes())
    (copy / journal.name).write_bytes(journal.read_bytes())
    conn = sqlite3.connect(copy / db.name)
    try:
        rows = conn.execute('SELECT timestamp, data FROM messages ORDER BY timestamp, id').fetchall()
    finally:
        conn.close()
    assert sorted((t, d) for _, t, d in msgs) == sorted((t, bytes(d)) for t, d in rows)


def test_unclosed_mcap_streams_in_time_order_across_out_of_order_chunks(tmp_path, folder_state):
    from acds_runtime.bag.reader import open_bag

    bag = tmp_path / 'late'
    make_bag(bag, steps=200, late=100, flush_every=40, spill=10, close=False)
    before = folder_state(bag)
    read = open_bag(bag)
    msgs = list(read.messages())
    assert folder_state(bag) == before
    assert read.unclosed == 'up to its last complete chunk'
    assert read.counts == {topics.CLOCK: 200, WHEELS: 100}
    starts = read.source.starts
    assert starts != sorted(starts), 'the late history makes a chunk start before the ones written earlier'
    stamps = [t for _, t, _ in msgs]
    assert stamps == sorted(stamps)
    assert [topic for topic, t, _ in msgs if t == 0] == [topics.CLOCK, WHEELS], 'equal times: recorded order'
    assert read.stats()[WHEELS].last_ns == 99 * 500_000_000


# ---- 2. acds recover SRC DEST ------------------------------------------------------------------------------

@pytest.mark.parametrize('storage', ['mcap', 'sqlite3'])
def test_recover_writes_a_repaired_copy_and_never_touches_the_source(tmp_path, folder_state, storage):
    from rosbags.rosbag2 import Reader

    src = tmp_path / 'src' / 'killed'
    make_bag(src, storage, steps=150, late=20, spill=25, close=False)
    before = folder_state(src.parent)
    dest = tmp_path / 'out' / 'repaired'
    proc = acds('recover', str(src), str(dest))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == str(dest)
    assert folder_state(src.parent) == before, 'recover changed its source'
    suffix = 'mcap' if storage == 'mcap' else 'db3'
    assert sorted(p.name for p in dest.iterdir()) == ['acds_run.yaml', 'metadata.yaml', f'repaired.{suffix}']
    with Reader(dest) as reader:  # plain rosbags reads the copy through its index and metadata
        got = [(c.topic, t, bytes(d)) for c, t, d in reader.messages()]
        assert {c.topic: c.msgcount for c in reader.connections} == {topics.CLOCK: 150, WHEELS: 20}
    custom = yaml.safe_load((dest / 'metadata.yaml').read_text())['rosbag2_bagfile_information']['custom_data']
    assert custom['acds.scenario_name'] == 'fault_campaign' and custom['acds.steps'] == '150'
    assert custom['acds.recovered'].startswith('170 messages from ')
    assert yaml.safe_load(custom['acds.publishers']) == {WHEELS: ['reaction_wheels']}
    from acds_runtime.bag.reader import open_bag
    assert got == list(open_bag(src).messages()), 'same messages, stamps and order'
    # the copy is an ordinary closed bag
    info = acds('info', str(dest))
    assert info.returncode == 0 and info.stderr == '' and 'recovered:  170 messages' in info.stdout


def test_recover_refuses_what_would_touch_the_source(tmp_path, folder_state):
    src = tmp_path / 'src'
    make_bag(src, steps=30, close=False)
    before = folder_state(tmp_path)
    for dest, reason in ((src / 'inside', 'is inside the bag'), (src, 'is inside the bag'),
                         (tmp_path, 'already exists')):
        proc = acds('recover', str(src), str(dest))
        line = one_line(proc)
        assert proc.returncode == 2 and reason in line, line
        assert folder_state(tmp_path) == before


# ---- 3. a bag being recorded is recognised, and not disturbed -------------------------------------------------

def test_a_bag_being_recorded_is_refused_in_one_line(tmp_path, folder_state, play_domain):
    from acds_runtime.bag.writer import BagWriter

    bag = tmp_path / 'live'
    writer = BagWriter(bag, 'mcap', {'scenario_name': 'fault_campaign'})
    try:
        assert (bag / 'acds_recording.lock').exists()
        before = folder_state(bag)
        for verb in (*BAG_VERBS, 'recover'):
            args = (['recover', str(bag), str(tmp_path / 'copy')] if verb == 'recover'
                    else verb_args(verb, bag, tmp_path, play_domain))
            proc = acds(*args)
            line = one_line(proc)
            assert proc.returncode == 2 and f'bag {bag}: is being recorded' in line, f'{verb}: {line}'
            assert folder_state(bag) == before, f'{verb} touched a bag being recorded'
    finally:
        writer.close()
    assert not (bag / 'acds_recording.lock').exists(), 'a clean close removes the marker'
    assert acds('info', str(bag)).returncode == 0


def test_a_dead_recorders_lock_file_does_not_look_like_a_recording(tmp_path, folder_state):
    """The killed writer leaves its lock file, and its child process (a node of a dead launcher) lives on:
    neither makes the bag look recorded (the lock is not inherited; a dead holder's lock is released)."""

    bag = tmp_path / 'crashed'
    got = make_bag(bag, steps=40, child=True, close=False)
    try:
        before = folder_state(bag)
        proc = acds('info', str(bag))
        assert proc.returncode == 0 and f'bag {bag} was not closed' in proc.stderr, proc.stderr
        assert folder_state(bag) == before
        assert (bag / 'acds_recording.lock').exists(), 'the dead writer left its lock file'
        from acds_runtime.bag.recording import being_recorded
        assert not being_recorded(bag)
    finally:
        os.kill(got['child'], signal.SIGKILL)


def test_info_during_acds_run_record_does_not_disturb_the_recording(launch_graph, tmp_path):
    from acds_runtime.bag.reader import open_bag

    bag = tmp_path / 'bag'
    with launch_graph('free_tumble_heao_b', steps=100000, record=bag) as graph:
        wait_for_messages(graph, topics.CLOCK, 5)
        proc = acds('info', str(bag))
        line = one_line(proc)
        assert proc.returncode == 2 and f'bag {bag}: is being recorded' in line, line
        seen = len(graph.monitor.messages(topics.CLOCK))
        wait_for_messages(graph, topics.CLOCK, seen + 20)
    read = open_bag(bag)  # closed when the run stopped
    assert read.unclosed is None and not (bag / 'acds_recording.lock').exists()
    clock = [t for _, t, _ in read.messages([topics.CLOCK])]
    assert len(clock) >= seen + 20, 'the bag holds the whole run, not what was there when info ran'
    assert clock == [k * 500_000_000 for k in range(len(clock))], 'no step lost or repeated'


# ---- 5. reading streams ----------------------------------------------------------------------------------------

@pytest.mark.parametrize(('storage', 'closed'), [('mcap', True), ('mcap', False), ('sqlite3', False)])
def test_info_streams_a_50_mb_bag(tmp_path, storage, closed):
    from acds_cli.bag.info import bag_info

    bag = tmp_path / 'big'
    make_bag(bag, storage, steps=3200, payload=16_000, flush_every=32, close=closed, compression='none')  # 50 MB on disk
    size = sum(f.stat().st_size for f in bag.iterdir())
    assert size > 50e6
    tracemalloc.start()
    try:
        text = bag_info(bag)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert 'messages:   9600 on 3 topics' in text, text
    assert peak < size / 8, f'info held {peak / 2**20:.1f} MiB reading a {size / 2**20:.1f} MiB bag'


# ---- 6. the bag verbs' bad options: one line, before anything starts --------------------------------------------

@pytest.fixture
def unclosed_bag(tmp_path):
    """An unclosed bag: reading it prints a note, so a check that runs first leaves stderr with its line only."""
    bag = tmp_path / 'area' / 'bag'
    make_bag(bag, steps=20, close=False)
    return bag


@pytest.mark.parametrize(('args', 'message'), [
    (['play', '{bag}', '--rate', '-1'], '--rate -1: must be a finite number >= 0'),
    (['play', '{bag}', '--rate', 'nan'], '--rate nan: must be a finite number >= 0'),
    (['play', '{bag}', '--rate', 'inf'], '--rate inf: must be a finite number >= 0'),
    (['compare', '{bag}', '--node', 'reaction_wheels', '--tolerance', 'nan'], '--tolerance nan: must be a finite'),
    (['compare', '{bag}', '--node', 'reaction_wheels', '--tolerance', '-1'], '--tolerance -1: must be a finite'),
    (['plot', '{bag}', '--out', '{file}'], 'output folder {file}: exists and is not a folder'),
    (['plot', '{bag}', '--out', '{file}/sub'], 'output folder {file}/sub: cannot write in {file}'),
])
def test_bad_bag_options_are_one_line_before_reading(tmp_path, unclosed_bag, folder_state, args, message):
    blocker = tmp_path / 'a_file'
    blocker.write_text('x')
    fill = {'bag': str(unclosed_bag), 'file': str(blocker)}
    before = folder_state(tmp_path)
    proc = acds(*(a.format(**fill) for a in args))
    line = one_line(proc)  # the unclosed-bag note would be a second line: the bag was not read
    assert proc.returncode == 2 and line.startswith(f'acds {args[0]}: ') and message.format(**fill) in line, line
    assert folder_state(tmp_path) == before
