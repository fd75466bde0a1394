"""How far and how well the chair's camera reads a tag: a seeded sweep in the simulator.

A :class:`~abcwc.perception.tags.FollowCard` is put at random distances, bearings and
turns in front of the chair's colour camera in an empty room; each view is rendered
with the frame's lighting, blur and noise, and read three ways: the ArUco marker (and
its pose by :func:`~abcwc.perception.tags.square_pose`), the QR code at the camera's
resolution, and the QR code on the image enlarged twice. The simulator's truth gives
the marker's real range and bearing from the camera, to judge the pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from abcwc.experiments.disk_cache import cached_on_disk
from abcwc.experiments.views import random_views
from abcwc.geometry import wrap_angle
from abcwc.params import ChairParams
from abcwc.perception.tags import FollowCard, detect_qr_codes, find_marker


@dataclass(frozen=True)
class TagSweep:
    """One row per view: its true ``distance`` (m, camera to the marker's centre),
    ``bearing`` (rad) and ``turn`` (rad, the card turned from facing the camera), and
    what was read: ``side_px`` (the marker's side, px; 0 if not found), the pose's
    ``range_error`` (relative) and ``bearing_error`` (rad), NaN where not found, and
    whether the QR code was decoded at 1x (``qr``) and 2x (``qr_upscaled``)."""

    distance: np.ndarray
    bearing: np.ndarray
    turn: np.ndarray
    side_px: np.ndarray
    range_error: np.ndarray
    bearing_error: np.ndarray
    qr: np.ndarray
    qr_upscaled: np.ndarray

    @property
    def found(self) -> np.ndarray:
        return self.side_px > 0

    def farthest(self, read: np.ndarray) -> float:
        """m: the farthest view where ``read`` (a bool row) is true."""
        return float(self.distance[read].max()) if read.any() else 0.0


@cached_on_disk  # seeded: a notebook and its student copy render the views once
def sweep_tag_views(count: int = 120, seed: int = 0, card: FollowCard | None = None,
                    distances: tuple[float, float] = (0.6, 9.0), max_bearing: float = 0.45,
                    max_turn: float = 0.9, params: ChairParams | None = None) -> TagSweep:
    """Render and read ``count`` random views (module notes): distance uniform in
    ``distances`` (m), bearing within ``max_bearing`` (rad) of the camera's axis, the
    card turned up to ``max_turn`` (rad) and its centre 0.8-1.0 m up."""
    card = card or FollowCard("ana", 7)
    rows = []
    for view in random_views(card.image(), card.width, count, seed, distances, max_bearing,
                             max_turn, (0.8, 1.0), params):
        # the marker is on the card's middle line: over the floor, the card's centre
        true_range, true_bearing = view.range_and_bearing(np.array(view.centre[:2]))
        gray, camera, turn = view.gray, view.camera, view.turn
        found = find_marker(gray, card.marker_id, card.side, camera)
        side, range_error, bearing_error = 0.0, math.nan, math.nan
        if found is not None:
            marker, tag = found
            side = marker.side_px
            range_error = (tag.range - true_range) / true_range
            bearing_error = wrap_angle(tag.bearing - true_bearing)
        qr = any(c.text == card.name for c in detect_qr_codes(gray))
        qr_upscaled = any(c.text == card.name for c in detect_qr_codes(gray, upscale=2))
        rows.append((true_range, true_bearing, turn, side, range_error, bearing_error, qr,
                     qr_upscaled))
    columns = [np.array(c) for c in zip(*rows)]
    return TagSweep(*columns[:6], columns[6].astype(bool), columns[7].astype(bool))


__all__ = ["TagSweep", "sweep_tag_views"]
