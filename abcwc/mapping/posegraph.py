"""Pose-graph optimisation: sparse Levenberg-Marquardt over SE(2).

The objective is the standard between-factor least squares of graph SLAM (Grisetti et
al., "A tutorial on graph-based SLAM", IEEE ITS Magazine 2010, eqns 1-4; Kümmerle et al.,
"g2o", ICRA 2011)::

    chi2(x) = sum over edges k = (i, j) of  e_k^T  I_k  e_k
    e_k     = Log( z_k^-1 (+) x_i^-1 (+) x_j )                       (3,)

with ``z_k`` the measured pose of ``j`` seen from ``i``, ``I_k`` its information matrix
and ``Log`` SE(2)'s logarithm: the angle ``wrap(theta_j - theta_i - theta_z)`` and the
translation ``V(theta)^-1 t`` of the residual pose, ``V^-1 = [[a, theta/2], [-theta/2,
a]]``, ``a = (theta/2) cot(theta/2)`` (Eade, "Lie groups for 2D and 3D transformations",
2017, sec. 3). This is GTSAM's ``BetweenFactor<Pose2>`` error (GTSAM's graph error is
half this chi2), so the figures here compare with GTSAM's one for one.

The solver linearises in the plain coordinates ``(x, y, theta)`` of every free pose
(updates add, angles wrap), with analytic Jacobians from the chain rule through ``Log``
(:func:`edge_jacobians`), and builds ``H = J^T I J`` and ``g = J^T I e`` block by block
for all edges at once (NumPy) into a scipy.sparse matrix whose pattern and fill-reducing
order are worked out once. Each step solves ``(H + lambda 1) h = -g`` by sparse LU
(SuperLU in symmetric mode; scipy has no sparse Cholesky), with Levenberg's damping
``lambda 1`` as GTSAM's default, started close to Gauss-Newton (``INITIAL_DAMPING``) and
updated by Nielsen's rule (Madsen, Nielsen and Tingleff, "Methods for non-linear least
squares problems", 2004, eqns 3.14-3.16): the gain ratio of actual to predicted decrease
scales lambda by ``max(1/3, 1 - (2 rho - 1)^3)`` after a good step; a step that does not
lower the cost is refused and lambda grows by ``nu`` = 2, 4, 8, ... Pose 0 is held fixed
(or the graph's ``FIX`` poses), which removes the gauge freedom.

Robust kernels (``robust="huber"`` or ``"cauchy"``, off by default) down-weight edges
whose error ``r = sqrt(e^T I e)`` is large, by iteratively reweighted least squares:
each linearisation weights edge k by ``w_k = rho'(r_k^2)``, and the steps minimise
``sum rho(r_k^2)`` (Huber: ``rho(s) = s`` for ``r <= c``, ``2 c r - c^2`` beyond;
Cauchy: ``c^2 log(1 + s / c^2)``; ``c = robust_width``, in standard deviations). With a
kernel, one false loop closure cannot bend the whole map; the reported chi2 stays the
plain objective above.

Where LM starts matters. From the file's poses or the chained odometry it may stall in a
poor local minimum; so may it from LAGO's linear estimate (Carlone et al., "A fast and
accurate approximation for planar pose graph optimization", IJRR 2014), whose headings
are the weighted linear least squares of ``theta_j - theta_i = theta_z + 2 pi k_ij``,
the whole turns ``k_ij`` taken from the given poses: where those poses are far off, some
``k_ij`` are wrong, and the error is spread round the graph. By default
(``initial="chordal"``) the headings come from the chordal relaxation instead (Martinec
and Pajdla, "Robust rotation and translation estimation in multiview reconstruction",
CVPR 2007; in 2D as in Carlone, Tron, Daniilidis and Dellaert, "Initialization
techniques for 3D SLAM: a survey on rotation estimation and its use in pose graph
optimization", ICRA 2015): each heading as a unit complex number ``c_i = e^(i theta_i)``,
the linear least squares of ``c_j = e^(i theta_z) c_i`` (no whole turns to guess), then
each ``c_i`` taken back to its angle. The positions then come, in both, from the linear
least squares of ``t_j - t_i = R(theta_i) t_z`` given those headings. On the MIT graph,
LM ends at chi2 770.2 from the file's poses and from LAGO, 41.21 from the chordal start;
on the noisy M3500 graphs (Olson's Manhattan world with 0.1, 0.2 and 0.3 rad of added
heading noise) 8310, 11074 and 9012 from LAGO, 912.2, 2055 and 4108 from the chordal
start (GTSAM 4.3's LM reaches the same four from the chordal starts). ``initial="lago"`` and
``"given"`` start from LAGO's estimate or from the graph's poses themselves. Either way,
the chi2 reported first is the one at the graph's poses.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from abcwc.geometry import relative, wrap_angle
from abcwc.mapping.g2o import PoseGraph

ROBUST_KERNELS = ("huber", "cauchy")
DEFAULT_ROBUST_WIDTH = math.sqrt(7.814727903251178)
"""sqrt of the 95 % point of chi2 with 3 degrees of freedom: an edge whose error is
within this many standard deviations counts in full."""
INITIALISATIONS = ("chordal", "lago", "given")
INITIAL_DAMPING = 1e-10
"""Levenberg's lambda at the start, as a fraction of the largest diagonal entry of H:
nearly Gauss-Newton, like GTSAM's default lambda = 1e-5 for information of this size."""

Progress = Callable[[int, float, float], None]
"""Called after every accepted step with (iteration, cost, lambda); the cost is chi2
unless a robust kernel is on."""


@dataclass(frozen=True)
class SolveResult:
    """What a solve did: chi2 at the graph's poses (``chi2_initial``), where LM started
    (``chi2_start``: the chordal or LAGO estimate, or the same) and at the end (the plain objective,
    whatever the kernel); the robust cost at the end (= chi2 without a kernel); accepted
    steps (``iterations``); linear solves, accepted or not; wall-clock ``seconds``
    including the initialisation; whether it converged and why it stopped."""

    chi2_initial: float
    chi2_start: float
    chi2_final: float
    cost_final: float
    iterations: int
    solves: int
    seconds: float
    converged: bool
    reason: str


# --- the error and its Jacobians ------------------------------------------------------


def _half_cot(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``a = (theta/2) cot(theta/2)`` and ``da/dtheta``; series near 0 (|theta| < 1e-4)."""
    small = np.abs(theta) < 1e-4
    half = np.where(small, 1.0, theta / 2.0)
    cot = np.cos(half) / np.sin(half)
    a = np.where(small, 1.0 - theta**2 / 12.0, half * cot)
    da = np.where(small, -theta / 6.0, 0.5 * cot - 0.5 * half / np.sin(half) ** 2)
    return a, da


def se2_log(poses: np.ndarray) -> np.ndarray:
    """SE(2)'s logarithm of (M, 3) poses ``(x, y, theta)``: ``(V^-1 (x, y), theta)`` with
    ``theta`` wrapped (Eade 2017, sec. 3); (M, 3) tangent vectors (m, m, rad)."""
    theta = wrap_angle(poses[:, 2])
    a, _ = _half_cot(theta)
    x, y = poses[:, 0], poses[:, 1]
    return np.stack([a * x + theta / 2.0 * y, -theta / 2.0 * x + a * y, theta], axis=1)


def _residual_poses(poses: np.ndarray, graph: PoseGraph) -> tuple[np.ndarray, np.ndarray]:
    """``relative(x_i, x_j)`` and the residual pose ``z^-1 (+) relative(x_i, x_j)``."""
    between = relative(poses[graph.i], poses[graph.j])
    return between, relative(graph.measurements, between)


def edge_errors(poses: np.ndarray, graph: PoseGraph) -> np.ndarray:
    """(M, 3) errors ``e_k = Log(z_k^-1 (+) x_i^-1 (+) x_j)`` of every edge (m, m, rad)."""
    return se2_log(_residual_poses(np.asarray(poses, dtype=float), graph)[1])


def edge_chi2(errors: np.ndarray, information: np.ndarray) -> np.ndarray:
    """(M,) ``e_k^T I_k e_k`` (dimensionless)."""
    return np.einsum("mi,mij,mj->m", errors, information, errors)


def chi2(poses: np.ndarray, graph: PoseGraph) -> float:
    """The objective ``sum e_k^T I_k e_k`` at ``poses`` (N, 3)."""
    poses = np.asarray(poses, dtype=float)
    if poses.shape != graph.poses.shape:
        raise ValueError(f"poses have shape {poses.shape}, the graph has {graph.poses.shape}")
    return float(edge_chi2(edge_errors(poses, graph), graph.information).sum())


def edge_jacobians(poses: np.ndarray,
                   graph: PoseGraph) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Errors (M, 3) and their Jacobians ``de/dx_i``, ``de/dx_j`` (M, 3, 3) with respect
    to the poses' plain coordinates ``(x, y, theta)``.

    Chain rule: the residual pose ``r = z^-1 (+) relative(x_i, x_j)`` has translation
    ``R(theta_z + theta_i)^T (t_j - t_i) - R(theta_z)^T t_z`` and angle
    ``theta_j - theta_i - theta_z``, so ``dr/dx_j = diag(R(theta_z + theta_i)^T, 1)``
    and ``dr/dx_i = [[-R(theta_z + theta_i)^T, R(theta_z)^T S b], [0, 0, -1]]`` with
    ``b = relative(x_i, x_j)``'s translation and ``S = [[0, 1], [-1, 0]]``; then
    ``dLog/dr = [[a, theta/2, a' x + y/2], [-theta/2, a, a' y - x/2], [0, 0, 1]]``.
    """
    between, residual = _residual_poses(poses, graph)
    x, y = residual[:, 0], residual[:, 1]
    theta = wrap_angle(residual[:, 2])
    a, da = _half_cot(theta)
    m = len(theta)
    dlog = np.zeros((m, 3, 3))
    dlog[:, 0, 0] = dlog[:, 1, 1] = a
    dlog[:, 0, 1], dlog[:, 1, 0] = theta / 2.0, -theta / 2.0
    dlog[:, 0, 2] = da * x + y / 2.0
    dlog[:, 1, 2] = da * y - x / 2.0
    dlog[:, 2, 2] = 1.0
    errors = np.stack([a * x + theta / 2.0 * y, -theta / 2.0 * x + a * y, theta], axis=1)

    angle = graph.measurements[:, 2] + poses[graph.i, 2]
    c, s = np.cos(angle), np.sin(angle)
    cz, sz = np.cos(graph.measurements[:, 2]), np.sin(graph.measurements[:, 2])
    bx, by = between[:, 0], between[:, 1]
    dr_j = np.zeros((m, 3, 3))
    dr_j[:, 0, 0], dr_j[:, 0, 1], dr_j[:, 1, 0], dr_j[:, 1, 1] = c, s, -s, c
    dr_j[:, 2, 2] = 1.0
    dr_i = -dr_j
    dr_i[:, 0, 2] = cz * by - sz * bx      # R(theta_z)^T (b_y, -b_x)
    dr_i[:, 1, 2] = -sz * by - cz * bx
    return errors, dlog @ dr_i, dlog @ dr_j


# --- robust kernels ---------------------------------------------------------------------


def robust_weights(squared: np.ndarray, kernel: str | None,
                   width: float) -> tuple[np.ndarray, np.ndarray]:
    """IRLS weights ``rho'(s)`` and costs ``rho(s)`` of squared errors ``s = e^T I e``."""
    if kernel is None:
        return np.ones_like(squared), squared
    c2 = width * width
    if kernel == "huber":
        r = np.sqrt(squared)
        inside = r <= width
        weights = np.where(inside, 1.0, width / np.maximum(r, width))
        return weights, np.where(inside, squared, 2.0 * width * r - c2)
    return 1.0 / (1.0 + squared / c2), c2 * np.log1p(squared / c2)  # cauchy


# --- the normal equations ----------------------------------------------------------------


class _NormalEquations:
    """``H = J^T W I J`` and ``g = J^T W I e`` over the free poses' coordinates, summed
    into a sparse pattern worked out once per graph.

    The unknowns are numbered in a fill-reducing order computed once on the pose graph
    itself (SuperLU's minimum degree on ``A^T + A`` of the poses' adjacency, each pose's
    three coordinates kept together), so every factorisation skips the ordering.
    """

    def __init__(self, graph: PoseGraph, fixed: np.ndarray) -> None:
        n = len(graph.ids)
        self.free = np.ones(n, dtype=bool)
        self.free[fixed] = False
        count = int(self.free.sum())
        variable = np.full(n, -1, dtype=np.int64)
        variable[self.free] = _pose_order(graph, variable_of=self.free, count=count)
        self.size = 3 * count
        vi, vj = variable[graph.i], variable[graph.j]
        r3 = np.arange(3)
        rows, cols = [], []
        for va, vb in ((vi, vi), (vi, vj), (vj, vi), (vj, vj)):   # blocks ii, ij, ji, jj
            valid = ((va >= 0) & (vb >= 0))[:, None, None]
            shape = (len(va), 3, 3)
            rows.append(np.where(valid, 3 * va[:, None, None] + r3[:, None], -1))
            cols.append(np.where(valid, 3 * vb[:, None, None] + r3[None, :], -1))
        row = np.concatenate([np.broadcast_to(r, shape).ravel() for r in rows])
        col = np.concatenate([np.broadcast_to(c, shape).ravel() for c in cols])
        self.keep = row >= 0
        keys = row[self.keep] * self.size + col[self.keep]
        unique, self.slot = np.unique(keys, return_inverse=True)
        self.indices = (unique % self.size).astype(np.int32)
        self.indptr = np.searchsorted(unique // self.size,
                                      np.arange(self.size + 1)).astype(np.int32)
        self.diagonal = np.nonzero(unique // self.size == unique % self.size)[0]
        grad_rows = np.concatenate([(3 * vi[:, None] + r3).ravel(),
                                    (3 * vj[:, None] + r3).ravel()])
        self.grad_keep = grad_rows >= 0
        self.grad_rows = grad_rows[self.grad_keep]
        self.unknown_of_pose = (3 * variable[self.free][:, None] + r3).ravel()

    def build(self, jac_i: np.ndarray, jac_j: np.ndarray, weighted_info: np.ndarray,
              errors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The data of ``H`` (in the fixed pattern) and the gradient ``g``."""
        ti = np.swapaxes(jac_i, 1, 2) @ weighted_info          # J_i^T W I
        tj = np.swapaxes(jac_j, 1, 2) @ weighted_info
        blocks = np.concatenate([(ti @ jac_i).ravel(), (ti @ jac_j).ravel(),
                                 (tj @ jac_i).ravel(), (tj @ jac_j).ravel()])
        data = np.bincount(self.slot, weights=blocks[self.keep], minlength=len(self.indices))
        grad_values = np.concatenate([(ti @ errors[:, :, None]).ravel(),
                                      (tj @ errors[:, :, None]).ravel()])
        gradient = np.bincount(self.grad_rows, weights=grad_values[self.grad_keep],
                               minlength=self.size)
        return data, gradient

    def solve(self, data: np.ndarray, damping: float, rhs: np.ndarray) -> np.ndarray:
        """Solve ``(H + damping I) h = rhs``; H given by its pattern's ``data``."""
        damped = data.copy()
        damped[self.diagonal] += damping
        matrix = sp.csc_matrix((damped, self.indices, self.indptr),
                               shape=(self.size, self.size))  # symmetric: CSR = CSC
        lu = spla.splu(matrix, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
        return lu.solve(rhs)

    def pose_steps(self, step: np.ndarray) -> np.ndarray:
        """The solution vector as (free poses, 3) steps, in the poses' own order."""
        return step[self.unknown_of_pose].reshape(-1, 3)


def _pose_order(graph: PoseGraph, variable_of: np.ndarray, count: int) -> np.ndarray:
    """Each free pose's place (0..count-1) in a fill-reducing elimination order."""
    index = np.cumsum(variable_of) - 1
    keep = variable_of[graph.i] & variable_of[graph.j]
    a, b = index[graph.i[keep]], index[graph.j[keep]]
    ones = np.ones(2 * len(a))
    adjacency = sp.coo_matrix((-ones, (np.r_[a, b], np.r_[b, a])), shape=(count, count))
    laplacian = (adjacency + sp.diags(np.bincount(np.r_[a, b], minlength=count) + 1.0))
    lu = spla.splu(laplacian.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    return lu.perm_c  # perm_c[k]: the place of pose k


# --- Levenberg-Marquardt ----------------------------------------------------------------


def _check_options(graph: PoseGraph, robust: str | None, robust_width: float,
                   max_iterations: int, relative_tolerance: float, initial: str) -> None:
    if robust is not None and robust not in ROBUST_KERNELS:
        raise ValueError(f"robust kernel {robust!r} unknown; allowed: None, "
                         f"{', '.join(ROBUST_KERNELS)}")
    if not (math.isfinite(robust_width) and robust_width > 0):
        raise ValueError(f"robust_width must be a finite number > 0, got {robust_width!r}")
    if not (isinstance(max_iterations, int) and max_iterations >= 0):
        raise ValueError(f"max_iterations must be an integer >= 0, got {max_iterations!r}")
    if not (0 <= relative_tolerance < 1):
        raise ValueError(f"relative_tolerance {relative_tolerance!r} outside [0, 1)")
    if initial not in INITIALISATIONS:
        raise ValueError(f"initial {initial!r} unknown; allowed: {', '.join(INITIALISATIONS)}")
    if not np.all(np.isfinite(graph.poses)):
        raise ValueError("the graph's initial poses must be finite")
    _check_anchored(graph)


def _check_anchored(graph: PoseGraph) -> None:
    """ValueError unless every pose is joined by edges to a fixed pose (else H is
    singular: nothing says where the unjoined poses are)."""
    n = len(graph.ids)
    fixed = _fixed_poses(graph)
    adjacency = sp.coo_matrix((np.ones(len(graph.edges)), (graph.i, graph.j)), shape=(n, n))
    _, component = connected_components(adjacency, directed=False)
    loose = np.nonzero(~np.isin(component, component[fixed]))[0]
    if len(loose):
        raise ValueError(f"{len(loose)} pose(s) not joined by edges to a fixed pose, "
                         f"e.g. vertex {graph.ids[loose[0]]}: the graph must be connected")


def optimise(graph: PoseGraph, *, robust: str | None = None,
             robust_width: float = DEFAULT_ROBUST_WIDTH, max_iterations: int = 100,
             relative_tolerance: float = 1e-6, initial: str = "chordal",
             progress: bool | Progress = False) -> tuple[np.ndarray, SolveResult]:
    """Minimise the graph's chi2 by sparse Levenberg-Marquardt; see the module notes.

    Starts from the chordal estimate (``initial="chordal"``, :func:`chordal`), LAGO's
    (``"lago"``, :func:`lago`) or from ``graph.poses`` (``"given"``). Stops when an
    accepted step lowers the cost by less than ``relative_tolerance`` of it, when the
    gradient or the step vanishes, when no step lowers it, or after ``max_iterations``
    accepted steps. ``robust``: None, ``"huber"`` or ``"cauchy"``
    with ``robust_width`` in standard deviations (sqrt of chi2 units). ``progress``:
    True for a tqdm bar, or a callable ``(iteration, chi2, lambda)``.
    Returns the optimised poses (N, 3) and a :class:`SolveResult`.
    """
    _check_options(graph, robust, robust_width, max_iterations, relative_tolerance, initial)
    start = time.perf_counter()
    fixed = _fixed_poses(graph)
    poses = {"given": lambda g: g.poses.copy(), "lago": lago, "chordal": chordal}[initial](graph)
    chi2_initial = chi2(graph.poses, graph)
    chi2_start = chi2_initial if initial == "given" else chi2(poses, graph)
    equations = _NormalEquations(graph, fixed)
    report, bar = _progress(progress, max_iterations)

    def linearise(x: np.ndarray):
        errors, jac_i, jac_j = edge_jacobians(x, graph)
        squared = edge_chi2(errors, graph.information)
        weights, costs = robust_weights(squared, robust, robust_width)
        data, gradient = equations.build(jac_i, jac_j,
                                         weights[:, None, None] * graph.information, errors)
        return data, gradient, float(costs.sum())

    def cost(x: np.ndarray) -> float:
        squared = edge_chi2(edge_errors(x, graph), graph.information)
        return float(robust_weights(squared, robust, robust_width)[1].sum())

    data, gradient, current = linearise(poses)
    damping, nu = INITIAL_DAMPING * data[equations.diagonal].max(), 2.0
    iterations = solves = 0
    converged, reason = False, "maximum iterations"
    while iterations < max_iterations:
        if np.abs(gradient).max() <= 1e-12 * max(current, 1.0):
            converged, reason = True, "gradient vanished"
            break
        step = equations.solve(data, damping, -gradient)
        solves += 1
        if np.abs(step).max() <= 1e-12 * (np.abs(poses).max() + 1e-12):
            converged, reason = True, "step vanished"
            break
        candidate = poses.copy()
        candidate[equations.free] += equations.pose_steps(step)
        candidate[:, 2] = wrap_angle(candidate[:, 2])
        new = cost(candidate)
        predicted = float(step @ (damping * step - gradient))  # L(0) - L(h), eqn 3.14
        gain = (current - new) / predicted if predicted > 0 else -1.0
        if gain > 0 and np.isfinite(new):
            decrease = (current - new) / max(current, 1e-300)
            poses = candidate
            iterations += 1
            damping *= max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3)   # Nielsen
            nu = 2.0
            data, gradient, current = linearise(poses)
            report(iterations, current, damping)
            if decrease < relative_tolerance:
                converged, reason = True, "relative decrease below tolerance"
                break
        else:
            damping *= nu
            nu *= 2.0
            if not damping < 1e16 * max(data[equations.diagonal].max(), 1.0):
                converged, reason = True, "no step lowers the cost"
                break
    if bar is not None:
        bar.close()
    result = SolveResult(chi2_initial, chi2_start, chi2(poses, graph), current, iterations,
                         solves, time.perf_counter() - start, converged, reason)
    return poses, result


def _progress(progress: bool | Progress, total: int):
    """The callback to report accepted steps to, and the tqdm bar to close (or None)."""
    if callable(progress):
        return progress, None
    if not progress:
        return (lambda *_: None), None
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc="pose graph LM", unit="step")

    def report(iteration: int, value: float, damping: float) -> None:
        bar.update(1)
        bar.set_postfix(chi2=f"{value:.6g}")

    return report, bar


# --- linear initial guesses: LAGO and the chordal relaxation -----------------------------


def lago(graph: PoseGraph) -> np.ndarray:
    """Initial poses (N, 3) by LAGO (Carlone et al. 2014): linear least squares for the
    headings, the whole turns taken from the given poses, then for the positions given
    the headings (:func:`positions_given_headings`); pose 0 (or the fixed poses) stay
    where the graph has them."""
    fixed = _fixed_poses(graph)
    i, j, z = graph.i, graph.j, graph.measurements
    # headings: theta_j - theta_i = z_theta + 2 pi k, k from the given headings
    wraps = np.round((graph.poses[j, 2] - graph.poses[i, 2] - z[:, 2]) / (2 * math.pi))
    target = z[:, 2] + 2 * math.pi * wraps
    theta = _anchored_least_squares(len(graph.ids), i, j, target[:, None],
                                    _heading_information(graph)[:, None, None], fixed,
                                    graph.poses[:, 2:3])[:, 0]
    return positions_given_headings(graph, theta)


def chordal(graph: PoseGraph) -> np.ndarray:
    """Initial poses (N, 3): headings by the chordal relaxation (module notes; Martinec
    and Pajdla 2007, Carlone et al. 2015), then the positions given them
    (:func:`positions_given_headings`). Each heading is a unit complex number ``c_i =
    (cos theta_i, sin theta_i)``; every edge asks ``c_j = R(theta_z) c_i``, weighted by
    the edge's heading information, and the fixed poses hold theirs. That is linear in
    the ``c_i``, with no whole turns to guess; its least squares (sparse LU of the normal
    equations) are taken back to angles by ``atan2``."""
    i, j, m = graph.i, graph.j, len(graph.i)
    free, variable = _unknowns(len(graph.ids), _fixed_poses(graph))
    anchor = np.column_stack([np.cos(graph.poses[:, 2]), np.sin(graph.poses[:, 2])])
    c, s = np.cos(graph.measurements[:, 2]), np.sin(graph.measurements[:, 2])
    turn = _rotations(c, s)  # R(theta_z)
    weight = np.sqrt(_heading_information(graph))
    # residual of edge k, rows 2k and 2k + 1: weight (c_j - R(theta_z) c_i)
    edge, axis = np.arange(m)[:, None, None], np.arange(2)
    rows, cols, values = [], [], []
    on_j, on_i = variable[j] >= 0, variable[i] >= 0
    rows.append((2 * edge[on_j, 0] + axis).ravel())
    cols.append((2 * variable[j][on_j, None] + axis).ravel())
    values.append(np.repeat(weight[on_j], 2))
    shape = (int(on_i.sum()), 2, 2)
    rows.append(np.broadcast_to(2 * edge[on_i] + axis[:, None], shape).ravel())
    cols.append(np.broadcast_to(2 * variable[i][on_i, None, None] + axis, shape).ravel())
    values.append((-weight[on_i, None, None] * turn[on_i]).ravel())
    known = (np.where(on_j[:, None], 0.0, anchor[j])
             - np.einsum("kab,kb->ka", turn, np.where(on_i[:, None], 0.0, anchor[i])))
    design = sp.coo_matrix((np.concatenate(values), (np.concatenate(rows),
                                                      np.concatenate(cols))),
                           shape=(2 * m, 2 * int(free.sum()))).tocsc()
    rhs = design.T @ (-(weight[:, None] * known).ravel())
    solution = _solve_symmetric((design.T @ design).tocsc(), rhs)
    theta = graph.poses[:, 2].astype(float)
    unit = solution.reshape(-1, 2)
    theta[free] = np.arctan2(unit[:, 1], unit[:, 0])
    return positions_given_headings(graph, theta)


def positions_given_headings(graph: PoseGraph, theta: np.ndarray) -> np.ndarray:
    """Poses (N, 3): the headings ``theta`` (rad) and the positions that are the linear
    least squares of ``t_j - t_i = R(theta_i) t_z``, with each edge's translation
    information turned into the world frame; the fixed poses keep theirs."""
    fixed = _fixed_poses(graph)
    i, j, z = graph.i, graph.j, graph.measurements
    c, s = np.cos(theta[i]), np.sin(theta[i])
    shift = np.stack([c * z[:, 0] - s * z[:, 1], s * z[:, 0] + c * z[:, 1]], axis=1)
    rotation = _rotations(c, s)  # R(theta_i)
    info_xy = np.linalg.inv(np.linalg.inv(graph.information)[:, :2, :2])
    info_world = rotation @ info_xy @ np.swapaxes(rotation, 1, 2)
    xy = _anchored_least_squares(len(graph.ids), i, j, shift, info_world, fixed,
                                 graph.poses[:, :2])
    return np.column_stack([xy, wrap_angle(theta)])


def _fixed_poses(graph: PoseGraph) -> np.ndarray:
    """The indices of the poses held in place: the graph's ``FIX`` poses, or pose 0."""
    return graph.fixed if len(graph.fixed) else np.array([0])


def _unknowns(n: int, fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Of ``n`` poses with ``fixed`` held: which are free (N,) bool, and each one's
    number among the free ones (N,) (-1 for the fixed)."""
    free = np.ones(n, dtype=bool)
    free[fixed] = False
    variable = np.full(n, -1)
    variable[free] = np.arange(free.sum())
    return free, variable


def _rotations(c: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(M, 2, 2) the rotation matrices of the angles whose cosines and sines are ``c``
    and ``s``."""
    return np.stack([np.stack([c, -s], 1), np.stack([s, c], 1)], 1)


def _solve_symmetric(matrix: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
    """``matrix x = rhs`` for a symmetric positive definite sparse ``matrix``: SuperLU
    in symmetric mode, its minimum-degree order on ``A^T + A``."""
    return spla.splu(matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                     options={"SymmetricMode": True}).solve(rhs)


def _heading_information(graph: PoseGraph) -> np.ndarray:
    """(M,) each edge's marginal heading information, 1 / var(theta_z)."""
    return 1.0 / np.linalg.inv(graph.information)[:, 2, 2]


def _anchored_least_squares(n: int, i: np.ndarray, j: np.ndarray, target: np.ndarray,
                            information: np.ndarray, fixed: np.ndarray,
                            anchor: np.ndarray) -> np.ndarray:
    """Minimise ``sum (v_j - v_i - target)^T W (v_j - v_i - target)`` over d-vectors
    ``v`` (N, d) with per-edge weights ``W`` = ``information`` (M, d, d), the ``fixed``
    rows held at ``anchor``'s values: the normal equations, block by block, solved by
    sparse LU."""
    d = target.shape[1]
    free, variable = _unknowns(n, fixed)
    known = anchor[j] * ~free[j][:, None] - anchor[i] * ~free[i][:, None]
    weighted = information @ (target - known)[:, :, None]                 # W (t - known)
    rd = np.arange(d)
    rows, cols, values = [], [], []
    for va, vb, sign in ((i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)):
        ra, rb = variable[va], variable[vb]
        ok = (ra >= 0) & (rb >= 0)
        shape = (int(ok.sum()), d, d)
        rows.append(np.broadcast_to(d * ra[ok, None, None] + rd[:, None], shape).ravel())
        cols.append(np.broadcast_to(d * rb[ok, None, None] + rd[None, :], shape).ravel())
        values.append(sign * information[ok].ravel())
    size = d * int(free.sum())
    normal = sp.coo_matrix((np.concatenate(values), (np.concatenate(rows),
                                                      np.concatenate(cols))),
                           shape=(size, size)).tocsc()
    rhs = np.zeros(size)
    for va, sign in ((j, 1.0), (i, -1.0)):
        ok = variable[va] >= 0
        np.add.at(rhs, (d * variable[va][ok, None] + rd).ravel(),
                  sign * weighted[ok, :, 0].ravel())
    solution = _solve_symmetric(normal, rhs)
    out = anchor.astype(float)
    out[free] = solution.reshape(-1, d)
    return out
