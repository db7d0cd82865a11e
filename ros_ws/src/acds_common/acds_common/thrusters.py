"""The cold-gas thruster arrangement: which thrusters torque which signed body axis, with what arm (seed 002 §5, §6.2.5).

Shared by the cold-gas reaction control node (the physics: the torque and force each firing gives) and the
controller (its gas law knows its actuators as a flight program does: the torque per signed axis), as
:mod:`acds_common.coupling` is shared by the magnetometer and the controller.

**Each signed axis: one thruster, or a couple fired together.** The study's system has *six* thrusters, at most
two valves open at once (Table 5-2; §13.2.2: thruster monitoring goes "from 12 to 6"). A signed axis is served by
one thruster whose torque lies along it alone, or, failing that, by two fired together whose torques add up to a
torque along it alone (a couple: the two valves Table 5-2 allows). Six thrusters cannot give six pure couples (the
pairing graph would be cycles: an odd cycle forces f = −f, an even one puts every thrust on one line, with no
torque about it), and no single thruster can torque the roll axis x alone unless its line of action lies in the
centre-of-mass station (r × d along x needs r_x = 0): so a layout on one station aft of the centre of mass rolls
with couples and pitches and yaws with single thrusters or couples. The net force of a firing (a couple's is zero
for roll) is stated in :attr:`Arrangement.force_per_thrust` and reported on ``cold_gas/wrench``; it is not fed to
the orbit (the orbit is Keplerian, spec §3): at 4.6 lb of GN₂ and Isp 65 s the whole load's impulse is 1330 N·s,
a Δv of at most 0.46 m/s on HEAO-B's 6,436 lb (2,919 kg, Table 4-1; docs/missions/heao.md, tests/test_docs_figures.py checks it).

**Default layout, ``platform`` (§6.2.5).** "The six thrusters located on the lower surface of the equipment
platform of the spacecraft equipment module … The thruster orientation is similar to the current HEAO reaction
control system." The HEAO-B geometry the study gives: the mass centre 100.3 in forward of the separation plane,
−0.5 in (y) and 0.7 in (z) off the spacecraft centre line (Table 4-1); the current RCS's "YAW/ROLL THRUSTER (4
PLACES)" at STA 4.36, 4.36 in above the separation plane (Figure 6-1 sheet 2, section E-E). Taken here (not in
the seed, stated): the platform's lower surface at STA 4.36, so every thruster is 95.94 in (2.437 m) aft of the
mass centre; the thrusters at the platform's edge on the ±z centre lines at 40.25 in (1.022 m) from the centre
line, the largest lateral station the study dimensions on that surface (section E-E: the z-axis electromagnet's
centre line at y = 40.25 in, beside the launch vehicle's clearance envelope). Orientation like the HEAO RCS's
yaw/roll thrusters: at each of the two places one thruster fires +y and one −y (tangential: a couple across the
two places rolls, the same two on one side yaw) and one fires radially outward along z (pitch, alone: its line
of action lies in the x–z plane through the centre line, 0.5 in from the mass centre's). Arms: pitch and yaw
2.437 m (yaw by a couple of two thrusters, 2 × 2.437 m per thruster's thrust), roll 2 × 1.022 m by a couple.

**Alternative, ``outriggers``** (the layout shipped before §6.2.5 was read): the pitch and yaw thrusters at an aft
bulkhead 2.4 m behind the centre of mass, the roll thrusters on outriggers in the centre-of-mass station at
1.2 m radius, each axis on one thruster. ``custom``: the scenario's ``thruster_positions`` and
``thruster_directions``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations

from acds_common.units import INCH_M

#: Signed body axes in thruster order: +x, −x, +y, −y, +z, −z.
SIGNED_AXES = ((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0))
AXIS_NAMES = ('+x', '-x', '+y', '-y', '+z', '-z')
#: HEAO-B mass centre (Table 4-1): station (in forward of the separation plane), y and z off the centre line (in).
HEAO_B_MASS_CENTRE_IN = (100.3, -0.5, 0.7)
#: The current RCS's yaw/roll thrusters' station, taken as the equipment platform's lower surface (Figure 6-1, in).
PLATFORM_THRUSTER_STATION_IN = 4.36
#: Lateral station of the platform thrusters from the centre line (Figure 6-1 section E-E, taken; in).
PLATFORM_THRUSTER_RADIUS_IN = 40.25


def _platform_layout() -> tuple[tuple[float, ...], tuple[float, ...]]:
    """§6.2.5's layout (module docstring): T1…T6 positions from the mass centre (m) and thrust directions."""
    x0, y0, z0 = HEAO_B_MASS_CENTRE_IN
    x = (PLATFORM_THRUSTER_STATION_IN - x0) * INCH_M
    y = -y0 * INCH_M
    up, down = (PLATFORM_THRUSTER_RADIUS_IN - z0) * INCH_M, (-PLATFORM_THRUSTER_RADIUS_IN - z0) * INCH_M
    # T1 +z place, thrust −y; T2 −z place, +y; T3 +z place, +y; T4 −z place, −y (the tangential pairs);
    # T5 −z place, thrust +z; T6 +z place, thrust −z (pitch; each exhausts outward, away from the centre line)
    positions = (x, y, up, x, y, down, x, y, up, x, y, down, x, y, down, x, y, up)
    directions = (0.0, -1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0)
    return positions, directions


#: The shipped layouts (module docstring): name → (positions, m, from the mass centre; thrust directions), T1…T6.
LAYOUTS: dict[str, tuple[tuple[float, ...], tuple[float, ...]]] = {
    'platform': _platform_layout(),
    'outriggers': ((0.0, 0.0, 1.2, 0.0, 0.0, -1.2, -2.4, 0.0, -1.2, -2.4, 0.0, 1.2, -2.4, 1.2, 0.0, -2.4, -1.2, 0.0),
                   (0.0, -1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, -1.0, 0.0, 0.0, 1.0, 0.0)),
}
#: The default layout (§6.2.5), and ``custom``: the scenario's positions and directions.
DEFAULT_LAYOUT = 'platform'
LAYOUT_CHOICES = (*LAYOUTS, 'custom')
#: Largest off-axis torque of a thruster or couple, as a fraction of its on-axis torque, accepted by default.
MAX_CROSS_COUPLING = 0.05


class ArrangementError(ValueError):
    """Thruster positions/directions that do not give a torque about each signed axis (names what is missing)."""


def _cross(r: Sequence[float], f: Sequence[float]) -> tuple[float, float, float]:
    return (r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0])


@dataclass(frozen=True)
class Arrangement:
    """Six thrusters: per thruster the torque and force per newton of thrust, and the thrusters of each signed axis.

    ``torque_per_thrust[j]``: r_j × d_j (m; N·m per N). ``force_per_thrust[j]``: d_j (unit).
    ``thrusters_of_axis[a]``: the thruster, or the couple fired together, serving signed axis a (order
    :data:`SIGNED_AXES`). ``arm_m[a]``: their on-axis torque per newton of each one's thrust (m; a couple's is the
    sum of both).
    """

    torque_per_thrust: tuple[tuple[float, float, float], ...]
    force_per_thrust: tuple[tuple[float, float, float], ...]
    thrusters_of_axis: tuple[tuple[int, ...], ...]
    arm_m: tuple[float, ...]

    def axes_of(self, thruster: int) -> tuple[int, ...]:
        """The signed-axis indexes a thruster serves (alone or in a couple)."""
        return tuple(a for a, group in enumerate(self.thrusters_of_axis) if thruster in group)

    def axis_names(self, thruster: int) -> str:
        """The signed axes a thruster serves, e.g. ``'+x +z'``."""
        return ' '.join(AXIS_NAMES[a] for a in self.axes_of(thruster))


def _about(tau: Sequence[float], a: int, limit: float) -> float:
    """The on-axis torque of ``tau`` about signed axis a if it is about that axis alone (off-axis ≤ limit), else 0."""
    axis, sign = SIGNED_AXES[a]
    on = sign * tau[axis]
    if on < 1e-6:
        return 0.0
    off = max(abs(tau[i]) for i in range(3) if i != axis)
    return on if off <= limit * on else 0.0


def arrangement(positions_m: Sequence[float], directions: Sequence[float],
                max_cross_coupling: float = MAX_CROSS_COUPLING) -> Arrangement:
    """Validate six thrusters (18 position and 18 direction components) and assign thrusters to the signed axes.

    Each signed axis gets the thruster whose torque r × d lies along it alone (off-axis components at most
    ``max_cross_coupling`` of the on-axis one), the largest if several; failing one, the couple (two thrusters
    fired together) whose summed torque does. Raises :class:`ArrangementError` naming the axis that neither
    gives, or the thruster that serves no axis.
    """
    if len(positions_m) != 18 or len(directions) != 18:
        raise ArrangementError(f'six thrusters need 18 position and 18 direction components, got '
                               f'{len(positions_m)} and {len(directions)}')
    if not all(math.isfinite(float(v)) for v in (*positions_m, *directions)):
        raise ArrangementError('thruster positions and directions must be finite')
    torques: list[tuple[float, float, float]] = []
    forces: list[tuple[float, float, float]] = []
    for j in range(6):
        r = tuple(float(v) for v in positions_m[3 * j:3 * j + 3])
        d = tuple(float(v) for v in directions[3 * j:3 * j + 3])
        n = math.sqrt(sum(c * c for c in d))
        if n < 1e-9:
            raise ArrangementError(f'thruster T{j + 1}: direction is the zero vector')
        d = (d[0] / n, d[1] / n, d[2] / n)
        tau = _cross(r, d)
        if max(abs(c) for c in tau) < 1e-6:
            raise ArrangementError(f'thruster T{j + 1}: its line of action passes through the centre of mass '
                                   '(no torque about any axis)')
        torques.append(tau)
        forces.append(d)
    groups: list[tuple[int, ...]] = []
    arms: list[float] = []
    missing: list[str] = []
    for a in range(6):
        best = max(((_about(torques[j], a, max_cross_coupling), (j,)) for j in range(6)), key=lambda c: c[0])
        if best[0] == 0.0:
            pairs = ((_about(tuple(p + q for p, q in zip(torques[i], torques[j], strict=True)), a, max_cross_coupling),
                      (i, j)) for i, j in combinations(range(6), 2))
            best = max(pairs, key=lambda c: c[0])
        if best[0] == 0.0:
            missing.append(AXIS_NAMES[a])
        groups.append(best[1])
        arms.append(best[0])
    if missing:
        near = '; '.join(f'T{j + 1} torque {[round(c, 4) for c in torques[j]]} N·m/N' for j in range(6))
        raise ArrangementError(f'no thruster, nor couple of two, gives a torque about {", ".join(missing)} alone '
                               f'(off-axis at most {max_cross_coupling:.0%}; {near})')
    idle = [f'T{j + 1}' for j in range(6) if not any(j in g for g in groups)]
    if idle:
        raise ArrangementError(f'{", ".join(idle)} serve(s) no axis, alone or in a couple (torque about one axis '
                               f'within {max_cross_coupling:.0%})')
    return Arrangement(tuple(torques), tuple(forces), tuple(groups), tuple(arms))


def arrangement_from_section(c: dict) -> Arrangement:
    """The arrangement of a scenario ``cold_gas`` section (SI): its ``thruster_layout``, or with ``custom`` its
    positions and directions; an :class:`ArrangementError` names the keys."""
    layout = c['thruster_layout']
    if layout == 'custom':
        positions, directions = c['thruster_positions'], c['thruster_directions']
    else:
        positions, directions = LAYOUTS[layout]
        if (tuple(c['thruster_positions']) != LAYOUTS[DEFAULT_LAYOUT][0]
                or tuple(c['thruster_directions']) != LAYOUTS[DEFAULT_LAYOUT][1]):
            raise ArrangementError(f'cold_gas.thruster_positions_m / thruster_directions are read only with '
                                   f'thruster_layout: custom (the layout is {layout!r})')
    try:
        return arrangement(positions, directions, c['max_cross_coupling'])
    except ArrangementError as exc:
        where = 'thruster_positions_m / thruster_directions' if layout == 'custom' else f'thruster_layout {layout!r}'
        raise ArrangementError(f'cold_gas.{where}: {exc}') from None
