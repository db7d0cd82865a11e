"""``acds recover SRC DEST``: write a repaired copy of a bag; SRC is only ever read.

The copy is rebuilt from SRC's storage file (read as :func:`open_bag` reads an
unclosed bag: MCAP up to its last complete chunk, sqlite3 up to its last
committed transaction) and its sidecar ``acds_run.yaml``: the same messages
with the same timestamps, in the same storage, with an index, ``metadata.yaml``
and the ``acds.*`` custom data (plus ``acds.recovered`` saying what was kept).
DEST must not exist and must not lie inside SRC's folder.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import yaml

from .reader import Bag, open_bag
from .writer import BagError, BagWriter, check_target

#: Sidecar keys that describe a writer's set-up, not the run (not copied as custom data).
WRITER_KEYS = ('storage', 'compression', 'flush_period_s', 'publishers', 'recovered')


def recover_bag(src: Path | str, dest: Path | str, compression: str | None = None) -> tuple[Bag, Bag]:
    """Write the repaired copy of ``src`` at ``dest`` (``compression`` None: the storage's default); return
    (``src`` as read, the copy). Raises :class:`BagError`."""
    src, dest = Path(src), Path(dest)
    bag = open_bag(src, use_metadata=False)
    if dest.resolve().is_relative_to(bag.path.resolve()):
        raise BagError(f'recover: {dest} is inside the bag {bag.path}: the copy must go elsewhere (SRC is never changed)')
    check_target(dest, bag.storage, compression)
    info = {k: v for k, v in bag.info.items() if k not in WRITER_KEYS}
    writer = BagWriter(dest, bag.storage, info, compression=compression)
    try:
        publishers = yaml.safe_load(bag.info.get('publishers', '') or '{}') or {}
        for topic, names in publishers.items():
            writer.note_publishers(str(topic), [str(n) for n in names or []])
        for topic, t, data in bag.messages():
            writer.write(topic, data, msgtype=bag.types[topic], qos=bag.qos.get(topic) or None, t_ns=t)
            if writer.error:
                break
        writer.info['recovered'] = f'{sum(writer.counts.values())} messages from {bag.path}, read {bag.unclosed}'
        writer.close()
        if writer.error:
            raise BagError(writer.error)
    except BaseException:
        writer.close()
        shutil.rmtree(dest, ignore_errors=True)  # only the copy this call created (check_target: it did not exist)
        raise
    return bag, open_bag(dest)
