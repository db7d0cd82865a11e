"""rosbag2 bags of ACDS runs, on top of ``rosbags``: writer, reader, player, replay-regression, plots, info.

Bags are ordinary rosbag2 bags (metadata version 9, MCAP by default, sqlite3 on
request) with message definitions and ``offered_qos_profiles`` per topic, so
``rosbags``, the ``mcap`` package, Foxglove and ``ros2 bag`` open them.
Timestamps are sim time: a message's ``header.stamp`` (``clock`` for
``/clock``); messages without a stamp (``events``, ``ground/*``) take the
latest ``/clock``. The run's scenario, the exact node parameters and who
published each topic are stored in ``custom_data`` (``acds.*`` keys) and, from
the moment recording starts, beside the storage file in ``acds_run.yaml``.

Reading never writes: every verb opens bags read-only and streams their
messages (:mod:`.reader`); an unclosed bag is read as far as it is readable
(:mod:`.salvage`), a bag being recorded is recognised by its writer's lock
(:mod:`.recording`), and a repaired copy is an explicit step (:mod:`.recover`).
"""

from __future__ import annotations

import signal
import threading

#: ``plot --format`` choices.
FORMATS = ('png', 'svg', 'pdf')


def stop_on_signals() -> threading.Event:
    """An event set by SIGINT or SIGTERM (the recorder and the player stop cleanly on either)."""
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda _signum, _frame: stop.set())
    return stop
