"""Go to a landmark: drive to a goal position given by the chair's own pose estimate.

Distance and heading to the goal (thesis 4.2.2, eqns 11-12; eqn 11 as printed has
``y_d - y_d``, read ``y_d - y_0``)::

    rho = sqrt((x_d - x_0)^2 + (y_d - y_0)^2)           (eqn 11)
    alpha = atan2(y_d - y_0, x_d - x_0) - theta_0       (eqn 12, wrapped to (-pi, pi])

Two behaviours (:class:`~abcwc.behaviours.base.BehaviourBase`), each a controller for
``Base.run``. Each takes a pose estimator
(:class:`~abcwc.estimation.estimator.PoseEstimator`: ``observe(frame)``, then ``pose``:
:class:`abcwc.estimation.Odometry`, :class:`abcwc.estimation.GyroOdometry`, the EKF's
:class:`abcwc.estimation.EkfEstimator`, a map localiser, ...), feeds it every frame,
and succeeds (stops for good) once the estimate is within ``tolerance`` of the goal.

* :class:`ThesisGoToLandmark`: appendix A.10's turn-then-drive, as a state machine
  (:func:`turn_then_drive`): turn on the spot at a fixed rate while the heading is off,
  drive straight at a fixed speed while it is not, stop within 0.5 m. What A.10 gets
  wrong, and what is changed here:

  - its heading error is the raw difference of two angles in (-pi, pi], never
    wrapped, so for a goal behind the chair near +-pi it reads up to 2 pi off and
    turns the long way round: :func:`distance_and_bearing` wraps alpha;
  - it turns left when ``theta - bearing`` is positive, i.e. when the goal lies to the
    *right* on A.9's counter-clockwise heading, so it turns away from the goal: here the
    turn follows the sign of alpha (positive = goal to the left = turn left);
  - it calls "forward" and "turn" in the same pass, and with A.2's helpers these set
    two different pots (FB and LR), neither of which is put back to neutral when its
    condition ends: the chair would drive and turn at once, and keep turning after
    the heading is good. Here each period is exactly one of turn on the spot, drive
    straight, or stop;
  - it runs every 500 ms; here every control period (20 ms);
  - it keeps the goal in globals where 0 means "no goal yet", so a goal on the line
    x = 0 or y = 0 cannot be entered; here the goal is an argument, any finite point.

  One addition, off by default: with ``align_tolerance`` below ``heading_tolerance``
  a turn goes on until the heading is within ``align_tolerance`` (hysteresis), so the
  chair sets off well aimed instead of up to ``heading_tolerance`` off.
* :class:`GoToLandmark`: the polar-coordinate go-to-goal law of Siegwart,
  Nourbakhsh & Scaramuzza, *Introduction to Autonomous Mobile Robots* (2nd ed., 2011),
  section 3.6.2, without its final-heading term (``k_beta = 0``: a landmark is a
  position): ``w = k_alpha alpha`` and ``v = k_rho rho cos(alpha)`` (no forward speed
  while facing away), each clipped to its limit; the speed also stays below
  ``sqrt(2 a rho)`` so it can brake in the distance left (:func:`proportional_command`).
  For small alpha, ``d(alpha)/dt ~ -(k_alpha - k_rho) alpha``, so the heading settles
  when ``k_alpha > k_rho`` (the book's condition). Success is latched, so the chair
  never hunts around the goal.
"""

from __future__ import annotations

import math

from abcwc.behaviours.base import LOOP_RATE_HZ, BehaviourBase, finite_point, positive_number
from abcwc.estimation.estimator import PoseEstimator
from abcwc.geometry import wrap_angle
from abcwc.types import Pose2D, SensorFrame, Twist

TURN = "turn"
DRIVE = "drive"
REACHED = "reached"
STATES = (TURN, DRIVE, REACHED)
"""The states of :func:`turn_then_drive`: turning on the spot, driving straight, stopped."""


def distance_and_bearing(pose: Pose2D, goal: tuple[float, float]) -> tuple[float, float]:
    """``(rho, alpha)``: distance (m) and heading error (rad, in (-pi, pi]) to the goal.

    Eqns 11-12: ``rho`` is the straight-line distance from the pose to ``goal``
    ``(x, y)`` (m); ``alpha`` is how far the chair must turn to face it, positive to
    the left (counter-clockwise). At the goal itself (``rho = 0``) alpha is ``-theta``
    wrapped (``atan2(0, 0) = 0``), a value with no meaning.
    """
    dx, dy = goal[0] - pose.x, goal[1] - pose.y
    return math.hypot(dx, dy), wrap_angle(math.atan2(dy, dx) - pose.theta)


def turn_then_drive(state: str, rho: float, alpha: float, *, tolerance: float = 0.5,
                    heading_tolerance: float = 0.3, align_tolerance: float | None = None,
                    speed: float = 0.5, turn_rate: float = 0.5) -> tuple[str, Twist]:
    """One period of the turn-then-drive state machine (A.10, fixed): ``(state, command)``.

    ``state`` is the state after the previous period (:data:`TURN` to begin with);
    ``rho`` (m) and ``alpha`` (rad) come from :func:`distance_and_bearing`. In order:

    1. ``"reached"``, or ``rho <= tolerance`` (m): ``"reached"``, stop. It stays so.
    2. ``"drive"`` with ``|alpha| > heading_tolerance`` (rad), or ``"turn"`` with
       ``|alpha| > align_tolerance`` (rad, default ``heading_tolerance``): ``"turn"``,
       on the spot at ``turn_rate`` (rad/s) towards the goal (the sign of alpha).
    3. Otherwise ``"drive"``: straight ahead at ``speed`` (m/s).
    """
    if state not in STATES:
        raise ValueError(f"state {state!r} unknown; allowed: {', '.join(STATES)}")
    align = heading_tolerance if align_tolerance is None else align_tolerance
    if state == REACHED or rho <= tolerance:
        return REACHED, Twist(0.0, 0.0)
    limit = align if state == TURN else heading_tolerance
    if abs(alpha) > limit:
        return TURN, Twist(0.0, math.copysign(turn_rate, alpha))
    return DRIVE, Twist(speed, 0.0)


def proportional_command(rho: float, alpha: float, *, k_rho: float = 0.8,
                         k_alpha: float = 1.5, max_speed: float = 0.8,
                         max_turn_rate: float = 0.8, decel: float = 0.5) -> Twist:
    """The proportional go-to-goal command (Siegwart et al. 3.6.2 with ``k_beta = 0``).

    ``w = clip(k_alpha alpha, +-max_turn_rate)`` (rad/s) and
    ``v = min(max_speed, k_rho rho, sqrt(2 decel rho)) * max(0, cos alpha)`` (m/s):
    proportional to the distance, never faster than the chair can brake from at
    ``decel`` (m/s^2) in the distance left, and no forward speed while the goal is
    more than 90 degrees off. Gains ``k_rho``, ``k_alpha`` in 1/s.
    """
    w = max(-max_turn_rate, min(max_turn_rate, k_alpha * alpha))
    v = min(max_speed, k_rho * rho, math.sqrt(2.0 * decel * rho))
    return Twist(v * max(0.0, math.cos(alpha)), w)


class GoalBehaviour(BehaviourBase):
    """Drive to a goal point by a pose estimate; succeed within ``tolerance`` (m).

    Every frame feeds the estimator (:meth:`observe`) and refreshes :attr:`pose`,
    :attr:`rho` (m) and :attr:`alpha` (rad); at ``rate_hz`` :meth:`update` succeeds
    once ``rho <= tolerance`` or asks :meth:`command` for this period's Twist.
    """

    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator, tolerance: float,
                 rate_hz: float):
        super().__init__(rate_hz)
        self.goal = finite_point(goal, "goal")
        self.estimator = estimator
        self.tolerance = positive_number("tolerance", tolerance, "m")
        self.pose = Pose2D()
        self.rho, self.alpha = math.inf, 0.0  # the latest distance (m) and bearing (rad)

    def set_goal(self, goal: tuple[float, float]) -> None:
        """Aim at a new goal from the latest pose (the estimator keeps its state)."""
        self.goal = finite_point(goal, "goal")
        self.rho, self.alpha = distance_and_bearing(self.pose, self.goal)

    def observe(self, frame: SensorFrame) -> None:
        self.estimator.observe(frame)
        self.pose = self.estimator.pose
        self.rho, self.alpha = distance_and_bearing(self.pose, self.goal)

    def update(self, frame: SensorFrame) -> Twist:
        if self.rho <= self.tolerance:
            self.succeed()
            return Twist(0.0, 0.0)
        return self.command(self.rho, self.alpha)

    def command(self, rho: float, alpha: float) -> Twist:
        """This period's Twist for distance ``rho`` (m) and bearing ``alpha`` (rad)."""
        raise NotImplementedError(f"{type(self).__name__} must define command(rho, alpha)")


class ThesisGoToLandmark(GoalBehaviour):
    """Turn-then-drive (A.10, fixed): :func:`turn_then_drive` every period.

    ``tolerance`` (m), ``heading_tolerance`` and ``align_tolerance`` (rad), ``speed``
    (m/s) and ``turn_rate`` (rad/s) as there; the defaults are A.10's (0.5 m, 0.3 rad,
    no hysteresis). :attr:`state` is the machine's state after the latest period.
    ``rate_hz`` (Hz) how often it decides (A.10 ran at 2 Hz; default every period).
    """

    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator,
                 tolerance: float = 0.5, heading_tolerance: float = 0.3,
                 speed: float = 0.5, turn_rate: float = 0.5,
                 align_tolerance: float | None = None, rate_hz: float = LOOP_RATE_HZ):
        super().__init__(goal, estimator, tolerance, rate_hz)
        self.heading_tolerance = positive_number("heading_tolerance", heading_tolerance, "rad")
        align = heading_tolerance if align_tolerance is None else align_tolerance
        self.align_tolerance = positive_number("align_tolerance", align, "rad")
        if self.align_tolerance > self.heading_tolerance:
            raise ValueError(f"align_tolerance {align!r} rad must not exceed "
                             f"heading_tolerance {heading_tolerance!r} rad")
        self.speed = positive_number("speed", speed, "m/s")
        self.turn_rate = positive_number("turn_rate", turn_rate, "rad/s")
        self.state = TURN

    def update(self, frame: SensorFrame) -> Twist:
        command = super().update(frame)
        if self.rho <= self.tolerance:
            self.state = REACHED
        return command

    def reset(self) -> None:
        """Start over from :data:`TURN`."""
        super().reset()
        self.state = TURN

    def command(self, rho: float, alpha: float) -> Twist:
        self.state, twist = turn_then_drive(
            self.state, rho, alpha, tolerance=self.tolerance,
            heading_tolerance=self.heading_tolerance, align_tolerance=self.align_tolerance,
            speed=self.speed, turn_rate=self.turn_rate)
        return twist


class GoToLandmark(GoalBehaviour):
    """Proportional go-to-goal with speed, turn-rate and braking limits.

    :func:`proportional_command` every period: ``k_rho`` (1/s), ``k_alpha`` (1/s);
    ``max_speed`` (m/s), ``max_turn_rate`` (rad/s), ``decel`` (m/s^2) the braking the
    chair can count on (its motors lag ~0.3 s). Succeeds (stops for good) within
    ``tolerance`` (m). ``rate_hz`` (Hz) how often it decides (default every period).
    """

    def __init__(self, goal: tuple[float, float], estimator: PoseEstimator,
                 tolerance: float = 0.1, max_speed: float = 0.8, max_turn_rate: float = 0.8,
                 k_rho: float = 0.8, k_alpha: float = 1.5, decel: float = 0.5,
                 rate_hz: float = LOOP_RATE_HZ):
        super().__init__(goal, estimator, tolerance, rate_hz)
        self.max_speed = positive_number("max_speed", max_speed, "m/s")
        self.max_turn_rate = positive_number("max_turn_rate", max_turn_rate, "rad/s")
        self.k_rho = positive_number("k_rho", k_rho, "1/s")
        self.k_alpha = positive_number("k_alpha", k_alpha, "1/s")
        self.decel = positive_number("decel", decel, "m/s^2")

    def command(self, rho: float, alpha: float) -> Twist:
        return proportional_command(rho, alpha, k_rho=self.k_rho, k_alpha=self.k_alpha,
                                    max_speed=self.max_speed,
                                    max_turn_rate=self.max_turn_rate, decel=self.decel)
