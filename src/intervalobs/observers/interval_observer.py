r"""The general-purpose interval observer (framer) for LTI systems with interval uncertainty.

On the sound sampled model :math:`x_{k+1} \in (\Phi \pm \delta\Phi)x_k + (\Gamma \pm \delta\Gamma)u_k
+ [c \pm r]` (:mod:`intervalobs.design.discretization`; a discrete-time system is its own sampled
model) and in coordinates :math:`z = Tx`, with :math:`M = T(\Phi - LC)T^{-1}`, the box
:math:`[z_c \pm z_r]` is propagated as

.. math::

    z_c^+ &= M z_c + TLy_k + T\Gamma u_k + T(c - LF v_c), \\
    z_r^+ &= |M| z_r + |T|\big(r + |LF| v_r + \delta\Gamma|u_k| + \delta\Phi(|x_c| + x_r)\big),

with :math:`x_c = T^{-1}z_c`, :math:`x_r = |T^{-1}|z_r`. This is the framer
:math:`\overline{z}^+ = M^+\overline{z} - M^-\underline{z} + \dots` of seed 002 (39)–(40) written in
centre–radius form, valid for any sign pattern of :math:`M`, with the interval term
:math:`\delta\Phi\,x` bounded exactly (seed 002, Lemma A.1). Each step follows from the inclusion of
the previous one, so the bounds hold for every admissible noise realisation, inside the steps too.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.cooperative import FramerDesign, design_framer, framer_matrices
from ..design.discretization import SampledModel, sampled_model
from ..errors import DataError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN
from ..recursion import LinearRecursion
from ..systems.lti import Bounds, LTISystem
from ..validation import as_box, as_matrix, as_vector, check_no_kwargs
from .base import Observer, ObserverState

__all__ = ["IntervalObserver"]

FloatArray = NDArray[np.float64]


class IntervalObserver(Observer):
    """Interval observer for an :class:`~intervalobs.systems.LTISystem`, continuous or discrete.

    Parameters
    ----------
    system : LTISystem
        The model (with optional interval ``dA``).
    bounds : Bounds
        Boxes of ``x0``, ``w`` and ``v``.
    L : array_like, shape (n, p)
        Gain of the sampled model.
    T : array_like, shape (n, n), optional
        Coordinate change ``z = T x`` (default identity).
    h : float, optional
        Sampling period; required for a continuous-time system (measurements arrive every ``h``).

    Raises
    ------
    DesignError
        When the width system ``|T(Φ - LC)T⁻¹| + |T|δΦ|T⁻¹|`` is not stable (spectral radius ≥ 1).
    """

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        L: ArrayLike,
        T: ArrayLike | None = None,
        h: float | None = None,
    ) -> None:
        if not isinstance(system, LTISystem):
            raise TypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise TypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        self.system = system
        self.bounds = bounds.for_system(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.model: SampledModel = sampled_model(system, self.bounds, h)
        self.h = self.model.h if system.continuous else float(system.dt or 1.0)
        self.L = as_matrix("L", L, (self.n, self.p))
        self.T = np.eye(self.n) if T is None else as_matrix("T", T, (self.n, self.n))
        if np.linalg.cond(self.T) > 1e12:
            raise DimensionError(
                f"T: expected an invertible coordinate change, got cond(T) = {np.linalg.cond(self.T):.3g}"
            )
        self.T_inv = np.linalg.inv(self.T)
        width_matrix, self.M = framer_matrices(self.model, system.C, self.L, self.T)
        self.spectral_radius = float(np.max(np.abs(np.linalg.eigvals(width_matrix))))
        if not self.spectral_radius < 1:
            raise DesignError(
                f"L, T: expected a stable width system, got spectral radius {self.spectral_radius:.6g} >= 1 "
                "of |T(Φ - LC)T⁻¹| + |T|δΦ|T⁻¹|; use IntervalObserver.design to find a gain"
            )
        assert self.bounds.v is not None
        v_center = 0.5 * (self.bounds.v[0] + self.bounds.v[1])
        v_radius = 0.5 * (self.bounds.v[1] - self.bounds.v[0])
        F = system.F
        self._abs_M = np.abs(self.M)
        self._abs_T = np.abs(self.T)
        self._abs_T_inv = np.abs(self.T_inv)
        self._TL = self.T @ self.L
        self._TGamma = self.T @ self.model.Gamma
        self._offset = self.T @ (self.model.noise_center - self.L @ F @ v_center)
        self._radius_input = self._abs_T @ (self.model.noise_radius + np.abs(self.L @ F) @ v_radius)
        self._K_phi = self._abs_T @ self.model.dPhi
        self._K_gamma = self._abs_T @ self.model.dGamma
        self._center_recursion = LinearRecursion(self.M)
        self._radius_recursion = LinearRecursion(self._abs_M)
        self._radius_cache = np.empty((0, self.n))
        # Worst-case linear accumulation of rounding through a recursion contracting at rate ρ, amplified
        # at most by the conditioning of the fast evaluation.
        amplification = max(self._center_recursion.error_factor, self._radius_recursion.error_factor)
        self.margin = max(
            ROUNDING_MARGIN, 8 * self.n * np.finfo(float).eps * amplification / (1 - self.spectral_radius)
        )
        self.design_result: FramerDesign | None = None

    @classmethod
    def design(cls, system: LTISystem, bounds: Bounds, h: float | None = None, **options: Any) -> IntervalObserver:
        """Find a gain and coordinates automatically and build the observer.

        Parameters
        ----------
        system : LTISystem
            The model.
        bounds : Bounds
            Boxes of ``x0``, ``w`` and ``v``.
        h : float, optional
            Sampling period (continuous time only).
        **options
            ``candidates``: dict of named coordinate changes ``T`` to try instead of the defaults
            (identity, real modal basis, pole-placed eigenvectors).

        Returns
        -------
        IntervalObserver
            With ``design_result`` holding the verified :class:`~intervalobs.design.cooperative.FramerDesign`.

        Raises
        ------
        DesignError
            When ``(A, C)`` is not detectable or no tried coordinates give a stable width system.
        """
        check_no_kwargs("IntervalObserver.design", options, ("candidates",))
        if not isinstance(system, LTISystem):
            raise TypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        full = bounds.for_system(system)
        model = sampled_model(system, full, h)
        assert full.v is not None
        v_radius = 0.5 * (full.v[1] - full.v[0])
        result = design_framer(model, system.C, system.F, v_radius, options.get("candidates"))
        observer = cls(system, bounds, result.L, result.T, h)
        observer.design_result = result
        return observer

    # -- protocol ------------------------------------------------------------------------------
    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at the first sample from the box of ``x(t_0)`` (default ``bounds.x0``).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, optional
            Prior box of the initial state.

        Returns
        -------
        ObserverState
        """
        if x0_lower is None or x0_upper is None:
            lo, hi = self.bounds.x0
        else:
            lo, hi = as_box("x0", (x0_lower, x0_upper), self.n)
        z_c = self.T @ (0.5 * (lo + hi))
        z_r = self._abs_T @ (0.5 * (hi - lo))
        lower, upper = self._x_box(z_c, z_r)
        return ObserverState(lower, upper, internal={"z_center": z_c, "z_radius": z_r})

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Propagate the box from ``t_k`` to ``t_{k+1}`` with ``y_k`` and ``u_k``.

        Parameters
        ----------
        state : ObserverState
            State at ``t_k``.
        y : array_like, shape (p,) or (M, p)
            Measurement at ``t_k``.
        u : array_like, shape (m,) or (M, m), optional
            Known input over ``[t_k, t_{k+1})``.

        Returns
        -------
        ObserverState
        """
        yk = as_vector("y", y, self.p) if np.ndim(y) <= 1 else np.asarray(y, dtype=float)
        if yk.shape[-1] != self.p or not np.all(np.isfinite(yk)):
            raise DataError(f"y: expected finite values with last dimension {self.p}, got shape {yk.shape}")
        uk = np.zeros(self.m) if u is None else np.asarray(u, dtype=float)
        z_c, z_r = state.internal["z_center"], state.internal["z_radius"]
        z_c, z_r = self._advance(z_c, z_r, yk, uk)
        lower, upper = self._x_box(z_c, z_r)
        return ObserverState(lower, upper, internal={"z_center": z_c, "z_radius": z_r})

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times (spacing ``h`` for a continuous-time system).
        y : array_like, shape (T, p) or (M, T, p)
            Measurements; a leading axis holds Monte Carlo runs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs, held over each sampling interval.

        Returns
        -------
        Estimate
        """
        times, ys, us = self._signals(t, y, u)
        if self.system.continuous and times.size > 1:
            spacing = np.diff(times)
            if np.max(np.abs(spacing - self.h)) > 1e-9 * self.h:
                raise DataError(
                    f"t: expected uniform spacing h = {self.h:g} (the design's sampling period), "
                    f"got spacings in [{spacing.min():g}, {spacing.max():g}]"
                )
        state = self.init()
        z_c0, z_r0 = state.internal["z_center"], state.internal["z_radius"]
        if self.model.uncertain:
            z_c = np.empty((*ys.shape[:-1], self.n))
            z_r = np.empty_like(z_c)
            c, r = np.broadcast_to(z_c0, z_c[..., 0, :].shape), np.broadcast_to(z_r0, z_c[..., 0, :].shape)
            for k in range(times.size):
                z_c[..., k, :], z_r[..., k, :] = c, r
                if k + 1 < times.size:
                    c, r = self._advance(c, r, ys[..., k, :], us[..., k, :])
        else:
            drive = ys[..., :-1, :] @ self._TL.T + us[..., :-1, :] @ self._TGamma.T + self._offset
            z_c = self._center_recursion(z_c0, drive)
            z_r = np.broadcast_to(self._default_radius(times.size), z_c.shape)
        lower, upper = self._x_box(z_c, z_r)
        return Estimate(times, lower, upper, meta=self.meta())

    # -- internals -------------------------------------------------------------------------------
    def _default_radius(self, steps: int) -> FloatArray:
        """Radii from the design's initial box: data-independent, so computed once and cached."""
        if self._radius_cache.shape[0] < steps:
            z_r0 = self._abs_T @ (0.5 * (self.bounds.x0[1] - self.bounds.x0[0]))
            constant = np.broadcast_to(self._radius_input, (steps - 1, self.n))
            self._radius_cache = self._radius_recursion(z_r0, constant)
        return self._radius_cache[:steps]

    def _advance(self, z_c: FloatArray, z_r: FloatArray, y: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        radius_input = self._radius_input
        if self.model.uncertain:
            x_abs = np.abs(z_c @ self.T_inv.T) + z_r @ self._abs_T_inv.T
            radius_input = radius_input + x_abs @ self._K_phi.T + np.abs(u) @ self._K_gamma.T
        new_c = z_c @ self.M.T + y @ self._TL.T + u @ self._TGamma.T + self._offset
        new_r = z_r @ self._abs_M.T + radius_input
        return new_c, new_r

    def _x_box(self, z_c: FloatArray, z_r: FloatArray) -> tuple[FloatArray, FloatArray]:
        x_c = z_c @ self.T_inv.T
        x_r = z_r @ self._abs_T_inv.T
        pad = self.margin * ((np.abs(z_c) + z_r) @ self._abs_T_inv.T) + np.finfo(float).tiny
        return x_c - x_r - pad, x_c + x_r + pad

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`."""
        info: dict[str, Any] = {
            "method": "IntervalObserver",
            "L": self.L.tolist(),
            "T": self.T.tolist(),
            "spectral_radius": self.spectral_radius,
            "h": self.h,
            "transient_s": 0.0,
        }
        if self.design_result is not None:
            info["coordinates"] = self.design_result.coordinates
            info["steady_width"] = (2 * self.design_result.steady_radius).tolist()
        return info
