r"""Tighter sound bounds without LPs: intersect observers run in parallel, and contract with the output.

Three sound operations, each kept only where it pays (measured in docs/benchmarks.md):

* **Intersection of members.** Every member's box contains :math:`x_k`, so their intersection does.
  Members that are framers (:class:`~intervalobs.observers.IntervalObserver` with ``method="framer"``)
  are restarted from the intersected box at every step: a framer step maps *any* box that contains
  :math:`x_k` to a box that contains :math:`x_{k+1}`, so the restart is sound and each member profits
  from the others. Other members (the error tube, zonotopes, ...) are intersected pointwise only: their
  recursions rely on their own history.
* **Output contraction.** :math:`x_k` also lies in :math:`\{x : y_k - Cx \in F[\underline v, \overline v]\}`.
  A forward–backward contractor on each output row (the exact box hull of one row's strip inside a box,
  repeated ``sweeps`` times over the rows) intersects the box with it before the members take their
  step. Each computed end is widened by :func:`~intervalobs.interval.inflate`.

The rows of :meth:`IntersectionObserver.run` are, as for every observer, the boxes of :math:`x_k` given
:math:`y_0 \dots y_{k-1}`; :meth:`IntersectionObserver.step` also returns the contracted box of
:math:`x_k` (which uses :math:`y_k`) in ``internal["filtered_lower"/"filtered_upper"]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.cooperative import coordinate_candidates
from ..errors import ArgumentTypeError, DataError, DesignError, DimensionError, InconsistentDataError
from ..interval import inflate, matvec_bounds
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem
from ..systems.sampling import sampled_model
from .base import Observer, ObserverState, options_after_bounds
from .interval_observer import IntervalObserver

__all__ = ["IntersectionObserver", "output_contraction"]

FloatArray = NDArray[np.float64]


def output_contraction(
    lower: FloatArray,
    upper: FloatArray,
    C: FloatArray,
    y_lower: FloatArray,
    y_upper: FloatArray,
    sweeps: int = 1,
    *,
    allow_empty: bool = False,
) -> tuple[FloatArray, FloatArray]:
    r"""Contract the box ``[lower, upper]`` with :math:`\{x : y_{lo} \le Cx \le y_{hi}\}` (sound).

    For each row :math:`c_i` and each component :math:`j` with :math:`c_{ij} \ne 0`,
    :math:`c_{ij}x_j \in [y_{lo,i}, y_{hi,i}] - \sum_{l \ne j} c_{il}[x_l]`; rows are applied in turn
    (Gauss–Seidel), ``sweeps`` times. For one row this is the exact box hull of the strip inside the box.

    Parameters
    ----------
    lower, upper : numpy.ndarray, shape (..., n)
        The box (leading axes: runs).
    C : numpy.ndarray, shape (p, n)
        Output matrix.
    y_lower, y_upper : numpy.ndarray, shape (..., p)
        Bounds of :math:`Cx` implied by the measurement and the noise box.
    sweeps : int
        Passes over the rows.
    allow_empty : bool
        Return an empty box (lower > upper somewhere) where the measurement contradicts the box and
        the noise bounds, instead of raising.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., n)
        The contracted box.

    Raises
    ------
    InconsistentDataError
        Where the contracted box is empty (the measurement contradicts the box and the noise bounds),
        unless ``allow_empty``.
    """
    lo, hi = np.array(lower, dtype=float), np.array(upper, dtype=float)
    for _ in range(sweeps):
        for i in range(C.shape[0]):
            row = C[i]
            terms_lo = np.minimum(row * lo, row * hi)
            terms_hi = np.maximum(row * lo, row * hi)
            sum_lo, sum_hi = terms_lo.sum(axis=-1), terms_hi.sum(axis=-1)
            scale = np.abs(terms_lo).sum(axis=-1) + np.abs(terms_hi).sum(axis=-1)
            for j in np.flatnonzero(row):
                rest_lo = sum_lo - terms_lo[..., j]
                rest_hi = sum_hi - terms_hi[..., j]
                size = scale + np.abs(y_lower[..., i]) + np.abs(y_upper[..., i])
                num_lo, num_hi = inflate(y_lower[..., i] - rest_hi, y_upper[..., i] - rest_lo, scale=size)
                a, b = num_lo / row[j], num_hi / row[j]
                new_lo, new_hi = np.minimum(a, b), np.maximum(a, b)
                new_lo, new_hi = inflate(new_lo, new_lo)[0], inflate(new_hi, new_hi)[1]
                lo[..., j] = np.maximum(lo[..., j], new_lo)
                hi[..., j] = np.minimum(hi[..., j], new_hi)
    if not allow_empty and np.any(lo > hi):
        raise InconsistentDataError(
            "y: the measurement is inconsistent with the state box and the noise bounds (empty set)"
        )
    return lo, hi


class IntersectionObserver(Observer):
    """Intersection of several sound observers, with framer restarts and output contraction.

    Parameters
    ----------
    members : sequence of Observer
        Sound observers of the same system (same ``n``, ``p``, ``m``); framers are restarted from the
        intersected box at every step.
    system : LTISystem
        The model (for the output contraction).
    bounds : Bounds
        Its boxes (``x0`` and ``v`` are used).
    contract : bool
        Apply the output contraction (default True).
    sweeps : int
        Passes of the contractor over the output rows (1 is exact for one output).
    """

    summary_fields = ("members", "contract")

    def __init__(
        self,
        members: Sequence[Observer],
        system: LTISystem,
        bounds: Bounds,
        contract: bool = True,
        sweeps: int = 1,
    ) -> None:
        if not members:
            raise DimensionError("members: expected at least one observer, got none")
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        for obs in members:
            if (obs.n, obs.p, obs.m) != (system.n, system.p, system.m):
                raise DimensionError(
                    f"members: expected observers with (n, p, m) = {(system.n, system.p, system.m)}, "
                    f"got {(obs.n, obs.p, obs.m)}"
                )
        periods = {obs.h for obs in members}
        if len(periods) > 1:
            raise DataError(f"members: expected one sampling period, got {sorted(map(str, periods))}")
        self.members = list(members)
        self.h = periods.pop()
        self.system = system
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.contract = bool(contract)
        self.sweeps = int(sweeps)
        self._fv_lo, self._fv_hi = matvec_bounds(system.F, self.bounds.v[0], self.bounds.v[1])
        self._restart = [isinstance(o, IntervalObserver) and o.method == "framer" for o in self.members]

    @classmethod
    @options_after_bounds("h", "extra", "contract", "sweeps", "max_members")
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        h: float | None = None,
        extra: Sequence[Observer] = (),
        contract: bool = True,
        sweeps: int = 1,
        max_members: int = 4,
    ) -> IntersectionObserver:
        """Framers in every candidate coordinate system (one LP gain each), intersected and contracted.

        Parameters
        ----------
        system : LTISystem
            The model.
        bounds : Bounds
            Boxes of ``x0``, ``w``, ``v``.
        h : float, optional
            Sampling period (continuous time).
        extra : sequence of Observer
            Observers to add as members (e.g. the error tube, a zonotopic observer).
        contract : bool
            Apply the output contraction.
        sweeps : int
            Passes of the contractor over the output rows.
        max_members : int
            Keep the framers with the smallest steady radius bound.

        Returns
        -------
        IntersectionObserver

        Raises
        ------
        DesignError
            When no candidate coordinates give a stable framer.
        """
        full = bounds.resolve(system)
        model = sampled_model(system, full, h)
        v_radius = full.radius("v")
        found: list[tuple[float, IntervalObserver]] = []
        for name, T in coordinate_candidates(model, system.C, system.F, v_radius).items():
            try:
                obs = IntervalObserver.design(system, full, h=h, method="framer", candidates={name: T})
            except DesignError:
                continue
            assert obs.design_result is not None
            found.append((float(np.sum(obs.design_result.steady_radius)), obs))
        if not found:
            raise DesignError("IntersectionObserver.design: no candidate coordinates give a stable framer")
        found.sort(key=lambda item: item[0])
        members: list[Observer] = [obs for _, obs in found[: int(max_members)]]
        members.extend(extra)
        return cls(members, system, full, contract, sweeps)

    # -- protocol ------------------------------------------------------------------------------
    @shared_docs
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample: every member started from the prior box.

        %(prior_box)s
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        states = [obs.init(lo, hi) for obs in self.members]
        lower, upper = self._intersect(states)
        return ObserverState(lower, upper, internal={"members": states})

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Contract with ``y_k``, restart the framers from the intersection, step every member.

        ``internal["filtered_lower"/"filtered_upper"]`` of the result: the box of ``x_k`` given ``y_0 … y_k``.
        """
        yk, uk = y, u
        lead = np.broadcast_shapes(state.lower.shape[:-1], yk.shape[:-1], uk.shape[:-1])  # runs of a batched y or u
        lo, hi = np.broadcast_to(state.lower, (*lead, self.n)), np.broadcast_to(state.upper, (*lead, self.n))
        if self.contract:
            lo, hi = output_contraction(lo, hi, self.system.C, yk - self._fv_hi, yk - self._fv_lo, self.sweeps)
        new_states = []
        for obs, member, restart in zip(self.members, state.internal["members"], self._restart):
            if restart:
                member = self._restarted(obs, member, lo, hi)  # type: ignore[arg-type]
            new_states.append(obs._step(member, yk, uk))
        lower, upper = self._intersect(new_states)
        return ObserverState(lower, upper, internal={"members": new_states, "filtered_lower": lo, "filtered_upper": hi})

    # -- internals -------------------------------------------------------------------------------
    @staticmethod
    def _restarted(obs: IntervalObserver, member: ObserverState, lo: FloatArray, hi: FloatArray) -> ObserverState:
        """The framer's z-box intersected with the hull of ``T·[lo, hi]`` (both contain ``T x_k``)."""
        z_c, z_r = member.internal["z_center"], member.internal["z_radius"]
        t_lo, t_hi = matvec_bounds(obs.T, lo, hi)
        t_lo, t_hi = inflate(t_lo, t_hi, scale=np.abs(t_lo) + np.abs(t_hi))
        z_lo = np.maximum(z_c - z_r, t_lo)
        z_hi = np.minimum(z_c + z_r, t_hi)
        z_hi = np.maximum(z_hi, z_lo)
        # centre–radius rounding: widen the radius by the rounding of the midpoint
        new_c = 0.5 * (z_lo + z_hi)
        _, new_r = inflate(0.0, 0.5 * (z_hi - z_lo), scale=np.abs(z_lo) + np.abs(z_hi))
        # keep the member's own numbers where the intersection does not shrink its box
        shrunk = np.any(new_r < z_r, axis=-1, keepdims=True)
        internal = dict(member.internal)
        internal["z_center"] = np.where(shrunk, new_c, z_c)
        internal["z_radius"] = np.where(shrunk, np.minimum(new_r, z_r + np.abs(new_c - z_c)), z_r)
        return ObserverState(lo, hi, internal=internal)

    @staticmethod
    def _intersect(states: Sequence[ObserverState]) -> tuple[FloatArray, FloatArray]:
        lower = np.max(np.stack([np.asarray(s.lower) for s in states]), axis=0)
        upper = np.min(np.stack([np.asarray(s.upper) for s in states]), axis=0)
        if np.any(lower > upper):
            raise DataError("members: the observers' boxes do not intersect; one of them is not sound")
        return lower, upper

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
        """
        return {
            "method": "IntersectionObserver",
            "members": [type(o).__name__ for o in self.members],
            "restarted": self._restart,
            "contract": self.contract,
            "sweeps": self.sweeps,
            "transient_s": 0.0,
        }
