"""A study's journal (samples.jsonl) read back by --resume: a line that is JSON but not a sample record is one
JournalError naming the line, not a KeyError/TypeError traceback."""

from __future__ import annotations

import json

import pytest
from acds_runtime.journal import Journal, JournalError, text_hash

STUDY = {'verb': 'montecarlo', 'scenario': 's', 'seed': 1, 'runs': 2}


def _journal(tmp_path, *lines: str):
    hashes = {('', 0): text_hash('a'), ('', 1): text_hash('b')}
    j = Journal(tmp_path, STUDY, hashes, resume=False)
    j.record(('', 0), {'scenario': 's_s1k0', 'steps': 3})
    j.close()
    with open(tmp_path / 'samples.jsonl', 'a') as fh:
        for line in lines:
            fh.write(line + '\n')
    return hashes


def test_a_resumed_journal_keeps_its_samples(tmp_path):
    hashes = _journal(tmp_path)
    j = Journal(tmp_path, STUDY, hashes, resume=True)
    assert j.done == {('', 0): {'scenario': 's_s1k0', 'steps': 3}}
    j.close()


@pytest.mark.parametrize('line', ['{"index": 1}', '[1, 2]', '7', json.dumps({'index': 1, 'case': ''})])
def test_a_line_that_is_not_a_sample_record_is_named(tmp_path, line):
    hashes = _journal(tmp_path, line)
    with pytest.raises(JournalError, match=r'samples.jsonl line 3 is not a sample record'):
        Journal(tmp_path, STUDY, hashes, resume=True)
