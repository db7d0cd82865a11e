"""rosbag2 bags of ACDS runs, on top of ``rosbags``: written in lockstep (:mod:`.writer`) and read (:mod:`.reader`).

Bags are ordinary rosbag2 bags (metadata version 9, MCAP by default, sqlite3 on
request) with message definitions and ``offered_qos_profiles`` per topic, so
``rosbags``, the ``mcap`` package, Foxglove and ``ros2 bag`` open them.
Timestamps are sim time: a message's ``header.stamp`` (``clock`` for
``/clock``); messages without a stamp (``events``, ``ground/*``) take the
latest ``/clock``. The run's scenario, the exact node parameters and who
published each topic are stored in ``custom_data`` (``acds.*`` keys) and, from
the moment recording starts, beside the storage file in ``acds_run.yaml``.

Reading never writes: bags are opened read-only and their messages streamed
(:mod:`.reader`); an unclosed bag is read as far as it is readable
(:mod:`.salvage`), a bag being recorded is recognised by its writer's lock
(:mod:`.recording`), and a repaired copy is an explicit step (:mod:`.recover`).

The option names below are here, not in :mod:`.writer`, so a command line can offer them without
importing rosbags.
"""

#: Bag storages (``--storage``), MCAP the default.
STORAGE_NAMES = ('mcap', 'sqlite3')
#: ``--compression`` choices; the default is zstd for MCAP (rosbag2's and libmcap's), none for sqlite3.
COMPRESSIONS = ('zstd', 'none')
