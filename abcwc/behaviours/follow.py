"""Follow a person who wears a tag: keep about a metre behind them, along their way.

The thesis's follower (4.3.3, appendix A.13) drove on the *change* of the tag's
position between two frames, ``v = 1000 (z_prev - z)``, ``w = 1000 (x_prev - x)``: a
person standing still gives no command at all, however far away, and one frame's noise
of a millimetre is a command of 1 m/s. :class:`ThesisFollower` is that law, kept to be
measured. :class:`TagFollower` is the one to use:

**Seeing.** Each new camera image (10 Hz), the ArUco marker of the person's
:class:`~abcwc.perception.tags.FollowCard` is found and its pose solved
(:func:`~abcwc.perception.tags.square_pose`); a marker under ``min_marker_px`` across
gives too poor a range to use (within 2 % from 20 px across, 6 % at 15 px). Its
centre goes from the optical frame to base_link through the camera's mount, and to the
odom frame through the chair's own odometry (wheels and gyro: a pose estimator,
``observe(frame)`` then ``pose``).

**Tracking.** The tag says *who*; the lidar says *where*, ten times a second, also when
the card on the person's back has turned too far from the camera to be read (round a
corner) or is out of the camera's 57 degrees. The person's centre (the tag's point
pushed ``person_radius`` m on along the line of sight; or a lidar person candidate, a
compact blob's mean pushed ``2 r / pi`` away from the sensor, where a half disc's arc has
its centroid) feeds an alpha-beta filter of position and velocity in the odom frame, as
:class:`~abcwc.navigation.people.PeopleTracker` tracks people. Lidar candidates are
taken only while the tag was read within ``trust_lidar_for`` s (it is the tag that
names the person), and only through the
:class:`~abcwc.behaviours.follow_identity.IdentityGate`: the one candidate within
``gate`` m of the prediction whose update keeps the track under ``max_person_speed``
(two inside the gate: neither; the track coasts until the tag is read). A tag read more
than ``gate`` m from the track means the track was on someone else: it starts again
from the tag. Once another walking person has come within ``gate`` m and a person's
width of her track, or once her track, updated from the lidar alone, runs back the way
it came (its velocity more than 120 degrees from the one ``turn_back_within`` s before:
two people crossing in a doorway, the one coming back hiding her, swap blobs that way),
the lidar is not trusted again until the tag is read, and a track that turned back goes
back to its old prediction and coasts. A track that has coasted (no update for
``lost_after`` s) is taken up again by the lidar only from a blob that walks (an
others' track that has moved ``walked`` m): a door's frame or a wall's corner is a
compact blob too, and one near a coasting guess would lead the track off along the
walls. Each update adds the track's point to the
person's :class:`~abcwc.behaviours.follow_trail.Trail`.

**The way she went.** Where the straight way from the chair's axle to her is clear of
the scan's returns by the chair's half width and ``clear_of_line`` m, the chair aims at
her (below). Where it is not (she has turned through a door, round a corner or a table),
it steers along her trail instead: for the farthest trail point the straight way to
which is clear (or, if the way to it is clear too, the first one ``lookahead`` m beyond
the trail's point nearest the axle: a chair that has come off her trail would otherwise
aim beside or behind itself and turn away from her), the gap measured along that way
and the trail beyond it, and no faster
than lets it turn the trail's corner at that point (:meth:`TagFollower._corner_speed`);
so it goes through a door where she did instead of cutting across its frame to her, and
wherever a door lies on her trail ahead (below) it keeps to her trail even while she is
in plain view: aimed at her, it would cut her corner and come to the door aslant.
Otherwise the aim changes between her and the trail only after the way has been clear (or not) for
``settle`` decisions running (meanwhile, on the trail, it pursues the trail point
``lookahead`` m ahead): a way at the edge of clear would switch the aim, and the turn,
to and fro with the scan's noise. **Door mode**: where her trail, anywhere between the
chair and her, goes through a gap in the scan narrower than ``door_width``
(:meth:`TagFollower._door_ahead`), the chair slows to be at ``door_speed`` by
``door_approach`` m before the gap's middle, its reaction time counted
(:meth:`TagFollower.door_speed_cap`): whoever comes out of a door is hidden behind its
wall, or behind her, until the chair is nearly there. From there, on her trail, it
pursues the gap's axis instead, lined up before it enters, as the navigator's door
mode does.

**Range and bearing.** With ``range`` and ``alpha`` the person's distance and bearing
from the chair's camera::

    v = min(v_person + k_gap gap, v_person + v_stop(gap), max_speed) * max(cos alpha, 0)
    w = clip(k_turn alpha, -max_turn_rate, max_turn_rate)

``v_person`` (how fast the person draws away along the line of sight, m/s, from the
track's velocity; never negative) is the feed-forward: without it a proportional law
keeps ``v_person / k_gap`` m more than ``distance`` behind a walking person (0.5 m at
0.7 m/s with ``k_gap`` 1.5); with their whole speed instead, a person turning across
the chair's way would be run up to. The turn is proportional, not A.13's derivative nor a
fixed rate, so it eases off as the person comes ahead and does not swing past:
with ``gap = range - distance`` and ``v_stop`` the speed from which the chair stops in
``gap`` at ``braking`` after its reaction time ``T`` (the safety filter's: sensing,
command delay and the wheels' lag), ``v T + v^2 / (2 braking) = gap``. Without that cap
a chair closing on a standing person from 2.5 m overshoots to 0.5 m.
``k_turn`` 1.5 1/s with the camera's 0.1 s is well inside the loop's margin (a pure
delay ``T`` allows ``k < pi / (2 T)``, 15.7 1/s).

**Lost.** With neither the tag nor the lidar on the person for ``lost_after`` s the
chair drives on along her trail to where she was last seen and on towards where she
would be by now (the track moved on at its last velocity, for at most ``predict_for``
s); once there, or after ``seek_for`` s, it turns on the spot at ``search_turn_rate``
towards the side where she would be by now, walking on at her last velocity
(:meth:`TagFollower._side_of_her`: she walked on past where the chair lost her), and
fails, "lost", after a full turn (counted from the odometry's heading: the turn made,
not the turn asked for) or after twice the time a full turn takes.

**Obstacles.** Every wanted command is checked against a local costmap built from the
newest lidar scan (``local_size`` m square round the chair, in base_link): the DWA
planner's footprint check over the window of commands reachable in one cycle. If the
wanted command's arc is not clear, the clear one nearest to it is sent (speeds scaled
by their limits), never a faster one than was asked for (a turn on the spot asked for
is not answered by driving off); with none, the chair stops. The person is in the scan too, so the
chair never drives into them. Other people are tracked in the scan too (a
:class:`~abcwc.navigation.people.PeopleTracker` without a map: compact blobs, their
velocities from an alpha-beta filter; a blob counts as a person once it has moved
``walked`` m, for without a map a door frame's end is a compact blob too). People are
judged by whether their motion and the chair's can meet, as the navigator's DWA judges
them: a command must leave the chair able to stop clear of where each person *ahead of
its front* will be within ``people_horizon`` s
(:meth:`~abcwc.navigation.dwa.DwaPlanner.people_gap`), so a passer-by crossing in front
is waited for, not met; a chair that only drives forward meets someone beside or
behind it only by turning or backing into them, so those are judged where they stand,
and someone walking up from behind is someone to keep ahead of, not a block. What the
body's :class:`~abcwc.control.safety.SafetyFilter` will stop for is foreseen with its
:class:`~abcwc.control.safety.ClearanceCheck`, and the window of commands is centred on
what the chair is driven at now, read from the frame's pot bytes
(:func:`~abcwc.control.velocity.pot_command_to_twist`: after the filter's ramp, ahead
of the wheels' lag); every command then passes the filter in the control loop.

**Recovery.** Asked to move but left only standing (no clear command, or the nearest
clear one is a stop) for ``patience`` s, the chair backs off ``back_off_distance`` m at
``back_off_speed`` (measured by the odometry), while the range sensors behind, the
costmap and everyone's predicted way (people behind as they walk, here) leave room,
then tries again: the navigator's back-off recovery, for a chair wedged in a doorway.
When someone other than her stands ahead of the axle within a person's width of the
chair (:meth:`TagFollower._someone_in_the_way`: at a door, someone coming out whom the
chair blocks, and who waits for it), it backs off ``give_way`` m instead, out of the
door's mouth, so that they can pass.

**Hand-over.** Blocked (or backing off) for ``hand_over_after`` s, counted while the
chair has not moved ``progress`` m, the chair hands over to the navigator
(:mod:`abcwc.behaviours.follow_handover`): a :class:`~abcwc.behaviours.navigator.
Navigator` on the map of everything its scans have seen (people left out), sent to her
last-seen point, or the nearest point back along her trail it can stand on, to find a
way round with its plan, door mode and recoveries. The follower takes over again when
the tag is read with the straight way to her clear, or when the navigator is there
(then, if she is not in sight, it looks for her as when lost) or has failed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from abcwc.behaviours.base import BehaviourBase, Status
from abcwc.behaviours.follow_handover import HandOver
from abcwc.behaviours.follow_identity import IdentityGate
from abcwc.behaviours.follow_trail import Trail
from abcwc.control.safety import ClearanceCheck
from abcwc.control.velocity import pot_command_to_twist
from abcwc.estimation.estimator import PoseEstimator
from abcwc.geometry import compose, rotation_matrix, transform_points, wrap_angle
from abcwc.navigation.costmap import FREE_SPACE, Costmap, chair_footprint
from abcwc.navigation.dwa import DwaPlanner
from abcwc.navigation.people import PeopleTracker, standing_still
from abcwc.params import ChairParams, default_params, load_navigation_params
from abcwc.perception.camera import PinholeCamera
from abcwc.perception.tags import MIN_POSE_SIDE_PX, FollowCard, find_marker
from abcwc.types import (
    CAMERA_FRAME,
    LIDAR_FRAME,
    CameraImage,
    LaserScan,
    Pose2D,
    PotCommand,
    SensorFrame,
    Twist,
)

FollowLaw = Callable[[float, float, float], tuple[float, float]]
"""``law(gap, bearing, receding) -> (v, w)``: a follow law (m, rad, m/s -> m/s, rad/s)."""


@dataclass(frozen=True)
class FollowSettings:
    """The follower's gains and limits (SI units; module notes for the laws)."""

    distance: float = 1.0  # m kept behind the person, along their way
    k_gap: float = 1.5  # 1/s
    k_turn: float = 1.5  # 1/s
    max_speed: float = 1.0  # m/s: the safety filter's cap for a seated person
    max_turn_rate: float = 0.8  # rad/s
    braking: float = 0.4  # m/s^2 planned (the safety filter's ramp allows 0.8, with lag)
    lost_after: float = 0.5  # s without a sighting
    predict_for: float = 2.0  # s the person's last velocity is trusted
    seek_for: float = 5.0  # s for the drive to where the person was last seen
    search_turn_rate: float = 0.5  # rad/s
    min_marker_px: float = MIN_POSE_SIDE_PX  # px across: narrower markers range poorly
    person_radius: float = 0.25  # m from a person's back to their centre
    gate: float = 0.5  # m round the predicted centre where lidar returns are the person's
    max_extent: float = 0.7  # m: a blob wider than this is not a person
    alpha: float = 0.5  # the track's position gain
    beta: float = 0.2  # the track's velocity gain
    trust_lidar_for: float = 10.0  # s after the tag was last read
    max_person_speed: float = 1.6  # m/s: a lidar update faster than this is someone else
    clear_of_line: float = 0.15  # m the straight way to her must be clear beside the chair
    settle: int = 3  # decisions the way must stay clear (or not) to change the aim
    lookahead: float = 0.5  # m from the axle to the point on the trail steered for
    trail_spacing: float = 0.1  # m between the trail's points
    door_width: float = 1.2  # m: a gap on her trail narrower than this is a door
    door_approach: float = 0.8  # m before a door's middle from which the chair is on its axis
    door_speed: float = 0.4  # m/s at most in door mode
    patience: float = 1.0  # s blocked before backing off
    back_off_distance: float = 0.3  # m
    back_off_speed: float = 0.2  # m/s
    give_way: float = 1.0  # m backed off when someone else stands in the way
    hand_over_after: float = 3.0  # s blocked, the chair not ``progress`` m on: navigator
    progress: float = 0.3  # m the chair must move for its blocked time to start again
    map_reach: float = 25.0  # m each way from the first scan that its map covers
    people_horizon: float = 2.0  # s others' paths are predicted for
    people_margin: float = 0.1  # m kept from others' predicted discs
    walked: float = 0.5  # m a blob must move to count as a walking person
    split_speed: float = 0.4  # m/s: a blob this fast by her, not hers, is someone else
    turn_back_within: float = 1.0  # s: a track reversing within this is on someone else
    local_size: float = 5.0  # m, the local costmap's side
    padding: float = 0.05  # m round the footprint in the obstacle check


@dataclass(frozen=True)
class Sighting:
    """The person seen at ``t`` s: ``position`` (x, y), the middle of their card in the
    odom frame, and the marker's ``range`` (m) and ``bearing`` (rad) from the camera."""

    t: float
    position: tuple[float, float]
    range: float
    bearing: float


class TagFollower(BehaviourBase):
    """Follow whoever wears ``card`` (module notes), with the chair's ``estimator`` for
    the odom frame; ``law`` replaces :meth:`range_and_bearing` (its output is still
    limited, checked against obstacles and people, and filtered). ``sightings`` keeps
    every sighting and ``log`` one row per decision (t, range or NaN, bearing or NaN, v,
    w, state) for plots."""

    def __init__(self, card: FollowCard, estimator: PoseEstimator,
                 params: ChairParams | None = None, settings: FollowSettings | None = None,
                 law: FollowLaw | None = None):
        super().__init__(rate_hz=10.0)
        self.law: FollowLaw = law or self.range_and_bearing
        self.card = card
        self.estimator = estimator
        self.params = p = params or default_params()
        self.settings = s = settings or FollowSettings()
        for name in ("distance", "k_gap", "k_turn", "max_speed", "max_turn_rate",
                     "lost_after", "predict_for", "search_turn_rate", "local_size", "seek_for",
                     "braking", "lookahead", "trail_spacing", "patience",
                     "back_off_distance", "back_off_speed", "door_width", "door_approach",
                     "door_speed", "hand_over_after", "progress", "map_reach"):
            value = getattr(s, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        self.stopping = ClearanceCheck(p)  # what the body's safety filter will stop for
        nav = load_navigation_params()
        local = replace(nav.local_planner, max_vel_x=s.max_speed, min_vel_x=0.0,
                        max_vel_theta=s.max_turn_rate, vx_samples=8, vtheta_samples=21)
        self.planner = DwaPlanner(chair_footprint(p), nav, local, padding=s.padding,
                                  braking_delay=self.stopping.reaction_time)
        if not (isinstance(s.settle, int) and s.settle >= 1):
            raise ValueError(f"settle must be a whole number of decisions >= 1, got "
                             f"{s.settle!r}")
        self.identity = IdentityGate(s.gate, s.max_person_speed)
        self.front = float(np.asarray(p.footprint, dtype=float)[:, 0].max())  # m, base_link
        self.reset()

    def reset(self) -> None:
        super().reset()
        self.pose = Pose2D()
        self.sightings: list[Sighting] = []
        self.log: list[tuple[float, float, float, float, float, str]] = []
        self.state = "searching"
        self._last_image = -math.inf
        self._search_turned, self._searching = 0.0, False
        self._search_heading: float | None = None  # the odometry's heading last decision
        self._search_since = -math.inf
        self.trail = Trail(self.settings.trail_spacing)  # where the person walked (odom)
        self.refused: dict[str, int] = {}  # lidar candidates the identity gate refused, why
        self._blocked_since: float | None = None
        self._scan_points: np.ndarray | None = None  # the newest scan's returns (odom)
        self._on_trail = False  # steering along her trail (not straight at her)
        self.door: tuple[np.ndarray, np.ndarray] | None = None  # (middle, axis) ahead
        self.lining_up = False  # door mode: on the door's axis
        self._unsettled = 0  # decisions running the way's state has disagreed with that
        self._first_seen: dict[int, np.ndarray] = {}  # others' tracks: where first seen
        self._hers: int | None = None  # the others' track her lidar updates last matched
        self._doubted = False  # someone else came near her since the tag was last read
        self._history: list[tuple[float, np.ndarray, np.ndarray]] = []  # (t, track, velocity)
        # (since, from, how far) while backing off
        self._backing: tuple[float, Pose2D, float] | None = None
        self.track: np.ndarray | None = None  # the person's centre (odom, m)
        self.velocity = np.zeros(2)  # m/s
        self._t = self._updated = self._tag_read = -math.inf
        self._last_scan = -math.inf
        self._side = 1.0  # the way the search turns (+1 left), set as it starts
        self.others = PeopleTracker(None, None, max_extent=self.settings.max_extent,
                                    person_radius=self.settings.person_radius)
        self.driven_at = Twist(0.0, 0.0)  # what the pots drive the chair at, each decision
        self.hand_over = HandOver(self.params, self.settings.map_reach)
        self._progress: tuple[float, float, float] | None = None  # t, x, y last moved on
        self._blocked_for = 0.0  # s blocked since then
        self._masked: tuple[float, float, LaserScan] | None = None  # (stamp, t, scan)

    # ---------------------------------------------------------------- every frame
    def observe(self, frame: SensorFrame) -> None:
        self.estimator.observe(frame)
        self.pose = self.estimator.pose
        if self.running:
            self.hand_over.observe(frame)  # the navigator, while handed over

    # ---------------------------------------------------------------- 10 Hz
    def update(self, frame: SensorFrame) -> Twist:
        self.driven_at = pot_command_to_twist(PotCommand(frame.pot_fb, frame.pot_lr),
                                              self.params)
        s = self.settings
        self._predict(frame.t)
        image = frame.readings.get(CAMERA_FRAME)
        seen = None
        if isinstance(image, CameraImage) and image.stamp > self._last_image:
            self._last_image = image.stamp
            seen = self._look(image)
        measured = []
        named = None  # the person's centre where the tag puts it
        if seen is not None:
            self.sightings.append(seen)
            named = self._centre_behind(seen.position)
            if self.track is None or np.hypot(*(named - self.track)) > s.gate:
                self._start_again_from(named)
            measured.append(named)
            self._tag_read = frame.t
            self._doubted = False
        scan = frame.readings.get(LIDAR_FRAME)
        new_scan = None
        if isinstance(scan, LaserScan) and scan.stamp > self._last_scan:
            self._last_scan = scan.stamp
            sensor = compose(self.pose, Pose2D(*self.params.lidar.mount))
            self.others.update(scan, sensor, scan.stamp)
            self._scan_points = transform_points(sensor, scan.points())
            new_scan = scan
            if self.track is not None and frame.t - self._tag_read <= s.trust_lidar_for:
                centre = self._lidar_centre(scan, named, frame.t)
                if centre is not None:
                    measured.append(centre)
        if measured:  # one update a decision: two sources apart would fake a velocity
            self._measured(frame.t, np.mean(measured, axis=0))
            if seen is None and self._turned_back(frame.t):
                self._doubted = True  # the lidar's blob is someone else's: coast
            else:
                self.trail.add(self.track)
        if len(self.trail):
            self.trail.passed((self.pose.x, self.pose.y))
        if new_scan is not None:  # into the map the navigator is handed (people out)
            self.hand_over.lay(self._without_people(new_scan, frame.t),
                               compose(self.pose, Pose2D(*self.params.lidar.mount)))
        if self.hand_over.active:
            command = self._handed_over(frame, seen is not None)
            if command is not None:
                self.log.append((frame.t, seen.range if seen else math.nan,
                                 seen.bearing if seen else math.nan, command.v, command.w,
                                 self.state))
                return command
        if self.track is None:
            wanted = self._search(frame, 1.0)
        elif frame.t - self._updated <= s.lost_after:
            self.state = "following"
            self._search_turned, self._searching, self._search_heading = 0.0, False, None
            wanted = self._pursue(self.track, self.velocity, s.distance)
        elif not self._searching and frame.t - self._updated <= s.lost_after + s.seek_for:
            # along the trail to where she was last seen, and on to where she would be
            # by now at her last velocity (for at most predict_for s)
            self.state = "going to where the person was last seen"
            wanted = self._pursue(self.track, self.velocity, s.distance)
            self._searching = wanted.v <= 0.02 and abs(wanted.w) <= 0.05  # there: look
        else:
            if self._search_heading is None:  # the search starts
                self._side = self._side_of_her(frame.t)
            self._searching = True
            wanted = self._search(frame, self._side)
        command = self._clear_of_obstacles(frame, wanted)
        if self._stuck(frame.t):
            command = self._hand_over(frame)
        self.log.append((frame.t, seen.range if seen else math.nan,
                         seen.bearing if seen else math.nan, command.v, command.w, self.state))
        return command

    def _look(self, image: CameraImage) -> Sighting | None:
        """The person's marker in ``image``, as a sighting (None if not seen, or too
        small to range)."""
        found = find_marker(image.pixels, self.card.marker_id, self.card.side,
                            PinholeCamera.of_image(image))
        if found is None or found[0].side_px < self.settings.min_marker_px:
            return None
        tag = found[1]  # on the card's middle line: over the floor, the card's middle
        # optical (x right, z ahead) -> the camera's floor frame (x ahead, y left)
        in_base = compose(Pose2D(*self.params.depth_scan.mount),
                          Pose2D(tag.position[2], -tag.position[0], 0.0))
        in_odom = compose(self.pose, in_base)
        return Sighting(image.stamp, (in_odom.x, in_odom.y), tag.range, tag.bearing)

    def _camera(self) -> Pose2D:
        return compose(self.pose, Pose2D(*self.params.depth_scan.mount))

    def _centre_behind(self, point: tuple[float, float]) -> np.ndarray:
        """A person's centre ``person_radius`` m beyond ``point`` (on their near side)
        along the camera's line of sight."""
        camera = self._camera()
        away = np.array([point[0] - camera.x, point[1] - camera.y])
        away /= max(float(np.hypot(*away)), 1e-9)
        return np.asarray(point) + self.settings.person_radius * away

    def _start_again_from(self, named: np.ndarray) -> None:
        """The tag names her at ``named`` (odom, m) more than ``gate`` from her track (or
        there is no track yet): the track was on someone else, or lagged; it starts again
        from the tag, and the trail, which may be someone else's, is forgotten."""
        self.track, self.velocity = np.asarray(named, dtype=float), np.zeros(2)
        self._history = []
        self._updated = -math.inf
        self.trail.clear()

    def _lidar_centre(self, scan: LaserScan, named: np.ndarray | None, now: float
                      ) -> np.ndarray | None:
        """The person's centre from the lidar (module notes): the one person candidate
        the identity gate lets through round the tag's point ``named`` (when the tag
        was read in this decision) or round the track's prediction; None if none is
        (the reason counted in :attr:`refused`)."""
        assert self.track is not None
        sensor = compose(self.pose, Pose2D(*self.params.lidar.mount))
        candidates = self.others.detect(scan, sensor)
        s = self.settings
        # round the tag's point it is her (no speed to judge); round the prediction,
        # only at a walking person's speed, and only with no one else walking near
        around, dt = (named, 0.0) if named is not None else (self.track, now - self._updated)
        if named is None and self._someone_else_near():
            self.refused["someone else near"] = self.refused.get("someone else near", 0) + 1
            return None
        if dt > s.lost_after:
            # her track has coasted: a blob near its guess is hers only if it walks (a
            # door's frame or a wall's corner is a compact blob too, and would lead the
            # track off through the walls)
            candidates = candidates[self._walking_blobs(candidates)]
        chosen, why = self.identity.choose(candidates, around, self.velocity, dt, s.beta)
        if chosen is not None:  # the others' track on the same blob is hers
            tracks = self.others.tracks
            gaps = [float(np.hypot(*(t.position - chosen))) for t in tracks]
            self._hers = (tracks[int(np.argmin(gaps))].track_id
                          if gaps and min(gaps) <= s.gate else None)
        if chosen is None and why == "none near" and dt <= s.lost_after:
            # her returns run into a door's frame (one blob too wide for a person): the
            # returns within a person's reach of the point, if they are compact
            chosen, why = self.identity.choose(self._near_returns(scan, sensor, around),
                                               around, self.velocity, dt, s.beta)
        if chosen is None:
            self.refused[why] = self.refused.get(why, 0) + 1
        return chosen

    def _walking_blobs(self, candidates: np.ndarray) -> np.ndarray:
        """(K,) whether each candidate (K, 2) is on an others' track that has walked
        (:meth:`_walked`)."""
        walked = self._walked()[:, :2]
        if not len(walked) or not len(candidates):
            return np.zeros(len(candidates), dtype=bool)
        gaps = np.hypot(*(candidates[:, None, :] - walked[None]).transpose(2, 0, 1))
        return gaps.min(axis=1) <= self.settings.gate

    def _someone_else_near(self) -> bool:
        """Whether someone else has come near her since the tag was last read: a
        walking person other than her (an other's track that has walked, or is
        walking at ``split_speed`` or more, not the one her lidar updates last matched,
        :attr:`_hers`) within ``gate`` m plus a
        person's width of her track. Once one has, the lidar alone cannot tell which of
        the two walked on as her (crossing in a doorway, one hides the other, and the
        blob that comes out may be his), so it is not trusted again until the tag names
        her (:attr:`_doubted`, cleared in :meth:`update`)."""
        s = self.settings
        if self._doubted:
            return True
        if self.track is None:
            return False
        for track, walked in zip(self.others.tracks, self._walked_mask()):
            # or walking off now (a blob that splits from hers as two part)
            walking = (track.hits >= self.others.confirm
                       and np.hypot(*track.velocity) >= s.split_speed)
            if ((walked or walking) and track.track_id != self._hers
                    and np.hypot(*(track.position - self.track)) <= s.gate
                    + 2 * s.person_radius):
                self._doubted = True
        return self._doubted

    def _near_returns(self, scan: LaserScan, sensor: Pose2D, around: np.ndarray
                      ) -> np.ndarray:
        """(0 or 1, 2): the centre of the returns within ``person_radius + 0.15`` m of
        ``around``, pushed ``2 r / pi`` away from the sensor, if there are at least three
        and they span at most ``2 person_radius`` m."""
        s = self.settings
        points = transform_points(sensor, scan.points())
        near = points[np.hypot(*(points - around).T) <= s.person_radius + 0.15]
        if len(near) < 3 or np.ptp(near, axis=0).max() > 2 * s.person_radius:
            return np.zeros((0, 2))
        mean = near.mean(axis=0)
        away = mean - (sensor.x, sensor.y)
        away /= max(float(np.hypot(*away)), 1e-9)
        return (mean + away * 2 * s.person_radius / math.pi).reshape(1, 2)

    def _predict(self, now: float) -> None:
        """Move the track on at its velocity (for at most ``predict_for`` s unseen)."""
        s = self.settings
        if self.track is not None and now - self._updated <= s.lost_after + s.predict_for:
            self.track = self.track + self.velocity * (now - self._t)
        self._t = now

    def _measured(self, now: float, centre: np.ndarray) -> None:
        """Alpha-beta update of the track with a measured ``centre`` (module notes)."""
        s = self.settings
        assert self.track is not None
        residual = centre - self.track
        self.track = self.track + s.alpha * residual
        if math.isfinite(self._updated) and now > self._updated:
            self.velocity = self.velocity + s.beta / (now - self._updated) * residual
        self._updated = now
        self._history = [h for h in self._history if now - h[0] <= s.turn_back_within]
        self._history.append((now, self.track.copy(), self.velocity.copy()))

    def _turned_back(self, now: float) -> bool:
        """Whether the track, updated from the lidar alone, now runs back the way it
        came (its velocity more than 120 degrees from the one ``turn_back_within`` s
        ago, both at a walk): two people crossing in a doorway, the one coming back
        hiding her, swap blobs that way, and a person who turns round stands first
        (and turns her tag to the chair). If so, the track goes back to the older
        state, moved on at its velocity, and coasts (the identity gate's third rule)."""
        s = self.settings
        t0, track0, velocity0 = self._history[0]
        speeds = math.hypot(*velocity0) * math.hypot(*self.velocity)
        if now - t0 < s.turn_back_within / 2 or speeds < 0.3 ** 2:
            return False
        if float(velocity0 @ self.velocity) > -0.5 * speeds:
            return False
        self.track = track0 + velocity0 * (now - t0)
        self.velocity = velocity0.copy()
        self._history = [(now, self.track.copy(), self.velocity.copy())]
        return True

    def _pursue(self, target: np.ndarray, velocity: np.ndarray, distance: float) -> Twist:
        """The follow law along the trail to ``target`` (odom, m; the person's centre,
        moving at ``velocity`` m/s), keeping ``distance`` m (module notes): aimed at her
        from the camera when the way to her is clear, else at the farthest trail point
        the way to which is, the gap measured along that way."""
        s = self.settings
        camera = self._camera()
        target = np.asarray(target, dtype=float)
        carrot, along = self._carrot(target)
        if self.lining_up:  # door mode: along its axis
            origin = (self.pose.x, self.pose.y, self.pose.theta)
            cap = s.door_speed
        elif carrot is target:  # in plain view: the line of sight, as ever
            origin = (camera.x, camera.y, camera.theta)
            cap = math.inf
        else:
            origin = (self.pose.x, self.pose.y, self.pose.theta)
            along -= math.hypot(camera.x - self.pose.x, camera.y - self.pose.y)
            cap = self._corner_speed(carrot)
        if self.door is not None:  # slow enough to be at door_speed by the approach
            cap = min(cap, self.door_speed_cap(
                math.hypot(*(self.door[0] - (self.pose.x, self.pose.y)))))
        dx, dy = carrot[0] - origin[0], carrot[1] - origin[1]
        reach = max(math.hypot(dx, dy), 1e-9)
        bearing = wrap_angle(math.atan2(dy, dx) - origin[2])
        receding = max(float(velocity[0] * dx + velocity[1] * dy) / reach, 0.0)
        v, w = self.law(along - s.person_radius - distance, bearing, receding)
        if not (math.isfinite(v) and math.isfinite(w)):
            raise ValueError(f"the follow law gave ({v!r}, {w!r}): it must give finite "
                             "(v m/s, w rad/s)")
        return Twist(min(max(float(v), 0.0), s.max_speed, cap),
                     min(max(float(w), -s.max_turn_rate), s.max_turn_rate))

    def door_speed_cap(self, to_door: float) -> float:
        """m/s: the fastest the chair may be sent with its axle ``to_door`` m from a
        door's middle and still be at ``door_speed`` by ``door_approach`` m before it:
        the command takes the safety filter's reaction time ``T`` to act (sensing,
        command delay, the wheels' lag) and then slows at ``braking`` ``b``, so, over
        the ``d = to_door - door_approach`` m left, ``v T + (v^2 - door_speed^2) /
        (2 b) = d``: ``v = -b T + sqrt((b T)^2 + 2 b d + door_speed^2)``. Someone
        coming out of the door, unseen behind its wall (or behind her) until then, is
        met at a speed the chair can stop from."""
        s = self.settings
        b, lag = s.braking, self.stopping.reaction_time
        room = max(to_door - s.door_approach, 0.0)
        return max(s.door_speed, -b * lag + math.sqrt((b * lag) ** 2 + 2 * b * room
                                                       + s.door_speed ** 2))

    def _carrot(self, target: np.ndarray) -> tuple[np.ndarray, float]:
        """The point to steer for and the length (m) of the way to ``target`` through
        it: ``target`` itself and the camera's distance to it while the straight way
        from the axle is clear (:meth:`_clear_ways`); else the last trail point before
        the first one the way to which is not, and the way's length from the axle
        (module notes: the aim changes after ``settle`` decisions)."""
        camera = self._camera()
        straight = math.hypot(target[0] - camera.x, target[1] - camera.y)
        self.door, self.lining_up = None, False
        if not len(self.trail):
            return target, straight
        pivot = np.array([self.pose.x, self.pose.y])
        ahead = np.vstack([self.trail.ahead_of((pivot[0], pivot[1])), target])
        # the aim changes between her and the trail only when the straight way has been
        # clear (or not) for ``settle`` decisions running: a way at the edge of clear
        # would switch the aim to and fro with the scan's noise, and the turn with it
        clear = self._clear_ways(pivot, ahead)
        if clear.all() == self._on_trail:
            self._unsettled += 1
            if self._unsettled >= self.settings.settle:
                self._on_trail, self._unsettled = not self._on_trail, 0
        else:
            self._unsettled = 0
        s = self.settings
        self.door = self._door_ahead(pivot, ahead)  # for the speed, in view of her or not
        if self.door is not None and not self._on_trail:
            # a door on her way: along her trail even in view of her (aimed at her, the
            # chair cuts her corner and comes to the door aslant, to wedge in its mouth)
            self._on_trail, self._unsettled = True, 0
        if not self._on_trail:
            return target, straight
        if self.door is not None and math.hypot(*(pivot - self.door[0])) <= (
                s.door_approach + s.lookahead):  # door mode: along the door's axis
            self.lining_up = True
            middle, axis = self.door
            at = float((pivot - middle) @ axis)  # m along the axis (negative: before it)
            on = min(max(at + s.lookahead, -s.door_approach), s.door_approach)
            return middle + on * axis, self.trail.length_from((float(pivot[0]),
                                                                float(pivot[1])), to=target)
        if clear.all():  # on the trail a moment longer: pure pursuit along it
            at = (float(pivot[0]), float(pivot[1]))
            off = float(math.hypot(*(ahead[0] - pivot)))
            return (self.trail.carrot(at, self.settings.lookahead + off),
                    self.trail.length_from(at, to=target))
        k = max(int(np.argmin(clear)) - 1, 0)
        # never a point nearer than the lookahead beyond the trail's nearest point (a
        # chair off her trail would aim beside or behind itself, away from her)
        reach = np.hypot(*(ahead - pivot).T)
        far = reach >= self.settings.lookahead + reach[0]
        if far.any() and clear[int(np.argmax(far))]:
            k = max(k, int(np.argmax(far)))
        steps = float(np.hypot(*np.diff(ahead[k:], axis=0).T).sum())
        return ahead[k], float(math.hypot(*(ahead[k] - pivot))) + steps

    def _door_ahead(self, pivot: np.ndarray, ahead: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray] | None:
        """Door mode (the navigator's, :meth:`~abcwc.behaviours.navigator.Navigator.
        _through_doors`, on the scan): the first gap narrower than ``door_width`` that
        the trail ``ahead`` (odom, m, from the point nearest the axle ``pivot``, up to
        her) goes through, as ``(middle, axis)``: the middle between the two nearest
        returns either side of the trail there (within 0.3 m along it), and the unit way
        through, at right angles to the line between them; None where there is none,
        or once the axle is ``lookahead`` m past the middle. From ``door_approach +
        lookahead`` m of the middle, pure pursuit on that axis lines the chair up
        before it enters, as a person pushing a wheelchair does, where aiming at the
        farthest point in view beyond the door would take the frame's corner."""
        s = self.settings
        if self._scan_points is None or len(ahead) < 2:
            return None
        path = ahead  # all of it, up to her: a door found late is met too fast
        reach = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
        tangent = np.gradient(path, axis=0)
        tangent /= np.maximum(np.hypot(*tangent.T), 1e-9)[:, None]
        points = self._scan_points
        if self.track is not None:  # her own returns (she may stand in the door)
            points = points[np.hypot(*(points - self.track).T) > s.person_radius + 0.1]
        near = np.hypot(*(points - pivot).T) <= reach[len(path) - 1] + s.door_width
        points = points[near]
        if not len(points):
            return None
        rel = points[None, :, :] - path[:, None, :]  # (K, P, 2)
        along = (rel * tangent[:, None, :]).sum(axis=2)
        across = rel[..., 1] * tangent[:, None, 0] - rel[..., 0] * tangent[:, None, 1]
        beside = np.abs(along) < 0.3  # the nearest return each side, not ahead or behind
        distance = np.hypot(along, across)
        left = np.where(beside & (across > 0), distance, np.inf)
        right = np.where(beside & (across < 0), distance, np.inf)
        width = left.min(axis=1) + right.min(axis=1)
        doors = np.flatnonzero(width < s.door_width)
        if not len(doors):
            return None
        run = doors[:np.argmax(np.diff(np.append(doors, doors[-1] + 2)) > 1) + 1]
        k = int(run[np.argmin(width[run])])
        left_end = points[int(np.argmin(left[k]))]
        right_end = points[int(np.argmin(right[k]))]
        middle = (left_end + right_end) / 2
        across_line = left_end - right_end
        axis = np.array([-across_line[1], across_line[0]]) / max(
            float(np.hypot(*across_line)), 1e-9)
        if axis @ tangent[k] < 0:
            axis = -axis
        return None if float((pivot - middle) @ axis) > s.lookahead else (middle, axis)

    def _clear_ways(self, start: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """(K,) whether the straight way from ``start`` to each of ``ends`` (odom, m)
        is clear of the newest scan's returns by the chair's half width and
        ``clear_of_line`` m (returns within ``gate`` of the track, hers, left out; the
        last ``person_radius + 0.1`` m of each way, where she stands, not judged)."""
        s = self.settings
        if self._scan_points is None or not len(self._scan_points):
            return np.ones(len(ends), dtype=bool)
        points = self._scan_points
        if self.track is not None:
            points = points[np.hypot(*(points - self.track).T) > s.gate]
        way = ends - start  # (K, 2)
        length = np.maximum(np.hypot(*way.T), 1e-9)
        unit = way / length[:, None]
        rel = points - start  # (P, 2)
        along = rel @ unit.T  # (P, K)
        across = np.abs(rel @ np.column_stack([-unit[:, 1], unit[:, 0]]).T)
        half = float(np.abs(np.asarray(self.params.footprint, dtype=float)[:, 1]).max())
        in_the_way = ((along > -0.2) & (along < length - self.settings.person_radius - 0.1)
                      & (across < half + s.clear_of_line))
        return ~in_the_way.any(axis=0)

    def _corner_speed(self, carrot: np.ndarray) -> float:
        """m/s: the fastest the chair may go towards ``carrot`` (a trail point short of
        her) and still slow, at ``braking``, to the speed at which it can turn the
        corner there: the way on from the carrot turns by ``phi`` from the way to it,
        and pure pursuit's turn rate for a goal at ``phi`` is ``w = 2 v sin(phi) / L``
        (Coulter 1992) with ``L`` the ``lookahead``, so ``max_turn_rate`` holds it to
        ``v_c = max_turn_rate L / (2 sin phi)`` (the curvature limit of the regulated
        pure pursuit: Macenski et al., "Regulated pure pursuit for robot path
        tracking", Autonomous Robots 47, 2023); the carrot ``d`` m away, less ``L``,
        allows ``sqrt(v_c^2 + 2 braking d)``."""
        s = self.settings
        pivot = np.array([self.pose.x, self.pose.y])
        ahead = self.trail.ahead_of((float(carrot[0]), float(carrot[1])))
        if len(ahead) < 2:
            return math.inf
        beyond = ahead[min(len(ahead) - 1, max(1, round(s.lookahead / s.trail_spacing)))]
        to, on = carrot - pivot, beyond - carrot
        phi = abs(wrap_angle(math.atan2(on[1], on[0]) - math.atan2(to[1], to[0])))
        corner = s.max_turn_rate * s.lookahead / (2 * math.sin(min(phi, math.pi / 2)) + 1e-9)
        room = max(float(math.hypot(*to)) - s.lookahead, 0.0)
        return math.sqrt(corner ** 2 + 2 * s.braking * room)

    def range_and_bearing(self, gap: float, bearing: float, receding: float
                          ) -> tuple[float, float]:
        """The follower's own law (module notes): ``(v, w)`` for a person ``gap`` m
        beyond the distance to keep, at ``bearing`` rad, drawing away at ``receding``
        m/s."""
        s = self.settings
        # no faster than can still stop in the gap left, after the chair's reaction time
        # T: v T + v^2 / (2 b) = gap (plus what the person draws away meanwhile)
        b, lag = s.braking, self.stopping.reaction_time
        stoppable = receding - b * lag + math.sqrt((b * lag) ** 2 + 2 * b * max(gap, 0.0))
        v = min(receding + s.k_gap * gap, stoppable) * max(math.cos(bearing), 0.0)
        return v, s.k_turn * bearing

    def _side_of_her(self, now: float) -> float:
        """+1 (left) or -1 (right): the side of the camera where she would be by now,
        walking on at her last velocity from where she was last seen (the track itself
        moved on for ``lost_after + predict_for`` s; on from there for as long as the
        follower went to look for her): she walked on past where the chair lost her."""
        s = self.settings
        assert self.track is not None
        walked_on = min(now - self._updated, s.lost_after + s.seek_for)
        where = self.track + self.velocity * max(walked_on - s.lost_after - s.predict_for,
                                                 0.0)
        camera = self._camera()
        bearing = wrap_angle(math.atan2(where[1] - camera.y, where[0] - camera.x)
                             - camera.theta)
        return 1.0 if bearing >= 0 else -1.0

    def _search(self, frame: SensorFrame, side: float) -> Twist:
        """Turn on the spot towards ``side`` (+1 left, -1 right); fail after a full
        turn, the turn the odometry says was made (not the one asked for), or after
        twice the time a full turn takes, saying how far it got."""
        s = self.settings
        heading = self.pose.theta
        if self._search_heading is None:
            self._search_heading, self._search_since = heading, frame.t
        self._search_turned += abs(wrap_angle(heading - self._search_heading))
        self._search_heading = heading
        full = 2 * math.pi
        if self._search_turned >= full:
            self.fail(f"lost: no sight of the person for {frame.t - self._updated:.0f} s, "
                      "and a full turn did not find them")
            return Twist(0.0, 0.0)
        if frame.t - self._search_since > 2 * full / s.search_turn_rate:
            self.fail(f"lost: no sight of the person for {frame.t - self._updated:.0f} s; "
                      f"the search could turn only {math.degrees(self._search_turned):.0f} "
                      "degrees")
            return Twist(0.0, 0.0)
        self.state = "searching"
        return Twist(0.0, side * s.search_turn_rate)

    def _clear_of_obstacles(self, frame: SensorFrame, wanted: Twist) -> Twist:
        """``wanted`` if its arc is clear in the local costmap and of people, else the
        nearest clear command reachable in one cycle, else a stop; blocked for
        ``patience`` s, a back-off (module notes)."""
        scan = frame.readings.get(LIDAR_FRAME)
        if not isinstance(scan, LaserScan):
            return wanted
        s = self.settings
        ahead, alongside = self._people_in_base()
        # the person followed and the others walking are moving discs, judged as such
        # (below), not walls: their returns leave the map (as the navigator's do)
        scan = self._without_people(scan, frame.t)
        local = Costmap.rolling_window(Pose2D(), s.local_size, 0.05, default=FREE_SPACE)
        local.add_scan(scan, self.params.lidar.mount, obstacle_range=s.local_size / 2,
                       raytrace_range=s.local_size / 2)
        if self._backing is not None:
            return self._back_off(frame, local, ahead, alongside)
        # the pots' bytes read back a little above the speed limit they were rounded from
        moving = (min(self.driven_at.v, s.max_speed),
                  min(max(self.driven_at.w, -s.max_turn_rate), s.max_turn_rate))
        samples = np.vstack([[wanted.v, wanted.w], self.planner.window(moving)])
        samples[:, 0] = np.clip(samples[:, 0], 0.0, s.max_speed)
        # what the safety filter will let through: a range sensor seeing something
        # within braking distance ahead stops the wheels but not the turn, and a turn
        # on the spot sweeps the chair's corners where the arc did not
        gap, _ = self.stopping.clearance(frame, forward=True)
        stopped = gap <= np.array([self.stopping.braking_distance(max(v, moving[0]))
                                   for v in samples[:, 0]])
        samples[stopped, 0] = 0.0
        valid = self.planner.check(local, Pose2D(), samples).valid
        valid &= self._clear_of_people(samples, ahead, alongside)
        valid[1:] &= samples[1:, 0] <= wanted.v + 0.05  # never faster than asked
        if valid[0]:
            self._blocked_since = None
            return Twist(float(samples[0, 0]), float(samples[0, 1]))
        best = -1
        if valid.any():
            distance = np.hypot((samples[:, 0] - wanted.v) / s.max_speed,
                                (samples[:, 1] - wanted.w) / s.max_turn_rate)
            best = int(np.argmin(np.where(valid, distance, np.inf)))
        # wedged: asked to move, and the nearest clear command is to stand
        asked = wanted.v > 0.05 or abs(wanted.w) > 0.1
        standing = best < 0 or (abs(samples[best, 0]) < 0.02 and abs(samples[best, 1]) < 0.05)
        if asked and standing:
            self.state = "blocked"
            if self._blocked_since is None:
                self._blocked_since = frame.t
            elif frame.t - self._blocked_since >= s.patience:
                self._blocked_since = None
                distance = (s.give_way if self._someone_in_the_way()
                            else s.back_off_distance)
                self._backing = (frame.t, self.pose, distance)
                return self._back_off(frame, local, ahead, alongside)
        else:
            self._blocked_since = None
        if best < 0:
            return Twist(0.0, 0.0)
        return Twist(float(samples[best, 0]), float(samples[best, 1]))

    def _without_people(self, scan: LaserScan, now: float) -> LaserScan:
        """``scan`` with the returns of the people tracked left out (NaN): those within
        ``person_radius + 0.1`` m of an others' track that has walked, and those within
        ``gate`` of her track while it is fresh. They are moving discs, judged as such,
        not walls (as the navigator's people are). Worked out once a decision."""
        if self._masked is not None and self._masked[:2] == (scan.stamp, now):
            return self._masked[2]
        s = self.settings
        sensor = compose(self.pose, Pose2D(*self.params.lidar.mount))
        theirs = scan.hits()
        ends = transform_points(sensor, scan.points())
        walking = self._walked()[:, :2]
        if len(walking):
            theirs[theirs] = (np.hypot(*(ends[:, None, :] - walking[None]).transpose(2, 0, 1))
                              <= s.person_radius + 0.1).any(axis=1)
        else:
            theirs[:] = False
        if self.track is not None and self._updated >= now - s.lost_after:
            theirs[scan.hits()] |= np.hypot(*(ends - self.track).T) <= s.gate
        masked = replace(scan, ranges=np.where(theirs, np.nan, scan.ranges))
        self._masked = (scan.stamp, now, masked)
        return masked

    def _stuck(self, now: float) -> bool:
        """Whether the chair has been blocked or backing off for ``hand_over_after`` s
        (decisions counted) since it last moved ``progress`` m: her trail is blocked, and
        the navigator is to find a way round (:meth:`_hand_over`)."""
        s = self.settings
        here = (self.pose.x, self.pose.y)
        if self._progress is None or math.hypot(here[0] - self._progress[1],
                                                here[1] - self._progress[2]) >= s.progress:
            self._progress, self._blocked_for = (now, *here), 0.0
        if self.state in ("blocked", "backing off"):
            self._blocked_for += 1.0 / self.rate_hz
        return self.track is not None and self._blocked_for >= s.hand_over_after

    def _hand_over(self, frame: SensorFrame) -> Twist:
        """Hand over to the navigator (:class:`~abcwc.behaviours.follow_handover.
        HandOver`), to her last-seen point, or failing that the first of her trail's
        points back from there, more than ``distance`` m from the chair, that it can
        stand on; a stop while it starts (its first command comes with the next
        frame)."""
        assert self.track is not None
        s = self.settings
        self._progress, self._blocked_for = None, 0.0
        pivot = np.array([self.pose.x, self.pose.y])
        back = self.trail.ahead_of((float(pivot[0]), float(pivot[1])))[::-1]
        goals = np.vstack([self.track[None], back.reshape(-1, 2)])
        goals = goals[np.hypot(*(goals - pivot).T) > s.distance]
        if self.hand_over.start(frame.t, self.pose, goals) is not None:
            return Twist(0.0, 0.0)  # no way to hand over: the follower's own recovery
        self._backing, self._blocked_since = None, None
        self.state = "navigating to where she was last seen"
        return Twist(0.0, 0.0)

    def _handed_over(self, frame: SensorFrame, seen: bool) -> Twist | None:
        """While handed over: the navigator's command, or None once the follower takes
        over again: the tag read with the straight way to her clear, or the navigator
        done (there, or failed: then the follower looks for her as when lost)."""
        assert self.track is not None
        pivot = np.array([self.pose.x, self.pose.y])
        if seen and self._clear_ways(pivot, self.track[None])[0]:
            self.hand_over.end(frame.t, "she was seen with the way to her clear")
            return None
        status = self.hand_over.status
        if status is Status.SUCCEEDED:
            self.hand_over.end(frame.t, "reached")
            return None
        if status is Status.FAILED:
            self.hand_over.end(frame.t, f"failed: {self.hand_over.failure}")
            return None
        self.state = "navigating to where she was last seen"
        return self.hand_over.command

    def _clear_of_people(self, samples: np.ndarray, ahead: np.ndarray,
                         alongside: np.ndarray) -> np.ndarray:
        """(S,) whether each command leaves the chair able to stop clear of the people
        ``ahead`` (moving discs, predicted) and does not turn or drive into those
        ``alongside`` or behind (where they stand: module notes)."""
        s = self.settings
        valid = np.ones(len(samples), dtype=bool)
        for discs in (ahead, standing_still(alongside)):
            if not len(discs):
                continue
            # someone already nearer than the margin (walking past close by): a command
            # that takes the chair no nearer is no worse than standing
            now = float(self.planner.people_gap(Pose2D(), np.zeros((1, 2)), discs, 0.0)[0])
            valid &= self.planner.people_gap(Pose2D(), samples, discs, s.people_horizon
                                             ) > min(s.people_margin, now) - 1e-3
        return valid

    def _back_off(self, frame: SensorFrame, local: Costmap, ahead: np.ndarray,
                  alongside: np.ndarray) -> Twist:
        """Reverse ``back_off_distance`` m (``give_way`` m when someone else stands in
        the way: :meth:`_someone_in_the_way`), measured by the odometry, at
        ``back_off_speed`` while the range sensors behind, the costmap (the way must not
        take the chair nearer to what it sees) and everyone's predicted way (people
        behind as they walk, here) leave room; else stop and wait."""
        assert self._backing is not None
        s = self.settings
        since, start, distance = self._backing
        moved = math.hypot(self.pose.x - start.x, self.pose.y - start.y)
        behind, _ = self.stopping.clearance(frame, forward=False)
        back = np.array([[-s.back_off_speed, 0.0]])
        people = np.vstack([ahead, alongside]).reshape(-1, 5)
        room = (behind > self.stopping.braking_distance(s.back_off_speed)
                + min(distance - moved, s.back_off_distance)
                and self._gets_away(local, back)
                and (not len(people) or self.planner.people_gap(
                    Pose2D(), back, people, s.people_horizon)[0] > s.people_margin))
        limit = 3 * distance / s.back_off_speed
        if not room or moved >= distance or frame.t - since > limit:
            self._backing = None
            return Twist(0.0, 0.0)
        self.state = "backing off"
        return Twist(-s.back_off_speed, 0.0)

    def _someone_in_the_way(self) -> bool:
        """Whether someone other than her (:meth:`_others`) stands ahead of the axle
        within a person's width (``2 person_radius``) of the chair's outline: at a
        door, someone coming out whom the chair blocks, and who cannot pass until it
        has backed out of the door's mouth."""
        s = self.settings
        people = self._to_base(self._others())
        people = people[people[:, 0] > 0.0]
        if not len(people):
            return False
        outline = np.asarray(self.params.footprint, dtype=float)
        nearest = np.column_stack([
            np.clip(people[:, 0], outline[:, 0].min(), outline[:, 0].max()),
            np.clip(people[:, 1], outline[:, 1].min(), outline[:, 1].max())])
        gaps = np.hypot(*(people[:, :2] - nearest).T) - people[:, 4]
        return bool(np.any(gaps < 2 * s.person_radius))

    def _gets_away(self, local: Costmap, sample: np.ndarray) -> bool:
        """Whether the chair's arc for ``sample`` ((1, 2): v, w) is clear in ``local``,
        or, wedged already nearer than the footprint check allows, at least never
        brings the footprint's covering circles nearer to what it touches."""
        check = self.planner.check(local, Pose2D(), sample)
        if check.valid[0]:
            return True
        nearest = check.clearance.min(axis=0)[0]  # (T + 1,): the nearest circle, per pose
        return bool(np.all(nearest >= nearest[0] - 1e-9) and nearest[-1] > nearest[0])

    def _walked_mask(self) -> np.ndarray:
        """(M,) for each of the others' tracks, whether it has walked ``walked`` m or
        more from where it was first seen (noted here): without a map, the end of a
        wall at a door is a compact blob too, and its track drifts a little as the chair
        moves round it; someone standing is in the scan, and so in the costmap."""
        for track in self.others.tracks:
            self._first_seen.setdefault(track.track_id, track.position.copy())
        return np.array([np.hypot(*(track.position - self._first_seen[track.track_id]))
                         >= self.settings.walked for track in self.others.tracks],
                        dtype=bool)

    def _walked(self) -> np.ndarray:
        """(M, 5) the moving discs of the others' tracks that have walked
        (:meth:`_walked_mask`)."""
        discs = self.others.moving_discs()
        return discs[self._walked_mask()] if len(discs) else discs

    def _others(self) -> np.ndarray:
        """(M, 5) DWA's moving discs (x, y, vx, vy, radius; odom) of the others who
        have walked (:meth:`_walked`), hers left out: the one nearest her track, within
        ``gate`` of it."""
        discs = self._walked()
        if self.track is not None and len(discs):
            gaps = np.hypot(*(discs[:, :2] - self.track).T)
            discs = discs[(gaps > self.settings.gate)
                          | (np.arange(len(discs)) != np.argmin(gaps))]
        return discs

    def _to_base(self, discs: np.ndarray) -> np.ndarray:
        """Moving discs (M, 5) from the odom frame to base_link."""
        if not len(discs):
            return np.zeros((0, 5))
        rotation = rotation_matrix(self.pose.theta)  # x R = R^T x: odom -> base_link
        position = (discs[:, :2] - (self.pose.x, self.pose.y)) @ rotation
        return np.column_stack([position, discs[:, 2:4] @ rotation, discs[:, 4]])

    def _people_in_base(self) -> tuple[np.ndarray, np.ndarray]:
        """Two (M, 5) arrays of DWA's moving discs (x, y, vx, vy, radius) in base_link:
        the people whose centre is ahead of the chair's front (the one followed, from
        the track, and the others tracked in the scan), and those beside or behind it.
        """
        s = self.settings
        discs = self._others()
        if self.track is not None and self._updated >= self._t - s.lost_after:
            discs = np.vstack([discs.reshape(-1, 5),
                               [*self.track, *self.velocity, s.person_radius]])
        discs = self._to_base(discs)
        in_front = discs[:, 0] > self.front
        return discs[in_front], discs[~in_front]


class ThesisFollower(BehaviourBase):
    """Appendix A.13's follower, to be measured against :class:`TagFollower`: at 10 Hz,
    while the tag is seen, ``v = 1000 (z_prev - z)`` and ``w = 1000 (x_prev - x)`` from
    the tag's position in the optical frame (m) in two successive images; a stop while
    it is not. (A.13 subscribes to ViSP's tracker; here the same marker pose.) Its
    commands pass the body's safety filter like every other: the chair is not let drive
    at whatever the law asks."""

    def __init__(self, card: FollowCard, params: ChairParams | None = None):
        super().__init__(rate_hz=10.0)
        self.card = card
        self.params = params or default_params()
        self.reset()

    def reset(self) -> None:
        super().reset()
        self._previous: np.ndarray | None = None
        self._last_image = -math.inf
        self.log: list[tuple[float, float, float, float, float, str]] = []

    def update(self, frame: SensorFrame) -> Twist:
        image = frame.readings.get(CAMERA_FRAME)
        if not isinstance(image, CameraImage) or image.stamp <= self._last_image:
            return self._last_command if isinstance(self._last_command, Twist) else Twist(0, 0)
        self._last_image = image.stamp
        found = find_marker(image.pixels, self.card.marker_id, self.card.side,
                            PinholeCamera.of_image(image))
        if found is None:
            self._previous = None
            self.log.append((frame.t, math.nan, math.nan, 0.0, 0.0, "searching"))
            return Twist(0.0, 0.0)
        tag = found[1]
        previous, self._previous = self._previous, tag.position
        if previous is None:
            command = Twist(0.0, 0.0)
        else:
            command = Twist(1000.0 * (previous[2] - tag.position[2]),
                            1000.0 * (previous[0] - tag.position[0]))
        self.log.append((frame.t, tag.range, tag.bearing, command.v, command.w, "following"))
        return command


__all__ = ["FollowLaw", "FollowSettings", "Sighting", "TagFollower", "ThesisFollower"]
