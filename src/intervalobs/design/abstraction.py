r"""Affine abstraction of a vector field over a box (Khajenejad & Yong, Proposition 1, LP (1), Corollary 1).

LP (1) looks for slopes and offsets with

.. math:: \underline{A}x_s + \underline{e} + \sigma \le q(x_s) \le \overline{A}x_s + \overline{e} - \sigma,\qquad
          (\overline{A} - \underline{A})x_s + \overline{e} - \underline{e} - 2\sigma \le \theta\mathbf 1

at every vertex :math:`x_s` of the box :math:`\mathcal B`, minimising :math:`\theta`. It is solved with
SciPy's HiGHS.

The margin :math:`\sigma`. Every :math:`x\in\mathcal B` is a convex combination
:math:`x = \sum_s\lambda_s(x)x_s` of the vertices with the multilinear weights, and affine functions
commute with it, so :math:`q_i(x) \le \overline{A}_ix + \overline{e}_i` holds on the box as soon as
:math:`\sigma_i \ge \sup_{x\in\mathcal B}|q_i(x) - \sum_s\lambda_s(x)q_i(x_s)|` (the interpolation error
of multilinear interpolation). For the class of :math:`C^1` functions with Jacobian bounds
:math:`a_{ij} \le \partial q_i/\partial x_j \le b_{ij}` (the class of Khajenejad & Yong's Assumption 1;
[18, Prop. 1] treats simplices, this is its box version): since :math:`\sum_s\lambda_s(x - x_s) = 0`,
any constant vector :math:`c_i` may be subtracted from the gradients in the mean-value form, and with
:math:`c_{ij} = (a_{ij} + b_{ij})/2`, :math:`G_{ij} = (b_{ij} - a_{ij})/2`,

.. math:: \Big|q_i(x) - \sum_s\lambda_s q_i(x_s)\Big| = \Big|\sum_s\lambda_s(\nabla q_i(\xi_s) - c_i)^\top(x - x_s)\Big|
          \le \sum_j G_{ij}\sum_s\lambda_s|x_j - x_{s,j}| \le \tfrac12\sum_j G_{ij}h_j

because :math:`\sum_s\lambda_s|x_j - x_{s,j}| = 2(x_j - \underline x_j)(\overline x_j - x_j)/h_j \le h_j/2`
(:math:`h` the box widths). Affine components get :math:`\sigma = 0`. For :math:`C^2` functions with
:math:`|\partial^2 q_i/\partial x_j^2| \le M_{ij}` the tensor-product interpolation error bound
:math:`\sigma_i = \tfrac18\sum_j M_{ij}h_j^2` is also offered; the smaller valid one is used.

Soundness does not rest on the LP solver's tolerances: after the solve, the offsets are recomputed
exactly from the vertex values (:math:`\overline e_i = \max_s(q_i(x_s) - \overline A_ix_s) + \sigma_i`,
likewise :math:`\underline e`), rounded outward.

Corollary 1 intersects these affine bounds (their range over the box, Proposition 2) with the
decomposition-function bounds: :func:`corollary1_bounds`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from ..errors import AssumptionError, BoundsError, DesignError, DimensionError
from ..inclusion import VectorFunction, evaluate_function
from ..interval import Interval, inflate, matvec_bounds
from ..lp.certified import LP_OPTIONS

__all__ = ["AffineAbstraction", "abstraction_sigma", "affine_abstraction", "corollary1_bounds"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class AffineAbstraction:
    r"""Affine bounds :math:`\underline Ax + \underline e \le q(x) \le \overline Ax + \overline e` on a box.

    Attributes
    ----------
    A_lower, A_upper : numpy.ndarray, shape (m, n)
        Lower and upper slopes.
    e_lower, e_upper : numpy.ndarray, shape (m,)
        Offsets (recomputed from the vertex values and rounded outward after the LP).
    theta : float
        Optimal value of the abstraction LP as reported by the solver.
    sigma : numpy.ndarray, shape (m,)
        The margin used for each component.
    domain : Interval
        The box on which the bounds hold.
    status : str
        Solver message.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): LP (1).
    """

    A_lower: FloatArray
    A_upper: FloatArray
    e_lower: FloatArray
    e_upper: FloatArray
    theta: float
    sigma: FloatArray
    domain: Interval
    status: str

    def range_bounds(self, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
        r"""Bounds of :math:`q` over sub-boxes of the domain (the range of the affine bounds).

        Rows whose box is not inside the domain get :math:`(-\infty, +\infty)` (no information).

        Parameters
        ----------
        lower, upper : array_like, shape (..., n)

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., m)

        References
        ----------
        Khajenejad & Yong (:mod:`intervalobs.references`): the :math:`\hat q` terms of Corollary 1.
        """
        lo = np.asarray(lower, dtype=float)
        hi = np.asarray(upper, dtype=float)
        low = matvec_bounds(self.A_lower, lo, hi)[0] + self.e_lower
        high = matvec_bounds(self.A_upper, lo, hi)[1] + self.e_upper
        low, high = inflate(low, high)
        inside = np.all((lo >= self.domain.lower) & (hi <= self.domain.upper), axis=-1)[..., None]
        return np.where(inside, low, -np.inf), np.where(inside, high, np.inf)


def abstraction_sigma(
    lower: ArrayLike,
    upper: ArrayLike,
    j_lower: ArrayLike | None = None,
    j_upper: ArrayLike | None = None,
    hessian_diag_bound: ArrayLike | None = None,
) -> FloatArray:
    r"""Sound :math:`\sigma` of the abstraction LP for a box, from Jacobian bounds and/or second-derivative bounds.

    Parameters
    ----------
    lower, upper : array_like, shape (n,)
        The box.
    j_lower, j_upper : array_like, shape (m, n), optional
        Jacobian bounds on the box: :math:`\sigma_i = \frac14\sum_j (b_{ij} - a_{ij})h_j`.
    hessian_diag_bound : array_like, shape (m, n), optional
        :math:`M_{ij} \ge |\partial^2 q_i/\partial x_j^2|` on the box: :math:`\sigma_i = \frac18\sum_j M_{ij}h_j^2`.

    Returns
    -------
    numpy.ndarray, shape (m,)
        The smaller of the available bounds, rounded up.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): LP (1).
    """
    h = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
    candidates = []
    if j_lower is not None and j_upper is not None:
        g = 0.5 * (np.asarray(j_upper, dtype=float) - np.asarray(j_lower, dtype=float))
        candidates.append(0.5 * g @ h)
    if hessian_diag_bound is not None:
        candidates.append(0.125 * np.abs(np.asarray(hessian_diag_bound, dtype=float)) @ (h * h))
    if not candidates:
        raise AssumptionError("abstraction_sigma: give Jacobian bounds or second-derivative bounds")
    sigma = np.min(np.stack(candidates), axis=0)
    if not np.all(np.isfinite(sigma)):
        raise AssumptionError(
            "abstraction_sigma: a derivative of the map is unbounded on the box: give a bounded domain"
        )
    return inflate(-sigma, sigma, floor=0.0)[1]  # an affine component keeps sigma = 0 exactly


def affine_abstraction(
    func: VectorFunction,
    lower: ArrayLike,
    upper: ArrayLike,
    sigma: ArrayLike,
    m: int | None = None,
) -> AffineAbstraction:
    r"""Solve the abstraction LP on a box with HiGHS and return sound affine bounds.

    Parameters
    ----------
    func : callable
        Component-convention vector function :math:`q`.
    lower, upper : array_like, shape (n,)
        The box :math:`\mathcal B` (finite).
    sigma : array_like, shape (m,) or scalar
        Margin σ of the LP for the function class (see :func:`abstraction_sigma`).
    m : int, optional
        Expected number of components of ``func``.

    Returns
    -------
    AffineAbstraction

    Raises
    ------
    DesignError
        If HiGHS does not return an optimal solution.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): LP (1); its margin σ.
    """
    box = Interval(lower, upper)
    if box.lower.ndim != 1:
        raise DimensionError(f"affine_abstraction: expected a single box, got shape {box.lower.shape}")
    if not np.all(np.isfinite(box.width)):
        raise BoundsError(f"lower, upper: expected finite ends, got {box.lower} and {box.upper}")
    vertices = box.vertices()
    values = evaluate_function(func, vertices, m)
    nv, n = vertices.shape
    mm = values.shape[1]
    sig = np.broadcast_to(np.asarray(sigma, dtype=float), (mm,)).copy()
    # variables: A_upper (m*n), A_lower (m*n), e_upper (m), e_lower (m), theta
    nvar = 2 * mm * n + 2 * mm + 1
    rows, rhs = [], []
    for i in range(mm):
        for s in range(nv):
            x = vertices[s]
            upper_row = np.zeros(nvar)  # -(A_u x + e_u) <= -(q + sigma)
            upper_row[i * n : (i + 1) * n] = -x
            upper_row[2 * mm * n + i] = -1.0
            rows.append(upper_row)
            rhs.append(-(values[s, i] + sig[i]))
            lower_row = np.zeros(nvar)  # A_l x + e_l <= q - sigma
            lower_row[mm * n + i * n : mm * n + (i + 1) * n] = x
            lower_row[2 * mm * n + mm + i] = 1.0
            rows.append(lower_row)
            rhs.append(values[s, i] - sig[i])
            gap = np.zeros(nvar)  # (A_u - A_l) x + e_u - e_l - theta <= 2 sigma
            gap[i * n : (i + 1) * n] = x
            gap[mm * n + i * n : mm * n + (i + 1) * n] = -x
            gap[2 * mm * n + i] = 1.0
            gap[2 * mm * n + mm + i] = -1.0
            gap[-1] = -1.0
            rows.append(gap)
            rhs.append(2.0 * sig[i])
    cost = np.zeros(nvar)
    cost[-1] = 1.0
    result = linprog(
        cost, A_ub=np.array(rows), b_ub=np.array(rhs), bounds=[(None, None)] * nvar, method="highs", options=LP_OPTIONS
    )
    if result.status != 0 or result.x is None:
        raise DesignError(f"affine_abstraction: HiGHS returned status {result.status} ({result.message})")
    z = result.x
    a_up = z[: mm * n].reshape(mm, n)
    a_lo = z[mm * n : 2 * mm * n].reshape(mm, n)
    # Offsets recomputed from the vertex values: exact vertex constraints, independent of LP tolerances.
    e_up = np.max(values - vertices @ a_up.T, axis=0) + sig
    e_lo = np.min(values - vertices @ a_lo.T, axis=0) - sig
    scale = np.max(np.abs(values), axis=0) + (np.abs(a_lo) + np.abs(a_up)) @ np.max(np.abs(vertices), axis=0)
    e_lo, e_up = inflate(e_lo, e_up, scale=scale)
    return AffineAbstraction(a_lo, a_up, e_lo, e_up, float(result.fun), sig, box, str(result.message))


def corollary1_bounds(
    decomposition: tuple[ArrayLike, ArrayLike], abstraction: tuple[ArrayLike, ArrayLike]
) -> tuple[FloatArray, FloatArray]:
    r"""The intersection of the decomposition and the affine bounds.

    :math:`\underline q = \max(q_d(\underline x,\overline x), \hat{\underline q})`, same for the upper.

    Parameters
    ----------
    decomposition : tuple of array_like
        Decomposition-function bounds (lower, upper).
    abstraction : tuple of array_like
        Affine-abstraction range bounds (lower, upper), e.g. :meth:`AffineAbstraction.range_bounds`.

    Returns
    -------
    lower, upper : numpy.ndarray

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): Corollary 1.
    """
    return (
        np.maximum(np.asarray(decomposition[0], dtype=float), np.asarray(abstraction[0], dtype=float)),
        np.minimum(np.asarray(decomposition[1], dtype=float), np.asarray(abstraction[1], dtype=float)),
    )
