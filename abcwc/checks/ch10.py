"""Checks for chapter 10, the EKF (thesis 4.3.5).

Exercises, on the state ``s = [x, y, theta, v, omega, b]`` (m, m, rad, m/s, rad/s, rad/s):

* ``motion_model(s, dt)`` and ``motion_jacobian(s, dt)``: the unicycle ``f`` (the bias
  held) and ``F = df/ds``, against :func:`abcwc.estimation.ekf.motion` /
  :func:`abcwc.estimation.ekf.motion_jacobian` and central finite differences;
* ``kalman_update(x, P, z, H, R) -> (x, P)``: one update step, against filterpy's
  ``filterpy.kalman.update`` for the wheel, gyro (``omega + b``) and fix measurements;
* ``nees_of_sample(truth, estimate, P)``: ``e^T P^-1 e`` for one pose error, the
  heading error wrapped to (-pi, pi].

The ``reference_*`` answers the notebook falls back on are the library's own.
* ``predicted_nees_verdicts()``: three words written down *before* section 8's runs:
  whether each EKF set-up's average NEES falls below, inside or above the band, judged
  against the runs.
* ``shares_inside(errors, sigmas)``: the share of the time each of x, y and the heading
  lies inside the filter's own 2-sigma band, measured on the five-minute drive and
  compared with the 95 % a 2-sigma band promises.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from abcwc.checks.report import NotYet, checker, expect, expect_close, expect_own, format_value
from abcwc.estimation.ekf import H_GYRO, H_POSE, H_WHEEL, POSE, kalman_update, nees
from abcwc.estimation.ekf import motion as reference_motion
from abcwc.estimation.ekf import motion_jacobian as reference_motion_jacobian
from abcwc.geometry import wrap_angle

__all__ = [
    "band_share_check",
    "nees_prediction_check",
    "kalman_update_check",
    "motion_check",
    "nees_check",
    "reference_kalman_update",
    "reference_motion",
    "reference_motion_jacobian",
    "reference_nees_sample",
]

reference_kalman_update = kalman_update


def reference_nees_sample(truth: np.ndarray, estimate: np.ndarray, p: np.ndarray) -> float:
    """NEES of one pose estimate: :func:`abcwc.estimation.nees` on a single row."""
    return float(nees(np.asarray(truth, dtype=float)[None], np.asarray(estimate, dtype=float)[None],
                      np.asarray(p, dtype=float)[None], POSE)[0])


# --- exercise 1: f and F --------------------------------------------------------------

_STATES = (  # (state, dt): straight, turning, reversing, across the +-pi seam, a long step
    ([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], 0.02),
    ([2.0, 9.0, 0.7, 0.8, 0.4, 0.005], 0.02),
    ([30.0, 8.8, -2.2, -0.3, -0.6, -0.004], 0.02),
    ([5.0, -1.0, 3.1, 0.5, 0.8, 0.002], 0.02),
    ([1.0, 2.0, 1.3, 0.9, -0.2, 0.01], 0.5),
)


def _fmt(values: np.ndarray) -> str:
    return "[" + ", ".join(f"{v:.4g}" for v in np.ravel(values)) + "]"


def _as_array(value: object, shape: tuple[int, ...], what: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise NotYet(f"{what} gave {format_value(value)}, expected an array of shape "
                     f"{shape}") from None
    expect(arr.shape == shape, f"{what} gave an array of shape {arr.shape}, expected {shape}")
    return arr


def _finite_difference(f: Callable, s: np.ndarray, dt: float, eps: float = 1e-6) -> np.ndarray:
    columns = []
    for e in np.eye(len(s)):
        plus = np.asarray(f(s + eps * e, dt), dtype=float)
        minus = np.asarray(f(s - eps * e, dt), dtype=float)
        columns.append((plus - minus) / (2 * eps))
    return np.column_stack(columns)


@checker("motion model f and Jacobian F")
def motion_check(motion_fn: Callable[[np.ndarray, float], np.ndarray],
                 jacobian_fn: Callable[[np.ndarray, float], np.ndarray]) -> str:
    """Check ``motion_fn(s, dt)`` (6,) and ``jacobian_fn(s, dt)`` (6, 6) at five states."""
    expect_own(jacobian_fn, reference_motion, reference_motion_jacobian)
    expect_own(motion_fn, reference_motion, reference_motion_jacobian)
    names = ("x'", "y'", "theta'", "v'", "omega'", "b'")
    for state, dt in _STATES:
        s = np.array(state)
        got = _as_array(motion_fn(s.copy(), dt), (6,), f"motion_model(s={_fmt(s)}, dt={dt})")
        want = reference_motion(s, dt)
        for i, name in enumerate(names):
            expect_close(got[i], want[i], what=f"{name} for s = {_fmt(s)}, dt = {dt}",
                         rtol=0.0, atol=1e-9,
                         ref="x' = x + v dt cos(theta), y' = y + v dt sin(theta), "
                             "theta' = theta + omega dt; v, omega and b are held")
    for state, dt in _STATES:
        s = np.array(state)
        got = _as_array(jacobian_fn(s.copy(), dt), (6, 6),
                        f"motion_jacobian(s={_fmt(s)}, dt={dt})")
        want = reference_motion_jacobian(s, dt)
        bad = np.argwhere(~np.isclose(got, want, rtol=0.0, atol=1e-9))
        if len(bad):
            i, j = (int(k) for k in bad[0])
            raise NotYet(f"F[{i}, {j}] = d{names[i][:-1]}'/d{names[j][:-1]} gave "
                         f"{got[i, j]:.6g}, expected {want[i, j]:.6g} for s = {_fmt(s)}, "
                         f"dt = {dt} (differentiate the row of f for {names[i]}; "
                         f"{len(bad)} of 36 entries differ)")
        numeric = _finite_difference(motion_fn, s, dt)
        expect(np.allclose(got, numeric, atol=1e-6),
               f"F disagrees with finite differences of your f at s = {_fmt(s)}")
    return (f"f and F match the library at {len(_STATES)} states, and F matches central "
            "finite differences of your f")


# --- exercise 2: one Kalman update ----------------------------------------------------


def _update_cases() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                  np.ndarray]]:
    rng = np.random.default_rng(10)
    a = rng.normal(scale=0.05, size=(6, 6))
    p = a @ a.T + np.diag([1e-3, 1e-3, 1e-4, 1e-4, 1e-4, 2.5e-5])
    x = np.array([12.0, 8.9, 0.3, 0.85, 0.12, 0.004])
    return [
        ("wheel update z = [v, omega]", x, p, np.array([0.9, 0.1]), np.asarray(H_WHEEL),
         np.diag([0.007 ** 2, 0.032 ** 2])),
        ("gyro update z = omega + b", x, p, np.array([0.131]), np.asarray(H_GYRO),
         np.array([[0.003 ** 2]])),
        ("fix z = [x, y, theta]", x, p, np.array([12.1, 8.85, 0.28]), np.asarray(H_POSE),
         np.diag([0.05 ** 2, 0.05 ** 2, 0.02 ** 2])),
    ]


@checker("one Kalman update")
def kalman_update_check(update_fn: Callable[..., tuple[np.ndarray, np.ndarray]]) -> str:
    """Check ``update_fn(x, P, z, H, R) -> (x, P)`` against filterpy's ``update``."""
    expect_own(update_fn, reference_kalman_update)
    from filterpy.kalman import update as filterpy_update

    for what, x, p, z, h, r in _update_cases():
        inputs = (x.copy(), p.copy(), z.copy(), h.copy(), r.copy())
        out = update_fn(*inputs)
        expect(isinstance(out, tuple) and len(out) == 2,
               f"{what}: return a tuple (x, P), got {format_value(out)}")
        got_x = _as_array(out[0], (6,), f"{what}: x")
        got_p = _as_array(out[1], (6, 6), f"{what}: P")
        expect(all(np.array_equal(a, b) for a, b in zip(inputs, (x, p, z, h, r))),
               f"{what}: your function changed the arrays passed in; compute new ones "
               "(x = x + K @ y, not x += ...)")
        want_x, want_p = filterpy_update(x.reshape(-1, 1), p, z, r, h)
        expect_close(got_x, want_x[:, 0], what=f"{what}: x", rtol=1e-9, atol=1e-12,
                     ref="x + K (z - H x), K = P H^T S^-1, S = H P H^T + R; filterpy")
        expect(not np.allclose(got_p, p, atol=1e-12),
               f"{what}: P came back unchanged; a measurement always shrinks it "
               "(P = P - K S K^T)")
        expect_close(got_p, want_p, what=f"{what}: P", rtol=1e-9, atol=1e-14,
                     ref="P - K S K^T = (I - K H) P; filterpy")
    return "wheel, gyro and fix updates match filterpy.kalman.update"


# --- exercise 3: NEES of one sample ---------------------------------------------------


@checker("NEES of a sample")
def nees_check(nees_fn: Callable[[np.ndarray, np.ndarray, np.ndarray], float]) -> str:
    """Check ``nees_fn(truth, estimate, P)`` for a pose (x, y, theta) and its 3 x 3 P."""
    expect_own(nees_fn, reference_nees_sample, nees)
    diag = np.diag([0.01, 0.04, 0.0025])
    rng = np.random.default_rng(3)
    a = rng.normal(scale=0.1, size=(3, 3))
    full = a @ a.T + np.diag([1e-3, 1e-3, 1e-4])
    cases = [
        ("0.1 m off in x, sigma_x 0.1 m", [1.1, 2.0, 0.5], [1.0, 2.0, 0.5], diag, 1.0),
        ("exactly right", [4.0, 3.0, -1.0], [4.0, 3.0, -1.0], diag, 0.0),
        ("off in all three", [1.2, 1.9, 0.4], [1.0, 2.0, 0.5], diag,
         0.2 ** 2 / 0.01 + 0.1 ** 2 / 0.04 + 0.1 ** 2 / 0.0025),
    ]
    cases += [("a full covariance", [10.0, 8.7, 2.0], [10.08, 8.75, 1.97], full, None),
              ("heading across the +-pi seam", [0.0, 0.0, 3.1], [0.0, 0.0, -3.1], diag, None)]
    for what, truth, estimate, p, closed in cases:
        truth, estimate = np.array(truth), np.array(estimate)
        want = reference_nees_sample(truth, estimate, p) if closed is None else closed
        got = nees_fn(truth.copy(), estimate.copy(), p.copy())
        if what.startswith("heading"):
            raw = (truth[2] - estimate[2]) ** 2 / p[2, 2]
            expect(not (np.ndim(got) == 0 and math.isclose(float(got), raw, rel_tol=1e-6)),
                   f"{what}: you used a heading error of {truth[2] - estimate[2]:.2f} rad; "
                   "3.1 and -3.1 rad are 0.08 rad apart: wrap the error to (-pi, pi]")
        e = truth - estimate
        e[2] = wrap_angle(e[2])
        expect(not (np.ndim(got) == 0 and math.isclose(float(got), e @ p @ e, rel_tol=1e-6)
                    and not math.isclose(e @ p @ e, want, rel_tol=1e-6)),
               f"{what}: you computed e^T P e; the NEES divides by the covariance: "
               "e^T P^-1 e (np.linalg.solve(P, e))")
        expect(np.ndim(got) == 0, f"{what}: expected one number, got {format_value(got)}")
        expect_close(got, want, what=what, rtol=1e-9, atol=1e-12, ref="e^T P^-1 e")
    return f"{len(cases)} samples match, the +-pi seam included"


# --- predict, then run: which set-up is honest --------------------------------------------------

VERDICTS = ("below", "inside", "above")
_WHY = {
    "bias held, gyro R = white noise": "a held bias with no uncertainty leaves its error out of "
    "the filter's sums: it believes its heading far better than it is (overconfident)",
    "bias held, its error spread into R": "the bias error, spread into the gyro's noise for "
    "the minute it was worked out for, is about the right size over that minute",
    "bias as a state (this chapter)": "with the bias a state the filter measures it and "
    "carries its uncertainty: the noise model of section 4, honest",
}


@checker("prediction")
def nees_prediction_check(predicted: Callable[[], tuple[str, str, str]],
                          verdicts: dict[str, str]) -> str:
    """Three of ``VERDICTS``, one per set-up in the order ``verdicts`` lists them (the
    runs' own), written before the runs."""
    value = predicted()
    try:
        guesses = tuple(value)
    except TypeError:
        guesses = ()
    expect(len(guesses) == len(verdicts) and all(g in VERDICTS for g in guesses),
           f"predicted_nees_verdicts() gave {format_value(value)}; return {len(verdicts)} of "
           f"{VERDICTS}, one per set-up, in the order of the table")
    wrong = [f"{name}: {measured}, not {guess} ({_WHY.get(name, '')})"
             for (name, measured), guess in zip(verdicts.items(), guesses) if guess != measured]
    if wrong:
        raise NotYet("not yet: " + "; ".join(wrong))
    return "all three as the runs found: " + ", ".join(
        f"{name} {measured}" for name, measured in verdicts.items())


# --- measure: how often the errors lie inside the filter's own band ----------------------------


@checker("measurement")
def band_share_check(fn: Callable[[np.ndarray, np.ndarray], np.ndarray], errors: np.ndarray,
                     sigmas: np.ndarray) -> str:
    """``fn(errors, sigmas)``: for (N, 3) errors of x, y, heading and the filter's (N, 3)
    standard deviations, the share of the rows in which each error lies within two of its
    standard deviations (3 fractions), against the same count made here."""
    errors, sigmas = np.asarray(errors, float), np.asarray(sigmas, float)
    got = fn(errors.copy(), sigmas.copy())
    try:
        got = np.asarray(got, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise NotYet(f"shares_inside gave {format_value(got)}; return three fractions: x, y, "
                     "heading") from None
    expect(got.size == 3, f"shares_inside gave {got.size} numbers; return three, one each "
           "for x, y and the heading")
    expected = (np.abs(errors) <= 2 * sigmas).mean(axis=0)
    if np.allclose(got, expected, atol=0.005):
        verdict = ("more often than the 95 % a 2-sigma band promises: a little cautious"
                   if expected.min() > 0.97 else "about the 95 % a 2-sigma band promises")
        return (f"x {100 * got[0]:.0f} %, y {100 * got[1]:.0f} %, heading {100 * got[2]:.0f} % "
                f"of the time inside +-2 sigma: {verdict}")
    if np.allclose(got, 100 * expected, atol=0.5):
        raise NotYet("those are percentages; return fractions between 0 and 1")
    if np.allclose(got, (np.abs(errors) <= sigmas).mean(axis=0), atol=0.005):
        raise NotYet("that is the 1-sigma band; the exercise asks for +-2 sigma")
    if np.allclose(got, (np.abs(errors) <= 2 * sigmas**2).mean(axis=0), atol=0.005):
        raise NotYet("sigmas are standard deviations already (metres and radians); "
                     "squaring them compares errors with variances")
    raise NotYet(f"got {np.round(got, 3).tolist()}, expected {np.round(expected, 3).tolist()}: "
                 "the share of rows with |error| <= 2 sigma, per column")
