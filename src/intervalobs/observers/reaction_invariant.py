r"""The interval asymptotic observer of reaction systems: bounds without any kinetic model.

For a :class:`~intervalobs.systems.reaction.ReactionSystem`, the reaction invariants
:math:`z = x_U + G x_M` obey :math:`\dot z = D(t)(z_{in} - z)` whatever the kinetics. With :math:`D`
constant (or held) on :math:`[t_k, t_{k+1}]`, the exact solution is

.. math::

    z(t_{k+1}) = a_k\, z(t_k) + (1 - a_k)\, z_{in}, \qquad a_k = e^{-D_k h} \in (0, 1],

a convex combination, so an interval of :math:`z(t_k)` and the box of :math:`z_{in}` give an interval
of :math:`z(t_{k+1})` by outward-rounded interval arithmetic (with :math:`a_k` itself enclosed). At
each sample, :math:`x_M(t_k) \in y_k - [v]` and :math:`x_U = z - G x_M`; with nonnegative
concentrations also :math:`x \ge 0` and :math:`z \ge G x_M`. The width of :math:`z` shrinks as
:math:`e^{-\int D}`: the prior is forgotten at the dilution rate, and then the width of
:math:`x_U` is that of :math:`G x_M`, i.e. of the measurement noise. No kinetic model enters, so
the bounds hold for every kinetics, known or not — and they cannot be tighter than what the
noise on :math:`x_M` leaves.

**References.**

* G. Bastin, D. Dochain, *On-line Estimation and Adaptive Control of Bioreactors*, Elsevier, 1990
  (asymptotic observers, ch. 3).
* J.-L. Gouzé, A. Rapaport, M. Z. Hadj-Sadok, "Interval observers for uncertain biological
  systems", *Ecological Modelling* 133(1-2):45-56, 2000. doi:10.1016/S0304-3800(00)00279-9
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import BoundsError, DataError
from ..estimate import Estimate
from ..interval import Interval
from ..systems.bounds import Bounds
from ..systems.reaction import ReactionSystem
from .base import Observer, ObserverState, record_consistency

__all__ = ["ReactionInvariantObserver"]

FloatArray = NDArray[np.float64]


class ReactionInvariantObserver(Observer):
    """Interval asymptotic observer of a :class:`ReactionSystem` (filtered rows).

    Parameters
    ----------
    system : ReactionSystem
        The model (yields, measured components, inlet, dilution).
    bounds : Bounds
        Boxes of ``x0`` (all ``n`` components) and of the measurement noise ``v``.
    h : float
        Sampling period of the records (the unit of the dilution rate's time).

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import Bounds, ReactionInvariantObserver, ReactionSystem
    >>> chemostat = ReactionSystem([[1.0], [-2.0]], measured=[1], inlet=[0.0, 5.0], dilution=0.2)
    >>> observer = ReactionInvariantObserver(chemostat, Bounds(x0=([1.0, 0.3], [3.0, 0.8]), v=(-0.02, 0.02)), h=0.1)
    >>> estimate = observer.run(np.arange(0.0, 30.0, 0.1), np.full((300, 1), 0.4))
    >>> bool(estimate.width()[-1, 0] < 0.05)  # X: the prior forgotten, the noise on S left
    True
    """

    rows = "filtered"

    def __init__(self, system: ReactionSystem, bounds: Bounds, h: float) -> None:
        if not isinstance(system, ReactionSystem):
            raise BoundsError(f"system: expected a ReactionSystem, got {type(system).__name__}")
        if not (isinstance(h, (int, float)) and np.isfinite(h) and h > 0):
            raise BoundsError(f"h: expected a positive sampling period, got {h!r}")
        self.system, self.bounds = system, bounds.resolve(system)
        self.n, self.p, self.m, self.h = system.n, system.p, system.m, float(h)
        self._period = float(h)
        self._noise = Interval(*self.bounds.v)
        self._gain = system.invariant_gain
        inlet = system.inlet
        self._z_inlet = inlet[system.unmeasured] + self._gain @ inlet[system.measured]

    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """The prior box of ``x(t_0)`` and its invariants, before the first measurement.

        %(prior_box)s
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        prior = Interval(lo, hi)
        z = prior[self.system.unmeasured] + self._gain @ prior[self.system.measured]
        internal = {"z_lower": z.lower, "z_upper": z.upper, "started": False, "u": None, "consistent": np.ones(1)}
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    def meta(self) -> dict[str, Any]:
        """Design facts: method, sampling period, measured components.

        Returns
        -------
        dict
        """
        return {"method": type(self).__name__, "h": self.h, "measured": self.system.measured.tolist()}

    def _decay(self, u: FloatArray) -> Interval:
        """Enclosure of :math:`e^{-D h}` for the dilution held over the last interval."""
        rate = np.full(u.shape[:-1], self.system.dilution) if self.system.dilution is not None else u[..., 0]
        if np.any(rate < 0):
            raise DataError(f"u: expected a nonnegative dilution rate, got {float(np.min(rate))!r}")
        decay: Interval = np.exp(Interval(rate, rate) * (-self._period))
        return decay[..., None]

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        internal = state.internal
        z = Interval._raw(internal["z_lower"], internal["z_upper"])
        if internal["started"]:
            decay = self._decay(internal["u"])
            z = decay * z + (1.0 - decay) * self._z_inlet
        measured = Interval._wrap(y) - self._noise
        floor = 0.0 if self.system.nonnegative else -np.inf
        measured = Interval._raw(np.maximum(measured.lower, floor), measured.upper)
        seen = self._gain @ measured
        if self.system.nonnegative:
            z = Interval._raw(np.maximum(z.lower, seen.lower), z.upper)
        unmeasured = z - seen
        unmeasured = Interval._raw(np.maximum(unmeasured.lower, floor), unmeasured.upper)
        consistent = np.asarray(internal["consistent"])[..., 0] > 0
        consistent = consistent & np.all(measured.lower <= measured.upper, -1) & np.all(z.lower <= z.upper, -1)
        lower = np.empty((*np.broadcast_shapes(y.shape[:-1], z.lower.shape[:-1]), self.n))
        upper = np.empty_like(lower)
        lower[..., self.system.measured], upper[..., self.system.measured] = measured.lower, measured.upper
        lower[..., self.system.unmeasured], upper[..., self.system.unmeasured] = unmeasured.lower, unmeasured.upper
        lower = np.where(consistent[..., None], lower, -np.inf)
        upper = np.where(consistent[..., None], upper, np.inf)
        internal = {"z_lower": z.lower, "z_upper": z.upper, "started": True, "u": u}
        internal["consistent"] = consistent[..., None].astype(float)
        return ObserverState(lower, upper, internal=internal)

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record (see :meth:`Observer.run`), with consistency in ``meta``.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times of the record, every ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Measured components (a leading axis of Monte Carlo runs).
        u : array_like, shape (T, 1) or (M, T, 1), optional
            The dilution rate, held between samples (only for a system built with ``dilution=None``).

        Returns
        -------
        Estimate
            ``meta`` holds ``consistent`` (bool, or a list per run) and ``inconsistent_from`` (the
            first time the record contradicts the model — a negative concentration, or invariants
            below what the measurements allow —, None when it never does); from then on the rows
            are infinite, and the run warns.
        """
        times, ys, us = self._signals(t, y, u)
        estimate, extras = self._loop(times, ys, us, collect=("consistent",))
        flags = extras["consistent"][..., 0] > 0
        starts = record_consistency(estimate, flags)
        if not flags.all():
            warnings.warn(
                f"the record contradicts the model from t = {next(s for s in starts if s is not None):.4g}: check "
                "the yields, the inlet, the dilution and the noise bound",
                RuntimeWarning,
                stacklevel=3,
            )
        return estimate
