"""The Foxglove layout of the live view (``foxglove/acds_layout.json``, issue 12 §4), built with ``foxglove.layouts``.

Regenerate the file after changing a topic or a view (a test compares the two)::

    .venv/bin/python -m acds_runtime.foxglove_layout > foxglove/acds_layout.json

Left: the 3D panel in the ECI frame (the body axes tumbling about the common origin, the sun frame whose z
axis is the sun line, the magnetometer frame on the body), the diagnostics summary below it. Right, sim
time on every x axis (one sliding hour): |body rates| in deg/s against the Mode 1A → 1B thresholds, the
sun angle against the capture cone, wheel momentum in ft-lb-s, the moment command and the achieved dipole
in A·m² between ±the command saturation, and the mode as a state timeline.
"""

from __future__ import annotations

import foxglove.layouts as fl
from acds_common import topics
from acds_common.parameters import node_parameters
from acds_common.scenario import load_scenario, shipped_role

from .foxglove_bridge import (
    VIEW_MODE,
    VIEW_MOMENT,
    VIEW_RATES,
    VIEW_SUN_ANGLE,
    VIEW_WHEEL_MOMENTUM,
    frames_of,
)

#: Axis colours (x, y, z), as the 3D panel draws frame axes.
COLORS = ('#e5533d', '#3fb950', '#4a90e2')
AXES = ('x', 'y', 'z')
#: Sim-time width of the plots' sliding window, s.
WINDOW_S = 3600.0


def _plot(title: str, y_label: str, series: list[fl.PlotSeries]) -> fl.PlotPanel:
    return fl.PlotPanel(title=title, config=fl.PlotConfig(
        paths=series, y_axis_label=y_label, show_legend=True, legend_display='floating',
        time_window_mode='sliding', following_view_width=WINDOW_S, playback_bar_position='right', is_synced=True))


def _xyz(topic: str, field: str, label: str, style: str = 'solid') -> list[fl.PlotSeries]:
    """One series per body axis: ``topic.<field with {a}>``."""
    return [fl.PlotSeries(value=f'{topic}.{field.format(a=a)}', label=label.format(a=a), color=c, line_style=style)
            for a, c in zip(AXES, COLORS, strict=True)]


def layout() -> fl.Layout:
    """The ACS engineer's layout of a live run or a played bag."""
    rates = _plot('|body rate| vs the Mode 1A → 1B thresholds', 'deg/s',
                  _xyz(VIEW_RATES, 'abs_{a}_deg_s', '|ω{a}|')
                  + _xyz(VIEW_RATES, 'threshold_{a}_deg_s', 'threshold {a}', 'dashed'))
    sun = _plot('sun angle (z body to the sun line) vs the capture cone', 'deg', [
        fl.PlotSeries(value=f'{VIEW_SUN_ANGLE}.sun_angle_deg', label='sun angle', color='#f5a623'),
        fl.PlotSeries(value=f'{VIEW_SUN_ANGLE}.capture_cone_deg', label='capture cone', color='#f5a623',
                      line_style='dashed')])
    wheels = _plot('wheel momentum', 'ft-lb-s', _xyz(VIEW_WHEEL_MOMENTUM, '{a}_ft_lb_s', 'h{a}'))
    moments = _plot('dipole: command (solid), achieved step average (dotted), ±saturation', 'A·m²',
                    _xyz(VIEW_MOMENT, '{a}_am2', 'M{a} command')
                    + _xyz(topics.resolve(topics.DIPOLE_AVG), 'vector.{a}', 'M{a} achieved', 'dotted')
                    + [fl.PlotSeries(value=f'{VIEW_MOMENT}.{key}', label=label, color='#999999', line_style='dashed')
                       for key, label in (('max_am2', '+max'), ('min_am2', '−max'))])
    mode = fl.StateTransitionsPanel(title='mode', config=fl.StateTransitionsConfig(
        paths=[fl.StateTransitionsSeries(value=f'{VIEW_MODE}.mode', label='mode')], is_synced=True,
        time_window_mode='sliding', x_axis_range=WINDOW_S, playback_bar_position='right'))
    # the main job's graph names the frames (every scenario's graph declares the same ones)
    frames = frames_of(node_parameters(load_scenario(shipped_role('main_job')), 1, 0.0))
    scene = fl.ThreeDeePanel(title=f'attitude: {frames.body} frame tumbling, sun line = {frames.sun} z, {frames.world} '
                                   'axes', config=fl.ThreeDeeConfig(
        fixed_frame=frames.world, follow_tf=frames.world, follow_mode='follow-none',
        camera_state=fl.ThreeDeeCameraState(distance=6.0, perspective=True, phi=60.0, theta_offset=45.0,
                                            target=(0.0, 0.0, 0.0), target_offset=(0.0, 0.0, 0.0),
                                            target_orientation=(0.0, 0.0, 0.0, 1.0), fovy=45.0, near=0.01,
                                            far=1000.0),
        scene=fl.BaseRendererSceneSettings(transforms=fl.BaseRendererTransforms(
            show_label=True, label_size=0.15, axis_size=1.5, line_width=2.0)),
        # The odometry pose sits at the orbit position (thousands of km off the frames' origin): hidden.
        topics={topics.resolve(topics.TRUTH_ODOMETRY): fl.BaseRendererPoseTopicSettings(visible=False)}))
    diagnostics = fl.DiagnosticsSummaryPanel(title='diagnostics', config=fl.DiagnosticsSummaryConfig(
        topic_to_render=topics.resolve(topics.DIAGNOSTICS), sort_by_level=True))
    left = fl.SplitContainer(direction='column', items=[fl.SplitItem(proportion=2, content=scene),
                                                        fl.SplitItem(proportion=1, content=diagnostics)])
    right = fl.SplitContainer(direction='column', items=[
        fl.SplitItem(proportion=1, content=panel) for panel in (rates, sun, wheels, moments)]
        + [fl.SplitItem(proportion=0.4, content=mode)])
    return fl.Layout(content=fl.SplitContainer(direction='row', items=[
        fl.SplitItem(proportion=1, content=left), fl.SplitItem(proportion=1.4, content=right)]))


def layout_json() -> str:
    """The layout file's text (indented JSON, one trailing newline)."""
    import json

    return json.dumps(json.loads(layout().to_json()), indent=2, ensure_ascii=False) + '\n'


if __name__ == '__main__':
    print(layout_json(), end='')
