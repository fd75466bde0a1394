"""The one shape of a pose estimator: ``observe(frame)`` with every frame, then ``pose``.

Wheel odometry (:class:`~abcwc.estimation.odometry.Odometry`), gyro odometry
(:class:`~abcwc.estimation.gyro.GyroOdometry`), the EKF fed frame by frame
(:class:`~abcwc.estimation.ekf.EkfEstimator`), the map localiser
(:class:`abcwc.navigation.localization.MapLocalizer`) and, for teaching runs that must
not depend on an estimator, the simulator's own pose
(:class:`abcwc.behaviours.GroundTruth`) all have it, so any of them can steer any
behaviour. As ROS's ``robot_localization`` nodes take messages as they come and
publish an estimate, an estimator here takes every frame (it must not miss one: it
integrates every encoder count and gyro sample) and keeps its newest estimate.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from abcwc.types import Pose2D, SensorFrame


@runtime_checkable
class PoseEstimator(Protocol):
    """Anything that takes every SensorFrame and keeps a pose estimate (map or odom
    frame, m and rad)."""

    @property
    def pose(self) -> Pose2D: ...

    def observe(self, frame: SensorFrame) -> None: ...
