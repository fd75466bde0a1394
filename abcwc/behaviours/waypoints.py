"""Follow a list of waypoints: one :class:`GoToLandmark` leg after another.

:class:`FollowWaypoints` is a behaviour (a controller for ``Base.run``): it drives to
each ``(x, y)`` in turn, switching to the next as soon as the current one is within
``tolerance``, and succeeds after the last. It steers by the pose estimator it is given
(:class:`~abcwc.estimation.estimator.PoseEstimator`; there is no default: a route
driven on a real chair needs one that works there). :class:`GroundTruth` is the
simulator's own pose in the same shape, for routes that must not depend on the
estimators being tested: the filters then only listen, they never steer.

:func:`floor_mixed_drive` is the five-minute mixed drive in the floor world used by
the EKF's tests and chapter 10: up and down the corridor (y 8..10 m) at up to
0.9 m/s, weaving by up to 0.6 m, with a U-turn at each end: straights, gentle curves,
sharp turns, braking and starting again.
"""

from __future__ import annotations

from collections.abc import Sequence

from abcwc.behaviours.base import LOOP_RATE_HZ, BehaviourBase, finite_point
from abcwc.behaviours.landmark import GoToLandmark
from abcwc.estimation.estimator import PoseEstimator
from abcwc.types import Pose2D, SensorFrame, Twist

# One lap of the floor world's corridor from its west end: east, weaving, then back.
_CORRIDOR_LAP = ((8.0, 8.8), (14.0, 9.3), (20.0, 8.7), (26.0, 9.3), (32.0, 8.8), (37.0, 9.0),
                 (30.0, 9.2), (24.0, 8.7), (18.0, 9.3), (12.0, 8.8), (3.0, 9.0))


class GroundTruth:
    """A "pose estimator" that reads the simulator's true pose from each frame (the one
    estimator shape: ``observe(frame)``, then :attr:`pose`)."""

    def __init__(self) -> None:
        self.pose = Pose2D()

    def observe(self, frame: SensorFrame) -> None:
        """Take ``frame.truth.pose``; a real chair has none, so this refuses its frames."""
        if frame.truth is None:
            raise ValueError("this frame has no ground-truth pose (a real chair's frames "
                             "never do); steer with an estimator such as Odometry instead")
        self.pose = frame.truth.pose


class FollowWaypoints(BehaviourBase):
    """Drive through ``waypoints`` in order, then stop (succeeded).

    ``estimator`` gives the pose to steer by (any
    :class:`~abcwc.estimation.estimator.PoseEstimator`; :class:`GroundTruth` in a
    simulated study that must not depend on one);
    ``tolerance`` (m) is how close counts as reached; the other keywords go to the
    :class:`GoToLandmark` that drives each leg (``max_speed`` m/s, ``max_turn_rate``
    rad/s, gains). :attr:`index` is the waypoint being driven to.
    """

    def __init__(self, waypoints: Sequence[tuple[float, float]],
                 estimator: PoseEstimator, tolerance: float = 0.5,
                 max_speed: float = 0.9, rate_hz: float = LOOP_RATE_HZ,
                 **leg_options: float):
        super().__init__(rate_hz)
        points = [] if isinstance(waypoints, (str, bytes)) else list(waypoints)
        if not points:
            raise ValueError("waypoints must be a non-empty list of finite (x, y) in metres, "
                             f"got {waypoints!r}")
        self.waypoints = [finite_point(point, f"waypoint {k}") for k, point in enumerate(points)]
        self.index = 0
        if not isinstance(estimator, PoseEstimator):
            raise ValueError(f"estimator must have observe(frame) and pose (Odometry, "
                             f"GyroOdometry, EkfEstimator, GroundTruth, ...), got {estimator!r}")
        self.leg = GoToLandmark(self.waypoints[0], estimator,
                                tolerance=tolerance, max_speed=max_speed, **leg_options)

    @property
    def estimator(self) -> PoseEstimator:
        """The pose estimator the legs steer by."""
        return self.leg.estimator

    def observe(self, frame: SensorFrame) -> None:
        self.leg.observe(frame)

    def update(self, frame: SensorFrame) -> Twist:
        if self.leg.rho <= self.leg.tolerance:
            if self.index == len(self.waypoints) - 1:
                self.succeed()
                return Twist(0.0, 0.0)
            self.index += 1
            self.leg.set_goal(self.waypoints[self.index])
        return self.leg.update(frame)

    def reset(self) -> None:
        """Start the route again from its first waypoint."""
        super().reset()
        self.index = 0
        self.leg.reset()
        self.leg.set_goal(self.waypoints[0])


def floor_mixed_drive(laps: int = 6) -> list[tuple[float, float]]:
    """Waypoints of the floor world's mixed drive, from its ``start`` place (2, 9).

    One lap is about 68 m and takes about 83 s; the default six are more than five
    minutes of driving, so a 300 s run never runs out of route.
    """
    if isinstance(laps, bool) or not isinstance(laps, int) or laps < 1:
        raise ValueError(f"laps must be a positive whole number, got {laps!r}")
    return list(_CORRIDOR_LAP) * laps
