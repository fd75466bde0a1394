"""Where the chair is on the map, without ground truth: the EKF corrected by scan matching.

move_base needs the chair's pose in the map frame. amcl gives it in ROS; here the
chapter 10 filter (:class:`~abcwc.estimation.ekf.ChairEkf`: wheel odometry, the gyro
and its bias) does the dead reckoning at 50 Hz, and every ``match_interval`` s a lidar
scan is laid on the map's occupied cells by point-to-line ICP
(:func:`abcwc.mapping.icp.icp`), started from the filter's estimate. The match is an
absolute fix of the pose with ICP's covariance (Bengtsson and Baerveldt 2003) plus a
floor of ``fix_floor`` standard deviations (that covariance is optimistic), and enters
the filter as chapter 10's fixes did, after two checks:

* the match must be good: at least ``min_fitness`` of the scan's points paired with a
  wall, their rms point-to-line distance at most ``max_rms`` (people and furniture not
  on the map are the unpaired rest);
* the fix must agree with the filter: its Mahalanobis distance
  ``d^2 = e^T (P + R)^-1 e`` below the chi-square 99.9 % point for 3 degrees of
  freedom (16.27), so one bad match cannot drag the estimate away.

A refused scan is not yet evidence that the estimate is wrong: a person standing by
the chair hides most of the walls, and the few returns left fit badly. What a wrong
estimate produces, and occlusion cannot, is a beam that reaches *past* a wall of the map
(the beam model's lesson: short returns are explained by things not on the map, long
ones are not; Thrun, Burgard and Fox, *Probabilistic Robotics*, 6.3). Only refused
scans with more than ``see_through`` of their beams passing through the map's walls,
and at least :data:`MIN_RETURNS` of them, count towards :attr:`MapLocalizer.lost`. In
the middle of a hall whose walls are beyond the lidar's reach a scan has a handful of
returns (a pillar's), too few to match and too few to be such evidence: one of eight
grazing a pillar's mapped edge is not a wrong estimate. The filter dead-reckons on
until the walls come back into reach.

A corridor fixes the pose across it and not along it: ICP's covariance is long along
the corridor, and the filter takes from the fix only what it fixes.

When the estimate is lost (a push, a wheel slipping on a ramp: the scans stop fitting
where the filter says the chair is), :meth:`MapLocalizer.recover` searches a window of
poses round the estimate exhaustively with the correlative matcher (Olson 2009,
:func:`abcwc.mapping.correlative.correlative_match`) instead of ICP's local descent,
refines the best with ICP, and takes it only if the scan fits there well and the
search's covariance says the place is unambiguous: amcl's global localisation, over a
window instead of the whole map.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.estimation.ekf import ChairEkf, EkfEstimator
from abcwc.geometry import transform_points, wrap_angle
from abcwc.mapping.correlative import LikelihoodField, correlative_match
from abcwc.mapping.grid import OCCUPIED, GridGeometry
from abcwc.mapping.icp import IcpTarget, TooFewPairsError, icp
from abcwc.mapping.raytrace import walk_cells
from abcwc.params import ChairParams, default_params
from abcwc.types import LIDAR_FRAME, LaserScan, Pose2D, SensorFrame

GATE_CHI2_3DOF = 16.27
"""The chi-square distribution's 99.9 % point for 3 degrees of freedom."""
MIN_RETURNS = 10
"""Returns a scan needs to be matched, and beams through the map's walls a refused scan
needs to count as evidence that the estimate is wrong (module notes)."""


def occupied_points(cells: np.ndarray, grid: GridGeometry) -> np.ndarray:
    """(N, 2) map-frame centres (m) of the ``OCCUPIED`` cells of a trinary map on ``grid``
    (a built map: its walls known to half a cell)."""
    rows, cols = np.nonzero(np.asarray(cells) == OCCUPIED)
    return grid.cell_to_world(rows, cols)


def wall_points(walls: np.ndarray, spacing: float = 0.05) -> np.ndarray:
    """(N, 2) points (m) every ``spacing`` m or closer along wall segments ((K, 4): x1 y1
    x2 y2), ends included (a world's own walls, known exactly)."""
    walls = np.asarray(walls, dtype=float).reshape(-1, 4)
    if not (math.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a finite number > 0 m, got {spacing!r}")
    lengths = np.hypot(walls[:, 2] - walls[:, 0], walls[:, 3] - walls[:, 1])
    steps = np.maximum(np.ceil(lengths / spacing).astype(int), 1)
    wall = np.repeat(np.arange(len(walls)), steps + 1)
    fraction = np.concatenate([np.linspace(0.0, 1.0, n + 1) for n in steps])
    start, end = walls[wall, :2], walls[wall, 2:]
    return start + fraction[:, None] * (end - start)


class MapLocalizer:
    """The chair's map pose from the EKF and scan-to-map matches (module notes).

    ``map_points`` (N, 2, m) are the map's occupied cell centres
    (:func:`occupied_points`) or its walls (:func:`wall_points`); ``ekf`` the filter,
    started at the chair's pose with UMBmark's correction and wheel base and the gyro's
    bias prior as chapter 10 builds it (default: nominal odometry from ``start``, known
    to 5 cm and 0.02 rad). Call :meth:`observe` with every frame.

    A scan that fits the map well (``fitness >= 0.8``, ``rms <= 0.02`` m) but fails the
    gate ``relocalise_after`` times in a row means the filter, not the scan, is wrong (a
    heading error it is too sure of): the pose is then reset to the match, as amcl's
    recovery re-seeds its particles, and :attr:`relocalisations` counts it.
    """

    def __init__(self, map_points: np.ndarray, start: Pose2D,
                 params: ChairParams | None = None, *, ekf: ChairEkf | None = None,
                 scan_frame: str = LIDAR_FRAME, match_interval: float = 0.5,
                 min_fitness: float = 0.5, max_rms: float = 0.05,
                 max_correspondence_distance: float = 0.3,
                 fix_floor: tuple[float, float, float] = (0.02, 0.02, 0.01),
                 relocalise_after: int = 5, lost_after: int = 30,
                 see_through: float = 0.1):
        self.params = p = params or default_params()
        if not 0.0 < see_through < 1.0:
            raise ValueError(f"see_through must be a fraction in (0, 1), got {see_through!r}")
        self.see_through = float(see_through)
        self.replace_map(map_points)
        self.ekf = ekf or ChairEkf(start, p, start_std=(0.05, 0.05, 0.02))
        scanners = [name for name, spec in p.sensors.items() if getattr(spec, "beams", 1) > 1]
        if scan_frame not in scanners:
            raise ValueError(f"scan_frame must be a scanner's frame id ({', '.join(scanners)}),"
                             f" got {scan_frame!r}")
        self.scan_frame = scan_frame
        self.mount = p.sensors[scan_frame].mount  # type: ignore[union-attr]
        if not (math.isfinite(match_interval) and match_interval >= 0):
            raise ValueError(f"match_interval must be a finite number >= 0 s, "
                             f"got {match_interval!r}")
        self.match_interval = float(match_interval)
        self.min_fitness, self.max_rms = float(min_fitness), float(max_rms)
        self.max_correspondence_distance = float(max_correspondence_distance)
        self.fix_floor = np.diag(np.square(fix_floor))
        self.dead_reckoning = EkfEstimator(self.ekf)  # wheels and gyro, every frame
        self._last_stamp = -math.inf
        self._last_match = -math.inf
        self.lost_after = int(lost_after)
        self.relocalise_after = int(relocalise_after)
        self.relocalisations = 0
        self._disagreeing = 0
        self.accepted = 0
        self.rejected = 0
        self.rejected_in_a_row = 0

    def replace_map(self, map_points: np.ndarray) -> None:
        """Match scans against ``map_points`` (N, 2, m; N >= 3) from now on: a map that
        grows as the chair explores. The estimate is kept."""
        points = np.asarray(map_points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
            raise ValueError(f"map_points must be (N, 2) with N >= 3, got {points.shape}")
        self.target = IcpTarget.build(points)
        self._map_points = points
        self._field: LikelihoodField | None = None  # built on the first recovery
        lo, hi = points.min(axis=0) - 1.0, points.max(axis=0) + 1.0
        size = np.ceil((hi - lo) / 0.05).astype(int) + 1
        self._wall_grid = GridGeometry(0.05, int(size[0]), int(size[1]), (lo[0], lo[1], 0.0))
        self._walls = np.zeros(self._wall_grid.shape, dtype=bool)
        self._walls[self._wall_grid.world_to_cell(points)] = True

    # ------------------------------------------------------------------ estimate
    @property
    def pose(self) -> Pose2D:
        """The estimate of base_link in the map frame."""
        return self.ekf.pose

    @property
    def lost(self) -> bool:
        """True after ``lost_after`` scan matches in a row were refused with beams through
        the map's walls: the scans no longer fit the map where the estimate says the
        chair is."""
        return self.rejected_in_a_row >= self.lost_after

    @property
    def covariance(self) -> np.ndarray:
        """3 x 3 covariance (m^2, m rad, rad^2) of :attr:`pose`."""
        return self.ekf.filter.P[:3, :3].copy()

    @property
    def velocity(self) -> tuple[float, float]:
        """The estimated ``(v, w)`` (m/s, rad/s)."""
        x = self.ekf.filter.x
        return float(x[3]), float(x[4])

    # ------------------------------------------------------------------ per frame
    def observe(self, frame: SensorFrame) -> None:
        """Dead-reckon over the period that ended at ``frame``, then match its scan if a
        new one has come and ``match_interval`` has passed since the last match."""
        self.dead_reckoning.observe(frame)
        scan = frame.readings.get(self.scan_frame)
        if (isinstance(scan, LaserScan) and scan.stamp > self._last_stamp
                and frame.t - self._last_match >= self.match_interval - 1e-9):
            self._last_stamp = scan.stamp
            if self.match(scan):
                self._last_match = frame.t

    def match(self, scan: LaserScan) -> bool:
        """Lay ``scan`` on the map from the current estimate; True if the fix was taken."""
        points = transform_points(self.mount, scan.points())
        estimate = self.pose
        guess = np.array([estimate.x, estimate.y, estimate.theta])
        if len(points) < MIN_RETURNS:  # too few returns to match: walls out of reach
            return self._refuse(points, guess)
        try:
            result = icp(points, self.target, guess,
                         max_correspondence_distance=self.max_correspondence_distance,
                         max_iterations=20, tolerance=1e-4)
        except TooFewPairsError:
            return self._refuse(points, guess)
        if result.fitness < self.min_fitness or result.rms > self.max_rms:
            return self._refuse(points, guess)
        fix_cov = result.covariance + self.fix_floor
        error = result.pose - guess
        error[2] = wrap_angle(float(error[2]))
        innovation = self.covariance + fix_cov
        fix = Pose2D(*map(float, result.pose))
        if float(error @ np.linalg.solve(innovation, error)) > GATE_CHI2_3DOF:
            fits_well = result.fitness >= 0.8 and result.rms <= 0.02
            self._disagreeing = self._disagreeing + 1 if fits_well else 0
            if self._disagreeing < self.relocalise_after:
                return self._refuse(points, guess)
            self._relocalise(fix, fix_cov)
        else:
            self.ekf.update_pose(fix, fix_cov)
        self.accepted += 1
        self.rejected_in_a_row = self._disagreeing = 0
        return True

    def recover(self, scan: LaserScan, window_xy: float = 2.0,
                window_theta: float = math.radians(45.0),
                max_std: tuple[float, float] = (0.1, 0.05)) -> bool:
        """Search ``+-window_xy`` m and ``+-window_theta`` rad round the estimate for where
        ``scan`` fits the map (module notes); True, and the pose reset there, if the
        search's standard deviations are within ``max_std`` (m, rad: one place, not a
        corridor's many), the scan fits there as a fix must (``min_fitness``,
        ``max_rms``) and no more than ``see_through`` of its beams pass through a wall."""
        points = transform_points(self.mount, scan.points())
        if len(points) < MIN_RETURNS:
            return False
        if self._field is None:
            self._field = LikelihoodField(self._map_points, resolution=0.05, sigma=0.05,
                                          margin=1.0)
        estimate = self.pose
        found = correlative_match(points, self._field, (estimate.x, estimate.y,
                                                        estimate.theta),
                                  window_xy=window_xy, window_theta=window_theta,
                                  angle_step=math.radians(1.0))
        std = np.sqrt(np.clip(np.diag(found.covariance), 0.0, None))
        if std[0] > max_std[0] or std[1] > max_std[0] or std[2] > max_std[1]:
            return False
        try:
            result = icp(points, self.target, found.pose,
                         max_correspondence_distance=self.max_correspondence_distance,
                         max_iterations=30, tolerance=1e-4)
        except TooFewPairsError:
            return False
        if (result.fitness < self.min_fitness or result.rms > self.max_rms
                or self.see_through_fraction(points, result.pose) > self.see_through):
            return False
        self._relocalise(Pose2D(*map(float, result.pose)), result.covariance + self.fix_floor)
        self.rejected_in_a_row = self._disagreeing = 0
        return True

    def _relocalise(self, fix: Pose2D, fix_cov: np.ndarray) -> None:
        """Put the pose at ``fix`` with covariance ``fix_cov``, its correlations with
        the other states dropped; velocity and gyro bias keep their estimates."""
        self.ekf.reset_pose(fix, fix_cov)
        self.relocalisations += 1

    def see_through_fraction(self, points: np.ndarray, pose: np.ndarray) -> float:
        """The fraction of a scan's beams (``points``, base_link, m) that, from ``pose``,
        pass through a wall of the map on their way to their return (the last 0.15 m
        before it left out: the wall the beam hit)."""
        through = self.beams_through_walls(points, pose)
        return float(through.mean()) if len(through) else 0.0

    def beams_through_walls(self, points: np.ndarray, pose: np.ndarray) -> np.ndarray:
        """(N,) bool: which of a scan's beams (``points``, base_link, m) pass through a
        wall of the map from ``pose`` (:meth:`see_through_fraction`)."""
        if not len(points):
            return np.zeros(0, dtype=bool)
        origin = transform_points(pose, np.asarray(self.mount[:2], dtype=float))
        ends = transform_points(pose, points)
        length = np.hypot(*(ends - origin).T)
        short = origin + (ends - origin) * (np.maximum(length - 0.15, 0.0) / np.maximum(
            length, 1e-9))[:, None]
        grid = self._wall_grid
        walk = walk_cells(np.broadcast_to(grid.to_cell_units(origin), short.shape),
                          grid.to_cell_units(short))
        inside = grid.contains(walk.row, walk.col)
        hit = np.zeros(len(walk.row), dtype=bool)
        hit[inside] = self._walls[walk.row[inside], walk.col[inside]]
        through = np.zeros(len(points), dtype=bool)
        through[walk.segment[hit]] = True
        return through

    def _refuse(self, points: np.ndarray, guess: np.ndarray) -> bool:
        """A refused scan; it counts towards :attr:`lost` only if its beams go through the
        map's walls from the estimate (module notes)."""
        self.rejected += 1
        through = self.beams_through_walls(points, guess)
        if through.sum() >= MIN_RETURNS and through.mean() > self.see_through:
            self.rejected_in_a_row += 1
        return False
