"""A node started by hand with ``acds params`` output, as a ROS user would (issue 12 §1, §2).

* ``acds params`` prints exactly what the launcher writes to a run's ``params.yaml``;
* ``.venv/bin/rigid_body --ros-args --params-file FILE`` with a required parameter removed stops
  at once, exit 2, with "missing parameter NAME" (not a model error about a zero inertia);
* a running node refuses ``set_parameters`` (rcl_interfaces ``SetParameters`` service, what
  ``ros2 param set`` calls) of its read-only parameters, in range or out of it, and says why;
  its descriptors carry the schema's range and unit.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import rclpy
import yaml
from acds_cli.__main__ import main
from acds_common.lockstep import release_node
from acds_common.parameters import node_parameters, parameters_yaml
from acds_common.scenario import load_scenario
from acds_runtime.launcher import FASTDDS_PROFILE, DomainLease
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import DescribeParameters, SetParameters
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

VENV_BIN = Path(sys.executable).parent
SCENARIO = 'heao_b_acquisition'


def _params_text(*argv: str) -> str:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(['params', *argv]) == 0
    return out.getvalue()


def test_params_verb_prints_the_launchers_params_file():
    sc = load_scenario(SCENARIO)
    assert _params_text(SCENARIO) == parameters_yaml(node_parameters(sc, sc.total_steps()))
    one = yaml.safe_load(_params_text(SCENARIO, '--node', 'em_driver', '--steps', '40'))
    assert list(one) == ['/acds/em_driver']
    assert one['/acds/em_driver']['ros__parameters'] == node_parameters(sc, 40)['em_driver']


def test_params_verb_prints_a_formation_vehicles_node_with_its_namespace():
    """``--node VEHICLE/NODE`` (the names its own error lists): the node's file, started in its vehicle's namespace
    (it was a KeyError traceback)."""
    text = _params_text('emff_testbed_hold', '--node', 'a/em_driver', '--steps', '40')
    head = [line for line in text.splitlines() if line.startswith('#')]
    assert head[1] == '# Start it by hand: .venv/bin/em_driver --ros-args -r __ns:=/acds/a --params-file THIS_FILE'
    assert head[3] == '#   a publisher on /acds/a/controller/moment_command (from a/formation_controller)', head
    assert head[-1].startswith('#   (no step after the one formation_dynamics names on /acds/lockstep/run_end'), head
    sc = load_scenario('emff_testbed_hold')
    assert yaml.safe_load(text) == {'/acds/a/em_driver': {'ros__parameters': node_parameters(sc, 40)['a/em_driver']}}


@pytest.mark.parametrize('rtf', ['-1', 'nan', 'inf', '2e6'])
def test_params_verb_refuses_a_real_time_factor_that_run_refuses(rtf, capsys):
    """``--rtf`` as ``acds run`` takes it (finite, in [0, 1e6]): one line, exit 2, no file with a value the time owner
    cannot start with."""
    with pytest.raises(SystemExit) as exc:
        main(['params', SCENARIO, '--rtf', rtf])
    assert exc.value.code == 2
    err = capsys.readouterr()
    assert err.out == '' and 'argument --rtf: must be a finite number in [0, 1e+06]' in err.err, err


@pytest.fixture
def ros_domain(tmp_path):
    """A leased ROS domain and the environment of a node started in it by hand."""
    lease = DomainLease()
    env = {**os.environ, 'ROS_DOMAIN_ID': str(lease.domain_id), 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST',
           'FASTRTPS_DEFAULT_PROFILES_FILE': str(FASTDDS_PROFILE), 'ROS_LOG_DIR': str(tmp_path / 'ros_log')}
    env.pop('ROS_LOCALHOST_ONLY', None)
    try:
        yield lease.domain_id, env
    finally:
        lease.close()


def _params_file(tmp_path: Path, node: str, drop: str | None = None, **values: float) -> Path:
    data = yaml.safe_load(_params_text(SCENARIO, '--node', node, '--steps', '50'))
    params = data[f'/acds/{node}']['ros__parameters']
    if drop is not None:
        del params[drop]
    params.update(values)
    path = tmp_path / f'{node}.yaml'
    path.write_text(yaml.safe_dump(data))
    return path


def test_node_without_a_required_parameter_names_it(tmp_path, ros_domain):
    _domain, env = ros_domain
    path = _params_file(tmp_path, 'rigid_body', drop='spacecraft_inertia_kg_m2')
    proc = subprocess.run([str(VENV_BIN / 'rigid_body'), '--ros-args', '--params-file', str(path)], env=env,
                          capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 2, proc.stderr
    assert 'missing parameter spacecraft_inertia_kg_m2' in proc.stderr
    assert 'positive definite' not in proc.stderr


def _call(executor: SingleThreadedExecutor, client, request, timeout_s: float = 30.0, attempt_s: float = 2.0):
    """Call a service, sending the request again every ``attempt_s``: ``service_is_ready`` means the server's
    request reader is matched, not that it has matched this client's response reader, and a response sent
    before that is lost (ROS 2 services do not resend). Describe and a refused set are idempotent."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        future = client.call_async(request)
        executor.spin_until_future_complete(future, timeout_sec=min(attempt_s, deadline - time.monotonic()))
        if future.done():
            return future.result()
        client.remove_pending_request(future)
    raise AssertionError(f'no answer from {client.srv_name} within {timeout_s} s')


def test_running_node_refuses_to_set_its_read_only_parameters(tmp_path, ros_domain):
    domain, env = ros_domain
    path = _params_file(tmp_path, 'reaction_wheels', input_timeout_s=120.0)
    # Its graph is absent, so it waits for /acds/controller/wheel_volts: 120 s (its readiness timeout) to be asked.
    proc = subprocess.Popen([str(VENV_BIN / 'reaction_wheels'), '--ros-args', '--params-file', str(path)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    context = Context()
    old_env = {k: os.environ.get(k) for k in ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'FASTRTPS_DEFAULT_PROFILES_FILE')}
    os.environ.update(ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', FASTRTPS_DEFAULT_PROFILES_FILE=str(FASTDDS_PROFILE))
    rclpy.init(context=context, domain_id=domain)
    try:
        node = Node('param_client', context=context)
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        setter = node.create_client(SetParameters, '/acds/reaction_wheels/set_parameters')
        describer = node.create_client(DescribeParameters, '/acds/reaction_wheels/describe_parameters')
        deadline = time.monotonic() + 20.0
        while not (setter.service_is_ready() and describer.service_is_ready()) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        assert setter.service_is_ready(), 'reaction_wheels never offered its parameter services'

        desc = _call(executor, describer, DescribeParameters.Request(names=['input_timeout_s'])).descriptors[0]
        assert desc.read_only and '[s]' in desc.description
        assert (desc.floating_point_range[0].from_value, desc.floating_point_range[0].to_value) == (0.1, 3600.0)

        def set_double(name: str, value: float):
            param = Parameter(name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value))
            return _call(executor, setter, SetParameters.Request(parameters=[param])).results[0]

        in_range, out_of_range = set_double('input_timeout_s', 60.0), set_double('input_timeout_s', -5.0)
        for result in (in_range, out_of_range):
            assert not result.successful, 'a read-only parameter was reported as set'
            assert 'read-only' in result.reason
        release_node(executor, node, context)
    finally:
        rclpy.try_shutdown(context=context)
        for key, value in old_env.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    assert proc.returncode == 0, out
