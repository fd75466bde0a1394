"""Worlds: wall segments, named places and walking people, loaded from JSON files.

A world file (``data/worlds/<name>.json``) holds::

    {
      "name": "lab",
      "description": "one line for people",
      "walls": [[[x, y], [x, y], ...], ...],      # polylines, metres
      "places": {"start": [x, y, theta], ...},     # theta in rad; "start" is required
      "people": [{"name": "ana", "path": [[x, y], ...], "speed": 0.8,
                  "radius": 0.25, "loop": true,
                  "tag": {"text": "ana", "marker_id": 7, "side": 0.2}}],  # optional
      "objects": [{"name": "table top", "outline": [[x, y], ...],
                   "z": [0.70, 0.75]}],            # optional
      "signs": [{"name": "exit", "word": "EXIT", "at": [x, y, z],
                 "facing": theta, "width": 0.6}],  # optional
      "markers": [{"id": 3, "at": [x, y, z], "facing": theta,
                   "side": 0.3}]                   # optional
    }

Every wall polyline becomes straight segments; a closed shape repeats its first point.
Walls stand from the floor to ``WALL_HEIGHT``. An object is an outline standing between
two heights ``z`` (m): a table is a top at 0.70-0.75 m over four legs from the floor
(:func:`table`). A sensor sees an object only where its view at that height reaches it
(a planar lidar at its mount height, a depth camera's band of rows); the chair collides
with every wall and object (each is below the seated person's head). A person may wear
a ``tag`` on their back, a :class:`~abcwc.perception.tags.FollowCard` (an ArUco marker
and a QR code of ``text``, each ``side`` m across) that the chair's camera sees. A sign
is a house-style door sign (:func:`~abcwc.perception.signs.house_sign`) saying ``word``,
``width`` m wide, hung flat with its centre ``at`` (m) and its face turned to ``facing``
(rad: the heading of the way it faces). A marker is a fixed ArUco marker
(:class:`~abcwc.perception.markers.FixedMarker`) at a surveyed place, hung the same way:
the landmarks the chair's filter takes fixes from.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from abcwc.paths import data_dir, read_document
from abcwc.perception.markers import FixedMarker
from abcwc.perception.signs import house_sign
from abcwc.perception.tags import FollowCard
from abcwc.types import Pose2D

WALL_HEIGHT = 2.5
"""m: walls stand from the floor to this height."""


class WorldError(ValueError):
    """A world file that cannot be used, with the reason and what is allowed."""


@dataclass(frozen=True)
class PersonSpec:
    """A person who walks a path at constant speed (m/s), as a disc of ``radius`` (m)."""

    name: str
    path: np.ndarray  # (K, 2) waypoints
    speed: float = 0.8
    radius: float = 0.25
    loop: bool = True
    tag: FollowCard | None = None  # worn on the back


@dataclass(frozen=True)
class SignSpec:
    """A house-style sign saying ``word``, ``width`` m wide, its centre at ``centre``
    (x, y, z m) and its face towards ``facing`` (rad)."""

    name: str
    word: str
    centre: tuple[float, float, float]
    facing: float
    width: float = 0.6


@dataclass(frozen=True)
class World:
    """Static segments (N, 4: x1 y1 x2 y2), each standing between two heights (``bands``,
    N x 2: bottom and top, m; walls from the floor to ``WALL_HEIGHT``), named places
    and people."""

    name: str
    walls: np.ndarray
    places: dict[str, Pose2D]
    people: tuple[PersonSpec, ...] = ()
    description: str = ""
    signs: tuple[SignSpec, ...] = ()
    markers: tuple[FixedMarker, ...] = ()
    source: Path | None = field(default=None, compare=False)
    bands: np.ndarray | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if self.bands is None:
            object.__setattr__(self, "bands", np.tile([0.0, WALL_HEIGHT], (len(self.walls), 1)))

    @property
    def start(self) -> Pose2D:
        """Where the chair starts: the place called ``start``."""
        return self.places["start"]

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of all walls (m)."""
        xs = np.concatenate([self.walls[:, 0], self.walls[:, 2]])
        ys = np.concatenate([self.walls[:, 1], self.walls[:, 3]])
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())


def available_worlds() -> list[str]:
    """Names of the worlds shipped in ``data/worlds``."""
    return sorted(p.stem for p in (data_dir() / "worlds").glob("*.json"))


def _point(value: object, where: str) -> tuple[float, float]:
    if (
        not isinstance(value, (list, tuple))
        or len(value) != 2
        or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in value)
    ):
        raise WorldError(f"{where}: expected a point [x, y] of finite numbers, got {value!r}")
    return float(value[0]), float(value[1])


def world_from_dict(raw: dict, source: Path | None = None) -> World:
    """Build and validate a :class:`World` from the parsed JSON structure."""
    label = str(source) if source else "world"
    if not isinstance(raw, dict):
        raise WorldError(f"{label}: top level must be an object with walls and places")
    missing = {"name", "walls", "places"} - raw.keys()
    if missing:
        raise WorldError(
            f"{label}: missing {', '.join(sorted(missing))} (need name, walls, places)"
        )
    unknown = raw.keys() - {"name", "walls", "places", "people", "objects", "signs",
                            "markers", "description"}
    if unknown:
        raise WorldError(
            f"{label}: unknown key(s) {', '.join(sorted(unknown))}; "
            "allowed: name, description, walls, places, people, objects, signs, markers"
        )
    if not isinstance(raw["walls"], list) or not raw["walls"]:
        raise WorldError(f"{label}: walls must be a non-empty list of polylines")
    segments = []
    for i, line in enumerate(raw["walls"]):
        segments += _polyline_segments(line, f"{label}: walls[{i}]")
    bands = [(0.0, WALL_HEIGHT)] * len(segments)
    objects = raw.get("objects", [])
    if not isinstance(objects, list):
        raise WorldError(f"{label}: objects must be a list of {{outline, z}} objects")
    for i, thing in enumerate(objects):
        where = f"{label}: objects[{i}]"
        if not isinstance(thing, dict) or not {"outline", "z"} <= thing.keys():
            raise WorldError(f"{where} must be an object with an outline and z [bottom, top]")
        outline = _polyline_segments(thing["outline"], where)
        z = thing["z"]
        if (not isinstance(z, list) or len(z) != 2
                or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in z)
                or not 0 <= z[0] < z[1]):
            raise WorldError(f"{where}: z must be [bottom, top] in m with 0 <= bottom < top,"
                             f" got {z!r}")
        segments += outline
        bands += [(float(z[0]), float(z[1]))] * len(outline)
    places = {}
    if not isinstance(raw["places"], dict):
        raise WorldError(f"{label}: places must be an object of name: [x, y, theta]")
    for name, value in raw["places"].items():
        if (
            not isinstance(value, list)
            or len(value) != 3
            or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in value)
        ):
            raise WorldError(f"{label}: place {name!r} must be [x, y, theta] (m, m, rad)")
        places[name] = Pose2D(*map(float, value))
    if "start" not in places:
        raise WorldError(f"{label}: places must include 'start', the chair's start pose")
    people = []
    for i, person in enumerate(raw.get("people", [])):
        if not isinstance(person, dict) or "path" not in person:
            raise WorldError(f"{label}: people[{i}] must be an object with a path")
        path = np.array([_point(p, f"{label}: people[{i}].path") for p in person["path"]])
        speed = person.get("speed", 0.8)
        radius = person.get("radius", 0.25)
        if len(path) < 2:
            raise WorldError(f"{label}: people[{i}].path needs at least 2 points")
        if not (isinstance(speed, (int, float)) and 0 < speed <= 3):
            raise WorldError(f"{label}: people[{i}].speed {speed!r} outside 0..3 m/s")
        if not (isinstance(radius, (int, float)) and 0.05 <= radius <= 1):
            raise WorldError(f"{label}: people[{i}].radius {radius!r} outside 0.05..1 m")
        people.append(
            PersonSpec(
                name=str(person.get("name", f"person{i}")),
                path=path,
                speed=float(speed),
                radius=float(radius),
                loop=bool(person.get("loop", True)),
                tag=_tag(person.get("tag"), f"{label}: people[{i}].tag"),
            )
        )
    return World(
        name=str(raw["name"]),
        walls=np.array(segments, dtype=float),
        places=places,
        people=tuple(people),
        description=str(raw.get("description", "")),
        source=source,
        bands=np.array(bands, dtype=float),
        signs=tuple(_sign(sign, f"{label}: signs[{i}]")
                    for i, sign in enumerate(_list(raw.get("signs", []), f"{label}: signs"))),
        markers=_markers(_list(raw.get("markers", []), f"{label}: markers"), label),
    )


def _list(raw: object, where: str) -> list:
    if not isinstance(raw, list):
        raise WorldError(f"{where} must be a list")
    return raw


def _hung(raw: dict, where: str) -> tuple[tuple[float, float, float], float]:
    """A sign's or marker's ``at`` [x, y, z] (m) and ``facing`` (rad), checked."""
    at, facing = raw["at"], raw["facing"]
    if (not isinstance(at, list) or len(at) != 3
            or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in at)
            or not 0 < at[2] < WALL_HEIGHT):
        raise WorldError(f"{where}.at must be [x, y, z] in m with 0 < z < {WALL_HEIGHT}, "
                         f"got {at!r}")
    if not (isinstance(facing, (int, float)) and math.isfinite(facing)):
        raise WorldError(f"{where}.facing must be a finite heading in rad, got {facing!r}")
    return (float(at[0]), float(at[1]), float(at[2])), float(facing)


def _markers(raw: list, label: str) -> tuple[FixedMarker, ...]:
    """The ``markers`` entries as FixedMarkers, each id once."""
    markers = []
    for i, entry in enumerate(raw):
        where = f"{label}: markers[{i}]"
        if not isinstance(entry, dict) or not {"id", "at", "facing"} <= entry.keys():
            raise WorldError(f"{where} must be an object with id, at [x, y, z] (m), facing "
                             "(rad) and optionally side (m)")
        centre, facing = _hung(entry, where)
        try:
            markers.append(FixedMarker(entry["id"], centre, facing,
                                       float(entry.get("side", 0.3))))
        except (TypeError, ValueError) as error:
            raise WorldError(f"{where}: {error}") from None
    ids = [m.marker_id for m in markers]
    if len(set(ids)) != len(ids):
        raise WorldError(f"{label}: markers: each id once (a sighting must name one place), "
                         f"got {sorted(ids)}")
    return tuple(markers)


def _sign(raw: object, where: str) -> SignSpec:
    """A ``signs`` entry as a SignSpec."""
    if not isinstance(raw, dict) or not {"name", "word", "at", "facing"} <= raw.keys():
        raise WorldError(f"{where} must be an object with name, word, at [x, y, z] (m), "
                         "facing (rad) and optionally width (m)")
    centre, facing = _hung(raw, where)
    width = raw.get("width", 0.6)
    if not (isinstance(width, (int, float)) and 0.05 <= width <= 3):
        raise WorldError(f"{where}.width must be 0.05..3 m, got {width!r}")
    word = raw["word"]
    try:
        house_sign(word)
    except ValueError as error:
        raise WorldError(f"{where}.word: {error}") from None
    return SignSpec(str(raw["name"]), word, centre, facing, float(width))


def _tag(raw: object, where: str) -> FollowCard | None:
    """A person's ``tag`` entry as a FollowCard (None when there is none)."""
    if raw is None:
        return None
    if not isinstance(raw, dict) or not {"text", "marker_id"} <= raw.keys():
        raise WorldError(f"{where} must be an object with text, marker_id and optionally "
                         "side (m)")
    try:
        return FollowCard(str(raw["text"]), raw["marker_id"], float(raw.get("side", 0.2)))
    except (TypeError, ValueError) as error:
        raise WorldError(f"{where}: {error}") from None


def _polyline_segments(line: object, where: str) -> list[tuple[float, float, float, float]]:
    if not isinstance(line, list) or len(line) < 2:
        raise WorldError(f"{where} must be a list of at least 2 points")
    pts = [_point(p, where) for p in line]
    segments = []
    for a, b in zip(pts, pts[1:]):
        if a == b:
            raise WorldError(f"{where} has a zero-length segment at {a}")
        segments.append((*a, *b))
    return segments


def table(centre: tuple[float, float], size: tuple[float, float] = (1.2, 0.8),
          yaw: float = 0.0, top: tuple[float, float] = (0.70, 0.75),
          leg: float = 0.05, name: str = "table") -> list[dict]:
    """World ``objects`` of a table: a top of ``size`` (m, length x width) between the
    heights ``top`` (m) over four square legs of side ``leg`` (m) at its corners, centred
    at ``centre`` and turned by ``yaw`` (rad)."""
    c, s = math.cos(yaw), math.sin(yaw)

    def outline(cx: float, cy: float, half_x: float, half_y: float) -> list[list[float]]:
        corners = [(-half_x, -half_y), (half_x, -half_y), (half_x, half_y),
                   (-half_x, half_y), (-half_x, -half_y)]
        return [[centre[0] + c * (cx + x) - s * (cy + y), centre[1] + s * (cx + x) + c * (cy + y)]
                for x, y in corners]

    half_x, half_y = size[0] / 2, size[1] / 2
    things = [{"name": f"{name} top", "outline": outline(0, 0, half_x, half_y),
               "z": [top[0], top[1]]}]
    for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        things.append({"name": f"{name} leg {k}",
                       "outline": outline(sx * (half_x - leg / 2), sy * (half_y - leg / 2),
                                          leg / 2, leg / 2),
                       "z": [0.0, top[0]]})
    return things


def box_world(width: float = 40.0, height: float = 40.0, extra: list | None = None,
              centred: bool = False, name: str = "box") -> World:
    """An empty rectangular room from (0, 0) to (width, height) m, its ``start`` in the
    middle facing +x; ``centred`` puts the middle (and the start) at the origin;
    ``extra`` adds wall polylines."""
    x0, y0 = (-width / 2, -height / 2) if centred else (0.0, 0.0)
    x1, y1 = x0 + width, y0 + height
    walls = [[[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]] + (extra or [])
    return world_from_dict({
        "name": name, "walls": walls,
        "places": {"start": [(x0 + x1) / 2, (y0 + y1) / 2, 0.0]},
    })


def load_world(name_or_path: str | Path) -> World:
    """Load a world by name (``"lab"``, ``"floor"``) or from a JSON file path."""
    candidate = Path(name_or_path)
    if candidate.suffix == ".json" or candidate.exists():
        path = candidate
    else:
        path = data_dir() / "worlds" / f"{name_or_path}.json"
        if not path.exists():
            raise WorldError(
                f"unknown world {str(name_or_path)!r}; available: {', '.join(available_worlds())}"
                " (or give a path to a .json world file)"
            )
    raw = read_document(path, json.loads, parse_errors=(json.JSONDecodeError,),
                        error=WorldError, kind="world file", language="JSON")
    return world_from_dict(raw, source=path)
