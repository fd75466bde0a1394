"""Planar pose graphs in g2o's text format: read, write, chain odometry.

The format of g2o (Kümmerle et al., "g2o: A general framework for graph optimization",
ICRA 2011), as used by the standard 2D SLAM benchmarks (Manhattan M3500, MIT, CSAIL,
Intel, ...). One record per line, fields separated by white space::

    VERTEX_SE2 id x y theta
    EDGE_SE2 i j dx dy dtheta I11 I12 I13 I22 I23 I33
    FIX id [id ...]

A vertex is a pose in the map frame (m, m, rad). An edge is a measurement of pose ``j``
seen from pose ``i`` (``relative(x_i, x_j)``, :func:`abcwc.geometry.relative`) with its
3x3 information matrix (the inverse covariance, in units of 1/m^2, 1/(m rad), 1/rad^2),
given by its upper triangle row by row. ``FIX`` holds the named vertices in place.

TORO's older format (Grisetti et al., "A tree parameterization for efficiently computing
maximum likelihood maps using gradient descent", RSS 2007), in which several benchmark
graphs are still published (the noisy M3500 variants, Intel), reads too::

    VERTEX2 id x y theta
    EDGE2 i j dx dy dtheta Ixx Ixy Iyy Itt Ixt Iyt

the same records with the information matrix's six entries in another order.

Choices made here:

* Files may be gzipped; they are recognised by their first two bytes (1f 8b), so a
  gzipped file without the ``.gz`` suffix reads too. :func:`write_g2o` gzips when the
  name ends in ``.gz``.
* Blank lines and lines starting with ``#`` are skipped. Any other tag (``VERTEX_XY``,
  ``EDGE_SE2_XY``, 3D records, ...) is refused rather than skipped: dropping landmark
  edges would silently optimise a different problem than the file describes.
* Where the file has no ``VERTEX_SE2`` at all (Manhattan, CSAIL), the initial poses are
  the odometry chain: pose 0 at the origin, then each pose composed with the edge from
  the previous id (``i -> i + 1``). A file with vertices must name every edge's ends.
* Anything wrong (a missing file, a line with too few or too many fields, text where a
  number belongs, NaN or infinity, an information matrix that is not symmetric positive
  definite, an edge to an unknown vertex, a duplicate vertex) raises
  :class:`GraphFileError`, a ``ValueError`` whose message names the file and the line.
"""

from __future__ import annotations

import gzip
import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from abcwc.geometry import chain_poses, wrap_angle

GZIP_MAGIC = b"\x1f\x8b"
UPPER_TRIANGLE = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
"""Row and column of I11 I12 I13 I22 I23 I33, the order the file gives them in."""
FIELD_COUNTS = {"VERTEX_SE2": 5, "EDGE_SE2": 12, "VERTEX2": 5, "EDGE2": 12}
"""Fields on a line of each record, its tag included (TORO's VERTEX2 and EDGE2 too)."""
TORO_TO_G2O_INFORMATION = (0, 1, 4, 2, 5, 3)
"""Where g2o's I11 I12 I13 I22 I23 I33 stand among TORO's Ixx Ixy Iyy Itt Ixt Iyt."""


class GraphFileError(ValueError):
    """A g2o file that cannot be read: the message names the file and the line."""


@dataclass
class PoseGraph:
    """A planar pose graph: N poses, M relative-pose measurements between them.

    ``ids`` (N,) the file's vertex ids, ascending; ``poses`` (N, 3) the initial poses
    (x m, y m, theta rad in (-pi, pi]), row k for ``ids[k]``; ``edges`` (M, 2) the row
    indices (not ids) of each edge's poses ``i`` and ``j``; ``measurements`` (M, 3) the
    measured ``relative(x_i, x_j)``; ``information`` (M, 3, 3) each edge's symmetric
    positive-definite information matrix; ``fixed`` the row indices of poses held in
    place (the file's ``FIX`` records; a solver fixes pose 0 when this is empty);
    ``poses_from`` ``"vertices"`` or ``"odometry"``: where the initial poses came from.
    """

    ids: np.ndarray
    poses: np.ndarray
    edges: np.ndarray
    measurements: np.ndarray
    information: np.ndarray
    fixed: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    poses_from: str = "vertices"

    def __post_init__(self) -> None:
        n, m = len(self.ids), len(self.edges)
        shapes = {"ids": (self.ids.shape, (n,)), "poses": (self.poses.shape, (n, 3)),
                  "edges": (self.edges.shape, (m, 2)),
                  "measurements": (self.measurements.shape, (m, 3)),
                  "information": (self.information.shape, (m, 3, 3))}
        for name, (got, want) in shapes.items():
            if got != want:
                raise ValueError(f"pose graph {name} has shape {got}, expected {want}")
        if m and (self.edges.min() < 0 or self.edges.max() >= n):
            raise ValueError(f"pose graph edges index rows 0..{n - 1}, got "
                             f"{self.edges.min()}..{self.edges.max()}")

    @property
    def i(self) -> np.ndarray:
        """(M,) row index of each edge's first pose."""
        return self.edges[:, 0]

    @property
    def j(self) -> np.ndarray:
        """(M,) row index of each edge's second pose."""
        return self.edges[:, 1]

    def with_poses(self, poses: np.ndarray) -> PoseGraph:
        """The same graph with other poses (N, 3), e.g. a solver's answer."""
        poses = np.array(poses, dtype=float)
        poses[:, 2] = wrap_angle(poses[:, 2])
        return PoseGraph(self.ids, poses, self.edges, self.measurements, self.information,
                         self.fixed, self.poses_from)


def _open_text(path: Path) -> io.TextIOBase:
    """The file as text, gunzipped if its first bytes are gzip's magic number."""
    with open(path, "rb") as raw:
        magic = raw.read(2)
    if magic == GZIP_MAGIC:
        return gzip.open(path, "rt", encoding="utf-8")
    return open(path, encoding="utf-8")


def _numbers(fields: list[str], where: str) -> list[float]:
    """The fields as finite floats; GraphFileError naming ``where`` otherwise."""
    try:
        values = [float(f) for f in fields]
    except ValueError:
        raise GraphFileError(f"{where}: expected numbers, got {' '.join(fields)!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise GraphFileError(f"{where}: numbers must be finite, got {' '.join(fields)!r}")
    return values


def _vertex_id(text: str, where: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise GraphFileError(f"{where}: vertex id must be an integer, got {text!r}") from None


@dataclass
class _Records:
    """What the lines of a g2o file said, with the line each record came from."""

    vertices: dict[int, tuple[list[float], int]] = field(default_factory=dict)
    edge_ids: list[tuple[int, int]] = field(default_factory=list)
    edge_values: list[list[float]] = field(default_factory=list)
    edge_lines: list[int] = field(default_factory=list)
    fixed_ids: list[tuple[int, int]] = field(default_factory=list)

    def add(self, fields: list[str], where: str, number: int) -> None:
        """Take one non-blank, non-comment line's fields; GraphFileError if bad."""
        tag = fields[0]
        if tag == "FIX":
            if len(fields) < 2:
                raise GraphFileError(f"{where}: FIX names no vertex")
            self.fixed_ids += [(_vertex_id(f, where), number) for f in fields[1:]]
            return
        if tag not in FIELD_COUNTS:
            raise GraphFileError(f"{where}: unsupported record {tag!r}; a planar pose "
                                 f"graph has only VERTEX_SE2, EDGE_SE2 and FIX (or TORO's "
                                 f"VERTEX2 and EDGE2)")
        if len(fields) != FIELD_COUNTS[tag]:
            raise GraphFileError(f"{where}: {tag} has {len(fields)} fields, "
                                 f"expected {FIELD_COUNTS[tag]}")
        if tag in ("VERTEX_SE2", "VERTEX2"):
            vertex = _vertex_id(fields[1], where)
            if vertex in self.vertices:
                raise GraphFileError(f"{where}: vertex {vertex} defined twice "
                                     f"(first on line {self.vertices[vertex][1]})")
            self.vertices[vertex] = (_numbers(fields[2:5], where), number)
            return
        a, b = _vertex_id(fields[1], where), _vertex_id(fields[2], where)
        if a == b:
            raise GraphFileError(f"{where}: edge joins vertex {a} to itself")
        values = _numbers(fields[3:12], where)
        if tag == "EDGE2":
            values = values[:3] + [values[3 + k] for k in TORO_TO_G2O_INFORMATION]
        self.edge_ids.append((a, b))
        self.edge_values.append(values)
        self.edge_lines.append(number)


def _read_records(path: Path) -> _Records:
    """Every record of the file, in order; GraphFileError naming the file and line."""
    records = _Records()
    number = 0
    try:
        with _open_text(path) as text:
            for number, line in enumerate(text, start=1):
                fields = line.split()
                if fields and not fields[0].startswith("#"):
                    records.add(fields, f"{path}, line {number}", number)
    except FileNotFoundError:
        raise GraphFileError(f"{path}: no such file") from None
    except (UnicodeDecodeError, EOFError, gzip.BadGzipFile, OSError) as exc:
        raise GraphFileError(f"{path}, after line {number}: not a readable g2o text file "
                             f"({exc})") from None
    return records


def read_g2o(path: str | Path) -> PoseGraph:
    """Read a planar g2o pose graph (plain or gzipped text); see the module notes.

    Raises :class:`GraphFileError` (a ``ValueError``) naming the file and line for any
    file that is missing or not a valid ``VERTEX_SE2``/``EDGE_SE2``/``FIX`` graph.
    """
    path = Path(path)
    records = _read_records(path)
    vertices, edge_lines = records.vertices, records.edge_lines
    if not records.edge_ids:
        raise GraphFileError(f"{path}: no EDGE_SE2 records")
    values = np.array(records.edge_values)
    information = _information(values[:, 3:], path, edge_lines)
    ids_of_edges = np.array(records.edge_ids, dtype=np.int64)
    if vertices:
        ids = np.array(sorted(vertices), dtype=np.int64)
        rows = np.searchsorted(ids, ids_of_edges).clip(0, len(ids) - 1)
        unknown = np.argwhere(ids[rows] != ids_of_edges)
        if len(unknown):
            k, end = unknown[0]
            raise GraphFileError(f"{path}, line {edge_lines[k]}: edge names vertex "
                                 f"{ids_of_edges[k, end]}, which has no VERTEX_SE2")
        poses = np.array([vertices[v][0] for v in ids])
        poses[:, 2] = wrap_angle(poses[:, 2])
        poses_from = "vertices"
    else:
        ids = np.unique(ids_of_edges)
        rows = np.searchsorted(ids, ids_of_edges)
        poses = chain_odometry(ids, rows, values[:, :3], path)
        poses_from = "odometry"
    fixed = []
    for vertex, number in records.fixed_ids:
        row = int(np.searchsorted(ids, vertex))
        if row >= len(ids) or ids[row] != vertex:
            raise GraphFileError(f"{path}, line {number}: FIX names unknown vertex {vertex}")
        fixed.append(row)
    return PoseGraph(ids, poses, rows, values[:, :3], information,
                     np.unique(np.array(fixed, dtype=np.int64)), poses_from)


def _information(upper: np.ndarray, path: Path, lines: list[int]) -> np.ndarray:
    """(M, 3, 3) symmetric matrices from (M, 6) upper triangles; each must be positive
    definite (all eigenvalues > 0), else GraphFileError naming the first bad edge's line."""
    information = np.zeros((len(upper), 3, 3))
    for k, (r, c) in enumerate(UPPER_TRIANGLE):
        information[:, r, c] = information[:, c, r] = upper[:, k]
    smallest = np.linalg.eigvalsh(information)[:, 0]
    bad = np.nonzero(~(smallest > 0))[0]
    if len(bad):
        k = bad[0]
        raise GraphFileError(f"{path}, line {lines[k]}: information matrix is not positive "
                             f"definite (smallest eigenvalue {smallest[k]:.3g})")
    return information


def chain_odometry(ids: np.ndarray, edges: np.ndarray, measurements: np.ndarray,
                   path: str | Path = "pose graph") -> np.ndarray:
    """Initial poses (N, 3) from the odometry chain: pose 0 at the origin, pose k =
    pose k-1 (+) the first edge from ``ids[k-1]`` to ``ids[k]``
    (:func:`abcwc.geometry.chain_poses`).

    ``edges`` (M, 2) row indices, ``measurements`` (M, 3). GraphFileError naming
    ``path`` when some consecutive pair has no edge to place the later pose with.
    """
    n = len(ids)
    step = np.full(n, -1, dtype=np.int64)
    forward = np.nonzero(edges[:, 1] == edges[:, 0] + 1)[0]
    step[edges[forward[::-1], 1]] = forward[::-1]  # the first such edge wins
    missing = np.nonzero(step[1:] < 0)[0]
    if len(missing):
        k = missing[0] + 1
        raise GraphFileError(f"{path}: no VERTEX_SE2 records and no odometry edge "
                             f"{ids[k - 1]} -> {ids[k]} to place vertex {ids[k]} with")
    return chain_poses((0.0, 0.0, 0.0), measurements[step[1:]])


def _format(value: float) -> str:
    """Shortest text that reads back to the same float."""
    return repr(float(value))


def write_g2o(graph: PoseGraph, path: str | Path) -> Path:
    """Write ``graph`` as g2o text (gzipped when ``path`` ends in ``.gz``): one
    ``VERTEX_SE2`` per pose, one ``EDGE_SE2`` per edge, a ``FIX`` line if any pose is
    fixed. Numbers are written to full precision, so :func:`read_g2o` gives them back."""
    path = Path(path)
    lines = [f"VERTEX_SE2 {v} " + " ".join(map(_format, pose)) + "\n"
             for v, pose in zip(graph.ids.tolist(), graph.poses)]
    upper = np.stack([graph.information[:, r, c] for r, c in UPPER_TRIANGLE], axis=1)
    ends = graph.ids[graph.edges].tolist()
    lines += [f"EDGE_SE2 {a} {b} " + " ".join(map(_format, np.concatenate([z, u]))) + "\n"
              for (a, b), z, u in zip(ends, graph.measurements, upper)]
    if len(graph.fixed):
        lines.append("FIX " + " ".join(str(v) for v in graph.ids[graph.fixed].tolist()) + "\n")
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "wt", encoding="utf-8") as out:
        out.writelines(lines)
    return path
