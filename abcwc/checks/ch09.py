"""Checks for chapter 09, gyro + encoders (thesis 4.2.4, eqns 14-16).

Exercises:

* ``estimate_bias(samples)``: the gyro's bias (rad/s), the mean of the rates read
  while the chair stands still; a ``ValueError`` for no samples or a NaN/inf one;
* ``integrate_heading(t, gyro_z, theta0, bias)``: the heading (rad) at every timestamp,
  ``theta[0] = theta0`` and ``theta[k + 1] = theta[k] + (g[k] - bias) (t[k + 1] - t[k])``
  (eqn 14, one rectangle per period; each sample is the rate over the period that
  starts at its timestamp);
* ``fused_step(pose, d_left, d_right, gyro_z, dt, bias)``: one step of eqn 16, the
  heading turned by ``phi = (gyro_z - bias) dt`` and the position moved by the wheels'
  mean travel ``(d_r + d_l) / 2`` along the step's mean heading ``theta + phi / 2``;
* ``predicted_end_heading_errors()``: two numbers written down *before* the five laps are
  plotted: the wheels' and the raw gyro's heading error at the end (degrees), from the
  worn chair's geometry and the bias the first seconds gave;
* ``measured_best_window()``: the pessimistic gyro's best standing time (s), measured by
  experiment on simulated power-ups, judged against section 2's formula
  ``T* = sqrt(3) sigma_w sqrt(dt) / K``.

Each ``reference_*`` answer, the one the notebook falls back on, is the library's own
(:mod:`abcwc.estimation.gyro`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_close,
    expect_no_slip,
    expect_own,
    format_value,
    numbers,
)
from abcwc.estimation.gyro import (
    estimate_gyro_bias,
    gyro_odometry_from_log,
    gyro_odometry_step,
    integrate_gyro_heading,
)
from abcwc.estimation.odometry import log_wheel_travel
from abcwc.geometry import wrap_angle
from abcwc.log import RunLog
from abcwc.params import default_params
from abcwc.types import Pose2D, Twist

__all__ = [
    "END_TURN",
    "best_standing_time",
    "end_heading_prediction_check",
    "best_window_check",
    "bias_check",
    "fused_step_check",
    "heading_check",
    "reference_estimate_bias",
    "reference_fused_step",
    "reference_integrate_heading",
    "still_log",
    "turning_log",
]

reference_estimate_bias = estimate_gyro_bias
reference_integrate_heading = integrate_gyro_heading
reference_fused_step = gyro_odometry_step

PERIOD = 0.02  # s, the gyro's 50 Hz


def still_log(seconds: float = 3.0, seed: int = 9) -> tuple[RunLog, float]:
    """A simulated chair standing still for ``seconds``, and its gyro's true bias (rad/s)."""
    from abcwc.sim.base import SimBase

    sim = SimBase(world="lab", seed=seed, start="centre", people=False)
    log = sim.drive(Twist(0.0, 0.0), seconds)
    return log, sim.gyro.bias


def turning_log(seconds: float = 10.0, still: float = 2.0, seed: int = 5
                ) -> tuple[RunLog, float]:
    """The worn simulated chair standing ``still`` seconds, then driving curves both ways.

    Returns the log and the gyro bias (rad/s) estimated from the still part.
    """
    from abcwc.sim.base import SimBase

    sim = SimBase(world="lab", seed=seed, start="centre", people=False)
    log = sim.run(lambda frame: Twist(0.0, 0.0) if frame.t < still
                  else Twist(0.5, 0.9 * math.sin(0.8 * (frame.t - still))), still + seconds)
    return log, estimate_gyro_bias(log.gyro_z[log.t <= still])


# --- exercise 1: the bias ---------------------------------------------------------------


def _refuses(fn: Callable[[object], object], samples: object, what: str) -> None:
    """Require ``fn(samples)`` to raise ValueError."""
    try:
        got = fn(samples)
    except ValueError:
        return
    except NotImplementedError:
        raise
    except Exception as exc:  # noqa: BLE001 - student code may raise anything
        raise NotYet(f"{what} raised {type(exc).__name__}; raise a ValueError that says "
                     "what is wrong") from None
    raise NotYet(f"{what} gave {format_value(got)}; refuse it with a ValueError (a bias "
                 "that is not a number would spoil every heading after it)")


@checker("gyro bias")
def bias_check(fn: Callable[[np.ndarray], float]) -> str:
    """``fn(samples) -> bias`` (rad/s): the mean of a still window; refuses empty/NaN."""
    expect_own(fn, reference_estimate_bias)
    rng = np.random.default_rng(9)
    log, truth = still_log()
    cases = [
        ("150 samples of exactly 0.0042 rad/s", np.full(150, 0.0042), 0.0042),
        ("the list [0.01, 0.02, 0.06]", [0.01, 0.02, 0.06], 0.03),
        ("250 noisy samples", rng.normal(0.003, 0.003, 250), None),
        ("a negative bias", rng.normal(-0.006, 0.003, 50), None),
        ("3 s of the simulated chair standing still", log.gyro_z.copy(), None),
    ]
    for what, samples, closed in cases:
        want = reference_estimate_bias(samples) if closed is None else closed
        got = fn(samples)
        median = float(np.median(np.asarray(samples, dtype=float)))
        expect(not (_number(got) and not math.isclose(median, want, abs_tol=1e-12)
                    and math.isclose(float(got), median, abs_tol=1e-12)),
               f"{what}: you returned the median ({median:.6f} rad/s); the bias is the "
               "mean of the samples")
        expect(_number(got), f"{what} gave {format_value(got)}, expected one number (rad/s)")
        expect_close(got, want, what=what, rtol=1e-9, atol=1e-12, unit="rad/s",
                     ref="the mean of the still samples")
    _refuses(fn, np.array([]), "no samples at all")
    _refuses(fn, np.array([0.004, np.nan, 0.005]), "a NaN sample (a missed gyro reading)")
    _refuses(fn, [0.004, math.inf], "an inf sample")
    estimate = reference_estimate_bias(log.gyro_z)
    return (f"{len(cases)} windows match and empty/NaN/inf are refused; 3 s still gives "
            f"{estimate:.5f} rad/s, the simulator's true bias is {truth:.5f} rad/s")


# --- exercise 2: the heading --------------------------------------------------------------


def _headings(got: object, n: int, what: str) -> np.ndarray:
    try:
        arr = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise NotYet(f"{what} gave {format_value(got)}, expected an array of {n} "
                     "headings (rad)") from None
    shape = "a single number" if arr.ndim == 0 else f"an array of shape {arr.shape}"
    expect(arr.shape == (n,), f"{what} gave {shape}, expected {n} headings, one per "
           "timestamp (the first is theta0)")
    return arr


def _wrapped_close(got: np.ndarray, want: np.ndarray, what: str, ref: str,
                   atol: float = 1e-9) -> None:
    """Compare headings modulo 2 pi (wrapped or unwrapped answers both pass)."""
    diff = wrap_angle(got - want)
    bad = np.flatnonzero(~(np.abs(diff) <= atol))
    if bad.size:
        k = int(bad[0])
        raise NotYet(f"{what}: heading[{k}] gave {got[k]:.6g} rad, expected {want[k]:.6g} rad "
                     f"(modulo 2 pi; {ref}; {bad.size} of {got.size} differ)")


@checker("heading from the gyro")
def heading_check(fn: Callable[..., np.ndarray]) -> str:
    """``fn(t, gyro_z, theta0, bias) -> headings`` against eqn 14, rectangle per period."""
    expect_own(fn, reference_integrate_heading)
    rng = np.random.default_rng(14)
    t2 = PERIOD * np.arange(101)
    t60 = PERIOD * np.arange(3001)
    t6 = PERIOD * np.arange(301)
    jitter = np.concatenate([[0.0], np.cumsum(PERIOD + rng.uniform(-0.004, 0.004, 400))])
    wavy = 0.6 * np.sin(1.3 * jitter) + 0.01 + rng.normal(0.0, 0.003, jitter.size)
    log, log_bias = turning_log()
    cases = [  # what, t, gyro, theta0, bias, closed form (or None: the library)
        ("constant 0.3 rad/s for 2 s from 0.5 rad", t2, np.full(t2.size, 0.3), 0.5, 0.0,
         0.5 + 0.3 * t2),
        ("standing still, a 0.005 rad/s bias left in, 60 s", t60, np.full(t60.size, 0.005),
         -1.0, 0.0, -1.0 + 0.005 * t60),
        ("the same with the bias removed", t60, np.full(t60.size, 0.005), -1.0, 0.005,
         np.full(t60.size, -1.0)),
        ("one and a half turns at pi/2 rad/s from 3.0 rad", t6, np.full(t6.size, np.pi / 2),
         3.0, 0.0, 3.0 + np.pi / 2 * t6),
        ("a wavy rate, uneven timestamps, bias 0.01", jitter, wavy, 0.2, 0.01, None),
        ("12 s of the simulated chair", log.t, log.gyro_z, 0.0, log_bias, None),
    ]
    for what, t, gyro, theta0, bias, closed in cases:
        want = reference_integrate_heading(t, gyro, theta0, bias) if closed is None else closed
        got = _headings(fn(t.copy(), gyro.copy(), theta0, bias), t.size, what)
        expect(abs(wrap_angle(got[0] - theta0)) < 1e-12,
               f"{what}: heading[0] gave {got[0]:.6g} rad, expected theta0 = {theta0:g} rad "
               "(the heading at the first timestamp is where we start)")
        if closed is None:
            _hint_rule(got, want, t, gyro, theta0, bias, what)
        _wrapped_close(got, want, what, "theta[k+1] = theta[k] + (g[k] - bias) dt[k]")
    return (f"{len(cases)} cases: constant rate -> straight line, a 0.005 rad/s bias drifts "
            f"{0.005 * 60:.2f} rad in 60 s, uneven timestamps and a full turn")


def _headings_match(a: np.ndarray, b: np.ndarray, atol: float = 1e-9) -> bool:
    return bool(np.all(np.abs(wrap_angle(a - b)) <= atol))


def _hint_rule(got: np.ndarray, want: np.ndarray, t: np.ndarray, gyro: np.ndarray,
               theta0: float, bias: float, what: str) -> None:
    """Say so when the answer integrates with another sample than the period's own."""
    dt = np.diff(t)
    rate = gyro - bias
    common = "one common dt instead of each t[k + 1] - t[k]"
    others = [
        ("the sample at the end of each period (g[k + 1])", rate[1:] * dt),
        ("the trapezoid (g[k] + g[k + 1]) / 2", (rate[1:] + rate[:-1]) / 2 * dt),
        (common, rate[:-1] * PERIOD),
        (common, rate[:-1] * dt[0]),
    ]
    for name, increments in others:
        alt = theta0 + np.concatenate([[0.0], np.cumsum(increments)])
        if _headings_match(alt, want):
            continue  # this case cannot tell the two apart
        expect(not _headings_match(got, alt),
               f"{what}: you used {name}; each sample g[k] is the rate over the period "
               "from t[k] to t[k + 1], so theta[k + 1] = theta[k] + (g[k] - bias) "
               "(t[k + 1] - t[k])")


# --- exercise 3: one fused step -------------------------------------------------------------


def _as_pose(got: object, what: str) -> Pose2D:
    if isinstance(got, Pose2D):
        return got
    try:
        arr = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        arr = np.zeros(0)
    expect(arr.shape == (3,), f"{what} gave {format_value(got)}, expected a Pose2D "
           "(or x, y, theta)")
    expect(bool(np.isfinite(arr).all()), f"{what} gave ({arr[0]:g}, {arr[1]:g}, {arr[2]:g}); "
           "a pose is three finite numbers")
    return Pose2D(*map(float, arr))


def _pose_close(got: Pose2D, want: Pose2D, what: str, atol: float, ref: str) -> None:
    expect_close(got.x, want.x, what=f"{what}: x", rtol=0.0, atol=atol, unit="m", ref=ref)
    expect_close(got.y, want.y, what=f"{what}: y", rtol=0.0, atol=atol, unit="m", ref=ref)
    dtheta = wrap_angle(got.theta - want.theta)
    expect(abs(dtheta) <= atol,
           f"{what}: theta gave {got.theta:.6g} rad, expected {want.theta:.6g} rad "
           "(modulo 2 pi; theta + (gyro_z - bias) dt)")


def _same(a: Pose2D, b: Pose2D) -> bool:
    return (abs(a.x - b.x) < 1e-12 and abs(a.y - b.y) < 1e-12
            and abs(wrap_angle(a.theta - b.theta)) < 1e-12)


def _hint_step(got: Pose2D, want: Pose2D, pose: Pose2D, d_left: float, d_right: float,
               gyro_z: float, dt: float, bias: float, what: str) -> None:
    """Name the likely slip when the answer equals a known wrong variant."""
    d_c = (d_left + d_right) / 2
    phi = (gyro_z - bias) * dt

    def moved(heading: float, turn: float) -> Pose2D:
        return Pose2D(pose.x + d_c * math.cos(heading), pose.y + d_c * math.sin(heading),
                      wrap_angle(pose.theta + turn))

    wheel_phi = (d_right - d_left) / default_params().wheel_base
    raw_phi = gyro_z * dt
    slips = {
        "you turned by the wheels, (d_r - d_l) / b (eqn 7); eqn 16 takes the heading "
        "from the gyro instead": moved(pose.theta + wheel_phi / 2, wheel_phi),
        "the bias was not subtracted: turn by (gyro_z - bias) dt":
            moved(pose.theta + raw_phi / 2, raw_phi),
        "you moved along the heading at the start of the step; use the step's mean "
        "heading theta + phi / 2 (the chord of the arc points that way)":
            moved(pose.theta, phi),
        "you moved along the heading at the end of the step (as A.11 does); use the "
        "step's mean heading theta + phi / 2": moved(pose.theta + phi, phi),
        "the heading changed by a thousand times too much: dt is in seconds":
            moved(pose.theta + phi / 2, phi * 1000.0),
    }
    # a variant that happens to equal the right answer here names no slip
    expect_no_slip(got, slips, lambda got, wrong: _same(got, wrong) and not _same(wrong, want),
                   prefix=f"{what}: ")


@checker("one fused odometry step")
def fused_step_check(fn: Callable[..., Pose2D]) -> str:
    """``fn(pose, d_left, d_right, gyro_z, dt, bias) -> Pose2D``: eqns 14 and 16."""
    expect_own(fn, reference_fused_step)
    cases = [  # what, pose, d_left, d_right, gyro_z, dt, bias
        ("straight ahead", Pose2D(1.0, 2.0, 0.3), 0.02, 0.02, 0.0, 0.02, 0.0),
        ("a spin on the spot", Pose2D(1.0, 2.0, 0.3), -0.005, 0.005, 0.5, 0.02, 0.0),
        ("wheels and gyro disagree", Pose2D(0.0, 0.0, 1.0), 0.018, 0.022, 0.2, 0.02, 0.0),
        ("standing on a biased gyro", Pose2D(-1.0, 0.5, -2.0), 0.0, 0.0, 0.0052, 0.02,
         0.0052),
        ("a curve across +-pi", Pose2D(0.0, 0.0, 3.14), 0.01, 0.012, 0.4, 0.02, 0.001),
        ("a long 0.2 s step", Pose2D(2.0, 3.0, 0.0), 0.10, 0.14, 0.8, 0.2, 0.01),
    ]
    for what, pose, d_left, d_right, gyro_z, dt, bias in cases:
        want = reference_fused_step(pose, d_left, d_right, gyro_z, dt, bias)
        got = _as_pose(fn(pose, d_left, d_right, gyro_z, dt, bias), what)
        _hint_step(got, want, pose, d_left, d_right, gyro_z, dt, bias, what)
        _pose_close(got, want, what, 1e-9, "eqn 16 with theta + phi / 2")
    log, bias = turning_log()
    travel = log_wheel_travel(log)
    pose = Pose2D(*map(float, log.pose[0]))
    for k in range(1, len(log)):
        pose = _as_pose(fn(pose, float(travel[k - 1, 0]), float(travel[k - 1, 1]),
                           float(log.gyro_z[k - 1]), float(log.t[k] - log.t[k - 1]), bias),
                        f"step {k} of the simulated drive")
    want_end = Pose2D(*map(float, gyro_odometry_from_log(log, bias, method="midpoint")[-1]))
    _pose_close(pose, want_end, f"after {len(log) - 1} steps of the simulated drive", 1e-6,
                "step by step = gyro_odometry_from_log")
    error = math.hypot(pose.x - log.pose[-1, 0], pose.y - log.pose[-1, 1])
    return (f"{len(cases)} steps and a {log.t[-1]:.0f} s drive match (it ends "
            f"{error * 100:.1f} cm from the true position)")


def _number(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, bool)


# --- exercise 4: measure the pessimistic part's best standing time ----------------------------


def best_standing_time(gyro: str = "pessimistic") -> float:
    """Section 2's ``T* = sqrt(3) sigma_w sqrt(dt) / K`` (s) for a gyro of
    ``load_params(gyro=...)``: the window whose bias estimate errs least."""
    from abcwc.params import load_params

    p = load_params(gyro=gyro)
    return math.sqrt(3) * p.gyro.noise_std * math.sqrt(p.control_period) / p.gyro.bias_walk_std


@checker("measurement")
def best_window_check(measured: Callable[[], float]) -> str:
    """The measured best window (s) against the formula: within a factor of two (the bowl
    is shallow near its bottom, and 400 power-ups measure it only so finely)."""
    value = measured()
    expect(isinstance(value, (int, float, np.floating)) and math.isfinite(float(value))
           and value > 0, f"measured_best_window() gave {format_value(value)}; return one "
           "window length in seconds")
    value = float(value)
    best, datasheet = best_standing_time("pessimistic"), best_standing_time("datasheet")
    if best / 2 <= value <= 2 * best:
        return (f"you measured {value:g} s; the formula gives T* = {best:.1f} s for the "
                f"pessimistic part (the datasheet part's is {datasheet:.0f} s)")
    if datasheet / 2 <= value <= 2 * datasheet:
        raise NotYet(f"{value:g} s is the datasheet part's T* ({datasheet:.0f} s): measure the "
                     "pessimistic part, load_params(gyro=\"pessimistic\").gyro, as gyro_model's "
                     "model")
    if value > 2 * best:
        raise NotYet(f"you measured {value:g} s, the formula gives {best:.1f} s: the error kept "
                     "falling with longer windows. Compare each estimate with the bias at the "
                     "window's end (when the chair drives off), not with the turn-on bias, and "
                     "try windows from half a second up")
    raise NotYet(f"you measured {value:g} s, the formula gives {best:.1f} s: a shorter window "
                 "than T* averages too few samples; is the error an RMS over all power-ups, "
                 "and the window the last T seconds?")


# --- exercise 4: predict the five laps' heading errors ---------------------------------------

END_TURN = 10 * math.pi
"""rad: five anticlockwise laps of the lab."""


@checker("prediction")
def end_heading_prediction_check(predicted: Callable[[], tuple[float, float]],
                                 wheels: float, raw_gyro: float, bias: float,
                                 driving: float) -> str:
    """(wheels, raw gyro) degrees written before the plots, against the measured end
    errors (``wheels``, ``raw_gyro``, degrees); ``bias`` (rad/s) and ``driving`` (s, the
    time after the still start) are what the notebook printed, for naming the slips."""
    value = predicted()
    guess_wheels, guess_raw = numbers(value, 2, "predicted_end_heading_errors()",
                                      "return two angles in degrees: (wheels, raw gyro)")
    expect(math.isfinite(guess_wheels) and math.isfinite(guess_raw),
           f"predicted ({guess_wheels}, {guess_raw}); both must be finite degrees")
    from abcwc.sim import ChairErrors

    worn = ChairErrors.worn()
    encoder = (worn.encoder_wheel_left + worn.encoder_wheel_right) / 2
    too_large = worn.wheel_base / encoder - 1  # every turn counted this much too large
    raw_expected = math.degrees(bias * driving)
    notes = []
    if abs(guess_raw - raw_gyro) > 4.0:
        if abs(guess_raw - math.radians(raw_gyro)) < 0.1:
            notes.append("the raw gyro's error is in radians; the check wants degrees")
        elif abs(guess_raw + raw_gyro) < 4.0:
            notes.append("the raw gyro's sign: a positive bias adds to every reading, so "
                         "its heading runs ahead, to the left")
        else:
            notes.append(f"the raw gyro: it adds its bias, {bias:.5f} rad/s, in every second "
                         f"of the {driving:.0f} s of driving: {raw_expected:.1f} deg")
    if abs(guess_wheels - wheels) > 5.0:
        if abs(guess_wheels - math.radians(wheels)) < 0.1:
            notes.append("the wheels' error is in radians; the check wants degrees")
        elif abs(guess_wheels - math.degrees((worn.wheel_base - 1) * END_TURN)) < 5.0:
            notes.append("the wheels: the 3 % wider wheel base makes the odometry see each "
                         "turn 3 % too large, but the encoder wheels count 1.2 % short, which "
                         f"shrinks what they see: {100 * too_large:.1f} % in all")
        elif abs(guess_wheels + wheels) < 5.0:
            notes.append("the wheels' sign: the odometry sees every turn too *large*, and "
                         "all the turns are to the left")
        else:
            notes.append(f"the wheels: five laps turn {END_TURN:.1f} rad, and the worn "
                         f"odometry counts every turn about {100 * too_large:.1f} % too large")
    if notes:
        raise NotYet(f"you predicted {guess_wheels:.1f} and {guess_raw:.1f} deg, the drive "
                     f"ended {wheels:.1f} and {raw_gyro:.1f} deg off: " + "; ".join(notes))
    return (f"you predicted {guess_wheels:.1f} deg for the wheels and {guess_raw:.1f} deg "
            f"for the raw gyro; the drive ended {wheels:.1f} and {raw_gyro:.1f} deg off")
