"""Checks for chapter 11, the chair's description and frames (thesis 3.3.7, 4.3.2;
the URDF specification; ROS REP 103 and REP 105).

Exercises:

* ``origin_transform(xyz, rpy)``: the 4 x 4 transform of a URDF joint origin,
  ``R = Rz(yaw) Ry(pitch) Rx(roll)`` and the translation;
* ``predicted_hit()``: an (x, y) written down *before* the cell that computes it: where
  in ``odom`` the thing an IR ranger sees lies;
* ``biggest_correction()``: a diagnosis from a log of ``odom -> base_link`` and the
  localiser's ``map -> base_link``: when the localiser made its big correction, and how
  far (m) and by how much (deg) it moved the chair's estimate.

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_no_slip,
    expect_own,
    format_value,
    numbers,
)
from abcwc.description import homogeneous
from abcwc.geometry import compose, inverse, wrap_angle
from abcwc.params import default_params

__all__ = [
    "HIT_RANGE",
    "HIT_RANGER",
    "HIT_CHAIR_POSE",
    "LocalisationLog",
    "correction_check",
    "hit_check",
    "localisation_log",
    "origin_check",
    "reference_biggest_correction",
    "reference_origin_transform",
]

# --- reference answers ----------------------------------------------------------------


def reference_origin_transform(xyz, rpy) -> np.ndarray:
    """4 x 4 transform of a URDF origin (the library's :func:`homogeneous`)."""
    return homogeneous(tuple(map(float, xyz)), tuple(map(float, rpy)))


# --- exercise 1: a joint's origin -------------------------------------------------------


def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def _origin(xyz, rotation: np.ndarray, rotate_translation: bool = False) -> np.ndarray:
    transform = np.eye(4)
    transform[:3, :3] = rotation
    transform[:3, 3] = rotation @ xyz if rotate_translation else xyz
    return transform


def origin_cases() -> list[tuple[np.ndarray, np.ndarray]]:
    """The (xyz, rpy) pairs the check tries: the chair's IR ranger 2, a camera tilted
    down, and seeded random ones with all three angles."""
    rng = np.random.default_rng(11)
    cases = [(np.array([-0.1, 0.17320508075688773, 0.0]), np.array([0.0, 0.0, 2 * math.pi / 3])),
             (np.array([0.3, 0.0, 0.73]), np.array([0.0, 0.35, 0.0]))]
    for _ in range(4):
        cases.append((rng.uniform(-1, 1, 3), rng.uniform(-math.pi, math.pi, 3)))
    return cases


def _same_transform(got: np.ndarray, wrong: np.ndarray) -> bool:
    return np.allclose(got, wrong, atol=1e-9)


@checker("joint origin")
def origin_check(fn: Callable) -> str:
    """``fn(xyz, rpy)`` against the rotations multiplied out here, and the usual slips."""
    expect_own(fn, reference_origin_transform, homogeneous)
    for xyz, rpy in origin_cases():
        roll, pitch, yaw = rpy
        expected = _origin(xyz, _rz(yaw) @ _ry(pitch) @ _rx(roll))
        got = fn(xyz.copy(), rpy.copy())
        try:
            got = np.asarray(got, dtype=float)
        except (TypeError, ValueError):
            raise NotYet(f"origin_transform gave {format_value(got)}; return a 4 x 4 "
                         "array") from None
        expect(got.shape == (4, 4), f"origin_transform gave an array of shape {got.shape}; "
               "a homogeneous transform is 4 x 4 (rotation, translation, then 0 0 0 1)")
        if np.allclose(got, expected, atol=1e-9):
            continue
        slips = {
            "the rotations are multiplied the other way round: URDF's rpy turns about the "
            "fixed axes, roll first, so R = Rz(yaw) Ry(pitch) Rx(roll)":
                _origin(xyz, _rx(roll) @ _ry(pitch) @ _rz(yaw)),
            "the rotation is transposed: that is the parent's axes in the child, the "
            "inverse of what a joint origin gives":
                _origin(xyz, (_rz(yaw) @ _ry(pitch) @ _rx(roll)).T),
            "the translation is rotated: a joint's xyz is already in the parent's frame":
                _origin(xyz, _rz(yaw) @ _ry(pitch) @ _rx(roll), rotate_translation=True),
            "the angles were taken as degrees: URDF angles are radians":
                _origin(xyz, _rz(math.radians(yaw)) @ _ry(math.radians(pitch))
                        @ _rx(math.radians(roll))),
        }
        expect_no_slip(got, slips, _same_transform,
                       prefix=f"xyz {np.round(xyz, 3).tolist()}, rpy {np.round(rpy, 3).tolist()}: ")
        expect(np.allclose(got[3], [0, 0, 0, 1]), "the bottom row of a homogeneous "
               f"transform is 0 0 0 1, got {np.round(got[3], 3).tolist()}")
        raise NotYet(f"xyz {np.round(xyz, 3).tolist()}, rpy {np.round(rpy, 3).tolist()}: "
                     f"got\n{np.round(got, 3)}\nexpected\n{np.round(expected, 3)}")
    return f"{len(origin_cases())} origins, including all three angles at once"


# --- exercise 2: predict where a ranger's reading lies ----------------------------------

HIT_RANGER = "ir_2_link"
"""The IR ranger of exercise 2."""
HIT_RANGE = 0.50
"""m: what it reads."""
HIT_CHAIR_POSE = (2.0, 1.0, math.pi / 2)
"""The chair's pose in odom (m, m, rad): 2 m along, 1 m left, facing +y."""


def _hit(mount: tuple[float, float, float], chair: tuple[float, float, float],
         reach: float) -> np.ndarray:
    mx, my, myaw = mount
    x, y, theta = chair
    bx, by = mx + reach * math.cos(myaw), my + reach * math.sin(myaw)
    c, s = math.cos(theta), math.sin(theta)
    return np.array([x + c * bx - s * by, y + s * bx + c * by])


@checker("prediction")
def hit_check(predicted: Callable[[], tuple[float, float]]) -> str:
    """The (x, y) written before the run against the chain worked out here."""
    value = predicted()
    try:
        point = np.asarray(value, dtype=float).reshape(2)
    except (TypeError, ValueError):
        raise NotYet(f"predicted_hit() gave {format_value(value)}; write (x, y) in m") from None
    expect(bool(np.all(np.isfinite(point))), "predicted_hit() must be two finite numbers")
    p = default_params()
    mount = tuple(p.ir.mounts[p.ir.frame_ids.index(HIT_RANGER)])
    expected = _hit(mount, HIT_CHAIR_POSE, HIT_RANGE)
    error = float(np.hypot(*(point - expected)))
    if error <= 0.05:
        return (f"you predicted ({point[0]:.2f}, {point[1]:.2f}), the tree gives "
                f"({expected[0]:.2f}, {expected[1]:.2f}) m in odom")
    slips = {
        "the chair's heading is missing: base_link's x points along odom's y here":
            _hit(mount, (*HIT_CHAIR_POSE[:2], 0.0), HIT_RANGE),
        f"the ranger's own facing is missing: {HIT_RANGER} faces "
        f"{math.degrees(mount[2]):.0f} degrees from the chair's front":
            _hit((*mount[:2], 0.0), HIT_CHAIR_POSE, HIT_RANGE),
        "the ranger's place on the rod is missing: it sits "
        f"({mount[0]:.2f}, {mount[1]:.2f}) m from base_link":
            _hit((0.0, 0.0, mount[2]), HIT_CHAIR_POSE, HIT_RANGE),
        "the turns go clockwise: angles count counter-clockwise from x (REP 103)":
            _hit((mount[0], -mount[1], -mount[2]), (*HIT_CHAIR_POSE[:2], -HIT_CHAIR_POSE[2]),
                 HIT_RANGE),
    }
    expect_no_slip(point, slips, lambda got, wrong: np.hypot(*(got - wrong)) <= 0.05,
                   prefix=f"you predicted ({point[0]:.2f}, {point[1]:.2f}), the tree gives "
                          f"({expected[0]:.2f}, {expected[1]:.2f}): ")
    raise NotYet(f"you predicted ({point[0]:.2f}, {point[1]:.2f}), the tree gives "
                 f"({expected[0]:.2f}, {expected[1]:.2f}), {error:.2f} m away: go down the "
                 "chain once more (odom -> base_link -> base_rod -> the ranger -> 0.5 m "
                 "along its x)")


# --- exercise 3: diagnose the localiser's correction ------------------------------------


@dataclass(frozen=True)
class LocalisationLog:
    """A drive as a localiser sees it, 10 Hz: ``odom`` is ``odom -> base_link`` (the
    wheel odometry, smooth), ``map`` the localiser's ``map -> base_link`` (m, m, rad)."""

    t: np.ndarray
    odom: np.ndarray
    map: np.ndarray


@dataclass(frozen=True)
class _Correction:
    """What the check knows of a log and the student is to find: when the localiser
    caught up after the corridor (s), and how far (m) and by how much (deg) it moved the
    estimate then."""

    at: float
    metres: float
    degrees: float


def _integrate(v: np.ndarray, w: np.ndarray, dt: float, start: np.ndarray) -> np.ndarray:
    """Poses from speeds (exact arcs would be overkill at 10 Hz: midpoint heading)."""
    theta = start[2] + np.concatenate([[0.0], np.cumsum(w * dt)])
    mid = (theta[:-1] + theta[1:]) / 2
    x = start[0] + np.concatenate([[0.0], np.cumsum(v * dt * np.cos(mid))])
    y = start[1] + np.concatenate([[0.0], np.cumsum(v * dt * np.sin(mid))])
    return np.column_stack([x, y, theta])


def localisation_log(seed: int = 11) -> LocalisationLog:
    """The log of :func:`_drive` as the student gets it: poses only, not the answer."""
    return _drive(seed)[0]


def _drive(seed: int) -> tuple[LocalisationLog, _Correction]:
    """A 60 s drive: the odometry turns 3 % too much and drifts 0.25 deg/s; the localiser
    fixes the estimate on the map every second, except in a corridor where its scans
    match nothing (from 22 s to a moment between 38 and 45 s that the seed picks), after
    which one fix pulls the estimate back."""
    rng = np.random.default_rng(seed)
    dt, steps = 0.1, 600
    t = np.arange(steps + 1) * dt
    v = np.full(steps, 0.6)
    w = 0.25 * np.sin(0.1 * t[:-1])
    truth = _integrate(v, w, dt, np.array([4.0, 3.0, 0.5]))
    odom = _integrate(0.99 * v, 1.03 * w + math.radians(0.25), dt, np.zeros(3))
    corridor = (22.0, round(float(rng.uniform(38.0, 45.0)), 1))
    map_to_odom = np.asarray(compose(truth[0], inverse(odom[0])), dtype=float)
    estimate = np.zeros_like(truth)
    correction = _Correction(math.nan, math.nan, math.nan)
    for k, time in enumerate(t):
        fix = (abs(time - round(time)) < 1e-9 and not corridor[0] < time < corridor[1]) \
            or abs(time - corridor[1]) < 1e-9
        if fix:  # the scan match puts the estimate near the truth
            matched = truth[k] + rng.normal(0.0, [0.01, 0.01, 0.002])
            before = np.asarray(compose(map_to_odom, odom[k]), dtype=float)
            map_to_odom = np.asarray(compose(matched, inverse(odom[k])), dtype=float)
            if abs(time - corridor[1]) < 1e-9:
                correction = _Correction(
                    float(time), float(np.hypot(*(matched[:2] - before[:2]))),
                    float(math.degrees(wrap_angle(matched[2] - before[2]))))
        estimate[k] = np.asarray(compose(map_to_odom, odom[k]), dtype=float)
    estimate[:, 2] = wrap_angle(estimate[:, 2])
    odom[:, 2] = wrap_angle(odom[:, 2])
    return LocalisationLog(t, odom, estimate), correction


def reference_biggest_correction(log: LocalisationLog) -> tuple[float, float, float]:
    """(t s, m, deg): the largest change of ``map -> odom`` between two samples, as the
    distance and turn it gave the chair's estimate."""
    map_to_odom = np.asarray(compose(log.map, inverse(log.odom)), dtype=float)
    # where the chair would be by the previous correction, at each sample's odometry
    by_old = np.asarray(compose(map_to_odom[:-1], log.odom[1:]), dtype=float)
    moved = np.hypot(*(log.map[1:, :2] - by_old[:, :2]).T)
    k = int(np.argmax(moved))
    turned = math.degrees(wrap_angle(log.map[k + 1, 2] - by_old[k, 2]))
    return float(log.t[k + 1]), float(moved[k]), float(turned)


@checker("the correction")
def correction_check(fn: Callable[[LocalisationLog], tuple[float, float, float]],
                     seeds: tuple[int, ...] = (11, 12, 13)) -> str:
    """``fn(log)`` on the chapter's log and on logs of other seeds."""
    expect_own(fn, reference_biggest_correction)
    for seed in seeds:
        log, truth = _drive(seed)
        value = fn(log)
        when, metres, degrees = numbers(value, 3, "biggest_correction",
                                        "return (time s, distance m, turn deg)")
        true_metres, true_degrees = truth.metres, truth.degrees
        found = f"(seed {seed}) you found t = {when:.1f} s, {metres:.3f} m, {degrees:+.2f} deg"
        if abs(when - truth.at) > 0.05:
            jumps = _map_to_odom_jumps(log)
            if abs(when - log.t[1 + int(np.argmax(jumps))]) < 0.05:
                raise NotYet(f"{found}; that is where map -> odom's origin jumped most, "
                             "but a small turn about the odom origin, metres from the "
                             "chair, swings that origin a long way: measure where each "
                             "correction puts the chair")
            raise NotYet(f"{found}; the big correction came at t = {truth.at:.1f} s. "
                         "Samples where the chair moves far are not corrections: look at "
                         "map -> odom, which only the localiser changes")
        if abs(degrees - math.radians(true_degrees)) < 0.01 and abs(true_degrees) > 0.5:
            raise NotYet(f"{found}; the turn looks like radians: give degrees")
        if abs(degrees - true_degrees) > 0.2:
            raise NotYet(f"{found}; the estimate turned {true_degrees:+.2f} deg then "
                         "(the change in map -> odom's angle; mind its sign)")
        if abs(metres - true_metres) > 0.01:
            odom_change = _map_to_odom_jump(log, truth.at)
            if abs(metres - odom_change) < 0.01:
                raise NotYet(f"{found}; that is how far map -> odom's origin moved, which "
                             "a turn about the far-away odom origin distorts; the chair's "
                             f"estimate moved {true_metres:.3f} m")
            raise NotYet(f"{found}; the chair's estimate moved {true_metres:.3f} m: compare "
                         "where the new map -> odom puts the chair with where the old one "
                         "would have put it, at the same odometry (the chair's own motion "
                         "in that tenth of a second is not part of the correction)")
    return (f"{len(seeds)} logs: the corridor's drift caught up at the right moment, "
            "by the right distance and turn")


def _map_to_odom_jumps(log: LocalisationLog) -> np.ndarray:
    """How far map -> odom's origin moved between each two samples (m)."""
    map_to_odom = np.asarray(compose(log.map, inverse(log.odom)), dtype=float)
    return np.hypot(*np.diff(map_to_odom[:, :2], axis=0).T)


def _map_to_odom_jump(log: LocalisationLog, at: float) -> float:
    """How far map -> odom's origin moved at time ``at`` (s), in m."""
    k = int(np.argmin(np.abs(log.t - at)))
    return float(_map_to_odom_jumps(log)[k - 1])
