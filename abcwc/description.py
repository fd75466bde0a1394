"""The chair's description: links, joints and shapes read from a URDF file.

URDF (the ROS Unified Robot Description Format, http://wiki.ros.org/urdf/XML) describes
a robot as a tree of *links* (rigid parts, with optional visual and collision shapes)
joined by *joints* (each with a parent, a child and the child's pose in the parent's
frame). The chair's file is ``data/chair.urdf``; :mod:`abcwc.params` takes the
footprint, the drive wheels and the sensors' mounts from it, and :mod:`abcwc.frames`
builds the frame tree from its joints.

A joint's ``<origin xyz="x y z" rpy="roll pitch yaw"/>`` is the child frame in the
parent frame: translation (m), then fixed-axis roll about x, pitch about y, yaw about z
(rad), so ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (the URDF specification, "joint" and
"link" elements). Read with the standard library's XML parser; every error names the
file and what is wrong.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from abcwc.paths import data_dir

JOINT_TYPES = ("fixed", "continuous", "revolute", "prismatic", "floating", "planar")
SHAPES = {"box": ("size",), "cylinder": ("radius", "length"), "sphere": ("radius",)}


class DescriptionError(ValueError):
    """A URDF file that cannot be used, with the file and the reason."""


def homogeneous(xyz: tuple[float, float, float] = (0.0, 0.0, 0.0),
                rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """4 x 4 transform of a URDF origin: translation ``xyz`` (m) and fixed-axis
    ``rpy`` (rad), ``R = Rz(yaw) Ry(pitch) Rx(roll)``."""
    roll, pitch, yaw = rpy
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    transform = np.eye(4)
    transform[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    transform[:3, 3] = xyz
    return transform


@dataclass(frozen=True)
class Shape:
    """A visual or collision shape: ``kind`` box / cylinder / sphere, its dimensions (m:
    box ``size`` x y z; cylinder ``radius``, ``length`` along its z; sphere ``radius``)
    and its pose in the link's frame."""

    kind: str
    dimensions: tuple[float, ...]
    origin: np.ndarray  # 4 x 4


@dataclass(frozen=True)
class Link:
    """A rigid part: its name (a frame id) and its shapes, if any."""

    name: str
    visual: Shape | None = None
    collision: Shape | None = None


@dataclass(frozen=True)
class Joint:
    """``child``'s frame in ``parent``'s frame (``origin``, 4 x 4) and how it moves."""

    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)


class RobotDescription:
    """A robot's links and joints, checked to form one tree."""

    def __init__(self, name: str, links: dict[str, Link], joints: dict[str, Joint],
                 source: str = "description"):
        self.name = name
        self.links = links
        self.joints = joints
        self.source = source
        self._joint_to = {}  # child link -> the joint that carries it
        for joint in joints.values():
            for end in (joint.parent, joint.child):
                if end not in links:
                    raise DescriptionError(f"{source}: joint {joint.name!r} names link "
                                           f"{end!r}, which is not defined")
            if joint.child in self._joint_to:
                raise DescriptionError(f"{source}: link {joint.child!r} has two parents "
                                       f"({self._joint_to[joint.child].parent!r} and "
                                       f"{joint.parent!r}); a URDF is a tree")
            self._joint_to[joint.child] = joint
        roots = [name for name in links if name not in self._joint_to]
        if len(roots) != 1:
            raise DescriptionError(f"{source}: a URDF needs exactly one root link, found "
                                   f"{roots or 'none (the joints form a loop)'}")
        self.root = roots[0]
        for name in links:  # every chain must end at the root
            self.chain(name)

    def parent_of(self, link: str) -> str | None:
        """The link ``link`` hangs from (``None`` for the root)."""
        self._check(link)
        joint = self._joint_to.get(link)
        return joint.parent if joint else None

    def children_of(self, link: str) -> list[str]:
        """Links hanging directly from ``link``, in file order."""
        self._check(link)
        return [j.child for j in self.joints.values() if j.parent == link]

    def chain(self, link: str) -> list[Joint]:
        """Joints from the root down to ``link``."""
        self._check(link)
        joints: list[Joint] = []
        while link in self._joint_to:
            joint = self._joint_to[link]
            joints.append(joint)
            link = joint.parent
            if len(joints) > len(self.links):
                raise DescriptionError(f"{self.source}: the joints above {link!r} form a loop")
        return joints[::-1]

    def transform(self, link: str, frame: str | None = None) -> np.ndarray:
        """4 x 4 pose of ``link`` in ``frame`` (default the root) with every moving joint
        at zero: a point ``p`` in ``link`` is ``T @ p`` in ``frame``."""
        pose = np.eye(4)
        for joint in self.chain(link):
            pose = pose @ joint.origin
        if frame is None or frame == self.root:
            return pose
        return np.linalg.inv(self.transform(frame)) @ pose

    def mount(self, link: str, frame: str | None = None) -> tuple[float, float, float]:
        """``(x, y, yaw)`` of ``link`` in ``frame`` (default the root): where a sensor
        sits in the plane and which way it faces (m, m, rad)."""
        pose = self.transform(link, frame)
        return (float(pose[0, 3]), float(pose[1, 3]),
                float(math.atan2(pose[1, 0], pose[0, 0])))

    def height(self, link: str) -> float:
        """Height (m) of ``link``'s origin above the root's (the floor, for the chair)."""
        return float(self.transform(link)[2, 3])

    def _check(self, link: str) -> None:
        if link not in self.links:
            raise DescriptionError(f"{self.source}: no link {link!r}; links: "
                                   f"{', '.join(self.links)}")


def _numbers(text: str | None, count: int, where: str, default: str) -> tuple[float, ...]:
    words = (text if text is not None else default).split()
    try:
        values = tuple(float(w) for w in words)
    except ValueError:
        values = ()
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise DescriptionError(f"{where}: expected {count} finite numbers, got {text!r}")
    return values


def _origin(element: ET.Element | None, where: str) -> np.ndarray:
    if element is None:
        return np.eye(4)
    xyz = _numbers(element.get("xyz"), 3, f"{where} origin xyz", "0 0 0")
    rpy = _numbers(element.get("rpy"), 3, f"{where} origin rpy", "0 0 0")
    return homogeneous(xyz, rpy)  # type: ignore[arg-type]


def _shape(element: ET.Element | None, where: str) -> Shape | None:
    if element is None:
        return None
    geometry = element.find("geometry")
    if geometry is None or len(geometry) != 1:
        raise DescriptionError(f"{where}: needs a <geometry> with one shape")
    kind = geometry[0].tag
    if kind not in SHAPES:
        raise DescriptionError(f"{where}: shape <{kind}> is not one of "
                               f"{', '.join(SHAPES)} (meshes are not read)")
    dimensions: tuple[float, ...] = ()
    for attribute in SHAPES[kind]:
        count = 3 if attribute == "size" else 1
        dimensions += _numbers(geometry[0].get(attribute), count,
                               f"{where} {kind} {attribute}", "")
    if any(d <= 0 for d in dimensions):
        raise DescriptionError(f"{where}: {kind} dimensions must be positive, got {dimensions}")
    return Shape(kind, dimensions, _origin(element.find("origin"), where))


def parse_urdf(text: str, source: str = "URDF") -> RobotDescription:
    """A :class:`RobotDescription` from URDF text (boxes, cylinders and spheres)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise DescriptionError(f"{source}: not well-formed XML ({error})") from None
    if root.tag != "robot":
        raise DescriptionError(f"{source}: the top element must be <robot>, not <{root.tag}>")
    links: dict[str, Link] = {}
    for element in root.findall("link"):
        name = element.get("name")
        if not name:
            raise DescriptionError(f"{source}: a <link> without a name")
        if name in links:
            raise DescriptionError(f"{source}: link {name!r} is defined twice")
        where = f"{source}: link {name!r}"
        links[name] = Link(name, _shape(element.find("visual"), f"{where} visual"),
                           _shape(element.find("collision"), f"{where} collision"))
    joints: dict[str, Joint] = {}
    for element in root.findall("joint"):
        name = element.get("name") or ""
        where = f"{source}: joint {name!r}"
        kind = element.get("type")
        if kind not in JOINT_TYPES:
            raise DescriptionError(f"{where}: type {kind!r} is not one of "
                                   f"{', '.join(JOINT_TYPES)}")
        parent, child = element.find("parent"), element.find("child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise DescriptionError(f"{where}: needs <parent link=...> and <child link=...>")
        axis = element.find("axis")
        joints[name] = Joint(
            name, kind, parent.get("link", ""), child.get("link", ""),
            _origin(element.find("origin"), where),
            _numbers(axis.get("xyz") if axis is not None else None, 3,  # type: ignore[arg-type]
                     f"{where} axis", "1 0 0"))
    if not links:
        raise DescriptionError(f"{source}: no <link> elements")
    return RobotDescription(root.get("name", ""), links, joints, source)


def load_urdf(path: str | Path) -> RobotDescription:
    """Read a URDF file; a missing or malformed file is a :class:`DescriptionError`."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise DescriptionError(f"{path}: cannot read the URDF ({error.strerror})") from None
    return parse_urdf(text, str(path))


@lru_cache(maxsize=1)
def chair_description() -> RobotDescription:
    """The Sterling Ruby's description, ``data/chair.urdf`` (cached)."""
    return load_urdf(data_dir() / "chair.urdf")
