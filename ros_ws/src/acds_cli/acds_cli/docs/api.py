"""The API reference of the pure cores: every module of the workspace's packages that does not import rclpy.

The cores are numpy + stdlib (house rule), so autodoc imports them without a ROS graph; a node module
(``*_node.py``) and the lockstep host are the thin ROS edge and are left out.
"""

from __future__ import annotations

import re
from pathlib import Path

#: A module that imports rclpy (directly) is ROS edge, not core.
_ROS_IMPORT = re.compile(r'^\s*(import rclpy|from rclpy)', re.M)


def core_modules(src: Path) -> dict[str, list[str]]:
    """{package: [module, ...]} of the pure-core modules under ``src`` (``ros_ws/src``)."""
    out: dict[str, list[str]] = {}
    for pkg_dir in sorted(p for p in src.iterdir() if (p / 'setup.py').exists()):
        pkg = pkg_dir.name
        mods = []
        for path in sorted((pkg_dir / pkg).rglob('*.py')):
            rel = path.relative_to(pkg_dir).with_suffix('')
            if path.name == '__main__.py' or path.name.endswith('_node.py') or _ROS_IMPORT.search(path.read_text()):
                continue
            if path.name == '__init__.py':
                rel = rel.parent
            mods.append('.'.join(rel.parts))
        if mods:
            out[pkg] = mods
    return out


def write_api(src: Path, out: Path) -> None:
    """One page per package (``out/<package>.md``: automodule of each core module) and an index."""
    out.mkdir(parents=True, exist_ok=True)
    modules = core_modules(src)
    index = ['# API reference of the pure cores', '',
             'Generated from the docstrings of every module that does not import rclpy: the models, laws and '
             'numerics of each package, and the shared mechanism (`acds_common`). The node modules '
             '(`*_node.py`) and the lockstep host are the thin ROS edge and are described in '
             '[Architecture](../../architecture.md).', '',
             '```{toctree}', ':maxdepth: 1', '', *modules, '```', '']
    (out / 'index.md').write_text('\n'.join(index))
    for pkg, mods in modules.items():
        lines = [f'# `{pkg}`', '']
        for mod in mods:
            lines += [f'## `{mod}`', '', '```{eval-rst}', f'.. automodule:: {mod}', '   :members:', '```', '']
        (out / f'{pkg}.md').write_text('\n'.join(lines))
