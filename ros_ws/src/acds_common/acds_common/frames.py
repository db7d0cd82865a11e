"""Coordinate frame names of the graph's messages (``header.frame_id``), per REP-103 and REP-105.

REP-103: right-handed frames, SI units, Hamilton quaternions (x, y, z, w); a stamped vector's
``frame_id`` is the frame its components are expressed in. REP-105 names the frame rigidly
attached to the vehicle ``base_link``; it has no inertial frame for orbits (its ``earth`` is
ECEF, which rotates), so the inertial frame keeps the field's usual name, ``eci``.

* :data:`ECI` — Earth-centred inertial: x to the vernal equinox, z along the Earth's spin axis
  (spec §3). Orbit position/velocity and the attitude quaternion (body → ECI) are in it:
  ``truth/odometry`` has ``frame_id`` eci and ``child_frame_id`` base_link.
* :data:`BODY` — the spacecraft body axes (the study's x roll, y pitch, z yaw; SSS: z the spin
  axis), REP-105's ``base_link``. Rates, torques, field, moments, wheel momenta, gyro and sun
  sensor are in it, and so are the direction cosines (B13, B23, B33): the sun frame's z axis in
  body components.
* :data:`SUN_FRAME` — the study's sun-pointed frame (seed 002 §4.3.1, Fig. 4-14): z to the sun, y in
  the ecliptic plane, x completing the set; B_ij = (body axis i)·(sun-frame axis j). No topic is
  expressed in it; it is the frame the attitude is judged against (ECI → sun_frame is fixed for a run).
* :data:`MAGNETOMETER` — the triaxial fluxgate's sensing axes (spec §5), mounted aligned with the
  body axes (identity rotation from base_link): its volts, bias volts and measured field.

* :data:`FORMATION` — a formation's frame of relative motion (spec §10): the air-bearing table's
  axes (``planar``, z vertical), an inertial frame (``free_space``) or the Hill frame of the reference
  orbit (``hill``: x radial, y along-track, z orbit normal). Every vehicle's position, velocity and
  attitude are in it; each vehicle's body frame is ``<vehicle>/base_link`` (:func:`vehicle_body`),
  the usual prefix of a multi-robot TF tree.

Where the messages depart from a ROS convention, it is said here: ``nav_msgs/Odometry`` asks for the
twist in ``child_frame_id``; ``truth/odometry`` has the body rates there (base_link) but its
``twist.linear`` is the ECI orbital velocity, beside the ECI position.
"""

from __future__ import annotations

ECI = 'eci'
BODY = 'base_link'
SUN_FRAME = 'sun_frame'
MAGNETOMETER = 'magnetometer'
FORMATION = 'formation'


def vehicle_body(vehicle: str) -> str:
    """The body frame of one vehicle of a formation."""
    return f'{vehicle}/{BODY}'

#: Every frame, parent first: (frame, parent or '' for the root, how the parent reaches it).
TREE: tuple[tuple[str, str, str], ...] = (
    (ECI, '', 'the inertial root'),
    (BODY, ECI, 'the attitude quaternion of truth/odometry (body → ECI)'),
    (SUN_FRAME, ECI, 'fixed for a run: the scenario sun and the ecliptic (acds_common.environment.sun_frame_dcm)'),
    (MAGNETOMETER, BODY, 'identity (axes aligned with the body)'),
    (FORMATION, '', "a formation's root (its own run; no ECI link kept outside the hill frame's reference orbit)"),
)
