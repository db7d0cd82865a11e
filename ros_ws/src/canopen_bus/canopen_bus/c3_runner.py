"""The user's OreSat C3 flight software, unmodified, started against a run's bus (spec §13, "The real C3").

The C3 (``oresat-c3`` 0.6.6 on ``oresat-olaf`` 3.7.4, installed by ``scripts/setup_env.sh`` into ``.venv-c3`` from
``requirements-c3.lock``) is the user's program: it is run as it ships, never patched, and everything it writes
stays in the run folder. As root it would write under ``/var/lib/oresat`` and ``/var/cache/oresat``
(``olaf/canopen/node.py``), to ``/tmp`` (its log ``/tmp/olaf.log``, its mock F-RAM ``/tmp/FM24CL64B.bin``, its file
caches ``/tmp/oresat``), set the system clock from an RTC (``oresat_c3/subsystems/rtc.py``) and restart network
interfaces (``olaf/canopen/network.py``). So it runs

* in a private mount namespace (``unshare --mount``) where the run folder's ``c3/tmp``, ``c3/var_tmp`` and
  ``c3/dev_shm`` are bound over ``/tmp``, ``/var/tmp`` and ``/dev/shm`` (anything of the checkout under ``/tmp`` is
  bound back in first, so its environment and the run folder stay reachable), and
* as the unprivileged user ``nobody`` (``setpriv``), with ``HOME`` in the run folder (OLAF's non-root paths are
  ``~/.oresat`` and ``~/.cache/oresat``) and only the capability to read and search any file
  (``CAP_DAC_READ_SEARCH``: the checkout may sit in a folder only root enters), so it can neither set the clock nor
  write a file outside the run folder;
* in mock-hardware mode with flight mode off (``-m all -d``) on python-can's ``socketcand`` bus
  (``-t socketcand -H HOST -b vcan0``), its REST API on a free loopback port.

OLAF opens the bus once at start (the hub must already listen) and always on port 29536: ``olaf_setup`` builds
``CanNetwork(bus_type, bus, host)`` without a port and the port defaults to 29536 (``olaf/canopen/network.py``).
Its output (loguru, unbuffered) goes to ``c3/c3.log`` in the run folder. The process is one exec chain
(``unshare`` → ``sh`` → ``setpriv`` → python), so its pid is the C3's; stopping sends SIGTERM (OLAF stops its
services and exits in about a second), then SIGKILL after a bound, and waits for it: no orphan is left.
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

#: The socketcand port the C3 connects to whatever it is told: OLAF passes no port (olaf/canopen/network.py: 29536).
C3_SOCKETCAND_PORT = 29536
#: The CANopen node id of the C3 (oresat-configs' cards table; its heartbeat is COB-ID 0x701).
C3_NODE_ID = 0x01
#: The unprivileged user the C3 runs as.
NOBODY_UID = NOBODY_GID = 65534
#: The channel name the C3 opens on the hub (a socketcand bus name; no kernel interface of that name is needed).
CHANNEL = 'vcan0'
#: How long a stopped C3 gets to end its services before SIGKILL, s.
STOP_GRACE_S = 10.0

#: Run inside the new mount namespace by /bin/sh: $1 the C3's folder in the run, $2 the C3's python, $3… its args,
#: with C3_BIND_BACK the paths under /tmp to bind back over the private /tmp (newline-separated).
_NAMESPACE_SCRIPT = r'''set -eu
dir=$1; py=$2; shift 2
printf '%s\n' "$C3_BIND_BACK" | while IFS= read -r p; do
  [ -n "$p" ] || continue
  mkdir -p "$dir/tmp${p#/tmp}"
  mount --bind "$p" "$dir/tmp${p#/tmp}"
done
mount --rbind "$dir/tmp" /tmp
mount --bind "$dir/var_tmp" /var/tmp
mount --bind "$dir/dev_shm" /dev/shm
cd "$dir/home"
exec setpriv --reuid=65534 --regid=65534 --clear-groups --inh-caps=+dac_read_search \
  --ambient-caps=+dac_read_search env -u C3_BIND_BACK HOME="$dir/home" PYTHONUNBUFFERED=1 "$py" -m oresat_c3 "$@"
'''


class C3Error(RuntimeError):
    """The C3 cannot be started here (one line naming what is missing)."""


def checkout_root() -> Path:
    """The checkout whose ``.venv`` runs this code (``ACDS_WORKSPACE`` when set, as ``scripts/acds`` sets it)."""
    given = os.environ.get('ACDS_WORKSPACE')
    return Path(given).resolve() if given else Path(sys.prefix).resolve().parent


def c3_python(root: Path | None = None) -> Path:
    """The C3 environment's interpreter (``.venv-c3``, made by ``scripts/setup_env.sh``)."""
    return (root or checkout_root()) / '.venv-c3' / 'bin' / 'python'


def _free_loopback_port() -> int:
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class C3Process:
    """One C3 process in its private namespace; a context manager that stops it on leaving."""

    def __init__(self, out_dir: Path, host: str = '127.0.0.1', port: int = C3_SOCKETCAND_PORT,
                 python: Path | None = None, verbose: bool = False) -> None:
        self.dir = Path(out_dir).resolve()
        self.host = host
        self.port = port
        self.python = Path(python) if python else c3_python()
        self.verbose = verbose
        self.proc: subprocess.Popen | None = None
        self.log_path = self.dir / 'c3.log'

    def check(self) -> None:
        """Everything the start needs, each failure one line (raised before any process starts)."""
        if self.port != C3_SOCKETCAND_PORT:
            raise C3Error(f'the C3 connects to socketcand port {C3_SOCKETCAND_PORT} only (OLAF passes no port to '
                          f'python-can), not {self.port}: run the bus on --can-port {C3_SOCKETCAND_PORT}')
        if not self.python.is_file():
            raise C3Error(f'no C3 environment at {self.python.parent.parent} (scripts/setup_env.sh creates it from '
                          'requirements-c3.lock)')
        if os.geteuid() != 0:
            raise C3Error('starting the C3 needs root: it runs in a private mount namespace as the user nobody, so '
                          'it writes nothing outside the run folder')
        for tool in ('unshare', 'setpriv', 'mount'):
            if shutil.which(tool) is None:
                raise C3Error(f'{tool} (util-linux) is not installed: it keeps the C3 inside the run folder')

    def command(self) -> list[str]:
        """The command line: the namespace, the drop to nobody, and the C3's own arguments."""
        args = ['-m', 'all', '-d', '-t', 'socketcand', '-H', self.host, '-b', CHANNEL,
                '-a', '127.0.0.1', '-p', str(_free_loopback_port())]
        if self.verbose:
            args.append('-v')
        return ['unshare', '--mount', '--propagation', 'private', '--', '/bin/sh', '-c', _NAMESPACE_SCRIPT, 'c3',
                str(self.dir), str(self.python), *args]

    def _bind_back(self) -> str:
        """Paths under /tmp the C3 must still see once /tmp is private: its environment and its own folder."""
        paths = {self.python.parent.parent.resolve(), self.dir}
        return '\n'.join(sorted(str(p) for p in paths if p.parts[:2] == ('/', 'tmp')))

    def start(self) -> C3Process:
        self.check()
        for sub in ('home', 'tmp', 'var_tmp', 'dev_shm'):
            (self.dir / sub).mkdir(parents=True, exist_ok=True)
        for path in (self.dir, *(p for p in self.dir.rglob('*') if not p.is_symlink())):
            os.chown(path, NOBODY_UID, NOBODY_GID)
        env = {**os.environ, 'C3_BIND_BACK': self._bind_back()}
        with open(self.log_path, 'ab') as log:
            self.proc = subprocess.Popen(self.command(), stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                                         env=env, start_new_session=True)
        return self

    @property
    def pid(self) -> int | None:
        return self.proc.pid if self.proc else None

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def stop(self, grace_s: float = STOP_GRACE_S) -> int | None:
        """SIGTERM, then SIGKILL after ``grace_s``; waits for the process and returns its exit status."""
        if self.proc is None:
            return None
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(grace_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return self.proc.returncode

    def __enter__(self) -> C3Process:
        return self.start()

    def __exit__(self, *_exc: object) -> None:
        self.stop()
