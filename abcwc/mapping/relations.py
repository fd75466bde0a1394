"""Benchmark relations and the relation error of Kümmerle et al. (2009).

R. Kümmerle, B. Steder, C. Dornhege, M. Ruhnke, G. Grisetti, C. Stachniss and A. Kleiner,
"On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4), 2009. A SLAM
result is judged by the relative poses it gives between pairs of its own poses, not by
its poses in a global frame: for each reference relation ``delta*_ij`` (the pose of scan
``j`` in the frame of scan ``i``, from a hand-checked alignment), the estimate's
``delta_ij = x_i^-1 (+) x_j`` is compared through

    epsilon_ij = delta_ij (-) delta*_ij        (with a (-) b = b^-1 (+) a)

and the paper reports, over all relations, the mean and standard deviation of the
absolute translational error ``|trans(epsilon_ij)|`` (m) and of the absolute rotational
error ``|rot(epsilon_ij)|`` (deg). The translational part's norm is
``|t_ij - t*_ij|`` whichever way round the difference is taken.

A ``.relations`` file has one relation a line: ``t1 t2 x y z roll pitch yaw`` (s, m,
rad), ``t1`` and ``t2`` scan timestamps of the log, written to the microsecond (ACES,
FR079) or rounded to 10 microseconds (MIT CSAIL); ``z``, ``roll`` and ``pitch`` are zero
for planar data and ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from abcwc.geometry import relative, wrap_angle

_SLACK = 1e-6  # s: float64 spacing at 1e9 s (Unix times) is 0.24 microseconds


@dataclass(frozen=True, eq=False)
class Relations:
    """Reference relative poses between scans of one log (M relations).

    ``first`` and ``second`` are ``(M,)`` scan indices into the log, ``stamps`` the
    ``(M, 2)`` timestamps (s) as written, ``reference`` the ``(M, 3)`` pose of scan
    ``second`` in the frame of scan ``first`` ``(x, y, yaw)`` (m, rad).
    """

    path: Path
    first: np.ndarray
    second: np.ndarray
    stamps: np.ndarray
    reference: np.ndarray

    def __len__(self) -> int:
        return len(self.first)

    def subset(self, keep: np.ndarray) -> Relations:
        """The relations selected by ``keep`` (a boolean mask or indices)."""
        return Relations(self.path, self.first[keep], self.second[keep],
                         self.stamps[keep], self.reference[keep])


@dataclass(frozen=True, eq=False)
class RelationErrors:
    """Per-relation absolute errors: ``translational`` (m) and ``rotational`` (rad), (M,).

    Means and standard deviations are over the relations (population std, ddof=0).
    """

    translational: np.ndarray
    rotational: np.ndarray

    @property
    def translational_mean(self) -> float:
        return float(np.mean(self.translational))

    @property
    def translational_std(self) -> float:
        return float(np.std(self.translational))

    @property
    def rotational_mean_deg(self) -> float:
        return math.degrees(float(np.mean(self.rotational)))

    @property
    def rotational_std_deg(self) -> float:
        return math.degrees(float(np.std(self.rotational)))


def read_relations(path: str | Path, scan_stamps: np.ndarray) -> Relations:
    """Read a ``.relations`` file and match its timestamps to ``scan_stamps`` (s).

    A relation's timestamp names the scan nearest to it, which must equal it to the
    precision it is written with (half a unit of its last decimal, plus 1 microsecond
    for float rounding). A line with other than 8 fields, a value that is not a number,
    or a timestamp that is not one of the scans' raises ValueError naming the file and
    line.
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="latin-1").splitlines()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the relations ({exc.strerror})") from exc
    numbers, rows, decimals = [], [], []
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        if len(fields) != 8:
            raise ValueError(f"{path}, line {number}: a relation is 8 fields "
                             f"(t1 t2 x y z roll pitch yaw), got {len(fields)}")
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            raise ValueError(f"{path}, line {number}: not all of {line.strip()!r} "
                             f"are numbers") from None
        numbers.append(number)
        decimals.append([_decimals(fields[0]), _decimals(fields[1])])
    table = np.array(rows, dtype=float).reshape(-1, 8)
    tolerance = 0.5 * 10.0 ** -np.array(decimals, dtype=float).reshape(-1, 2) + _SLACK
    indices = [_nearest_scans(path, numbers, table[:, column], tolerance[:, column],
                              np.asarray(scan_stamps, dtype=float)) for column in (0, 1)]
    reference = table[:, [2, 3, 7]].copy()
    reference[:, 2] = wrap_angle(reference[:, 2])
    return Relations(path, indices[0], indices[1], table[:, :2].copy(), reference)


def _decimals(text: str) -> int:
    """How many digits follow the decimal point in ``text``."""
    mantissa = text.lower().split("e")[0]
    return len(mantissa.split(".")[1]) if "." in mantissa else 0


def _nearest_scans(path: Path, numbers: list[int], wanted: np.ndarray,
                   tolerance: np.ndarray, stamps: np.ndarray) -> np.ndarray:
    """Index of the scan nearest each wanted time (s); a ValueError if one is further
    than its tolerance (s)."""
    if len(stamps) == 0:
        raise ValueError(f"{path}: the log has no scans to match relations to")
    order = np.argsort(stamps, kind="stable")
    ordered = stamps[order]
    after = np.clip(np.searchsorted(ordered, wanted), 0, len(ordered) - 1)
    before = np.maximum(after - 1, 0)
    pick = np.where(np.abs(ordered[after] - wanted) < np.abs(ordered[before] - wanted),
                    after, before)
    missed = np.abs(ordered[pick] - wanted) > tolerance
    if np.any(missed):
        k = int(np.flatnonzero(missed)[0])
        raise ValueError(f"{path}, line {numbers[k]}: timestamp {wanted[k]:.6f} is not "
                         f"the time of a scan in the log (nearest scan "
                         f"{ordered[pick[k]]:.6f})")
    return order[pick]


def relation_errors(poses: np.ndarray, relations: Relations) -> RelationErrors:
    """The relation errors of ``poses`` ``(N, 3)``, one per scan of the log (m, rad):
    the scans' own poses, the laser's (a relation is "the pose of the scan stamped t2 in
    the frame of the scan stamped t1"; ``SlamResult.laser_poses``).

    ``epsilon = delta (-) delta*`` with ``delta = relative(poses[first], poses[second])``
    (Kümmerle et al. 2009); the answer holds ``|trans(epsilon)|`` and
    ``|rot(epsilon)|`` per relation.
    """
    poses = np.asarray(poses, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"poses must be (N, 3), one per scan, got shape {poses.shape}")
    top = max(int(relations.first.max(initial=-1)), int(relations.second.max(initial=-1)))
    if top >= len(poses):
        raise ValueError(f"{relations.path} refers to scan {top}, "
                         f"but only {len(poses)} poses were given")
    estimated = np.asarray(relative(poses[relations.first], poses[relations.second]))
    return relative_pose_errors(estimated, relations.reference)


def relative_pose_errors(estimated: np.ndarray, reference: np.ndarray) -> RelationErrors:
    """The errors of estimated relative poses ``(M, 3)`` against reference ones."""
    epsilon = np.asarray(relative(np.asarray(reference, float), np.asarray(estimated, float)))
    epsilon = epsilon.reshape(-1, 3)
    return RelationErrors(translational=np.hypot(epsilon[:, 0], epsilon[:, 1]),
                          rotational=np.abs(epsilon[:, 2]))


def format_relation_errors(errors: RelationErrors) -> str:
    """Two lines: ``translational error: 0.043 ± 0.051 m`` and
    ``rotational error: 0.41 ± 0.52 deg`` (mean ± std)."""
    return (f"translational error: {errors.translational_mean:.3f} ± "
            f"{errors.translational_std:.3f} m\n"
            f"rotational error: {errors.rotational_mean_deg:.2f} ± "
            f"{errors.rotational_std_deg:.2f} deg")
