r"""LPV interval observer (Rotondo et al., (31)–(34)) and LPV interval UIO with isolation signals ((69)–(72)).

Continuous-time theory (Theorem 3.1, Lemma 4.1): with :math:`T C = I - R` (36), :math:`S` from
(37)–(42) and Metzler :math:`\underline F, \overline F`, the lower observer state :math:`\underline z`
is a lower bound of :math:`v = R(\vartheta)x` and :math:`\underline x = \underline z + T y` (32). The
estimation errors obey :math:`\dot{\underline e} = \underline F\,\underline e + w + H u_{un}` (46),
(80) with :math:`w \ge 0`, and the isolation signals :math:`\underline\varepsilon = C^\dagger(y - C
\underline x)`, :math:`\overline\varepsilon = C^\dagger(C\overline x - y)` (29)–(30) stay nonnegative
along every column :math:`H^{(j)}` whose unknown input is zero (27).

**Sound sampling** (DESIGN.md). Measurements arrive every :math:`h`; nothing is assumed about
:math:`x, \vartheta` between samples except the model. Over :math:`[t_k, t_k + h]`, with
:math:`\psi = \tfrac{d}{dt}v - \underline F v` and :math:`\underline F` constant Metzler,

.. math:: v(t_{k+1}) = e^{\underline F h} v(t_k) + \int_0^h e^{\underline F (h-s)}\psi(t_k + s)\,ds
          \;\ge\; e^{\underline F h}\,\underline z_k + \Phi\,\underline\psi_k,
          \qquad \Phi = \int_0^h e^{\underline F s}\,ds \ge 0,

where :math:`\underline\psi_k` bounds :math:`\psi` from below over the whole step, computed from a
box :math:`X_k` that contains :math:`x(t)` on the step (the model's
:meth:`~intervalobs.systems.lpv.SampledLPVModel.step_enclosure`):

.. math:: \underline\psi_k = \underline{[(\dot R + RA)x + RBu + Rc]}_{X_k}
          + \underline{[-\underline F Rx]}_{X_k} + \underline{[\Delta A_R]\cdot B_k}
          + \underline{[\Delta B_R]\,u_k} + \underline{[\Delta B_{un,R}]\,[\underline u_{un},
          \overline u_{un}]}\ (\text{UIO only}),

the last three being the terms of (31)/(69) with exact interval products
(:func:`~intervalobs.interval.interval_matvec_bounds`, never looser than the paper's
:math:`\underline{\Delta A_R}^+\underline x^+ - \dots`). The state box in the :math:`\Delta A_R` term is
:math:`B_k = \operatorname{hull}([\underline x_k, \overline x_k], X_k)`: for a measured component this is
exactly the paper's switching rule of (69)/(71) — when :math:`\underline\varepsilon^{(i)} < 0`,
:math:`\underline x^{(i)}` is replaced by :math:`\tilde x^{(i)} = (C^\dagger y)^{(i)}` (73) — extended
from the sample instant to the whole step. All outputs are widened by ``ROUNDING_MARGIN``.

**Generic models** (:meth:`LPVIntervalObserver.design`). From the user's matrix functions and
bounds (:class:`~intervalobs.systems.lpv.LPVSystem`) and a design of
:func:`~intervalobs.design.lpv_gains.design_lpv_observer` (constant :math:`R`, so :math:`\dot R = 0`):
the scheduling vector is measured at the samples and :math:`|\dot\vartheta| \le \rho` (``theta_rate``;
``inf`` allowed: then only :math:`\vartheta \in \Theta` is used), so
:math:`\Theta_k = [\vartheta_k \mp \rho h] \cap \Theta` holds over the step. Every matrix is
evaluated over :math:`\Theta_k` by interval arithmetic (:mod:`intervalobs.inclusion`). The step box
:math:`X_k` is the a-priori enclosure of Picard–Lindelöf type: if
:math:`S_k + [0, h]\,f(X) \subseteq X` (with :math:`S_k` the box at :math:`t_k`, measured states exact,
:math:`f` the interval right-hand side over every admissible :math:`\Delta A, \Delta B, d` and, for the
UIO, :math:`u_{un}`), then :math:`x(t) \in S_k + [0, h] f(X)` on the step. The observer matrix of the
step is :math:`F_k = F(\vartheta_k)` (designed left columns, right columns :math:`A_R(\vartheta_k)`;
negative off-diagonal entries, possible off the design grid, are set to 0), and
:math:`\psi = [R(A + \Delta A)(\Theta_k) - F_k R]\,X_k + R(B + \Delta B)(\Theta_k)u + R[d] + Rc
(+ R\Delta B_{un}[u_{un}])`, the bracket evaluated as one interval matrix so that the unmeasured columns
cancel to an :math:`O(\rho h)` interval. Soundness needs none of (17)–(18), Hurwitz or the LMI: those
give boundedness.

Step semantics: the box of :math:`x(t_k)` needs the current output (32), so
``step(state_k, y_k, u_k)`` returns a state whose ``lower``/``upper`` are the box of :math:`x(t_k)` and
whose ``internal`` holds :math:`\underline z_{k+1}, \overline z_{k+1}` and the isolation signals at
:math:`t_k`; ``run`` row ``k`` is the same box, so ``run`` equals repeated ``step`` exactly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.lpv_gains import LPVObserverDesign, design_lpv_observer
from ..errors import ArgumentTypeError, AssumptionError, DataError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import ROUNDING_MARGIN, inflate, interval_matvec_bounds, matvec_bounds
from ..systems.bounds import Bounds
from ..systems.lpv import LPVSystem, SampledLPVModel, StepEnclosure
from ..validation import as_array, as_box, as_matrix, as_positive
from ._lpv_step import GenericStepEnclosure, metzler_step_matrices
from .base import Observer, ObserverState, options_after_bounds

__all__ = ["LPVIntervalObserver", "LPVIntervalUIO"]

FloatArray = NDArray[np.float64]


def _check_metzler_hurwitz(name: str, f: FloatArray) -> None:
    off = f - np.diag(np.diag(f))
    if np.any(off < 0):
        i, j = np.argwhere(off < 0)[0]
        raise AssumptionError(f"{name}: expected a Metzler matrix, got {name}[{i},{j}] = {f[i, j]:g} < 0")
    if np.max(np.linalg.eigvals(f).real) >= 0:
        raise DesignError(
            f"{name}: expected a Hurwitz matrix, got spectral abscissa {np.max(np.linalg.eigvals(f).real):g}"
        )


def _measured_inverse(system: LPVSystem) -> FloatArray:
    """:math:`\\tilde C^{-1}` for :math:`C = (\\tilde C\\ 0)` (9), measured states first."""
    p = system.p
    if np.any(system.C[:, p:] != 0.0):
        raise AssumptionError(
            f"C: expected the measured states first, C = (C̃ 0), got nonzero columns beyond the first {p}"
        )
    return np.asarray(np.linalg.inv(system.C[:, :p]))


@dataclass(frozen=True)
class _KnownTerms:
    r"""The parts of a step of :class:`LPVIntervalObserver` that do not depend on :math:`z` (one sample or several).

    ``rate_*``: the known rate plus :math:`-F` times the bounds of :math:`Rx`; ``input_*``: :math:`\Delta B_R u`;
    ``unknown_*``: :math:`\Delta B_{un,R}` times the unknown input's box (when ``unknown_input``). Their sum with
    :math:`\Delta A_R` times the box of the step is :math:`\psi`, added in that order.
    """

    flow_lower: FloatArray
    flow_upper: FloatArray
    da_lower: FloatArray
    da_upper: FloatArray
    rate_lower: FloatArray
    rate_upper: FloatArray
    input_lower: FloatArray
    input_upper: FloatArray
    unknown_lower: FloatArray
    unknown_upper: FloatArray
    unknown_input: bool


class LPVIntervalObserver(Observer):
    r"""Interval observer of an uncertain LPV system, sampled soundly (module docstring).

    Two ways to build one: from a model with its own sampled-data enclosures (a
    :class:`~intervalobs.systems.lpv.SampledLPVModel`, e.g. the manipulator's, and given Metzler
    :math:`F`), or from any :class:`~intervalobs.systems.lpv.LPVSystem` with :meth:`design` (F, R, T
    from the LMIs, enclosures by interval evaluation).

    Parameters
    ----------
    model : SampledLPVModel
        The model with its sampled-data enclosures and :math:`R(\vartheta)`.
    h : float
        Sampling interval (s).
    f_lower, f_upper : array_like, shape (n, n)
        Constant Metzler Hurwitz :math:`\underline F, \overline F` (the manipulator example uses
        :math:`-\lambda I`).
    bounds : Bounds, optional
        Default prior box ``x0`` of :math:`x(t_0)`; its disturbance box ``w`` must be zero.

    Raises
    ------
    AssumptionError
        If F is not Metzler, C is not square invertible (a model-specific enclosure measures the whole
        state; use :meth:`design` for n_y < n_x), or ``bounds`` has a disturbance d.
    DesignError
        If F is not Hurwitz.

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): the observer (31)–(34), the prior box (20), the
    example's :math:`F = -\lambda I` (Section 5).
    """

    summary_fields: tuple[str, ...] = ("method",)

    h: float

    method = "lpv-interval-observer"
    rows = "filtered"

    def __init__(
        self,
        model: SampledLPVModel,
        h: float,
        f_lower: ArrayLike,
        f_upper: ArrayLike | None = None,
        bounds: Bounds | None = None,
    ) -> None:
        if not isinstance(model, SampledLPVModel):
            raise DimensionError(f"model: expected a SampledLPVModel, got {type(model).__name__}")
        system = model.system
        self.model: SampledLPVModel | None = model
        self.generic: GenericStepEnclosure | None = None
        self.design_result: LPVObserverDesign | None = None
        self.system = system
        self.n, self.p, self.m = system.n, system.p, system.m
        self.c_inv = _measured_inverse(system)
        self.bounds = None if bounds is None else bounds.resolve(system)
        if self.bounds is not None and (np.any(self.bounds.w[0] != 0) or np.any(self.bounds.w[1] != 0)):
            raise AssumptionError(
                "bounds.w: the model-specific enclosure covers c but not a bounded disturbance d; "
                f"expected zeros, got {self.bounds.w[0].tolist()}, {self.bounds.w[1].tolist()}"
            )
        self.h = self._check_h(h)
        if self.p != self.n:
            raise AssumptionError(
                f"C: expected n_y = n_x for a model-specific enclosure, got n_y = {self.p}, n_x = {self.n}; "
                f"use LPVIntervalObserver.design for unmeasured states"
            )
        self.f_lower = as_matrix("f_lower", f_lower, (self.n, self.n))
        self.f_upper = self.f_lower.copy() if f_upper is None else as_matrix("f_upper", f_upper, (self.n, self.n))
        _check_metzler_hurwitz("f_lower", self.f_lower)
        _check_metzler_hurwitz("f_upper", self.f_upper)
        self.e_lower, self.phi_lower = metzler_step_matrices(self.f_lower, self.h)
        self.e_upper, self.phi_upper = metzler_step_matrices(self.f_upper, self.h)

    @staticmethod
    def _check_h(h: float) -> float:
        return as_positive("h", h, "a positive sampling interval")

    @classmethod
    @options_after_bounds("h", "theta_rate")
    def design(
        cls,
        system: LPVSystem,
        bounds: Bounds,
        *,
        h: float,
        theta_rate: ArrayLike,
        **design_options: Any,
    ) -> LPVIntervalObserver:
        r"""Design the gains by LMIs on a grid of the scheduling box; run with enclosures of the model between samples.

        Parameters
        ----------
        system : LPVSystem
            Model with :math:`C = (\tilde C\ 0)` (measured states first) and matrix functions in the
            component convention.
        bounds : Bounds
            Prior box ``x0`` of :math:`x(t_0)` and the box ``w`` of the disturbance d.
        h : float
            Sampling interval (s).
        theta_rate : array_like, shape (n_theta,) or float
            Bound of :math:`|\dot\vartheta|` (``inf``: only :math:`\vartheta \in \Theta` is used).
        **design_options
            Passed to :func:`~intervalobs.design.lpv_gains.design_lpv_observer` (``R``, ``grid``,
            ``fine_grid``, ``eps2``, ``q_scale``, ``gain_bound``).

        Returns
        -------
        LPVIntervalObserver

        Raises
        ------
        DesignError
            Naming the failed design condition.

        References
        ----------
        Rotondo et al.: LMIs (63)–(66); the prior box (20) and the disturbance box (10).
        """
        unknown = {"R", "grid", "fine_grid", "eps2", "q_scale", "gain_bound"}
        for key in design_options:
            if key not in unknown:
                raise ArgumentTypeError(f"design() got an unexpected keyword argument {key!r}")
        return cls._generic(system, bounds, h, theta_rate, design_lpv_observer(system, **design_options), None)

    @classmethod
    def _generic(
        cls,
        system: LPVSystem,
        bounds: Bounds,
        h: float,
        theta_rate: ArrayLike,
        design: LPVObserverDesign,
        unknown_input: tuple[FloatArray, FloatArray] | None,
    ) -> Any:
        if not isinstance(system, LPVSystem):
            raise DimensionError(f"system: expected an LPVSystem, got {type(system).__name__}")
        obs = cls.__new__(cls)
        obs.model = None
        obs.system = system
        obs.n, obs.p, obs.m = system.n, system.p, system.m
        obs.h = cls._check_h(h)
        obs.design_result = design
        obs.c_inv = design.C_tilde_inv
        obs.bounds = bounds.resolve(system)
        obs.generic = GenericStepEnclosure(system, design, theta_rate, obs.h, unknown_input, obs.bounds.w)
        return obs

    # --- the recursion ----------------------------------------------------------------------------
    def _unknown_input_term(self, bul: FloatArray, buh: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        return None

    def advance(
        self, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray, u: FloatArray, theta: FloatArray | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""One sample: box of :math:`x(t_k)`, isolation signals at :math:`t_k`, and :math:`z_{k+1}`.

        Parameters
        ----------
        z_lower, z_upper : numpy.ndarray, shape (M, n)
            Observer states at :math:`t_k`.
        y, u : numpy.ndarray, shape (M, p) and (M, m)
            Output and known input at :math:`t_k` (u held over the step).
        theta : numpy.ndarray, shape (M, n_theta), optional
            Scheduling vector at :math:`t_k` (designed observers only).

        Returns
        -------
        x_lower, x_upper, eps_lower, eps_upper, z_lower_next, z_upper_next : numpy.ndarray
        """
        if self.generic is not None:
            return self._advance_generic(z_lower, z_upper, y, u, theta)
        model = self.model
        assert model is not None
        x_lo, x_hi, eps_lo, eps_hi = self._state_box(model.r_matrix(y), z_lower, z_upper, y)
        known = self._known_terms(model.step_enclosure(x_lo, x_hi, y, u, self.h), u)
        return (x_lo, x_hi, eps_lo, eps_hi, *self._next_z(known, x_lo, x_hi, z_lower, z_upper))

    def advance_many(
        self, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        r""":meth:`advance` over ``S`` consecutive samples: the same numbers, the enclosures of all samples at once.

        When the model's enclosures do not read the observer's box
        (:attr:`~intervalobs.systems.lpv.SampledLPVModel.box_free`), everything but the recursion of
        :math:`z` is evaluated for the ``S`` samples in one vectorised call and the recursion of :math:`z`
        runs compiled (:func:`~intervalobs.observers.lpv_kernel.run_z`, the same operations in the same
        order), so a long record of few runs no longer costs a few hundred small array operations a sample
        (issue 36: the manipulator campaign's fixed cost per task). Otherwise it is :meth:`advance` sample
        after sample.

        Parameters
        ----------
        z_lower, z_upper : numpy.ndarray, shape (M, n)
            Observer states at the first sample.
        y, u : numpy.ndarray, shape (S, M, p) and (S, M, m)
            Outputs and known inputs of the ``S`` samples.

        Returns
        -------
        x_lower, x_upper, eps_lower, eps_upper : numpy.ndarray, shape (S, M, n)
            Boxes and isolation signals at the ``S`` samples.
        z_lower_next, z_upper_next : numpy.ndarray, shape (M, n)
            Observer states after the last sample.
        """
        model = self.model
        if model is None or self.generic is not None or not model.box_free:
            out = np.empty((4, *np.shape(y)[:2], self.n))
            for k in range(out.shape[1]):
                *boxes, z_lower, z_upper = self.advance(z_lower, z_upper, y[k], u[k])
                out[:, k] = boxes
            return out[0], out[1], out[2], out[3], z_lower, z_upper
        return self._advance_compiled(model, z_lower, z_upper, y, u)

    def _advance_compiled(
        self, model: SampledLPVModel, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`advance_many` for enclosures that ignore the box: all but :math:`z` at once, :math:`z` compiled."""
        from .lpv_kernel import run_z  # Numba only where a campaign needs it

        known = self._known_terms(model.step_enclosure(y, y, y, u, self.h), u)
        x_m = y @ self.c_inv.T
        v_m = np.einsum("...ij,...j->...i", model.r_matrix(y)[..., : self.p, : self.p], x_m)
        names = ("rate", "input", "unknown") if known.unknown_input else ("rate", "input")
        terms = np.array(
            [
                [np.broadcast_to(getattr(known, f"{name}_{end}"), x_m.shape) for name in names]
                for end in ("lower", "upper")
            ]
        )
        z = np.array([np.broadcast_to(z_lower, x_m.shape[1:]), np.broadcast_to(z_upper, x_m.shape[1:])])
        out = np.empty((4, *x_m.shape))
        run_z(
            z,
            np.stack([x_m, v_m]),
            np.stack([known.flow_lower, known.flow_upper]),
            np.stack([known.da_lower, known.da_upper]),
            terms,
            np.stack([self.e_lower, self.phi_lower, self.e_upper, self.phi_upper]),
            ROUNDING_MARGIN,
            float(np.finfo(float).tiny),
            out,
        )
        return out[0], out[1], out[2], out[3], z[0], z[1]

    def _known_terms(self, enc: StepEnclosure, u: FloatArray) -> _KnownTerms:
        r"""The terms of :math:`\psi` (33) that do not depend on :math:`z`: all but :math:`\Delta A_R` times the box."""
        ub_lo, ub_hi = interval_matvec_bounds(enc.db_lower, enc.db_upper, u, u)
        fl_lo = matvec_bounds(-self.f_lower, enc.rx_lower, enc.rx_upper)[0]
        fu_hi = matvec_bounds(-self.f_upper, enc.rx_lower, enc.rx_upper)[1]
        extra = self._unknown_input_term(enc.dbun_lower, enc.dbun_upper)
        zero = np.zeros(())
        return _KnownTerms(
            enc.flow_lower,
            enc.flow_upper,
            enc.da_lower,
            enc.da_upper,
            enc.rate_lower + fl_lo,
            enc.rate_upper + fu_hi,
            ub_lo,
            ub_hi,
            zero if extra is None else extra[0],
            zero if extra is None else extra[1],
            extra is not None,
        )

    def _next_z(
        self, known: _KnownTerms, x_lo: FloatArray, x_hi: FloatArray, z_lower: FloatArray, z_upper: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        r""":math:`z_{k+1}` (33)–(34) from the known terms and the box of :math:`x(t_k)`."""
        b_lo, b_hi = np.minimum(x_lo, known.flow_lower), np.maximum(x_hi, known.flow_upper)
        a_lo, a_hi = interval_matvec_bounds(known.da_lower, known.da_upper, b_lo, b_hi)
        psi_lo = known.rate_lower + a_lo + known.input_lower
        psi_hi = known.rate_upper + a_hi + known.input_upper
        if known.unknown_input:
            psi_lo = psi_lo + known.unknown_lower
            psi_hi = psi_hi + known.unknown_upper
        zl = z_lower @ self.e_lower.T + psi_lo @ self.phi_lower.T
        zu = z_upper @ self.e_upper.T + psi_hi @ self.phi_upper.T
        return inflate(zl, zu)

    def _state_box(
        self, r: FloatArray, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        r"""Box of :math:`x(t_k)` and isolation signals from the bounds of :math:`v = R(\vartheta_k)x` and :math:`y_k`.

        Measured states :math:`x_m = \tilde C^{-1}y` (9) get the paper's box (32),
        :math:`z_m + (I - R_{11})x_m`, and :math:`\underline\varepsilon = R_{11}x_m - \underline z_m`,
        :math:`\overline\varepsilon = \overline z_m - R_{11}x_m` (29)–(30) (with :math:`C^\dagger =
        (\tilde C^{-1}; 0)`; for :math:`C = I` this is (32) with :math:`T = (I - R)C^{-1}`). Unmeasured states:
        :math:`v_u = R_{21}x_m + R_{22}x_u` gives :math:`x_u = R_{22}^{-1}(v_u - R_{21}x_m)`, whose box over
        :math:`v_u \in [\underline z_u, \overline z_u]` is the exact hull :func:`matvec_bounds` (:math:`R` is a
        point matrix at the sample: it depends on measured states only). ``r`` is (n, n) or one per run
        (M, n, n).
        """
        p = self.p
        x_m = y @ self.c_inv.T
        r11 = r[..., :p, :p]
        v_m = np.einsum("...ij,...j->...i", r11, x_m)
        shape = np.broadcast_shapes(z_lower.shape, (y.shape[0], self.n))
        x_lo, x_hi = np.empty(shape), np.empty(shape)
        x_lo[:, :p], x_hi[:, :p] = z_lower[:, :p] + x_m - v_m, z_upper[:, :p] + x_m - v_m  # (32)
        if p < self.n:
            r21x = np.einsum("...ij,...j->...i", r[..., p:, :p], x_m)
            x_lo[:, p:], x_hi[:, p:] = matvec_bounds(
                np.linalg.inv(r[..., p:, p:]), z_lower[:, p:] - r21x, z_upper[:, p:] - r21x
            )
        x_lo, x_hi = inflate(x_lo, x_hi)
        eps_lo, eps_hi = np.zeros(shape), np.zeros(shape)
        eps_lo[:, :p] = v_m - z_lower[:, :p]  # (29)
        eps_hi[:, :p] = z_upper[:, :p] - v_m  # (30)
        return x_lo, x_hi, eps_lo, eps_hi

    def _advance_generic(
        self, z_lower: FloatArray, z_upper: FloatArray, y: FloatArray, u: FloatArray, theta: FloatArray | None
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        gen, des = self.generic, self.design_result
        assert gen is not None and des is not None
        if theta is None:
            raise DataError(
                f"theta: expected the measured scheduling vector, shape (..., {self.system.n_theta}), got None"
            )
        x_meas = y @ des.C_tilde_inv.T  # measured states, (9)
        x_lo, x_hi, eps_lo, eps_hi = self._state_box(des.R, z_lower, z_upper, y)  # (32), (29)-(30)
        psi_lo, psi_hi, el, pl, eu, pu = gen.step(x_lo, x_hi, x_meas, u, theta)
        zl = np.einsum("mij,mj->mi", el, z_lower) + np.einsum("mij,mj->mi", pl, psi_lo)
        zu = np.einsum("mij,mj->mi", eu, z_upper) + np.einsum("mij,mj->mi", pu, psi_hi)
        zl, zu = inflate(zl, zu)
        return x_lo, x_hi, eps_lo, eps_hi, zl, zu

    def _check_theta(self, theta: ArrayLike | None, lead: tuple[int, ...]) -> FloatArray | None:
        if self.generic is None:
            if theta is not None:
                raise DataError("theta: this observer's model computes the scheduling vector itself; got theta")
            return None
        if theta is None:
            raise DataError(
                f"theta: expected the measured scheduling vector, shape (..., {self.system.n_theta}), got None"
            )
        th = as_array("theta", theta)
        n_t = self.system.n_theta
        if n_t == 1 and th.shape in (lead, lead[-1:]):
            th = th[..., None]
        if th.shape[-1] != n_t or th.shape[:-1] not in (lead, lead[-1:]) or not np.all(np.isfinite(th)):
            raise DataError(f"theta: expected finite values of shape {(*lead, n_t)}, got {np.shape(theta)}")
        lo, hi = self.system.theta_box
        if np.any(th < lo) or np.any(th > hi):
            raise DataError(f"theta: expected values in theta_box [{lo.tolist()}, {hi.tolist()}], got values outside")
        return np.asarray(np.broadcast_to(th, (*lead, n_t)))

    # --- protocol ---------------------------------------------------------------------------------
    def _rx_bounds(self, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        if self.model is not None:
            return self.model.rx_bounds(lo, hi)
        assert self.design_result is not None
        return matvec_bounds(self.design_result.R, lo, hi)

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State at :math:`t_0` from the prior box: :math:`\\underline z_0, \\overline z_0` bound
        :math:`R(\\vartheta_0)x_0` over the box (the paper's :math:`\\underline\\xi_0`).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,) or (M, n), optional
            Prior box (default: ``bounds.x0`` of the constructor).

        Returns
        -------
        ObserverState
        """
        if x0_lower is None or x0_upper is None:
            if self.bounds is None:
                raise DataError("x0_lower, x0_upper: expected a prior box (or bounds in the constructor), got None")
            lo, hi = self.bounds.x0
        else:
            lo = np.asarray(x0_lower, dtype=float)
            hi = np.asarray(x0_upper, dtype=float)
            if lo.shape != hi.shape or lo.shape[-1] != self.n or np.any(lo > hi) or not np.all(np.isfinite(lo + hi)):
                raise DataError(
                    f"x0: expected finite lower <= upper of shape (..., {self.n}), got {lo.shape}, {hi.shape}"
                )
        lo2, hi2 = np.atleast_2d(lo), np.atleast_2d(hi)
        zl, zu = inflate(*self._rx_bounds(lo2, hi2))
        if lo.ndim == 1:
            zl, zu = zl[0], zu[0]
        return ObserverState(
            lower=np.array(lo, dtype=float), upper=np.array(hi, dtype=float), internal={"z_lower": zl, "z_upper": zu}
        )

    def step(
        self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None, theta: ArrayLike | None = None
    ) -> ObserverState:
        """Consume ``y_k, u_k`` (and ``theta_k``); return the box of :math:`x(t_k)` and :math:`z_{k+1}`.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or a previous :meth:`step`.
        y : array_like, shape (p,) or (M, p)
            Output at :math:`t_k`.
        u : array_like, shape (m,) or (M, m), optional
            Known input at :math:`t_k` (default 0).
        theta : array_like, shape (n_theta,) or (M, n_theta), optional
            Scheduling vector at :math:`t_k` (required by designed observers).

        Returns
        -------
        ObserverState
            ``internal`` holds ``z_lower``, ``z_upper`` (at :math:`t_{k+1}`), ``eps_lower``,
            ``eps_upper`` (at :math:`t_k`).
        """
        ys = as_array("y", y)
        if ys.shape[-1:] != (self.p,) or ys.ndim > 2 or not np.all(np.isfinite(ys)):
            raise DataError(f"y: expected finite values of shape (..., {self.p}), got {ys.shape}")
        us = self._input(u, ys.shape[:-1])
        th = None if theta is None else np.atleast_2d(as_array("theta", theta))
        th = self._check_theta(th, (np.atleast_2d(ys).shape[0],))
        return self._step(state, ys, us, th if th is None or ys.ndim == 2 else th[0])

    def _step(
        self, state: ObserverState, y: FloatArray, u: FloatArray, theta: FloatArray | None = None
    ) -> ObserverState:
        """:meth:`step` on a validated sample (``theta`` of the sample's leading shape, or None)."""
        single = y.ndim == 1
        zl = np.atleast_2d(state.internal["z_lower"])
        zu = np.atleast_2d(state.internal["z_upper"])
        th = None if theta is None else np.atleast_2d(theta)
        x_lo, x_hi, e_lo, e_hi, zl, zu = self.advance(zl, zu, np.atleast_2d(y), np.atleast_2d(u), th)
        if single:
            x_lo, x_hi, e_lo, e_hi, zl, zu = (a[0] for a in (x_lo, x_hi, e_lo, e_hi, zl, zu))
        return ObserverState(
            lower=x_lo,
            upper=x_hi,
            internal={"z_lower": zl, "z_upper": zu, "eps_lower": e_lo, "eps_upper": e_hi},
        )

    def run_with_signals(
        self,
        t: ArrayLike,
        y: ArrayLike,
        u: ArrayLike | None = None,
        x0_lower: ArrayLike | None = None,
        x0_upper: ArrayLike | None = None,
        theta: ArrayLike | None = None,
    ) -> tuple[Estimate, FloatArray, FloatArray]:
        """Like :meth:`run`, also returning the isolation signals (lower and upper ε).

        A component of a signal below zero says the output left the bounds from that side: a fault acts
        on that direction.

        Parameters
        ----------
        t : array_like, shape (T,)
            Uniform sample times, spacing ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Outputs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs.
        x0_lower, x0_upper : array_like, optional
            Prior box (default: the constructor's ``bounds.x0``).
        theta : array_like, shape (T, n_theta) or (M, T, n_theta), optional
            Measured scheduling vector (required by designed observers).

        Returns
        -------
        estimate : Estimate
        eps_lower, eps_upper : numpy.ndarray, shape like ``estimate.lower``

        References
        ----------
        Rotondo et al.: the isolation signals (29)–(30).
        """
        times, ys, us = self._signals(t, y, u)
        th = self._check_theta(theta, ys.shape[:-1])
        state = self.init(x0_lower, x0_upper)
        signals = {} if th is None else {"theta": th}
        estimate, eps = self._loop(times, ys, us, state, signals, collect=("eps_lower", "eps_upper"))
        return estimate, eps["eps_lower"], eps["eps_upper"]

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            ``method`` and ``h``.
        """
        return {"method": self.method, "h": self.h}

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None, theta: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record; ``y`` is (T, p) or (M, T, p); row k is the box of :math:`x(t_k)`.

        Parameters
        ----------
        t : array_like, shape (T,)
            Uniform sample times, spacing ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Outputs.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known inputs (held over each step).
        theta : array_like, shape (T, n_theta) or (M, T, n_theta), optional
            Measured scheduling vector (required by designed observers).

        Returns
        -------
        Estimate
        """
        return self.run_with_signals(t, y, u, theta=theta)[0]


class LPVIntervalUIO(LPVIntervalObserver):
    r"""Interval unknown-input observer of an uncertain LPV system, with fault-isolation signals.

    On top of :class:`LPVIntervalObserver`: the bounded term of :math:`R\Delta B_{un}u_{un}` enters
    both bounds (:math:`\underline w^4, \overline w^4 \ge 0`); the switching rule is built into the
    sampled step (module docstring); :math:`H = R B_{un}` must be constant and its columns
    eigenvectors of both F, so that each unknown input moves the error along its own direction only —
    checked here.

    Parameters
    ----------
    model : SampledLPVModel
        As for :class:`LPVIntervalObserver`.
    h : float
        Sampling interval (s).
    f_lower, f_upper : array_like, shape (n, n)
        Metzler Hurwitz observer matrices.
    bounds : Bounds, optional
        Default prior box ``x0`` (its disturbance box ``w`` must be zero).
    unknown_input : tuple of array_like
        ``(lower, upper)`` of :math:`u_{un}` with lower ≤ 0 ≤ upper (no fault is a possible value).

    Raises
    ------
    AssumptionError
        If :math:`RB_{un}` is not constant, the bounds do not contain 0, or H's columns are not
        eigenvectors of F.

    References
    ----------
    Rotondo et al.: the observer (69)–(72) with the isolation signals (29)–(30); the bounds (69), (71)
    with the terms of (83), (85); H of (26) and its eigenvector condition (103)–(104), Theorem 4.1; the
    input bounds of Assumption 2.2.
    """

    summary_fields = ("method", "q")

    method = "lpv-interval-uio"

    def __init__(
        self,
        model: SampledLPVModel,
        h: float,
        f_lower: ArrayLike,
        f_upper: ArrayLike | None = None,
        bounds: Bounds | None = None,
        unknown_input: tuple[ArrayLike, ArrayLike] = ((), ()),
    ) -> None:
        super().__init__(model, h, f_lower, f_upper, bounds)
        system = model.system
        if system.B_un is None:
            raise AssumptionError("B_un: the interval UIO needs unknown-input directions, got None")
        self.q = system.q
        self.u_un = self._unknown_input_box(system, unknown_input)
        points = system.test_points()
        rb = np.einsum("kij,kjl->kil", model.r_matrix(points @ system.C.T), system.matrix_at("B_un", points))
        self.H = rb[0]
        if not np.allclose(rb, self.H, atol=1e-9 * max(1.0, float(np.abs(self.H).max()))):
            raise AssumptionError(
                "R, B_un: expected R(θ) B_un(θ) = H constant on theta_box (unknown-input directions fixed)"
            )
        for name, f in (("f_lower", self.f_lower), ("f_upper", self.f_upper)):
            gam = np.linalg.pinv(self.H) @ f @ self.H
            if not np.allclose(f @ self.H, self.H @ np.diag(np.diag(gam)), atol=1e-9):
                raise AssumptionError(
                    f"{name}: expected F H = H Γ with Γ diagonal (each unknown input decays on its own)"
                )

    @staticmethod
    def _unknown_input_box(
        system: LPVSystem, unknown_input: tuple[ArrayLike, ArrayLike]
    ) -> tuple[FloatArray, FloatArray]:
        box = as_box("unknown_input", unknown_input, system.q)
        if np.any(box[0] > 0) or np.any(box[1] < 0):
            raise AssumptionError("unknown_input: expected lower <= 0 <= upper (no fault is a possible value)")
        return box

    @classmethod
    @options_after_bounds("h", "theta_rate", "unknown_input", "decay")
    def design(
        cls,
        system: LPVSystem,
        bounds: Bounds,
        *,
        h: float,
        theta_rate: ArrayLike,
        unknown_input: tuple[ArrayLike, ArrayLike] = ((), ()),
        decay: float = 1.0,
        **design_options: Any,
    ) -> LPVIntervalUIO:
        r"""Design the gains by LMIs with decay :math:`\Gamma = -\lambda I` and run with generic enclosures.

        Parameters
        ----------
        system : LPVSystem
            Model with :math:`C = (\tilde C\ 0)`, a constant ``B_un``, and an uncertainty of the
            measured states' equations that involves no unmeasured state (ΔA12 = 0).
        bounds : Bounds
            Prior box ``x0`` of :math:`x(t_0)` and the box ``w`` of the disturbance d.
        h : float
            Sampling interval (s).
        theta_rate : array_like, shape (n_theta,) or float
            Bound of :math:`|\dot\vartheta|` (``inf`` allowed).
        unknown_input : tuple of array_like
            ``(lower, upper)`` of :math:`u_{un}`, lower ≤ 0 ≤ upper (no fault is a possible value).
        decay : float
            :math:`\lambda` of :math:`\Gamma = -\lambda I`.
        **design_options
            Passed to :func:`~intervalobs.design.lpv_gains.design_lpv_observer` (``grid``,
            ``fine_grid``, ``eps2``, ``q_scale``, ``gain_bound``).

        Returns
        -------
        LPVIntervalUIO

        Raises
        ------
        AssumptionError
            If the input bounds exclude 0, ΔA12 ≠ 0, or B_un is missing or not constant.
        DesignError
            Naming the failed design condition.

        References
        ----------
        Rotondo et al.: LMIs (107)–(117), Corollary 4.1; Assumptions 2.2 (input bounds) and 2.3
        (ΔA12 = 0).
        """
        for key in design_options:
            if key not in {"grid", "fine_grid", "eps2", "q_scale", "gain_bound"}:
                raise ArgumentTypeError(f"design() got an unexpected keyword argument {key!r}")
        if system.B_un is None:
            raise AssumptionError("B_un: the interval UIO needs unknown-input directions, got None")
        box = cls._unknown_input_box(system, unknown_input)
        _check_assumption_3(system)
        design = design_lpv_observer(system, uio=True, decay=decay, **design_options)
        obs = cls._generic(system, bounds, h, theta_rate, design, box)
        obs.q = system.q
        obs.u_un = box
        assert design.H is not None
        obs.H = design.H
        return obs

    def _unknown_input_term(self, bul: FloatArray, buh: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        return interval_matvec_bounds(bul, buh, self.u_un[0], self.u_un[1])


def _check_assumption_3(system: LPVSystem) -> None:
    """Assumption 2.3 (25): the uncertainty does not couple the unmeasured states into the measured ones."""
    p = system.p
    points = system.test_points()
    bounds = system.bounds_at("dA", points)
    if bounds is not None and (np.any(bounds[0][:, :p, p:] != 0) or np.any(bounds[1][:, :p, p:] != 0)):
        raise AssumptionError(
            "dA: expected ΔA12 = 0: the unmeasured states must act on the measured ones through exactly known terms"
        )
