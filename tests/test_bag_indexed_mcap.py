"""A closed MCAP bag's messages from its chunk index (:mod:`acds_runtime.bag.indexed_mcap`): the messages rosbags
reads, in rosbags' order (timestamp; equal times in the file's order), across overlapping chunks and every chunk
compression; a damaged chunk is one line naming the bag; an unindexed file is still read through rosbags."""

from __future__ import annotations

import shutil
import struct

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.bag.indexed_mcap import IndexedMcap, indexed
from acds_runtime.bag.reader import _Rosbags, open_bag
from acds_runtime.bag.writer import BagError
from acds_runtime.direct import DirectRun
from mcap.writer import CompressionType, IndexType, Writer

TOPICS = ('/a', '/b', '/c')


def _messages(n: int = 600) -> list[tuple[str, int, bytes]]:
    """Times that go back within and across chunks, with ties (what a monitor taking messages as they arrive
    writes), on three channels."""
    return [(TOPICS[i % 3], 100 + (i // 12) * 10 - 17 * (i % 5 == 0), f'message {i}'.encode()) for i in range(n)]


def _write(path, messages, compression=CompressionType.ZSTD, index_types=IndexType.ALL, chunk_size=300):
    with path.open('wb') as fh:
        writer = Writer(fh, chunk_size=chunk_size, compression=compression, index_types=index_types)
        writer.start(profile='ros2')
        schema = writer.register_schema('std_msgs/msg/String', 'ros2msg', b'string data')
        ids = {t: writer.register_channel(t, 'cdr', schema) for t in TOPICS}
        for topic, t, data in messages:
            writer.add_message(ids[topic], t, data, t)
        writer.finish()
    return path


@pytest.mark.parametrize('compression', list(CompressionType))
def test_overlapping_chunks_come_out_in_time_then_file_order(tmp_path, compression):
    written = _messages()
    file = _write(tmp_path / 'x.mcap', written, compression)
    assert indexed(file)
    expected = sorted(written, key=lambda m: m[1])  # stable: equal times keep the order they were written in
    assert list(IndexedMcap(file).messages(None)) == expected
    assert list(IndexedMcap(file).messages({'/b', '/c'})) == [m for m in expected if m[0] != '/a']
    assert list(IndexedMcap(file).messages({'/nothing'})) == []


def test_a_recorded_bag_reads_as_rosbags_reads_it(tmp_path):
    bag = tmp_path / 'bag'
    DirectRun(load_scenario('heao_b_acquisition_short'), steps=300, record=bag).run()
    opened = open_bag(bag)
    assert isinstance(opened.source, IndexedMcap)
    reference = _Rosbags(bag)
    assert list(opened.messages()) == list(reference.messages(None))
    chosen = {'/acds/mode', '/acds/truth/odometry', '/clock'}
    assert list(opened.messages(chosen)) == list(reference.messages(chosen))


def test_a_damaged_chunk_is_one_line_naming_the_bag(tmp_path):
    bag = tmp_path / 'bag'
    DirectRun(load_scenario('heao_b_acquisition_short'), steps=50, record=bag, record_compression='none').run()
    damaged = tmp_path / 'damaged'
    shutil.copytree(bag, damaged)
    (file,) = damaged.glob('*.mcap')
    data = bytearray(file.read_bytes())
    at = 8  # after the magic: records of an opcode byte and a u64 length, up to the first chunk
    while data[at] != 0x06:
        at += 9 + struct.unpack_from('<Q', data, at + 1)[0]
    # the chunk's first record (after its times, sizes, CRC, compression '' and records' length) runs past its end
    struct.pack_into('<Q', data, at + 9 + 8 + 8 + 8 + 4 + 4 + 8 + 1, 10**9)
    file.write_bytes(bytes(data))
    with pytest.raises(BagError) as err:
        list(open_bag(damaged).messages())
    assert str(err.value).startswith(f'bag {damaged}: reading its messages failed: ValueError: the chunk at offset')
    assert str(err.value).endswith(': its last record runs past its end') and '\n' not in str(err.value)


def test_an_unindexed_file_is_not_taken_for_an_indexed_one(tmp_path):
    file = _write(tmp_path / 'x.mcap', _messages(50), index_types=IndexType.NONE)
    assert not indexed(file)
