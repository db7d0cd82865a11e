"""``acds info``: a bag's topics, types, counts, sim-time span and the run's scenario."""

from __future__ import annotations

from pathlib import Path

import yaml

from .reader import open_bag


def bag_info(bag_path: Path | str, *, scenario: bool = True) -> str:
    """The text ``acds info`` prints."""
    bag = open_bag(bag_path)
    t0, t1 = bag.span_ns()
    total = sum(len(v) for v in bag.raw.values())
    size = sum(f.stat().st_size for f in bag.path.iterdir() if f.is_file())
    lines = [f'bag:        {bag.path}',
             f'storage:    {bag.storage} ({size / 2**20:.2f} MiB), rosbag2 metadata version 9',
             f'sim time:   {t0 / 1e9:.3f} s … {t1 / 1e9:.3f} s ({(t1 - t0) / 60e9:.2f} min)',
             f'messages:   {total} on {len(bag.raw)} topics']
    if bag.info.get('scenario_name'):
        lines.append(f'scenario:   {bag.info["scenario_name"]} ({bag.info.get("steps", "?")} steps of '
                     f'{bag.info.get("control_period_s", "?")} s; nodes {bag.info.get("nodes", "?")})')
    if bag.recovered is not None or 'recovered' in bag.info:
        lines.append(f'recovered:  {bag.info.get("recovered", bag.recovered)}')
    pubs = yaml.safe_load(bag.info.get('publishers', '') or '{}') or {}
    width = max((len(t) for t in bag.raw), default=10)
    lines.append('')
    lines.append(f'{"topic":{width}s}  {"type":38s} {"count":>7s}  {"first s":>9s} {"last s":>9s}  publishers')
    for topic in sorted(bag.raw):
        msgs = bag.raw[topic]
        first = f'{msgs[0][0] / 1e9:9.2f}' if msgs else ' ' * 9
        last = f'{msgs[-1][0] / 1e9:9.2f}' if msgs else ' ' * 9
        lines.append(f'{topic:{width}s}  {bag.types[topic]:38s} {len(msgs):7d}  {first} {last}  '
                     f'{", ".join(pubs.get(topic, []))}')
    if scenario and bag.info.get('scenario'):
        lines += ['', '--- scenario (as run) ---', bag.info['scenario'].rstrip()]
    return '\n'.join(lines)
