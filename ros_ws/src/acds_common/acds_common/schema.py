"""Scenario keys as declared: a :class:`Field` per key, and the unit tables keys accept (spec header "Units").

A package declares the scenario sections its nodes read as ``{section: {key: Field}}``
(:class:`acds_common.declarations.Package`); :mod:`acds_common.scenario` validates a scenario
against every declared section and converts each key to SI, and
:mod:`acds_common.parameters` turns each key into the ROS parameter
``<section>_<key>_<si unit>`` (:meth:`Field.param_name`) of every node that reads the section.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

from acds_common import units as u

#: The default of a key the scenario must give (no default).
REQUIRED = object()
#: One degree in radians.
DEG = math.pi / 180.0


@dataclass(frozen=True)
class Field:
    """One scenario key: type, SI unit suffix, accepted units → SI factor, default, range, meaning."""

    kind: str  # 'float' | 'int' | 'bool' | 'str' | 'floats' | 'strs'
    doc: str
    default: Any = REQUIRED
    si: str = ''
    units: dict[str, float] = field(default_factory=dict)
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    length: int | None = None
    pattern: re.Pattern[str] | None = None  # 'str': the whole value must match
    unique: bool = False  # 'strs': no entry twice
    quaternion: bool = False  # 'floats' (x, y, z, w): must be normalisable
    path: bool = False  # 'str': a file name, resolved relative to the scenario file that gives it ('' = none)

    def param_name(self, section: str, name: str) -> str:
        """The ROS parameter name this key becomes."""
        base = f'{section}_{name}' if section else name
        return f'{base}_{self.si}' if self.si else base


def quantity(doc: str, default: Any, si: str, units: dict[str, float], **kw: Any) -> Field:
    """A physical quantity: given in any of ``units`` (the key's suffix), held in ``si``; a list default (or
    ``length``) makes it a vector."""
    kind = 'floats' if isinstance(default, list) or kw.get('length') else 'float'
    return Field(kind, doc, default, si, units, **kw)


ANGLE = {'deg': DEG, 'rad': 1.0}
RATE = {'deg_s': DEG, 'rad_s': 1.0, 'rpm': 2 * math.pi / 60}
LENGTH = {'nmi': u.NMI_M, 'km': 1e3, 'm': 1.0}
RADIUS = {**LENGTH, 'earth_radii': u.EARTH_RADIUS_M}
INERTIA = {'slug_ft2': u.SLUG_FT2_KG_M2, 'kg_m2': 1.0}
MOMENTUM = {'ft_lb_s': u.FT_LB_S_NMS, 'nms': 1.0}
FIELD = {'gauss': u.GAUSS_T, 't': 1.0}
COUPLING = {'g_per_am2': u.GAUSS_T, 't_per_am2': 1.0}
TIME = {'s': 1.0, 'min': 60.0}
MOMENT_OF_INERTIA = {**INERTIA, 'g_mm2': u.G_MM2_KG_M2}
TORQUE = {'ft_lb': u.FT_LB_NM, 'nm': 1.0}
#: The seed-000 dump gain k: amp-turn-m² per (ft-lb-sec · Wb/m²), amp-turn-ft² per (ft-lb-sec · Wb/m²) (the
#: reading of the memo's k that fits its stated range, acds_controller.cmg_dump), or SI A·m²/(N·m·s·T) = 1/(s·T²).
DUMP_GAIN = {'am2_per_ftlbs_t': u.dump_gain_seed_to_si(1.0), 'aft2_per_ftlbs_t': u.dump_gain_seed_to_si(u.FOOT_M ** 2),
             'per_s_t2': 1.0}
