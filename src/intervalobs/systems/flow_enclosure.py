r"""Validated enclosure of a nonlinear flow over one sampling interval (no ODE solver in any bound).

The object propagated is a *zonotope* of the augmented state :math:`z = (x, \theta)` (parameters as
states that do not move, :meth:`ContinuousNonlinearSystem.augmented_field`),

.. math:: \mathcal Z = \{c + G\xi : \xi \in [-1, 1]^m\},\quad c \in \mathbb{R}^N,\ G \in \mathbb{R}^{N\times m},

which, like the parallelepiped of Lohner's method (Lohner 1987) and with Kühn's zonotopes (Kühn
1998) against its wrapping, keeps the dependence between the states and the parameters that a box
would lose. One step of length :math:`\tau` maps it to a zonotope containing :math:`z(\tau)` for every
:math:`z(0) \in \mathcal Z` and every measurable :math:`w(\cdot)` with values in :math:`[w]`. With
:math:`F(Z) = \tilde f(Z) + E[w]` the interval extension of the right-hand side (outward rounded):

1. **A priori enclosure** (Picard–Lindelöf; Nedialkov, Jackson & Corliss 1999, Section 3). Let
   :math:`\mathcal D` be the state domain, which the model states that trajectories never leave.
   If a box :math:`\tilde Z` satisfies
   :math:`[\mathcal Z] + [0, \tau] F(\tilde Z \cap \mathcal D) \subset \operatorname{int}\tilde Z`,
   every trajectory from :math:`\mathcal Z` stays in :math:`\tilde Z` on :math:`[0, \tau]`: while it
   does, :math:`z(s) - z(0)` is :math:`s` times an average of values of
   :math:`F(\tilde Z \cap \mathcal D)` (convexity), so :math:`z(s)` lies in the interior of
   :math:`\tilde Z` and, by continuity, cannot reach its boundary first. Then
   :math:`z(s) \in ([\mathcal Z] + [0,\tau]F(\tilde Z \cap \mathcal D)) \cap \mathcal D`, the tighter
   box returned. :math:`\tilde Z` is found by epsilon-inflation of the motion
   :math:`[0,\tau]F` (not of the set, whose size is irrelevant here); when it is not found the step
   is halved.
2. **The trajectory of the centre.** Let :math:`\hat z` start at :math:`c` with the same
   :math:`w(\cdot)`, and :math:`\hat Z` its a priori box (computed without the domain: the centre
   may lie outside it). Since
   :math:`\tilde f(\hat z(s)) - \tilde f(c) = J(s)(\hat z(s) - c)` with :math:`J(s) \in [J_{\hat Z}]`
   (the interval Jacobian over :math:`\hat Z`, :mod:`intervalobs.interval_dual`; the mean-value
   theorem row by row) and :math:`\hat z(s) - c \in s\,F(\hat Z)` (convexity),

   .. math:: \hat z(\tau) \in c + \tau F(c) + \tfrac{\tau^2}{2}\,[J_{\hat Z}]\,F(\hat Z)

   (:math:`\int_0^\tau s\,q(s)\,ds \in \tfrac{\tau^2}{2}Q` for :math:`q(s) \in Q` convex).
3. **The spread around it** (a first-order Taylor model of the variational equation). The difference
   :math:`\delta = z - \hat z` of two trajectories with the same :math:`w` obeys
   :math:`\dot\delta = J(s)\delta` with :math:`J(s) \in [J] = J(\tilde Z \cup \hat Z)` (the Jacobian
   over the hull of both a priori boxes, which contain the two trajectories): the disturbance
   cancels. So :math:`\delta(\tau) = \Phi(\tau)\delta(0)`, with
   :math:`\Phi = I + \int J\Phi`. Grönwall bounds :math:`\Phi(s)` on :math:`[0, \tau]` by a box
   :math:`\tilde\Phi` (:func:`_fundamental_a_priori`, which treats the state and parameter columns
   separately so that the parameters' units do not enter the state's bound), and substituting
   :math:`\Phi(s) - I = \int_0^s J\Phi \in s[J]\tilde\Phi` once more,

   .. math:: \Phi(\tau) \in [\Phi] = I + \tau[J] + \tfrac{\tau^2}{2}[J]\big([J]\tilde\Phi\big).

4. **Back to a zonotope.** With :math:`x(0) = c + G\xi`,
   :math:`z(\tau) \in [\hat z(\tau)] + [\Phi]G\xi`; with :math:`M = \mathrm{mid}[\Phi]` the new
   generators are :math:`G' = \mathrm{fl}(MG)` and everything else — :math:`[\hat z(\tau)]`,
   :math:`([\Phi] - M)[G\xi]`, :math:`(MG - G')\xi` — is a box :math:`[e]`, whose centre is the new
   centre and whose radii are new generators (one per coordinate). The generators beyond
   ``order`` are reduced: ``reduction="box"`` (Combastel 2003: the smallest replaced by the box of their hull,
   :func:`intervalobs.zonotope.reduce_order`, rounded upward) or ``"frame"`` (the smallest boxed in the frame that
   the flow carried from the previous reduction, :func:`_reduce_in_frame`: less wrapping under a rotating flow).

Every interval operation is outward rounded (:class:`~intervalobs.interval.Interval`); the
floating-point :math:`G'` and :math:`c'` need no rounding because whatever they miss is in
:math:`[e]`. The width added per step is of second order in the set's size and in :math:`\tau`, so the
bound converges to the true reachable set as the set and the step shrink.

**References.**

* R. J. Lohner, "Enclosing the solutions of ordinary initial and boundary value problems", in
  E. Kaucher, U. Kulisch, C. Ullrich (eds.), *Computer Arithmetic: Scientific Computation and
  Programming Languages*, Teubner, 1987, pp. 255-286.
* N. S. Nedialkov, K. R. Jackson, G. F. Corliss, "Validated solutions of initial value problems
  for ordinary differential equations", *Applied Mathematics and Computation* 105(1):21-68, 1999.
  DOI: 10.1016/S0096-3003(98)10083-8 (the VNODE survey).
* W. Kühn, "Rigorously computed orbits of dynamical systems without the wrapping effect",
  *Computing* 61(1):47-67, 1998.
* C. Combastel, "A state bounding observer based on zonotopes", *European Control Conference*,
  2003.
* T. Kapela, M. Mrozek, D. Wilczak, P. Zgliczyński, "CAPD::DynSys: a flexible C++ toolbox for
  rigorous numerical analysis of dynamical systems", *Communications in Nonlinear Science and
  Numerical Simulation* 101:105578, 2021.
* J. Alexandre dit Sandretto, A. Chapoutot, "Validated explicit and implicit Runge-Kutta
  methods", *Reliable Computing* 22:79-103, 2016 (the DynIbex library).

(DOIs are given where they were checked.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ArgumentError, AssumptionError, BoundsError
from ..inclusion import VectorFunction, interval_function
from ..interval import Interval
from ..interval_dual import value_and_jacobian
from ..zonotope import reduce_order
from .bounds import Bounds
from .continuous_nonlinear import ContinuousNonlinearSystem
from .field_tape import FieldTape, kernel_batch

__all__ = [
    "REDUCTIONS",
    "FlowEnclosure",
    "StateZonotope",
    "a_priori",
    "flow_enclosure",
    "interval_product",
    "propagate",
]

_EPS = float(np.finfo(float).eps)

FloatArray = NDArray[np.float64]

ORDER_FACTOR = 4
"""Default number of generators kept, per dimension of the augmented state."""
MAX_HALVINGS = 12
"""A step is halved at most this many times before the a priori enclosure is declared lost."""
_PICARD_ITERATIONS = 6
_INFLATION = 0.5
_LOST = (
    "no validated enclosure of the flow: the set of states is too large for the vector field to stay bounded on it "
    "over one step (narrow the initial box or shorten h)"
)


@dataclass
class StateZonotope:
    r"""The zonotope :math:`\{c + G\xi : \xi \in [-1, 1]^m\}` of augmented states (leading axes of runs allowed).

    Parameters
    ----------
    centre : numpy.ndarray, shape (..., N)
    generators : numpy.ndarray, shape (..., N, m)
    """

    centre: FloatArray
    generators: FloatArray

    @classmethod
    def from_box(cls, lower: ArrayLike, upper: ArrayLike, order: int | None = None) -> StateZonotope:
        """The box ``[lower, upper]`` as a zonotope (centre, diagonal generators of the radii, rounded up).

        Parameters
        ----------
        lower, upper : array_like, shape (..., N)
            Finite ends.
        order : int, optional
            Number of generator columns (zero columns appended; default N).

        Returns
        -------
        StateZonotope
        """
        lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        centre = 0.5 * (lo + hi)
        radius = np.where(hi > lo, np.nextafter(np.maximum(hi - centre, centre - lo), np.inf), 0.0)
        diagonal = radius[..., :, None] * np.eye(lo.shape[-1])
        return cls(centre, diagonal if order is None else _reduce(diagonal, order))

    def box(self) -> Interval:
        r"""The interval hull :math:`c \pm |G|\mathbf 1` (outward rounded).

        Returns
        -------
        Interval, shape (..., N)
        """
        return hull_box(self.centre, self.generators)

    def with_box(self, extra: Interval, order: int, reduction: str = "box", persistent: int = 0) -> StateZonotope:
        """The sum with a box (its centre moves the centre, its radii are new generators), ``order`` generators.

        Parameters
        ----------
        extra : Interval, shape (..., N)
            Box added (Minkowski sum).
        order : int
            Most generators kept (at least N + ``persistent``).
        reduction : {"box", "frame"}
            How the generators beyond ``order`` are reduced (:data:`REDUCTIONS`).
        persistent : int
            Leading generator columns never reduced (their symbols keep their meaning from step to step).

        Returns
        -------
        StateZonotope
        """
        shifted = extra + self.centre
        centre = shifted.centre
        radius = np.nextafter(np.maximum(shifted.upper - centre, centre - shifted.lower), np.inf)
        size = centre.shape[-1]
        generators = np.concatenate([self.generators, radius[..., :, None] * np.eye(size)], axis=-1)
        kept, rest = generators[..., :persistent], generators[..., persistent:]
        return StateZonotope(centre, np.concatenate([kept, _reduce(rest, order - persistent, reduction)], axis=-1))


_GAMMA_PAD = float(np.finfo(float).eps)
"""Machine epsilon :math:`\\varepsilon = 2u`: a row of m terms is padded by :math:`(m + 2)\\varepsilon` of its
magnitude, the dot-product bound of ``Interval.__matmul__``."""
_TINY = float(np.finfo(float).tiny)


def hull_box(centre: FloatArray, generators: FloatArray) -> Interval:
    r"""The interval hull :math:`c \pm |G|\mathbf 1`, outward rounded: ``G @ [-1, 1] + c`` without the products.

    The terms of :math:`G[-1, 1]^m` are :math:`\pm|G_{ij}|` exactly, so ``Interval.__matmul__``'s bound reduces to
    the row sum :math:`s` of :math:`|G|` padded by :math:`\gamma s` + the smallest normal number
    (:math:`\gamma = 2(m + 2)u`) and rounded outward; then the centre is added (rounded outward). Bit for bit the
    same ends as the product form.

    Parameters
    ----------
    centre : numpy.ndarray, shape (..., N)
    generators : numpy.ndarray, shape (..., N, m)

    Returns
    -------
    Interval, shape (..., N)
    """
    spread = _unit_cube_image(np.abs(generators))
    return Interval._raw(np.nextafter(spread.lower + centre, -np.inf), np.nextafter(spread.upper + centre, np.inf))


def _unit_cube_image(magnitude: FloatArray) -> Interval:
    r"""``Interval(M_lo, M_hi) @ [-1, 1]^m`` for a matrix whose entries' largest magnitudes are ``magnitude``.

    Each term's hull is :math:`\pm\max(|a|, |b|)` exactly, so the product form's ends are the row sums padded by
    its dot-product bound and rounded outward; computed here without forming the products (same ends).
    """
    total = magnitude.sum(axis=-1)
    gamma = (magnitude.shape[-1] + 2) * _GAMMA_PAD
    reach = total + (gamma * total + _TINY)
    return Interval._raw(np.nextafter(-reach, -np.inf), np.nextafter(reach, np.inf))


def _reduce(generators: FloatArray, order: int, reduction: str = "box") -> FloatArray:
    """Exactly ``order`` generators: :func:`reduce_order` with its box rounded upward (``reduction="box"``) or
    :func:`_reduce_in_frame` (``"frame"``), or zero columns appended.

    A sum of ``m`` nonnegative terms is within ``m`` ulps of its value, so the box is widened by that.
    A fixed count keeps the sets of all runs and parts one array.
    """
    count = generators.shape[-1]
    if count <= order:
        pad = np.zeros((*generators.shape[:-1], order - count))
        return np.concatenate([generators, pad], axis=-1)
    if reduction == "frame":
        return _reduce_in_frame(generators, order)
    reduced = reduce_order(generators, order)
    size = generators.shape[-2]
    idx = np.arange(size)
    box = reduced[..., idx, order - size + idx]
    reduced[..., idx, order - size + idx] = np.nextafter(box * (1.0 + 2 * count * _EPS), np.inf)
    return reduced


REDUCTIONS = ("box", "frame")
"""The reductions of :class:`StateZonotope`: ``"box"`` (Combastel's, :func:`intervalobs.zonotope.reduce_order`) and
``"frame"`` (the small generators boxed in a frame carried by the flow, :func:`_reduce_in_frame`)."""
_FRAME_BITS = 26
"""Significant bits of the frame's entries and of the box's radii: their products (at most 53 bits) are exact."""
_FRAME_ACCEPT = 0.25
"""A candidate joins the frame when at least this fraction of its norm is orthogonal to the frame so far."""
_FRAME_RESIDUAL = 0.25
"""Largest verified :math:`\\|I - QP\\|_\\infty` (:math:`Q` the floating inverse of the frame) for which it is used."""
_FRAME_FLOOR = 2.0**-500
"""Smallest radius of a frame direction (no product with a frame entry of at least ``_FRAME_TINY`` underflows)."""
_FRAME_TINY = 2.0**-60
"""Frame entries below this magnitude are set to zero (the frame stays exactly representable)."""


def _round_bits(values: FloatArray, up: bool) -> FloatArray:
    """Values with ``_FRAME_BITS`` significant bits: to nearest (``up`` False) or upward (nonnegative ``values``)."""
    mantissa, exponent = np.frexp(values)
    scaled = mantissa * 2.0**_FRAME_BITS  # exact: a power of two
    rounded = np.ceil(scaled) if up else np.floor(scaled + 0.5)
    return np.ldexp(rounded * 2.0**-_FRAME_BITS, exponent)


def _frame(leading: FloatArray) -> FloatArray:
    r"""A frame (unit columns) of the candidates ``leading`` taken in turn, then of the unit axes.

    A candidate joins when at least ``_FRAME_ACCEPT`` of its norm is orthogonal to the frame so far (Gram-Schmidt
    twice against the accepted ones, for the test only: the frame holds the candidate itself, normalised, as
    Lohner's parallelepiped and Kühn's zonotope reduction do); an axis needs only :math:`\min(1/4, 1/(2\sqrt N))`,
    so the frame is always completed. Rounded to ``_FRAME_BITS`` bits, entries below ``_FRAME_TINY`` zeroed.
    """
    batch, size, _ = leading.shape
    basis = np.zeros((batch, size, size))
    frame = np.zeros((batch, size, size))
    found = np.zeros(batch, dtype=np.intp)
    candidates = np.concatenate([leading, np.broadcast_to(np.eye(size), (batch, size, size))], -1)
    rows = np.arange(batch)
    for j in range(candidates.shape[-1]):
        if np.all(found == size):
            break
        vector = candidates[..., j]
        residual = vector
        for _ in range(2):  # classical Gram-Schmidt twice against the accepted ones (zero columns beyond)
            residual = residual - (basis @ (np.swapaxes(basis, -1, -2) @ residual[..., None]))[..., 0]
        norm = np.sqrt(np.sum(residual * residual, axis=-1))
        length = np.sqrt(np.sum(vector * vector, axis=-1))
        share = _FRAME_ACCEPT if j < candidates.shape[-1] - size else min(_FRAME_ACCEPT, 0.5 / np.sqrt(size))
        take = (found < size) & (norm > share * length)
        slot = np.minimum(found, size - 1)[take]
        basis[rows[take], :, slot] = (residual / np.where(take, norm, 1.0)[:, None])[take]
        frame[rows[take], :, slot] = (vector / np.where(take, length, 1.0)[:, None])[take]
        found += take
    frame = _round_bits(frame, up=False)
    return np.where(np.abs(frame) < _FRAME_TINY, 0.0, frame)


def _reduce_in_frame(generators: FloatArray, order: int) -> FloatArray:
    r"""``order`` generators: the ``order - N`` largest, then the small ones boxed in a frame carried by the flow.

    The small generators :math:`G_s` are replaced by :math:`P\,\mathrm{diag}(d)` with :math:`d \ge |P^{-1}G_s|\mathbf 1`
    (the box of :math:`P^{-1}G_s\xi` in the frame's coordinates; Combastel's reduction is the case :math:`P = I`), so
    :math:`G_s\xi = P(P^{-1}G_s\xi) \in \{P\,\mathrm{diag}(d)\eta : |\eta| \le 1\}` and the reduced zonotope contains
    the original. The frame's candidates are, in turn, the columns ``order - N`` to ``order`` of ``generators`` (the
    box of the previous reduction, as the flow step and the strip update leave them: the set's first ``order``
    columns come first), largest first, then the ``2N`` largest generators, then the axes (:func:`_frame`). A box
    carried by the flow is thus boxed again in its own turned and sheared frame (Lohner's parallelepiped, Kühn's
    zonotopes), instead of in the axes, where a rotating flow makes each step's box wrap the previous one.

    **Soundness.** :math:`d` is an upper bound proved in floating point. With :math:`Q` a floating inverse of
    :math:`P` and :math:`R = I - QP`, :math:`P x = g` gives :math:`x = Qg + Rx`; if :math:`\|R\|_\infty \le \beta < 1`,
    then :math:`\|x\|_\infty \le \|Qg\|_\infty / (1 - \beta)` and :math:`|x| \le |Qg| + |R|\mathbf 1\,\|x\|_\infty`.
    Summed over the small generators,

    .. math:: |P^{-1}G_s|\mathbf 1 \le \sum_j \overline{|Qg_j|} + \overline{|R|}\mathbf 1
              \frac{\sum_j \|\overline{|Qg_j|}\|_\infty}{1 - \beta},

    where :math:`\overline{|Qg_j|} = |\mathrm{fl}(Qg_j)| + \gamma|Q||g_j| + \eta` and :math:`\overline{|R|}` likewise
    bound the products' rounding (:math:`\gamma = (N + 2)\varepsilon`, :math:`\eta` the smallest normal number, the
    bound of ``Interval.__matmul__``), and every sum, product and quotient of these nonnegative bounds is rounded
    upward; no property of :math:`Q` is assumed. :math:`P`'s entries carry ``_FRAME_BITS`` significant bits and
    :math:`d` is rounded upward to as many, so :math:`P\,\mathrm{diag}(d)` is computed exactly (:math:`d \ge`
    ``_FRAME_FLOOR``, entries of :math:`P` at most 1 and not below ``_FRAME_TINY``: no product underflows or
    overflows). Where :math:`\beta` exceeds ``_FRAME_RESIDUAL`` (an ill-conditioned frame) or a bound is not finite,
    the set falls back to Combastel's axis box (always sound).

    References
    ----------
    R. J. Lohner, "Enclosing the solutions of ordinary initial and boundary value problems", 1987.
    W. Kühn, "Rigorously computed orbits of dynamical systems without the wrapping effect", *Computing*
    61(1):47-67, 1998. X. Yang, J. K. Scott, "A comparison of zonotope order reduction techniques", *Automatica*
    95:378-384, 2018.
    """
    lead, (size, count) = generators.shape[:-2], generators.shape[-2:]
    flat = generators.reshape(-1, size, count)
    keep = order - size
    norms = np.sqrt(np.sum(flat * flat, axis=-2))
    ranked = np.argsort(-norms, axis=-1, kind="stable")
    ordered = np.take_along_axis(flat, ranked[:, None, :], axis=-1)
    turn = np.argsort(-norms[:, order - size : order], axis=-1, kind="stable")
    carried = np.take_along_axis(flat[..., order - size : order], turn[:, None, :], axis=-1)
    frame = _frame(np.concatenate([carried, ordered[..., : 2 * size]], axis=-1))
    try:  # nonsingular: each column has a quarter of its norm off the others' span (unless the data are not finite)
        inverse = np.linalg.inv(frame)
    except np.linalg.LinAlgError:
        inverse = np.full_like(frame, np.nan)  # every set of the batch falls back to the axis box
    small = ordered[..., keep:]
    gamma = (size + 2) * _EPS
    image = np.nextafter(np.abs(inverse @ small) + (gamma * (np.abs(inverse) @ np.abs(small)) + _TINY), np.inf)
    spread = small.shape[-1] * 2 * _EPS
    total = np.nextafter(image.sum(-1) * (1.0 + spread), np.inf)
    reach = np.nextafter(image.max(-2).sum(-1) * (1.0 + spread), np.inf)
    loss = np.nextafter(np.abs(np.eye(size) - inverse @ frame), np.inf)
    loss = np.nextafter((loss + (gamma * (np.abs(inverse) @ np.abs(frame)) + _TINY)) * (1.0 + 2 * _EPS), np.inf)
    rows = np.nextafter(loss.sum(-1) * (1.0 + 2 * size * _EPS), np.inf)
    beta = rows.max(-1)
    factor = np.nextafter(1.0 / np.nextafter(1.0 - np.minimum(beta, 0.5), -np.inf), np.inf)
    scaled = np.nextafter(reach * factor, np.inf)
    radius = np.nextafter(total + np.nextafter(rows * scaled[:, None], np.inf), np.inf)
    radius = _round_bits(np.maximum(radius, _FRAME_FLOOR), up=True)
    usable = (beta <= _FRAME_RESIDUAL) & np.all(np.isfinite(radius), axis=-1)
    box = np.nextafter(np.abs(small).sum(-1) * (1.0 + 2 * count * _EPS), np.inf)
    reduced = np.where(usable[:, None, None], frame * radius[:, None, :], box[:, :, None] * np.eye(size))
    return np.concatenate([ordered[..., :keep], reduced], axis=-1).reshape(*lead, size, order)


def interval_product(a: Interval, b: Interval) -> Interval:
    """The interval product of matrices ``(..., m, k)`` and ``(..., k, n)`` (outward rounded).

    Parameters
    ----------
    a, b : Interval
        Interval (or, wrapped, point) matrices.

    Returns
    -------
    Interval, shape (..., m, n)
    """
    cols = Interval._raw(np.swapaxes(b.lower, -1, -2), np.swapaxes(b.upper, -1, -2))
    rows = Interval._raw(a.lower[..., None, :, :], a.upper[..., None, :, :]) @ cols
    return Interval._raw(np.swapaxes(rows.lower, -1, -2), np.swapaxes(rows.upper, -1, -2))


def _disturbance_box(system: ContinuousNonlinearSystem, w: Interval) -> Interval | None:
    """:math:`E[w]` on the augmented state (zero on the parameters); None without a disturbance."""
    if system.nw == 0:
        return None
    disturbance = system.E @ w
    pad = np.zeros(system.n_params)
    return Interval._raw(np.concatenate([disturbance.lower, pad]), np.concatenate([disturbance.upper, pad]))


def _right_side(field: VectorFunction, disturbance: Interval | None, box: Interval) -> Interval:
    """:math:`F(Z) = \\tilde f(Z) + E[w]` on the augmented state; non-finite ends where undefined."""
    try:
        lo, hi = interval_function(field, box.lower, box.upper)
    except (BoundsError, ZeroDivisionError, FloatingPointError):
        inf = np.full(box.shape, np.inf)
        return Interval._raw(-inf, inf)
    rates = Interval._raw(lo, hi)
    return rates if disturbance is None else rates + disturbance


def _within(box: Interval, low: FloatArray, high: FloatArray) -> Interval:
    """The box intersected with the state domain (kept non-empty: a set outside it is left as it is)."""
    lower, upper = np.maximum(box.lower, low), np.minimum(box.upper, high)
    inside = lower <= upper
    return Interval._raw(np.where(inside, lower, box.lower), np.where(inside, upper, box.upper))


def a_priori(
    system: ContinuousNonlinearSystem, u: FloatArray, w: Interval, start: Interval, tau: float, domain: bool = True
) -> Interval | None:
    """A box containing every trajectory from ``start`` on ``[0, tau]`` (step 1 of the module), or None.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
    u : numpy.ndarray, shape (..., m)
        Held input.
    w : Interval, shape (nw,)
        Disturbance box.
    start : Interval, shape (..., N)
        Box of the augmented state at the start.
    tau : float
        Step length.
    domain : bool
        Use the state domain (for the true trajectories, which never leave it); False for the
        trajectory of the set's centre, which may start outside it.

    Returns
    -------
    Interval or None
        None when epsilon-inflation found no box (the caller halves the step).
    """
    free = np.full(system.n, np.inf)
    low = np.concatenate([system.domain[0] if domain else -free, np.full(system.n_params, -np.inf)])
    high = np.concatenate([system.domain[1] if domain else free, np.full(system.n_params, np.inf)])
    field, disturbance = system.augmented_field(u), _disturbance_box(system, w)
    return _picard(lambda box: _right_side(field, disturbance, box), start, tau, low, high)


def _picard(rates: Callable[[Interval], Interval], start: Interval, tau: float, low: Any, high: Any) -> Interval | None:
    """Step 1 of the module for boxes ``start`` with domains ``[low, high]`` (broadcast); None if not found.

    ``rates`` is :math:`F`: the box of the right-hand side over a box (non-finite ends where it is undefined).
    """
    span = Interval._raw(np.zeros(()), np.asarray(tau, dtype=float))
    guess = start + span * rates(start)
    for _ in range(_PICARD_ITERATIONS):
        if not (np.all(np.isfinite(guess.lower)) and np.all(np.isfinite(guess.upper))):
            return None
        motion = np.maximum(guess.upper - start.upper, start.lower - guess.lower)
        pad = _INFLATION * motion + 1e-12 * (1.0 + np.abs(guess.centre))
        candidate = Interval._raw(guess.lower - pad, guess.upper + pad)
        image = start + span * rates(_within(candidate, low, high))
        if np.all(image.lower > candidate.lower) and np.all(image.upper < candidate.upper):
            return _within(image, low, high)
        guess = image
    return None


def _stacked(*boxes: Interval) -> Interval:
    """Boxes of the same shape as one, along a new leading axis (one evaluation of a function for all)."""
    return Interval._raw(np.stack([b.lower for b in boxes]), np.stack([b.upper for b in boxes]))


@dataclass(frozen=True)
class _Flow:
    """What stays fixed over one call of :func:`propagate`: the field for the held input, :math:`E[w]`, domains.

    ``tape``: the field recorded (:mod:`intervalobs.systems.field_tape`), evaluated compiled with the same ends
    as ``field``; None evaluates ``field`` in Python.
    """

    field: VectorFunction
    disturbance: Interval | None
    low: FloatArray
    high: FloatArray
    n: int
    u: FloatArray
    compiled: bool = False
    tape: FieldTape | None = None
    reduction: str = "box"

    @classmethod
    def build(
        cls,
        system: ContinuousNonlinearSystem,
        u: FloatArray,
        w: Interval,
        ndim: int,
        compiled: tuple[bool, FieldTape | None] = (False, None),
        reduction: str = "box",
    ) -> _Flow:
        """The set's domain (row 0) and the centre's (row 1, none) for centres of ``ndim`` axes."""
        size = system.n + system.n_params
        free = np.full(system.n, np.inf)
        params = np.full(system.n_params, np.inf)
        low = np.stack([np.concatenate([system.domain[0], -params]), np.concatenate([-free, -params])])
        high = np.stack([np.concatenate([system.domain[1], params]), np.concatenate([free, params])])
        shape = (2,) + (1,) * (ndim - 1) + (size,)
        disturbance = _disturbance_box(system, w)
        field = system.augmented_field(u)
        return cls(field, disturbance, low.reshape(shape), high.reshape(shape), system.n, u, *compiled, reduction)

    def rates(self, box: Interval) -> Interval:
        """:math:`F(Z) = \\tilde f(Z) + E[w]` over boxes (:func:`_right_side`, by the tape where there is one)."""
        if self.tape is None:
            return _right_side(self.field, self.disturbance, box)
        try:
            rates = self.tape.evaluate(box.lower, box.upper, self.u)[0]
        except BoundsError:
            inf = np.full(box.shape, np.inf)
            return Interval._raw(-inf, inf)
        return rates if self.disturbance is None else rates + self.disturbance

    def value_and_jacobian(self, box: Interval) -> tuple[Interval, Interval]:
        """The boxes of the field and of its Jacobian over boxes (:func:`value_and_jacobian`, or the tape's)."""
        if self.tape is None:
            return value_and_jacobian(self.field, box.lower, box.upper, box.shape[-1])
        value, jacobian = self.tape.evaluate(box.lower, box.upper, self.u, derivative=True)
        assert jacobian is not None
        return value, jacobian


def _fundamental_a_priori(jac: Interval, n: int, tau: float) -> Interval:
    r"""A box of the fundamental matrix :math:`\Phi(s)`, :math:`s \in [0, \tau]` (step 3 of the module).

    The parameter rows of :math:`[J]` are zero, so :math:`\Phi = [[\Phi_{xx}, \Phi_{x\theta}], [0, I]]`.
    Grönwall on :math:`\dot\Phi_{xx} = J_{xx}\Phi_{xx}` gives :math:`\|\Phi_{xx} - I\|_\infty \le e^{\tau L} - 1`,
    :math:`L = \|\,|[J_{xx}]|\,\|_\infty`, and on :math:`\dot\phi_j = J_{xx}\phi_j + J_{x\theta_j}`,
    :math:`\phi_j(0) = 0` (a column of :math:`\Phi_{x\theta}`),
    :math:`\|\phi_j\|_\infty \le \|[J_{x\theta_j}]\|_\infty\,\tau e^{\tau L}`. One Picard sweep
    :math:`I + [0, \tau][J]\tilde\Phi`, intersected with the box, tightens it (both contain every
    :math:`\Phi(s)`).
    """
    size = jac.shape[-1]
    magnitude = np.maximum(-jac.lower, jac.upper)
    lipschitz = magnitude[..., :n, :n].sum(axis=-1).max(axis=-1)
    growth = np.nextafter(np.expm1(tau * lipschitz) * (1.0 + 1e-12), np.inf)
    radius = np.zeros(jac.shape)
    radius[..., :n, :n] = growth[..., None, None]
    columns = magnitude[..., :n, n:].max(axis=-2) * tau * (1.0 + growth[..., None]) * (1.0 + 1e-12)
    radius[..., :n, n:] = np.nextafter(columns, np.inf)[..., None, :]
    eye = np.eye(size)
    box = Interval._raw(eye - radius, eye + radius)
    span = Interval._raw(np.zeros(()), np.asarray(tau, dtype=float))
    sweep = span * interval_product(jac, box) + eye
    return Interval._raw(np.maximum(box.lower, sweep.lower), np.minimum(box.upper, sweep.upper))


def _step(
    flow: _Flow, zset: StateZonotope, tau: float, order: int, persistent: int = 0
) -> tuple[StateZonotope, Interval] | None:
    """Steps 1-4 of the module over ``[0, tau]``; None when an a priori enclosure is not found."""
    point = Interval._wrap(zset.centre)
    size = zset.centre.shape[-1]
    boxes = _picard(flow.rates, _stacked(zset.box(), point), tau, flow.low, flow.high)
    if boxes is None:  # the set's trajectories and its centre's, one batch (the centre ignores the domain)
        return None
    tilde, hat = boxes[0], boxes[1]
    both = Interval._raw(np.minimum(tilde.lower, hat.lower), np.maximum(tilde.upper, hat.upper))
    # one forward-mode pass: the Jacobians over both boxes and over the centre's, the rates over it and at the centre
    values, jacs = flow.value_and_jacobian(_stacked(both, hat, point))
    rates = values[1:] if flow.disturbance is None else values[1:] + flow.disturbance
    jac, jac_hat = jacs[0], jacs[1]
    half_square = 0.5 * tau * tau
    centre_end = point + rates[1] * tau + (jac_hat @ rates[0]) * half_square
    if flow.compiled:
        return _compiled_rest(flow, zset, (centre_end, jac), tau, (order, persistent)), tilde
    spread = _fundamental_a_priori(jac, flow.n, tau)
    phi = jac * tau + interval_product(jac, interval_product(jac, spread)) * half_square + np.eye(size)
    mid = phi.centre
    generators = mid @ zset.generators
    exact = interval_product(Interval._wrap(mid), Interval._wrap(zset.generators)) - generators
    spread_box = _unit_cube_image(np.abs(zset.generators))
    exact_box = _unit_cube_image(np.maximum(np.abs(exact.lower), np.abs(exact.upper)))
    error = centre_end - zset.centre + (phi - mid) @ spread_box + exact_box
    return StateZonotope(zset.centre, generators).with_box(error, order, flow.reduction, persistent), tilde


def _compiled_rest(
    flow: _Flow, zset: StateZonotope, boxes: tuple[Interval, Interval], tau: float, kept: tuple[int, int]
) -> StateZonotope:
    """Steps 3-4 by :func:`intervalobs.systems.flow_kernel.advance` (the same formulas compiled), all sets flattened;
    ``kept``: ``(order, persistent)``."""
    from . import flow_kernel  # Numba is imported only where a record is long enough to pay for it

    centre_end, jac = boxes
    order, persistent = kept
    lead, size = zset.centre.shape[:-1], zset.centre.shape[-1]
    vector, matrix = (size,), (size, size)
    centre, generators = flow_kernel.advance(
        kernel_batch(zset.centre, lead, vector),
        kernel_batch(zset.generators, lead, zset.generators.shape[-2:]),
        (kernel_batch(centre_end.lower, lead, vector), kernel_batch(centre_end.upper, lead, vector)),
        (kernel_batch(jac.lower, lead, matrix), kernel_batch(jac.upper, lead, matrix)),
        (float(tau), int(flow.n), int(order), int(persistent), int(flow.reduction == "frame")),
    )
    return StateZonotope(centre.reshape(*lead, size), generators.reshape(*lead, size, order))


def propagate(
    system: ContinuousNonlinearSystem,
    u: ArrayLike,
    w: Interval,
    zset: StateZonotope,
    h: float,
    substeps: int = 1,
    order: int | None = None,
    compiled: bool = False,
    *,
    tape: FieldTape | None = None,
    reduction: str = "box",
    persistent: int = 0,
    halvings: int = MAX_HALVINGS,
) -> tuple[StateZonotope, Interval]:
    """Carry a zonotope of augmented states over ``[0, h]`` (the module's steps, ``substeps`` of them).

    Parameters
    ----------
    system : ContinuousNonlinearSystem
    u : array_like, shape (..., m)
        Input held over the interval.
    w : Interval, shape (nw,)
        Disturbance box.
    zset : StateZonotope
        Set at the start.
    h : float
        Interval length.
    substeps : int
        Steps per interval (each halved again where an a priori enclosure is not found).
    order : int, optional
        Most generators kept (default ``ORDER_FACTOR`` times the augmented dimension).
    compiled : bool
        Do steps 3-4 in :mod:`intervalobs.systems.flow_kernel` (Numba; the same bounds up to the order of a few
        sums, several times faster on small sets); False keeps Numba unimported.
    tape : FieldTape, optional
        The system's field recorded (:func:`intervalobs.systems.field_tape.trace_field`): every evaluation of
        the field is the tape's compiled replay (the same ends), and with ``compiled`` every step is done in one
        call of :func:`intervalobs.systems.flow_kernel.propagate`; default: the field in Python.
    reduction : {"box", "frame"}
        How the generators beyond ``order`` are reduced after each step (:data:`REDUCTIONS`): in the axes
        (Combastel) or in the frame of the largest (:func:`_reduce_in_frame`, less wrapping under rotation).
    persistent : int
        Leading generator columns never reduced: the set stays :math:`c + G_p\\xi + G_r\\eta` with the *same*
        symbols :math:`\\xi` as at the start (step 4 maps :math:`G_p` by :math:`M` and puts all the rest in
        :math:`G_r`), so the states at several times are affine in one :math:`\\xi` up to a box each
        (:mod:`intervalobs.observers.set_inversion`). At most ``order`` minus the augmented dimension, and at most
        the start's generator columns.
    halvings : int
        Most halvings of a step where no a priori enclosure is found (then :class:`AssumptionError`).

    Returns
    -------
    StateZonotope
        Contains the augmented state at ``h`` for every start in ``zset``, every parameter and every
        measurable disturbance in its box.
    Interval
        Hull of the a priori boxes: contains every trajectory on ``[0, h]``.

    Raises
    ------
    ArgumentError
        ``persistent`` is negative, leaves fewer than N other generators in ``order`` or exceeds the start's columns.
    AssumptionError
        When no a priori enclosure is found even for steps ``2**halvings`` times shorter (the
        set is too large or the vector field blows up on it).
    """
    size = zset.centre.shape[-1]
    kept = ORDER_FACTOR * size + persistent if order is None else int(order)
    limit = min(kept - size, zset.generators.shape[-1])
    if not 0 <= persistent <= limit:
        raise ArgumentError(
            f"propagate: expected 0 <= persistent <= min(order - N, start's generators) = {limit}, got {persistent}"
        )
    flow = _Flow.build(system, np.asarray(u, dtype=float), w, zset.centre.ndim, (compiled, tape), reduction)
    if compiled and tape is not None:
        return _propagate_taped(flow, zset, (float(h), int(substeps)), (kept, int(persistent)))
    remaining, tau, halved = float(h), float(h) / substeps, 0
    hull: Interval | None = None
    while remaining > 0.0:
        tau = min(tau, remaining)
        result = _step(flow, zset, tau, kept, persistent)
        if result is None:
            halved += 1
            if halved > halvings:
                raise AssumptionError(_LOST)
            tau *= 0.5
            continue
        zset, tilde = result
        hull = (
            tilde
            if hull is None
            else Interval._raw(np.minimum(hull.lower, tilde.lower), np.maximum(hull.upper, tilde.upper))
        )
        remaining = 0.0 if tau >= remaining else remaining - tau
    assert hull is not None
    return zset, hull


def _propagate_taped(
    flow: _Flow, zset: StateZonotope, interval: tuple[float, int], kept: tuple[int, int]
) -> tuple[StateZonotope, Interval]:
    """:func:`propagate` in one call of :func:`intervalobs.systems.flow_kernel.propagate` (the field by its tape);
    ``kept``: ``(order, persistent)``."""
    from . import flow_kernel  # Numba is imported only where a record is long enough to pay for it

    assert flow.tape is not None
    order, persistent = kept
    lead, size = zset.centre.shape[:-1], zset.centre.shape[-1]
    sets = (
        kernel_batch(zset.centre, lead, (size,)),
        kernel_batch(zset.generators, lead, zset.generators.shape[-2:]),
        kernel_batch(flow.u, lead, flow.u.shape[-1:]),
    )
    no_box = flow.disturbance is None
    box = np.zeros((2, size)) if no_box else np.stack([flow.disturbance.lower, flow.disturbance.upper])  # type: ignore[union-attr]
    domain = np.stack([flow.low.reshape(2, size), flow.high.reshape(2, size)])
    centre, generators, hull, status = flow_kernel.propagate(
        flow.tape.arrays,
        sets,
        ((box, not no_box), domain),
        interval,
        (flow.n, order, persistent, int(flow.reduction == "frame")),
    )
    if status == 1:
        raise AssumptionError(_LOST)
    if status == 2:
        raise BoundsError(
            "the vector field's Jacobian is undefined on a box (a divisor containing 0, log or sqrt below 0)"
        )
    end = StateZonotope(centre.reshape(*lead, size), generators.reshape(*lead, size, order))
    return end, Interval._raw(hull[0].reshape(*lead, size), hull[1].reshape(*lead, size))


@dataclass(frozen=True)
class FlowEnclosure:
    """What :func:`flow_enclosure` proves about one sampling interval.

    Attributes
    ----------
    lower, upper : numpy.ndarray, shape (..., n)
        Box of :math:`x(t_0 + h)`.
    a_priori_lower, a_priori_upper : numpy.ndarray, shape (..., n)
        Box of :math:`x(t)` for every :math:`t \\in [t_0, t_0 + h]`.
    zonotope : StateZonotope
        The zonotope of augmented states :math:`(x, \\theta)` at :math:`t_0 + h`.
    """

    lower: FloatArray
    upper: FloatArray
    a_priori_lower: FloatArray
    a_priori_upper: FloatArray
    zonotope: StateZonotope


def flow_enclosure(
    system: ContinuousNonlinearSystem,
    bounds: Bounds,
    h: float,
    x_lower: ArrayLike | None = None,
    x_upper: ArrayLike | None = None,
    u: ArrayLike | None = None,
    substeps: int = 4,
) -> FlowEnclosure:
    """The sound box of :math:`x(t_0 + h)` for every :math:`x(t_0)` in a box, every parameter, every :math:`w(\\cdot)`.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
    bounds : Bounds
        The boxes ``w`` (disturbance), ``p`` (parameters) and, unless ``x_lower``/``x_upper`` are
        given, ``x0`` (the start box).
    h : float
        Interval length (> 0).
    x_lower, x_upper : array_like, shape (..., n), optional
        Start box (default: ``bounds.x0``).
    u : array_like, shape (..., m), optional
        Input held over the interval (default: zero; required when ``m > 0``).
    substeps : int
        Validated steps per interval.

    Returns
    -------
    FlowEnclosure

    Raises
    ------
    BoundsError
        ``h`` is not a positive number, or ``u`` is missing for a system with inputs.
    AssumptionError
        No validated enclosure exists at any step length (see :func:`propagate`).

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import Bounds, ContinuousNonlinearSystem
    >>> from intervalobs.systems import flow_enclosure
    >>> decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    >>> box = flow_enclosure(decay, Bounds(x0=(1.0, 1.0), p=(1.0, 1.0)), h=1.0)
    >>> bool(box.lower[0] <= np.exp(-1.0) <= box.upper[0]), float(box.upper[0] - box.lower[0]) < 1e-3
    (True, True)
    """
    if not (isinstance(h, (int, float)) and np.isfinite(h) and h > 0):
        raise BoundsError(f"h: expected a positive step length, got {h!r}")
    if u is None and system.m > 0:
        raise BoundsError(f"u: expected the held input (the system has m = {system.m}), got None")
    resolved = bounds.resolve(system)
    lo = np.asarray(resolved.x0[0] if x_lower is None else x_lower, dtype=float)
    hi = np.asarray(resolved.x0[1] if x_upper is None else x_upper, dtype=float)
    lead = lo.shape[:-1]
    p_lo = np.broadcast_to(resolved.p[0], (*lead, system.n_params))
    p_hi = np.broadcast_to(resolved.p[1], (*lead, system.n_params))
    start = np.concatenate([lo, p_lo], axis=-1), np.concatenate([hi, p_hi], axis=-1)
    zset = StateZonotope.from_box(*start, ORDER_FACTOR * (system.n + system.n_params))
    held = np.zeros((*lead, system.m)) if u is None else np.asarray(u, dtype=float)
    end, hull = propagate(system, held, Interval._raw(*resolved.w), zset, float(h), substeps)
    box = end.box()
    n = system.n
    return FlowEnclosure(box.lower[..., :n], box.upper[..., :n], hull.lower[..., :n], hull.upper[..., :n], end)
