r"""Design of the high-gain interval observer for width (the sampled-output high-gain paper, made to look at the bounds
it gives).

The paper chooses the LMI regions by hand and takes the least-norm gain that puts the eigenvalues of
:math:`A - L_1C` in them (Algorithm 1); nothing in that choice looks at the width of the bounds. Here
the gain is chosen by minimising a computable bound of the steady-state width, under the paper's
constraints, and the regions of Algorithm 1 are derived from the optimum.

**The bound.** In the modal coordinates of :mod:`intervalobs.observers.hgio`,
:math:`\zeta = \operatorname{diag}(e^{-i\omega_1t})v_1x` (eq. (13), (17) with θ cancelled), the
radii of the state-bound observer (Theorem 4.5) obey the linear recursion

.. math:: \zeta^r_{k+1} = e^{p_1h}\zeta^r_k
          + \phi_1\,(|\operatorname{Re}(e^{-i\omega_1t_k}v_1)| + |\omega_1|h|v_1|)\,g^r,
          \qquad x^r_k = |\operatorname{Re}B_k|\zeta^r_k + |\operatorname{Im}B_k|\zeta^i_k,

:math:`B_k = v_1^{-1}\operatorname{diag}(e^{i\omega_1t_k})`, with nonnegative coefficients, driven by the
radius :math:`g^r = \varphi^r + d^r + |L_1|y^r` of the input :math:`g = \varphi + d + L_1Cx` (φ over
the box, the disturbance, the output bound over a step). Run to its periodic steady state from
zero (:func:`scipy.signal.lfilter`, one first-order filter per mode) it gives the mean and the
largest steady width :math:`2x^r` of the observer's box whenever the input radii stay below the
given ones: the observer's own radii are never larger (same recursion, same or smaller input, and
its intersections only shrink them). It is a bound *for given input radii*: :math:`\varphi^r` is
known a priori for a bounded nonlinearity (:math:`e^{-|x|} \in (0, 1]` gives 0.5), the output radius
:math:`y^r` is a design value (default: the noise radius δ, which the sampled output bound hovers
around). Soundness of the observer never depends on it.

**The design.** :math:`\min_{L}\ w^T\,\overline{\text{width}}(L)` over the gain, subject to the paper's
constraints: every eigenvalue of :math:`A - LC` in every constraint region (half-planes, sectors,
strips, disks: :mod:`intervalobs.design.regions`), distinct (separation at least ``min_separation``)
and :math:`\operatorname{cond}(v_1)` at most ``max_condition`` (the C-diagonalisation (13) must be
well conditioned for the modal box to be useful). Nelder–Mead from pole-placed starts. Then each
optimal eigenvalue gets its own disk (disjoint, inside the constraint regions: distinct eigenvalues
by construction) and Algorithm 1 (Theorem 4.1, LMI (15)) places :math:`A - L_1C` in them; the
verified gain of Algorithm 1 is the result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize
from scipy.signal import lfilter, place_poles

from ..errors import DesignError
from ..validation import as_matrix, as_vector
from .regions import Disk, ModalDecomposition, Region, RegionPlacement, in_region, modal_decomposition, place_in_disks

__all__ = ["WidthBound", "WidthDesign", "design_for_width", "modal_width_bound"]

FloatArray = NDArray[np.float64]

_SETTLE_TIME_CONSTANTS = 12.0
_WINDOW_PERIODS = 6.0
_DISK_FRACTION = 0.3
_SHIFTS = (0.25, 0.5, 1.0, 2.0)
_IMAG_SCALES = (1.0, 1.3)
_SEARCHED_STARTS = 3
_SHRINKS = 3
_RING_POINTS = 64
_SEARCH_POINTS_INV = 1.0 / 100.0


@dataclass(frozen=True)
class WidthBound:
    """Steady-state width bound of the state-bound observer for given input radii (module docstring).

    Attributes
    ----------
    mean : numpy.ndarray, shape (n,)
        Time-averaged steady width :math:`2x^r` per state.
    sup : numpy.ndarray, shape (n,)
        Largest steady width per state.
    input_radius : numpy.ndarray, shape (n,)
        :math:`g^r = \\varphi^r + d^r + |L_1|y^r` used.
    window_s : float
        Length of the steady window averaged over (after ``settle_s``).
    settle_s : float
        Time after which the recursion started from zero is taken as steady.
    """

    mean: FloatArray
    sup: FloatArray
    input_radius: FloatArray
    window_s: float
    settle_s: float


def modal_width_bound(modal: ModalDecomposition, input_radius: ArrayLike, h: float) -> WidthBound:
    r"""Mean and largest steady width of the modal interval observer for the input radius :math:`g^r`.

    Parameters
    ----------
    modal : ModalDecomposition
        :math:`A - L_1C = v_1^{-1}\operatorname{diag}(p_1 + i\omega_1)v_1`.
    input_radius : array_like, shape (n,)
        :math:`g^r`, radius of :math:`\varphi + d + L_1Cx` over a step (nonnegative).
    h : float
        Grid step of the observer (its exact discretisation, :mod:`intervalobs.observers.hgio`).

    Returns
    -------
    WidthBound

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): eq. (13).
    """
    lam = modal.eigenvalues
    n = lam.size
    gr = as_vector("input_radius", input_radius, n)
    if np.any(gr < 0):
        raise DesignError(f"input_radius: expected nonnegative radii, got {gr}")
    p, w = lam.real, lam.imag
    settle = _SETTLE_TIME_CONSTANTS / float(np.min(-p))
    rotating = np.abs(w[w != 0])
    window = _WINDOW_PERIODS * 2 * np.pi / float(np.min(rotating)) if rotating.size else 1.0
    window = max(window, settle / 2)
    t = np.arange(0.0, settle + window, h)
    rot = np.exp(-1j * w[None, :] * t[:, None])
    rv = rot[:, :, None] * modal.v1[None, :, :]
    slack = (np.abs(w) * h)[:, None] * np.abs(modal.v1)
    phi1 = np.expm1(p * h) / p
    drive_re = phi1[None, :] * ((np.abs(rv.real) + slack[None]) @ gr)
    drive_im = phi1[None, :] * ((np.abs(rv.imag) + slack[None]) @ gr)
    eph = np.exp(p * h)
    # ζ^r_{k+1} = e^{ph} ζ^r_k + drive_k from ζ^r_0 = 0: the filter of the drive delayed by one step
    zr = np.column_stack([lfilter([0.0, 1.0], [1.0, -eph[j]], drive_re[:, j]) for j in range(n)])
    zi = np.column_stack([lfilter([0.0, 1.0], [1.0, -eph[j]], drive_im[:, j]) for j in range(n)])
    back = modal.v1_inv[None, :, :] * np.conj(rot)[:, None, :]
    xr = np.einsum("tij,tj->ti", np.abs(back.real), zr) + np.einsum("tij,tj->ti", np.abs(back.imag), zi)
    steady = xr[t >= settle]
    return WidthBound(2 * steady.mean(axis=0), 2 * steady.max(axis=0), gr, window, settle)


@dataclass(frozen=True)
class WidthDesign:
    """Result of :func:`design_for_width`.

    Attributes
    ----------
    L : numpy.ndarray, shape (n, p)
        Gain :math:`L_1` placed in ``disks`` (verified).
    bound : WidthBound
        Width bound of ``L``.
    placement : RegionPlacement
        the disk placement in the derived disks.
    disks : tuple of Disk
        One disjoint disk per optimal eigenvalue, inside every constraint region.
    regions : tuple
        The constraint regions every eigenvalue had to lie in.
    optimum_L : numpy.ndarray, shape (n, p)
        The gain the optimiser found (the disk placement reproduces it up to the LMI solver's accuracy).
    objective : float
        ``weights @ bound.mean`` at ``L``.
    weights : numpy.ndarray, shape (n,)
        Weights of the objective.
    output_radius : numpy.ndarray, shape (p,)
        :math:`y^r` used in the bound.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): Algorithm 1, Theorem 4.1, LMI (15).
    """

    L: FloatArray
    bound: WidthBound
    placement: RegionPlacement
    disks: tuple[Disk, ...]
    regions: tuple[Region, ...]
    optimum_L: FloatArray
    objective: float
    weights: FloatArray
    output_radius: FloatArray


def _starts(a: FloatArray, c: FloatArray) -> list[FloatArray]:
    """Pole-placed starting gains: the open-loop spectrum shifted left, imaginary parts scaled."""
    vals = np.linalg.eigvals(a)
    starts = []
    for shift in _SHIFTS:
        for scale in _IMAG_SCALES:
            poles = vals.real - shift * (1.0 + np.abs(vals.real)) + 1j * scale * vals.imag
            poles = poles + 1e-3 * np.arange(poles.size) * (poles.imag == 0)  # distinct real poles
            try:
                starts.append(place_poles(a.T, c.T, poles).gain_matrix.T)
            except (ValueError, np.linalg.LinAlgError):
                continue
    if np.max(vals.real) < 0:
        starts.append(np.zeros((a.shape[0], c.shape[0])))
    return starts


def _disks(vals: NDArray[np.complex128], regions: Sequence[Region], shrink: int) -> tuple[Disk, ...] | None:
    """One disk per eigenvalue, centred on it: disjoint, in the left half-plane, inside every region.

    The radius starts at ``_DISK_FRACTION`` of the distance to the nearest other eigenvalue and to the
    imaginary axis and is halved up to ``shrink`` times until the disk fits (None if it never does).
    """
    n = vals.size
    gaps = np.abs(vals[:, None] - vals[None, :]) + np.diag(np.full(n, np.inf))
    boundary = np.exp(2j * np.pi * np.arange(_RING_POINTS) / _RING_POINTS)
    disks = []
    for j, lam in enumerate(vals):
        radius = _DISK_FRACTION * min(float(np.min(gaps[j])) if n > 1 else np.inf, float(-lam.real))
        centre = complex(lam.real, 0.0) if lam.imag == 0 else complex(lam)
        for _ in range(shrink + 1):
            if all(np.all(in_region(r, centre + radius * boundary)) for r in regions):
                break
            radius /= 2
        else:
            return None
        disks.append(Disk(centre, radius))
    return tuple(disks)


def design_for_width(
    A: ArrayLike,
    C: ArrayLike,
    h: float,
    *,
    d_radius: ArrayLike,
    phi_radius: ArrayLike,
    output_radius: ArrayLike,
    weights: ArrayLike | None = None,
    regions: Sequence[Region] = (),
    max_condition: float = 100.0,
    min_separation: float = 0.05,
    max_iterations: int = 400,
) -> WidthDesign:
    r"""Gain and LMI regions of the HGIO that minimise the steady-state width bound (module docstring).

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix of the partially linear model.
    C : array_like, shape (p, n)
        Output matrix.
    h : float
        Grid step of the observer.
    d_radius : array_like, shape (n,)
        :math:`d^r`, the radius of the disturbance box.
    phi_radius : array_like, shape (n,)
        Radius of the range of φ over any box and the input over one step (e.g. 0.5 for
        :math:`e^{-|x|}`, plus :math:`|B_u|\dot u_{\max}h` for a known input term).
    output_radius : array_like, shape (p,)
        :math:`y^r`, radius of the output bound the state-bound observer receives (design value).
    weights : array_like, shape (n,), optional
        Weights of the mean widths in the objective (default all ones).
    regions : sequence of Disk, HalfPlane, VerticalStrip, HorizontalStrip, Sector
        Every eigenvalue of :math:`A - L_1C` must lie in all of them.
    max_condition : float
        Largest accepted :math:`\operatorname{cond}(v_1)`.
    min_separation : float
        Smallest accepted distance between two eigenvalues.
    max_iterations : int
        Nelder–Mead iterations per start.

    Returns
    -------
    WidthDesign

    Raises
    ------
    DesignError
        If no start is feasible or the disk placement fails in the derived disks.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): model (8), the disturbance radius of
    Assumption 3.1, Algorithm 1.
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    c = as_matrix("C", C, (None, n))
    p = c.shape[0]
    dr = as_vector("d_radius", d_radius, n)
    pr = as_vector("phi_radius", phi_radius, n)
    yr = as_vector("output_radius", output_radius, p)
    wts = np.ones(n) if weights is None else as_vector("weights", weights, n)
    objective = _WidthObjective(a, c, h, pr + dr, yr, wts, tuple(regions), max_condition, min_separation)
    optimum = _nelder_mead_search(objective, _starts(a, c), max_iterations)
    optimum_modal = objective.modal_of(optimum)
    assert optimum_modal is not None
    disks = _disks(optimum_modal.eigenvalues, objective.regions, _SHRINKS)
    assert disks is not None
    placement = place_in_disks(a, c, disks, objective="center")
    final = objective.modal_of(placement.L)
    if final is None:
        raise DesignError(
            "design_for_width: the gain placed in the derived disks violates the constraints "
            "(conditioning, separation or regions); verification failed"
        )
    bound = objective.bound_of(placement.L, final, h)
    return WidthDesign(
        L=placement.L,
        bound=bound,
        placement=placement,
        disks=disks,
        regions=objective.regions,
        optimum_L=optimum,
        objective=float(wts @ bound.mean),
        weights=wts,
        output_radius=yr,
    )


class _WidthObjective:
    """The weighted mean steady width bound of a gain, infinite where the gain breaks a constraint."""

    def __init__(
        self,
        a: FloatArray,
        c: FloatArray,
        h: float,
        model_radius: FloatArray,
        output_radius: FloatArray,
        weights: FloatArray,
        regions: tuple[Region, ...],
        max_condition: float,
        min_separation: float,
    ) -> None:
        self.a, self.c, self.h = a, c, h
        self.model_radius, self.output_radius, self.weights = model_radius, output_radius, weights
        self.regions, self.max_condition, self.min_separation = regions, max_condition, min_separation

    def modal_of(self, gain: FloatArray) -> ModalDecomposition | None:
        """The modal decomposition of ``A - L C``, or None if conditioning, separation or regions fail."""
        try:
            modal = modal_decomposition(self.a, self.c, gain)
        except DesignError:
            return None
        if modal.condition > self.max_condition or modal.separation < self.min_separation:
            return None
        if self.regions and _disks(modal.eigenvalues, self.regions, _SHRINKS) is None:
            return None  # every eigenvalue keeps room for its own disk inside the regions
        return modal

    def bound_of(self, gain: FloatArray, modal: ModalDecomposition, step: float) -> WidthBound:
        """The width bound of ``gain`` on a grid of ``step``."""
        return modal_width_bound(modal, self.model_radius + np.abs(gain) @ self.output_radius, step)

    def __call__(self, flat: FloatArray) -> float:
        gain = flat.reshape(self.c.shape[1], self.c.shape[0])
        modal = self.modal_of(gain)
        if modal is None:
            return np.inf
        # the search runs the recursion on a coarser grid (a few hundred points per time constant or
        # rotation period); the reported bound uses the observer's step
        fastest = float(np.max(np.abs(modal.eigenvalues)))
        return float(self.weights @ self.bound_of(gain, modal, max(self.h, _SEARCH_POINTS_INV / fastest)).mean)


def _nelder_mead_search(objective: _WidthObjective, starts: Sequence[FloatArray], max_iterations: int) -> FloatArray:
    """The best gain of Nelder–Mead runs from the ``_SEARCHED_STARTS`` best feasible starts."""
    n, p = objective.c.shape[1], objective.c.shape[0]
    scored = sorted(((objective(s.ravel()), k, s) for k, s in enumerate(starts)), key=lambda item: item[:2])
    best: tuple[float, FloatArray] | None = None
    for value, _, start in scored[:_SEARCHED_STARTS]:
        if not np.isfinite(value):
            continue
        simplex = start.ravel()[None, :] + np.vstack([np.zeros(n * p), np.diag(0.2 * (1.0 + np.abs(start.ravel())))])
        result = minimize(
            objective,
            start.ravel(),
            method="Nelder-Mead",
            options={"initial_simplex": simplex, "maxiter": max_iterations, "xatol": 1e-4, "fatol": 1e-5},
        )
        if np.isfinite(result.fun) and (best is None or result.fun < best[0]):
            best = (float(result.fun), np.asarray(result.x, dtype=float).reshape(n, p))
    if best is None:
        raise DesignError(
            "design_for_width: no pole-placed start satisfies the constraints (regions, max_condition, "
            "min_separation); relax them"
        )
    return best[1]
