"""The range and bearing of a known landmark, as a sensor on the chair sees it: the
measurement model an EKF needs to take a sighting of a fixed marker as a fix.

A sensor mounted at ``mount = (mx, my, myaw)`` in base_link sits, for the chair at
``(x, y, theta)``, at ``c = (x + mx cos(theta) - my sin(theta), y + mx sin(theta) +
my cos(theta))`` looking along ``theta + myaw``. A landmark at ``L = (lx, ly)`` is then
seen at range and bearing (Thrun, Burgard and Fox, *Probabilistic Robotics*, table 7.2,
EKF localisation with known correspondences, with the sensor's offset added)::

    r   = |L - c|
    phi = atan2(ly - cy, lx - cx) - theta - myaw

and the filter linearises both about its estimate: the Jacobian ``H`` below, with
``d = L - c`` and ``dc/dtheta = (-mx sin(theta) - my cos(theta), mx cos(theta) -
my sin(theta))``::

    dr/dx = -dx / r        dr/dy = -dy / r        dr/dtheta = -(d . dc/dtheta) / r
    dphi/dx = dy / r^2     dphi/dy = -dx / r^2
    dphi/dtheta = (dy dcx/dtheta - dx dcy/dtheta) / r^2 - 1
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.geometry import wrap_angle


def range_bearing(pose: np.ndarray, landmark: tuple[float, float],
                  mount: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """``(z, H)``: the range (m) and bearing (rad, left positive, wrapped) at which a
    sensor at ``mount`` on the chair at ``pose`` (x, y, theta; further state components
    are ignored and get zero columns) sees ``landmark`` (x, y, m), and their Jacobian
    ``H`` (2 x len(pose)) with respect to the state."""
    state = np.asarray(pose, dtype=float)
    x, y, theta = state[:3]
    mx, my, myaw = (float(v) for v in mount)
    c, s = math.cos(theta), math.sin(theta)
    cx, cy = x + mx * c - my * s, y + mx * s + my * c
    dx, dy = float(landmark[0]) - cx, float(landmark[1]) - cy
    r2 = dx * dx + dy * dy
    if r2 < 1e-12:
        raise ValueError("the landmark is at the sensor: no bearing to it")
    r = math.sqrt(r2)
    bearing = wrap_angle(math.atan2(dy, dx) - theta - myaw)
    dcx, dcy = -mx * s - my * c, mx * c - my * s  # d(c)/d(theta)
    jacobian = np.zeros((2, len(state)))
    jacobian[0, :3] = (-dx / r, -dy / r, -(dx * dcx + dy * dcy) / r)
    jacobian[1, :3] = (dy / r2, -dx / r2, (dy * dcx - dx * dcy) / r2 - 1.0)
    return np.array([r, bearing]), jacobian


__all__ = ["range_bearing"]
