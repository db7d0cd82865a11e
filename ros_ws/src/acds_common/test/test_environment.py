"""Tests of acds_common.environment: orbits, tilted dipole, sun, sun-pointed frame (spec §3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from acds_common import units
from acds_common.environment import (
    OBLIQUITY_RAD,
    EarthFieldConfig,
    EnvironmentModelError,
    Orbit,
    OrbitConfig,
    Sun,
    SunConfig,
    TiltedDipoleField,
    ecliptic_normal_eci,
    solve_kepler,
    sun_frame_dcm,
)
from hypothesis import given, settings
from hypothesis import strategies as st

R_225 = units.EARTH_RADIUS_M + 225.0 * units.NMI_M


def _sss_orbit() -> Orbit:
    return Orbit(OrbitConfig(kind="elliptical", inclination_rad=math.radians(3.0), raan_rad=1.0,
                             perigee_altitude_m=120.0 * units.NMI_M,
                             apogee_radius_m=5.2 * units.EARTH_RADIUS_M, arg_perigee_rad=0.4,
                             mean_anomaly0_rad=0.3))


# ----------------------------------------------------------------------------------------- field


def test_dipole_magnitude_equator_and_pole_at_225_nmi() -> None:
    field = TiltedDipoleField(EarthFieldConfig(greenwich_angle0_rad=0.7))
    t = 1234.0
    pole = field.dipole_axis_eci(t)
    equator = np.cross(pole, [0.0, 0.0, 1.0])
    equator /= np.linalg.norm(equator)
    expected = units.MU0 * field.cfg.dipole_moment_am2 / (4.0 * math.pi * R_225 ** 3)
    b_eq = field.b_eci(R_225 * equator, t)
    b_pole = field.b_eci(R_225 * pole, t)
    assert np.linalg.norm(b_eq) == pytest.approx(expected, rel=1e-12)
    assert np.linalg.norm(b_pole) == pytest.approx(2.0 * expected, rel=1e-12)
    # Spec §3: about 0.25 G and 0.5 G.
    assert units.tesla_to_gauss(np.linalg.norm(b_eq)) == pytest.approx(0.25, rel=0.03)
    assert units.tesla_to_gauss(np.linalg.norm(b_pole)) == pytest.approx(0.5, rel=0.03)
    # Equator: field parallel to the dipole axis, pointing north; northern pole: field points down.
    assert np.dot(b_eq, pole) / np.linalg.norm(b_eq) == pytest.approx(1.0, abs=1e-12)
    assert np.dot(b_pole, pole) / np.linalg.norm(b_pole) == pytest.approx(-1.0, abs=1e-12)


def test_dipole_field_at_220_nmi_matches_spec_value() -> None:
    field = TiltedDipoleField(EarthFieldConfig())
    pole = field.dipole_axis_eci(0.0)
    eq = np.cross(pole, [1.0, 0.0, 0.0])
    r = units.EARTH_RADIUS_M + 220.0 * units.NMI_M
    b = np.linalg.norm(field.b_eci(r * eq / np.linalg.norm(eq), 0.0))
    assert b == pytest.approx(0.26e-4, rel=0.03)


def test_dipole_geometry_tilt_and_longitude() -> None:
    g0 = math.radians(50.0)
    field = TiltedDipoleField(EarthFieldConfig(greenwich_angle0_rad=g0))
    axis = field.dipole_axis_eci(0.0)
    assert math.degrees(math.acos(axis[2])) == pytest.approx(11.0, abs=1e-9)
    # Pole at 20° W of Greenwich, Greenwich 50° from the equinox: right ascension 30°.
    assert math.degrees(math.atan2(axis[1], axis[0])) == pytest.approx(30.0, abs=1e-9)


def test_field_rotates_with_one_sidereal_day_period() -> None:
    field = TiltedDipoleField(EarthFieldConfig())
    r = np.array([R_225, 0.0, 0.0])
    sidereal_day = 2.0 * math.pi / units.EARTH_RATE_RAD_S
    b0 = field.b_eci(r, 100.0)
    assert np.allclose(field.b_eci(r, 100.0 + sidereal_day), b0, rtol=0.0, atol=1e-9 * np.linalg.norm(b0))
    b_half = field.b_eci(r, 100.0 + 0.5 * sidereal_day)
    assert np.linalg.norm(b_half - b0) > 0.1 * np.linalg.norm(b0)
    # Axis azimuth advances at the Earth rate.
    a0, a1 = field.dipole_axis_eci(0.0), field.dipole_axis_eci(3600.0)
    dphi = math.atan2(a1[1], a1[0]) - math.atan2(a0[1], a0[0])
    assert dphi == pytest.approx(units.EARTH_RATE_RAD_S * 3600.0, rel=1e-9)


def test_field_rejects_bad_inputs() -> None:
    with pytest.raises(EnvironmentModelError):
        EarthFieldConfig(dipole_moment_am2=float("nan"))
    with pytest.raises(EnvironmentModelError):
        EarthFieldConfig(dipole_moment_am2=-1.0)
    with pytest.raises(EnvironmentModelError):
        TiltedDipoleField(EarthFieldConfig()).b_eci(np.zeros(3), 0.0)


# ----------------------------------------------------------------------------------------- orbit


def test_sss_elliptical_orbit_period_and_radii() -> None:
    orbit = _sss_orbit()
    assert orbit.period_s / 3600.0 == pytest.approx(7.75, abs=0.02)
    r_p = units.EARTH_RADIUS_M + 120.0 * units.NMI_M
    r_a = 5.2 * units.EARTH_RADIUS_M
    times = np.linspace(0.0, orbit.period_s, 20001)
    radii = np.array([np.linalg.norm(orbit.position_velocity_eci(t)[0]) for t in times])
    assert radii.min() == pytest.approx(r_p, rel=1e-5)
    assert radii.max() == pytest.approx(r_a, rel=1e-6)
    r0, v0 = orbit.position_velocity_eci(0.0)
    r1, v1 = orbit.position_velocity_eci(orbit.period_s)
    assert np.linalg.norm(r1 - r0) < 1e-6 * np.linalg.norm(r0)
    assert np.linalg.norm(v1 - v0) < 1e-6 * np.linalg.norm(v0)


def test_elliptical_orbit_conserves_energy_and_momentum_and_velocity_is_derivative() -> None:
    orbit = _sss_orbit()
    mu = units.EARTH_MU_M3_S2
    r0, v0 = orbit.position_velocity_eci(0.0)
    e0 = 0.5 * v0 @ v0 - mu / np.linalg.norm(r0)
    h0 = np.cross(r0, v0)
    for t in np.linspace(0.0, orbit.period_s, 37):
        r, v = orbit.position_velocity_eci(t)
        assert 0.5 * v @ v - mu / np.linalg.norm(r) == pytest.approx(e0, rel=1e-10)
        assert np.allclose(np.cross(r, v), h0, rtol=1e-10)
        dt = 0.01
        fd = (orbit.position_velocity_eci(t + dt)[0] - orbit.position_velocity_eci(t - dt)[0]) / (2 * dt)
        assert np.allclose(fd, v, rtol=0.0, atol=1e-4 * np.linalg.norm(v))
    assert math.degrees(math.acos(h0[2] / np.linalg.norm(h0))) == pytest.approx(3.0, abs=1e-9)


def test_circular_orbit_geometry() -> None:
    cfg = OrbitConfig(kind="circular", inclination_rad=math.radians(22.5), raan_rad=math.radians(180.0),
                      altitude_m=180.0 * units.NMI_M, arg_latitude0_rad=0.0)
    orbit = Orbit(cfg)
    r_exp = units.EARTH_RADIUS_M + 180.0 * units.NMI_M
    assert orbit.period_s == pytest.approx(2 * math.pi * math.sqrt(r_exp ** 3 / units.EARTH_MU_M3_S2))
    r0, v0 = orbit.position_velocity_eci(0.0)
    # Argument of latitude 0 is the ascending node, at RA 180°, moving north.
    assert np.allclose(r0 / r_exp, [-1.0, 0.0, 0.0], atol=1e-12)
    assert v0[2] > 0.0
    for t in (0.0, 1000.0, 4321.0):
        r, v = orbit.position_velocity_eci(t)
        assert np.linalg.norm(r) == pytest.approx(r_exp, rel=1e-12)
        assert abs(r @ v) < 1e-6 * np.linalg.norm(r) * np.linalg.norm(v)
        hz = np.cross(r, v)
        assert math.degrees(math.acos(hz[2] / np.linalg.norm(hz))) == pytest.approx(22.5, abs=1e-9)


@settings(derandomize=True, max_examples=300)
@given(st.floats(-50.0, 50.0), st.floats(0.0, 0.995))
def test_kepler_solver_residual(mean_anomaly: float, ecc: float) -> None:
    e_anom = solve_kepler(mean_anomaly, ecc)
    assert abs(e_anom - ecc * math.sin(e_anom) - mean_anomaly) < 1e-11


def test_orbit_config_validation() -> None:
    with pytest.raises(EnvironmentModelError, match="kind"):
        OrbitConfig(kind="hyperbolic")
    with pytest.raises(EnvironmentModelError, match="apogee"):
        OrbitConfig(kind="elliptical", apogee_radius_m=units.EARTH_RADIUS_M)
    with pytest.raises(EnvironmentModelError):
        OrbitConfig(altitude_m=float("inf"))
    with pytest.raises(EnvironmentModelError):
        OrbitConfig(inclination_rad=4.0)
    with pytest.raises(EnvironmentModelError):
        solve_kepler(0.1, 1.0)


# ------------------------------------------------------------------------------------------- sun


def test_sun_angle_constructor_is_ecliptic_longitude() -> None:
    s0 = Sun(SunConfig.from_sun_angle(0.0)).direction_eci(0.0)
    assert np.allclose(s0, [1.0, 0.0, 0.0], atol=1e-12)
    s90 = SunConfig.from_sun_angle(math.radians(90.0))
    assert math.degrees(s90.declination_rad) == pytest.approx(23.44, abs=1e-9)
    s = Sun(SunConfig.from_sun_angle(math.radians(-120.0))).direction_eci(0.0)
    assert abs(s @ ecliptic_normal_eci()) < 1e-12
    assert s[0] == pytest.approx(math.cos(math.radians(-120.0)), abs=1e-12)


def test_eclipse_cylindrical_shadow() -> None:
    r = 7.0e6
    lit = Sun(SunConfig(eclipse=True))
    assert lit.present(np.array([r, 0.0, 0.0]), 0.0)
    assert not lit.present(np.array([-r, 0.0, 0.0]), 0.0)
    assert lit.present(np.array([-r, 0.0, 1.01 * units.EARTH_RADIUS_M]), 0.0)
    assert Sun(SunConfig(eclipse=False)).present(np.array([-r, 0.0, 0.0]), 0.0)
    with pytest.raises(EnvironmentModelError):
        SunConfig(declination_rad=2.0)


@settings(derandomize=True, max_examples=50)
@given(st.floats(-math.pi, math.pi), st.floats(-1.2, 1.2))
def test_sun_frame_dcm_is_right_handed_with_y_in_ecliptic(ra: float, dec: float) -> None:
    s = Sun(SunConfig(right_ascension_rad=ra, declination_rad=dec)).direction_eci(0.0)
    n = ecliptic_normal_eci()
    dcm = sun_frame_dcm(s, n)
    assert np.allclose(dcm @ dcm.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(dcm) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(dcm[2], s, atol=1e-12)
    assert abs(dcm[1] @ n) < 1e-12


def test_ecliptic_normal_uses_obliquity() -> None:
    n = ecliptic_normal_eci()
    assert math.acos(n[2]) == pytest.approx(OBLIQUITY_RAD)
    # The June solstice Sun (RA 90°) is north of the equator: the ecliptic normal leans to −y.
    assert n[1] < 0.0
