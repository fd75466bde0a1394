"""Go to a landmark: drive to a goal position given by the chair's own pose estimate.

Distance and heading to the goal (thesis 4.2.2, eqns 11-12; eqn 11 as printed has
``y_d - y_d``, read ``y_d - y_0``)::

    rho = sqrt((x_d - x_0)^2 + (y_d - y_0)^2)           (eqn 11)
    alpha = atan2(y_d - y_0, x_d - x_0) - theta_0       (eqn 12, wrapped to (-pi, pi])

Two controllers, both callables for ``SimBase.run``. Each takes a pose estimator, any
object with ``update_frame(frame) -> Pose2D`` (:class:`abcwc.estimation.Odometry`,
:class:`abcwc.estimation.GyroOdometry`, ...), and feeds it every frame.

* :class:`ThesisGoToLandmark`: appendix A.10's rule. Turn on the spot at a fixed rate
  while the heading is off by more than 0.3 rad, otherwise drive ahead at a fixed
  speed, and stop within 0.5 m. (A.10 does not wrap alpha, so a goal behind the
  chair near +-pi can send it the long way round; its turn directions are also
  compared as ``theta - bearing`` with left for a positive difference, which turns
  away from the goal on our counter-clockwise convention. Both are fixed here.)
* :class:`GoToLandmark`: proportional in both: ``w = k_alpha alpha`` and
  ``v = k_rho rho cos(alpha)`` (no forward speed while facing away), each clipped
  to its limit; the speed also stays below ``sqrt(2 a rho)`` so it can stop in the
  distance left. It latches "reached" inside the tolerance and stays stopped, so it
  never hunts around the goal.
"""

from __future__ import annotations

import math
from typing import Protocol

from abcwc.types import Pose2D, SensorFrame, Twist, wrap_angle


class PoseEstimator(Protocol):
    """Anything that turns each SensorFrame into a pose estimate."""

    def update_frame(self, frame: SensorFrame) -> Pose2D: ...


def distance_and_bearing(pose: Pose2D, goal: tuple[float, float]) -> tuple[float, float]:
    """``(rho, alpha)``: distance (m) and heading error (rad) to the goal (eqns 11-12)."""
    dx, dy = goal[0] - pose.x, goal[1] - pose.y
    return math.hypot(dx, dy), wrap_angle(math.atan2(dy, dx) - pose.theta)


class _GoalController:
    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator, tolerance: float):
        if not (len(goal) == 2 and all(math.isfinite(float(g)) for g in goal)):
            raise ValueError(f"goal must be a finite (x, y) in metres, got {goal!r}")
        if not tolerance > 0:
            raise ValueError(f"tolerance must be > 0 m, got {tolerance!r}")
        self.goal = (float(goal[0]), float(goal[1]))
        self.estimator = estimator
        self.tolerance = float(tolerance)
        self.reached = False
        self.pose = Pose2D()

    def __call__(self, frame: SensorFrame) -> Twist:
        self.pose = self.estimator.update_frame(frame)
        rho, alpha = distance_and_bearing(self.pose, self.goal)
        if self.reached or rho <= self.tolerance:
            self.reached = True
            return Twist(0.0, 0.0)
        return self.command(rho, alpha)

    def command(self, rho: float, alpha: float) -> Twist:
        raise NotImplementedError


class ThesisGoToLandmark(_GoalController):
    """Turn-then-drive (A.10): fixed turn rate (rad/s) and speed (m/s), bang-bang."""

    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator,
                 tolerance: float = 0.5, heading_tolerance: float = 0.3,
                 speed: float = 0.5, turn_rate: float = 0.5):
        super().__init__(goal, estimator, tolerance)
        self.heading_tolerance, self.speed, self.turn_rate = heading_tolerance, speed, turn_rate

    def command(self, rho: float, alpha: float) -> Twist:
        if abs(alpha) > self.heading_tolerance:
            return Twist(0.0, math.copysign(self.turn_rate, alpha))
        return Twist(self.speed, 0.0)


class GoToLandmark(_GoalController):
    """Proportional go-to-goal with speed, turn-rate and deceleration limits.

    ``k_rho`` (1/s), ``k_alpha`` (1/s); ``max_speed`` (m/s), ``max_turn_rate`` (rad/s),
    ``decel`` (m/s^2) the braking the chair can count on (its motors lag ~0.3 s).
    """

    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator,
                 tolerance: float = 0.1, max_speed: float = 0.8, max_turn_rate: float = 0.8,
                 k_rho: float = 0.8, k_alpha: float = 1.5, decel: float = 0.5):
        super().__init__(goal, estimator, tolerance)
        self.max_speed, self.max_turn_rate = max_speed, max_turn_rate
        self.k_rho, self.k_alpha, self.decel = k_rho, k_alpha, decel

    def command(self, rho: float, alpha: float) -> Twist:
        w = max(-self.max_turn_rate, min(self.max_turn_rate, self.k_alpha * alpha))
        v = min(self.max_speed, self.k_rho * rho, math.sqrt(2 * self.decel * rho))
        return Twist(v * max(0.0, math.cos(alpha)), w)
