r"""A moving-window validated observer for continuous-time nonlinear systems with a bounded disturbance.

The row of sample :math:`k` bounds :math:`x(t_k)` given the samples :math:`s = \max(0, k - H), \dots, k` and a
sound box of :math:`x(t_s)` (the prior box for :math:`s = 0`, else the estimator's own row :math:`s`):

1. **One symbol vector for the whole window.** The start box (with the parameters' box) is the zonotope
   :math:`c_0 + G_0\zeta_0`, :math:`\zeta_0 \in [-1, 1]^N`. Each sampling period is carried by the validated flow
   enclosure (:func:`~intervalobs.systems.flow_enclosure.propagate`) with *every* column persistent
   (``persistent`` = the columns so far, ``order`` = those plus N): its step 4 maps the columns by the midpoint
   matrix and appends the box of everything else — the centre's enclosure, the linearisation remainder and the
   disturbance's effect over the period — as N new columns with fresh symbols. Nothing is ever reduced across a
   sample, so for every trajectory of the model through the window there is *one* vector
   :math:`\zeta = (\zeta_0, \dots, \zeta_L) \in [-1, 1]^{N(L+1)}` with :math:`z(t_{s+i}) = c_i + G_i\zeta` at every
   sample :math:`i` of it (:math:`G_i` padded with zero columns). Where a period is split by the step control, the
   columns appended inside it are reduced together, which only merges symbols that no sample sees.
2. **Rows.** The mean-value form of :math:`g` over the hull of :math:`c_i + G_i\zeta` turns each sample into
   rows :math:`y_{s+i} - \overline v - g(c_i) - r_i \le a_i^\top\zeta \le y_{s+i} - \underline v - g(c_i) + r_i`
   (:math:`a_i` the midpoint of :math:`[J_g] G_i`, :math:`r_i` the rest of the interval row; for a linear output
   :math:`r_i` is round-off only).
3. **Bounds.** Each state at :math:`t_k` is :math:`c_L + G_L\zeta`; its least and greatest values over the rows and
   :math:`|\zeta| \le 1` are linear programmes, whose bounds are certified by weak duality
   (:class:`~intervalobs.lp.certified.DenseLP`), then intersected with the state domain. A window whose rows an LP
   proves infeasible contradicts the model (the record is flagged, never raised on).

**Why every** :math:`x(t_k)` **is in the row.** By induction on :math:`k`: the start box holds :math:`x(t_s)`
(the prior's assumption, or the row :math:`s < k`), so the true trajectory is one of those the flow enclosure
covers, with one :math:`\zeta^\star` in the unit cube; the true outputs satisfy every row at :math:`\zeta^\star`
(the noise is in its box and the mean-value form holds), so :math:`\zeta^\star` is in the LP's feasible set and
:math:`x(t_k) = c_L + G_L\zeta^\star` lies between the certified bounds (rounded outward). The window is the
whole-window version of the strip-by-strip update of
:class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver`, which intersects each sample's
strip with a zonotope by one Alamo cut (a parallelotope around the intersection, lossy) and reduces the generators
after every step; here the polytope of :math:`\zeta` is kept exactly over the window.

The window's start carries the information older than :math:`H` samples as a box (the dependence on the earlier
symbols is dropped there), so :math:`H` trades tightness against cost: :math:`H` validated steps per sample (the
windows of :math:`H` consecutive samples are carried in one batch) and :math:`2n` LPs of :math:`N(H+1)` variables
and :math:`p(H+1)` rows.

**References.**

* D. Q. Mayne, "Moving horizon estimation" and the set-membership variant: A. Alessandri, M. Baglietto,
  G. Battistelli, "Moving-horizon state estimation for nonlinear discrete-time systems: new stability results
  and approximation schemes", *Automatica* 44(7):1753-1765, 2008 (moving windows of bounded-error data).
* T. Alamo, J. M. Bravo, E. F. Camacho, "Guaranteed state estimation by zonotopes", *Automatica* 41(6):1035-1043,
  2005 (the strip cut this estimator replaces by an exact polytope over the window).
* R. J. Lohner, "Enclosing the solutions of ordinary initial and boundary value problems", 1987, and
  W. Kühn, "Rigorously computed orbits of dynamical systems without the wrapping effect", *Computing*
  61(1):47-67, 1998 (the validated flow enclosure with zonotopes).
* A. Neumaier, O. Shcherbina, "Safe bounds in linear and mixed-integer linear programming",
  *Mathematical Programming* 99(2):283-296, 2004 (certified LP bounds).
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError
from ..estimate import Estimate
from ..interval import Interval
from ..interval_dual import value_and_jacobian
from ..lp.certified import DenseLP
from ..systems.bounds import Bounds
from ..systems.continuous_nonlinear import ContinuousNonlinearSystem
from ..systems.field_tape import FieldTape, trace_field
from ..systems.flow_enclosure import StateZonotope, interval_product, propagate
from .base import Observer, ObserverState, record_consistency
from .continuous_nonlinear import COMPILED_MIN_STEPS, check_model
from .set_inversion import _feasible, _magnitude_sum, _radius, _unit_image

__all__ = ["ContinuousWindowObserver"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

_EPS = float(np.finfo(float).eps)
_HALVINGS = 3
_NEGLIGIBLE = 1e-10
"""States whose hull's radius is below this, relative to their magnitude, take the hull without linear programmes (a
clock state, a state the output equals)."""


class ContinuousWindowObserver(Observer):
    """Filtered bounds of a :class:`ContinuousNonlinearSystem` with a disturbance from a moving window of samples.

    Each row bounds ``x(t_k)`` by certified linear programmes over the last ``window`` samples, carried by the
    validated flow enclosure with every generator kept (one symbol vector for the whole window, the module's
    steps), starting from the estimator's own row ``window`` samples earlier. Tighter than
    :class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver` where its one-strip-at-a-time
    cuts lose (a rotating, partly observed block), at ``window`` flow steps and ``2n`` LPs a sample.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
        The model (a disturbance ``w`` allowed).
    bounds : Bounds
        Boxes of ``x0``, ``w``, ``v`` and the parameters ``p`` (finite ``x0`` and ``p``).
    h : float
        Sampling period of the records.
    window : int
        Samples in a window after its start (``H``; fewer at the start of a record).
    substeps : int
        Validated steps per sampling period (the columns appended inside a period are merged).
    compiled : bool, optional
        Carry the windows in the compiled kernels (:mod:`intervalobs.systems.flow_kernel`, the field by its tape
        where it can be recorded: the same sets up to the order of a few sums, about 10x faster here); False keeps
        Numba unimported; None (default): where a record takes at least ``COMPILED_MIN_STEPS`` set-steps
        (samples times runs times ``window``).

    Attributes
    ----------
    rows : str
        ``"filtered"``.

    Raises
    ------
    BoundsError
        A box is infinite or an argument is out of range.

    Examples
    --------
    A decay with a disturbance, measured with noise:

    >>> import numpy as np
    >>> from intervalobs import Bounds, ContinuousNonlinearSystem, ContinuousWindowObserver
    >>> decay = ContinuousNonlinearSystem(lambda x, u, p: (-x[0],), lambda x, u: (x[0],), n=1, E=[[1.0]])
    >>> bounds = Bounds(x0=(0.0, 2.0), w=(-0.05, 0.05), v=(-0.05, 0.05))
    >>> observer = ContinuousWindowObserver(decay, bounds, h=0.1, window=10)
    >>> t = np.arange(0.0, 2.01, 0.1)
    >>> estimate = observer.run(t, (np.exp(-t) + 0.04 * np.cos(7 * t))[:, None])
    >>> bool(np.all((estimate.lower[:, 0] <= np.exp(-t)) & (np.exp(-t) <= estimate.upper[:, 0])))
    True
    """

    rows = "filtered"
    batched = False
    summary_fields = ("window", "substeps")

    def __init__(
        self,
        system: ContinuousNonlinearSystem,
        bounds: Bounds,
        h: float,
        *,
        window: int = 30,
        substeps: int = 1,
        compiled: bool | None = None,
    ) -> None:
        check_model(system, h)
        for name, value in (("window", window), ("substeps", substeps)):
            if not (isinstance(value, (int, np.integer)) and value >= 1):
                raise BoundsError(f"{name}: expected a positive integer, got {value!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m, self.h = system.n, system.p, system.m, float(h)
        self._period = float(h)
        self.size = system.n + system.n_params
        self.window, self.substeps = int(window), int(substeps)
        if not (np.all(np.isfinite(self.bounds.x0)) and np.all(np.isfinite(self.bounds.p))):
            raise BoundsError("bounds: the window observer needs finite boxes of x0 and of the parameters")
        self._w = Interval._raw(*self.bounds.w)
        self._v = Interval._raw(*self.bounds.v)
        if compiled not in (None, True, False):
            raise BoundsError(f"compiled: expected None, True or False, got {compiled!r}")
        self.compiled = compiled
        self._low = np.concatenate([self.bounds.x0[0], self.bounds.p[0]])
        self._high = np.concatenate([self.bounds.x0[1], self.bounds.p[1]])
        self._tape: FieldTape | None = None

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """The prior box of the states (the observer has no step: :meth:`run` takes the whole record).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional
            Prior box (default: the bounds' ``x0``).

        Returns
        -------
        ObserverState
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        return ObserverState(lo.copy(), hi.copy())

    def meta(self) -> dict[str, Any]:
        """Design facts: method, sampling period, window, substeps.

        Returns
        -------
        dict
        """
        return {"method": type(self).__name__, "h": self.h, "window": self.window, "substeps": self.substeps}

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Filtered bounds over a whole record (each run of a leading axis on its own).

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times, spaced by ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs, held between samples.

        Returns
        -------
        Estimate
            ``meta`` holds ``consistent`` and ``inconsistent_from`` (rows from the first window an LP proves
            infeasible are the state domain), ``lost_from`` (the first time a window's validated step was lost;
            that row is the domain), ``diverging`` (True when a row was lost) and ``ms_per_sample`` (CPU).
        """
        times, ys, us = self._signals(t, y, u)
        clock = time.process_time()
        lead = ys.shape[:-2]
        count = int(np.prod(lead))
        kernels = self.compiled if self.compiled is not None else times.size * count * self.window >= COMPILED_MIN_STEPS
        self._kernels = bool(kernels)
        if self._kernels and self._tape is None:
            self._tape = trace_field(self.system, self._low, self._high)[0]
        runs = [
            self._one_run(times, yr, ur)
            for yr, ur in zip(ys.reshape(count, *ys.shape[-2:]), us.reshape(count, *us.shape[-2:]))
        ]
        lower = np.stack([r[0] for r in runs]).reshape(*lead, times.size, self.n)
        upper = np.stack([r[1] for r in runs]).reshape(*lead, times.size, self.n)
        flags = np.stack([r[2] for r in runs]).reshape(*lead, times.size)
        estimate = Estimate(
            times, lower, upper, meta={**self.meta(), "rows": self.rows}, state_names=self._channel_names("state") or ()
        )
        record_consistency(estimate, flags)
        lost = [r[3] for r in runs if r[3] is not None]
        estimate.meta["lost_from"] = min(lost) if lost else None
        estimate.meta["diverging"] = bool(lost)
        estimate.meta["compiled"] = self._kernels
        estimate.meta["ms_per_sample"] = 1000.0 * (time.process_time() - clock) / (times.size * len(runs))
        if lost:
            warnings.warn(
                f"a window's validated flow enclosure was lost at t = {min(lost):.4g}: those rows are the state "
                "domain; shorten the window, add substeps or narrow the prior box",
                RuntimeWarning,
                stacklevel=2,
            )
        return estimate

    # -- one record -------------------------------------------------------------------------------------------------

    def _one_run(
        self, t: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, BoolArray, float | None]:
        """Rows of one record: the windows of ``window`` consecutive samples in one batch each."""
        size, n, horizon = t.size, self.n, self.window
        domain_lo = np.broadcast_to(self.system.domain[0], (n,)).astype(float)
        domain_hi = np.broadcast_to(self.system.domain[1], (n,)).astype(float)
        lower = np.tile(domain_lo, (size, 1))
        upper = np.tile(domain_hi, (size, 1))
        flags = np.ones(size, dtype=bool)
        lost_from: float | None = None
        prior = (np.asarray(self.bounds.x0[0], dtype=float), np.asarray(self.bounds.x0[1], dtype=float))
        # the first block: one chain from the prior box, window k uses its samples 0 … k
        blocks: list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]] = []
        first = np.arange(min(horizon + 1, size))
        blocks.append((np.zeros(1, dtype=np.int64), first, np.zeros(first.size, dtype=np.int64)))
        k0 = horizon + 1
        while k0 < size:
            ks = np.arange(k0, min(k0 + horizon, size))
            blocks.append((ks - horizon, ks, np.arange(ks.size)))
            k0 += horizon
        for starts, ks, chains in blocks:
            start_lo = np.stack([prior[0] if s == 0 else lower[s] for s in starts.tolist()])
            start_hi = np.stack([prior[1] if s == 0 else upper[s] for s in starts.tolist()])
            steps = int(ks[-1] - starts[chains[-1]])
            centres, generators, reached = self._chain(start_lo, start_hi, starts, steps, u)
            for k, b in zip(ks.tolist(), chains.tolist()):
                if not flags[k - 1 if k else 0]:  # the record already contradicts the model
                    flags[k] = False
                    continue
                s = int(starts[b])
                steps_k = k - s
                if reached[b] < steps_k:
                    lost_from = float(t[k]) if lost_from is None else min(lost_from, float(t[k]))
                    continue
                bounds = self._window_bounds(centres[b, : steps_k + 1], generators[b, : steps_k + 1], y, u, s)
                if bounds is None:
                    flags[k:] = False
                    continue
                lower[k] = np.maximum(bounds[0], domain_lo)
                upper[k] = np.minimum(bounds[1], domain_hi)
        return lower, upper, flags, lost_from

    def _chain(
        self, start_lo: FloatArray, start_hi: FloatArray, starts: NDArray[np.int64], steps: int, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
        """Step 1 of the module for a batch of windows: centres (B, steps + 1, N), generators (B, steps + 1, N, M)
        with ``M = N (steps + 1)`` (zero-padded), and the last sample each window reached."""
        count, size = starts.size, self.size
        total = size * (steps + 1)
        centres = np.full((count, steps + 1, size), np.nan)
        generators = np.zeros((count, steps + 1, size, total))
        reached = np.full(count, -1, dtype=np.int64)
        finite = np.all(np.isfinite(start_lo) & np.isfinite(start_hi), axis=-1)
        low = np.concatenate([np.where(finite[:, None], start_lo, 0.0), np.tile(self.bounds.p[0], (count, 1))], -1)
        high = np.concatenate([np.where(finite[:, None], start_hi, 0.0), np.tile(self.bounds.p[1], (count, 1))], -1)
        zset = StateZonotope.from_box(low, high)
        alive = finite.copy()
        centres[:, 0], generators[:, 0, :, :size] = zset.centre, zset.generators
        reached[alive] = 0
        for i in range(steps):
            cols = size * (i + 1)
            held = u[np.minimum(starts + i, u.shape[0] - 1)]
            zset, failed = self._advance(zset, held, cols)
            alive &= ~failed
            if not alive.any():
                break
            centres[:, i + 1], generators[:, i + 1, :, : cols + size] = zset.centre, zset.generators
            reached[alive] = i + 1
        return centres, generators, reached

    def _advance(self, zset: StateZonotope, held: FloatArray, cols: int) -> tuple[StateZonotope, BoolArray]:
        """One sampling period of every window, every column kept; where that fails, each window alone."""
        failed = np.zeros(zset.centre.shape[0], dtype=bool)

        def move(sets: StateZonotope, inputs: FloatArray) -> StateZonotope:
            return propagate(
                self.system,
                inputs,
                self._w,
                sets,
                self._period,
                self.substeps,
                cols + self.size,
                self._kernels,
                tape=self._tape if self._kernels else None,
                reduction="box",
                persistent=cols,
                halvings=_HALVINGS,
            )[0]

        try:
            return move(zset, held), failed
        except AssumptionError:
            pass
        centre = zset.centre.copy()
        generators = np.concatenate([zset.generators, np.zeros((*zset.centre.shape, self.size))], axis=-1)
        for b in range(failed.size):
            try:
                moved = move(StateZonotope(zset.centre[b : b + 1], zset.generators[b : b + 1]), held[b : b + 1])
            except AssumptionError:
                failed[b] = True
                continue
            centre[b], generators[b] = moved.centre[0], moved.generators[0]
        return StateZonotope(centre, generators), failed

    def _rows(
        self, centres: FloatArray, generators: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        r"""Step 2 of the module: rows :math:`a` and ends :math:`\underline s \le a\zeta \le \overline s`."""
        hull = Interval._wrap(centres) + _unit_image(generators)
        output = self.system.output_map(u)
        ends = (np.stack([hull.lower, centres]), np.stack([hull.upper, centres]))
        values, slopes = value_and_jacobian(output, *ends, self.p)
        image = interval_product(slopes[0], Interval._wrap(generators))
        rows = image.centre
        strip = (Interval._wrap(y) - self._v) - values[1] - _unit_image(_radius(image))
        return rows.reshape(-1, rows.shape[-1]), strip.lower.reshape(-1), strip.upper.reshape(-1)

    def _window_bounds(
        self, centres: FloatArray, generators: FloatArray, y: FloatArray, u: FloatArray, start: int
    ) -> tuple[FloatArray, FloatArray] | None:
        """Step 3 of the module for one window (samples ``start …``): bounds of the states at its last sample, None
        when an LP proves that no trajectory of the model fits its samples."""
        count = centres.shape[0]
        used = self.size * count
        generators = generators[..., :used]
        a, low, high = self._rows(centres, generators, y[start : start + count], u[start : start + count])
        usable = np.all(np.isfinite(a), axis=1) & np.isfinite(low) & np.isfinite(high)
        a, low, high = a[usable], low[usable], high[usable]
        last_c, last_g = centres[-1, : self.n], generators[-1, : self.n]
        reach = _magnitude_sum(last_g)
        lp_lo, lp_hi = -reach, reach
        active = np.flatnonzero(reach > _NEGLIGIBLE * (1.0 + np.abs(last_c)))  # others: the hull is tight enough
        if a.shape[0] and active.size:
            solver = DenseLP()
            solver.load(a, -np.ones(used), np.ones(used), low, high)
            failed = solver.path.failed
            costs = last_g[active]
            least = solver.minima(costs)[0]
            most = -solver.minima(-costs)[0]
            if solver.path.failed > failed and _feasible((a, low, high)) is None:
                return None
            lp_lo, lp_hi = lp_lo.copy(), lp_hi.copy()
            lp_lo[active] = np.maximum(lp_lo[active], least)
            lp_hi[active] = np.minimum(lp_hi[active], most)
            if np.any(lp_lo > lp_hi):  # certified bounds that cross: no zeta meets the rows
                return None
        centre = Interval._wrap(last_c)
        bound_lo = (centre + Interval._raw(lp_lo, lp_lo)).lower
        bound_hi = (centre + Interval._raw(lp_hi, lp_hi)).upper
        return bound_lo, bound_hi
