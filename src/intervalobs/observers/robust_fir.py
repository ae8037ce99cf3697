r"""The FIR bank under an interval :math:`\Delta A`: LP-free, data-dependent boxes at observer cost.

:class:`~intervalobs.observers.fir.FiniteMemoryObserver` evaluates a bank of linear window filters
:math:`\hat x_k = \sum_j K_j y_{s+j} + \sum_l M_l u_{s+l} + d` (:math:`s = k - N`) of a point model. Here
the model is the linearisation :func:`~intervalobs.systems.sampling.delta_linearisation` (shared with
:class:`~intervalobs.observers.robust_hull.RobustHullEstimator`) around the centre :math:`\Delta A_c` of the
box, :math:`\delta = \Delta A - \Delta A_c`:

.. math::

    x_{j+1} = \Phi_c x_j + \Gamma_c u_j + G\eta_j + e_j,\qquad
    e_j = \sum_{(a,b)} \delta_{ab}\,(M_{ab}x_j + N_{ab}u_j) + \varrho_j,\qquad
    |\varrho_j| \le R_x|x_j| + R_u|u_j|

(discrete time: :math:`M_{ab} = e_ae_b^\top`, :math:`N = 0`, :math:`R = 0`; continuous time: the
Fréchet derivatives of the sampled exponential and their proven second-order remainder, with the noise
box of the sound sampled model, valid for every :math:`\Delta A` of the box). The error of a filter is
the point-model error of the FIR module plus :math:`\sum_{l<N} D_l e_{s+l}`, with the same
:math:`D_l`. Its :math:`\delta` part is **bilinear** in the one unknown :math:`\delta` (the same at
every step) and the window's states; with the observer's own boxes :math:`x_{s+l} \in \hat x_l \pm
h_l` (midpoints and half-widths; :math:`\bar x_l = |\hat x_l| + h_l`):

.. math::

    \Big|\sum_l D_l e_{s+l}\Big| \le \sum_{(a,b)} D_{ab}\Big(\Big|\sum_l D_l(M_{ab}\hat x_l + N_{ab}u_{s+l})\Big|
        + \sum_l |D_lM_{ab}|\,h_l\Big) + \sum_l |D_l|\,(R_x\bar x_l + R_u|u_{s+l}|),

where :math:`D_{ab}` is the radius of entry :math:`(a, b)` of the box. The first sum keeps the shared
:math:`\delta`: the window's midpoints may cancel (it is the robust window LP's :math:`\delta` column
evaluated at its certificate), and only the box *widths*, not the states, enter elementwise. This term is
added to each filter's radius at each step: the width follows the data through the certificates, the
boxes of the window and the state's size, and no LP runs online.

**Rounding.** :math:`D_l` carries the rounding bound :math:`\gamma_D` of the FIR module;
:math:`D_lM_{ab}` adds ``n`` roundings, the online sums ``N(3n + 2m) + n_δ + n`` more, and the
midpoint/half-width split two. All are bounded by :math:`2\gamma_\Delta\sum_l \mathrm{mag}(D_l)
\big((\sum D_{ab}|M_{ab}| + R_x)\bar x_l + (\sum D_{ab}|N_{ab}| + R_u)|u_{s+l}|\big)` with
:math:`\gamma_\Delta = \gamma_D + (N(3n + 2m) + n_\delta + n + 8)\,\varepsilon` and
:math:`\mathrm{mag}(D_l)` the FIR module's magnitude bound of :math:`D_l` (factor 2 to spare), which is
added to the radius.

The box is intersected with the interval prediction of the previous box through
:math:`(\Phi \pm \delta\Phi, \Gamma \pm \delta\Gamma)` and with a sound fallback (default the
:class:`~intervalobs.observers.interval_observer.IntervalObserver` designed for the same model), so it
is never wider than that observer on the same data.

**The bank.** :meth:`RobustFiniteMemoryObserver.learn` takes the certificates that
:meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>` learns for the
centre model and adds the filter minimising the worst-case radius with the :math:`\Delta A` term charged
at a given state size (``FiniteMemoryObserver.design``'s LP with a larger noise weight). Any weights
are sound; the bank only decides how tight.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.fir_bank import _worst_case_gains
from ..errors import AssumptionError, DataError
from ..systems.bounds import Bounds, ResolvedBounds
from ..systems.lti import LTISystem
from ..systems.sampling import delta_linearisation
from .base import Observer, options_after_bounds
from .fir import FiniteMemoryObserver
from .interval_observer import IntervalObserver

__all__ = ["RobustFiniteMemoryObserver"]

FloatArray = NDArray[np.float64]
_EPS = float(np.finfo(float).eps)


class RobustFiniteMemoryObserver(FiniteMemoryObserver):
    r"""A bank of FIR filters whose radii cover an interval ``ΔA`` (module docstring), LP-free online.

    Build it with :meth:`learn` (certificates of the centre model plus a robust worst-case filter) or
    :meth:`design` (the robust worst-case filter only). The constructor takes any weights, like
    :class:`~intervalobs.observers.fir.FiniteMemoryObserver`, for a model with an interval ``dA``.

    Parameters
    ----------
    system : LTISystem
        Model with an interval ``dA``; continuous time needs ``h``.
    bounds : Bounds
        Initial-state and noise boxes.
    gains : numpy.ndarray, shape (n, B, N, p) or (n, N, p); ``N + 1`` instead of ``N`` when filtered
        Weights of the filters (see :class:`~intervalobs.observers.fir.FiniteMemoryObserver`).
    fallback : Observer
        Sound observer of the same model run in parallel; its box is intersected with the filters'.
    h : float, optional
        Sampling period of a continuous-time system.
    lp_seconds : float
        Design-time LP cost (recorded in :meth:`meta`).
    filtered : bool
        Whether the last weight multiplies :math:`y_k`.
    """

    covers_dA = True

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        gains: ArrayLike,
        fallback: Observer,
        h: float | None = None,
        lp_seconds: float = 0.0,
        filtered: bool = False,
    ) -> None:
        if system.dA is None:
            raise AssumptionError("system.dA: expected an interval ΔA (without it, use FiniteMemoryObserver)")
        super().__init__(system, bounds, gains, fallback, h=h, lp_seconds=lp_seconds, filtered=filtered)
        model = delta_linearisation(system, self.bounds, self.h if system.continuous else None)
        n, m, big_n = self.n, self.m, self.window
        radius = np.array([model.radius[a, b] for a, b in model.entries])  # D_ab of the uncertain entries
        nd = radius.size
        d_mats = self._bank.d_mats  # (N, n, B, n): D_l of filter (i, b)
        filters = n * d_mats.shape[2]
        d_flat = np.moveaxis(d_mats, 0, 2).reshape(filters, big_n, n)  # (F, N, n), filter order (i, b)
        mag = np.moveaxis(self._bank.d_mag, 0, 2).reshape(filters, big_n, n)
        q_x = np.einsum("flq,eqr->lrfe", d_flat, model.M)  # D_l M_ab: (N, n, F, n_δ)
        q_u = np.einsum("flq,eqr->lrfe", d_flat, model.N)  # D_l N_ab: (N, m, F, n_δ)
        # centre terms: (x̂_0 … x̂_{N-1}, u_0 … u_{N-1}) @ weights -> (F n_δ), one product per step
        self._centre_weights_dA = np.concatenate(
            [q_x.reshape(big_n * n, filters * nd), q_u.reshape(big_n * m, filters * nd)]
        )
        self._entry_radius = radius
        gamma = self._bank.gamma_d + (big_n * (3 * n + 2 * m) + nd + n + 8) * _EPS
        spread_x = np.einsum("e,eqr->qr", radius, np.abs(model.M))  # Σ D_ab |M_ab|
        spread_u = np.einsum("e,eqr->qr", radius, np.abs(model.N))
        half_w = np.einsum("lrfe,e->lrf", np.abs(q_x), radius).reshape(big_n * n, filters)
        mag_w = np.einsum("flq,qr->lrf", np.abs(d_flat), model.R_x)
        mag_w += 2 * gamma * np.einsum("flq,qr->lrf", mag, spread_x + model.R_x)
        u_w = np.einsum("flq,qr->lrf", np.abs(d_flat), model.R_u)
        u_w += 2 * gamma * np.einsum("flq,qr->lrf", mag, spread_u + model.R_u)
        # spread terms: (h_0 … h_{N-1}, x̄_0 … x̄_{N-1}, |u_0| … |u_{N-1}|) @ weights -> (F,)
        self._spread_weights_dA = np.concatenate(
            [half_w, mag_w.reshape(big_n * n, filters), u_w.reshape(big_n * m, filters)]
        )

    @classmethod
    @options_after_bounds("window", "h", "fallback", "state_size")
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        window: int = 10,
        h: float | None = None,
        fallback: Observer | None = None,
        state_size: ArrayLike | None = None,
    ) -> RobustFiniteMemoryObserver:
        """One filter per component: the worst-case LP of the centre model with the ``ΔA`` term charged.

        Parameters
        ----------
        system : LTISystem
            Model with an interval ``dA``.
        bounds : Bounds
            Initial-state and noise boxes.
        window : int
            Memory ``N``.
        h : float, optional
            Sampling period of a continuous-time system.
        fallback : Observer, optional
            Sound observer to intersect with; default :meth:`IntervalObserver.design` of ``system``.
        state_size : array_like, shape (n,), optional
            Typical magnitude of the states at which the ``ΔA`` term is charged (default: the largest
            magnitude of the initial box).

        Returns
        -------
        RobustFiniteMemoryObserver
        """
        full, centre = _resolve(system, bounds)
        gains, elapsed = _robust_gains(system, centre, full, window, h, state_size)
        if fallback is None:
            fallback = IntervalObserver.design(system, full, h=h)
        return cls(system, full, gains, fallback, h=h, lp_seconds=elapsed)

    @classmethod
    def learn(
        cls,
        system: LTISystem,
        bounds: Bounds,
        window: int = 10,
        records: int = 6,
        steps: int = 200,
        seed: int = 0,
        size: int | None = None,
        h: float | None = None,
        fallback: Observer | None = None,
        filtered: bool = False,
        state_size: ArrayLike | None = None,
        tolerance: float | None = None,
        selection: str = "random",
    ) -> RobustFiniteMemoryObserver:
        """A bank: the centre model's learned certificates plus the robust worst-case filter.

        Parameters
        ----------
        system : LTISystem
            Model with an interval ``dA`` whose centre has a stable sampled matrix.
        bounds : Bounds
            Initial-state and noise boxes.
        window, records, steps, seed : int
            As in :meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>`,
            on the centre model ``A + ΔA_c``.
        size : int, optional
            As in :meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>`.
        h : float, optional
            Sampling period of a continuous-time system.
        fallback : Observer, optional
            Sound observer to intersect with; default :meth:`IntervalObserver.design` of ``system``.
        filtered : bool
            As in :meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>`.
        state_size : array_like, shape (n,), optional
            State magnitude of the robust worst-case filter (see :meth:`design`).
        tolerance : float, optional
            As in :meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>`.
        selection : {"random", "cover"}
            As in :meth:`FiniteMemoryObserver.learn <intervalobs.observers.fir.FiniteMemoryObserver.learn>`.

        Returns
        -------
        RobustFiniteMemoryObserver
            ``meta()["bank"]`` is the number of filters per component.
        """
        full, centre = _resolve(system, bounds)
        if fallback is None:
            fallback = IntervalObserver.design(system, full, h=h)
        nominal = FiniteMemoryObserver.learn(
            centre,
            full,
            window,
            records,
            steps,
            seed,
            size,
            h=h,
            fallback=fallback,
            filtered=filtered,
            tolerance=tolerance,
            selection=selection,
        )
        robust, elapsed = _robust_gains(system, centre, full, window, h, state_size)
        if filtered:  # a predicted filter is a filtered one with no weight on y_k
            robust = np.concatenate([robust, np.zeros_like(robust[:, :1])], axis=1)
        gains = np.concatenate([robust[:, None], nominal.K], axis=1)
        return cls(system, full, gains, fallback, h=h, lp_seconds=elapsed + nominal.lp_seconds, filtered=filtered)

    def _delta_pad(self, rows_lo: FloatArray, rows_hi: FloatArray, us: FloatArray) -> FloatArray:
        """Bound of every filter's ``ΔA`` error (module docstring), shape (..., n B), from the window's boxes."""
        mid, half = 0.5 * (rows_lo + rows_hi), 0.5 * (rows_hi - rows_lo)
        big = np.maximum(np.abs(rows_lo), np.abs(rows_hi))
        lead = mid.shape[:-2]
        u = np.broadcast_to(us, (*lead, *us.shape[-2:])).reshape(*lead, -1)
        centre = np.concatenate([mid.reshape(*lead, -1), u], axis=-1) @ self._centre_weights_dA
        shared = np.abs(centre.reshape(*lead, self._bank.offset_flat.size, -1)) @ self._entry_radius
        spread = np.concatenate([half.reshape(*lead, -1), big.reshape(*lead, -1), np.abs(u)], axis=-1)
        return shared + spread @ self._spread_weights_dA

    def _bank_box(
        self, est: FloatArray, pad: FloatArray, rows_lo: FloatArray, rows_hi: FloatArray, us: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The point-model boxes of the bank with every radius enlarged by its ``ΔA`` error bound."""
        return super()._bank_box(est, pad + self._delta_pad(rows_lo, rows_hi, us), rows_lo, rows_hi, us)

    def _predict(self, lower: FloatArray, upper: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        """One-step interval prediction through ``Φ ± δΦ``, ``Γ ± δΓ`` and the noise box, inflated."""
        return self._model.image(lower, upper, u)

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            As :meth:`FiniteMemoryObserver.meta <intervalobs.observers.fir.FiniteMemoryObserver.meta>`, with
            ``method`` ``"RobustFiniteMemoryObserver"``.
        """
        return {**super().meta(), "method": "RobustFiniteMemoryObserver"}


def _resolve(system: LTISystem, bounds: Bounds) -> tuple[ResolvedBounds, LTISystem]:
    """The resolved bounds and the centre model ``A + ΔA_c`` (a point model) of a system with interval ``dA``."""
    if system.dA is None:
        raise AssumptionError("system.dA: expected an interval ΔA (without it, use FiniteMemoryObserver)")
    full = bounds.resolve(system)
    a_centre = system.A + 0.5 * (system.dA[0] + system.dA[1])
    centre = LTISystem(a_centre, system.C, B=system.B, E=system.E, F=system.F, dt=system.dt)
    return full, centre


def _robust_gains(
    system: LTISystem,
    centre: LTISystem,
    full: ResolvedBounds,
    window: int,
    h: float | None,
    state_size: ArrayLike | None,
) -> tuple[FloatArray, float]:
    """Worst-case weights of the centre model with the ``ΔA`` term ``Σ D_ab |M_ab| x̄`` charged as noise."""
    model = delta_linearisation(system, full, h if system.continuous else None)
    if state_size is None:
        size = np.maximum(np.abs(full.x0[0]), np.abs(full.x0[1]))
    else:
        size = np.asarray(state_size, dtype=float)
        if size.shape != (system.n,) or not np.all(np.isfinite(size)) or np.any(size < 0):
            raise DataError(f"state_size: expected {system.n} finite nonnegative values, got {state_size!r}")
    radius = np.array([model.radius[a, b] for a, b in model.entries])
    charge = np.einsum("e,eqr,r->q", radius, np.abs(model.M), size) + model.R_x @ size if radius.size else 0.0
    return _worst_case_gains(centre, full, window, h, extra=charge)
