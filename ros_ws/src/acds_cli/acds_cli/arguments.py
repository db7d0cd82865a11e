"""Command-line checks shared by the verbs: a bad option is one line and exit 2, before anything runs.

Value checks are argparse ``type`` functions (their message names the option);
output paths are checked for writability before a run starts, not when its
results are written; :class:`OneLineParser` prints an error as one line
instead of the usage block followed by the error.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
from pathlib import Path
from typing import NoReturn

from acds_common.parameters import MAX_REAL_TIME_FACTOR
from acds_common.scenario import MAX_STEPS


class UsageError(Exception):
    """A command-line option cannot work (the message names it); the verb exits 2 before anything starts."""


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line: ``acds VERB: error: <what> (see acds VERB --help)``."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f'{self.prog}: error: {message} (see {self.prog} --help)\n')


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a whole number, got {text!r}') from None


def positive_int(text: str) -> int:
    """An integer ≥ 1 (worker counts)."""
    value = _whole(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be a positive integer, got {text}')
    return value


def non_negative_int(text: str) -> int:
    """An integer ≥ 0 (counts that may be none)."""
    value = _whole(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'must be a whole number >= 0, got {text}')
    return value


#: ROS domain ids DDS can map to ports (Fast DDS refuses a domain above 232; rclpy one below 0).
ROS_DOMAINS = range(0, 233)


def domain_in(text: str, domains: range = ROS_DOMAINS) -> int:
    """A ROS domain id in ``domains`` (``play``/``record --domain``: any; ``run --domain``: the launcher's range)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value not in domains:
        raise argparse.ArgumentTypeError(f'expected a ROS domain id in {domains.start}..{domains.stop - 1}, '
                                         f'got {text!r}')
    return value


def step_count(text: str) -> int:
    """A number of control steps: 1 … MAX_STEPS."""
    value = positive_int(text)
    if value > MAX_STEPS:
        raise argparse.ArgumentTypeError(f'{value:,} steps is more than the {MAX_STEPS:,} a run may have')
    return value


def positive_number(text: str) -> float:
    """A finite number > 0, in the unit the option names (checked as typed, before any conversion)."""
    value = _number(text)
    if not math.isfinite(value) or value <= 0.0:
        raise argparse.ArgumentTypeError(f'must be a finite number > 0, got {text}')
    return value


def non_negative_number(text: str) -> float:
    """A finite number ≥ 0, in the unit the option names."""
    value = _number(text)
    if not math.isfinite(value) or value < 0.0:
        raise argparse.ArgumentTypeError(f'must be a finite number >= 0, got {text}')
    return value


def positive_minutes(text: str) -> float:
    """A finite sim time > 0, minutes."""
    value = _number(text)
    if not math.isfinite(value) or value <= 0.0:
        raise argparse.ArgumentTypeError(f'must be a finite number of minutes > 0, got {text}')
    return value


def real_time_factor(text: str) -> float:
    """A finite pacing factor in [0, MAX_REAL_TIME_FACTOR]; 0 means as fast as possible."""
    value = _number(text)
    if not math.isfinite(value) or not 0.0 <= value <= MAX_REAL_TIME_FACTOR:
        raise argparse.ArgumentTypeError(f'must be a finite number in [0, {MAX_REAL_TIME_FACTOR:g}] '
                                         f'(0: as fast as possible), got {text}')
    return value


def peer_host(text: str) -> str:
    """A host discovery can reach (``--peer``; one entry of ROS_STATIC_PEERS): a name or address that resolves, as
    Fast DDS resolves it when the first participant is created (there, an unresolvable peer was a traceback)."""
    import socket

    if not text or ';' in text or text != text.strip():
        raise argparse.ArgumentTypeError(f'expected one host name or address (repeat --peer for more), got {text!r}')
    try:
        socket.getaddrinfo(text, None)
    except (OSError, UnicodeError) as exc:
        raise argparse.ArgumentTypeError(f'cannot resolve host {text!r}: {exc}') from None
    return text


def tcp_port(text: str) -> int:
    """A TCP port to listen on: 0 (any free port) … 65535."""
    value = _whole(text)
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f'must be a TCP port in [0, 65535] (0: any free port), got {text}')
    return value


#: Port of the live view when ``--foxglove`` names none: the one the Foxglove app proposes (ws://localhost:8765).
FOXGLOVE_PORT = 8765
#: Address it listens on unless ``--foxglove-host`` says otherwise: this machine only.
FOXGLOVE_HOST = '127.0.0.1'


def add_foxglove_options(parser: argparse.ArgumentParser, what: str) -> None:
    """``--foxglove [PORT]`` and ``--foxglove-host``: serve ``what`` live to Foxglove (run and play)."""
    parser.add_argument('--foxglove', nargs='?', type=tcp_port, const=FOXGLOVE_PORT, metavar='PORT',
                        help=f'serve {what} live over the Foxglove WebSocket protocol on PORT (default '
                             f'{FOXGLOVE_PORT}, 0: any free port); layout for the app: foxglove/acds_layout.json')
    parser.add_argument('--foxglove-host', default=FOXGLOVE_HOST, metavar='HOST',
                        help=f'address the Foxglove server listens on (default {FOXGLOVE_HOST}: this machine only)')


def _probe(option: str, path: Path, folder: Path) -> None:
    """Create (and at once drop) an unnamed file in ``folder``: the one honest writability test."""
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as exc:
        raise UsageError(f'{option} {path}: cannot write in {folder}: {exc.strerror or exc}') from None


def _existing_ancestor(option: str, path: Path, folder: Path) -> Path:
    """The nearest existing folder at or above ``folder`` (created folders go below it); it must be a directory."""
    folder = folder.absolute()
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    if not folder.is_dir():
        raise UsageError(f'{option} {path}: {folder} is not a directory')
    return folder


def check_output_dir(option: str, path: Path) -> None:
    """``path`` can be (or already is) a folder this process writes into."""
    if path.exists() and not path.is_dir():
        raise UsageError(f'{option} {path}: exists and is not a directory')
    _probe(option, path, _existing_ancestor(option, path, path))


def check_output_file(option: str, path: Path) -> None:
    """``path`` can be written as a file (missing folders above it are created when it is written)."""
    if path.is_dir():
        raise UsageError(f'{option} {path}: is a directory, not a file')
    if path.exists() and not os.access(path, os.W_OK):
        raise UsageError(f'{option} {path}: the file is not writable')
    _probe(option, path, _existing_ancestor(option, path, path.absolute().parent))
