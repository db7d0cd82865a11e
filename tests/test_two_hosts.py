"""The external node on another machine (issue 20 §6): two network namespaces joined by a veth pair stand for two
hosts; the graph runs in one, the example flight software (examples/oresat_detumble_fsw) in the other, and
discovery crosses the link only: the launcher's participants contact the other host as a static peer
(``acds run --peer``, ROS_STATIC_PEERS; discovery otherwise stays on the host, ROS_AUTOMATIC_DISCOVERY_RANGE=
LOCALHOST), the flight computer contacts the graph's host the same way and speaks UDP only (a Fast DDS profile
without shared memory, which two real hosts cannot share either). The run must equal the single-host one.
Creating namespaces needs root (CI runs as root); elsewhere the test skips, saying so.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from acds_common.scenario import load_scenario
from acds_runtime.direct import DirectRun
from acds_runtime.launcher import DOMAIN_RANGE, DomainLease

ROOT = Path(__file__).resolve().parents[1]
STEPS = 400
UDP_ONLY = """<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <transport_descriptors>
      <transport_descriptor><transport_id>udp</transport_id><type>UDPv4</type></transport_descriptor>
    </transport_descriptors>
    <participant profile_name="udp_only" is_default_profile="true">
      <rtps>
        <userTransports><transport_id>udp</transport_id></userTransports>
        <useBuiltinTransports>false</useBuiltinTransports>
      </rtps>
    </participant>
  </profiles>
</dds>
"""


def _ip(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(['ip', *args], capture_output=True, text=True, check=False, timeout=30)


@pytest.fixture
def two_hosts():
    """(graph host, flight computer): two namespaces, a veth pair between them, their addresses."""
    if shutil.which('ip') is None:
        pytest.skip('no ip command (iproute2): network namespaces cannot be created here')
    tag = f'{os.getpid() % 100000}'
    a, b = f'acds_graph_{tag}', f'acds_fsw_{tag}'
    made = _ip('netns', 'add', a)
    if made.returncode != 0:
        pytest.skip(f'network namespaces cannot be created here: {made.stderr.strip()}')
    subnet = f'10.{200 + os.getpid() % 50}.{os.getpid() % 250}'
    try:
        steps = [('netns', 'add', b), ('link', 'add', f'va{tag}', 'type', 'veth', 'peer', 'name', f'vb{tag}'),
                 ('link', 'set', f'va{tag}', 'netns', a), ('link', 'set', f'vb{tag}', 'netns', b),
                 ('-n', a, 'addr', 'add', f'{subnet}.1/24', 'dev', f'va{tag}'),
                 ('-n', b, 'addr', 'add', f'{subnet}.2/24', 'dev', f'vb{tag}'),
                 ('-n', a, 'link', 'set', f'va{tag}', 'up'), ('-n', b, 'link', 'set', f'vb{tag}', 'up'),
                 ('-n', a, 'link', 'set', 'lo', 'up'), ('-n', b, 'link', 'set', 'lo', 'up')]
        for step in steps:
            done = _ip(*step)
            assert done.returncode == 0, f'ip {" ".join(step)}: {done.stderr.strip()}'
        yield (a, f'{subnet}.1'), (b, f'{subnet}.2')
    finally:
        _ip('netns', 'del', a)
        _ip('netns', 'del', b)


@pytest.mark.slow
def test_the_flight_computer_on_another_host_flies_the_single_host_run(two_hosts, tmp_path):
    (graph_ns, graph_ip), (fsw_ns, fsw_ip) = two_hosts
    profile = tmp_path / 'udp_only.xml'
    profile.write_text(UDP_ONLY)
    domain = str(next(d for d in DOMAIN_RANGE if not DomainLease.held(d)))  # the launcher leases it (or refuses)
    fsw_env = {**os.environ, 'ROS_DOMAIN_ID': domain, 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
               'ROS_STATIC_PEERS': graph_ip, 'FASTRTPS_DEFAULT_PROFILES_FILE': str(profile),
               'ROS_LOG_DIR': str(tmp_path / 'fsw_log')}
    fsw_env.pop('ACDS_LAUNCHER_PID', None)
    exe = shutil.which('oresat_detumble_fsw', path=str(Path(sys.executable).parent))
    assert exe, 'the example is not installed (./scripts/acds setup installs examples/*)'
    summary = tmp_path / 'summary.json'
    with (tmp_path / 'fsw.log').open('w') as log:
        fsw = subprocess.Popen(['ip', 'netns', 'exec', fsw_ns, exe], env=fsw_env, stdout=log,
                               stderr=subprocess.STDOUT, start_new_session=True)
        try:
            run = subprocess.run(
                ['ip', 'netns', 'exec', graph_ns, sys.executable, '-m', 'acds_cli', 'run', 'oresat_detumble',
                 '--steps', str(STEPS), '--external', 'acds_controller=oresat_detumble_fsw', '--domain', domain,
                 '--peer', fsw_ip, '--no-record', '--quiet', '--run-dir', str(tmp_path / 'run'),
                 '--summary-json', str(summary)],
                cwd=ROOT, capture_output=True, text=True, timeout=240, check=False)
        finally:
            fsw.terminate()
            fsw.wait(timeout=30)
    assert run.returncode == 0, run.stderr[-3000:] + (tmp_path / 'fsw.log').read_text()[-2000:]
    two = json.loads(summary.read_text())
    one = DirectRun(load_scenario('oresat_detumble'), steps=STEPS).run().summary
    assert two['truth_digest'] == one['truth_digest']
    assert two['timing']['acds_controller']['steps'] == STEPS + 1
    print(f"\ntwo hosts: truth digest {two['truth_digest'][:16]}… = single host; flight computer step time "
          f"p50 {two['timing']['acds_controller']['p50_ms']:.3f} ms, p99 {two['timing']['acds_controller']['p99_ms']:.3f} ms")
