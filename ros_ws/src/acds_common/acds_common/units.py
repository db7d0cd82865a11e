"""Unit conversions: the one place seed units meet SI (spec header, "Units").

Everything inside the emulator is SI (m, s, kg, N·m, T, A·m², rad). Seed units
(gauss, ft-lb, ft-lb-sec, slug-ft², dyne-cm, nmi, degrees) appear only at the
edges: scenario files, printed reports, plots.
"""

from __future__ import annotations

import math

#: 1 gauss in tesla.
GAUSS_T = 1e-4
#: 1 nanotesla in tesla (IGRF field values, ppigrf's unit).
NANOTESLA_T = 1e-9
#: 1 kilometre in m (ppigrf takes radii in km).
KM_M = 1e3
#: 1 ft-lb in N·m (also 1 ft-lb-sec in N·m·s, 1 slug-ft² in kg·m²).
FT_LB_NM = 1.3558179
#: 1 ft-lb-sec in N·m·s.
FT_LB_S_NMS = FT_LB_NM
#: 1 slug-ft² in kg·m².
SLUG_FT2_KG_M2 = FT_LB_NM
#: 1 dyne-cm in N·m.
DYNE_CM_NM = 1e-7
#: 1 nautical mile in m.
NMI_M = 1852.0
#: 1 g·mm² in kg·m² (seed 003 quotes J_min from the CAD model in g·mm²).
G_MM2_KG_M2 = 1e-9
#: 1 pound-mass in kg (also: a weight in lbs at 1 g, as the seeds quote hardware weights).
LB_KG = 0.45359237
#: 1 inch in m.
INCH_M = 0.0254
#: 1 foot in m.
FOOT_M = 0.3048
#: 1 pound-force in N (seed 002 §5: thrust in lb, impulse in "lb/sec", i.e. lbf·s).
LBF_N = 4.4482216152605
#: 1 psi in Pa (cold-gas pressures, seed 002 §5).
PSI_PA = 6894.757293168361
#: Standard gravity g0, m/s² (specific impulse in s: v_e = Isp·g0).
STANDARD_GRAVITY_M_S2 = 9.80665
#: Mean equatorial Earth radius, m.
EARTH_RADIUS_M = 6378137.0
#: Earth gravitational parameter μ, m³/s².
EARTH_MU_M3_S2 = 3.986004418e14
#: Earth sidereal rotation rate, rad/s.
EARTH_RATE_RAD_S = 7.2921150e-5
#: Vacuum permeability μ0, T·m/A.
MU0 = 4e-7 * math.pi


def deg(x_rad: float) -> float:
    """Radians to degrees."""
    return math.degrees(x_rad)


def rad(x_deg: float) -> float:
    """Degrees to radians."""
    return math.radians(x_deg)


def gauss_to_tesla(b_g):
    """Gauss to tesla (works on floats and numpy arrays)."""
    return b_g * GAUSS_T


def tesla_to_gauss(b_t):
    """Tesla to gauss."""
    return b_t / GAUSS_T


def ftlbs_to_nms(h):
    """ft-lb-sec to N·m·s."""
    return h * FT_LB_S_NMS


def nms_to_ftlbs(h):
    """N·m·s to ft-lb-sec."""
    return h / FT_LB_S_NMS


def ftlb_to_nm(t):
    """ft-lb to N·m."""
    return t * FT_LB_NM


def nm_to_dyne_cm(t):
    """N·m to dyne-cm."""
    return t / DYNE_CM_NM


def slugft2_to_kgm2(i):
    """slug-ft² to kg·m²."""
    return i * SLUG_FT2_KG_M2


def rpm_to_rad_s(w_rpm):
    """Revolutions per minute to rad/s."""
    return w_rpm * 2.0 * math.pi / 60.0


def rad_s_to_rpm(w):
    """rad/s to revolutions per minute."""
    return w * 60.0 / (2.0 * math.pi)


def dump_gain_seed_to_si(k):
    """Seed 000's dump gain k, amp-turn-m² per (ft-lb-sec · Wb/m²), to SI A·m²/(N·m·s·T) = 1/(s·T²)."""
    return k / FT_LB_S_NMS


def dump_gain_si_to_seed(k):
    """SI dump gain, 1/(s·T²), to seed 000's amp-turn-m² per (ft-lb-sec · Wb/m²)."""
    return k * FT_LB_S_NMS


#: Study gain unit (s·G²)⁻¹ with B in G and H in ft-lb-s gives M in ft-lb/G;
#: 1 ft-lb/G = 13558.2 A·m² (spec §7).
FTLB_PER_GAUSS_AM2 = FT_LB_NM / GAUSS_T


def ohm_in_to_ohm_m(rho):
    """Resistivity ohm-inch (seed 000 Appendix D "ohms per in.") to ohm-metre."""
    return rho * INCH_M


def lb_in3_to_kg_m3(sigma):
    """Specific weight lbs per in.³ (seed 000 Appendix D) to density kg/m³."""
    return sigma * LB_KG / INCH_M ** 3
