"""UMBmark trials on a chair: drive the squares, collect the return errors.

Borenstein and Feng (1996) as the thesis ran it (4.3.6): :func:`run_square` drives one
square with :class:`abcwc.behaviours.SquareDriver` on any body (simulator, firmware in
the loop, real chair) and returns where the odometry thinks it ended and, where the
body knows it, where it really did; :func:`run_umbmark` does ``runs`` squares each way
on fresh seeded simulators; :func:`calibrate_distance_scale` measures the mean wheel
size that UMBmark cannot see. The corrections themselves come from
:func:`abcwc.estimation.umbmark.umbmark_corrections`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from abcwc.base import Base
from abcwc.behaviours.square import SquareDriver
from abcwc.estimation.odometry import Odometry
from abcwc.estimation.umbmark import THESIS_SIDE
from abcwc.geometry import wrap_angle
from abcwc.types import Pose2D, Twist


@dataclass(frozen=True)
class SquareRun:
    """One square driven by odometry, in its start frame (x ahead, y left; m, rad)."""

    direction: str
    side: float  # m
    seconds: float  # s of driving, including the wait for the wheels to stop
    odometric_end: Pose2D  # where the odometry says the chair ended
    true_path: np.ndarray  # (N, 3) ground truth in the start frame; NaN on the real chair

    @property
    def true_end(self) -> Pose2D | None:
        """Where the chair really ended (start frame), or None without ground truth."""
        last = self.true_path[-1] if len(self.true_path) else np.full(3, np.nan)
        return Pose2D(*map(float, last)) if np.isfinite(last).all() else None

    @property
    def error(self) -> np.ndarray:
        """Return error ``true - odometric`` end ``[x, y, theta]``; NaN without ground truth."""
        true_end, end = self.true_end, self.odometric_end
        if true_end is None:
            return np.full(3, np.nan)
        return np.array([true_end.x - end.x, true_end.y - end.y,
                         wrap_angle(true_end.theta - end.theta)])


def run_square(base: Base, direction: str, side: float = THESIS_SIDE,
               correction: tuple[float, float] = (1.0, 1.0), wheel_base: float | None = None,
               speed: float = 0.5, turn_rate: float = 0.5, settle: float = 0.6,
               timeout: float = 200.0, chunk: float = 1.0, **driver_options: float
               ) -> SquareRun:
    """Drive one UMBmark square on any chair body (simulator, firmware, real chair).

    A :class:`SquareDriver` steers by odometry that starts at the origin of the start
    frame; the chair runs in ``chunk`` second pieces until the square is done, then
    one more second for the wheels to stop. Where the body reports ground truth (the
    simulator, the firmware in the loop) the true path comes back in the start frame;
    on the real chair it is NaN and you measure the end by hand. ``driver_options``
    (``brake_gain``, ``turn_gain``) go to the :class:`SquareDriver`.
    """
    if not (chunk > 0 and timeout > 0):
        raise ValueError(f"chunk and timeout must be > 0 s, got {chunk!r}, {timeout!r}")
    params = base.params
    first = base.read()
    odometry = Odometry(params, correction=correction, wheel_base=wheel_base)
    driver = SquareDriver(odometry, side, direction, speed, turn_rate, settle,
                          **driver_options)
    logs = []
    elapsed = 0.0
    while driver.running:
        if elapsed >= timeout:
            raise RuntimeError(f"{direction} square not finished in {timeout:g} s")
        logs.append(base.run(driver, chunk))
        elapsed += chunk
    logs.append(base.run(driver, 1.0))  # succeeded: it sends zero; let the wheels stop
    odometry.observe(base.read())
    poses = np.vstack([log.pose for log in logs])
    start = first.truth.pose if first.truth is not None else None
    if start is None or not np.isfinite(poses).all():
        path = np.full_like(poses, np.nan)
    else:
        c, s = math.cos(start.theta), math.sin(start.theta)
        dx, dy = poses[:, 0] - start.x, poses[:, 1] - start.y
        heading = [wrap_angle(theta - start.theta) for theta in poses[:, 2]]
        path = np.column_stack([c * dx + s * dy, -s * dx + c * dy, heading])
    seconds = sum(len(log) for log in logs) * base.period
    return SquareRun(direction, float(side), float(seconds), odometry.pose, path)


def drive_square(sim, direction: str, side: float = THESIS_SIDE,
                 correction: tuple[float, float] = (1.0, 1.0),
                 wheel_base: float | None = None, speed: float = 0.5,
                 timeout: float = 200.0) -> np.ndarray:
    """Drive one UMBmark square on ``sim`` (a SimBase) by its odometry; return its error.

    The return error ``true - odometric`` end (start frame, ``[x, y, theta]``) is what
    the odometry got wrong; the controller's own stopping error cancels out. See
    :func:`run_square` for the whole run.
    """
    run = run_square(sim, direction, side, correction, wheel_base, speed, timeout=timeout)
    if run.true_end is None:
        raise ValueError("drive_square needs a body with ground truth (the simulator); "
                         "use run_square on the real chair")
    return run.error


def run_umbmark(make_sim: Callable[[int], object], runs: int = 5, side: float = THESIS_SIDE,
                correction: tuple[float, float] = (1.0, 1.0),
                wheel_base: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``runs`` CW and ``runs`` CCW squares, each on a fresh ``make_sim(seed)``.

    Returns the ``(runs, 3)`` CW and CCW return errors.
    """
    out = {}
    for k, direction in enumerate(("cw", "ccw")):
        out[direction] = np.array([
            drive_square(make_sim(2 * i + k), direction, side, correction, wheel_base)
            for i in range(runs)])
    return out["cw"], out["ccw"]


def calibrate_distance_scale(sim, seconds: float = 10.0, speed: float = 0.5,
                             correction: tuple[float, float] = (1.0, 1.0)) -> float:
    """True / odometric distance of a straight drive: the scale UMBmark cannot see.

    UMBmark fixes the ratio of the wheels and the wheel base but keeps their mean
    size; the mean comes from driving a measured distance (the thesis's firmware
    carries such a calibration: 1242.7 counts per wheel turn, not the nominal 1258).
    Multiply both correction factors by the result.
    """
    start = sim.pose
    odometry = Odometry(sim.params, correction=correction, start=start)
    odometry.observe(sim.frame)
    t0 = sim.t
    sim.run(lambda frame: Twist(speed, 0.0) if frame.t - t0 < seconds else Twist(), seconds + 1)
    odometry.observe(sim.frame)
    true = math.hypot(sim.pose.x - start.x, sim.pose.y - start.y)
    if odometry.distance <= 0:
        raise RuntimeError("the chair did not move forward; cannot calibrate the scale")
    return true / odometry.distance
