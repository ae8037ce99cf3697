r"""Two-joint planar manipulator of Rotondo et al., Section 5, as an uncertain LPV system.

Dynamics (121)–(122) with :math:`\phi = x_2 - x_1`, :math:`\kappa = \cos\phi`, :math:`\sigma = \sin\phi`,
state :math:`x = (q_1, q_2, \dot q_1, \dot q_2)`, :math:`\vartheta = x`, :math:`C = I`:

.. math::
    \tilde M(\phi)\ddot q = \tau + \tau_{un} + \tilde b\sigma\begin{pmatrix} \dot q_2^2 \\ -\dot q_1^2\end{pmatrix},
    \qquad \tilde M = \begin{pmatrix} \tilde a & \tilde b\kappa \\ \tilde b\kappa & \tilde c\end{pmatrix},

so :math:`\tilde A_{33..44} = \tilde M^{-1}\tilde N` with :math:`\tilde N = \tilde b\sigma
\begin{pmatrix} 0 & x_4 \\ -x_3 & 0\end{pmatrix}` and :math:`\tilde B = \tilde B_{un} = [0; \tilde M^{-1}]`.
With the paper's :math:`R = \begin{pmatrix} M & 0\\ 0 & I\end{pmatrix}` written in the column order
of its (16) (:math:`M` the nominal mass matrix acting on the velocities),
:math:`RB_{un} = H = [I_2; 0]` (26) and

.. math::
    \Delta B_R = M\tilde M^{-1} - I,\qquad
    \Delta A_R[1{:}2, 3] = \sigma x_3\,(b e_2 - \tilde b\, M\tilde M^{-1} e_2),\qquad
    \Delta A_R[1{:}2, 4] = \sigma x_4\,(\tilde b\, M\tilde M^{-1} e_1 - b e_1).

Every entry is a rational function of :math:`(\tilde a, \tilde b, \tilde c, \kappa)` times a scheduling
factor; :func:`intervalobs.design.lpv.certify_vertex_extremes` proves that its range over the
parameter box is the range over the 8 vertices (see :class:`ManipulatorModel`).

The controller of the paper (Yu et al. 2002) is not given: we use computed torque with the nominal
model and PD gains (:func:`controller`) tracking :func:`reference`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..design.lpv import CertifiedVertexBounds, certify_vertex_extremes
from ..errors import AssumptionError, BoundsError
from ..interval import Interval, product_bounds
from ..simulate import runge_kutta_step
from ..systems.lpv import LPVSystem, SampledLPVModel, StepEnclosure
from ..validation import as_vector

__all__ = [
    "FAULT_BOUND",
    "FAULT_ONSET",
    "LAMBDA",
    "NOMINAL",
    "PAPER_DELTA",
    "THETA_BOX",
    "TRUE_PARAMETERS",
    "X0",
    "ManipulatorModel",
    "controller",
    "reference",
    "simulate_closed_loop",
]

FloatArray = NDArray[np.float64]

NOMINAL = (5.75, 1.5, 1.75)
"""Nominal a, b, c (kg·m²)."""
PAPER_DELTA = (0.2, 0.1, 0.1)
"""Half-widths of the uncertainty intervals of a, b, c (kg·m²)."""
TRUE_PARAMETERS = (5.6, 1.4, 1.7)
"""The paper's true ã, b̃, c̃."""
LAMBDA = 1.0
"""Γ = −λI, F = −λI (Section 5)."""
FAULT_BOUND = 5.0
"""``|u_un| ≤ 5`` (Section 5)."""
FAULT_ONSET = 20.0
"""Faults act for t > 20 s (scenarios 2–4)."""
X0 = (np.pi / 12, -np.pi / 12, 0.0, 0.0)
"""True initial state."""
THETA_BOX = ((-np.pi, -np.pi, -1.0, -1.0), (np.pi, np.pi, 1.0, 1.0))
"""Θ of the boundedness analysis (the paper's 10 000-point grid)."""

ENTRY_NAMES = (
    # rotated: ΔB_R (rows 1-2) and the coefficients of ΔA_R (× σx3 in column 3, × σx4 in column 4)
    "dBR11", "dBR12", "dBR21", "dBR22", "gAR13", "gAR23", "gAR14", "gAR24",
    # unrotated: ΔB (rows 3-4) and the coefficients of ΔA (rows 3-4)
    "dB31", "dB32", "dB41", "dB42", "ga33", "ga43", "ga34", "ga44",
)  # fmt: skip

_KP, _KD = 4.0, 4.0


def _rational_factory(nominal: tuple[float, float, float]) -> Any:
    r"""Entries as ratios of multi-affine functions of (ã, c̃), coefficients in (b̃, κ).

    Monomial order of the affine parameters (ã, c̃): ``1, c̃, ã, ãc̃``. With
    :math:`\tilde D = \tilde a\tilde c - \tilde b^2\kappa^2` and :math:`D_0 = ac - b^2\kappa^2`:
    :math:`M\tilde M^{-1} = \tilde D^{-1}\begin{pmatrix} a\tilde c - b\tilde b\kappa^2 &
    \kappa(b\tilde a - a\tilde b) \\ \kappa(b\tilde c - c\tilde b) & c\tilde a - b\tilde b\kappa^2
    \end{pmatrix}`, :math:`\tilde M^{-1} = \tilde D^{-1}\operatorname{adj}\tilde M`.
    """
    a, b, c = nominal

    def rational(bt: Any, k: Any) -> list[tuple[Any, ...]]:
        k2 = k**2
        d0 = a * c - b * b * k2
        den = [-(bt**2) * k2, 0.0, 0.0, 1.0]  # D̃ = ã c̃ − b̃² κ²

        def lin(*coef: Any) -> list[Any]:
            return list(coef)

        def comb(x: list[Any], sx: Any, y: list[Any], sy: Any) -> list[Any]:
            return [sx * xi + sy * yi for xi, yi in zip(x, y)]

        m11 = lin(-b * bt * k2, a, 0.0, 0.0)
        n12 = lin(-a * bt, 0.0, b, 0.0)  # m12 = κ n12 / D̃
        n21 = lin(-c * bt, b, 0.0, 0.0)  # m21 = κ n21 / D̃
        m22 = lin(-b * bt * k2, 0.0, c, 0.0)
        one = lin(1.0, 0.0, 0.0, 0.0)
        c_t = lin(0.0, 1.0, 0.0, 0.0)
        a_t = lin(0.0, 0.0, 1.0, 0.0)
        den0 = [d0 * x for x in den]
        return [
            (comb(m11, 1.0, den, -1.0), den),  # ΔB_R 11
            (n12, den, k),  # ΔB_R 12
            (n21, den, k),  # ΔB_R 21
            (comb(m22, 1.0, den, -1.0), den),  # ΔB_R 22
            ([-(bt * x) for x in n12], den, k),  # ΔA_R 13 / (σ x3)
            (comb(den, b, m22, -bt), den),  # ΔA_R 23 / (σ x3)
            (comb(m11, bt, den, -b), den),  # ΔA_R 14 / (σ x4)
            ([bt * x for x in n21], den, k),  # ΔA_R 24 / (σ x4)
            (comb(c_t, d0, den, -c), den0),  # ΔB 31 = c̃/D̃ − c/D0
            (comb(den, b, one, -bt * d0), den0, k),  # ΔB 32 = κ(b/D0 − b̃/D̃)
            (comb(den, b, one, -bt * d0), den0, k),  # ΔB 41
            (comb(a_t, d0, den, -a), den0),  # ΔB 42 = ã/D̃ − a/D0
            (comb(one, (bt**2) * d0, den, -b * b), den0, k),  # ΔA 33 / (σ x3) = κ(b̃²/D̃ − b²/D0)
            (comb(den, a * b, a_t, -bt * d0), den0),  # ΔA 43 / (σ x3)
            (comb(c_t, bt * d0, den, -b * c), den0),  # ΔA 34 / (σ x4)
            (comb(den, b * b, one, -(bt**2) * d0), den0, k),  # ΔA 44 / (σ x4) = κ(b²/D0 − b̃²/D̃)
        ]

    return rational


def _fast_factory(nominal: tuple[float, float, float]) -> Any:
    """Closed form of the 8 rotated entries (ΔB_R, ΔA_R coefficients), checked against the rational form."""
    a, b, c = nominal

    def fast(at: FloatArray, bt: FloatArray, ct: FloatArray, k: FloatArray) -> FloatArray:
        k2 = k * k
        inv = 1.0 / (at * ct - bt * bt * k2)
        m11 = (a * ct - b * bt * k2) * inv
        m12 = k * (b * at - a * bt) * inv
        m21 = k * (b * ct - c * bt) * inv
        m22 = (c * at - b * bt * k2) * inv
        out = np.empty((8, *np.broadcast_shapes(np.shape(at), np.shape(k))))
        out[0], out[1], out[2], out[3] = m11 - 1.0, m12, m21, m22 - 1.0
        out[4], out[5], out[6], out[7] = -bt * m12, b - bt * m22, bt * m11 - b, bt * m21
        return out

    return fast


def reference(t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""Joint reference :math:`q_r(t)` and its first two derivatives (our choice; the paper's is not given).

    :math:`q_{r} = (\pi/12 + 0.5\sin 0.5t,\; -\pi/12 + 0.5\sin 0.7t)`, so :math:`q_r(0) = (x_0)_{1:2}` and
    :math:`|\dot q_r| \le 0.35` rad/s (inside Θ).

    Parameters
    ----------
    t : array_like
        Times (s).

    Returns
    -------
    q, qd, qdd : numpy.ndarray, shape (..., 2)
    """
    tt = np.asarray(t, dtype=float)
    q = np.stack([np.pi / 12 + 0.5 * np.sin(0.5 * tt), -np.pi / 12 + 0.5 * np.sin(0.7 * tt)], axis=-1)
    qd = np.stack([0.25 * np.cos(0.5 * tt), 0.35 * np.cos(0.7 * tt)], axis=-1)
    qdd = np.stack([-0.125 * np.sin(0.5 * tt), -0.245 * np.sin(0.7 * tt)], axis=-1)
    return q, qd, qdd


def controller(x: ArrayLike, t: float, nominal: tuple[float, float, float] = NOMINAL) -> FloatArray:
    r"""Computed-torque tracking controller with the nominal model (our choice, documented).

    .. math:: \tau^* = M(\phi)\big(\ddot q_r + K_d(\dot q_r - \dot q) + K_p(q_r - q)\big)
              - b\sigma\,(\dot q_2^2, -\dot q_1^2),\quad K_p = K_d = 4.

    Parameters
    ----------
    x : array_like, shape (..., 4)
        Measured state (C = I).
    t : float
        Time (s).
    nominal : tuple of float
        a, b, c used by the controller.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        Known input u = τ* (N·m).
    """
    a, b, c = nominal
    xs = np.asarray(x, dtype=float)
    q, qd, qdd = reference(t)
    phi = xs[..., 1] - xs[..., 0]
    kap, sig = np.cos(phi), np.sin(phi)
    acc = qdd + _KD * (qd - xs[..., 2:]) + _KP * (q - xs[..., :2])
    t1 = a * acc[..., 0] + b * kap * acc[..., 1] - b * sig * xs[..., 3] ** 2
    t2 = b * kap * acc[..., 0] + c * acc[..., 1] + b * sig * xs[..., 2] ** 2
    return np.stack([t1, t2], axis=-1)


def _true_rate(x: FloatArray, tau: FloatArray, at: FloatArray, bt: FloatArray, ct: FloatArray) -> FloatArray:
    phi = x[..., 1] - x[..., 0]
    kap, sig = np.cos(phi), np.sin(phi)
    bk = bt * kap
    inv = 1.0 / (at * ct - bk * bk)
    bs = bt * sig
    r1 = tau[..., 0] + bs * x[..., 3] ** 2
    r2 = tau[..., 1] - bs * x[..., 2] ** 2
    out = np.empty_like(x)
    out[..., :2] = x[..., 2:]
    out[..., 2] = (ct * r1 - bk * r2) * inv
    out[..., 3] = (at * r2 - bk * r1) * inv
    return out


def rk4_step(x: FloatArray, tau: FloatArray, params: FloatArray, h: float) -> FloatArray:
    """One classical RK4 step (:func:`~intervalobs.simulate.runge_kutta_step`) of the true manipulator, torque held.

    Parameters
    ----------
    x : numpy.ndarray, shape (M, 4)
        States of M runs.
    tau : numpy.ndarray, shape (M, 2)
        Total torque (known input plus fault), constant over the step.
    params : numpy.ndarray, shape (M, 3)
        True ã, b̃, c̃ of each run.
    h : float
        Step (s).

    Returns
    -------
    numpy.ndarray, shape (M, 4)
    """
    at, bt, ct = params[:, 0], params[:, 1], params[:, 2]
    return runge_kutta_step(lambda _, xx: _true_rate(xx, tau, at, bt, ct), 0.0, x, h)


def simulate_closed_loop(
    t: ArrayLike,
    params: ArrayLike,
    fault: ArrayLike,
    x0: ArrayLike = X0,
    onset: float = FAULT_ONSET,
    substeps: int = 1,
    nominal: tuple[float, float, float] = NOMINAL,
) -> tuple[FloatArray, FloatArray]:
    r"""Closed-loop truth: RK4 with ``substeps`` steps per sample, controller held over each sample.

    Parameters
    ----------
    t : array_like, shape (T,)
        Uniform sample times (s).
    params : array_like, shape (M, 3)
        True ã, b̃, c̃ per run.
    fault : array_like, shape (M, 2)
        Fault torque u_un acting for t > ``onset`` (constant, N·m).
    x0 : array_like, shape (4,) or (M, 4)
        Initial state.
    onset : float
        Fault onset (s).
    substeps : int
        RK4 steps per sample interval.
    nominal : tuple of float
        Nominal a, b, c of the controller.

    Returns
    -------
    x : numpy.ndarray, shape (M, T, 4)
    u : numpy.ndarray, shape (M, T, 2)
        Known input (held over [t_k, t_{k+1})).
    """
    tt = np.asarray(t, dtype=float)
    par = np.atleast_2d(np.asarray(params, dtype=float))
    runs = par.shape[0]
    f = np.broadcast_to(np.asarray(fault, dtype=float), (runs, 2))
    x = np.broadcast_to(np.asarray(x0, dtype=float), (runs, 4)).copy()
    xs = np.empty((runs, tt.size, 4))
    us = np.empty((runs, tt.size, 2))
    h = float(tt[1] - tt[0]) / substeps if tt.size > 1 else 0.0
    for k in range(tt.size):
        xs[:, k] = x
        u = controller(x, float(tt[k]), nominal)
        us[:, k] = u
        if k + 1 < tt.size:
            tau = u + (f if tt[k] >= onset else 0.0)
            for _ in range(substeps):
                x = rk4_step(x, tau, par, h)
    return xs, us


class ManipulatorModel(SampledLPVModel):
    r"""The manipulator as an :class:`~intervalobs.systems.lpv.LPVSystem` plus its sampled-data enclosures.

    Implements :class:`~intervalobs.systems.lpv.SampledLPVModel` for the paper's
    :math:`R(\vartheta)` (Section 5). The elementwise bounds of :math:`\Delta A, \Delta B` and of the
    rotated :math:`\Delta A_R, \Delta B_R = \Delta B_{un,R}` are *exact* ranges over the parameter
    box, certified by :func:`~intervalobs.design.lpv.certify_vertex_extremes` (extremes at the
    8 vertices, slack reported in :attr:`bounds`).

    Parameters
    ----------
    nominal : tuple of float
        a, b, c.
    delta : tuple of float
        Half-widths of the intervals of a, b, c (the paper: 0.2, 0.1, 0.1).
    fault_bound : float
        Bound of ``|u_un|`` (each component).
    cells, splits, pieces : int
        Resolution of the certificate (see :func:`certify_vertex_extremes`).

    Raises
    ------
    AssumptionError
        If :math:`\tilde a\tilde c - \tilde b^2\cos^2\phi` can vanish on the parameter box.
    """

    n = 4
    box_free = True  # the state is measured: the enclosures depend on y and u only

    def __init__(
        self,
        nominal: tuple[float, float, float] = NOMINAL,
        delta: tuple[float, float, float] = PAPER_DELTA,
        fault_bound: float = FAULT_BOUND,
        cells: int = 64,
        splits: int = 8,
        pieces: int = 4,
    ) -> None:
        nom = as_vector("nominal", nominal, 3)
        dl = as_vector("delta", delta, 3)
        if np.any(nom <= 0) or np.any(dl < 0):
            raise BoundsError(f"nominal, delta: expected positive nominal and nonnegative delta, got {nom}, {dl}")
        self.nominal = (float(nom[0]), float(nom[1]), float(nom[2]))
        self.p_lower = nom - dl
        self.p_upper = nom + dl
        d_min = self.p_lower[0] * self.p_lower[2] - self.p_upper[1] ** 2
        if self.p_lower.min() <= 0 or d_min <= 0:
            raise AssumptionError(
                f"delta: expected ã c̃ − b̃² cos²φ > 0 on the parameter box (Section 5), got min {d_min:.4g}"
            )
        self.d_min = float(d_min)
        self.fault_bound = float(fault_bound)
        self.bounds: CertifiedVertexBounds = certify_vertex_extremes(
            _rational_factory(self.nominal),
            ENTRY_NAMES,
            self.p_lower,
            self.p_upper,
            (-1.0, 1.0),
            affine=(0, 2),
            cells=cells,
            splits=splits,
            pieces=pieces,
        )
        self._fast = _fast_factory(self.nominal)
        self.bounds.check_fast(self._fast, range(8))

        def stacked(f: Any) -> Any:
            return lambda th: f(np.stack(np.broadcast_arrays(*th), axis=-1))

        self.system = LPVSystem(
            A=stacked(self.a_matrix),
            B=stacked(self.b_matrix),
            C=np.eye(4),
            theta_box=THETA_BOX,
            B_un=stacked(self.b_matrix),
            dA=stacked(self.da_bounds),
            dB=stacked(self.db_bounds),
            dB_un=stacked(self.db_bounds),
        )

    # --- nominal matrices -----------------------------------------------------------------------
    def a_matrix(self, theta: ArrayLike) -> FloatArray:
        """Nominal :math:`A(\\vartheta)`.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        numpy.ndarray, shape (..., 4, 4)
        """
        a, b, c = self.nominal
        th = np.asarray(theta, dtype=float)
        phi = th[..., 1] - th[..., 0]
        kap, sig = np.cos(phi), np.sin(phi)
        den = a * c - b * b * kap * kap
        out = np.zeros((*th.shape[:-1], 4, 4))
        out[..., 0, 2] = out[..., 1, 3] = 1.0
        out[..., 2, 2] = b * b * sig * kap * th[..., 2] / den
        out[..., 2, 3] = b * c * sig * th[..., 3] / den
        out[..., 3, 2] = -a * b * sig * th[..., 2] / den
        out[..., 3, 3] = -b * b * sig * kap * th[..., 3] / den
        return out

    def b_matrix(self, theta: ArrayLike) -> FloatArray:
        """Nominal :math:`B(\\vartheta) = B_{un}(\\vartheta)`.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        numpy.ndarray, shape (..., 4, 2)
        """
        a, b, c = self.nominal
        th = np.asarray(theta, dtype=float)
        kap = np.cos(th[..., 1] - th[..., 0])
        den = a * c - b * b * kap * kap
        out = np.zeros((*th.shape[:-1], 4, 2))
        out[..., 2, 0] = c / den
        out[..., 2, 1] = out[..., 3, 0] = -b * kap / den
        out[..., 3, 1] = a / den
        return out

    def r_matrix(self, y: ArrayLike) -> FloatArray:
        """The paper's :math:`R(\\vartheta)` (Section 5) at measured states.

        Parameters
        ----------
        y : array_like, shape (..., 4)
            Measured state (C = I).

        Returns
        -------
        numpy.ndarray, shape (..., 4, 4)
        """
        a, b, c = self.nominal
        th = np.asarray(y, dtype=float)
        bk = b * np.cos(th[..., 1] - th[..., 0])
        out = np.zeros((*th.shape[:-1], 4, 4))
        out[..., 0, 2] = a
        out[..., 0, 3] = out[..., 1, 2] = bk
        out[..., 1, 3] = c
        out[..., 2, 0] = out[..., 3, 1] = 1.0
        return out

    # --- certified bounds at points -----------------------------------------------------------
    def _entry_bounds(self, theta: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        th = np.asarray(theta, dtype=float)
        phi = th[..., 1] - th[..., 0]
        lo, hi = self.bounds.evaluate(np.clip(np.cos(phi), -1.0, 1.0))
        s = np.sin(phi)
        return lo, hi, s * th[..., 2], s * th[..., 3]

    @staticmethod
    def _velocity_columns(
        lo: FloatArray, hi: FloatArray, f3: FloatArray, f4: FloatArray, first: int, row: int
    ) -> tuple[FloatArray, FloatArray]:
        """A 4×4 bound with entries ``first … first + 3`` times ``f3, f3, f4, f4`` at rows ``row, row + 1`` of
        columns 3, 3, 4, 4 (the σ x3 and σ x4 columns of ΔA and ΔA_R)."""
        al, ah = np.zeros((*f3.shape, 4, 4)), np.zeros((*f3.shape, 4, 4))
        for k, f in enumerate((f3, f3, f4, f4)):
            i, j, e = row + k % 2, 2 + k // 2, first + k
            al[..., i, j], ah[..., i, j] = np.minimum(f * lo[e], f * hi[e]), np.maximum(f * lo[e], f * hi[e])
        return al, ah

    @staticmethod
    def _input_block(lo: FloatArray, hi: FloatArray, first: int, row: int) -> tuple[FloatArray, FloatArray]:
        """A 4×2 bound with entries ``first … first + 3`` row by row at rows ``row, row + 1`` (ΔB, ΔB_R)."""
        bl, bh = np.zeros((*lo.shape[1:], 4, 2)), np.zeros((*lo.shape[1:], 4, 2))
        bl[..., row : row + 2, :] = np.moveaxis(lo[first : first + 4].reshape(2, 2, *lo.shape[1:]), (0, 1), (-2, -1))
        bh[..., row : row + 2, :] = np.moveaxis(hi[first : first + 4].reshape(2, 2, *hi.shape[1:]), (0, 1), (-2, -1))
        return bl, bh

    def rotated_bounds_at(self, theta: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Exact bounds of :math:`\\Delta A_R` and :math:`\\Delta B_R` (uncertainty in observer coordinates) at points.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        da_lower, da_upper : numpy.ndarray, shape (..., 4, 4)
        db_lower, db_upper : numpy.ndarray, shape (..., 4, 2)

        References
        ----------
        Rotondo et al., (14)–(15).
        """
        lo, hi, f3, f4 = self._entry_bounds(theta)
        return (*self._velocity_columns(lo, hi, f3, f4, 4, 0), *self._input_block(lo, hi, 0, 0))

    def da_bounds(self, theta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Exact elementwise bounds of :math:`\\Delta A(\\vartheta)` over the parameter box.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., 4, 4)

        References
        ----------
        Rotondo et al. (:mod:`intervalobs.references`), (11).
        """
        lo, hi, f3, f4 = self._entry_bounds(theta)
        return self._velocity_columns(lo, hi, f3, f4, 12, 2)

    def db_bounds(self, theta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Exact elementwise bounds of :math:`\\Delta B(\\vartheta) = \\Delta B_{un}(\\vartheta)` on the box.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., 4, 2)

        References
        ----------
        Rotondo et al., (12) and (23).
        """
        lo, hi, _, _ = self._entry_bounds(theta)
        return self._input_block(lo, hi, 8, 2)

    def naive_rotated_bounds_at(self, theta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        r"""Bounds of :math:`\Delta A_R` from :math:`R \cdot [\underline{\Delta A}, \overline{\Delta A}]` by
        interval arithmetic (the paper's element-by-element recipe): sound but wider.

        Parameters
        ----------
        theta : array_like, shape (..., 4)
            Scheduling vector :math:`\\vartheta = x`.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., 4, 4)
        """
        al, ah = self.da_bounds(theta)
        r = self.r_matrix(theta)
        rp, rn = np.maximum(r, 0), np.maximum(-r, 0)
        return rp @ al - rn @ ah, rp @ ah - rn @ al

    # --- sampled-data enclosures (SampledLPVModel) --------------------------------------------
    def _accel_bound(self, w_abs: FloatArray, u: FloatArray) -> FloatArray:
        at, bt, ct = self.p_upper
        cor = bt * w_abs[..., ::-1] ** 2
        drive = np.abs(u) + self.fault_bound + cor
        out = np.empty_like(drive)
        out[..., 0] = (ct * drive[..., 0] + bt * drive[..., 1]) / self.d_min
        out[..., 1] = (bt * drive[..., 0] + at * drive[..., 1]) / self.d_min
        return out

    def flow_box(
        self, x_lower: FloatArray, x_upper: FloatArray, y: FloatArray, u: FloatArray, h: float
    ) -> tuple[FloatArray, FloatArray]:
        r"""A box containing :math:`x(t)`, :math:`t \in [t_k, t_k + h]`, from the measured :math:`x_k = y_k`.

        With :math:`W_0 = |\dot q_k| + 1` and :math:`\alpha(W)` the bound of :math:`|\ddot q|` for
        :math:`|\dot q| \le W` (any parameter in the box, any fault with :math:`|u_{un}| \le` the
        bound, torque held), :math:`h\alpha(W_0) \le 1` keeps :math:`|\dot q| \le W_0` on the step
        (first-exit argument), hence :math:`|\dot q - \dot q_k| \le h\alpha(W_1)` with
        :math:`W_1 = |\dot q_k| + h\alpha(W_0)`, and :math:`q - q_k \in [0, h]\cdot[\dot q_k \mp h\alpha]`.

        Parameters
        ----------
        x_lower, x_upper : numpy.ndarray, shape (M, 4)
            Observer box at :math:`t_k` (unused: the state is measured).
        y : numpy.ndarray, shape (M, 4)
            Measured state at :math:`t_k`.
        u : numpy.ndarray, shape (M, 2)
            Known torque held over the step.
        h : float
            Step (s).

        Returns
        -------
        lower, upper : numpy.ndarray, shape (M, 4)
        """
        return self.flow_box_from_angles(y[..., :2], y[..., 2:], y[..., 2:], u, h)

    def flow_box_from_angles(
        self, q: FloatArray, w_lower: FloatArray, w_upper: FloatArray, u: FloatArray, h: float
    ) -> tuple[FloatArray, FloatArray]:
        r""":meth:`flow_box` from the angles at :math:`t_k` and a box of the velocities.

        Parameters
        ----------
        q : numpy.ndarray, shape (M, 2)
            Joint angles at :math:`t_k` (rad).
        w_lower, w_upper : numpy.ndarray, shape (M, 2)
            Box of the joint velocities at :math:`t_k` (rad/s).
        u, h : numpy.ndarray and float
            Torque held over the step and step length, as for :meth:`flow_box`.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (M, 4)
            The flow box, as :meth:`flow_box` returns it.

        Raises
        ------
        AssumptionError
            If :math:`h\max|\ddot q| > 1` (the first-exit argument of :meth:`flow_box` needs it).
        """
        w_abs = np.maximum(np.abs(w_lower), np.abs(w_upper))
        a0 = self._accel_bound(w_abs + 1.0, u)
        if np.any(h * a0 > 1.0):
            raise AssumptionError(f"h: expected h·max|q̈| ≤ 1 for the flow enclosure, got {float(np.max(h * a0)):.3g}")
        a1 = self._accel_bound(w_abs + h * a0, u)
        dw = h * a1
        lo = np.empty((*q.shape[:-1], 4))
        hi = np.empty((*q.shape[:-1], 4))
        lo[..., 2:], hi[..., 2:] = w_lower - dw, w_upper + dw
        lo[..., :2] = q + np.minimum(0.0, h * (w_lower - dw))
        hi[..., :2] = q + np.maximum(0.0, h * (w_upper + dw))
        return lo, hi

    @staticmethod
    def _phase(lo: FloatArray, hi: FloatArray) -> Interval:
        """Range of :math:`q_2 - q_1` over a box of states."""
        return Interval._raw(lo[..., 1] - hi[..., 0], hi[..., 1] - lo[..., 0])

    def rx_bounds(self, x_lower: FloatArray, x_upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Bounds of :math:`R(\\vartheta)x = (M(\\phi)\\dot q, q)` over a box of states.

        Parameters
        ----------
        x_lower, x_upper : numpy.ndarray, shape (M, 4)
            Box of states.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (M, 4)
        """
        return self._rx(np.cos(self._phase(x_lower, x_upper)), x_lower, x_upper)

    def _rx(self, kappa: Interval, x_lower: FloatArray, x_upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        a, b, c = self.nominal
        w1l, w1h, w2l, w2h = x_lower[..., 2], x_upper[..., 2], x_lower[..., 3], x_upper[..., 3]
        p12 = product_bounds(b * kappa.lower, b * kappa.upper, w2l, w2h)
        p21 = product_bounds(b * kappa.lower, b * kappa.upper, w1l, w1h)
        lo = np.stack([a * w1l + p12[0], p21[0] + c * w2l, x_lower[..., 0], x_lower[..., 1]], axis=-1)
        hi = np.stack([a * w1h + p12[1], p21[1] + c * w2h, x_upper[..., 0], x_upper[..., 1]], axis=-1)
        return lo, hi

    def step_enclosure(
        self, x_lower: FloatArray, x_upper: FloatArray, y: FloatArray, u: FloatArray, h: float
    ) -> StepEnclosure:
        r"""Enclosures over one step (:class:`~intervalobs.systems.lpv.StepEnclosure`).

        Known rate: :math:`(\dot R + RA)x + RBu = (b\sigma\dot q_1\dot q_2 + u_1,\,
        -b\sigma\dot q_1\dot q_2 + u_2,\, \dot q_1,\, \dot q_2)` (from :math:`\dot M\dot q + N\dot q`).
        Uncertainty: :math:`\Delta A_R` column 3 is :math:`\sigma x_3` times the certified range of its
        coefficient over the parameter box and the κ-interval of the step, column 4 likewise with
        :math:`\sigma x_4`; :math:`\Delta B_R = \Delta B_{un,R}` are the certified ranges.

        Parameters
        ----------
        x_lower, x_upper : numpy.ndarray, shape (M, 4)
            Observer box at :math:`t_k` (unused: the state is measured).
        y : numpy.ndarray, shape (M, 4)
            Measured state at :math:`t_k`.
        u : numpy.ndarray, shape (M, 2)
            Known torque held over the step.
        h : float
            Step (s).

        Returns
        -------
        StepEnclosure
        """
        return self.box_enclosure(*self.flow_box(x_lower, x_upper, y, u, h), u)

    def box_enclosure(self, flo: FloatArray, fhi: FloatArray, u: FloatArray) -> StepEnclosure:
        """:meth:`step_enclosure` from a box ``[flo, fhi]`` that contains :math:`x(t)` on the step.

        Parameters
        ----------
        flo, fhi : numpy.ndarray, shape (M, 4)
            Flow box of the step (:meth:`flow_box`).
        u : numpy.ndarray, shape (M, 2)
            Known torque held over the step.

        Returns
        -------
        StepEnclosure
        """
        phase = self._phase(flo, fhi)
        return self.box_enclosure_at_phase(flo, fhi, u, np.cos(phase), np.sin(phase))

    def box_enclosure_at_phase(
        self, flo: FloatArray, fhi: FloatArray, u: FloatArray, kappa: Interval, sigma: Interval
    ) -> StepEnclosure:
        r""":meth:`box_enclosure` given the ranges of cos φ and sin φ over the box.

        Parameters
        ----------
        flo, fhi : numpy.ndarray, shape (M, 4)
            Flow box of the step.
        u : numpy.ndarray, shape (M, 2)
            Known torque held over the step.
        kappa, sigma : Interval, shape (M,)
            Ranges of :math:`\cos\phi` and :math:`\sin\phi` over the box.

        Returns
        -------
        StepEnclosure
        """
        b = self.nominal[1]
        w1l, w1h, w2l, w2h = flo[..., 2], fhi[..., 2], flo[..., 3], fhi[..., 3]
        rx_lo, rx_hi = self._rx(kappa, flo, fhi)
        # known rate
        ww = product_bounds(w1l, w1h, w2l, w2h)
        sw = product_bounds(b * sigma.lower, b * sigma.upper, ww[0], ww[1])
        rate_lo, rate_hi = np.empty_like(flo), np.empty_like(fhi)
        rate_lo[..., 0], rate_hi[..., 0] = sw[0] + u[..., 0], sw[1] + u[..., 0]
        rate_lo[..., 1], rate_hi[..., 1] = u[..., 1] - sw[1], u[..., 1] - sw[0]
        rate_lo[..., 2:], rate_hi[..., 2:] = flo[..., 2:], fhi[..., 2:]
        # rotated uncertainty
        g_lo, g_hi = self.bounds.evaluate(kappa.lower, kappa.upper, select=range(8), fast=self._fast)
        f3 = product_bounds(sigma.lower, sigma.upper, w1l, w1h)
        f4 = product_bounds(sigma.lower, sigma.upper, w2l, w2h)
        shape = kappa.shape
        al, ah = np.zeros((*shape, 4, 4)), np.zeros((*shape, 4, 4))
        for (i, j), e, f in (((0, 2), 4, f3), ((1, 2), 5, f3), ((0, 3), 6, f4), ((1, 3), 7, f4)):
            al[..., i, j], ah[..., i, j] = product_bounds(f[0], f[1], g_lo[e], g_hi[e])
        bl, bh = self._input_block(g_lo, g_hi, 0, 0)
        return StepEnclosure(flo, fhi, rate_lo, rate_hi, rx_lo, rx_hi, al, ah, bl, bh, bl, bh)

    def sample_parameters(self, runs: int, rng: np.random.Generator) -> FloatArray:
        """Uniform draws of (ã, b̃, c̃) in the parameter box.

        Parameters
        ----------
        runs : int
            Number of draws.
        rng : numpy.random.Generator
            Random source.

        Returns
        -------
        numpy.ndarray, shape (runs, 3)
        """
        return np.asarray(rng.uniform(self.p_lower, self.p_upper, size=(runs, 3)))
