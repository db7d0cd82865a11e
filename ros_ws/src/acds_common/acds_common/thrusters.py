"""The cold-gas thruster arrangement: which thruster torques which signed body axis, with what arm (seed 002 §3.2, §5).

Shared by the cold-gas reaction control node (the physics: the torque and force each firing gives) and the
controller (its gas law knows its actuators as a flight program does: the torque per signed axis), as
:mod:`acds_common.coupling` is shared by the magnetometer and the controller.

**Why one thruster per signed axis, not couples.** The study's system has *six* thrusters, at most two
valves open at once (Table 5-2; §13.2.2: thruster monitoring goes "from 12 to 6"). A pure couple needs two
thrusts f_j = −f_i on different lines. Six thrusters giving six pure couples (±x, ±y, ±z), one pair each,
would need every thruster in two pairs: the pairing graph is 2-regular on six vertices, i.e. cycles. An odd
cycle forces f = −f; an even cycle puts every thrust on one line ±d, and no thrust along d gives a torque
about d. So six thrusters cannot give six pure couples (the 12 of the hydrazine RCS, Table 6-1's "6 duals",
could). The arrangement taken here fires **one thruster per signed axis**: each gives a torque about one body
axis only (its line of action passes through the other two axes' lines through the centre of mass) and a net
force equal to its thrust, stated in :attr:`Arrangement.force_per_thrust`. Two valves open = two axes at once.
That force is not fed to the orbit (the orbit is Keplerian, spec §3); at 4.6 lb of GN₂ its whole Δv is
≈ 1334 N·s / 3150 kg ≈ 0.4 m/s, reported by the node, not flown.

Default arrangement (HEAO-B, metres from the centre of mass; the seed gives no layout, so this is the
engineering choice an ACS engineer would make with the HEAO envelope, ≈ 2.7 m across): the pitch and yaw
thrusters at the aft bulkhead 2.4 m behind the centre of mass (arm 2.4 m), the roll thrusters on outriggers
in the centre-of-mass station at 1.2 m radius (arm 1.2 m: a roll thruster off that station would couple into
yaw by the station offset over the radius).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

#: Signed body axes in thruster order: +x, −x, +y, −y, +z, −z.
SIGNED_AXES = ((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0))
AXIS_NAMES = ('+x', '-x', '+y', '-y', '+z', '-z')
#: Default positions (m, body axes, from the centre of mass), one (x, y, z) per thruster T1…T6.
HEAO_B_POSITIONS_M = (0.0, 0.0, 1.2, 0.0, 0.0, -1.2,
                      -2.4, 0.0, -1.2, -2.4, 0.0, 1.2,
                      -2.4, 1.2, 0.0, -2.4, -1.2, 0.0)
#: Default thrust directions (unit, body axes): the force on the spacecraft, opposite to the exhaust.
HEAO_B_DIRECTIONS = (0.0, -1.0, 0.0, 0.0, -1.0, 0.0,
                     0.0, 0.0, 1.0, 0.0, 0.0, -1.0,
                     0.0, -1.0, 0.0, 0.0, 1.0, 0.0)
#: Largest off-axis torque of a thruster, as a fraction of its on-axis torque, accepted by default.
MAX_CROSS_COUPLING = 0.05


class ArrangementError(ValueError):
    """Thruster positions/directions that do not give a torque about each signed axis (names what is missing)."""


def _cross(r: Sequence[float], f: Sequence[float]) -> tuple[float, float, float]:
    return (r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0])


@dataclass(frozen=True)
class Arrangement:
    """Six thrusters: per thruster the torque and force per newton of thrust, and the thruster of each signed axis.

    ``torque_per_thrust[j]``: r_j × d_j (m; N·m per N). ``force_per_thrust[j]``: d_j (unit).
    ``thruster_of_axis[a]``: index of the thruster serving signed axis a (order :data:`SIGNED_AXES`).
    ``arm_m[a]``: its moment arm |τ_a · e_axis| (m).
    """

    torque_per_thrust: tuple[tuple[float, float, float], ...]
    force_per_thrust: tuple[tuple[float, float, float], ...]
    thruster_of_axis: tuple[int, ...]
    arm_m: tuple[float, ...]

    def axis_of(self, thruster: int) -> int:
        """The signed-axis index a thruster serves."""
        return self.thruster_of_axis.index(thruster)


def arrangement(positions_m: Sequence[float], directions: Sequence[float],
                max_cross_coupling: float = MAX_CROSS_COUPLING) -> Arrangement:
    """Validate six thrusters (18 position and 18 direction components) and assign each to its signed axis.

    Each thruster's torque r × d must lie along one body axis, its off-axis components at most
    ``max_cross_coupling`` of the on-axis one, and the six must serve the six signed axes once each.
    Raises :class:`ArrangementError` naming the thruster or the axis that has no torque.
    """
    if len(positions_m) != 18 or len(directions) != 18:
        raise ArrangementError(f'six thrusters need 18 position and 18 direction components, got '
                               f'{len(positions_m)} and {len(directions)}')
    if not all(math.isfinite(float(v)) for v in (*positions_m, *directions)):
        raise ArrangementError('thruster positions and directions must be finite')
    torques: list[tuple[float, float, float]] = []
    forces: list[tuple[float, float, float]] = []
    serves: dict[int, list[int]] = {}
    for j in range(6):
        r = tuple(float(v) for v in positions_m[3 * j:3 * j + 3])
        d = tuple(float(v) for v in directions[3 * j:3 * j + 3])
        n = math.sqrt(sum(c * c for c in d))
        if n < 1e-9:
            raise ArrangementError(f'thruster T{j + 1}: direction is the zero vector')
        d = (d[0] / n, d[1] / n, d[2] / n)
        tau = _cross(r, d)
        axis = max(range(3), key=lambda i: abs(tau[i]))
        on = abs(tau[axis])
        if on < 1e-6:
            raise ArrangementError(f'thruster T{j + 1}: its line of action passes through the centre of mass '
                                   '(no torque about any axis)')
        off = max(abs(tau[i]) for i in range(3) if i != axis)
        if off > max_cross_coupling * on:
            raise ArrangementError(f'thruster T{j + 1}: torque {[round(c, 4) for c in tau]} N·m/N is not about one '
                                   f'axis (off-axis {off / on:.1%} of on-axis, limit {max_cross_coupling:.0%})')
        signed = SIGNED_AXES.index((axis, math.copysign(1.0, tau[axis])))
        serves.setdefault(signed, []).append(j)
        torques.append(tau)
        forces.append(d)
    missing = [AXIS_NAMES[a] for a in range(6) if a not in serves]
    if missing:
        twice = '; '.join(f'{" and ".join(f"T{j + 1}" for j in js)} torque {AXIS_NAMES[a]}'
                          for a, js in sorted(serves.items()) if len(js) > 1)
        raise ArrangementError(f'no thruster gives a torque about {", ".join(missing)} ({twice})')
    serves_one = {a: js[0] for a, js in serves.items()}
    return Arrangement(tuple(torques), tuple(forces), tuple(serves_one[a] for a in range(6)),
                       tuple(abs(torques[serves_one[a]][SIGNED_AXES[a][0]]) for a in range(6)))


def arrangement_from_section(c: dict) -> Arrangement:
    """The arrangement of a scenario ``cold_gas`` section (SI); an :class:`ArrangementError` names the keys."""
    try:
        return arrangement(c['thruster_positions'], c['thruster_directions'], c['max_cross_coupling'])
    except ArrangementError as exc:
        raise ArrangementError(f'cold_gas.thruster_positions_m / thruster_directions: {exc}') from None

