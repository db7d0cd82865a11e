"""The bag verbs of the command line: recorder, player, replay regression, plots, info, dump report.

Bags are read and written by :mod:`acds_runtime.bag` (format, reader, salvage, recover, writer).
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
