r"""The general-purpose interval observer for LTI systems with interval uncertainty.

:class:`IntervalObserver` propagates a box whose centre is a Luenberger estimate on the sound sampled
model of the system; its radius follows the exact error tube (default) or the classical framer. The
equations are in the class docstring.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.cooperative import FramerDesign, design_framer, framer_matrices, is_detectable, unstable_vertex
from ..design.tube import BlockNorms, TubeDesign, abs_powers, coupling, design_tube_gain, tube_horizon, tube_stability
from ..errors import DesignError, DimensionError
from ..estimate import Estimate
from ..interval import inflate, recursion_margin
from ..recursion import LinearRecursion
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem
from ..systems.sampling import SampledModel, sampled_model
from ..validation import as_choice, as_matrix, check_no_kwargs
from .base import Observer, ObserverState

__all__ = ["METHODS", "IntervalObserver"]

FloatArray = NDArray[np.float64]

METHODS = ("tube", "framer")


class IntervalObserver(Observer):
    r"""Interval observer for an :class:`~intervalobs.systems.LTISystem`, continuous or discrete.

    Parameters
    ----------
    system : LTISystem
        The model (with optional interval ``dA``).
    bounds : Bounds
        Boxes of ``x0``, ``w`` and ``v``.
    L : array_like, shape (n, p)
        Gain of the sampled model.
    T : array_like, shape (n, n), optional
        Coordinate change ``z = T x`` in which the radius is propagated (default identity).
    h : float, optional
        Sampling period; required for a continuous-time system (measurements arrive every ``h``).
    method : {"tube", "framer"}
        Radius propagation (see Notes).
    blocks : sequence of int, optional
        Tube only: sizes (1 or 2) of consecutive blocks of ``z`` whose Euclidean norms the tube bounds
        (default: every block of size 1, a box; 2×2 blocks suit the rotations of a real modal basis).

    Raises
    ------
    DesignError
        When the radius recursion is not bounded with this gain: ``ρ(|M^J| + GδΦ) ≥ 1`` for the
        tube, ``ρ(|T(Φ - LC)T⁻¹| + |T|δΦ|T⁻¹|) ≥ 1`` for the framer.

    Notes
    -----
    Both methods run on the sound sampled model :math:`x_{k+1} \in (\Phi \pm \delta\Phi)x_k +
    (\Gamma \pm \delta\Gamma)u_k + [c \pm r]` (:mod:`intervalobs.systems.sampling`; a discrete-time
    system is its own sampled model) and propagate a box :math:`[\hat x \pm \rho]` whose centre is a
    Luenberger estimate, in coordinates :math:`z = Tx` with :math:`M = T(\Phi - LC)T^{-1}`:

    .. math:: z_c^+ = M z_c + TLy_k + T\Gamma u_k + T(c - LF v_c).

    They differ in the radius.

    ``method="tube"`` (default): the exact error tube of :mod:`intervalobs.design.tube` (in coordinates
    :math:`T`: :meth:`design` picks :math:`T = I`, or the real modal basis of :math:`\Phi - LC` for a slow
    error mode),

    .. math:: \rho_{k+1} = |M^{\ell}|\,\rho_{k+1-\ell} + \sum_{i<\ell} |M^i|\, d_{k-i},\quad
              \ell = \min(k+1, J),\quad d_k = |T|\big(r + |LF|v_r + \delta\Gamma|u_k| + \delta\Phi(|x_c| + x_r)\big),

    which only needs :math:`\rho(\Phi - LC) < 1` and is never wider than the framer with the same gain and
    coordinates. Outside the identity coordinates the :math:`\delta\Phi` terms are
    :math:`\min(|T|\delta\Phi|x_c|, S|z_c|) + S\rho` with :math:`S = \min(|T|\delta\Phi|T^{-1}|, B)` and
    :math:`B \ge |T\Delta\Phi T^{-1}|` (:meth:`~intervalobs.systems.sampling.SampledModel.dphi_in`): each
    block column of :math:`T\Delta\Phi T^{-1}z` is bounded by either;
    with ``blocks`` every :math:`|\cdot|` of :math:`z` quantities is a block norm
    (:class:`~intervalobs.design.tube.BlockNorms`).

    ``method="framer"``: the classical framer :math:`\overline{z}^+ = M^+\overline{z} - M^-\underline{z} + \dots`
    of seed 002 (39)–(40), written in centre–radius form and valid for any sign pattern of :math:`M`,

    .. math:: z_r^+ = |M| z_r + |T|\big(r + |LF| v_r + \delta\Gamma|u_k| + \delta\Phi(|x_c| + x_r)\big),

    with :math:`x_c = T^{-1}z_c`, :math:`x_r = |T^{-1}|z_r`; the interval term :math:`\delta\Phi\,x` is
    bounded exactly (seed 002, Lemma A.1). It needs a stable width system
    :math:`\rho(|M| + |T|\delta\Phi|T^{-1}|) < 1`.

    Each step follows from the inclusion of the previous one, so both hold for every admissible noise
    realisation, inside the sampling intervals too.
    """

    summary_fields = ("method", "spectral_radius", "horizon")

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        L: ArrayLike,
        T: ArrayLike | None = None,
        h: float | None = None,
        method: str = "tube",
        blocks: Sequence[int] | None = None,
    ) -> None:
        if not isinstance(system, LTISystem):
            raise TypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise TypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        as_choice("method", method, METHODS)
        self.system = system
        self.method = method
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.model: SampledModel = sampled_model(system, self.bounds, h)
        self._uncertain = self.model.uncertain  # data-dependent radii (interval ΔA): read once per step
        self.h = self.model.h if system.continuous else float(system.dt or 1.0)
        self.L = as_matrix("L", L, (self.n, self.p))
        self.T = np.eye(self.n) if T is None else as_matrix("T", T, (self.n, self.n))
        if np.linalg.cond(self.T) > 1e12:
            raise DimensionError(
                f"T: expected an invertible coordinate change, got cond(T) = {np.linalg.cond(self.T):.3g}"
            )
        self.T_inv = np.linalg.inv(self.T)
        self.norms = BlockNorms((1,) * self.n if blocks is None or len(blocks) == 0 else blocks)
        if self.norms.n != self.n or (method == "framer" and not self.norms.singleton):
            raise DimensionError(
                f"blocks: expected sizes 1 or 2 summing to n = {self.n} (tube only), got {self.norms.sizes}"
            )
        width_matrix, self.M = framer_matrices(self.model, system.C, self.L, self.T)
        v_center = self.bounds.centre("v")
        v_radius = self.bounds.radius("v")
        F = system.F
        self._abs_T = np.abs(self.T)
        self._abs_T_inv = np.abs(self.T_inv)
        self._TL = self.T @ self.L
        self._TGamma = self.T @ self.model.Gamma
        self._offset = self.T @ (self.model.noise_center - self.L @ F @ v_center)
        self._radius_input = self.norms.vector(self._abs_T @ (self.model.noise_radius + np.abs(self.L @ F) @ v_radius))
        self._back = self.norms.cols(self._abs_T_inv)  # x radius = back @ z radius
        self._K_phi = self._abs_T @ self.model.dPhi
        self._K_gamma = self._abs_T @ self.model.dGamma
        # Outside the identity coordinates: the coupling S >= blockwise |TΔΦT⁻¹| of the tube (design/tube.py).
        self._identity = self.norms.singleton and np.array_equal(self.T, np.eye(self.n))
        if method == "tube" and self._uncertain and not self._identity:
            self._S_phi = coupling(self.model, self.T, self.norms)
        self._center_recursion = LinearRecursion(self.M)
        self._radius_cache = np.empty((0, self.norms.count))
        if method == "framer":
            self.spectral_radius = float(np.max(np.abs(np.linalg.eigvals(width_matrix))))
            if not self.spectral_radius < 1:
                raise DesignError(
                    f"L, T: expected a stable width system, got spectral radius {self.spectral_radius:.6g} >= 1 "
                    "of |T(Φ - LC)T⁻¹| + |T|δΦ|T⁻¹|; use IntervalObserver.design to find a gain"
                )
            self._abs_M = np.abs(self.M)
            self._radius_recursion = LinearRecursion(self._abs_M)
            amplification = max(self._center_recursion.error_factor, self._radius_recursion.error_factor)
            contraction = self.spectral_radius
        else:
            horizon = tube_horizon(self.M, self.norms)
            if horizon is None:
                raise DesignError(
                    "L: expected Φ - LC to be Schur stable (and to contract within 4000 steps), "
                    f"got spectral radius {np.max(np.abs(np.linalg.eigvals(self.M))):.6g}"
                )
            self.horizon = horizon
            self.spectral_radius, _ = tube_stability(
                self.model, self.M, self._radius_input, horizon, self.T, self.norms
            )
            if not self.spectral_radius < 1:
                raise DesignError(
                    f"L: expected a bounded error tube, got ρ(|M^J| + GδΦ) = {self.spectral_radius:.6g} >= 1; "
                    "reduce dA or use IntervalObserver.design"
                )
            self._abs_powers = abs_powers(self.M, horizon + 1, self.norms)
            amplification = self._center_recursion.error_factor
            contraction = float(np.max(np.abs(np.linalg.eigvals(self.M))))
        self.margin = recursion_margin(self.n, amplification, contraction)
        self.design_result: FramerDesign | TubeDesign | None = None

    @classmethod
    def design(cls, system: LTISystem, bounds: Bounds, h: float | None = None, **options: Any) -> IntervalObserver:
        """Find a gain (and, for the framer, coordinates) automatically and build the observer.

        The tube (default) compares steady-state Kalman gains of the sampled model and the framer's
        LP gains by their steady error tube; the framer searches coordinates and gains by LP
        (:func:`~intervalobs.design.cooperative.design_framer`). Every result is verified by eigenvalues.

        Parameters
        ----------
        system : LTISystem
            The model.
        bounds : Bounds
            Boxes of ``x0``, ``w`` and ``v``.
        h : float, optional
            Sampling period (continuous time only).
        **options
            ``method``: ``"tube"`` (default) or ``"framer"``; ``candidates``: dict of named coordinate
            changes ``T`` for the framer search instead of the defaults (identity, real modal basis,
            pole-placed eigenvectors).

        Returns
        -------
        IntervalObserver
            With ``design_result`` holding the verified design.

        Raises
        ------
        DesignError
            When ``(A, C)`` is not detectable or no tried gain gives a bounded radius; when then a
            vertex of the ``dA`` box is found unstable (:func:`~intervalobs.design.cooperative.unstable_vertex`),
            the message names it and its spectral abscissa (spectral radius in discrete time).
        """
        check_no_kwargs("IntervalObserver.design", options, ("candidates", "method"))
        if not isinstance(system, LTISystem):
            raise TypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        method = as_choice("method", options.get("method", "tube"), METHODS)
        full = bounds.resolve(system)
        model = sampled_model(system, full, h)
        v_radius = full.radius("v")
        if not is_detectable(model, system.C):
            raise DesignError("system: the pair (A, C) is not detectable, so no interval observer gain exists")
        framer: FramerDesign | None = None
        try:
            framer = design_framer(model, system.C, system.F, v_radius, options.get("candidates"))
        except DesignError:
            if method == "framer":
                _refuse_unstable_box(system)
                raise
        if method == "framer":
            assert framer is not None
            observer = cls(system, full, framer.L, framer.T, h, method="framer")
            observer.design_result = framer
            return observer
        extra = {} if framer is None else {f"framer-{framer.coordinates}": framer.L}
        tube = design_tube_gain(model, system.C, system.F, v_radius, extra)
        if tube is None:
            _refuse_unstable_box(system)
            raise DesignError(
                "IntervalObserver.design: no candidate gain gives a bounded error tube; "
                "the pair (A, C) may not be detectable or dA is too wide for this sampling period"
            )
        observer = cls(system, full, tube.L, tube.T, h, method="tube", blocks=tube.blocks)
        observer.design_result = tube
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
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        z_c = self.T @ (0.5 * (lo + hi))
        z_r = self.norms.vector(self._abs_T @ (0.5 * (hi - lo)))
        internal: dict[str, Any] = {"z_center": z_c, "z_radius": z_r}
        if self.method == "tube":
            internal.update(
                k=0,
                rho_queue=np.repeat(z_r[None, :], self.horizon, axis=0),
                d_history=np.zeros((self.horizon, self.norms.count)),
            )
        lower, upper = self._x_box(z_c, z_r)
        # In coordinates T ≠ I the z-box maps back wider than the prior: report their intersection.
        return ObserverState(np.maximum(lower, lo), np.minimum(upper, hi), internal=internal)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Propagate the box from ``t_k`` to ``t_{k+1}`` with ``y_k`` and ``u_k`` (held over the step)."""
        internal = self._advance(state.internal, y, u)
        lower, upper = self._x_box(internal["z_center"], internal["z_radius"])
        return ObserverState(lower, upper, internal=internal)

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record; a point model's recursion is evaluated without a Python loop.

        A point model's centres go through the compiled linear recursion and its radii, which do not
        depend on the data, are computed once. With interval ``ΔA`` the radii depend on the data: the
        loop advances centres and radii only and maps them to boxes once for the whole record, where
        the base loop would form every step's box (measurably faster on a single record).
        Both give the numbers of :meth:`step`.

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
        state = self.init()
        if self.model.uncertain:
            z_c = np.empty((*ys.shape[:-1], self.n))
            z_r = np.empty((*ys.shape[:-1], self.norms.count))
            internal = state.internal
            for k in range(times.size):
                z_c[..., k, :], z_r[..., k, :] = internal["z_center"], internal["z_radius"]
                if k + 1 < times.size:
                    internal = self._advance(internal, ys[..., k, :], us[..., k, :])
        else:
            drive = ys[..., :-1, :] @ self._TL.T + us[..., :-1, :] @ self._TGamma.T + self._offset
            z_c = self._center_recursion(state.internal["z_center"], drive)
            z_r = np.broadcast_to(self._default_radius(times.size), (*z_c.shape[:-1], self.norms.count))
        lower, upper = self._x_box(z_c, z_r)
        lower[..., 0, :], upper[..., 0, :] = state.lower, state.upper
        return Estimate(times, lower, upper, meta={**self.meta(), "rows": self.rows})

    # -- internals -------------------------------------------------------------------------------
    def _default_radius(self, steps: int) -> FloatArray:
        """Radii from the design's initial box for a point model: data-independent, computed once."""
        if self._radius_cache.shape[0] < steps:
            state = self.init()
            if self.method == "framer":
                constant = np.broadcast_to(self._radius_input, (steps - 1, self.n))
                self._radius_cache = self._radius_recursion(state.internal["z_radius"], constant)
            else:
                self._radius_cache = self._point_tube_radius(state.internal["z_radius"], steps)
        return self._radius_cache[:steps]

    def _point_tube_radius(self, rho0: FloatArray, steps: int) -> FloatArray:
        """Tube radii for a constant disturbance radius, vectorised: the same recursion as ``_advance``.

        For ``k ≤ J``: ``ρ_k = |M^k|ρ₀ + Σ_{i<k}|M^i|d``; after that ``ρ_k = |M^J|ρ_{k-J} + Σ_{i<J}|M^i|d``,
        evaluated a block of ``J`` steps at a time.
        """
        horizon = self.horizon
        d = self._radius_input
        radii = np.empty((max(steps, horizon + 1), self.norms.count))
        terms = self._abs_powers[:horizon] @ d
        radii[0] = rho0
        radii[1 : horizon + 1] = self._abs_powers[1:] @ rho0 + np.cumsum(terms, axis=0)
        constant = terms.sum(axis=0)
        lagged = self._abs_powers[horizon].T
        for start in range(horizon + 1, steps, horizon):
            stop = min(start + horizon, steps)
            radii[start:stop] = radii[start - horizon : stop - horizon] @ lagged + constant
        return radii[:steps]

    def _disturbance_radius(self, z_c: FloatArray, z_r: FloatArray, u: FloatArray) -> FloatArray:
        """Radius of the box of everything unknown that enters one step (in z-coordinates)."""
        radius = self._radius_input
        if not self._uncertain:
            return np.asarray(radius)
        if self.method == "framer" or self._identity:
            x_abs = np.abs(z_c @ self.T_inv.T) + z_r @ self._abs_T_inv.T
            return np.asarray(radius + x_abs @ self._K_phi.T + np.abs(u) @ self._K_gamma.T)
        # Tube in other coordinates (design/tube.py, block norms): min of two bounds of ‖(TΔΦx_c)_b‖, S ρ.
        centre = np.minimum(
            self.norms.vector(np.abs(z_c @ self.T_inv.T) @ self._K_phi.T), self.norms.vector(z_c) @ self._S_phi.T
        )
        inputs = self.norms.vector(np.abs(u) @ self._K_gamma.T)
        return np.asarray(radius + inputs + centre + z_r @ self._S_phi.T)

    def _advance(self, internal: dict[str, Any], y: FloatArray, u: FloatArray) -> dict[str, Any]:
        z_c, z_r = internal["z_center"], internal["z_radius"]
        disturbance = self._disturbance_radius(z_c, z_r, u)
        new_c = z_c @ self.M.T + y @ self._TL.T + u @ self._TGamma.T + self._offset
        if self.method == "framer":
            return {"z_center": new_c, "z_radius": z_r @ self._abs_M.T + disturbance}
        k = internal["k"]
        queue, history = internal["rho_queue"], internal["d_history"]
        # A batched y or u (or a batched ΔA disturbance) gives the queues their leading axes.
        lead = np.broadcast_shapes(np.shape(disturbance)[:-1], z_r.shape[:-1], new_c.shape[:-1])
        count = self.norms.count
        disturbance = np.broadcast_to(disturbance, (*lead, count))
        if queue.shape[:-2] != lead:  # the first step of a batch from the shared prior
            history = np.broadcast_to(history, (*lead, self.horizon, count))
            queue = np.broadcast_to(queue, (*lead, self.horizon, count))
        history = np.concatenate([disturbance[..., None, :], history[..., :-1, :]], axis=-2)
        lag = min(k + 1, self.horizon)
        new_r = queue[..., 0, :] @ self._abs_powers[lag].T + np.einsum(
            "ijl,...il->...j", self._abs_powers[: self.horizon], history
        )
        queue = np.concatenate([queue[..., 1:, :], new_r[..., None, :]], axis=-2)
        return {"z_center": new_c, "z_radius": new_r, "k": k + 1, "rho_queue": queue, "d_history": history}

    def _x_box(self, z_c: FloatArray, z_r: FloatArray) -> tuple[FloatArray, FloatArray]:
        x_c = z_c @ self.T_inv.T
        if self.norms.singleton:
            x_r = z_r @ self._abs_T_inv.T
            scale = (np.abs(z_c) + z_r) @ self._abs_T_inv.T
        else:
            x_r = z_r @ self._back.T
            scale = np.abs(z_c) @ self._abs_T_inv.T + x_r
        return inflate(x_c - x_r, x_c + x_r, self.margin, scale=scale)

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            ``method`` (``"IntervalObserver/<method>"``), ``L``, ``T``, ``spectral_radius``, ``h``,
            ``transient_s``; ``horizon`` (and ``blocks`` when not all of size 1) for the tube method;
            after :meth:`design`, ``steady_width``
            (noise-only steady-state width bound).
        """
        info: dict[str, Any] = {
            "method": f"IntervalObserver/{self.method}",
            "L": self.L.tolist(),
            "T": self.T.tolist(),
            "spectral_radius": self.spectral_radius,
            "h": self.h,
            "transient_s": 0.0,
        }
        if self.method == "tube":
            info["horizon"] = self.horizon
            if not self.norms.singleton:
                info["blocks"] = list(self.norms.sizes)
        if self.design_result is not None:
            info["steady_width"] = (2 * self.design_result.steady_radius).tolist()
        return info


def _refuse_unstable_box(system: LTISystem) -> None:
    """Raise a DesignError naming an unstable matrix of the ``dA`` box, when a search finds one."""
    if system.dA is None:
        return
    found = unstable_vertex(system.A, system.dA[0], system.dA[1], system.continuous)
    if found is not None:
        measure = "spectral abscissa" if system.continuous else "spectral radius"
        limit = 0 if system.continuous else 1
        raise DesignError(
            f"dA: expected a box of stable matrices, got a vertex A + ΔA with {measure} {found[1]:.3g} >= {limit}; "
            "the state can grow without bound there, and so does every interval bound that does not know ΔA: "
            "reduce dA"
        )
