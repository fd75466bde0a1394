"""How far and how well the chair's camera finds a known sign, and how often a look-alike
fools it: a seeded sweep in the simulator (:mod:`abcwc.experiments.views`).

The sign shown is the house-style sign saying ``shown``; the detector looks for the one
saying ``sought``. With both ``"EXIT"`` the sweep measures detection: how far, at what
turn, and how well the bearing agrees with the truth. With ``"STAIRS"`` shown it
measures false detections: what the pipeline reports before and after verification.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from abcwc.experiments.views import random_views
from abcwc.geometry import wrap_angle
from abcwc.params import ChairParams
from abcwc.perception.known_objects import KnownObject, ObjectDetector
from abcwc.perception.signs import WORD_BOX, house_sign
from abcwc.sim.colour_camera import Imaging


@dataclass(frozen=True)
class SignSweep:
    """One row per view: the true ``distance`` (m, camera to the sign's centre),
    ``bearing`` and ``turn`` (rad), the sign's ``width_px`` in the image (its true
    corners projected), then for the detector: whether steps 1-4 reported the sought
    sign (``matched``), its ``correlation`` (nan where not matched), whether it was
    ``verified``, its ``bearing_error`` (rad, nan where not matched) and the
    detector's time (``ms``)."""

    features: str
    shown: str
    sought: str
    distance: np.ndarray
    bearing: np.ndarray
    turn: np.ndarray
    width_px: np.ndarray
    matched: np.ndarray
    correlation: np.ndarray
    verified: np.ndarray
    bearing_error: np.ndarray
    ms: np.ndarray

    def farthest(self, found: np.ndarray) -> float:
        """m: the farthest view where ``found`` (a bool row) is true."""
        return float(self.distance[found].max()) if found.any() else 0.0

    def rate(self, found: np.ndarray, within: tuple[float, float],
             max_turn: float = math.pi) -> float:
        """The share of views ``within`` (near, far) m, the sign turned at most
        ``max_turn`` rad from facing the camera, where ``found`` is true."""
        band = ((self.distance >= within[0]) & (self.distance < within[1])
                & (np.abs(self.turn) <= max_turn))
        return float(found[band].mean()) if band.any() else math.nan


def sweep_sign_views(features: str = "sift", shown: str = "EXIT", sought: str = "EXIT",
                     count: int = 60, seed: int = 0, distances: tuple[float, float] = (1.5, 9.0),
                     max_bearing: float = 0.4, max_turn: float = 1.0,
                     width: float = 0.6, params: ChairParams | None = None,
                     detector: ObjectDetector | None = None,
                     imaging: Imaging | None = None) -> SignSweep:
    """Render ``count`` random views of the sign saying ``shown`` (``width`` m wide, its
    centre 1.1-1.3 m up) and look in each for the one saying ``sought`` with SIFT or ORB
    (``features``; or a ``detector`` of one's own), verification reported separately."""
    detector = detector or ObjectDetector(
        [KnownObject(sought.lower(), house_sign(sought), width, WORD_BOX)], features=features,
        verify=False)
    name = detector.objects[0].name
    image = house_sign(shown)
    rows = []
    for view in random_views(image, width, count, seed, distances, max_bearing, max_turn,
                             (1.1, 1.3), params, imaging):
        true_range, true_bearing = view.range_and_bearing(np.array(view.centre[:2]))
        half = width / 2 * np.array([-math.sin(view.facing), math.cos(view.facing)])
        ends = [view.range_and_bearing(np.array(view.centre[:2]) + k * half) for k in (-1, 1)]
        width_px = abs(view.camera.fx * (math.tan(ends[0][1]) - math.tan(ends[1][1])))
        start = time.perf_counter()
        found = [d for d in detector.detect(view.gray, view.camera.fx, view.camera.cx)
                 if d.name == name]
        ms = (time.perf_counter() - start) * 1000
        best = found[0] if found else None
        rows.append((true_range, true_bearing, view.turn, width_px, best is not None,
                     best.correlation if best else math.nan,
                     bool(best and best.verified),
                     wrap_angle(best.bearing - true_bearing) if best else math.nan,
                     ms))
    columns = [np.array(c) for c in zip(*rows)]
    return SignSweep(detector.features,
                     shown, sought, *columns[:4], columns[4].astype(bool), columns[5],
                     columns[6].astype(bool), columns[7], columns[8])


__all__ = ["SignSweep", "sweep_sign_views"]
