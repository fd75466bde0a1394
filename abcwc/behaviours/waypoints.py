"""Follow a list of waypoints: one :class:`GoToLandmark` leg after another.

:class:`FollowWaypoints` is a controller for ``SimBase.run`` (or a real chair's
``run``): it drives to each ``(x, y)`` in turn, switching to the next as soon as the
current one is within ``tolerance``, and stops after the last. It steers by any pose
estimator (``update_frame(frame) -> Pose2D``). :class:`GroundTruth` is the
simulator's own pose, for routes that must not depend on the estimators being
tested: the filters then only listen, they never steer.

:func:`floor_mixed_drive` is the five-minute mixed drive in the floor world used by
the EKF's tests and chapter 10: up and down the corridor (y 8..10 m) at up to
0.9 m/s, weaving by up to 0.6 m, with a U-turn at each end: straights, gentle curves,
sharp turns, braking and starting again.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from abcwc.behaviours.landmark import GoToLandmark, PoseEstimator
from abcwc.types import Pose2D, SensorFrame, Twist

# One lap of the floor world's corridor from its west end: east, weaving, then back.
_CORRIDOR_LAP = ((8.0, 8.8), (14.0, 9.3), (20.0, 8.7), (26.0, 9.3), (32.0, 8.8), (37.0, 9.0),
                 (30.0, 9.2), (24.0, 8.7), (18.0, 9.3), (12.0, 8.8), (3.0, 9.0))


class GroundTruth:
    """A "pose estimator" that reads the simulator's true pose from each frame."""

    def update_frame(self, frame: SensorFrame) -> Pose2D:
        """``frame.pose``; a real chair has none, so this refuses its frames."""
        if frame.pose is None:
            raise ValueError("this frame has no ground-truth pose (a real chair's frames "
                             "never do); steer with an estimator such as Odometry instead")
        return frame.pose


class FollowWaypoints:
    """Drive through ``waypoints`` in order, then stop.

    ``estimator`` gives the pose to steer by (default :class:`GroundTruth`);
    ``tolerance`` (m) is how close counts as reached; the other keywords go to each
    :class:`GoToLandmark` leg (``max_speed`` m/s, ``max_turn_rate`` rad/s, gains).
    :attr:`index` is the waypoint being driven to; :attr:`done` is set after the last.
    """

    def __init__(self, waypoints: Sequence[tuple[float, float]],
                 estimator: PoseEstimator | None = None, tolerance: float = 0.5,
                 max_speed: float = 0.9, **leg_options: float):
        points = [tuple(map(float, point)) for point in waypoints]
        if not points or any(len(p) != 2 or not all(map(math.isfinite, p)) for p in points):
            raise ValueError("waypoints must be a non-empty list of finite (x, y) in metres, "
                             f"got {waypoints!r}")
        self.waypoints: list[tuple[float, float]] = points  # type: ignore[assignment]
        self.estimator = estimator or GroundTruth()
        self.tolerance = tolerance
        self.leg_options = dict(leg_options, max_speed=max_speed)
        self.index = 0
        self.leg = self._leg(0)

    def _leg(self, index: int) -> GoToLandmark:
        return GoToLandmark(self.waypoints[index], self.estimator, tolerance=self.tolerance,
                            **self.leg_options)

    @property
    def done(self) -> bool:
        """True once the last waypoint has been reached."""
        return self.index == len(self.waypoints) - 1 and self.leg.reached

    def __call__(self, frame: SensorFrame) -> Twist:
        command = self.leg(frame)
        if self.leg.reached and self.index < len(self.waypoints) - 1:
            self.index += 1
            self.leg = self._leg(self.index)
            command = self.leg(frame)
        return command


def floor_mixed_drive(laps: int = 6) -> list[tuple[float, float]]:
    """Waypoints of the floor world's mixed drive, from its ``start`` place (2, 9).

    One lap is about 68 m and takes about 83 s; the default six are more than five
    minutes of driving, so a 300 s run never runs out of route.
    """
    if isinstance(laps, bool) or not isinstance(laps, int) or laps < 1:
        raise ValueError(f"laps must be a positive whole number, got {laps!r}")
    return list(_CORRIDOR_LAP) * laps
