"""UMBmark: measure and correct systematic odometry errors (thesis 4.2.3, 4.3.6, A.16).

The maths only: the square is driven by :class:`abcwc.behaviours.SquareDriver`, and the
trials on a chair are run by :mod:`abcwc.experiments.umbmark_trials`.

Borenstein and Feng, "Measurement and correction of systematic odometry errors in
mobile robots", IEEE Trans. Robotics and Automation 12(6), 1996. The chair drives an
``L x L`` square clockwise and counter-clockwise by its own odometry, several times
each way; each run's *return error* is where it really ends minus where its odometry
says it ends. Two systematic errors dominate:

* type A, a wrong wheel base ``E_b = b_actual / b_nominal``: every 90 degree turn
  comes out as ``90 deg - alpha`` (too short if ``E_b > 1``), in both directions;
* type B, unequal wheels ``E_d = D_R / D_L``: every "straight" leg is really an arc
  that turns the chair by ``beta`` (to the left if ``E_d > 1``), in both directions.

Small-angle model of the return errors (derived in our REP 103 frame: start at the
origin facing +x, y to the left; see :func:`model_return_error`)::

    x_cw  = -2L (alpha + beta)      y_cw  = -2L (alpha + beta)
    x_ccw = -2L (alpha - beta)      y_ccw = +2L (alpha - beta)

so from the centres of gravity of each direction's errors (all angles in radians)::

    alpha = (x_cw + x_ccw) / (-4 L)            beta = (x_cw - x_ccw) / (-4 L)
    R = (L / 2) / sin(beta / 2)                (radius of the "straight" legs)
    E_d = (R + b / 2) / (R - b / 2)
    E_b = (pi/2) / (pi/2 - alpha),   b_actual = E_b b_nominal
    c_l = 2 / (E_d + 1),             c_r = 2 / (1 / E_d + 1)

and ``E_max,syst = max(|cg_cw|, |cg_ccw|)``. Equation numbers (5.x) in this module are
those of the same derivation in chapter 5 of Borenstein, Everett and Feng's report
*Where am I? Sensors and methods for mobile robot positioning* (1996). ``c_l`` and
``c_r`` multiply each wheel's distance per count: they fix the ratio of the two wheels
and keep their mean. The paper's x formulas come out with the same signs in our frame;
its y formulas are the sign pattern above (``alpha = (y_cw - y_ccw)/(-4L)``,
``beta = (y_cw + y_ccw)/(-4L)``).

Where the thesis's A.16 script goes wrong (:func:`thesis_a16_outputs` runs it as printed):

1. it turns alpha and beta into degrees (``* 180/pi``) and then takes ``sin(beta/2)``
   with MATLAB's radian ``sin``, and multiplies R by ``180/3.14`` afterwards: for beta
   of a few tenths of a degree the two slips nearly cancel (the thesis's own data: R
   -702.8 for -700.0 m), for a few degrees they do not (R twice too long at 4 deg);
2. ``E_d = (R + beta/2) / (R - beta/2)`` puts the angle ``beta`` where the wheel base
   ``b`` belongs, so E_d is not a wheel-diameter ratio at all;
3. ``E_b = 90 / (90 - alpha)`` is right (alpha in degrees there);
4. its offsets are all positive: they look like unsigned distances, but the method
   needs signed errors in one frame (the sign tells type A from type B), so the
   centres of gravity it takes are not the paper's;
5. ``x = [x_CW x_CCW]`` names variables that do not exist (MATLAB is case-sensitive),
   and ``theta`` has nine values where the table (figure 51) has ten, with the third
   and fourth swapped; the printed 0.0042 comes from those nine values.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from abcwc.paths import data_dir

THESIS_SIDE = 3.5  # m, the thesis's square (A.16: L = 3.5)


@dataclass(frozen=True)
class UmbmarkResult:
    """What UMBmark measures and the corrections it gives (m, rad, ratios)."""

    side: float
    cg_cw: tuple[float, float]  # centre of gravity of the CW return errors (m)
    cg_ccw: tuple[float, float]
    e_max_syst: float  # m
    alpha: float  # rad, type A turn error per 90 degree turn
    beta: float  # rad, type B heading change per straight leg
    radius: float  # m, radius of the curved "straight" legs (inf when beta = 0)
    e_d: float  # D_R / D_L
    e_b: float  # b_actual / b_nominal
    wheel_base: float  # m, b_actual
    c_left: float
    c_right: float

    @property
    def correction(self) -> tuple[float, float]:
        """``(c_left, c_right)`` for :class:`abcwc.estimation.Odometry`."""
        return (self.c_left, self.c_right)


def e_max_syst(cw_errors: np.ndarray, ccw_errors: np.ndarray) -> float:
    """``max(|cg_cw|, |cg_ccw|)`` (m): the larger distance of the two centres of gravity."""
    cw = _errors(cw_errors, "cw_errors")[:, :2].mean(axis=0)
    ccw = _errors(ccw_errors, "ccw_errors")[:, :2].mean(axis=0)
    return float(max(np.hypot(*cw), np.hypot(*ccw)))


def _errors(errors: np.ndarray, name: str) -> np.ndarray:
    arr = np.atleast_2d(np.asarray(errors, dtype=float))
    if arr.ndim != 2 or arr.shape[1] not in (2, 3) or len(arr) == 0:
        raise ValueError(f"{name} must be (n, 2) or (n, 3) return errors (x, y[, theta]), "
                         f"got shape {np.shape(errors)}")
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} has non-finite values")
    return arr


def centres_of_gravity(cw_errors: np.ndarray, ccw_errors: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` centres of gravity (m) of the CW and of the CCW return errors.

    Borenstein and Feng's ``x_c.g. = (1/n) sum eps_x``, ``y_c.g. = (1/n) sum eps_y`` for
    each direction (eqn 5.4 in Borenstein, Everett and Feng's report). ``*_errors``
    are ``(n, 2)`` or ``(n, 3)`` arrays; a theta column is ignored.
    """
    cw = _errors(cw_errors, "cw_errors")[:, :2].mean(axis=0)
    ccw = _errors(ccw_errors, "ccw_errors")[:, :2].mean(axis=0)
    return cw, ccw


def alpha_beta(cg_cw: np.ndarray, cg_ccw: np.ndarray, side: float,
               use: str = "xy") -> tuple[float, float]:
    """Type A and type B angles ``(alpha, beta)`` (rad) from the two centres of gravity.

    ``use="x"``: the paper's ``alpha = (x_cw + x_ccw) / (-4L)``, ``beta = (x_cw - x_ccw)
    / (-4L)`` (its eqns 5.9, 5.10 without the ``180/pi``); ``"y"``: the same from the y
    errors, ``alpha = (y_cw - y_ccw) / (-4L)``, ``beta = (y_cw + y_ccw) / (-4L)``;
    ``"xy"``: their mean (see :func:`umbmark_corrections`).
    """
    if not side > 0:
        raise ValueError(f"side must be > 0 m, got {side!r}")
    (x_cw, y_cw), (x_ccw, y_ccw) = _centre(cg_cw, "cg_cw"), _centre(cg_ccw, "cg_ccw")
    alpha_x, beta_x = (x_cw + x_ccw) / (-4.0 * side), (x_cw - x_ccw) / (-4.0 * side)
    alpha_y, beta_y = (y_cw - y_ccw) / (-4.0 * side), (y_cw + y_ccw) / (-4.0 * side)
    if use == "x":
        return float(alpha_x), float(beta_x)
    if use == "y":
        return float(alpha_y), float(beta_y)
    if use == "xy":
        return float(alpha_x + alpha_y) / 2, float(beta_x + beta_y) / 2
    raise ValueError(f"use must be 'x', 'y' or 'xy', got {use!r}")


def _centre(cg: np.ndarray, name: str) -> np.ndarray:
    """A centre of gravity ``(x, y)`` (m) from ``(x, y)`` or ``(x, y, theta)``; ValueError
    unless finite."""
    arr = np.asarray(cg, dtype=float)
    if arr.shape not in ((2,), (3,)) or not np.isfinite(arr[:2]).all():
        raise ValueError(f"{name} must be a finite (x, y) in metres, got {cg!r}")
    return arr[:2]


def curve_radius(beta: float, side: float) -> float:
    """Radius (m) of the "straight" legs: ``R = (L/2) / sin(beta/2)`` (eqn 5.11).

    A leg of length L that turns the chair by ``beta`` (rad) is an arc of that radius;
    positive R curves left. ``inf`` when ``beta`` is 0.
    """
    if not side > 0:
        raise ValueError(f"side must be > 0 m, got {side!r}")
    if not math.isfinite(beta):
        raise ValueError(f"beta must be a finite angle (rad), got {beta!r}")
    return math.inf if beta == 0.0 else (side / 2) / math.sin(beta / 2)


def wheel_diameter_ratio(radius: float, wheel_base: float) -> float:
    """``E_d = D_R / D_L = (R + b/2) / (R - b/2)`` (eqn 5.12); 1 for a straight leg.

    ``b`` (m) is the wheel base the wheels really have: the two wheels roll on arcs
    ``b`` apart. The paper writes the nominal b here; :func:`umbmark_corrections`
    passes the corrected one, ``E_b b_nominal`` (3 % of a 1 % effect).
    """
    if not wheel_base > 0:
        raise ValueError(f"wheel_base must be > 0 m, got {wheel_base!r}")
    if math.isinf(radius):
        return 1.0
    if abs(radius) <= wheel_base / 2:
        raise ValueError(f"radius {radius:.3g} m is inside the wheel base: beta is too large "
                         "for the small-error model")
    return (radius + wheel_base / 2) / (radius - wheel_base / 2)


def wheel_base_ratio(alpha: float) -> float:
    """``E_b = b_actual / b_nominal = 90 deg / (90 deg - alpha)`` (eqn 5.15), alpha in rad."""
    if not abs(alpha) < math.pi / 2:
        raise ValueError(f"alpha {alpha!r} rad is not a small turn error (|alpha| < pi/2)")
    return (math.pi / 2) / (math.pi / 2 - alpha)


def wheel_correction_factors(e_d: float) -> tuple[float, float]:
    """``(c_left, c_right) = (2 / (E_d + 1), 2 / (1/E_d + 1))``.

    They multiply each wheel's distance per count: their ratio is ``E_d`` and their
    mean stays 1 (to first order), so the average wheel size is left alone.
    """
    if not e_d > 0:
        raise ValueError(f"E_d must be > 0, got {e_d!r}")
    return 2.0 / (e_d + 1.0), 2.0 / (1.0 / e_d + 1.0)


def umbmark_corrections(
    cw_errors: np.ndarray, ccw_errors: np.ndarray, side: float, wheel_base: float,
    use: str = "xy",
) -> UmbmarkResult:
    """Borenstein and Feng's corrections from the CW and CCW return errors.

    ``*_errors`` are ``(n, 2)`` or ``(n, 3)`` arrays of return errors (actual minus
    odometric end, metres, in the start frame: x forward, y left); ``side`` is L (m)
    and ``wheel_base`` the nominal b (m) the odometry used.

    ``use`` picks the formulas: ``"x"`` the paper's (from the x errors), ``"y"`` its
    alternative from the y errors, ``"xy"`` (default) their mean. The two sets err
    in opposite directions at second order: the heading error piles up to about
    ``4 (alpha + beta)`` over a square and turns the error vector, moving x and y
    errors against each other. With 3 % and 1 % errors on a 3.5 m square each set
    alone misses alpha by ~30 %, their mean by ~5 %.
    """
    if not side > 0 or not wheel_base > 0:
        raise ValueError(f"side and wheel_base must be > 0 m, got {side!r}, {wheel_base!r}")
    cw, ccw = centres_of_gravity(cw_errors, ccw_errors)
    alpha, beta = alpha_beta(cw, ccw, side, use)
    e_b = wheel_base_ratio(alpha)
    b_actual = e_b * wheel_base
    radius = curve_radius(beta, side)
    e_d = wheel_diameter_ratio(radius, b_actual)
    c_left, c_right = wheel_correction_factors(e_d)
    return UmbmarkResult(
        side=side, cg_cw=(float(cw[0]), float(cw[1])), cg_ccw=(float(ccw[0]), float(ccw[1])),
        e_max_syst=float(max(np.hypot(*cw), np.hypot(*ccw))), alpha=float(alpha),
        beta=float(beta), radius=float(radius), e_d=float(e_d), e_b=float(e_b),
        wheel_base=float(b_actual), c_left=float(c_left), c_right=float(c_right),
    )


def cancelling_wheel_ratio(e_b: float, side: float, wheel_base: float) -> float:
    """The ``E_d`` whose curved legs give back, on a counter-clockwise square of ``side``
    m, exactly what each turn loses to a wheel base ``E_b`` times the nominal
    ``wheel_base`` (m): ``beta = alpha``, so the two type-A and type-B errors cancel
    going one way round and add up the other (Borenstein and Feng 1996, section 5.1: why
    the benchmark drives both directions). ``alpha = pi/2 (1 - 1/E_b)`` is each turn's
    shortfall, the legs' radius is eqn 5.11's for ``beta = alpha`` and ``E_d`` is eqn
    5.12's with the actual wheel base."""
    if not (math.isfinite(e_b) and e_b > 0):
        raise ValueError(f"e_b must be a finite ratio > 0, got {e_b!r}")
    alpha = math.pi / 2 * (1 - 1 / e_b)
    return wheel_diameter_ratio(curve_radius(alpha, side), e_b * wheel_base)


def model_return_error(side: float, wheel_base: float, e_d: float, e_b: float,
                       direction: str) -> tuple[float, float]:
    """Return error (x, y) (m) of one square by the small-angle model above.

    ``alpha = pi/2 (1 - 1/E_b)``; ``beta = 2 asin(L / 2R)`` with the R for which
    ``(R + b/2)/(R - b/2) = E_d`` (b the actual wheel base, ``E_b b``).
    """
    values = {"side": side, "wheel_base": wheel_base, "e_d": e_d, "e_b": e_b}
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    alpha = math.pi / 2 * (1.0 - 1.0 / e_b)
    if e_d == 1.0:
        beta = 0.0
    else:
        radius = e_b * wheel_base / 2 * (e_d + 1) / (e_d - 1)
        beta = 2 * math.asin(side / (2 * radius))
    if direction == "cw":
        return -2 * side * (alpha + beta), -2 * side * (alpha + beta)
    if direction == "ccw":
        return -2 * side * (alpha - beta), 2 * side * (alpha - beta)
    raise ValueError(f"direction must be 'cw' or 'ccw', got {direction!r}")


# --------------------------------------------------------------------- the thesis's trials
def load_thesis_trials(path: str | Path | None = None) -> dict[str, np.ndarray]:
    """The ten end positions of figure 51: ``{"cw": (5, 3), "ccw": (5, 3)}`` (m, m, rad)."""
    path = Path(path) if path is not None else data_dir() / "umbmark_thesis_trials.csv"
    rows: dict[str, list[list[float]]] = {"cw": [], "ccw": []}
    with open(path, newline="") as handle:
        for row in csv.DictReader(row for row in handle if not row.startswith("#")):
            rows[row["direction"].lower()].append(
                [float(row["x"]), float(row["y"]), float(row["theta"])])
    return {k: np.array(v) for k, v in rows.items()}


def trial_covariance(ends: np.ndarray, ddof: int = 1) -> np.ndarray:
    """Covariance (3 x 3) of ``(n, 3)`` end poses; ``ddof=1`` is MATLAB's ``cov``."""
    ends = np.asarray(ends, dtype=float)
    if ends.ndim != 2 or ends.shape[1] != 3 or len(ends) <= ddof:
        raise ValueError(f"ends must be (n, 3) with n > ddof, got shape {ends.shape}")
    return np.cov(ends, rowvar=False, ddof=ddof)


def thesis_a16_outputs(trials: dict[str, np.ndarray] | None = None) -> dict[str, float]:
    """What A.16 computes, run as printed (degree/radian mix and all), for comparison.

    Its ``theta`` vector is the listing's nine values, not the table's ten.
    """
    trials = trials or load_thesis_trials()
    cw, ccw = trials["cw"], trials["ccw"]
    side = THESIS_SIDE
    x_cw, y_cw, x_ccw, y_ccw = cw[:, 0].mean(), cw[:, 1].mean(), ccw[:, 0].mean(), ccw[:, 1].mean()
    alpha_deg = (x_cw + x_ccw) / (-4 * side) * 180 / math.pi
    beta_deg = (x_cw - x_ccw) / (-4 * side) * 180 / math.pi
    radius = (side / 2) / math.sin(beta_deg / 2) * 180 / 3.14
    e_d = (radius + beta_deg / 2) / (radius - beta_deg / 2)
    theta9 = np.array([0.15, 0.13, 0.09, 0.01, 0.03, 0.12, 0.16, 0.21, 0.16])
    x = np.concatenate([cw[:, 0], ccw[:, 0]])
    y = np.concatenate([cw[:, 1], ccw[:, 1]])
    return {
        "emax": float(max(math.hypot(x_cw, y_cw), math.hypot(x_ccw, y_ccw))),
        "alpha_deg": alpha_deg, "beta_deg": beta_deg, "R": radius, "E_d": e_d,
        "E_b": 90 / (90 - alpha_deg), "c_l": 2 / (e_d + 1), "c_r": 2 / (1 / e_d + 1),
        "cov_x": float(np.var(x, ddof=1)), "cov_y": float(np.var(y, ddof=1)),
        "cov_theta": float(np.var(theta9, ddof=1)),
    }
