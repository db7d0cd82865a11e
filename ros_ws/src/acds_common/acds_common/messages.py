"""numpy ↔ standard message conversions shared by the nodes (ROS plumbing only)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Vector3Stamped
from sensor_msgs.msg import MagneticField


def vec(msg: Vector3Stamped | None, default: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Vector3Stamped → 3-vector (``default`` for an absent input)."""
    if msg is None:
        return np.array(default, dtype=float)
    v = msg.vector
    return np.array([v.x, v.y, v.z])


def vector3_stamped(values: Iterable[float], frame_id: str = 'body') -> Vector3Stamped:
    """3-vector → Vector3Stamped (stamp is set by the lockstep publish)."""
    msg = Vector3Stamped()
    msg.header.frame_id = frame_id
    msg.vector.x, msg.vector.y, msg.vector.z = (float(x) for x in values)
    return msg


def field(msg: MagneticField | None) -> np.ndarray:
    """MagneticField → 3-vector, tesla."""
    if msg is None:
        return np.zeros(3)
    f = msg.magnetic_field
    return np.array([f.x, f.y, f.z])


def magnetic_field(b_t: Iterable[float], covariance: Iterable[float] | None = None,
                   frame_id: str = 'body') -> MagneticField:
    """3-vector (T) → MagneticField; covariance row-major 3×3 in T² (zeros = unknown)."""
    msg = MagneticField()
    msg.header.frame_id = frame_id
    msg.magnetic_field.x, msg.magnetic_field.y, msg.magnetic_field.z = (float(x) for x in b_t)
    if covariance is not None:
        msg.magnetic_field_covariance = [float(c) for c in covariance]
    return msg


def diagnostic(node: str, values: dict[str, object], message: str = 'ok',
               level: bytes = DiagnosticStatus.OK) -> DiagnosticArray:
    """One DiagnosticStatus named after the node, with key/value telemetry."""
    arr = DiagnosticArray()
    status = DiagnosticStatus(level=level, name=node, message=message, hardware_id=node)
    status.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
    arr.status = [status]
    return arr


#: Name of the mode manager's status inside the ``mode`` DiagnosticArray.
MODE_STATUS = 'ascs_mode_manager'


def mode_status(msg: DiagnosticArray | None, node: str) -> tuple[str | None, list[str]]:
    """(mode, commands forwarded to ``node`` in order) from the step's ``mode`` array; (None, []) if absent.

    The mode manager forwards accepted ground commands for other nodes as ``command/<node>`` keys.
    """
    if msg is None:
        return None, []
    key = f'command/{node}'
    for status in msg.status:
        if status.name == MODE_STATUS:
            values = [(kv.key, kv.value) for kv in status.values]
            mode = next((v for k, v in values if k == 'mode'), status.message)
            return mode, [v for k, v in values if k == key]
    return None, []
