"""A frame tree: named coordinate frames and the transforms between them (tf2's job).

ROS REP 105 names a mobile base's frames ``map -> odom -> base_link``: ``odom`` is where
the wheel odometry started (continuous, drifting), ``map`` the world's fixed frame (a
localiser publishes ``map -> odom`` so that ``map -> base_link`` is its estimate without
the odometry ever jumping). Below ``base_link`` hang the sensors' frames, fixed by the
robot's description (:mod:`abcwc.description`).

Each edge holds the child frame's pose in its parent as a 4 x 4 homogeneous transform
``T``: a point ``p`` given in the child frame is ``T @ p`` in the parent. A lookup walks
both frames up to their common ancestor, as tf2's ``lookupTransform(target, source)``
does::

    tree = FrameTree.from_description(chair_description())
    tree.set_pose("map", "odom", Pose2D(0, 0, 0))
    tree.set_pose("odom", "base_link", odometry_pose)
    points_in_map = tree.transform_points(scan.points(), "lidar_link", "map")
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.description import RobotDescription
from abcwc.types import Pose2D


class FrameError(LookupError):
    """A frame that is not in the tree, or two frames with no path between them."""


def _xyt(pose: Pose2D | tuple[float, float, float]) -> tuple[float, float, float]:
    values = (pose.x, pose.y, pose.theta) if isinstance(pose, Pose2D) else tuple(pose)
    if len(values) != 3 or not all(math.isfinite(float(v)) for v in values):
        raise ValueError(f"a pose is (x, y, theta) of finite numbers, got {pose!r}")
    return float(values[0]), float(values[1]), float(values[2])


def planar_transform(pose: Pose2D | tuple[float, float, float]) -> np.ndarray:
    """4 x 4 transform of a pose in the plane: ``(x, y, theta)`` (m, m, rad), z up."""
    x, y, theta = _xyt(pose)
    c, s = math.cos(theta), math.sin(theta)
    transform = np.eye(4)
    transform[:2, :2] = [[c, -s], [s, c]]
    transform[:2, 3] = (x, y)
    return transform


def transform_to_pose(transform: np.ndarray) -> Pose2D:
    """The plane pose ``(x, y, yaw)`` of a 4 x 4 transform (its z and tilt dropped)."""
    return Pose2D(float(transform[0, 3]), float(transform[1, 3]),
                  float(math.atan2(transform[1, 0], transform[0, 0])))


class FrameTree:
    """Frames joined by transforms, each frame with at most one parent."""

    def __init__(self) -> None:
        self._parent: dict[str, str] = {}
        self._to_parent: dict[str, np.ndarray] = {}
        self._frames: list[str] = []

    @classmethod
    def from_description(cls, description: RobotDescription,
                         world: tuple[str, ...] = ("map", "odom")) -> FrameTree:
        """The REP 105 tree: ``world`` frames chained above the description's root (each
        at identity until set), then every link at its joints' zero position."""
        tree = cls()
        chain = (*world, description.root)
        for parent, child in zip(chain, chain[1:]):
            tree.set_transform(parent, child, np.eye(4))
        for joint in description.joints.values():
            tree.set_transform(joint.parent, joint.child, joint.origin)
        return tree

    @property
    def frames(self) -> list[str]:
        """Every frame, in the order it joined the tree."""
        return list(self._frames)

    def parent(self, frame: str) -> str | None:
        """``frame``'s parent (``None`` for a root)."""
        self._check(frame)
        return self._parent.get(frame)

    def children(self, frame: str) -> list[str]:
        """Frames whose parent is ``frame``."""
        self._check(frame)
        return [child for child, parent in self._parent.items() if parent == frame]

    def set_transform(self, parent: str, child: str, transform: np.ndarray) -> None:
        """Put ``child`` under ``parent`` at ``transform`` (4 x 4), or move it there."""
        transform = np.asarray(transform, dtype=float)
        if transform.shape != (4, 4) or not np.all(np.isfinite(transform)):
            raise ValueError(f"the transform {parent} -> {child} must be a finite 4 x 4 "
                             f"matrix, got shape {transform.shape}")
        if child == parent or child in self._ancestors(parent):
            raise FrameError(f"{parent} -> {child} would make a loop: {child} is above "
                             f"{parent}")
        if child in self._parent and self._parent[child] != parent:
            raise FrameError(f"{child} already hangs from {self._parent[child]}; a frame "
                             f"has one parent (tf2's rule)")
        for frame in (parent, child):
            if frame not in self._frames:
                self._frames.append(frame)
        self._parent[child] = parent
        self._to_parent[child] = transform

    def set_pose(self, parent: str, child: str, pose: Pose2D | tuple[float, float, float]
                 ) -> None:
        """Put ``child`` at a pose in ``parent``'s plane (as ``odom -> base_link``)."""
        self.set_transform(parent, child, planar_transform(pose))

    def lookup(self, target: str, source: str) -> np.ndarray:
        """4 x 4 transform taking points in ``source`` to ``target`` (tf2's
        ``lookupTransform(target, source)``): up from ``source`` to the common ancestor,
        then down to ``target``."""
        self._check(source)
        self._check(target)
        up_source = [source, *self._ancestors(source)]
        up_target = [target, *self._ancestors(target)]
        common = next((f for f in up_source if f in up_target), None)
        if common is None:
            raise FrameError(f"{source} and {target} are in separate trees (roots "
                             f"{up_source[-1]} and {up_target[-1]})")
        return np.linalg.inv(self._to_ancestor(target, common)) @ \
            self._to_ancestor(source, common)

    def pose_of(self, frame: str, in_frame: str) -> Pose2D:
        """Where ``frame`` is in ``in_frame``'s plane (x, y, yaw)."""
        return transform_to_pose(self.lookup(in_frame, frame))

    def transform_points(self, points: np.ndarray, source: str, target: str) -> np.ndarray:
        """Points (N, 2) or (N, 3) given in ``source``, expressed in ``target``. 2D
        points lie in ``source``'s z = 0 plane; the answer has as many columns."""
        points = np.asarray(points, dtype=float)
        if points.ndim != 2 or points.shape[1] not in (2, 3):
            raise ValueError(f"points must be (N, 2) or (N, 3), got shape {points.shape}")
        transform = self.lookup(target, source)
        full = np.zeros((len(points), 3))
        full[:, :points.shape[1]] = points
        moved = full @ transform[:3, :3].T + transform[:3, 3]
        return moved[:, :points.shape[1]]

    def transform_pose(self, pose: Pose2D | tuple[float, float, float], source: str,
                       target: str) -> Pose2D:
        """A plane pose given in ``source``, expressed in ``target``."""
        return transform_to_pose(self.lookup(target, source) @ planar_transform(pose))

    def _ancestors(self, frame: str) -> list[str]:
        chain = []
        while frame in self._parent:
            frame = self._parent[frame]
            chain.append(frame)
        return chain

    def _to_ancestor(self, frame: str, ancestor: str) -> np.ndarray:
        transform = np.eye(4)
        while frame != ancestor:
            transform = self._to_parent[frame] @ transform
            frame = self._parent[frame]
        return transform

    def _check(self, frame: str) -> None:
        if frame not in self._frames:
            raise FrameError(f"no frame {frame!r}; frames: {', '.join(self._frames)}")
