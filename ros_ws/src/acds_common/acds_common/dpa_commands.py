"""The DPA's ground-command interface: selectable laws and run-time gains with their ranges (spec §7, §8).

The controller applies ``law <slot> <name>`` and ``gain <name> <value>`` commands; the mode
manager validates them before forwarding (a command the controller would refuse is refused
on the ground link, with the reason). Both read this one table. Ranges bracket the study's
values (seed 002 §4.2.3, Table 4-2); the CubeSat laws' gains (seed 003): k_ω up to
1e3 kg·m²/s (J_min ≈ 2.5e5 kg·m² in a 90-min orbit; OreSat's is 2.054e-5), k_h up to 1 s⁻¹.
"""

from __future__ import annotations

import math

#: Selectable magnetic laws per slot: acquisition (Mode 1A) and unloading (Mode 1B, cruise).
LAW_CHOICES: dict[str, tuple[str, ...]] = {
    'acquisition': ('bxh', 'bdot', 'b_cross_omega'),
    'unloading': ('bxh', 'lead', 'none', 'b_cross_h'),
}
#: Scalar run-time gains: name → (low, high, unit).
SCALAR_GAINS: dict[str, tuple[float, float, str]] = {
    'acquisition_gain': (0.0, 5.0, '(s·G²)⁻¹'),
    'bdot_gain': (0.0, 100.0, 'ft-lb-s/G²'),
    'unloading_gain_mode_1b': (0.0, 1.0, '(s·G²)⁻¹'),
    'unloading_gain_scan': (0.0, 1.0, '(s·G²)⁻¹'),
    'unloading_gain_point': (0.0, 1.0, '(s·G²)⁻¹'),
    'max_moment': (0.0, 5000.0, 'A·m²'),
    'scan_rate_rpm': (-1.0, 1.0, 'rpm'),
    'lead_time': (0.0, 1e5, 's'),
    'detumble_gain': (0.0, 1e3, 'kg·m²/s'),
    'dump_gain': (0.0, 1.0, '1/s'),
}
#: Wheel-law gain sets and their per-axis parameters (Table 4-2): name → (low, high, unit).
WHEEL_SETS = ('acquisition', 'normal')
WHEEL_PARAMS: dict[str, tuple[float, float, str]] = {
    'kp': (0.0, 1e8, 'V/rad'),
    'kr': (0.0, 1e5, 's'),
    'theta_limit': (1e-9, math.pi, 'rad'),
}
AXES = ('x', 'y', 'z')
#: Every gain a ground command may set: name → (low, high, unit); wheel gains as wheel_<set>_<param>_<axis>.
GAIN_TABLE: dict[str, tuple[float, float, str]] = {
    **SCALAR_GAINS,
    **{f'wheel_{s}_{p}_{a}': bounds for s in WHEEL_SETS for p, bounds in WHEEL_PARAMS.items() for a in AXES},
}
#: Gain name → (low, high).
GAIN_LIMITS: dict[str, tuple[float, float]] = {name: (lo, hi) for name, (lo, hi, _) in GAIN_TABLE.items()}
