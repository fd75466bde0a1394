"""People in the lidar scan: what the map does not explain, grouped, tracked, predicted.

A person walking down a corridor does not wait for the chair, and a chair that only
avoids where a person *is* steps into where they *will be*. Each scan:

1. **Unexplained returns.** A return more than ``unexplained`` m from every wall of the
   static map (one lookup in the map's distance transform) belongs to something the map
   does not hold.
2. **Clusters.** Unexplained returns closer than ``cluster_gap`` m to a neighbour form
   one object (single-linkage clustering, :func:`scipy.cluster.hierarchy.fcluster`); an
   object of at least ``min_points`` returns and at most ``max_extent`` m across is a
   person candidate. Without a map, a wall's piece is compact too (the end of a wall
   at a door, partly hidden by someone walking through it): a cluster of at least
   ``STRAIGHT_MIN_POINTS`` returns over ``STRAIGHT_MIN_EXTENT`` m or more, all within
   ``STRAIGHT_TOLERANCE`` of its extent of one line (a total least-squares fit), is a
   straight piece of wall, not a person, whose visible arc bows 0.05-0.1 m from its
   chord. The lidar sees the near half of a person's disc of radius ``r``,
   whose arc's centroid lies ``2 r / pi`` in front of the centre, so the centre is put
   that far behind the returns' mean, away from the sensor.
3. **Tracks.** Each candidate joins the nearest track predicted within ``gate`` m
   (global nearest neighbour, greedily by distance), else starts one. A track's
   position and velocity follow an alpha-beta filter (Benedict and Bordner, "Synthesis
   of an optimal set of radar track-while-scan smoothing equations", IRE Trans.
   Automatic Control 7(4), 1962)::

       predicted = x + v dt;   r = z - predicted
       x = predicted + alpha r;   v = v + (beta / dt) r

   A track unseen for ``max_age`` s is dropped; a track's velocity is trusted once it
   has been seen ``confirm`` times.

:meth:`PeopleTracker.moving_discs` gives the tracks as ``(x, y, vx, vy, radius)`` rows,
what the DWA planner needs to keep its trajectories out of people's way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.cluster.hierarchy import fcluster, linkage

from abcwc.geometry import PoseLike, transform_points
from abcwc.mapping.grid import GridGeometry
from abcwc.types import LaserScan

STRAIGHT_MIN_POINTS = 4
"""Returns a cluster needs before it can be judged straight (three always fit a line
within the scan's noise)."""
STRAIGHT_MIN_EXTENT = 0.25
"""m: a cluster this wide or wider can be judged straight (a person's arc at 5 m is
0.3-0.5 m wide)."""
STRAIGHT_TOLERANCE = 0.03
"""The largest distance of a return from the cluster's line, as a share of its extent,
for it to be a piece of wall: measured in the building follow trial, wall pieces lie
within 1-13 mm of their line over 0.30-0.58 m (at most 2.2 %), people's arcs 50-105 mm
from it over 0.36-0.45 m (at least 14 %)."""

WALKING = 0.3
"""m/s: a confirmed track once this fast is a person walking (a post the map lacks
never is; a slow person may not be either, and is then treated as a post)."""


@dataclass
class PersonTrack:
    """One tracked person: ``position`` and ``velocity`` (m, m/s, map frame)."""

    track_id: int
    position: np.ndarray
    velocity: np.ndarray
    last_seen: float  # s
    hits: int = 1
    walked: bool = False  # confirmed and once faster than WALKING m/s: a person, not a post


def is_straight(points: np.ndarray) -> bool:
    """Whether a cluster of lidar returns ``points`` (N, 2; m) is a straight piece of
    wall (module notes): at least ``STRAIGHT_MIN_POINTS`` returns spanning at least
    ``STRAIGHT_MIN_EXTENT`` m, each within ``STRAIGHT_TOLERANCE`` times that span of the
    total least-squares line through them (its normal, the direction of least spread:
    the last right singular vector of the centred points)."""
    points = np.asarray(points, dtype=float)
    if len(points) < STRAIGHT_MIN_POINTS:
        return False
    extent = float(np.ptp(points, axis=0).max())
    if extent < STRAIGHT_MIN_EXTENT:
        return False
    centred = points - points.mean(axis=0)
    normal = np.linalg.svd(centred, full_matrices=False)[2][-1]
    return bool(np.abs(centred @ normal).max() <= STRAIGHT_TOLERANCE * extent)


class PeopleTracker:
    """Track moving objects the static map does not explain (module notes).

    ``walls`` is a (height, width) bool array of the static map's wall cells on ``grid``;
    without a map (``walls`` and ``grid`` None) every return is unexplained, and only
    ``max_extent`` and a straight cluster's line (:func:`is_straight`) tell a person
    from a wall.
    """

    def __init__(self, walls: np.ndarray | None, grid: GridGeometry | None, *,
                 unexplained: float = 0.2,
                 cluster_gap: float = 0.3, min_points: int = 3, max_extent: float = 1.0,
                 person_radius: float = 0.25, gate: float = 0.6, alpha: float = 0.5,
                 beta: float = 0.2, max_age: float = 1.0, confirm: int = 3):
        self.grid = grid
        self.wall_distance: np.ndarray | None = None
        if walls is not None and grid is not None:
            walls = np.asarray(walls, dtype=bool)
            if walls.shape != grid.shape:
                raise ValueError(f"walls {walls.shape} must lie on the grid's {grid.shape} "
                                 "cells")
            self.wall_distance = ndimage.distance_transform_edt(~walls) * grid.resolution
        elif (walls is None) != (grid is None):
            raise ValueError("give both walls and grid, or neither (no map)")
        self.unexplained, self.cluster_gap = float(unexplained), float(cluster_gap)
        self.min_points, self.max_extent = int(min_points), float(max_extent)
        self.person_radius, self.gate = float(person_radius), float(gate)
        self.alpha, self.beta = float(alpha), float(beta)
        self.max_age, self.confirm = float(max_age), int(confirm)
        self.tracks: list[PersonTrack] = []
        self._next_id = 0
        self._t: float | None = None

    def detect(self, scan: LaserScan, sensor_pose: PoseLike) -> np.ndarray:
        """(K, 2) map-frame centres of the person candidates in one scan."""
        points = transform_points(sensor_pose, scan.points())
        if self.grid is not None and self.wall_distance is not None:
            rows, cols = self.grid.world_to_cell(points)
            on_map = self.grid.contains(rows, cols)
            distance = np.full(len(points), np.inf)
            distance[on_map] = self.wall_distance[rows[on_map], cols[on_map]]
            points = points[distance > self.unexplained]
        if len(points) < self.min_points:
            return np.zeros((0, 2))
        labels = (fcluster(linkage(points, method="single"), self.cluster_gap,
                           criterion="distance") if len(points) > 1 else np.ones(1, int))
        sensor = transform_points(sensor_pose, np.zeros(2))
        centres = []
        for label in np.unique(labels):
            members = points[labels == label]
            extent = np.ptp(members, axis=0).max() if len(members) > 1 else 0.0
            if len(members) < self.min_points or extent > self.max_extent:
                continue
            if self.wall_distance is None and is_straight(members):
                continue  # without a map: a piece of wall
            mean = members.mean(axis=0)
            away = (mean - sensor) / max(np.hypot(*(mean - sensor)), 1e-9)
            centres.append(mean + away * 2 * self.person_radius / math.pi)
        return np.array(centres).reshape(-1, 2)

    def update(self, scan: LaserScan, sensor_pose: PoseLike, t: float) -> list[PersonTrack]:
        """Detect, associate and filter one scan taken at ``t`` s; the live tracks."""
        dt = 0.0 if self._t is None else t - self._t
        if dt < 0:
            raise ValueError(f"scans must come in time order: {t} s after {self._t} s")
        self._t = t
        detections = self.detect(scan, sensor_pose)
        predicted = np.array([tr.position + tr.velocity * dt for tr in self.tracks]
                             ).reshape(-1, 2)
        taken_tracks: set[int] = set()
        taken_detections: set[int] = set()
        if len(predicted) and len(detections):
            gaps = np.hypot(*(predicted[:, None, :] - detections[None, :, :]).transpose(2, 0, 1))
            for flat in np.argsort(gaps, axis=None):
                k, j = divmod(int(flat), len(detections))
                if gaps[k, j] > self.gate:
                    break
                if k in taken_tracks or j in taken_detections:
                    continue
                taken_tracks.add(k)
                taken_detections.add(j)
                track = self.tracks[k]
                residual = detections[j] - predicted[k]
                track.position = predicted[k] + self.alpha * residual
                if dt > 0:
                    track.velocity = track.velocity + self.beta / dt * residual
                track.last_seen, track.hits = t, track.hits + 1
                track.walked |= (track.hits >= self.confirm
                                 and float(np.hypot(*track.velocity)) > WALKING)
        for k, track in enumerate(self.tracks):
            if k not in taken_tracks:
                track.position = predicted[k]
        for j, centre in enumerate(detections):
            if j not in taken_detections:
                self.tracks.append(PersonTrack(self._next_id, centre.copy(), np.zeros(2), t))
                self._next_id += 1
        self.tracks = [tr for tr in self.tracks if t - tr.last_seen <= self.max_age]
        return self.tracks

    def walkers(self) -> np.ndarray:
        """(W, 3): ``x, y, radius`` (m) of each live track that has walked (``WALKING``):
        people, as against unmapped things that stand still."""
        rows = [(*tr.position, self.person_radius) for tr in self.tracks if tr.walked]
        return np.array(rows, dtype=float).reshape(-1, 3)

    def moving_discs(self, walked_only: bool = False) -> np.ndarray:
        """(M, 5): each live track's ``x, y, vx, vy, radius`` (m, m/s); the velocity is
        zero until the track is confirmed. With ``walked_only``, only the tracks that
        have walked (:meth:`walkers`): the others are posts, left to the costmap."""
        rows = [(*tr.position, *(tr.velocity if tr.hits >= self.confirm else (0.0, 0.0)),
                 self.person_radius) for tr in self.tracks if tr.walked or not walked_only]
        return np.array(rows, dtype=float).reshape(-1, 5)


def standing_still(discs: np.ndarray) -> np.ndarray:
    """(M, 5): the moving discs (x, y, vx, vy, radius) as they would be if each person
    stopped where they are: a person who sees the chair in the way may do just that."""
    standing = np.array(discs, dtype=float).reshape(-1, 5)
    standing[:, 2:4] = 0.0
    return standing


def predicted_sweep(discs: np.ndarray, grid: GridGeometry, horizon: float,
                    min_speed: float = 0.2) -> np.ndarray:
    """(height, width) bool on ``grid``: the cells each moving disc ((M, 5): x, y, vx, vy,
    radius) covers as it walks on at its velocity for ``horizon`` s, a capsule from
    where it is to where it will be. Discs slower than ``min_speed`` m/s are left out
    (the scan already marks where they stand)."""
    swept = np.zeros(grid.shape, dtype=bool)
    for x, y, vx, vy, radius in np.asarray(discs, dtype=float).reshape(-1, 5):
        if math.hypot(vx, vy) < min_speed:
            continue
        start, end = np.array([x, y]), np.array([x + vx * horizon, y + vy * horizon])
        corners = np.array([np.minimum(start, end) - radius, np.maximum(start, end) + radius])
        rows, cols = grid.world_to_cell(corners)
        r0, r1 = np.clip(np.sort(rows), 0, grid.height - 1)
        c0, c1 = np.clip(np.sort(cols), 0, grid.width - 1)
        rr, cc = np.mgrid[r0:r1 + 1, c0:c1 + 1]
        centres = grid.cell_to_world(rr.ravel(), cc.ravel())
        along = end - start
        t = np.clip((centres - start) @ along / max(along @ along, 1e-12), 0.0, 1.0)
        near = np.hypot(*(centres - (start + t[:, None] * along)).T) <= radius
        swept[rr.ravel()[near], cc.ravel()[near]] = True
    return swept
