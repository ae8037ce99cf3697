r"""The general-purpose interval observer for LTI systems with interval uncertainty.

:class:`IntervalObserver` propagates a box whose centre is a Luenberger estimate on the sound sampled
model of the system; its radius follows the exact error tube (default) or the classical framer. The
equations are in the class docstring.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.cooperative import FramerDesign, design_framer, framer_matrices, is_detectable, unstable_vertex
from ..design.tube import (
    BlockNorms,
    TubeDesign,
    abs_powers,
    coupling,
    design_tube_gain,
    noise_sums,
    tube_horizon,
    tube_stability,
)
from ..errors import ArgumentTypeError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import inflate, recursion_margin
from ..systems.balancing import balanced, state_scales
from ..systems.bounds import Bounds, ResolvedBounds
from ..systems.lti import LTISystem
from ..systems.sampling import SampledModel, sampled_model
from ..validation import as_array, as_choice, as_matrix, check_no_kwargs
from .base import Observer, ObserverState, options_after_bounds

__all__ = ["METHODS", "IntervalObserver"]

FloatArray = NDArray[np.float64]

METHODS = ("tube", "framer")

COMPILED_MIN_SAMPLES = 20_000
"""Samples (times runs) from which :meth:`IntervalObserver.run` loads the compiled loop into a process that has not
used it yet: loading it from Numba's cache costs about 0.3 s (a first compile on a fresh install 3 s or more), the
step loop about 65 µs a sample at n = 2, so the default reproductions, whose records are shorter, compile nothing."""

COMPILED_WARM_MIN_SAMPLES = 16
"""Samples (times runs) from which :meth:`IntervalObserver.run` uses the compiled loop once it is loaded in the
process (a campaign of short records, a notebook after a long run): about 0.5 ms of fixed cost against 65 µs a
sample for the step loop."""


def _kernel_loaded() -> bool:
    """Whether this process has already loaded the compiled loop (one compiled signature or more)."""
    module = sys.modules.get(f"{__package__}.tube_kernel")
    return module is not None and bool(module.run_boxes.signatures)


class IntervalObserver(Observer):
    r"""Interval observer for an :class:`~intervalobs.systems.LTISystem`, continuous or discrete.

    Parameters
    ----------
    system : LTISystem
        The model (with optional interval ``dA``).
    bounds : Bounds
        Boxes of ``x0``, ``w`` and ``v``.
    L : array_like, shape (n, p) or (G, n, p)
        Gain of the sampled model; with ``G`` gains (tube only) the observer runs one tube per gain, in
        the same coordinates, and returns their intersection at every step (see Notes).
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

    .. math:: \rho_{k+1} = |M^{\ell}|\,\rho_{k+1-\ell} + c_\ell + \sum_{i<\ell} |M^i|\, d_{k-i},\quad
              \ell = \min(k+1, J),\quad d_k = |T|\big(\delta\Gamma|u_k| + \delta\Phi(|x_c| + x_r)\big),

    which only needs :math:`\rho(\Phi - LC) < 1` and is never wider than the framer with the same gain and
    coordinates. The noise enters as generators, not as its box: with :math:`N` the process noise's
    generators (:meth:`~intervalobs.systems.sampling.SampledModel.generators`: :math:`E\,\mathrm{diag}(w_r)`
    in discrete time, the box :math:`\mathrm{diag}(r)` in continuous time) and
    :math:`G = T[N,\ -LF\,\mathrm{diag}(v_r)]`, the constant :math:`c_\ell \ge \sum_{i<\ell}|M^iG|\,1`
    (:func:`~intervalobs.design.tube.noise_sums`, computed once) is never above the box term
    :math:`\sum_{i<\ell}|M^i|\,|T|(r + |LF|v_r)` and keeps the cancellations between the noise channels.
    Outside the identity coordinates the :math:`\delta\Phi` terms are
    :math:`\min(|T|\delta\Phi|x_c|, S|z_c|) + S\rho` with :math:`S = \min(|T|\delta\Phi|T^{-1}|, B)` and
    :math:`B \ge |T\Delta\Phi T^{-1}|` (:meth:`~intervalobs.systems.sampling.SampledModel.dphi_in`): each
    block column of :math:`T\Delta\Phi T^{-1}z` is bounded by either;
    with ``blocks`` every :math:`|\cdot|` of :math:`z` quantities is a block norm
    (:class:`~intervalobs.design.tube.BlockNorms`).

    ``method="framer"``: the classical framer :math:`\overline{z}^+ = M^+\overline{z} - M^-\underline{z} + \dots`
    of the integrated-observer paper, (39)–(40), written in centre–radius form and valid for any sign pattern of
    :math:`M`,

    .. math:: z_r^+ = |M| z_r + |T|\big(r + |LF| v_r + \delta\Gamma|u_k| + \delta\Phi(|x_c| + x_r)\big),

    with :math:`x_c = T^{-1}z_c`, :math:`x_r = |T^{-1}|z_r`; the interval term :math:`\delta\Phi\,x` is
    bounded exactly (the integrated-observer paper, Lemma A.1). It needs a stable width system
    :math:`\rho(|M| + |T|\delta\Phi|T^{-1}|) < 1`.

    Several gains (tube only; :meth:`design` passes the winning gain and the other candidates bounded in
    the identity coordinates, :attr:`~intervalobs.design.tube.TubeDesign.companions`): each gain
    :math:`L_g` runs its own centre and tube, and the box is the intersection
    :math:`[\max_g(\hat x_g - \rho_g), \min_g(\hat x_g + \rho_g)]`, never wider than any single gain's
    box at any step. In the identity coordinates every tube's :math:`\delta\Phi` term bounds :math:`|x_k|`
    by the reported box (that intersection, each gain's box widened by its rounding margin),
    :math:`|x_k| \le \max(|\underline{x}_k|, |\overline{x}_k|) \le |\hat x_g| + \rho_g` (plus that margin),
    so each tube is also never wider than it is alone (the recursion is monotone in :math:`d_k`), and the
    bound holds whatever the rounding of the other gains' recursions.

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
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise ArgumentTypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        as_choice("method", method, METHODS)
        self.system = system
        self.method = method
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.model: SampledModel = sampled_model(system, self.bounds, h)
        self._uncertain = self.model.uncertain  # data-dependent radii (interval ΔA): read once per step
        self.h = self.model.h if system.continuous else float(system.dt or 1.0)
        gains = as_array("L", L)
        gains = gains[None] if gains.ndim < 3 else gains
        if gains.ndim != 3 or gains.shape[0] == 0 or (method == "framer" and gains.shape[0] > 1):
            expected = f"({self.n}, {self.p})" + ("" if method == "framer" else f" or (G, {self.n}, {self.p})")
            raise DimensionError(f"L: expected shape {expected} ({method}), got shape {np.shape(L)}")
        self.gains = np.stack([as_matrix("L", gain, (self.n, self.p)) for gain in gains])
        self.L = self.gains[0]
        self.T = np.eye(self.n) if T is None else as_matrix("T", T, (self.n, self.n))
        if _equilibrated_condition(self.T) > 1e12:
            raise DimensionError(
                "T: expected an invertible coordinate change, got a condition number of "
                f"{_equilibrated_condition(self.T):.3g} (after scaling its columns)"
            )
        self.T_inv = np.linalg.inv(self.T)
        self.norms = BlockNorms((1,) * self.n if blocks is None or len(blocks) == 0 else blocks)
        if self.norms.n != self.n or (method == "framer" and not self.norms.singleton):
            raise DimensionError(
                f"blocks: expected sizes 1 or 2 summing to n = {self.n} (tube only), got {self.norms.sizes}"
            )
        matrices = [framer_matrices(self.model, system.C, gain, self.T) for gain in self.gains]
        width_matrix, self.M = matrices[0]
        self._Ms = np.stack([m for _, m in matrices])  # (G, n, n)
        v_center = self.bounds.centre("v")
        v_radius = self.bounds.radius("v")
        gains_F = self.gains @ system.F
        self._abs_T = np.abs(self.T)
        self._abs_T_inv = np.abs(self.T_inv)
        self._TL = self.T @ self.gains  # (G, n, p)
        self._TGamma = self.T @ self.model.Gamma
        self._offset = (self.model.noise_center - gains_F @ v_center) @ self.T.T  # (G, n)
        self._radius_input = self.norms.vector(  # (G, count)
            (self.model.noise_radius + np.abs(gains_F) @ v_radius) @ self._abs_T.T
        )
        # the same disturbance as generators of a unit box: T[N, -LF diag(v_r)] per gain (G, n, q)
        noise = self.model.generators()
        self._generators = self.T @ np.concatenate(
            [np.broadcast_to(noise, (self.gains.shape[0], *noise.shape)), gains_F * v_radius], axis=-1
        )
        self._back = self.norms.cols(self._abs_T_inv)  # x radius = back @ z radius
        self._K_phi = self._abs_T @ self.model.dPhi
        self._K_gamma = self._abs_T @ self.model.dGamma
        # Outside the identity coordinates: the coupling S >= blockwise |TΔΦT⁻¹| of the tube (design/tube.py).
        self._identity = self.norms.singleton and np.array_equal(self.T, np.eye(self.n))
        if method == "tube" and self._uncertain and not self._identity:
            self._S_phi = coupling(self.model, self.T, self.norms)
        if method == "framer":
            self.spectral_radius = float(np.max(np.abs(np.linalg.eigvals(width_matrix))))
            if not self.spectral_radius < 1:
                raise DesignError(
                    f"L, T: expected a stable width system, got spectral radius {self.spectral_radius:.6g} >= 1 "
                    "of |T(Φ - LC)T⁻¹| + |T|δΦ|T⁻¹|; use IntervalObserver.design to find a gain"
                )
            self._abs_M = np.abs(self.M)
            self.margin: float | FloatArray = recursion_margin(self.n, 1.0, self.spectral_radius)
        else:
            self._tubes()
            self.margin = np.array(  # each gain's box its own margin, shape (G, 1)
                [[recursion_margin(self.n, 1.0, float(np.max(np.abs(np.linalg.eigvals(m)))))] for m in self._Ms]
            )
        self.design_result: FramerDesign | TubeDesign | None = None

    @classmethod
    @options_after_bounds("h")
    def design(cls, system: LTISystem, bounds: Bounds, *, h: float | None = None, **options: Any) -> IntervalObserver:
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
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        method = as_choice("method", options.get("method", "tube"), METHODS)
        full = bounds.resolve(system)
        scales = state_scales(system, full, powers_of_two=False)  # the observer is verified as built
        if scales is None:
            result = _design(system, full, h, method, options.get("candidates"))
        else:  # states in very different units: designed in balanced coordinates (systems/balancing.py)
            result = _unbalanced(_design(*balanced(system, full, scales), h, method, options.get("candidates")), scales)
        if isinstance(result, FramerDesign):
            observer = cls(system, full, result.L, result.T, h, method="framer")
        else:
            gains = np.stack((result.L, *result.companions))
            observer = cls(
                system, full, gains if len(gains) > 1 else result.L, result.T, h, method="tube", blocks=result.blocks
            )
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
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        z_c = self.T @ (0.5 * (lo + hi))
        z_r = self.norms.vector(self._abs_T @ (0.5 * (hi - lo)))
        internal: dict[str, Any] = {"z_center": z_c, "z_radius": z_r, "drive": np.zeros_like(z_c)}
        if self.method == "tube":  # every gain starts from the same box: a leading gain axis
            gains, longest = self.gains.shape[0], self._abs_powers.shape[1] - 1
            internal.update(
                z_center=np.repeat(z_c[None, :], gains, axis=0),
                z_radius=np.repeat(z_r[None, :], gains, axis=0),
                drive=np.zeros((gains, self.n)),
                k=0,
                rho_queue=np.repeat(z_r[None, None, :], gains, axis=0).repeat(longest, axis=1),
                d_history=np.zeros((gains, longest, self.norms.count)),
            )
        lower, upper = self._x_box(internal["z_center"], internal["z_radius"], internal["drive"])
        # In coordinates T ≠ I the z-box maps back wider than the prior: report their intersection.
        return ObserverState(np.maximum(lower, lo), np.minimum(upper, hi), internal=internal)

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Propagate the box from ``t_k`` to ``t_{k+1}`` with ``y_k`` and ``u_k`` (held over the step)."""
        internal = self._advance(state.internal, y, u)
        lower, upper = self._x_box(internal["z_center"], internal["z_radius"], internal["drive"])
        return ObserverState(lower, upper, internal=internal)

    @shared_docs
    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record: the compiled recursion for long records, :meth:`step` for short ones.

        From ``COMPILED_MIN_SAMPLES`` samples (times runs) on, or ``COMPILED_WARM_MIN_SAMPLES`` once the process
        has loaded it, the recursion of :meth:`step` runs in one compiled loop
        (:mod:`intervalobs.observers.tube_kernel`: the same sums, the same outward margins); shorter records go
        through the step loop, which costs less than loading the compiled code.
        Both give the numbers of :meth:`step` up to rounding, covered by the margin (tested).

        Parameters
        ----------
        %(runs)s
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs, held over each sampling interval.

        Returns
        -------
        Estimate
        """
        times, ys, us = self._signals(t, y, u)
        state = self.init()
        if ys[..., 0].size < (COMPILED_WARM_MIN_SAMPLES if _kernel_loaded() else COMPILED_MIN_SAMPLES):
            return self._loop(times, ys, us, state)[0]
        lead = ys.shape[:-2]
        runs = int(np.prod(lead, dtype=int))
        flat_y, flat_u = (
            np.ascontiguousarray(np.broadcast_to(a, (*lead, *a.shape[-2:])).reshape(runs, *a.shape[-2:]))
            for a in (ys, us)
        )
        lower, upper = self._compiled(state, flat_y, flat_u)
        lower, upper = lower.reshape(*lead, times.size, self.n), upper.reshape(*lead, times.size, self.n)
        lower[..., 0, :], upper[..., 0, :] = state.lower, state.upper
        meta = {"transient_s": float(times[0]), **self.meta(), "rows": self.rows}
        return Estimate.from_boxes(times, lower, upper, meta=meta)

    def _compiled(self, state: ObserverState, ys: FloatArray, us: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Boxes of runs ``ys`` (R, T, p), ``us`` (R, T, m) by the compiled loop, from the initial ``state``."""
        from . import tube_kernel  # Numba is imported only for a record long enough to pay for it

        gains, count = self.gains.shape[0], self.norms.count
        if self.method == "framer":  # the tube of horizon 1: |M^0| = I, |M^1| = |M|, c_1 = the box d
            powers = np.stack([np.eye(self.n), self._abs_M])[None]
            sums = np.stack([np.zeros(count), self._radius_input[0]])[None]
            lags, mode = np.ones(1, dtype=np.int64), tube_kernel.FRAMER
        else:
            powers, lags, sums = self._abs_powers, self._lags.astype(np.int64), self._noise_sums
            mode = tube_kernel.TUBE_IDENTITY if self._identity else tube_kernel.TUBE_COORDINATES
        mode = mode if self._uncertain else tube_kernel.POINT
        coupling = getattr(self, "_S_phi", np.zeros((count, count)))
        dense = [  # every float array C-contiguous: one compiled signature for every observer
            np.ascontiguousarray(a, dtype=float)
            for a in (
                np.reshape(state.internal["z_center"], (gains, self.n)),
                np.reshape(state.internal["z_radius"], (gains, count)),
                self._K_phi,
                self._K_gamma,
                self.T_inv,
                self._abs_T_inv,
                coupling,
            )
        ]
        linear = [np.ascontiguousarray(a, dtype=float) for a in (self._Ms, self._TL, self._TGamma, self._offset)]
        margin = np.broadcast_to(np.ravel(self.margin), (gains,)).astype(float)
        lower, upper = tube_kernel.run_boxes(
            ys,
            us,
            (dense[0], dense[1]),
            (linear[0], linear[1], linear[2], linear[3]),
            (np.ascontiguousarray(powers, dtype=float), lags, np.ascontiguousarray(sums, dtype=float)),
            (dense[2], dense[3], dense[4], dense[5], dense[6]),
            np.ascontiguousarray(self._back, dtype=float),
            (np.asarray(self.norms.sizes, dtype=np.int64), self.norms.rounding),
            (margin, float(np.finfo(float).tiny), bool(self._identity), bool(self.norms.singleton)),
            mode,
        )
        return lower, upper

    # -- internals -------------------------------------------------------------------------------
    def _tubes(self) -> None:
        """Horizon ``J_g``, verified ``ρ(|M_g^J| + GS) < 1`` and powers ``|M_g^i|`` of every gain's tube.

        The powers are kept up to the longest horizon: ``_abs_powers[g, i]`` is zero for ``i > J_g``, and
        ``_terms`` holds ``|M_g^i|``, ``i < J_g``, flattened against a history of ``J_max`` disturbances,
        so that every gain's sum ``Σ_{i<J_g}|M_g^i| d_{k-i}`` is one product.
        """
        horizons, radii = [], []
        for g, (m, disturbance) in enumerate(zip(self._Ms, self._radius_input)):
            which = f" (gain {g})" if self._Ms.shape[0] > 1 else ""
            horizon = tube_horizon(m, self.norms)
            if horizon is None:
                raise DesignError(
                    "L: expected Φ - LC to be Schur stable (and to contract within 4000 steps), "
                    f"got spectral radius {np.max(np.abs(np.linalg.eigvals(m))):.6g}{which}"
                )
            radius, _ = tube_stability(self.model, m, disturbance, horizon, self.T, self.norms)
            if not radius < 1:
                raise DesignError(
                    f"L: expected a bounded error tube, got ρ(|M^J| + GδΦ) = {radius:.6g} >= 1{which}; "
                    "reduce dA or use IntervalObserver.design"
                )
            horizons.append(horizon)
            radii.append(radius)
        self.horizons = tuple(horizons)
        self.horizon = horizons[0]
        self.spectral_radius = max(radii)
        count, longest = self.norms.count, max(horizons)
        self._abs_powers = np.zeros((len(horizons), longest + 1, count, count))
        for g, (m, horizon) in enumerate(zip(self._Ms, horizons)):
            self._abs_powers[g, : horizon + 1] = abs_powers(m, horizon + 1, self.norms)
        terms = self._abs_powers[:, :longest].copy()
        for g, horizon in enumerate(horizons):
            terms[g, horizon:] = 0.0
        self._terms = terms.transpose(0, 1, 3, 2).reshape(len(horizons), longest * count, count)
        self._noise_sums = np.zeros((len(horizons), longest + 1, count))  # c_ℓ of gain g at [g, ℓ], ℓ ≤ J_g
        for g, (m, horizon) in enumerate(zip(self._Ms, horizons)):
            self._noise_sums[g, : horizon + 1] = noise_sums(
                m, self._generators[g], self._radius_input[g], horizon, self.norms
            )
        self._lags = np.asarray(horizons)
        self._lag = self._abs_powers[np.arange(len(horizons)), self._lags]  # |M_g^{J_g}|, from step J_g on
        self._oldest = longest - self._lags  # queue position of ρ_{k+1-J_g}

    def _data_radius(self, z_c: FloatArray, z_r: FloatArray, u: FloatArray, drive: FloatArray) -> FloatArray | None:
        """Radius of the data-dependent part of one step's disturbance (``δΦ``, ``δΓ``; z-coordinates), per gain.

        None for a point model: then the whole disturbance is the noise, whose part of the tube is the
        constant ``_noise_sums`` (the framer's its box ``_radius_input``).
        """
        if not self._uncertain:
            return None
        inputs = self.norms.vector(np.abs(u) @ self._K_gamma.T)
        if self.method == "framer":
            x_abs = np.abs(z_c @ self.T_inv.T) + z_r @ self._abs_T_inv.T
            return np.asarray(x_abs @ self._K_phi.T + inputs)
        if self._identity:  # |x_k| from the box the observer reports: the gains' boxes intersected
            lower, upper = self._x_box(z_c, z_r, drive)
            x_abs = np.maximum(np.abs(lower), np.abs(upper))
            return np.asarray((x_abs @ self._K_phi.T + inputs)[..., None, :])
        # Tube in other coordinates (design/tube.py, block norms): min of two bounds of ‖(TΔΦx_c)_b‖, S ρ.
        centre = np.minimum(
            self.norms.vector(np.abs(z_c @ self.T_inv.T) @ self._K_phi.T), self.norms.vector(z_c) @ self._S_phi.T
        )
        return np.asarray(inputs[..., None, :] + centre + z_r @ self._S_phi.T)

    def _advance(self, internal: dict[str, Any], y: FloatArray, u: FloatArray) -> dict[str, Any]:
        z_c, z_r, drive = internal["z_center"], internal["z_radius"], internal["drive"]
        data = self._data_radius(z_c, z_r, u, drive)
        known = u @ self._TGamma.T
        # the largest drive so far (the terms added to the centres): the scale of their rounding (_x_box)
        term = np.einsum("gip,...p->...gi", np.abs(self._TL), np.abs(y)) + np.abs(known)[..., None, :]
        term = term + np.abs(self._offset)
        if self.method == "framer":
            new_c = z_c @ self.M.T + y @ self._TL[0].T + known + self._offset[0]
            new_drive = np.maximum(drive, term[..., 0, :])
            new_r = z_r @ self._abs_M.T + self._radius_input[0] + (0.0 if data is None else data)
            return {"z_center": new_c, "z_radius": new_r, "drive": new_drive}
        # every gain at once: centres and radii carry a gain axis before the state axis
        new_c = (
            np.einsum("gij,...gj->...gi", self._Ms, z_c)
            + np.einsum("gip,...p->...gi", self._TL, y)
            + known[..., None, :]
            + self._offset
        )
        k = internal["k"]
        queue, history = internal["rho_queue"], internal["d_history"]
        # A batched y or u (or state) gives the centres, and then the queues, their leading axes.
        lead, gains = new_c.shape[:-2], self._Ms.shape[0]
        if queue.shape[:-3] != lead:  # the first step of a batch from the shared prior
            history = np.broadcast_to(history, (*lead, *history.shape[-3:]))
            queue = np.broadcast_to(queue, (*lead, *queue.shape[-3:]))
        # queue[j] = ρ_{k+1-J_max+j} (ρ₀ before the record); history[i] = data part d_{k-i}, i < J_max
        index = np.arange(gains)
        reach = np.minimum(k + 1, self._lags)  # ℓ_g
        lag = self._lag if k + 1 >= queue.shape[-2] else self._abs_powers[index, reach]
        oldest = queue[..., index, self._oldest, :]
        new_r = np.einsum("gjl,...gl->...gj", lag, oldest) + self._noise_sums[index, reach]
        if data is not None:
            data = np.broadcast_to(data, (*lead, gains, self.norms.count))
            history = np.concatenate([data[..., None, :], history[..., :-1, :]], axis=-2)
            new_r = new_r + (history.reshape(*lead, gains, 1, -1) @ self._terms)[..., 0, :]
        queue = np.concatenate([queue[..., 1:, :], new_r[..., None, :]], axis=-2)
        return {
            "z_center": new_c,
            "z_radius": new_r,
            "drive": np.maximum(drive, term),
            "k": k + 1,
            "rho_queue": queue,
            "d_history": history,
        }

    def _x_box(self, z_c: FloatArray, z_r: FloatArray, drive: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The x box of a z box; for the tube the intersection of the gains' boxes (axis -2 of ``z_c``).

        The margin is relative to the centre's magnitude plus ``drive``, the largest of the terms added to the
        centres so far (``|TL||y| + |TΓ||u| + |offset|``): where they cancel (a large gain on exact data) the
        rounding of the centre is of the size of the terms, not of the centre.
        """
        if self._identity:  # the products with T⁻¹ = I below are exact: skip them (once a step for the tube)
            scale = np.abs(z_c) + z_r + drive
            return self._intersected(*inflate(z_c - z_r, z_c + z_r, self.margin, scale=scale))
        x_c = z_c @ self.T_inv.T
        if self.norms.singleton:
            x_r = z_r @ self._abs_T_inv.T
            scale = (np.abs(z_c) + z_r + drive) @ self._abs_T_inv.T
        else:
            x_r = z_r @ self._back.T
            scale = (np.abs(z_c) + drive) @ self._abs_T_inv.T + x_r
        return self._intersected(*inflate(x_c - x_r, x_c + x_r, self.margin, scale=scale))

    def _intersected(self, lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The tube's boxes intersected over the gain axis (axis -2); the framer's box as it is."""
        if self.method == "framer":
            return lower, upper
        return np.max(lower, axis=-2), np.min(upper, axis=-2)

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            ``method`` (``"IntervalObserver/<method>"``), ``L`` (the first gain), ``T``, ``spectral_radius``
            (the largest over the gains), ``h``, ``transient_s``; ``horizon`` (the first gain's; and ``blocks``
            when not all of size 1) for the tube method, with ``gains`` and ``horizons`` of every gain when
            there are several; after :meth:`design`, ``steady_width`` (noise-only steady-state width
            bound of the first gain).
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
            if self.gains.shape[0] > 1:
                info["gains"] = self.gains.tolist()
                info["horizons"] = list(self.horizons)
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


def _design(
    system: LTISystem, full: ResolvedBounds, h: float | None, method: str, candidates: Any
) -> FramerDesign | TubeDesign:
    """The framer (``method="framer"``) or tube design of :meth:`IntervalObserver.design`."""
    model = sampled_model(system, full, h)
    v_radius = full.radius("v")
    if not is_detectable(model, system.C):
        raise DesignError("system: the pair (A, C) is not detectable, so no interval observer gain exists")
    framer: FramerDesign | None = None
    try:
        framer = design_framer(model, system.C, system.F, v_radius, candidates)
    except DesignError:
        if method == "framer":
            _refuse_unstable_box(system)
            raise
    if method == "framer":
        assert framer is not None
        return framer
    extra = {} if framer is None else {f"framer-{framer.coordinates}": framer.L}
    tube = design_tube_gain(model, system.C, system.F, v_radius, extra)
    if tube is None:
        _refuse_unstable_box(system)
        raise DesignError(
            "IntervalObserver.design: no candidate gain gives a bounded error tube; "
            "the pair (A, C) may not be detectable or dA is too wide for this sampling period"
        )
    return tube


def _unbalanced(result: FramerDesign | TubeDesign, scales: FloatArray) -> FramerDesign | TubeDesign:
    """A design of the balanced model ``x_b = S x`` in the original coordinates: ``L = S⁻¹L_b``, ``T = T_b S``.

    The observer of the original model with these matrices is the balanced one: ``T(Φ - LC)T⁻¹ =
    T_b(Φ_b - L_bC_b)T_b⁻¹``, and the products with powers of two are exact (systems/balancing.py).
    """
    column = scales[:, None]
    L, T, steady = result.L / column, result.T * scales, result.steady_radius / scales
    if isinstance(result, TubeDesign):
        companions = tuple(gain / column for gain in result.companions)
        return replace(result, L=L, T=T, steady_radius=steady, companions=companions)
    return replace(result, L=L, T=T, steady_radius=steady)


def _equilibrated_condition(T: FloatArray) -> float:
    """Condition number of ``T`` with its columns scaled to norms in [1, 2) by powers of two.

    A coordinate change ``T = T_b S`` with a diagonal ``S`` of powers of two (a design in balanced
    coordinates, systems/balancing.py) is inverted as accurately as ``T_b``: LU with partial pivoting picks the
    same pivots and the scaling is exact. Its plain condition number counts the units' spread instead.
    """
    norms = np.linalg.norm(T, axis=0)
    if not np.all(np.isfinite(norms)) or np.any(norms == 0):
        return float("inf")
    return float(np.linalg.cond(T * np.ldexp(1.0, -np.floor(np.log2(norms)).astype(int))))
