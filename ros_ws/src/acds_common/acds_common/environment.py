"""Environment: Keplerian orbit, tilted-dipole (or IGRF) Earth field, Sun and the sun-pointed frame (spec §3).

Shared: the dynamics propagates the spacecraft in it, and on-board software that predicts the field
along the coming orbit (the AAP minimum-energy dump law, seed 000 eq. 3) uses the same models.

Frames. ECI: inertial, x to the vernal equinox, z to the celestial north pole. ECEF: rotates about
ECI z at ``units.EARTH_RATE_RAD_S``; its x axis (Greenwich meridian) is at the Earth rotation
angle ``greenwich_angle0_rad + EARTH_RATE_RAD_S * t`` from ECI x.

Seed: 002_heao_acds_study.txt §4.3 (tilted dipole 11° / 20° from Greenwich, orbit conditions of
§4.3.1 and §4.3.2, sun-pointed frame of Figure 4-14).
"""

from __future__ import annotations

import datetime
import math
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from acds_common import kernels, units, validation
from acds_common.vec3 import Vec3  # the fast paths take and return float triples (RK4 stage times)

#: Mean obliquity of the ecliptic, rad (spec §3).
OBLIQUITY_RAD = math.radians(23.44)
#: Earth dipole moment, A·m²: gives 0.253 G at the magnetic equator and 0.506 G at the magnetic pole
#: at 225 nmi altitude (spec §3 "about 0.25 G ... 0.5 G").
DEFAULT_DIPOLE_MOMENT_AM2 = 7.94e22
#: Dipole tilt from the spin axis, rad (seed 002 §4.3: "inclined 11°").
DEFAULT_DIPOLE_TILT_RAD = math.radians(11.0)
#: East longitude of the boreal (northern-hemisphere) geomagnetic pole, rad. The seed says only
#: "offset 20° from the Greenwich meridian" (§4.3); we take 20° WEST, the side of the real
#: geomagnetic north pole (≈70° W in 1970). A scenario may override it.
DEFAULT_DIPOLE_LONGITUDE_RAD = math.radians(-20.0)

_KEPLER_TOL_RAD = 1e-14
_KEPLER_MAX_ITER = 60


class EnvironmentModelError(ValueError):
    """Invalid orbit, field or sun parameters (the message names the parameter)."""


def finite_float(name: str, value: float) -> float:
    """Return ``value`` as a finite float or raise EnvironmentModelError naming ``name``."""
    value = float(value)
    if not math.isfinite(value):
        raise EnvironmentModelError(f"{name} must be a finite number, got {value!r}")
    return value


def finite_vector3(name: str, value: object) -> np.ndarray:
    """Return ``value`` as a finite float 3-vector or raise EnvironmentModelError naming ``name``."""
    return validation.finite_vector3(name, value, EnvironmentModelError)


def rot_z(angle_rad: float) -> np.ndarray:
    """Active rotation matrix about z by ``angle_rad``."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rot_x(angle_rad: float) -> np.ndarray:
    """Active rotation matrix about x by ``angle_rad``."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


# --------------------------------------------------------------------------------------------- orbit


@dataclass(frozen=True)
class OrbitConfig:
    """Orbit parameters, SI and radians (spec §3 "Orbits").

    ``kind='circular'``: ``altitude_m`` above ``units.EARTH_RADIUS_M`` and ``arg_latitude0_rad`` (argument
    of latitude at t = 0). ``kind='elliptical'``: ``perigee_altitude_m``, ``apogee_radius_m``
    (geocentric), ``arg_perigee_rad``, ``mean_anomaly0_rad``. Both: ``inclination_rad`` and
    ``raan_rad`` (right ascension of the ascending node).
    """

    kind: str = "circular"
    inclination_rad: float = math.radians(22.5)
    raan_rad: float = 0.0
    altitude_m: float = 225.0 * units.NMI_M
    arg_latitude0_rad: float = 0.0
    perigee_altitude_m: float = 120.0 * units.NMI_M
    apogee_radius_m: float = 5.2 * units.EARTH_RADIUS_M
    arg_perigee_rad: float = 0.0
    mean_anomaly0_rad: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("circular", "elliptical"):
            raise EnvironmentModelError(f"OrbitConfig.kind must be 'circular' or 'elliptical', got {self.kind!r}")
        for name in ("inclination_rad", "raan_rad", "altitude_m", "arg_latitude0_rad", "perigee_altitude_m",
                     "apogee_radius_m", "arg_perigee_rad", "mean_anomaly0_rad"):
            finite_float(f"OrbitConfig.{name}", getattr(self, name))
        if not 0.0 <= self.inclination_rad <= math.pi:
            raise EnvironmentModelError(f"OrbitConfig.inclination_rad must be in [0, pi], got {self.inclination_rad}")
        if self.kind == "circular" and self.altitude_m <= 0.0:
            raise EnvironmentModelError(f"OrbitConfig.altitude_m must be > 0 m, got {self.altitude_m}")
        if self.kind == "elliptical":
            if self.perigee_altitude_m <= 0.0:
                raise EnvironmentModelError(
                    f"OrbitConfig.perigee_altitude_m must be > 0 m, got {self.perigee_altitude_m}")
            if self.apogee_radius_m < units.EARTH_RADIUS_M + self.perigee_altitude_m:
                raise EnvironmentModelError(
                    "OrbitConfig.apogee_radius_m is geocentric and must be >= the perigee radius "
                    f"{units.EARTH_RADIUS_M + self.perigee_altitude_m} m, got {self.apogee_radius_m}")


def solve_kepler(mean_anomaly_rad: float, eccentricity: float) -> float:
    """Eccentric anomaly E solving Kepler's equation E − e sin E = M (0 ≤ e < 1).

    Newton iteration from E0 = M (e < 0.8) or π (e ≥ 0.8), each step bracketed in [−π, π] around
    the wrapped M and falling back to bisection if a Newton step leaves the bracket, so it converges
    for every M and every e < 1.
    """
    if not 0.0 <= eccentricity < 1.0:
        raise EnvironmentModelError(f"eccentricity must be in [0, 1), got {eccentricity}")
    m = math.remainder(mean_anomaly_rad, 2.0 * math.pi)  # in [-pi, pi]
    # f(E) = E - e sin E - m is increasing; root lies in [m - e, m + e] ∩ [-pi, pi].
    lo, hi = max(-math.pi, m - eccentricity), min(math.pi, m + eccentricity)
    e_anom = m if eccentricity < 0.8 else math.copysign(math.pi, m)
    e_anom = min(max(e_anom, lo), hi)
    for _ in range(_KEPLER_MAX_ITER):
        f = e_anom - eccentricity * math.sin(e_anom) - m
        if f > 0.0:
            hi = e_anom
        else:
            lo = e_anom
        step = f / (1.0 - eccentricity * math.cos(e_anom))
        new = e_anom - step
        if not lo <= new <= hi:
            new = 0.5 * (lo + hi)
        if abs(new - e_anom) < _KEPLER_TOL_RAD:
            e_anom = new
            break
        e_anom = new
    return e_anom + (mean_anomaly_rad - m)


@kernels.helper
def circular_in_plane(a_m: float, n_rad_s: float, t_s: float) -> tuple[float, float, float, float]:
    """(x, y, ẋ, ẏ) in the node-line frame of a circular orbit of radius ``a_m`` and mean motion ``n_rad_s`` at
    ``t_s`` (spec §3 "Orbits"): a plain-float helper, the same for :class:`Orbit` and compiled kernels."""
    u = n_rad_s * t_s
    cu, su = math.cos(u), math.sin(u)
    return a_m * cu, a_m * su, -a_m * n_rad_s * su, a_m * n_rad_s * cu


@kernels.helper
def in_plane_to_eci(x: float, y: float, p_axis: Vec3, q_axis: Vec3) -> Vec3:
    """The in-plane vector x·P + y·Q in ECI (P, Q: the orbit plane's axes in ECI), on floats."""
    (p0, p1, p2), (q0, q1, q2) = p_axis, q_axis
    return x * p0 + y * q0, x * p1 + y * q1, x * p2 + y * q2


class Orbit:
    """Two-body Keplerian orbit about a point-mass Earth (spec §3 "Orbits")."""

    def __init__(self, cfg: OrbitConfig) -> None:
        self.cfg = cfg
        if cfg.kind == "circular":
            r_p = r_a = units.EARTH_RADIUS_M + cfg.altitude_m
            self._arg0 = cfg.arg_latitude0_rad
        else:
            r_p = units.EARTH_RADIUS_M + cfg.perigee_altitude_m
            r_a = cfg.apogee_radius_m
            self._arg0 = cfg.arg_perigee_rad
        self.perigee_radius_m = r_p
        self.apogee_radius_m = r_a
        self.semi_major_axis_m = 0.5 * (r_p + r_a)
        self.eccentricity = (r_a - r_p) / (r_a + r_p)
        self.mean_motion_rad_s = math.sqrt(units.EARTH_MU_M3_S2 / self.semi_major_axis_m ** 3)
        #: Orbit period, s.
        self.period_s = 2.0 * math.pi / self.mean_motion_rad_s
        # Perifocal (or node-line) frame to ECI: R3(Ω) R1(i) R3(ω or u0); its first two columns P, Q
        # (the in-plane axes in ECI) as floats, so that r = x_p·P + y_p·Q.
        pqw_to_eci = rot_z(cfg.raan_rad) @ rot_x(cfg.inclination_rad) @ rot_z(self._arg0)
        self._p_axis: Vec3 = tuple(float(c) for c in pqw_to_eci[:, 0])  # type: ignore[assignment]
        self._q_axis: Vec3 = tuple(float(c) for c in pqw_to_eci[:, 1])  # type: ignore[assignment]
        self._circular = cfg.kind == "circular"
        self._semi_minor_axis_m = self.semi_major_axis_m * math.sqrt(1.0 - self.eccentricity ** 2)

    def _in_plane(self, t_s: float) -> tuple[float, float, float, float]:
        """(x_p, y_p, ẋ_p, ẏ_p): position (m) and velocity (m/s) in the orbit plane at ``t_s``."""
        a, n = self.semi_major_axis_m, self.mean_motion_rad_s
        if self._circular:
            return circular_in_plane(a, n, t_s)
        e, b = self.eccentricity, self._semi_minor_axis_m
        e_anom = solve_kepler(self.cfg.mean_anomaly0_rad + n * t_s, e)
        ce, se = math.cos(e_anom), math.sin(e_anom)
        edot = n / (1.0 - e * ce)
        return a * (ce - e), b * se, -a * se * edot, b * ce * edot

    def state_xyz(self, t_s: float) -> tuple[Vec3, Vec3]:
        """Fast path of :meth:`position_velocity_eci`: (position m, velocity m/s) as float triples, no checks."""
        x, y, vx, vy = self._in_plane(t_s)
        return in_plane_to_eci(x, y, self._p_axis, self._q_axis), in_plane_to_eci(vx, vy, self._p_axis, self._q_axis)

    def position_xyz(self, t_s: float) -> Vec3:
        """Fast path: ECI position (m) at ``t_s`` as a float triple, no checks."""
        x, y, _vx, _vy = self._in_plane(t_s)
        return in_plane_to_eci(x, y, self._p_axis, self._q_axis)

    def node_time_s(self) -> float:
        """A time (s) at which the orbit passes its ascending node: the argument of latitude (for an
        elliptical orbit its mean value ω + M) is zero there, −u0/n; orbits counted from the node start here."""
        u0 = self.cfg.arg_latitude0_rad if self.cfg.kind == "circular" else (
            self.cfg.arg_perigee_rad + self.cfg.mean_anomaly0_rad)
        return -u0 / self.mean_motion_rad_s

    def position_velocity_eci(self, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Position (m) and velocity (m/s) in ECI at time ``t_s`` (s from scenario start)."""
        r, v = self.state_xyz(finite_float("t_s", t_s))
        return np.array(r), np.array(v)


# ------------------------------------------------------------------------------------- magnetic field


@dataclass(frozen=True)
class EarthFieldConfig:
    """Tilted-dipole Earth field parameters (spec §3; seed 002 §4.3).

    ``dipole_moment_am2`` (A·m²), ``tilt_rad`` (dipole axis from the spin axis),
    ``dipole_longitude_rad`` (east longitude of the northern geomagnetic pole, where the field points
    down; default 20° W, see DEFAULT_DIPOLE_LONGITUDE_RAD), ``greenwich_angle0_rad`` (Earth rotation
    angle at t = 0: angle from the vernal equinox to Greenwich, e.g. 50° in the seed's scan case).
    """

    dipole_moment_am2: float = DEFAULT_DIPOLE_MOMENT_AM2
    tilt_rad: float = DEFAULT_DIPOLE_TILT_RAD
    dipole_longitude_rad: float = DEFAULT_DIPOLE_LONGITUDE_RAD
    greenwich_angle0_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("dipole_moment_am2", "tilt_rad", "dipole_longitude_rad", "greenwich_angle0_rad"):
            finite_float(f"EarthFieldConfig.{name}", getattr(self, name))
        if self.dipole_moment_am2 <= 0.0:
            raise EnvironmentModelError(
                f"EarthFieldConfig.dipole_moment_am2 must be > 0 A·m², got {self.dipole_moment_am2}")
        if not 0.0 <= self.tilt_rad <= math.pi / 2:
            raise EnvironmentModelError(f"EarthFieldConfig.tilt_rad must be in [0, pi/2], got {self.tilt_rad}")


@kernels.helper
def greenwich_angle_rad(greenwich_angle0_rad: float, t_s: float) -> float:
    """Earth rotation angle (vernal equinox to Greenwich), rad, at ``t_s`` from its value at t = 0."""
    return greenwich_angle0_rad + units.EARTH_RATE_RAD_S * t_s


@kernels.helper
def dipole_axis_xyz(pole_ecef: Vec3, greenwich_angle0_rad: float, t_s: float) -> Vec3:
    """The pole's ECEF unit vector rotated about ECI z by the Earth rotation angle at ``t_s`` (ECI), on floats."""
    g = greenwich_angle_rad(greenwich_angle0_rad, t_s)
    c, s = math.cos(g), math.sin(g)
    px, py, pz = pole_ecef
    return c * px - s * py, s * px + c * py, pz


@kernels.helper
def dipole_b_eci_xyz(pole_ecef: Vec3, k_tm3: float, greenwich_angle0_rad: float, r_eci_m: Sequence[float],
                     t_s: float) -> Vec3:
    """The tilted dipole's field (T, ECI) at ``r_eci_m`` (m, finite, off-centre) and ``t_s``, on floats: pole
    ``pole_ecef``, k = μ0/(4π)·|m| (T·m³). With m̂ = −p̂: B = k/|r|³·(3(m̂·r)/|r|²·r − m̂), the dipole formula of
    :class:`TiltedDipoleField` (spec §3), the same for the class and compiled kernels."""
    px, py, pz = dipole_axis_xyz(pole_ecef, greenwich_angle0_rad, t_s)
    rx, ry, rz = r_eci_m
    r2 = rx * rx + ry * ry + rz * rz
    k = k_tm3 / (r2 * math.sqrt(r2))
    f = -3.0 * (px * rx + py * ry + pz * rz) / r2
    return k * (f * rx + px), k * (f * ry + py), k * (f * rz + pz)


class TiltedDipoleField:
    """Centred tilted dipole rotating with the Earth (spec §3; seed 002 §4.3).

    B = μ0/(4π r³)·(3(m·r̂)r̂ − m), m = −|m|·p̂ where p̂ points to the northern geomagnetic pole, so the
    field points down (toward the Earth) in the northern hemisphere as for the real Earth.
    """

    def __init__(self, cfg: EarthFieldConfig) -> None:
        self.cfg = cfg
        st = math.sin(cfg.tilt_rad)
        lon = cfg.dipole_longitude_rad
        self._pole_ecef: Vec3 = (st * math.cos(lon), st * math.sin(lon), math.cos(cfg.tilt_rad))
        self._k = units.MU0 / (4.0 * math.pi) * cfg.dipole_moment_am2

    def greenwich_angle_rad(self, t_s: float) -> float:
        """Earth rotation angle (vernal equinox to Greenwich), rad, at ``t_s``."""
        return greenwich_angle_rad(self.cfg.greenwich_angle0_rad, t_s)

    def dipole_axis_eci(self, t_s: float) -> np.ndarray:
        """Unit vector to the northern geomagnetic pole in ECI at ``t_s`` (the moment is antiparallel)."""
        return np.array(dipole_axis_xyz(self._pole_ecef, self.cfg.greenwich_angle0_rad, t_s))

    def b_eci_xyz(self, r_eci_m: Sequence[float], t_s: float) -> Vec3:
        """Fast path of :meth:`b_eci` on float triples (no checks: the point must be finite and off-centre)."""
        return dipole_b_eci_xyz(self._pole_ecef, self._k, self.cfg.greenwich_angle0_rad, r_eci_m, t_s)

    def b_eci(self, r_eci_m: np.ndarray, t_s: float) -> np.ndarray:
        """Field (T) in ECI at position ``r_eci_m`` (m) and time ``t_s`` (s)."""
        r = np.asarray(r_eci_m, dtype=float)
        rn = math.sqrt(float(r @ r))
        if not rn > 0.0 or not math.isfinite(rn):
            raise EnvironmentModelError(f"field point must be finite and away from the Earth's centre, got {r}")
        return np.array(self.b_eci_xyz([float(c) for c in r], t_s))


#: A circular orbit and the tilted-dipole field as plain floats (:func:`circular_dipole_parameters`): orbit radius
#: (m), mean motion (rad/s), the plane's axes P and Q in ECI, the pole in ECEF, k = μ0/(4π)·|m| (T·m³), the Earth
#: rotation angle at t = 0 (rad).
CircularDipole = tuple[float, float, Vec3, Vec3, Vec3, float, float]


def circular_dipole_parameters(orbit: Orbit, field: object) -> CircularDipole | None:
    """The orbit and field as the floats :func:`circular_dipole_environment` takes, so that a compiled kernel
    evaluates them itself; None unless the orbit is circular and the field the tilted dipole."""
    if not (orbit._circular and isinstance(field, TiltedDipoleField)):
        return None
    return (orbit.semi_major_axis_m, orbit.mean_motion_rad_s, orbit._p_axis, orbit._q_axis, field._pole_ecef,
            field._k, field.cfg.greenwich_angle0_rad)


@kernels.helper
def circular_dipole_environment(params: CircularDipole, t_s: float, with_field: bool) -> tuple[Vec3, Vec3, Vec3]:
    """(r_eci m, v_eci m/s, B_eci T) at ``t_s`` of the circular orbit and tilted dipole ``params``, the same
    operations as :meth:`Orbit.state_xyz` and :meth:`TiltedDipoleField.b_eci_xyz` (B zero unless ``with_field``)."""
    a, n, p_axis, q_axis, pole, k, g0 = params
    x, y, vx, vy = circular_in_plane(a, n, t_s)
    r = in_plane_to_eci(x, y, p_axis, q_axis)
    b = dipole_b_eci_xyz(pole, k, g0, r, t_s) if with_field else (0.0, 0.0, 0.0)
    return r, in_plane_to_eci(vx, vy, p_axis, q_axis), b


class MagneticFieldModel(Protocol):
    """What the rigid body asks of an Earth field model: B in ECI (T) at a position (m) and time (s)."""

    def b_eci(self, r_eci_m: np.ndarray, t_s: float) -> np.ndarray:
        """Field (T) in ECI at position ``r_eci_m`` (m) and time ``t_s`` (s from scenario start)."""
        ...


def field_xyz(field: MagneticFieldModel) -> Callable[[Vec3, float], Vec3]:
    """The field model as a function of float triples, what the rigid body's RK4 stages call: its
    ``b_eci_xyz(r, t_s)`` fast path when it has one (the tilted dipole), else its ``b_eci`` wrapped
    (numpy in, floats out, e.g. the IGRF option), so any :class:`MagneticFieldModel` plugs in."""
    fast = getattr(field, "b_eci_xyz", None)
    if fast is not None:
        return fast  # type: ignore[no-any-return]

    def wrapped(r: Vec3, t_s: float) -> Vec3:
        b = field.b_eci(np.array(r), t_s)
        return float(b[0]), float(b[1]), float(b[2])
    return wrapped


def gravity_gradient_torque_nm(inertia_kg_m2: np.ndarray, r_body_m: np.ndarray) -> np.ndarray:
    """Gravity-gradient torque T_gg = 3 μ/r³ · r̂_b × (I r̂_b), N·m (spec §3); ``r_body_m`` is the geocentric
    position of the spacecraft in body axes (m), ``inertia_kg_m2`` its 3×3 tensor. The rigid body integrates
    this formula (in its small-vector kernel); an on-board computer uses it as a torque model."""
    r = finite_vector3("r_body_m", r_body_m)
    rn = math.sqrt(float(r @ r))
    if not rn > 0.0:
        raise EnvironmentModelError("gravity gradient needs a position away from the Earth's centre")
    r_hat = r / rn
    return 3.0 * units.EARTH_MU_M3_S2 / rn ** 3 * np.cross(r_hat, np.asarray(inertia_kg_m2, dtype=float) @ r_hat)


# ------------------------------------------------------------------------------ from scenario sections


def orbit_from_section(orbit: Mapping[str, Any]) -> Orbit:
    """The orbit of a scenario ``orbit`` section (SI values, ``acds_common.scenario.SCHEMA['orbit']``).

    The dynamics and the on-board computer (the controller's field prediction) build theirs here, so
    both fly the same orbit from the same keys.
    """
    return Orbit(OrbitConfig(
        kind=orbit['kind'], inclination_rad=orbit['inclination'], raan_rad=orbit['raan'],
        altitude_m=orbit['altitude'], arg_latitude0_rad=orbit['arg_latitude0'],
        perigee_altitude_m=orbit['perigee_altitude'], apogee_radius_m=orbit['apogee_radius'],
        arg_perigee_rad=orbit['arg_perigee'], mean_anomaly0_rad=orbit['mean_anomaly0']))


def field_from_section(earth: Mapping[str, Any]) -> MagneticFieldModel:
    """The Earth field of a scenario ``earth`` section (SI values), for the dynamics and on board: the study's
    tilted dipole (``model: dipole``, default) or IGRF-14 at the epoch date (``model: igrf``, spec §3)."""
    if earth['model'] == 'igrf':
        return IgrfField(IgrfConfig(epoch_year=earth['epoch'], greenwich_angle0_rad=earth['greenwich_angle0']))
    return TiltedDipoleField(EarthFieldConfig(
        dipole_moment_am2=earth['dipole_moment'], tilt_rad=earth['dipole_tilt'],
        dipole_longitude_rad=earth['dipole_longitude'], greenwich_angle0_rad=earth['greenwich_angle0']))


# ------------------------------------------------------------------------------------ IGRF (option)

#: Years covered by IGRF-14 as ppigrf ships it (``IGRF14.shc``): main-field models every 5 years from
#: 1900.0 to 2025.0, then the 2025–2030 secular variation.
IGRF_FIRST_YEAR = 1900.0
IGRF_LAST_YEAR = 2030.0
#: Edge of one cubic tile of the IGRF cache (ECEF), m.
IGRF_TILE_M = 1000e3
#: Lattice nodes per tile edge: degree-9 Lagrange interpolation along each axis.
IGRF_TILE_NODES = 10
#: The cache holds the field at whole days from the epoch and interpolates linearly in time.
IGRF_TIME_STEP_S = 86400.0
#: Tiles kept (least recently used dropped): 48 kB each.
IGRF_CACHE_TILES = 64


def decimal_year_datetime(year: float) -> datetime.datetime:
    """Decimal year (IGRF's date convention: 2025.5 is half-way through 2025) → naive UTC datetime."""
    year = finite_float("epoch_year", year)
    whole = math.floor(year)
    start = datetime.datetime(whole, 1, 1)
    return start + (datetime.datetime(whole + 1, 1, 1) - start) * (year - whole)


@dataclass(frozen=True)
class IgrfConfig:
    """IGRF option (spec §3): ``epoch_year`` the decimal-year date at t = 0; ``greenwich_angle0_rad`` the Earth
    rotation angle at t = 0, as for the tilted dipole (the scenario's ``earth.greenwich_angle0``: for the real
    geometry of that date, set it to the epoch's sidereal angle)."""

    epoch_year: float = 2025.0
    greenwich_angle0_rad: float = 0.0

    def __post_init__(self) -> None:
        finite_float("IgrfConfig.greenwich_angle0_rad", self.greenwich_angle0_rad)
        if not IGRF_FIRST_YEAR <= finite_float("IgrfConfig.epoch_year", self.epoch_year) <= IGRF_LAST_YEAR:
            raise EnvironmentModelError(f"IgrfConfig.epoch_year must be in [{IGRF_FIRST_YEAR:g}, "
                                        f"{IGRF_LAST_YEAR:g}] (IGRF-14), got {self.epoch_year}")


def igrf_ecef_t(r_ecef_m: np.ndarray, dates: list[datetime.datetime]) -> np.ndarray:
    """IGRF-14 field (T) in ECEF Cartesian axes at points ``r_ecef_m`` (N×3, m): one ppigrf call, shape (dates, N, 3).

    ppigrf's geocentric ``igrf_gc`` gives (B_r, B_θ, B_φ) in nT at radius (km), colatitude and east
    longitude (deg); they are turned into ECEF x, y, z here.
    """
    import ppigrf  # ppigrf (and pandas) load only when a scenario asks for IGRF

    p = np.asarray(r_ecef_m, dtype=float).reshape(-1, 3)
    rho = np.hypot(p[:, 0], p[:, 1])
    theta, phi = np.arctan2(rho, p[:, 2]), np.arctan2(p[:, 1], p[:, 0])
    b_r, b_t, b_p = (np.asarray(c, dtype=float).reshape(len(dates), -1) * units.NANOTESLA_T for c in ppigrf.igrf_gc(
        np.linalg.norm(p, axis=1) / units.KM_M, np.degrees(theta), np.degrees(phi), dates))
    st, ct, sp, cp = np.sin(theta), np.cos(theta), np.sin(phi), np.cos(phi)
    return np.stack([b_r * st * cp + b_t * ct * cp - b_p * sp,
                     b_r * st * sp + b_t * ct * sp + b_p * cp,
                     b_r * ct - b_t * st], axis=-1)


class IgrfField:
    """IGRF-14 main field to degree 13 (ppigrf), rotating with the Earth: a higher-order option (spec §3).

    Same interface as :class:`TiltedDipoleField` (:meth:`b_eci`). One ppigrf evaluation costs tens of ms
    (mostly its coefficient interpolation in pandas), ~10⁴ times a dipole, and the rigid body asks for the
    field at every RK4 stage. So the field is cached on a lattice fixed in the Earth: ECEF space is cut into
    cubes of :data:`IGRF_TILE_M`; the first point that falls in a cube (within one day from the epoch)
    costs one ppigrf call on the cube's 10×10×10 nodes at both ends of that day (≈ 30 ms), and every point
    in it is then interpolated: degree-9 Lagrange along each axis (error below 1e-4 nT from low orbit out,
    far under the coefficients' 0.01 nT), linear in time (exact: IGRF coefficients are linear in time over
    each 5-year interval and the field is linear in them). A LEO spacecraft crosses a cube in about two
    minutes (~250 HEAO control steps). The lattice is fixed, so ``b_eci(r, t)`` depends on (r, t) alone, never on what
    was asked before; the lattice is offset by half a node spacing, so no node lies on the polar axis
    (where B_φ's 1/sin θ is singular).
    """

    def __init__(self, cfg: IgrfConfig) -> None:
        self.cfg = cfg
        self.epoch = decimal_year_datetime(cfg.epoch_year)
        self._last = decimal_year_datetime(IGRF_LAST_YEAR)
        n = IGRF_TILE_NODES
        self._nodes = np.linspace(0.0, 1.0, n)
        self._barycentric = np.array([1.0 / np.prod([self._nodes[j] - self._nodes[m] for m in range(n) if m != j])
                                      for j in range(n)])
        self._offset_m = 0.5 * IGRF_TILE_M / (n - 1)
        self._lattice = np.stack(np.meshgrid(self._nodes, self._nodes, self._nodes, indexing="ij"),
                                 axis=-1).reshape(-1, 3) * IGRF_TILE_M
        self._tiles: OrderedDict[tuple[int, int, int, int], np.ndarray] = OrderedDict()
        #: ppigrf calls made so far (one per tile).
        self.evaluations = 0

    def greenwich_angle_rad(self, t_s: float) -> float:
        """Earth rotation angle (vernal equinox to Greenwich), rad, at ``t_s``."""
        return greenwich_angle_rad(self.cfg.greenwich_angle0_rad, t_s)

    def date(self, t_s: float) -> datetime.datetime:
        """UTC date at ``t_s`` (s from the epoch)."""
        return self.epoch + datetime.timedelta(seconds=t_s)

    def _tile(self, key: tuple[int, int, int, int]) -> np.ndarray:
        tile = self._tiles.get(key)
        if tile is not None:
            self._tiles.move_to_end(key)
            return tile
        dates = [self.date(key[3] * IGRF_TIME_STEP_S), self.date((key[3] + 1) * IGRF_TIME_STEP_S)]
        if dates[0] < decimal_year_datetime(IGRF_FIRST_YEAR) or dates[1] > self._last:
            raise EnvironmentModelError(f"IGRF-14 covers {IGRF_FIRST_YEAR:g}–{IGRF_LAST_YEAR:g}; the run reaches "
                                        f"{dates[1]:%Y-%m-%d} (epoch {self.epoch:%Y-%m-%d} + {key[3] + 1} days)")
        origin = np.array(key[:3], dtype=float) * IGRF_TILE_M + self._offset_m
        n = IGRF_TILE_NODES
        values = igrf_ecef_t(origin + self._lattice, dates)  # (2, n³, 3)
        tile = values.reshape(2, n, n, n, 3).transpose(1, 2, 3, 0, 4).reshape(n, -1)
        self.evaluations += 1
        self._tiles[key] = tile
        if len(self._tiles) > IGRF_CACHE_TILES:
            self._tiles.popitem(last=False)
        return tile

    def b_ecef(self, r_ecef_m: np.ndarray, t_s: float) -> np.ndarray:
        """Field (T) in ECEF at ``r_ecef_m`` (m, Earth-fixed) and ``t_s`` (s), from the cache."""
        scaled = (np.asarray(r_ecef_m, dtype=float) - self._offset_m) / IGRF_TILE_M
        cell = np.floor(scaled)
        day = math.floor(t_s / IGRF_TIME_STEP_S)
        tile = self._tile((int(cell[0]), int(cell[1]), int(cell[2]), day))
        # Lagrange weights per axis, barycentric form: w_j = (λ_j / (u − u_j)) / Σ_k λ_k / (u − u_k).
        d = (scaled - cell)[:, None] - self._nodes[None, :]
        exact = d == 0.0
        if exact.any():  # on a node plane: that node's weight is 1
            d[exact.any(axis=1)] = 1.0
            q = np.where(exact, 1.0, np.where(exact.any(axis=1, keepdims=True), 0.0, self._barycentric / d))
        else:
            q = self._barycentric / d
        w = q / q.sum(axis=1, keepdims=True)
        n = IGRF_TILE_NODES
        b = (w[2] @ (w[1] @ (w[0] @ tile).reshape(n, -1)).reshape(n, -1)).reshape(2, 3)
        frac = t_s / IGRF_TIME_STEP_S - day
        return b[0] + frac * (b[1] - b[0])

    def b_eci(self, r_eci_m: np.ndarray, t_s: float) -> np.ndarray:
        """Field (T) in ECI at position ``r_eci_m`` (m) and time ``t_s`` (s)."""
        r = np.asarray(r_eci_m, dtype=float)
        t_s = finite_float("t_s", t_s)
        rn = math.sqrt(float(r @ r))
        if not rn > 0.0 or not math.isfinite(rn):
            raise EnvironmentModelError(f"field point must be finite and away from the Earth's centre, got {r}")
        g = self.greenwich_angle_rad(t_s)
        c, s = math.cos(g), math.sin(g)
        b = self.b_ecef(np.array([c * r[0] + s * r[1], -s * r[0] + c * r[1], r[2]]), t_s)
        return np.array([c * b[0] - s * b[1], s * b[0] + c * b[1], b[2]])


# ------------------------------------------------------------------------------------------------ sun


def ecliptic_normal_eci(obliquity_rad: float = OBLIQUITY_RAD) -> np.ndarray:
    """Unit normal of the ecliptic (north ecliptic pole) in ECI: (0, −sin ε, cos ε)."""
    return np.array([0.0, -math.sin(obliquity_rad), math.cos(obliquity_rad)])


def ecliptic_to_radec(ecliptic_longitude_rad: float,
                      obliquity_rad: float = OBLIQUITY_RAD) -> tuple[float, float]:
    """(right ascension, declination), rad, of a point on the ecliptic at the given longitude."""
    lam = ecliptic_longitude_rad
    v = rot_x(obliquity_rad) @ np.array([math.cos(lam), math.sin(lam), 0.0])
    return math.atan2(v[1], v[0]), math.asin(max(-1.0, min(1.0, v[2])))


@dataclass(frozen=True)
class SunConfig:
    """Sun direction for a run (spec §3 "Sun").

    The direction is fixed for the run (runs are ≲ 1 day; the Sun moves ≈ 1°/day along the ecliptic,
    which is ignored). ``right_ascension_rad``/``declination_rad`` in ECI; ``eclipse`` enables a
    cylindrical Earth shadow (default off: sun always present).
    """

    right_ascension_rad: float = 0.0
    declination_rad: float = 0.0
    eclipse: bool = False

    def __post_init__(self) -> None:
        finite_float("SunConfig.right_ascension_rad", self.right_ascension_rad)
        finite_float("SunConfig.declination_rad", self.declination_rad)
        if abs(self.declination_rad) > math.pi / 2:
            raise EnvironmentModelError(
                f"SunConfig.declination_rad must be in [-pi/2, pi/2], got {self.declination_rad}")

    @classmethod
    def from_sun_angle(cls, sun_angle_rad: float, eclipse: bool = False) -> SunConfig:
        """Sun from the study's "sun angle" (seed 002 §4.3.2.1: "Sun Angle −120 deg").

        The seed does not define it. Interpretation: the Sun's ecliptic longitude measured from the
        vernal equinox (the season), so −120° ≡ 240°, late November. The Sun is on the ecliptic
        (latitude 0).
        """
        ra, dec = ecliptic_to_radec(finite_float("sun_angle_rad", sun_angle_rad))
        return cls(right_ascension_rad=ra, declination_rad=dec, eclipse=eclipse)


@kernels.helper
def sun_present_xyz(direction_xyz: Vec3, eclipse: bool, r_eci_m: Sequence[float]) -> bool:
    """Whether the Sun (unit ECI ``direction_xyz``) is visible from ``r_eci_m``: outside the cylindrical Earth shadow
    when ``eclipse``, always otherwise (:meth:`Sun.present_xyz`; a helper a compiled kernel calls)."""
    if not eclipse:
        return True
    rx, ry, rz = r_eci_m
    sx, sy, sz = direction_xyz
    along = rx * sx + ry * sy + rz * sz
    if along >= 0.0:
        return True
    px, py, pz = rx - along * sx, ry - along * sy, rz - along * sz
    return px * px + py * py + pz * pz > units.EARTH_RADIUS_M ** 2


class Sun:
    """Sun direction and presence (spec §3 "Sun"; sensors ideal per seed 002 §4.3)."""

    def __init__(self, cfg: SunConfig) -> None:
        self.cfg = cfg
        ca, sa = math.cos(cfg.right_ascension_rad), math.sin(cfg.right_ascension_rad)
        cd, sd = math.cos(cfg.declination_rad), math.sin(cfg.declination_rad)
        #: Unit vector to the Sun in ECI as floats (constant over the run).
        self.direction_xyz: Vec3 = (cd * ca, cd * sa, sd)

    def direction_eci(self, t_s: float) -> np.ndarray:
        """Unit vector to the Sun in ECI (constant over the run; ``t_s`` kept for the interface)."""
        finite_float("t_s", t_s)
        return np.array(self.direction_xyz)

    def present_xyz(self, r_eci_m: Sequence[float]) -> bool:
        """Fast path of :meth:`present` on a float triple (the Sun is fixed, so no time)."""
        return sun_present_xyz(self.direction_xyz, self.cfg.eclipse, r_eci_m)

    def present(self, r_eci_m: np.ndarray, t_s: float) -> bool:
        """True when the Sun is visible from ``r_eci_m`` (always True when eclipse is disabled)."""
        if self.cfg.eclipse:
            finite_float("t_s", t_s)
        return self.present_xyz([float(c) for c in np.asarray(r_eci_m, dtype=float)])


def sun_frame_dcm(sun_eci_unit: np.ndarray, ecliptic_normal_eci: np.ndarray) -> np.ndarray:
    """Rows = sun-pointed frame axes in ECI (spec §3; seed 002 §4.3.1, Figure 4-14).

    z to the Sun, y in the ecliptic plane (y = n̂_ecl × z, i.e. toward increasing ecliptic longitude),
    x = y × z completing the right-handed set (for a Sun on the ecliptic x = −n̂_ecl, ecliptic south).
    """
    z = finite_vector3("sun_eci_unit", sun_eci_unit)
    z = z / np.linalg.norm(z)
    n = finite_vector3("ecliptic_normal_eci", ecliptic_normal_eci)
    y = np.cross(n, z)
    norm_y = np.linalg.norm(y)
    if norm_y < 1e-9:
        raise EnvironmentModelError("sun direction is parallel to the ecliptic normal: sun frame undefined")
    y = y / norm_y
    x = np.cross(y, z)
    return np.vstack([x, y, z])


def hill_frame(orbit: Orbit, t_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(R_ECI←Hill, r, v) of the reference orbit at ``t_s``: the Hill frame's axes as columns — radial out,
    along track, orbit normal — and the reference position (m) and velocity (m/s) in ECI (seed 004 slide
    63, Clohessy–Wiltshire)."""
    r, v = orbit.position_velocity_eci(t_s)
    x = r / np.linalg.norm(r)
    z = np.cross(r, v)
    z = z / np.linalg.norm(z)
    return np.stack([x, np.cross(z, x), z], axis=1), r, v
