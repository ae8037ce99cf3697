r"""Interval estimator of a two-link arm's velocities from its joint angles only (:math:`C = (I_2\ 0)`).

Rotondo et al.'s observer needs :math:`\dot q` measured: it is part of the scheduling vector
:math:`\vartheta = x`, and :math:`CB_{un} = 0` for :math:`C = (I_2\ 0)`. Here the scheduling variable
:math:`\phi = q_2 - q_1` is measured and the velocities enter only through boxes (interval scheduling).
Coordinates: the nominal momentum :math:`p = M(\phi)\dot q`, :math:`M = \left(\begin{smallmatrix} a &
b\kappa\\ b\kappa & c\end{smallmatrix}\right)`, :math:`\kappa = \cos\phi`, whose rate is the first two
rows of the paper's :math:`\tfrac{d}{dt}(Rx)` (the model's ``box_enclosure``):

.. math:: \dot p = (b\sigma\dot q_1\dot q_2 + u_1,\, -b\sigma\dot q_1\dot q_2 + u_2)
          + \Delta A_R x + \Delta B_R u + (I + \Delta B_{un,R})u_{un}.

On the step :math:`[t_k, t_{k+1}]`, with :math:`q_k` measured,
:math:`\zeta = M(\phi)(\dot q - \lambda(q - q_k))` obeys :math:`\dot\zeta = -\lambda\zeta + \psi`,
:math:`\psi = \dot p - \lambda(\dot M + \lambda M)(q - q_k)`, :math:`\dot M = -b\sigma\dot\phi
\left(\begin{smallmatrix}0&1\\1&0\end{smallmatrix}\right)` (a constant Metzler :math:`F = -\lambda I`
in coordinates :math:`R(\phi)` that depend on the measured angle only). With :math:`X_k` a box of
:math:`x(t)` on the step (the model's flow box from the angles and the velocity box), :math:`\psi` is
bounded over :math:`X_k` by interval arithmetic, and

.. math:: p_{k+1} \in e^{-\lambda h}P_k + \tfrac{1 - e^{-\lambda h}}{\lambda}[\underline\psi_k,
          \overline\psi_k] + \lambda M(\phi_{k+1})(q_{k+1} - q_k),\qquad
          \dot q_k \in M(\phi_k)^{-1}P_k \ \text{(exact hull)}.

The angle increment also bounds :math:`p_k` (one step late): :math:`M(\phi_k)(q_{k+1} - q_k) =
\int p\,dt + \int (M(\phi_k) - M(\phi))\dot q\,dt \in h p_k + \tfrac{h^2}{2}[\dot p] +
h\,b(\kappa_k - \cos\Phi_k)\left(\begin{smallmatrix}0&1\\1&0\end{smallmatrix}\right)\dot Q_k`
(weights :math:`h - s \ge 0`), a box :math:`C_k` of :math:`p_k`. The estimator intersects
:math:`P_k` with :math:`C_k` before propagating; the consistency signals are :math:`\overline{C}_k -
\underline{P}_k` and :math:`\overline{P}_k - \underline{C}_k`: negative means the intersection is
empty, i.e. the record is inconsistent with the run's fault box. The run then restarts from
:math:`C_k` alone: its box means nothing any more, but it stays finite, so a refuted hypothesis does
not stop the other runs of a bank. All boxes are widened by :func:`~intervalobs.interval.inflate`.

Soundness needs only the model, its parameter box, :math:`u_{un} \in` the fault box and
:math:`h\max|\ddot q| \le 1` (checked by the model's flow box); :math:`\lambda > 0` makes the widths
bounded (the velocity box enters :math:`\psi` only through the Coriolis terms, :math:`\Delta A_R` and
:math:`O(h)` terms).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import BoundsError, DataError
from ..estimate import Estimate
from ..interval import Interval, inflate, interval_matvec_bounds, matvec_bounds, product_bounds
from ..systems.bounds import Bounds
from ..systems.lpv import StepEnclosure
from ..validation import as_box, as_positive
from .base import Observer, ObserverState

__all__ = ["AnglesOnlyObserver"]

FloatArray = NDArray[np.float64]
Box = tuple[FloatArray, FloatArray]


class TwoLinkArmModel(Protocol):
    r"""What :class:`AnglesOnlyObserver` needs of a two-link arm (``examples.manipulator.ManipulatorModel``).

    A structural type for the annotations (not exported): any object with these members will do.

    The state is :math:`x = (q_1, q_2, \dot q_1, \dot q_2)` and the nominal mass matrix
    :math:`M(\phi) = \left(\begin{smallmatrix} a & b\cos\phi\\ b\cos\phi & c\end{smallmatrix}\right)`,
    :math:`\phi = q_2 - q_1`.
    """

    nominal: tuple[float, float, float]
    r"""The nominal a, b, c of :math:`M(\phi)`."""
    fault_bound: float
    """The bound of :math:`|u_{un}|` (each component) that the flow box assumes."""

    def flow_box_from_angles(
        self, q: FloatArray, w_lower: FloatArray, w_upper: FloatArray, u: FloatArray, h: float
    ) -> Box:
        """A box of :math:`x(t)` over :math:`[t_k, t_k + h]` from the angles and a box of the velocities at ``t_k``."""
        ...  # pragma: no cover

    def box_enclosure_at_phase(
        self, flo: FloatArray, fhi: FloatArray, u: FloatArray, kappa: Interval, sigma: Interval
    ) -> StepEnclosure:
        """The rate and uncertainty enclosures over a flow box, given the ranges of cos φ and sin φ on it."""
        ...  # pragma: no cover


class AnglesOnlyObserver(Observer):
    r"""Velocity bounds of a two-link arm from its joint angles (momentum coordinates; module docstring).

    Row ``k`` of :meth:`run` bounds :math:`x(t_k) = (q, \dot q)` given :math:`y_0, \dots, y_k` (angles
    exact, velocities bounded). A leading axis of the record holds runs; the fault box may differ per run
    (a bank of hypotheses such as "fault 1 absent").

    Parameters
    ----------
    model : TwoLinkArmModel
        The arm (nominal parameters, certified parameter box, fault bound of the flow box).
    h : float
        Sampling period (s); the record must be sampled every ``h``.
    velocity_box : tuple of array_like, shape (2,)
        Prior box of :math:`\dot q(t_0)` (rad/s).
    unknown_input : tuple of array_like, shape (2,) or (M, 2)
        Box of :math:`u_{un}` assumed by every run, or one per run: lower ≤ 0 ≤ upper, inside the model's
        fault bound.
    decay : float
        :math:`\lambda > 0` (1/s). The angle increments (the boxes :math:`C_k`) dominate the widths; a large
        λ lets the injection :math:`\lambda M(q_{k+1} - q_k)` absorb a fault before the signals see it.

    Raises
    ------
    BoundsError
        If the fault box does not contain 0 or exceeds the model's fault bound.
    """

    h: float
    rows = "filtered"
    summary_fields = ("decay",)
    method = "angles-only"

    def __init__(
        self,
        model: TwoLinkArmModel,
        h: float,
        velocity_box: tuple[ArrayLike, ArrayLike],
        unknown_input: tuple[ArrayLike, ArrayLike],
        decay: float = 1.0,
    ) -> None:
        self.model = model
        self.n, self.p, self.m = 4, 2, 2
        self.h = as_positive("h", h, "a positive sampling period")
        self.decay = as_positive("decay", decay, "a positive decay rate λ (1/s)")
        self.velocity_box = as_box("velocity_box", velocity_box, 2)
        self.unknown_input = _fault_box(unknown_input, model.fault_bound)
        self._faults: dict[int, Box] = {}  # the fault box broadcast to a number of runs
        # ζ over one step: e^{-λh} and (1 - e^{-λh})/λ
        self._propagation = float(np.exp(-self.decay * self.h)), float(-np.expm1(-self.decay * self.h) / self.decay)

    @classmethod
    def design(
        cls,
        system: TwoLinkArmModel,
        bounds: Bounds,
        *,
        h: float,
        unknown_input: tuple[ArrayLike, ArrayLike],
        decay: float = 1.0,
    ) -> AnglesOnlyObserver:
        r"""The estimator for a prior box of the state: only its velocity part is used (the angles are measured).

        Parameters
        ----------
        system : TwoLinkArmModel
            The arm.
        bounds : Bounds
            ``x0``: prior box of :math:`x(t_0) = (q, \dot q)`; no disturbance or noise box (the fault box
            is ``unknown_input``).
        h : float
            Sampling period (s).
        unknown_input : tuple of array_like, shape (2,) or (M, 2)
            Box of :math:`u_{un}`, one for every run or one per run.
        decay : float
            :math:`\lambda > 0` (1/s).

        Returns
        -------
        AnglesOnlyObserver
        """
        x0_lower, x0_upper = as_box("bounds.x0", bounds.x0, 4)
        for name in ("w", "v"):
            box = getattr(bounds, name)
            if box is not None and (np.any(box[0] != 0) or np.any(box[1] != 0)):
                raise BoundsError(f"bounds.{name}: expected none (the arm's only unknown input is the fault box)")
        return cls(system, h, (x0_lower[2:], x0_upper[2:]), unknown_input, decay)

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            ``method``, ``h`` and ``decay``.
        """
        return {"method": self.method, "h": self.h, "decay": self.decay}

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """State before the first sample: the prior box of the velocities (the angles come with ``y_0``).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (4,), optional
            Prior box of :math:`x(t_0)` (default: the velocity box of the constructor); its angles are unused.

        Returns
        -------
        ObserverState
        """
        v_lo, v_hi = self.velocity_box
        if x0_lower is not None and x0_upper is not None:
            x_lo, x_hi = as_box("x0", (x0_lower, x0_upper), 4)
            v_lo, v_hi = x_lo[2:], x_hi[2:]
        lower, upper = np.concatenate([np.full(2, -np.inf), v_lo]), np.concatenate([np.full(2, np.inf), v_hi])
        return ObserverState(lower=lower, upper=upper)

    def step(self, state: ObserverState, y: ArrayLike, u: ArrayLike | None = None) -> ObserverState:
        """Consume the angles ``y_k`` and the torque ``u_k``; return the box of :math:`x(t_k)`.

        Parameters
        ----------
        state : ObserverState
            From :meth:`init` or the previous :meth:`step`.
        y : array_like, shape (2,) or (M, 2)
            Measured joint angles at ``t_k`` (rad).
        u : array_like, shape (2,) or (M, 2)
            Known torque at ``t_k``, held until ``t_{k+1}`` (N·m).

        Returns
        -------
        ObserverState
            Box of :math:`x(t_k)` given :math:`y_0 \\dots y_k`; ``internal`` holds the momentum box and the
            consistency signals at ``t_k`` (``inf`` at the first sample).
        """
        yk, uk = self._sample(y, u)
        previous = state.internal.get("angles")
        pair = yk[..., None, :] if previous is None else np.stack(np.broadcast_arrays(previous, yk), axis=-2)
        terms = {name: value[..., -1, :] for name, value in self._angle_terms(pair).items()}
        return self._step(state, yk, uk, **terms)

    def run_with_signals(
        self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None
    ) -> tuple[Estimate, FloatArray, FloatArray]:
        """Bounds over a whole record and the consistency signals of every sample.

        Parameters
        ----------
        t : array_like, shape (T,)
            Sample times (s), spacing ``h``.
        y : array_like, shape (T, 2) or (M, T, 2)
            Measured joint angles (rad).
        u : array_like, shape (T, 2) or (M, T, 2)
            Known torque, held over each step (N·m).

        Returns
        -------
        estimate : Estimate
        signal_lower, signal_upper : numpy.ndarray, shape (T, 2) or (M, T, 2)
            :math:`\\overline C_{k-1} - \\underline P_{k-1}` and :math:`\\overline P_{k-1} - \\underline C_{k-1}`,
            known at ``t_k`` (row 0: ``inf``). Both are :math:`\\ge 0` for every admissible realisation of the
            run's fault box; a negative value proves the angles inconsistent with it.
        """
        times, ys, us = self._signals(t, y, u)
        estimate, signals = self._loop(
            times, ys, us, signals=self._angle_terms(ys), collect=("signal_lower", "signal_upper")
        )
        return estimate, signals["signal_lower"], signals["signal_upper"]

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds over a whole record: :meth:`init`, then :meth:`step` at every sample.

        Parameters
        ----------
        t, y, u : array_like
            Sample times, joint angles and torques, as for :meth:`run_with_signals`.

        Returns
        -------
        Estimate
            Row ``k`` bounds :math:`x(t_k)` given :math:`y_0 \\dots y_k`.
        """
        return self.run_with_signals(t, y, u)[0]

    def _angle_terms(self, angles: FloatArray) -> dict[str, FloatArray]:
        """:func:`_angle_terms` of a record (..., T, 2), each sample's row holding what its step uses."""
        lead = angles.shape[:-2]
        flat = angles.reshape(-1, *angles.shape[-2:])
        kappa, mass, inverse, (meas, meas_scale), (shift, shift_scale) = _angle_terms(
            self.model.nominal, flat, self.h, self.decay
        )

        def late(values: FloatArray) -> FloatArray:  # the increment from t_{k-1} to t_k, used at t_k
            return np.concatenate([np.full((values.shape[0], 1, *values.shape[2:]), np.nan), values], axis=1)

        terms = {
            "mass": mass.reshape(*flat.shape[:2], 4),
            "inverse": inverse.reshape(*flat.shape[:2], 4),
            "kappa": late(kappa[:, :-1, None]),
            "meas": late(meas),
            "meas_scale": late(meas_scale),
            "shift": late(shift),
            "shift_scale": late(shift_scale),
        }
        return {name: value.reshape(*lead, *value.shape[1:]) for name, value in terms.items()}

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray, **terms: FloatArray) -> ObserverState:
        """:meth:`step` on a validated sample, given its :meth:`_angle_terms` (one record: a run axis of 1)."""
        single = y.ndim == 1

        def runs_first(value: FloatArray) -> FloatArray:
            return value[None] if single else value

        qk, uk = runs_first(y), runs_first(u)
        term = {name: runs_first(value) for name, value in terms.items()}
        previous = {name: runs_first(value) for name, value in state.internal.items()}
        lower, upper = runs_first(state.lower), runs_first(state.upper)
        runs = qk.shape[0]
        if "angles" not in previous:  # the first sample: the prior velocity box in momentum coordinates
            v_lo, v_hi = np.broadcast_to(lower[..., 2:], (runs, 2)), np.broadcast_to(upper[..., 2:], (runs, 2))
            p_lo, p_hi = inflate(*matvec_bounds(term["mass"].reshape(-1, 2, 2), v_lo, v_hi))
            sig_lo, sig_hi = np.full((runs, 2), np.inf), np.full((runs, 2), np.inf)
        else:
            (p_lo, p_hi), (sig_lo, sig_hi) = self._advance(previous, (lower[:, 2:], upper[:, 2:]), term)
        w_lo, w_hi = inflate(*matvec_bounds(term["inverse"].reshape(-1, 2, 2), p_lo, p_hi))
        lower, upper = np.concatenate([qk, w_lo], axis=-1), np.concatenate([qk, w_hi], axis=-1)
        internal = {
            "momentum_lower": p_lo,
            "momentum_upper": p_hi,
            "angles": qk,
            "torque": uk,
            "signal_lower": sig_lo,
            "signal_upper": sig_hi,
        }
        if single:
            lower, upper = lower[0], upper[0]
            internal = {name: value[0] for name, value in internal.items()}
        return ObserverState(lower=lower, upper=upper, internal=internal)

    def _advance(self, previous: dict[str, FloatArray], velocity: Box, term: dict[str, FloatArray]) -> tuple[Box, Box]:
        """The momentum box at ``t_k`` from the state at ``t_{k-1}``, and the signals of its intersection with C."""
        p_lo, p_hi = previous["momentum_lower"], previous["momentum_upper"]
        (psi_lo, psi_hi), (m_lo, m_hi) = _step_bounds(
            self.model,
            previous["angles"],
            previous["torque"],
            velocity,
            self._fault_for(p_lo.shape[0]),
            self.decay,
            self.h,
            term["kappa"],
            term["meas"],
            term["meas_scale"],
        )
        signals = (m_hi - p_lo, p_hi - m_lo)
        ok = np.all((m_hi >= p_lo) & (m_lo <= p_hi), axis=-1)[:, None]
        p_lo, p_hi = np.where(ok, np.maximum(p_lo, m_lo), m_lo), np.where(ok, np.minimum(p_hi, m_hi), m_hi)
        # propagate ζ over the step and shift to p_k
        decay, gain = self._propagation
        shift = term["shift"]
        size = decay * np.maximum(np.abs(p_lo), np.abs(p_hi)) + gain * np.maximum(np.abs(psi_lo), np.abs(psi_hi))
        momentum = inflate(
            decay * p_lo + gain * psi_lo + shift, decay * p_hi + gain * psi_hi + shift, scale=size + term["shift_scale"]
        )
        return momentum, signals

    def _fault_for(self, runs: int) -> Box:
        """The fault box of each of ``runs`` runs (one box for all, or one per run)."""
        if runs not in self._faults:
            f_lo, f_hi = self.unknown_input
            if f_lo.ndim == 2 and f_lo.shape[0] not in (1, runs):
                raise DataError(f"y: expected {f_lo.shape[0]} runs (one per fault box of unknown_input), got {runs}")
            self._faults[runs] = np.broadcast_to(f_lo, (runs, 2)), np.broadcast_to(f_hi, (runs, 2))
        return self._faults[runs]


def _fault_box(unknown_input: tuple[ArrayLike, ArrayLike], bound: float) -> Box:
    """``(lower, upper)`` of shape (2,) or (M, 2), finite, lower ≤ 0 ≤ upper, within ``±bound``."""
    f_lo, f_hi = (np.array(side, dtype=float) for side in unknown_input)
    if f_lo.shape != f_hi.shape or f_lo.shape[-1:] != (2,) or f_lo.ndim > 2 or not np.all(np.isfinite(f_lo + f_hi)):
        raise BoundsError(
            f"unknown_input: expected finite boxes of shape (2,) or (M, 2), got {f_lo.shape}, {f_hi.shape}"
        )
    if np.any(f_lo > 0) or np.any(f_hi < 0) or np.any(np.maximum(-f_lo, f_hi) > bound):
        raise BoundsError(
            f"unknown_input: expected lower <= 0 <= upper within ±{bound:g}, got {f_lo.tolist()}, {f_hi.tolist()}"
        )
    return f_lo, f_hi


def _mass(nominal: tuple[float, float, float], kappa: FloatArray) -> FloatArray:
    """Nominal :math:`M(\\phi)` at points :math:`\\kappa = \\cos\\phi`, shape (..., 2, 2)."""
    a, b, c = nominal
    out = np.empty((*kappa.shape, 2, 2))
    out[..., 0, 0], out[..., 1, 1] = a, c
    out[..., 0, 1] = out[..., 1, 0] = b * kappa
    return out


def _step_bounds(
    model: TwoLinkArmModel,
    qk: FloatArray,
    uk: FloatArray,
    velocity: Box,
    fault: Box,
    lam: float,
    h: float,
    kap: FloatArray,
    meas: FloatArray,
    meas_scale: FloatArray,
) -> tuple[Box, Box]:
    r"""Bounds of ψ over the step from ``t_k`` and the box ``C_k`` of ``p_k`` from the angle increment.

    ``kap`` is :math:`\kappa_k` (shape (M, 1)), ``meas`` is :math:`M(\phi_k)(q_{k+1} - q_k)/h` and
    ``meas_scale`` the size of its terms (for the outward margin); see the module docstring.
    """
    b = model.nominal[1]
    diag = lam * lam * np.array([model.nominal[0], model.nominal[2]])
    eye = np.eye(2)
    flo, fhi = model.flow_box_from_angles(qk, velocity[0], velocity[1], uk, h)
    phase = Interval._raw(flo[..., 1] - fhi[..., 0], fhi[..., 1] - flo[..., 0])  # φ = q2 − q1 over the flow box
    kappa, sigma = np.cos(phase), np.sin(phase)
    enc = model.box_enclosure_at_phase(flo, fhi, uk, kappa, sigma)
    # ṗ over the step; ΔA_R has nonzero entries only in rows 1-2, columns 3-4
    da = interval_matvec_bounds(enc.da_lower[:, :2, 2:], enc.da_upper[:, :2, 2:], flo[:, 2:], fhi[:, 2:])
    db = interval_matvec_bounds(enc.db_lower[:, :2], enc.db_upper[:, :2], uk, uk)
    fb = interval_matvec_bounds(eye + enc.dbun_lower[:, :2], eye + enc.dbun_upper[:, :2], fault[0], fault[1])
    pd_lo = enc.rate_lower[:, :2] + da[0] + db[0] + fb[0]
    pd_hi = enc.rate_upper[:, :2] + da[1] + db[1] + fb[1]
    # ψ = ṗ − λ(Ṁ + λM)(q − q_k): diagonal λ²(a, c), off-diagonal λb(λκ − σφ̇); q − q_k ∈ [dl, dh] ∋ 0
    s_lo, s_hi = product_bounds(sigma.lower, sigma.upper, flo[:, 3] - fhi[:, 2], fhi[:, 3] - flo[:, 2])
    off_lo, off_hi = lam * b * (lam * kappa.lower - s_hi), lam * b * (lam * kappa.upper - s_lo)
    dl, dh = flo[:, :2] - qk, fhi[:, :2] - qk
    o_lo, o_hi = product_bounds(off_lo[:, None], off_hi[:, None], dl[:, ::-1], dh[:, ::-1])
    psi = (pd_lo - diag * dh - o_hi, pd_hi - diag * dl - o_lo)
    # the angle increment bounds p_k (box C_k): M(φ_k)Δq/h − (h/2)[ṗ] − b(κ_k − cos Φ)J[q̇]
    e_lo, e_hi = product_bounds(
        b * (kap - kappa.upper[:, None]), b * (kap - kappa.lower[:, None]), flo[:, [3, 2]], fhi[:, [3, 2]]
    )
    return psi, inflate(meas - 0.5 * h * pd_hi - e_hi, meas - 0.5 * h * pd_lo - e_lo, scale=meas_scale)


def _angle_terms(
    nominal: tuple[float, float, float], qs: FloatArray, h: float, lam: float
) -> tuple[FloatArray, FloatArray, FloatArray, Box, Box]:
    r"""Everything of the estimator that depends on the measured angles only, for all samples at once.

    ``qs`` has shape (M, T, 2). Returns :math:`\kappa` (M, T), :math:`M(\phi)` and its inverse
    (M, T, 2, 2), then :math:`M(\phi_k)(q_{k+1} - q_k)/h` and :math:`\lambda M(\phi_{k+1})(q_{k+1} - q_k)`
    (M, T - 1, 2), each with the size of its terms (for the outward margin).
    """
    a, b, c = nominal
    kap_all = np.cos(qs[..., 1] - qs[..., 0])  # (M, T)
    mass = _mass(nominal, kap_all)  # (M, T, 2, 2)
    det = a * c - (b * kap_all) ** 2
    inv = np.stack([np.full_like(kap_all, c), -b * kap_all, -b * kap_all, np.full_like(kap_all, a)], axis=-1)
    inv = inv.reshape(mass.shape)
    inv = inv / det[..., None, None]
    dq_all = np.diff(qs, axis=1)  # (M, T - 1, 2)
    q_abs = np.abs(qs[:, :-1]) + np.abs(qs[:, 1:])
    meas_all = np.einsum("mkij,mkj->mki", mass[:, :-1], dq_all) / h  # M(φ_k)(q_{k+1} − q_k)/h
    meas_scale = np.abs(meas_all) + np.einsum("mkij,mkj->mki", np.abs(mass[:, :-1]), q_abs) / h
    shift_all = lam * np.einsum("mkij,mkj->mki", mass[:, 1:], dq_all)  # λM(φ_{k+1})(q_{k+1} − q_k)
    shift_scale = np.abs(shift_all) + lam * np.einsum("mkij,mkj->mki", np.abs(mass[:, 1:]), q_abs)
    return kap_all, mass, inv, (meas_all, meas_scale), (shift_all, shift_scale)
