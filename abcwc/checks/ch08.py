"""Checks for chapter 08, UMBmark calibration (thesis 4.2.3, 4.3.6, A.16).

Borenstein and Feng (1996), "Measurement and correction of systematic odometry errors
in mobile robots"; equation numbers are those of the same derivation in chapter 5 of
Borenstein, Everett and Feng's report *Where am I?* (1996). Exercises:

* ``centres_of_gravity_and_emax(cw_errors, ccw_errors)``: the centre of gravity
  ``(x, y)`` of each direction's return errors (eqn 5.4) and
  ``E_max,syst = max(|cg_cw|, |cg_ccw|)`` (eqns 5.5, 5.6);
* ``alpha_beta_radius(cg_cw, cg_ccw, side)``: the type A and type B angles from the
  x coordinates, in radians (eqns 5.9, 5.10 without the ``180/pi``), and the radius
  of the curved legs ``R = (L/2) / sin(beta/2)`` (eqn 5.11);
* ``correction_factors(alpha, radius, wheel_base)``: ``E_b = (pi/2) / (pi/2 - alpha)``
  (eqn 5.15), ``b_actual = E_b b`` (eqn 5.14), ``E_d = (R + b_actual/2) /
  (R - b_actual/2)`` (eqn 5.12) and the wheels' factors ``c_L = 2 / (E_d + 1)``,
  ``c_R = 2 / (1/E_d + 1)``;
* ``diagnosis()``: a second chair, back from the workshop, whose return errors
  (:func:`second_chair_return_errors`) the student reads: which of its encoder wheels is
  the larger (or neither) and whether its effective wheel base is wider or narrower than
  the nominal 440 mm (or neither), judged against the faults the simulator was given.

Each ``reference_*`` function is the answer the notebook falls back on; it calls the
library (:mod:`abcwc.estimation.umbmark`).
* ``trials_covariance(ends)``: the covariance (3 x 3) of the thesis's ten end positions,
  measured from figure 51's data and compared with the matrix the thesis printed.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from abcwc.checks.report import NotYet, checker, expect, expect_close, expect_own, format_value
from abcwc.estimation import umbmark
from abcwc.params import default_params

__all__ = [
    "WHEEL_ANSWERS",
    "covariance_check",
    "WHEEL_BASE_ANSWERS",
    "alpha_beta_radius_check",
    "diagnosis_check",
    "centres_check",
    "correction_factors_check",
    "reference_alpha_beta_radius",
    "reference_centres_of_gravity_and_emax",
    "reference_correction_factors",
    "second_chair_return_errors",
    "worked_example",
]

WHEEL_BASE = default_params().wheel_base  # m, the chair's nominal b (A.18: 440 mm)


# --- reference answers ----------------------------------------------------------------


def reference_centres_of_gravity_and_emax(cw_errors, ccw_errors
                                          ) -> tuple[np.ndarray, np.ndarray, float]:
    """``(cg_cw, cg_ccw, E_max,syst)``: two ``(x, y)`` arrays (m) and a distance (m).

    ``*_errors`` are ``(n, 2)`` or ``(n, 3)`` return errors; a theta column is ignored.
    """
    cg_cw, cg_ccw = umbmark.centres_of_gravity(cw_errors, ccw_errors)
    return cg_cw, cg_ccw, umbmark.e_max_syst(cw_errors, ccw_errors)


def reference_alpha_beta_radius(cg_cw, cg_ccw, side: float) -> tuple[float, float, float]:
    """``(alpha, beta, R)`` (rad, rad, m) from the x coordinates of the two centres."""
    alpha, beta = umbmark.alpha_beta(cg_cw, cg_ccw, side, use="x")
    return alpha, beta, umbmark.curve_radius(beta, side)


def reference_correction_factors(alpha: float, radius: float, wheel_base: float
                                 ) -> tuple[float, float, float, float, float]:
    """``(E_b, b_actual, E_d, c_left, c_right)`` for a nominal wheel base (m)."""
    e_b = umbmark.wheel_base_ratio(alpha)
    b_actual = e_b * wheel_base
    e_d = umbmark.wheel_diameter_ratio(radius, b_actual)
    c_left, c_right = umbmark.wheel_correction_factors(e_d)
    return e_b, b_actual, e_d, c_left, c_right


def worked_example(e_d: float = 1.01, e_b: float = 1.03, side: float = umbmark.THESIS_SIDE,
                   wheel_base: float = WHEEL_BASE) -> dict[str, np.ndarray]:
    """Return errors ``{"cw": (1, 2), "ccw": (1, 2)}`` of the small-angle model (m)."""
    return {d: np.array([umbmark.model_return_error(side, wheel_base, e_d, e_b, d)])
            for d in ("cw", "ccw")}


# --- helpers --------------------------------------------------------------------------


def _parts(got: object, count: int, names: str) -> Sequence:
    """``got`` as a sequence of ``count`` parts, or NotYet saying what to return."""
    expect(isinstance(got, (tuple, list)) and len(got) == count,
           f"expected {count} values ({names}), got {format_value(got)}")
    return got


def _scatter(rng: np.random.Generator, centre, n: int, spread: float) -> np.ndarray:
    """``n`` return errors ``(x, y, theta)`` around ``centre`` (x, y)."""
    xy = np.asarray(centre, dtype=float) + rng.normal(0.0, spread, (n, 2))
    return np.column_stack([xy, rng.normal(0.0, 0.02, n)])


def _cases() -> list[tuple[str, np.ndarray, np.ndarray]]:
    trials = umbmark.load_thesis_trials()
    model = worked_example()
    rng = np.random.default_rng(8)
    return [
        ("the thesis's ten trials (figure 51)", trials["cw"], trials["ccw"]),
        ("the worked example (E_d 1.01, E_b 1.03)", model["cw"], model["ccw"]),
        ("5 + 5 scattered runs", _scatter(rng, model["cw"][0], 5, 0.05),
         _scatter(rng, model["ccw"][0], 5, 0.05)),
        ("3 CW and 6 CCW runs", _scatter(rng, (-0.3, -0.2), 3, 0.1),
         _scatter(rng, (0.9, -0.6), 6, 0.1)),
    ]


# --- checks ---------------------------------------------------------------------------


@checker("centres of gravity and E_max,syst")
def centres_check(fn: Callable[[np.ndarray, np.ndarray], tuple]) -> str:
    """``fn(cw_errors, ccw_errors) -> (cg_cw, cg_ccw, e_max)`` against eqns 5.4-5.6."""
    expect_own(fn, reference_centres_of_gravity_and_emax)
    cases = _cases()
    for label, cw, ccw in cases:
        got = _parts(fn(cw.copy(), ccw.copy()), 3, "cg_cw, cg_ccw, e_max")
        cg_cw, cg_ccw, e_max = reference_centres_of_gravity_and_emax(cw, ccw)
        expect_close(got[0], cg_cw, what=f"{label}: cg_cw", atol=1e-9, unit="m",
                     ref="eqn 5.4: the mean x and mean y of the CW errors")
        expect_close(got[1], cg_ccw, what=f"{label}: cg_ccw", atol=1e-9, unit="m",
                     ref="eqn 5.4")
        mean_distance = max(np.hypot(cw[:, 0], cw[:, 1]).mean(),
                            np.hypot(ccw[:, 0], ccw[:, 1]).mean())
        expect(not (np.isscalar(got[2]) and len(cw) > 1
                    and math.isclose(float(got[2]), mean_distance, rel_tol=1e-9)),
               f"{label}: e_max gave {format_value(got[2])} m, the mean distance of the "
               "errors; E_max,syst is the distance of each centre of gravity from the "
               "origin (eqn 5.5), the larger of the two (eqn 5.6)")
        expect_close(got[2], e_max, what=f"{label}: e_max", atol=1e-9, unit="m",
                     ref="eqns 5.5, 5.6: max(|cg_cw|, |cg_ccw|)")
    return f"{len(cases)} cases; figure 51's numbers give E_max,syst {e_max_of_thesis():.4f} m"


def e_max_of_thesis() -> float:
    """E_max,syst of figure 51's numbers as printed (m): A.16's ``emax``."""
    return umbmark.e_max_syst(*_thesis_pair())


@checker("alpha, beta and R")
def alpha_beta_radius_check(fn: Callable[[np.ndarray, np.ndarray, float], tuple]) -> str:
    """``fn(cg_cw, cg_ccw, side) -> (alpha, beta, R)`` against eqns 5.9-5.11 (radians)."""
    expect_own(fn, reference_alpha_beta_radius, umbmark.alpha_beta)
    model = worked_example()
    side = umbmark.THESIS_SIDE
    cases = [("the worked example", model["cw"][0], model["ccw"][0], side),
             ("the thesis's centres", *umbmark.centres_of_gravity(*_thesis_pair()), side),
             ("a chair curving right, 4 m square", np.array([0.35, -0.42]),
              np.array([-0.55, -0.48]), 4.0)]
    for label, cg_cw, cg_ccw, side in cases:
        got = _parts(fn(np.array(cg_cw), np.array(cg_ccw), side), 3, "alpha, beta, R")
        alpha, beta, radius = reference_alpha_beta_radius(cg_cw, cg_ccw, side)
        for name, value, expected, ref in (("alpha", got[0], alpha, "eqn 5.9"),
                                           ("beta", got[1], beta, "eqn 5.10")):
            expect(not (_number(value) and abs(expected) > 1e-6 and math.isclose(
                float(value), math.degrees(expected), rel_tol=1e-6)),
                f"{label}: {name} gave {format_value(value)}, which is degrees; keep it in "
                f"radians ({format_value(expected)}): leave out the paper's 180/pi")
            expect(not (_number(value) and abs(expected) > 1e-6 and math.isclose(
                float(value), -expected, rel_tol=1e-6)),
                f"{label}: {name} gave {format_value(value)}, the right size with the wrong "
                f"sign ({ref}: divide by -4L)")
            expect_close(value, expected, what=f"{label}: {name}", atol=1e-12, rtol=1e-9,
                         unit="rad", ref=ref)
        expect_close(got[2], radius, what=f"{label}: R", rtol=1e-9, unit="m",
                     ref="eqn 5.11: R = (L/2) / sin(beta/2)")
    alpha, beta, radius = reference_alpha_beta_radius(model["cw"][0], model["ccw"][0],
                                                      umbmark.THESIS_SIDE)
    return (f"{len(cases)} cases; worked example alpha {alpha:.5f} rad, beta {beta:.5f} rad, "
            f"R {radius:.2f} m")


def _thesis_pair() -> tuple[np.ndarray, np.ndarray]:
    trials = umbmark.load_thesis_trials()
    return trials["cw"], trials["ccw"]


def _number(value: object) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, bool)


@checker("E_b, E_d and the correction factors")
def correction_factors_check(fn: Callable[[float, float, float], tuple]) -> str:
    """``fn(alpha, R, b) -> (E_b, b_actual, E_d, c_left, c_right)``, eqns 5.12-5.15."""
    expect_own(fn, reference_correction_factors)
    worked_alpha = math.pi / 2 * (1 - 1 / 1.03)
    worked_radius = 1.03 * WHEEL_BASE / 2 * 2.01 / 0.01
    cases = [("the worked example", worked_alpha, worked_radius, WHEEL_BASE),
             ("a narrow chair curving right", -0.012, -60.0, 0.35),
             ("the thesis's numbers", -0.024142857, -700.0, WHEEL_BASE)]
    names = ("E_b", "b_actual", "E_d", "c_left", "c_right")
    refs = ("eqn 5.15: (pi/2) / (pi/2 - alpha), alpha in rad", "eqn 5.14: E_b b",
            "eqn 5.12 with b_actual", "2 / (E_d + 1)", "2 / (1/E_d + 1)")
    for label, alpha, radius, base in cases:
        got = _parts(fn(alpha, radius, base), 5, ", ".join(names))
        expected = reference_correction_factors(alpha, radius, base)
        with_nominal_b = umbmark.wheel_diameter_ratio(radius, base)
        expect(not (_number(got[2]) and math.isclose(float(got[2]), with_nominal_b,
                                                     rel_tol=1e-12)),
               f"{label}: E_d gave {format_value(got[2])}, from the nominal wheel base; the "
               f"wheels really roll b_actual = E_b b apart, which gives "
               f"{format_value(expected[2])}")
        expect(not (_number(got[3]) and math.isclose(float(got[3]), expected[4],
                                                     rel_tol=1e-12)),
               f"{label}: c_left gave {format_value(got[3])}, which is c_right: the left "
               "factor is 2 / (E_d + 1)")
        for name, value, want, ref in zip(names, got, expected, refs):
            expect_close(value, want, what=f"{label}: {name}", rtol=1e-9, ref=ref)
    e_b, b_actual, e_d, c_left, c_right = reference_correction_factors(
        worked_alpha, worked_radius, WHEEL_BASE)
    return (f"{len(cases)} cases; worked example E_b {e_b:.4f}, E_d {e_d:.4f}, "
            f"c = ({c_left:.5f}, {c_right:.5f})")


# --- exercise 4: diagnose a second chair -----------------------------------------------------

WHEEL_ANSWERS = ("left larger", "right larger", "equal")
WHEEL_BASE_ANSWERS = ("wider", "narrower", "nominal")
# The second chair's faults, which the notebook does not print: a new right encoder wheel
# 0.8 % smaller than the left, and tyres that wore to a 2 % narrower effective wheel base.
_SECOND_CHAIR = {"encoder_wheel_left": 1.0, "encoder_wheel_right": 0.992, "wheel_base": 0.98,
                 "slip_std": 0.003}
_SECOND_TRUTH = {"wheels": "left larger", "wheel base": "narrower"}


def second_chair_return_errors(runs: int = 3, side: float = umbmark.THESIS_SIDE
                               ) -> tuple[np.ndarray, np.ndarray]:
    """The second chair's UMBmark return errors, ``runs`` squares of ``side`` m each way
    round in an empty hall ((runs, 3) CW and CCW, as ``run_umbmark`` gives them)."""
    import abcwc
    from abcwc.experiments.umbmark_trials import run_umbmark
    from abcwc.sim import ChairErrors
    from abcwc.sim.world import box_world

    hall = box_world(20, 20, centred=True, name="hall")
    errors = ChairErrors(**_SECOND_CHAIR)
    return run_umbmark(lambda seed: abcwc.connect(world=hall, seed=100 + seed, errors=errors,
                                                  people=False), runs=runs, side=side)


@checker("diagnosis")
def diagnosis_check(diagnosis: Callable[[], dict]) -> str:
    """``diagnosis()``: ``{"wheels": one of WHEEL_ANSWERS, "wheel base": one of
    WHEEL_BASE_ANSWERS}`` against the faults the second chair was given."""
    said = diagnosis()
    expect(isinstance(said, dict) and set(said) == {"wheels", "wheel base"},
           f'diagnosis() gave {format_value(said)}; return {{"wheels": ..., "wheel base": '
           '...}}')
    wheels, base = said["wheels"], said["wheel base"]
    expect(wheels in WHEEL_ANSWERS, f'"wheels" is {wheels!r}; say one of {WHEEL_ANSWERS}')
    expect(base in WHEEL_BASE_ANSWERS,
           f'"wheel base" is {base!r}; say one of {WHEEL_BASE_ANSWERS}')
    truth = _SECOND_TRUTH
    wrong = []
    if base != truth["wheel base"]:
        if base == "wider":
            wrong.append("the wheel base: a wider one makes every odometric turn come out "
                         "short; this chair's turns came out long (alpha has the other "
                         "sign), so its wheels are closer together than the software thinks")
        else:
            wrong.append("the wheel base: alpha is not zero, every corner comes out too long "
                         "whichever way round (a type A error): the wheels are closer "
                         "together than the software thinks")
    if wheels != truth["wheels"]:
        if wheels == "right larger":
            wrong.append("the wheels: E_d = D_R / D_L comes out below 1, so the right encoder "
                         "wheel is the smaller (a smaller encoder wheel counts more per "
                         "metre, and the chair, driving what its odometry calls straight, "
                         "curves towards that side)")
        else:
            wrong.append("the wheels: beta is not zero, every leg curves to the same side "
                         "whichever way round (a type B error)")
    if wrong:
        raise NotYet("not yet on " + "; and ".join(wrong))
    return ("right: the second chair's right encoder wheel is 0.8 % smaller than its left, "
            "and its effective wheel base 2 % narrower than the nominal 440 mm")


# --- measure: figure 51's covariance from its own trials ---------------------------------------

PRINTED_FIGURE_51 = np.diag([0.0212, 0.0041, 0.0042])


@checker("measurement")
def covariance_check(fn: Callable[[np.ndarray], np.ndarray]) -> str:
    """``fn(ends)``: the (3, 3) covariance of the ten trials' (x, y, theta), as figure 51
    computed it (MATLAB's ``cov``: divided by n - 1), against the printed matrix."""
    ends = np.vstack([(t := umbmark.load_thesis_trials())["cw"], t["ccw"]])
    got = fn(ends.copy())
    try:
        got = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise NotYet(f"trials_covariance gave {format_value(got)}; return a 3 x 3 array") from None
    expect(got.shape == (3, 3), f"trials_covariance gave shape {got.shape}; the covariance of "
           "(x, y, theta) is 3 x 3 (np.cov wants the variables as rows: ends.T)")
    expected = np.cov(ends.T, ddof=1)
    if np.allclose(got, expected, atol=1e-9):
        return (f"var x {got[0, 0]:.4f} and var y {got[1, 1]:.4f} as printed; var theta "
                f"{got[2, 2]:.4f}, not the printed {PRINTED_FIGURE_51[2, 2]}, and x and y "
                f"covary ({got[0, 1]:.4f}), which the printed matrix leaves out")
    if np.allclose(got, np.cov(ends.T, ddof=0), atol=1e-9):
        raise NotYet("that divides by n = 10; figure 51's 0.0212 and 0.0041 come from n - 1 "
                     "(MATLAB's cov, the unbiased estimate)")
    if np.allclose(got, np.diag(np.diag(expected)), atol=1e-9):
        raise NotYet("only the variances: the trials' x and y errors vary together, and the "
                     "covariance keeps that off the diagonal")
    if np.allclose(got, np.cov(ends, ddof=1)[:3, :3], atol=1e-9):
        raise NotYet("np.cov takes each row as a variable: pass ends.T")
    raise NotYet(f"var x came out {got[0, 0]:.4f}, expected {expected[0, 0]:.4f}; the "
                 "covariance of the ten (x, y, theta) rows, divided by n - 1")
