"""The workspace packages behave like ROS 2 packages (issue 12 §1).

* ``colcon build`` (colcon from PyPI, into a temporary folder, no symlinks) installs every
  console script where ``ros2 run PKG EXE`` looks for it, ``install/PKG/lib/PKG/EXE``, and the
  installed executable runs (it answers a bad parameter as a node does, exit 2);
* each ``package.xml`` declares exactly what the package's code needs at run time: the imports of
  its modules (an AST scan, tests excluded) mapped to ROS package keys, the message packages of
  the topics its nodes publish and read, ``rclpy`` for a package with node executables.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from importlib import metadata
from pathlib import Path

import pytest
from acds_common import topics
from acds_common.graph import declared_nodes, node_spec
from acds_common.scenario import SCHEMA

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / 'ros_ws' / 'src'
PACKAGES = sorted(p.name for p in SRC.iterdir() if (p / 'package.xml').is_file())
VENV_BIN = Path(sys.executable).parent
#: Python distributions → their ROS package keys (rosdep names).
PYTHON_KEYS = {'numpy': 'python3-numpy', 'yaml': 'python3-yaml', 'matplotlib': 'python3-matplotlib',
               'pytest': 'python3-pytest', 'rosbags': 'python3-rosbags-pip', 'rclpy': 'rclpy',
               'dask': 'python3-dask', 'tqdm': 'python3-tqdm', 'ppigrf': 'python3-ppigrf-pip',
               'foxglove': 'python3-foxglove-sdk-pip', 'websockets': 'python3-websockets', 'mcap': 'python3-mcap-pip',
               'numba': 'python3-numba', 'sphinx': 'python3-sphinx', 'docutils': 'python3-docutils',
               'can': 'python3-can', 'canopen': 'python3-canopen-pip', 'oresat_configs': 'python3-oresat-configs-pip',
               'zstandard': 'python3-zstandard', 'lz4': 'python3-lz4'}
#: Packages whose code publishes or subscribes to any graph topic by its type name
#: (``acds_common.lockstep.message_class``: the node host, the runtime's monitor and recorder, the CLI's recorder and player).
EVERY_TOPIC = {'acds_common', 'acds_runtime', 'acds_cli'}
#: Packages that start every node (the launcher runs each node's executable, the direct engine
#: imports each stepper by its ``package.module:Class`` path).
EVERY_NODE = {'acds_runtime'}


def _message_package(type_name: str) -> str:
    return type_name.split('/')[0]


def _imports(package: str) -> set[str]:
    """Top-level modules imported by the package's modules (tests excluded)."""
    found: set[str] = set()
    for path in (SRC / package / package).rglob('*.py'):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                found.update(alias.name.split('.')[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                found.add(node.module.split('.')[0])
    return found


def variant_parameters(node: str) -> list[dict]:
    """Parameters of ``node`` that reach each of its variants: its sections' defaults, then each choice of each
    of their string keys in turn (a variant is picked by one key: ``wheels.kind``, ``modes.system``, ...), and
    every declared node in the graph (the controller's cold-gas variant flies with node ``cold_gas``)."""
    _pkg, decl = declared_nodes()[node]
    fields = {f.param_name(s, k): f for s in decl.sections for k, f in SCHEMA[s].items()}
    base = {name: f.default for name, f in fields.items()} | {'formation_vehicles': ['a', 'b'], 'graph_nodes': []}
    return [base, {**base, 'graph_nodes': list(declared_nodes())}] + [
        {**base, name: choice} for name, f in fields.items() if f.kind == 'str' for choice in f.choices]


def _node_message_packages(package: str) -> set[str]:
    """Message packages of every topic the package's nodes publish or read (every variant)."""
    out: set[str] = set()
    for node, (pkg, _decl) in declared_nodes().items():
        if pkg.name != package:
            continue
        for params in variant_parameters(node):
            spec = node_spec(node, params)
            out.update(_message_package(o.msg_type) for o in spec.outputs)
            out.update(_message_package(topics.type_of(i.topic)) for st in spec.stages for i in st.inputs)
            if spec.ground_commands:
                out.add(_message_package(topics.TYPES[topics.GROUND_COMMAND]))
    return out


def required_dependencies(package: str) -> set[str]:
    """What ``package`` needs at run time, as ROS package keys."""
    needed: set[str] = set()
    for module in _imports(package) - {package, '__future__'}:
        if module in sys.stdlib_module_names:
            continue
        if module in PACKAGES or module.endswith('_msgs') or module == 'rcl_interfaces':
            needed.add(module)
        elif module in PYTHON_KEYS:
            needed.add(PYTHON_KEYS[module])
        else:
            raise AssertionError(f'{package} imports {module}: add its ROS package key to PYTHON_KEYS')
    needed |= _node_message_packages(package)
    if package in EVERY_TOPIC:
        needed |= {_message_package(t) for t in topics.all_types().values()}
    if package in EVERY_NODE:
        needed |= {pkg.name for pkg, _decl in declared_nodes().values()}
    if console_scripts(package):
        needed.add('rclpy')  # a node executable is an rclpy process
    return needed


def declared_dependencies(package: str) -> set[str]:
    """The ``<exec_depend>`` and ``<depend>`` entries of the package's ``package.xml``."""
    root = ET.parse(SRC / package / 'package.xml').getroot()
    return {e.text.strip() for tag in ('exec_depend', 'depend') for e in root.iter(tag)}


def console_scripts(package: str) -> list[str]:
    """Console-script names the package's distribution declares (its setup.py entry points)."""
    return sorted(ep.name for ep in metadata.distribution(package).entry_points if ep.group == 'console_scripts')


def test_every_package_has_node_executables_as_the_graph_needs():
    executables = {exe: pkg for pkg in PACKAGES for exe in console_scripts(pkg)}
    for name, (pkg, _decl) in declared_nodes().items():
        assert executables.get(name) == pkg.name, f'node {name}: no console script in {pkg.name}'


@pytest.mark.parametrize('package', PACKAGES)
def test_package_xml_declares_what_the_code_imports(package):
    required, declared = required_dependencies(package), declared_dependencies(package)
    assert not required - declared, f'{package}/package.xml misses <exec_depend> {sorted(required - declared)}'
    assert not declared - required, f'{package}/package.xml declares unused {sorted(declared - required)}'


def test_dependency_scan_sees_what_the_issue_found_missing():
    """The scan is not vacuous: the dependencies issue 12 found missing are required by it."""
    assert 'nav_msgs' in required_dependencies('dynamics')
    assert 'nav_msgs' in required_dependencies('acds_controller')
    assert {'rcl_interfaces', 'python3-yaml'} <= required_dependencies('acds_common')


def _tree_state() -> str:
    """Changed, untracked and ignored paths under ros_ws/src, less the ``__pycache__`` folders that any import
    writes (the other test worker imports the cores meanwhile; colcon's own output is what must not appear)."""
    out = subprocess.run(['git', 'status', '--porcelain', '--ignored', '--', 'ros_ws/src'], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    return ''.join(line for line in out.splitlines(keepends=True) if not line.rstrip().endswith('__pycache__/'))


@pytest.mark.slow
@pytest.mark.timeout(900)  # eight packages built one after the other: > 300 s on a loaded 2-core machine
def test_colcon_build_installs_executables_where_ros2_run_looks(tmp_path):
    before = _tree_state()
    proc = subprocess.run(
        [str(VENV_BIN / 'colcon'), '--log-base', str(tmp_path / 'log'), 'build', '--base-paths', str(SRC),
         '--build-base', str(tmp_path / 'build'), '--install-base', str(tmp_path / 'install'),
         '--event-handlers', 'console_direct-'],
        cwd=tmp_path, capture_output=True, text=True, timeout=600, check=False)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert f'{len(PACKAGES)} packages finished' in proc.stdout + proc.stderr
    install = tmp_path / 'install'
    site = [str(p) for p in sorted(install.glob('*/lib/python3*/site-packages'))]
    assert len(site) == len(PACKAGES)
    for package in PACKAGES:
        assert (install / package / 'share' / 'ament_index' / 'resource_index' / 'packages' / package).is_file()
        assert (install / package / 'share' / package / 'package.xml').is_file()
        assert not (install / package / 'bin').exists(), f'{package}: executables in bin/, where ros2 run never looks'
        for exe in console_scripts(package):
            path = install / package / 'lib' / package / exe
            assert path.is_file() and not path.is_symlink() and os.access(path, os.X_OK), f'{package} {exe}: {path}'
    # the installed executable is the node: it starts rclpy and refuses an unknown parameter (exit 2)
    env = {**os.environ, 'PYTHONPATH': os.pathsep.join(site), 'ROS_LOG_DIR': str(tmp_path / 'ros_log')}
    run = subprocess.run([str(install / 'dynamics' / 'lib' / 'dynamics' / 'reaction_wheels'), '--ros-args',
                          '-p', 'no_such_parameter:=1.0'], env=env, capture_output=True, text=True, timeout=60,
                         check=False)
    assert run.returncode == 2 and 'unknown parameter(s) no_such_parameter' in run.stderr, run.stderr
    assert _tree_state() == before, 'colcon build wrote into the source tree'
