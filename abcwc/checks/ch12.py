"""Checks for chapter 12, range sensors (thesis 2.2.5, 3.2.2, 5.3.2; ROS
depthimage_to_laserscan).

Exercises:

* ``depth_to_ranges(depth, fx, cx, scan_height, range_min, range_max)``: the nearest
  valid range in each column of a depth image's central band of rows, and each
  column's bearing, as depthimage_to_laserscan computes them;
* ``predicted_reach()``: a number written down *before* the run that measures it: from
  how far (m) the depth scan first sees a box 0.30 m tall;
* ``could_have_seen()``: a diagnosis: which of the chair's range sensors could have seen
  the table top the chair drove into.

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from abcwc.checks.report import NotYet, checker, expect, expect_no_slip, expect_own, format_value
from abcwc.params import default_params
from abcwc.perception.depth import depth_image_to_scan

__all__ = [
    "BOX_HEIGHT",
    "SEEN_BY",
    "depth_cases",
    "ranges_check",
    "reach_check",
    "reference_depth_to_ranges",
    "seen_check",
    "true_reach",
]

BOX_HEIGHT = 0.30
"""m: the box of exercise 2."""


def reference_depth_to_ranges(depth, fx: float, cx: float, scan_height: int,
                              range_min: float, range_max: float
                              ) -> tuple[np.ndarray, np.ndarray]:
    """(bearings rad, ranges m) per column: the band of ``scan_height`` rows centred on
    the image's middle, each pixel's range ``z sqrt(1 + ((u - cx) / fx)^2)``, the
    nearest inside the limits (``inf`` if none), bearing ``-atan((u - cx) / fx)``."""
    depth = np.asarray(depth, dtype=float)
    rows, width = depth.shape
    top = int(round((rows - 1) / 2 - scan_height / 2))
    band = depth[top:top + scan_height]
    lateral = (np.arange(width) - cx) / fx
    with np.errstate(invalid="ignore"):
        ranges = band * np.sqrt(1 + lateral**2)
        ok = np.isfinite(ranges) & (ranges >= range_min) & (ranges <= range_max)
    return -np.arctan(lateral), np.where(ok, ranges, np.inf).min(axis=0)


# --- exercise 1: a depth image's fake laser scan ------------------------------------------


def depth_cases() -> list[tuple[np.ndarray, float, float, int, float, float]]:
    """Depth images the check tries: a wall at 2 m seen square on (a flat z), a table
    edge over the floor, and seeded random scenes with holes (nan) and readings
    beyond the limits."""
    rng = np.random.default_rng(12)
    cases = []
    width, height = 64, 48
    fx = width / 2 / math.tan(math.radians(57) / 2)
    cx = (width - 1) / 2
    cases.append((np.full((height, width), 2.0), fx, cx, 19, 0.8, 4.0))
    table = np.full((height, width), 3.5)
    table[:20, 20:44] = 1.2  # a top in the upper rows
    table[30:] = 1.0  # the floor in the lower rows, nearer still
    cases.append((table, fx, cx, 19, 0.8, 4.0))
    for _ in range(3):
        image = rng.uniform(0.3, 6.0, (height, width))
        image[rng.random((height, width)) < 0.2] = np.nan
        cases.append((image, fx, cx, int(rng.integers(5, 30)), 0.5, 4.5))
    return cases


@checker("depth to ranges")
def ranges_check(fn: Callable) -> str:
    """``fn(depth, fx, cx, scan_height, range_min, range_max)`` against the rule worked
    out here, and the usual slips."""
    expect_own(fn, reference_depth_to_ranges, depth_image_to_scan)
    for depth, fx, cx, band, low, high in depth_cases():
        bearings, ranges = reference_depth_to_ranges(depth, fx, cx, band, low, high)
        got = fn(depth.copy(), fx, cx, band, low, high)
        try:
            got_bearings, got_ranges = (np.asarray(a, dtype=float) for a in got)
        except (TypeError, ValueError):
            raise NotYet(f"depth_to_ranges gave {format_value(got)}; return two arrays "
                         "(bearings, ranges), one value per column") from None
        expect(got_ranges.shape == ranges.shape and got_bearings.shape == bearings.shape,
               f"a {depth.shape[0]} x {depth.shape[1]} image gave arrays of shapes "
               f"{got_bearings.shape} and {got_ranges.shape}: one value per column "
               f"({depth.shape[1]})")
        if not np.allclose(got_bearings, bearings, atol=1e-9):
            if np.allclose(got_bearings, -bearings, atol=1e-9):
                raise NotYet("the bearings have the wrong sign: image columns run to the "
                             "right, a scan's angles grow to the left (REP 103)")
            raise NotYet(f"bearings: expected -atan((u - cx) / fx), e.g. "
                         f"{bearings[0]:.4f} rad for column 0, got {got_bearings[0]:.4f}")
        if np.array_equal(np.isinf(got_ranges), np.isinf(ranges)) and np.allclose(
                got_ranges[np.isfinite(ranges)], ranges[np.isfinite(ranges)], atol=1e-9):
            continue
        _explain_ranges(depth, fx, cx, band, low, high, got_ranges, ranges)
    return f"{len(depth_cases())} images: every column's nearest valid range and bearing"


def _explain_ranges(depth, fx, cx, band, low, high, got, expected) -> None:
    rows = depth.shape[0]
    lateral = (np.arange(depth.shape[1]) - cx) / fx
    top = int(round((rows - 1) / 2 - band / 2))

    def nearest(values, limits=True):
        with np.errstate(invalid="ignore"):
            ok = np.isfinite(values)
            if limits:
                ok &= (values >= low) & (values <= high)
        return np.where(ok, values, np.inf).min(axis=0)

    def same(answer, candidate):
        return np.array_equal(np.isinf(candidate), np.isinf(answer)) and np.allclose(
            candidate[np.isfinite(answer)], answer[np.isfinite(answer)], atol=1e-9)

    slips = {
        "these are the depths z, not ranges: a pixel off the axis is sqrt(x^2 + z^2) "
        "away, x = (u - cx) z / fx": nearest(depth[top:top + band]),
        "every row was used: the band is scan_height rows round the middle (the rows "
        "below see the floor, the rows above may see a table top)":
            nearest(depth * np.sqrt(1 + lateral**2)),
        "the range limits are not applied: a reading outside [range_min, range_max] is "
        "no reading": nearest(depth[top:top + band] * np.sqrt(1 + lateral**2), False),
    }
    expect_no_slip(got, slips, same)
    column = int(np.argmax(~np.isclose(np.where(np.isinf(got), -1, got),
                                       np.where(np.isinf(expected), -1, expected))))
    raise NotYet(f"column {column} gave {got[column]:.4f} m, expected "
                 f"{expected[column]:.4f} m (the nearest valid range in the band; inf if "
                 "none)")


# --- exercise 2: predict the reach -------------------------------------------------------


def true_reach(box_height: float = BOX_HEIGHT) -> float:
    """m: where the band's lower edge comes down to ``box_height``: the camera's height
    less the box's, over the band's slope ``tan(vfov / 2) scan_height / image_height``."""
    p = default_params().depth_scan
    return (p.height - box_height) / math.tan(p.vertical_half_angle)


@checker("prediction")
def reach_check(predicted: Callable[[], float], measured: float) -> str:
    """The distance written before the run against the formula and the run."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
           f"predicted_reach() gave {format_value(value)}; write one distance in m")
    truth = true_reach()
    p = default_params().depth_scan
    if abs(value - truth) <= 0.25:
        return (f"you predicted {value:.2f} m; the band reaches {BOX_HEIGHT} m at "
                f"{truth:.2f} m, and the run lost the box at {measured:.2f} m")
    whole_view = (p.height - BOX_HEIGHT) / math.tan(math.radians(p.vertical_fov_deg) / 2)
    if abs(value - whole_view) <= 0.25:
        raise NotYet(f"you predicted {value:.2f} m: that is where the whole image's lower "
                     f"edge reaches the box; the scan takes only {p.scan_height_px} of "
                     f"{p.image_height_px} rows, a narrower band: {truth:.2f} m")
    raise NotYet(f"you predicted {value:.2f} m; the band's lower edge falls "
                 f"{math.tan(p.vertical_half_angle):.3f} m per metre from "
                 f"{p.height:.2f} m and reaches {BOX_HEIGHT} m at {truth:.2f} m (the run: "
                 f"{measured:.2f} m)")


# --- exercise 3: which sensors could have seen it ------------------------------------------

SEEN_BY = frozenset({"sonar_link", "depth_scan_link"})
"""The frames that can see a table top 0.70-0.75 m up from the chair's way: the sonar's
17-degree cone from 0.69 m, the depth scan's band round 0.76 m."""


@checker("diagnosis")
def seen_check(could_have_seen: Callable[[], set]) -> str:
    """The set of frame ids against the heights and spreads in the URDF."""
    answer = could_have_seen()
    try:
        frames = {str(f) for f in answer}
    except TypeError:
        raise NotYet(f"could_have_seen() gave {format_value(answer)}; return a set of "
                     "frame ids such as {'lidar_link'}") from None
    known = set(default_params().sensors)
    unknown = frames - known
    expect(not unknown, f"{sorted(unknown)} are not the chair's frames; they are "
           f"{sorted(known)}")
    p = default_params()
    reasons = {
        "lidar_link": f"the lidar's plane is {p.lidar.height:.2f} m up: it passes under "
                      "the top and sees only the legs",
        "sonar_link": f"the sonar's cone spreads {p.sonar.half_angle_deg:.0f} degrees up "
                      f"and down from {p.sonar.height:.2f} m: the top is in it",
        "depth_scan_link": "the depth scan's band spreads "
                           f"{math.degrees(p.depth_scan.vertical_half_angle):.1f} degrees "
                           f"round {p.depth_scan.height:.2f} m: the top is in it",
    }
    for frame in p.ir.frame_ids:
        reasons[frame] = (f"the IR rangers are thin beams {p.ir.height:.2f} m up: under "
                          "the top")
    missing, extra = SEEN_BY - frames, frames - SEEN_BY
    if missing or extra:
        said = [f"{f}: {reasons.get(f, 'not a range sensor: it measures no distance at all')}"
                for f in sorted(missing | extra)]
        raise NotYet(("missing " + ", ".join(sorted(missing)) + "; " if missing else "")
                     + ("not " + ", ".join(sorted(extra)) + "; " if extra else "")
                     + " / ".join(said))
    return "the sonar and the depth scan; the lidar and the IR ring look under the top"
