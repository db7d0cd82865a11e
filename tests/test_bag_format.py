"""Bags as rosbag2 Jazzy writes them (issue 12 §3 "Bags like rosbag2 writes them").

* MCAP chunks zstd-compressed by default, plain with ``compression='none'``, the same messages
  either way; ``ros_distro: jazzy`` in ``metadata.yaml`` and in the storage's own copy of it;
* each MCAP channel carries rosbag2's ``topic_type_hash``: the RIHS01 hash that the installed
  ROS message packages ship for the type (``share/<pkg>/msg/<Type>.json``);
* ``acds run ... --storage sqlite3`` records a sqlite3 bag (jazzy schema), and a sqlite3 bag with
  zstd is refused in one line before anything runs;
* durability pin: what the writer relies on in rosbags' storages (closing the pending MCAP chunk,
  the sqlite connection) still makes every message written before :meth:`BagWriter.flush` readable
  from the unclosed bag — a rosbags upgrade that breaks it fails here.
"""

from __future__ import annotations

import json
import os
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from acds_common import topics
from acds_common.cdr import Codec
from acds_common.scenario import load_scenario
from acds_runtime.bag.reader import open_bag
from acds_runtime.direct import DirectRun
from mcap.reader import make_reader
from rosbags.rosbag2 import Reader

SHARE = Path(sys.prefix) / 'share'
ROOT = Path(__file__).resolve().parents[1]


def _direct_bag(tmp_path: Path, compression: str | None) -> Path:
    bag = tmp_path / f'bag_{compression}'
    DirectRun(load_scenario('heao_b_acquisition_short'), steps=100, record=bag, record_compression=compression).run()
    return bag


def _installed_hash(msgtype: str) -> str:
    pkg, _, name = msgtype.split('/')
    data = json.loads((SHARE / pkg / 'msg' / f'{name}.json').read_text())
    return next(h['hash_string'] for h in data['type_hashes'] if h['type_name'] == msgtype)


def _mcap(bag: Path) -> Path:
    (path,) = bag.glob('*.mcap')
    return path


def test_mcap_bags_are_written_as_rosbag2_jazzy_writes_them(tmp_path):
    zstd_bag, plain_bag = _direct_bag(tmp_path, None), _direct_bag(tmp_path, 'none')
    for bag, compression in ((zstd_bag, 'zstd'), (plain_bag, '')):
        meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
        assert meta['ros_distro'] == 'jazzy' and meta['storage_identifier'] == 'mcap'
        assert meta['compression_format'] == '' and meta['compression_mode'] == ''  # storage-level, as rosbag2
        with _mcap(bag).open('rb') as fh:
            reader = make_reader(fh)
            summary = reader.get_summary()
            chunks = {c.compression for c in summary.chunk_indexes}
            assert chunks == {compression}, chunks
            stored = yaml.safe_load(next(m for m in reader.iter_metadata() if m.name == 'rosbag2')
                                    .metadata['serialized_metadata'])
            assert stored['ros_distro'] == 'jazzy'
            schemas = summary.schemas
            for channel in summary.channels.values():
                msgtype = schemas[channel.schema_id].name
                assert set(channel.metadata) == {'offered_qos_profiles', 'topic_type_hash'}, channel.topic
                assert channel.metadata['topic_type_hash'] == _installed_hash(msgtype), channel.topic
                assert meta['topics_with_message_count'][0]['topic_metadata']['type_description_hash'].startswith(
                    'RIHS01_')
    with Reader(zstd_bag) as a, Reader(plain_bag) as b:  # rosbags reads both; the same data in both
        def data(reader):  # /diagnostics aside: rigid_body's health carries its wall time
            return [(c.topic, t, d) for c, t, d in reader.messages() if c.topic != topics.DIAGNOSTICS]
        assert data(a) == data(b) and len(data(a)) > 1000
    assert _mcap(zstd_bag).stat().st_size < 0.5 * _mcap(plain_bag).stat().st_size


def _acds(*argv: str, tmp_path: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, ROS_LOG_DIR=str(tmp_path / 'ros_log'))
    return subprocess.run([sys.executable, '-m', 'acds_cli', *argv], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=300, check=False)


def test_run_records_sqlite3_and_refuses_compressed_sqlite3(tmp_path):
    bag = tmp_path / 'sq_bag'
    proc = _acds('run', 'free_tumble_heao_b', '--steps', '40', '--storage', 'sqlite3', '--record', str(bag),
                 '--run-dir', str(tmp_path / 'run'), '--quiet', tmp_path=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    (db,) = bag.glob('*.db3')
    with sqlite3.connect(f'file:{db}?mode=ro', uri=True) as conn:
        assert conn.execute('SELECT ros_distro FROM schema').fetchone() == ('jazzy',)
        (stored,) = conn.execute('SELECT metadata FROM metadata').fetchone()
        assert yaml.safe_load(stored)['ros_distro'] == 'jazzy'
        hashes = dict(conn.execute('SELECT type, type_description_hash FROM topics').fetchall())
    assert hashes and all(h == _installed_hash(t) for t, h in hashes.items())
    meta = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert meta['storage_identifier'] == 'sqlite3' and meta['ros_distro'] == 'jazzy'
    read = open_bag(bag)
    assert read.count(topics.TRUTH_ODOMETRY) == 41 and read.info['run_id'] == 'run'
    proc = _acds('run', 'free_tumble_heao_b', '--steps', '40', '--storage', 'sqlite3', '--compression', 'zstd',
                 '--record', str(tmp_path / 'never'), '--run-dir', str(tmp_path / 'run2'), '--quiet', tmp_path=tmp_path)
    err = proc.stderr
    assert proc.returncode == 2 and 'sqlite3 bags are not compressed' in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / 'never').exists() and not (tmp_path / 'run2').exists()


_KILLED_WRITER = """
import os, signal, sys
from acds_common import topics
from acds_common.cdr import Codec
from acds_runtime.bag.writer import BagWriter
path, storage, compression = sys.argv[1:]
codec = Codec(topics.TYPES[topics.WHEEL_MOMENTUM], 'base_link')
writer = BagWriter(path, storage, {'control_period_s': '0.5'}, flush_period_s=3600.0, compression=compression)
for k in range(300):  # far below a chunk's 1 MiB and FLUSH_MESSAGES: only flush() makes them durable
    writer.write(topics.resolve(topics.WHEEL_MOMENTUM), codec.encode(k * 500_000_000, (k, -1.0, 2.0)))
assert writer.error is None, writer.error
writer.flush()
assert writer.error is None, writer.error
os.kill(os.getpid(), signal.SIGKILL)
"""


@pytest.mark.parametrize(('storage', 'compression'), [('mcap', 'zstd'), ('mcap', 'none'), ('sqlite3', 'none')])
def test_flush_makes_every_written_message_survive_a_sigkill(tmp_path, storage, compression):
    path = tmp_path / 'bag'
    proc = subprocess.run([sys.executable, '-c', _KILLED_WRITER, str(path), storage, compression],
                          capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == -9, proc.stderr
    assert not (path / 'metadata.yaml').exists()
    bag = open_bag(path)  # unclosed: read from the storage as it is on disk
    codec = Codec(topics.TYPES[topics.WHEEL_MOMENTUM], 'base_link')
    assert [codec.decode(data)[1][0] for _topic, _t, data in bag.messages()] == [float(k) for k in range(300)]
