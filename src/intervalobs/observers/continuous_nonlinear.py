r"""Guaranteed filtering of a continuous-time nonlinear system: validated prediction, contraction at samples.

The observer keeps a zonotope :math:`\{c + G\xi : |\xi| \le 1\}` of the augmented state
:math:`z = (x, \theta)` (:class:`~intervalobs.systems.flow_enclosure.StateZonotope`) that contains the
true state and parameters given :math:`y_0 \dots y_k`. Between samples it is carried by the validated
flow enclosure (:func:`~intervalobs.systems.flow_enclosure.propagate`: every admissible start,
parameter and measurable disturbance); at each sample it is *contracted* by strips:

* **measurement** :math:`y_{k,i} - v_{k,i} = g_i(x)`: by the mean-value form
  :math:`g(x) \in g(c) + [J_g(\bar X)](x - c)` over the set's hull :math:`\bar X`, each output gives a
  strip :math:`a^\top z \in [s]` with :math:`a = \mathrm{mid}[J_g]_i` and the rest of the interval
  row in :math:`[s]`; the zonotope is replaced by one containing its intersection with the strip
  (Alamo, Bravo & Camacho 2005), with the gain chosen coordinate by coordinate so that no hull
  widens (:func:`_strip_update`);
* **state domain and parameter box**: each finite end is a strip on one coordinate, used the same way
  where it cuts the set.

A wide prior is *split* into parts (``splits``), one zonotope each, so that the validated step, whose
loss grows with the square of the set's size, stays accurate; a part the data contradict is dropped.
With ``refine`` the parts form a *bundle*: whenever the data have dropped half of them, the live ones are
bisected, so the parts gather where the states and parameters are still consistent with the record.
Moisan, Bernard & Gouzé (2009) run several observers of the same set and intersect them; here the
parts partition the set and the report is the hull of their union. A strip whose cut is shallow changes no coordinate's
hull, so one zonotope does not learn a parameter from many such cuts (a chemostat's μmax and Ks keep
their whole box); the bundle learns them by dropping the parts that a cut misses entirely.
Rows are *filtered*: row :math:`k` bounds :math:`x(t_k)` given :math:`y_0 \dots y_k` (the hull of
the live parts). When every part is contradicted the record contradicts the model (or its boxes):
the run's bounds stay as they were up to that sample, the rows after it are ``[-inf, inf]``, and
``meta["consistent"]`` is False with ``meta["inconsistent_from"]`` the first such sample time;
nothing is raised. A part whose validated step cannot be found any more makes its run's bounds
infinite from then on; that, and widths that end above ``divergence_factor`` times the prior's,
warn (``RuntimeWarning``) and set ``meta["diverging"]``.

**References.**

* T. Alamo, J. M. Bravo, E. F. Camacho, "Guaranteed state estimation by zonotopes", *Automatica*
  41(6):1035-1043, 2005. DOI: 10.1016/j.automatica.2004.12.008.
* L. Jaulin, M. Kieffer, O. Didrit, É. Walter, *Applied Interval Analysis*, Springer, 2001.
  DOI: 10.1007/978-1-4471-0249-6.
* M. Moisan, O. Bernard, J.-L. Gouzé, "Near optimal interval observers bundle for uncertain
  bioreactors", *Automatica* 45(1):291-295, 2009.
* C. Combastel, "Zonotopes and Kalman observers: gain optimality under distinct uncertainty
  paradigms and robust convergence", *Automatica* 55:265-273, 2015.
"""

from __future__ import annotations

import sys
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError
from ..estimate import Estimate
from ..interval import Interval
from ..interval_dual import value_and_jacobian
from ..systems.bounds import Bounds
from ..systems.continuous_nonlinear import ContinuousNonlinearSystem
from ..systems.field_tape import FieldTape, kernel_batch, trace_field
from ..systems.flow_enclosure import ORDER_FACTOR, REDUCTIONS, StateZonotope, interval_product, propagate
from .base import Observer, ObserverState, record_consistency

__all__ = ["ContinuousNonlinearObserver"]

_EPS = float(np.finfo(float).eps)
COMPILED_MIN_STEPS = 1000
"""Set-steps (samples × runs × parts) from which :meth:`ContinuousNonlinearObserver.run` runs each sample in the
compiled kernels (:mod:`intervalobs.systems.flow_kernel`, the recorded field and output map) when ``compiled`` is
None: importing Numba and loading the cached kernels cost about a second of CPU (the first run after an install
compiles them, about a minute), and the kernels save 2-4.4 CPU ms per sample of one part against the NumPy path
(``benchmarks/continuous_cost.json``)."""
_NEGLIGIBLE = 1e-9
"""A domain or parameter end is used to contract only where the set crosses it by more than this fraction of its
width (a parameter's box is crossed by rounding after every step; leaving such a crossing is sound and saves a
contraction per coordinate and sample)."""

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def check_model(system: Any, h: Any) -> None:
    """Refuse anything but a :class:`ContinuousNonlinearSystem` and a positive sampling period.

    Raises
    ------
    BoundsError
    """
    if not isinstance(system, ContinuousNonlinearSystem):
        raise BoundsError(f"system: expected a ContinuousNonlinearSystem, got {type(system).__name__}")
    if not (isinstance(h, (int, float)) and np.isfinite(h) and h > 0):
        raise BoundsError(f"h: expected a positive sampling period, got {h!r}")


def prior_splits(splits: int | tuple[int, ...], n: int, size: int) -> tuple[int, ...]:
    """Parts along each state and parameter from ``splits`` (an int: along every state; n of them: states only).

    Parameters
    ----------
    splits : int or sequence of int
    n, size : int
        Numbers of states and of states and parameters.

    Returns
    -------
    tuple of int, length ``size``

    Raises
    ------
    BoundsError
        Not a positive integer, or neither n nor ``size`` of them.
    """
    parts = (splits,) * n if isinstance(splits, int) else tuple(splits)
    parts = parts + (1,) * (size - len(parts)) if len(parts) == n else parts
    if len(parts) != size or not all(isinstance(k, (int, np.integer)) and k >= 1 for k in parts):
        raise BoundsError(
            f"splits: expected a positive integer, {n} of them (states) or {size} (states and parameters), "
            f"got {splits!r}"
        )
    return tuple(int(k) for k in parts)


def prior_parts(low: FloatArray, high: FloatArray, splits: tuple[int, ...]) -> tuple[FloatArray, FloatArray]:
    """The grid of ``splits`` boxes covering ``[low, high]``: their lower and upper ends, shape (P, N).

    Parameters
    ----------
    low, high : numpy.ndarray, shape (N,)
    splits : tuple of int, length N

    Returns
    -------
    part_lo, part_hi : numpy.ndarray, shape (P, N)
    """
    size = low.size
    grids = [np.linspace(low[i], high[i], k + 1) for i, k in enumerate(splits)]
    index = np.stack(np.meshgrid(*[np.arange(k) for k in splits], indexing="ij"), -1).reshape(-1, size)
    part_lo = np.stack([grids[i][index[:, i]] for i in range(size)], -1)
    part_hi = np.stack([grids[i][index[:, i] + 1] for i in range(size)], -1)
    return part_lo, part_hi


def _hull_gain(generators: FloatArray, row: FloatArray, sigma: FloatArray) -> FloatArray:
    r"""Per coordinate, the :math:`\lambda_i` minimising :math:`\sum_j |G_{ij} - \lambda_i b_j| + \sigma|\lambda_i|`.

    A convex piecewise-linear function of :math:`\lambda_i`, minimised at a weighted median of the
    breakpoints :math:`G_{ij}/b_j` (weights :math:`|b_j|`) and :math:`0` (weight :math:`\sigma`).
    """
    live = np.abs(row) > 0
    safe = np.where(live, row, 1.0)
    points = np.concatenate([generators / safe[..., None, :], np.zeros((*generators.shape[:-1], 1))], axis=-1)
    weights = np.concatenate([np.where(live, np.abs(row), 0.0), sigma[..., None]], axis=-1)
    weights = np.broadcast_to(weights[..., None, :], points.shape)
    order = np.argsort(points, axis=-1)
    sorted_points = np.take_along_axis(points, order, axis=-1)
    cumulative = np.cumsum(np.take_along_axis(weights, order, axis=-1), axis=-1)
    half = 0.5 * cumulative[..., -1:]
    index = np.argmax(cumulative >= half, axis=-1)
    return np.take_along_axis(sorted_points, index[..., None], axis=-1)[..., 0]


def _strip_update(
    zset: StateZonotope, a: FloatArray, strip: Interval, order: int, compiled: bool = False, reduction: str = "box"
) -> tuple[StateZonotope, BoolArray]:
    r"""A zonotope containing :math:`\{x \in \langle c, G\rangle : a^\top x \in [s]\}`; also whether that set is empty.

    The strip is first cut to the zonotope's support :math:`a^\top c \pm |a^\top G|\mathbf 1`
    (empty: the data contradict the set). With :math:`[s] \subseteq [y - \sigma, y + \sigma]`, every
    point of the intersection is :math:`x = c + G\xi` with :math:`a^\top x = y + \sigma\eta`,
    :math:`|\eta| \le 1`, hence for any :math:`\lambda`

    .. math:: x = c + \lambda(y - a^\top c) + (I - \lambda a^\top)G\xi + \sigma\lambda\eta,

    a zonotope with one more generator; :math:`\lambda = GG^\top a/(a^\top GG^\top a + \sigma^2)`
    minimises its Frobenius radius (Alamo, Bravo & Camacho 2005). The centre and generators are
    computed in interval arithmetic; their midpoints are kept and the rest joins the box term. ``compiled``:
    the same in :func:`intervalobs.systems.flow_kernel.strip_update`; ``reduction``: how the generators beyond
    ``order`` are reduced (:data:`~intervalobs.systems.flow_enclosure.REDUCTIONS`).
    """
    if compiled:
        return _compiled_strip_update(zset, a, strip, order, reduction)
    generators = zset.generators
    row = Interval._wrap(a[..., None, :])
    image = interval_product(row, Interval._wrap(generators))[..., 0, :]
    level = (row @ Interval._wrap(zset.centre))[..., 0]
    reach = np.nextafter(
        np.maximum(-image.lower, image.upper).sum(-1) * (1.0 + 2 * generators.shape[-1] * _EPS), np.inf
    )
    low = np.maximum(strip.lower, level.lower - reach)
    high = np.minimum(strip.upper, level.upper + reach)
    empty = ~(low <= high)
    low, high = np.where(empty, level.lower, low), np.where(empty, level.upper, high)
    target = 0.5 * (low + high)
    sigma = np.nextafter(np.maximum(high - target, target - low), np.inf)
    gain = _hull_gain(generators, image.centre, sigma)
    gain_i = Interval._wrap(gain)
    centre = gain_i * (target - level)[..., None] + zset.centre
    moved = Interval._wrap(generators) - Interval._raw(gain[..., :, None], gain[..., :, None]) * image[..., None, :]
    extra = gain_i * sigma[..., None]
    new = np.concatenate([moved.centre, extra.centre[..., :, None]], axis=-1)
    slack = np.concatenate([moved.radius, extra.radius[..., :, None]], axis=-1).sum(-1)
    slack = np.nextafter(slack * (1.0 + 2 * new.shape[-1] * _EPS), np.inf)
    box = Interval._raw(centre.lower - centre.centre - slack, centre.upper - centre.centre + slack)
    return StateZonotope(centre.centre, new).with_box(box, order, reduction), empty


def _compiled_strip_update(
    zset: StateZonotope, a: FloatArray, strip: Interval, order: int, reduction: str = "box"
) -> tuple[StateZonotope, BoolArray]:
    """:func:`_strip_update` by the compiled kernel, every set of the batch flattened."""
    from ..systems import flow_kernel  # Numba is imported only where a record is long enough to pay for it

    lead, size = zset.centre.shape[:-1], zset.centre.shape[-1]
    centre, generators, empty = flow_kernel.strip_update(
        kernel_batch(zset.centre, lead, (size,)),
        kernel_batch(zset.generators, lead, zset.generators.shape[-2:]),
        kernel_batch(a, lead, (size,)),
        (kernel_batch(strip.lower, lead, ()), kernel_batch(strip.upper, lead, ())),
        int(order),
        reduction == "frame",
    )
    return StateZonotope(centre.reshape(*lead, size), generators.reshape(*lead, size, order)), empty.reshape(lead)


class ContinuousNonlinearObserver(Observer):
    """Validated flow prediction and measurement contraction for a :class:`ContinuousNonlinearSystem`.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
        The model.
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v`` and the parameters ``p``.
    h : float
        Sampling period of the records (hours, seconds: the unit of the model's time).
    substeps : int
        Validated steps per sampling period (more: tighter and slower).
    splits : int or sequence of int
        Parts of the prior box along each state (an int: along every state), or along each state and
        parameter. The observer carries one
        set per part and reports the hull of the parts that stay consistent with the data; a part
        the data contradict is dropped. A wide prior on a state that is seen only through the
        dynamics (the biomass of a chemostat) needs parts: the validated step loses width in the
        square of the set's size.
    order : int, optional
        Generators kept by the zonotopes (default: ``ORDER_FACTOR`` times the number of states and
        parameters).
    divergence_factor : float
        A width that ends above this many times the prior's (or infinite) warns.
    refine : int
        The bundle (0: off): the most parts carried per run. Whenever the data have dropped at least
        half of them, each live part is bisected along the coordinate (state or parameter) whose
        width is largest relative to the prior box's, so the parts gather where the data leave the
        states and parameters (:func:`_bisect_parts`). Each half is the part cut by a strip, so the
        halves together hold every point the part held.
    compiled : bool, optional
        Run each sample in compiled kernels (Numba, the same bounds up to the order of a few sums): ``f`` and ``g``
        recorded as tapes (:mod:`intervalobs.systems.field_tape`) and the whole prediction and correction in one
        call each; where a function cannot be recorded, it is evaluated in Python and only the array part of each
        step (:mod:`intervalobs.systems.flow_kernel`) is compiled (``meta["field_tape"]`` says which). Default:
        for a run of at least ``COMPILED_MIN_STEPS`` set-steps, or when the kernels are already loaded in the
        process (``init``/``step`` then use them too).
    reduction : {"frame", "box"}
        How the zonotopes' generators beyond ``order`` are reduced after every step and strip: ``"frame"`` (the
        default: the smallest boxed in the frame that the flow carried from the previous reduction, so a rotating
        flow does not make the boxes wrap; :func:`~intervalobs.systems.flow_enclosure._reduce_in_frame`) or
        ``"box"`` (Combastel's: boxed in the axes).

    Attributes
    ----------
    rows : str
        ``"filtered"``.

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import Bounds, ContinuousNonlinearObserver, ContinuousNonlinearSystem
    >>> decay = ContinuousNonlinearSystem(lambda x, u, p: (-p[0] * x[0],), lambda x, u: (x[0],), n=1, n_params=1)
    >>> observer = ContinuousNonlinearObserver(decay, Bounds(x0=(0.0, 2.0), v=(-0.1, 0.1), p=(0.9, 1.1)), h=0.1)
    >>> t = np.arange(0.0, 1.01, 0.1)
    >>> estimate = observer.run(t, np.exp(-t)[:, None])
    >>> bool(np.all((estimate.lower[:, 0] <= np.exp(-t)) & (np.exp(-t) <= estimate.upper[:, 0])))
    True
    """

    rows = "filtered"
    summary_fields = ("substeps", "splits", "refine")

    def __init__(
        self,
        system: ContinuousNonlinearSystem,
        bounds: Bounds,
        h: float,
        *,
        substeps: int = 2,
        splits: int | tuple[int, ...] = 1,
        order: int | None = None,
        divergence_factor: float = 10.0,
        refine: int = 0,
        compiled: bool | None = None,
        reduction: str = "frame",
    ) -> None:
        check_model(system, h)
        if not (isinstance(substeps, int) and substeps >= 1):
            raise BoundsError(f"substeps: expected a positive integer, got {substeps!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m, self.h = system.n, system.p, system.m, float(h)
        self._period = float(h)
        self.substeps, self.divergence_factor = substeps, float(divergence_factor)
        self.splits = prior_splits(splits, system.n, system.n + system.n_params)
        self.order = ORDER_FACTOR * (system.n + system.n_params) if order is None else int(order)
        if self.order < system.n + system.n_params:
            raise BoundsError(f"order: expected at least {system.n + system.n_params} generators, got {order!r}")
        count = int(np.prod(self.splits))
        if not (isinstance(refine, (int, np.integer)) and (refine == 0 or refine >= max(2, count))):
            raise BoundsError(
                f"refine: expected 0 or a number of parts of at least 2 and {count} (splits), got {refine!r}"
            )
        self.refine = int(refine)
        if compiled not in (None, True, False):
            raise BoundsError(f"compiled: expected None, True or False, got {compiled!r}")
        self.compiled = compiled
        if reduction not in REDUCTIONS:
            raise BoundsError(f"reduction: expected one of {', '.join(map(repr, REDUCTIONS))}, got {reduction!r}")
        self.reduction = reduction
        self._limits = (
            np.concatenate([system.domain[0], self.bounds.p[0]]),
            np.concatenate([system.domain[1], self.bounds.p[1]]),
        )
        self._limited = np.flatnonzero(np.isfinite(self._limits[0]) | np.isfinite(self._limits[1]))
        self._w = Interval._raw(*self.bounds.w)
        self._v = Interval._raw(*self.bounds.v)
        self._tapes: dict[bool, tuple[FieldTape | None, str]] = {}

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """The prior: the box of ``x(t_0)`` and of the parameters (split into parts), before the first measurement.

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Prior box of the state (default: the bounds' ``x0``).

        Returns
        -------
        ObserverState
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        low, high = np.concatenate([lo, self.bounds.p[0]]), np.concatenate([hi, self.bounds.p[1]])
        part_lo, part_hi = prior_parts(low, high, self.splits)
        count = part_lo.shape[0]
        zset = StateZonotope.from_box(part_lo, part_hi, self.order)
        if self.refine:
            zset = StateZonotope(
                np.concatenate([zset.centre, np.repeat(zset.centre[:1], self.refine - count, axis=0)]),
                np.concatenate([zset.generators, np.repeat(zset.generators[:1], self.refine - count, axis=0)]),
            )
        alive = np.arange(max(count, self.refine)) < count
        self._scale = np.maximum(high - low, np.finfo(float).tiny)
        internal = {"set": zset, "alive": alive, "lost": np.zeros((), dtype=bool)}
        internal.update(started=False, u=None, lost_flag=np.zeros(1))
        internal["consistent"] = np.ones(1)
        internal["compiled"] = _kernels_loaded() if self.compiled is None else self.compiled
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        lead = y.shape[:-1]
        compiled = bool(state.internal["compiled"])
        zset: StateZonotope = _broadcast(state.internal["set"], lead)
        alive = np.broadcast_to(state.internal["alive"], zset.centre.shape[:-1]).copy()
        lost = np.broadcast_to(state.internal["lost"], lead).copy()
        if state.internal["started"]:
            held = np.broadcast_to(state.internal["u"][..., None, :], (*alive.shape, self.m))
            zset, failed = self._predict(zset, held, compiled)
            lost |= (failed & alive).any(-1)
            alive &= ~failed
        parts_y = np.broadcast_to(y[..., None, :], (*alive.shape, self.p))
        corrected, empty = self._correct(zset, parts_y, u[..., None, :], compiled)
        alive &= ~empty
        zset = _revive(alive, _select(alive, corrected, zset))
        if self.refine:
            zset, alive = _bisect_parts(zset, alive, self._scale, self.order, compiled, self.reduction)
        consistent = alive.any(-1) | lost
        box = zset.box()
        n = self.n
        part_lo = np.where(alive[..., None], box.lower[..., :n], np.inf).min(-2)
        part_hi = np.where(alive[..., None], box.upper[..., :n], -np.inf).max(-2)
        bounded = (consistent & ~lost)[..., None]
        lower = np.where(bounded, np.maximum(part_lo, self.system.domain[0]), -np.inf)
        upper = np.where(bounded, np.minimum(part_hi, self.system.domain[1]), np.inf)
        internal = {"set": zset, "alive": alive, "lost": lost, "started": True, "u": u, "compiled": compiled}
        internal["consistent"] = consistent[..., None].astype(float)
        internal["lost_flag"] = lost[..., None].astype(float)
        return ObserverState(lower, upper, internal=internal)

    def _predict(self, zset: StateZonotope, held: FloatArray, compiled: bool) -> tuple[StateZonotope, BoolArray]:
        """The flow enclosure of every part; a part whose enclosure is lost becomes a point and is flagged.

        All parts go in one batch; only when that fails (some part too wide for a validated step) is
        each part tried on its own, so one diverging part does not stop the others.
        """
        failed = np.zeros(zset.centre.shape[:-1], dtype=bool)
        tape = self._recorded(output=False)[0] if compiled else None

        def step(sets: StateZonotope, inputs: FloatArray) -> StateZonotope:
            return propagate(
                self.system,
                inputs,
                self._w,
                sets,
                self._period,
                self.substeps,
                self.order,
                compiled,
                tape=tape,
                reduction=self.reduction,
            )[0]

        try:
            return step(zset, held), failed
        except AssumptionError:
            pass
        centre, generators = zset.centre.copy(), np.zeros_like(zset.generators)
        for index in np.ndindex(*failed.shape):
            single = StateZonotope(zset.centre[index], zset.generators[index])
            try:
                moved = step(single, held[index])
            except AssumptionError:
                failed[index] = True
                continue
            centre[index], generators[index] = moved.centre, moved.generators
        return StateZonotope(centre, generators), failed

    def _recorded(self, output: bool) -> tuple[FieldTape | None, str]:
        """The system's field (or output map) recorded once (:func:`trace_field`, probed on the prior box), or None
        and why."""
        if output not in self._tapes:
            low = np.concatenate([self.bounds.x0[0], self.bounds.p[0]])
            high = np.concatenate([self.bounds.x0[1], self.bounds.p[1]])
            self._tapes[output] = trace_field(self.system, low, high, output=output)
        return self._tapes[output]

    def _compiled_correct(
        self, zset: StateZonotope, y: FloatArray, u: FloatArray
    ) -> tuple[StateZonotope, BoolArray] | None:
        """:meth:`_correct` in one call of :func:`intervalobs.observers.correction_kernel.correct` (the output map by
        its tape); None where the output map is not recorded."""
        tape = self._recorded(output=True)[0]
        if tape is None or zset.generators.shape[-1] != self.order:
            return None
        from . import correction_kernel  # Numba is imported only where a record is long enough to pay for it

        lead, size = zset.centre.shape[:-1], zset.centre.shape[-1]
        centre, generators, empty, ok = correction_kernel.correct(
            tape.arrays,
            (kernel_batch(zset.centre, lead, (size,)), kernel_batch(zset.generators, lead, (size, self.order))),
            (kernel_batch(y, lead, (self.p,)), kernel_batch(u, lead, (self.m,)), np.stack(self.bounds.v)),
            (*self._limits, self._limited.astype(np.int64), _NEGLIGIBLE),
            self.reduction == "frame",
        )
        if not ok:
            raise BoundsError(
                "g: the output map is undefined on a set's hull (a divisor containing 0, log or sqrt below 0)"
            )
        end = StateZonotope(centre.reshape(*lead, size), generators.reshape(*lead, size, self.order))
        return end, empty.reshape(lead)

    def _correct(
        self, zset: StateZonotope, y: FloatArray, u: FloatArray, compiled: bool
    ) -> tuple[StateZonotope, BoolArray]:
        """Contract by the state domain and parameter box, then by each output (module docstring)."""
        recorded = self._compiled_correct(zset, y, u) if compiled else None
        if recorded is not None:
            return recorded
        empty = np.zeros(y.shape[:-1], dtype=bool)
        zset, empty = self._domain_contract(zset, empty, compiled)
        output = self.system.output_map(u)
        for i in range(self.p):
            hull = zset.box()
            # one forward-mode pass: the output Jacobian over the set's hull (row 0) and g at its centre (row 1)
            ends = (np.stack([hull.lower, zset.centre]), np.stack([hull.upper, zset.centre]))
            values, slopes = value_and_jacobian(output, *ends, self.p)
            slope = slopes[0][..., i, :]
            a = slope.centre
            centre = values[1][..., i]
            remainder = _slope_remainder(slope - a, zset)
            level = (Interval._wrap(a[..., None, :]) @ Interval._wrap(zset.centre))[..., 0]
            strip = (y[..., i] - self._v[i]) - centre - remainder + level
            updated, now_empty = _strip_update(zset, a, strip, self.order, compiled, self.reduction)
            empty |= now_empty
            zset = _select(~empty, updated, zset)
            zset, empty = self._domain_contract(zset, empty, compiled)
        return zset, empty

    def _domain_contract(
        self, zset: StateZonotope, empty: BoolArray, compiled: bool = False
    ) -> tuple[StateZonotope, BoolArray]:
        """Contract by the state domain and the parameter box (strips on single coordinates) where they cut.

        A crossing below ``_NEGLIGIBLE`` times the set's width is left (no contraction is needed for soundness).
        """
        low, high = self._limits
        size = low.size
        hull: Interval | None = None
        for i in self._limited:
            hull = zset.box() if hull is None else hull  # the hull changes only where a strip was applied
            slack = _NEGLIGIBLE * (hull.upper[..., i] - hull.lower[..., i])
            if not np.any((hull.lower[..., i] < low[i] - slack) | (hull.upper[..., i] > high[i] + slack)):
                continue
            a = np.broadcast_to(np.eye(size)[i], zset.centre.shape)
            updated, now_empty = _strip_update(
                zset, a, Interval._raw(np.asarray(low[i]), np.asarray(high[i])), self.order, compiled, self.reduction
            )
            empty = empty | now_empty
            zset, hull = _select(~empty, updated, zset), None
        return zset, empty

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record (see :meth:`Observer.run`), with consistency and divergence in ``meta``.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times, spaced by ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements (a leading axis of Monte Carlo runs).
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs, held between samples.

        Returns
        -------
        Estimate
            ``meta`` holds ``consistent`` (bool, or a list per run), ``inconsistent_from`` (the first
            time the record contradicts the model, the earliest over the runs, None when it never does;
            per run in ``inconsistent_from_runs``), ``diverging``, ``compiled`` (whether the compiled kernels ran)
            and ``field_tape``, ``output_tape`` (with the kernels: ``"recorded"`` where f, g were evaluated by
            their compiled tapes, else why they were evaluated in Python; None without the kernels).
        """
        times, ys, us = self._signals(t, y, u)
        state = self.init()
        if self.compiled is None:  # the kernels where the record pays for loading them
            sets = times.size * int(np.prod(ys.shape[:-2])) * max(int(np.prod(self.splits)), self.refine)
            state.internal["compiled"] = state.internal["compiled"] or sets >= COMPILED_MIN_STEPS
        estimate, extras = self._loop(times, ys, us, state=state, collect=("consistent", "lost_flag"))
        flags = extras["consistent"][..., 0] > 0
        lost = extras["lost_flag"][..., 0] > 0
        record_consistency(estimate, flags)
        estimate.meta["diverging"] = self._diverging(estimate, flags, lost)
        estimate.meta["compiled"] = bool(state.internal["compiled"])
        compiled = bool(state.internal["compiled"])
        estimate.meta["field_tape"] = self._recorded(output=False)[1] if compiled else None
        estimate.meta["output_tape"] = self._recorded(output=True)[1] if compiled else None
        return estimate

    def _diverging(self, estimate: Estimate, flags: BoolArray, lost: BoolArray) -> bool:
        """Whether a run lost its flow enclosure or ends wider than ``divergence_factor`` times its prior; warn."""
        prior = self.bounds.x0[1] - self.bounds.x0[0]
        final = (estimate.upper - estimate.lower)[..., -1, :]
        live = flags[..., -1]
        limit = self.divergence_factor * np.maximum(prior, np.finfo(float).tiny)
        grown = live[..., None] & ~(final <= limit)
        if not np.any(grown):
            return False
        state = int(np.argwhere(grown)[0][-1])
        when = np.argmax(lost.reshape(-1, lost.shape[-1]).any(0)) if lost.any() else None
        cause = (
            f"the validated flow enclosure was lost at t = {float(estimate.t[when]):.4g} (bounds infinite from then)"
            if when is not None
            else f"the bounds of state {state + 1} grew to {float(np.max(final[..., state])):.3g} "
            f"(prior width {prior[state]:.3g})"
        )
        warnings.warn(
            f"{cause}: the measurements do not contract the set enough; split the prior box (splits=), narrow "
            "the parameter box, add substeps or an output that sees the state",
            RuntimeWarning,
            stacklevel=3,
        )
        return True

    def meta(self) -> dict[str, Any]:
        """Design facts: method, sampling period, substeps.

        Returns
        -------
        dict
        """
        return {"method": type(self).__name__, "h": self.h, "substeps": self.substeps}


def _slope_remainder(slope: Interval, zset: StateZonotope) -> Interval:
    r"""Bounds of :math:`[J]G\xi` for :math:`|\xi| \le 1` (the mean-value form's interval part)."""
    image = interval_product(
        Interval._raw(slope.lower[..., None, :], slope.upper[..., None, :]), Interval._wrap(zset.generators)
    )
    reach = np.maximum(-image.lower, image.upper)[..., 0, :].sum(-1)  # m nonnegative terms: within (m - 1)u
    reach = np.nextafter(reach * (1.0 + 2 * zset.generators.shape[-1] * _EPS), np.inf)
    return Interval._raw(-reach, reach)


def _bisect_parts(
    zset: StateZonotope,
    alive: BoolArray,
    scale: FloatArray,
    order: int,
    compiled: bool = False,
    reduction: str = "box",
) -> tuple[StateZonotope, BoolArray]:
    r"""Where at most half the parts of a run live, bisect each live part into its own slot and a dropped one's.

    A part is cut along its coordinate :math:`i` of widest hull relative to ``scale``, at the middle
    :math:`m` of that hull: the halves are the part intersected with the strips :math:`z_i \in [l, m]`
    and :math:`z_i \in [m, u]` (:func:`_strip_update`), so their union holds every point of the part.
    Runs with more than half their parts alive are left as they are.
    """
    parts = alive.shape[-1]
    count = alive.sum(-1, keepdims=True)
    split = (2 * count <= parts) & (count > 0)
    if not split.any():
        return zset, alive
    hull = zset.box()
    coordinate = np.argmax((hull.upper - hull.lower) / scale, axis=-1)
    row = np.eye(scale.size)[coordinate]
    low = np.take_along_axis(hull.lower, coordinate[..., None], -1)[..., 0]
    high = np.take_along_axis(hull.upper, coordinate[..., None], -1)[..., 0]
    middle = 0.5 * (low + high)
    lower_half, lower_empty = _strip_update(zset, row, Interval._raw(low, middle), order, compiled, reduction)
    upper_half, upper_empty = _strip_update(zset, row, Interval._raw(middle, high), order, compiled, reduction)
    slots = np.argsort(~alive, axis=-1, kind="stable")
    rank = np.argsort(slots, axis=-1)
    source = np.take_along_axis(slots, np.clip(rank - count, 0, parts - 1), axis=-1)
    keeps = split & (rank < count)
    takes = split & (rank >= count) & (rank < 2 * count)
    moved = StateZonotope(
        np.take_along_axis(upper_half.centre, source[..., None], axis=-2),
        np.take_along_axis(upper_half.generators, source[..., None, None], axis=-3),
    )
    zset = _select(takes, moved, _select(keeps, lower_half, zset))
    alive = np.where(keeps, alive & ~lower_empty, alive)
    alive = np.where(takes, ~np.take_along_axis(upper_empty, source, axis=-1), alive)
    return zset, alive


def _kernels_loaded() -> bool:
    """Whether this process has already compiled or loaded the kernels (a step's and the strip update's)."""
    module = sys.modules.get("intervalobs.systems.flow_kernel")
    if module is None or not module.strip_update.signatures:
        return False
    return bool(module.advance.signatures) or bool(module.propagate.signatures)


def _broadcast(zset: StateZonotope, lead: tuple[int, ...]) -> StateZonotope:
    parts = zset.centre.shape[-2:]
    return StateZonotope(
        np.broadcast_to(zset.centre, (*lead, *parts)).copy(),
        np.broadcast_to(zset.generators, (*lead, *zset.generators.shape[-3:])).copy(),
    )


def _revive(alive: BoolArray, zset: StateZonotope) -> StateZonotope:
    """Replace the set of each part found empty by a live part's of the same run (by a point where none lives).

    An empty part holds no state any more; carrying its last set forward could only grow without bound.
    The copy changes nothing (the hull is over live parts only) and keeps every part propagable.
    """
    if alive.all():
        return zset
    donor = np.argmax(alive, axis=-1)[..., None]
    centre = np.take_along_axis(zset.centre, donor[..., None], axis=-2)
    generators = np.take_along_axis(zset.generators, donor[..., None, None], axis=-3)
    copy = StateZonotope(np.broadcast_to(centre, zset.centre.shape), np.broadcast_to(generators, zset.generators.shape))
    point = StateZonotope(zset.centre, np.zeros_like(zset.generators))
    none = np.broadcast_to(~alive.any(-1, keepdims=True), alive.shape)
    return _select(alive, zset, _select(none, point, copy))


def _select(mask: BoolArray, chosen: StateZonotope, other: StateZonotope) -> StateZonotope:
    """Per run and part: ``chosen`` where ``mask``, else ``other``."""
    return StateZonotope(
        np.where(mask[..., None], chosen.centre, other.centre),
        np.where(mask[..., None, None], chosen.generators, other.generators),
    )
