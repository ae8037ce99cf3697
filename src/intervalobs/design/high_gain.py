r"""The high-gain parameter :math:`\theta` of the sampled-output high-gain paper, Theorem 4.4, computed as printed and
as it must be read.

Theorem 4.4 solves LMI (32) :math:`M_1^TQ + 2D + QM_1 \prec 0` (:math:`Q \succ 0`, :math:`D \prec 0`),
sets :math:`M_2 = DQ^{-1}`, picks :math:`\alpha` from conditions (34)

.. math:: |\operatorname{diag}(e^{-(\Theta + i\omega_1)t})v_1d^r| \le \alpha_d\mathbf 1,\qquad
          |\operatorname{diag}(e^{-(\Theta + i\omega_1)t})v_1L_1\delta| \le \alpha_n\mathbf 1_\ell

through (43), and takes :math:`\theta = \alpha - \lambda_{\min}(M_2)` (33).

What the printed steps really give (all computed by :func:`theta_design`):

* **the paper's reading** of (43), :math:`\alpha_j = |\log(v_1d^r)_j - \log\alpha_d + \lambda_{\min} - i\omega_j|`,
  takes the *modulus* of a complex number whose real part is negative for the noise terms; with the
  printed :math:`v_1, L_1` and :math:`\lambda_{\min}(M_2) = -1` it gives :math:`\alpha = 8.7585`
  (printed 8.7586, :math:`\theta = 9.7586`);
* **a sound reading**: (34) cannot hold at :math:`t = 0` for any :math:`\theta` (the factor is 1 there),
  and for :math:`t > 0` it holds from :math:`t^\star = \max_j \log(|(v_1d^r)_j|/\alpha_d)/\theta` on. Read
  at :math:`t = 1`, the real-valued solution of (42) is
  :math:`\theta = \max_j \log(|\cdot|_j/\alpha_\cdot)` (the modulus of the phase
  :math:`e^{-i\omega t}` is 1, it does not enter);
* whatever :math:`\theta`, the Metzler matrix (35) with the reported :math:`\alpha, \theta` is not
  Hurwitz (``mat_abscissa``), and LMI (32) does not certify anything (a very negative :math:`D` makes
  it feasible for every :math:`M_1`);
* the bounds do not depend on :math:`\theta` at all in exact arithmetic: the change of coordinates
  :math:`T_1(t) = e^{-\theta t}\operatorname{diag}(e^{-i\omega_1t})v_1` only multiplies the centre and
  the radius by the positive scalar :math:`e^{-\theta t}`, which passes through :math:`|\cdot|` and is
  undone by :math:`T_1^{-1}`. The observer (:mod:`intervalobs.observers.hgio`) therefore works in
  :math:`\zeta = e^{\theta t}z` (no overflow), and :math:`\theta` is reported, not used.
"""

from __future__ import annotations

from dataclasses import dataclass

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import DesignError, DimensionError
from ..validation import as_matrix, as_vector
from .lmi import solve_lmi, verify_definite
from .regions import ModalDecomposition, radius_matrix

__all__ = ["ThetaDesign", "euler_radius_factor", "mat_matrix", "theta_design"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ThetaDesign:
    """The high gain θ and its margin α, in the paper's reading and in a sound one (module docstring).

    Attributes
    ----------
    lambda_min_M2 : float
        :math:`\\lambda_{\\min}(DQ^{-1})` from the paper's LMI.
    alpha_paper, theta_paper : float
        α with the modulus of the complex logarithm (the paper's reading), and θ from it.
    alpha_sound, theta_sound : float
        The real-valued α at ``t = 1`` (sound reading), and θ from it.
    t_star_paper, t_star_sound : float
        Time from which the margin conditions on the disturbance and the noise hold with ``theta_paper`` /
        ``theta_sound``.
    condition34_at_0 : numpy.ndarray
        ``|v1 d^r|`` (must be <= alpha_d at t = 0 for the margin condition); the values do not depend on theta.
    mat_abscissa_paper, mat_abscissa_sound : float
        Largest real eigenvalue of the radius matrix (:func:`mat_matrix`) with each (alpha, theta); >= 0 means not
        Hurwitz.
    radius_abscissa : float
        Largest real eigenvalue of M1 (the matrix that really decides the radius stability when
        phi is bounded by its range, alpha = 0, in coordinates where theta cancels).

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): Theorem 4.4: LMI (32), α from (43) (paper)
    or (42) (sound), θ from (33), conditions (34), matrix (35).
    """

    lambda_min_M2: float
    alpha_paper: float
    theta_paper: float
    alpha_sound: float
    theta_sound: float
    t_star_paper: float
    t_star_sound: float
    condition34_at_0: FloatArray
    mat_abscissa_paper: float
    mat_abscissa_sound: float
    radius_abscissa: float


def mat_matrix(modal: ModalDecomposition, L: ArrayLike, C: ArrayLike, alpha: float, theta: float) -> FloatArray:
    r"""The radius matrix of the θ-shifted observer.

    .. math:: M_1 + [\operatorname{diag}(-\Theta) + \alpha I,\, \alpha I;\; \alpha I,\,
              \operatorname{diag}(-\Theta) + \alpha I]

    Parameters
    ----------
    modal : ModalDecomposition
        Decomposition of ``A - L C``.
    L : array_like, shape (n, p)
        Gain.
    C : array_like, shape (p, n)
        Output matrix.
    alpha, theta : float
        The margin α and the high gain θ.

    Returns
    -------
    numpy.ndarray, shape (2n, 2n)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): matrices (35)/(36), the scalars of Theorem
    4.4.
    """
    n = modal.eigenvalues.size
    eye = np.eye(n)
    m2 = np.block([[(alpha - theta) * eye, alpha * eye], [alpha * eye, (alpha - theta) * eye]])
    return radius_matrix(modal, L, C) + m2


def _lambda_min_m2(m1: FloatArray) -> float:
    """Solve LMI (32) with the normalisation ``Q >= I``, ``D <= -I`` (least trace of Q)."""
    size = m1.shape[0]
    q = cp.Variable((size, size), symmetric=True)
    d = cp.Variable((size, size), symmetric=True)
    lmi = m1.T @ q + q @ m1 + 2 * d
    constraints = [q >> np.eye(size), d << -np.eye(size), 0.5 * (lmi + lmi.T) << -1e-7 * np.eye(size)]
    problem = cp.Problem(cp.Minimize(cp.trace(q) - cp.trace(d)), constraints)
    relax = "M1 is badly scaled for the solvers: pass lambda_min explicitly"
    solve_lmi(problem, "high-gain parameter", relax)
    qv, dv = np.asarray(q.value), np.asarray(d.value)
    verify_definite("(32): M1ᵀQ + QM1 + 2D", m1.T @ qv + qv @ m1 + 2 * dv, -1, relax)
    m2 = dv @ np.linalg.inv(qv)
    return float(np.min(np.linalg.eigvals(m2).real))


def theta_design(
    modal: ModalDecomposition,
    L: ArrayLike,
    C: ArrayLike,
    d_radius: ArrayLike,
    v_radius: ArrayLike,
    alpha_d: float,
    alpha_n: float,
    lambda_min: float | None = None,
    paper_v1: ArrayLike | None = None,
) -> ThetaDesign:
    r"""The high gain θ with its margin α, as printed and as sound (with :math:`\lambda_{\min}(M_2)`).

    Parameters
    ----------
    modal : ModalDecomposition
        Decomposition of ``A - L C``.
    L : array_like, shape (n, p)
        Gain :math:`L_1`.
    C : array_like, shape (p, n)
        Output matrix.
    d_radius : array_like, shape (n,)
        :math:`d^r`, radius of the additive disturbance.
    v_radius : array_like, shape (p,)
        :math:`\delta`, bound of the measurement noise.
    alpha_d, alpha_n : float
        The margins θ must leave for the disturbance and the noise (printed: 0.08 and 0.03).
    lambda_min : float, optional
        Use this :math:`\lambda_{\min}(M_2)` instead of solving the paper's LMI (its value depends only on
        the LMI's normalisation; the paper's numbers imply -1).
    paper_v1 : array_like, shape (n, n), optional
        The :math:`v_1` to use in the paper's reading of α only, e.g. the paper's printed one. That
        reading takes the complex logarithm of :math:`(v_1d^r)_j`, which depends on the arbitrary phase of
        row :math:`j` of :math:`v_1`; the sound reading uses moduli only and always takes ``modal.v1``.
        Default: ``modal.v1`` (canonical phase, :func:`~intervalobs.design.regions.canonical_eigenvectors`).

    Returns
    -------
    ThetaDesign

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): Theorem 4.4: LMI (32), conditions (34) with
    the scalars α_d, α_n, the complex logarithm of (43); the decomposition (13).
    """
    n = modal.eigenvalues.size
    gain = as_matrix("L", L, (n, None))
    c = as_matrix("C", C, (gain.shape[1], n))
    dr = as_vector("d_radius", d_radius, n)
    vr = as_vector("v_radius", v_radius, c.shape[0])
    if not (alpha_d > 0 and alpha_n > 0):
        raise DesignError(f"alpha_d, alpha_n: expected positive scalars, got {alpha_d}, {alpha_n}")
    m1 = radius_matrix(modal, gain, c)
    lam = _lambda_min_m2(m1) if lambda_min is None else float(lambda_min)
    omega = modal.omega1
    vd = modal.v1 @ dr
    vl = modal.v1 @ gain * vr[None, :]
    v1_read = modal.v1 if paper_v1 is None else np.asarray(paper_v1, dtype=complex)
    if v1_read.shape != (n, n) or not np.all(np.isfinite(v1_read)):
        raise DimensionError(f"paper_v1: expected a finite {n}×{n} matrix, got shape {v1_read.shape}")
    vd_read = v1_read @ dr
    vl_read = v1_read @ gain * vr[None, :]
    # paper (43): modulus of the complex expression; zeros (log 0) are ignored
    with np.errstate(divide="ignore"):
        terms_d = np.abs(np.log(vd_read) - np.log(alpha_d) + lam - 1j * omega)
        terms_n = np.abs(np.log(vl_read) - np.log(alpha_n) + lam - 1j * omega[:, None])
        ratio_d = np.log(np.abs(vd) / alpha_d)
        ratio_n = np.log(np.abs(vl) / alpha_n)
    finite = [x[np.isfinite(x)] for x in (terms_d, terms_n)]
    alpha_paper = float(max(np.max(f) if f.size else -np.inf for f in finite))
    theta_paper = alpha_paper - lam
    needed = np.concatenate([ratio_d.ravel(), ratio_n.ravel()])
    needed = needed[np.isfinite(needed)]
    theta_sound = float(max(np.max(needed), 0.0)) if needed.size else 0.0
    alpha_sound = theta_sound + lam

    def t_star(theta: float) -> float:
        worst = float(np.max(needed)) if needed.size else 0.0
        return 0.0 if worst <= 0 else (np.inf if theta <= 0 else worst / theta)

    def abscissa(alpha: float, theta: float) -> float:
        return float(np.max(np.linalg.eigvals(mat_matrix(modal, gain, c, alpha, theta)).real))

    return ThetaDesign(
        lambda_min_M2=lam,
        alpha_paper=alpha_paper,
        theta_paper=theta_paper,
        alpha_sound=alpha_sound,
        theta_sound=theta_sound,
        t_star_paper=t_star(theta_paper),
        t_star_sound=t_star(theta_sound),
        condition34_at_0=np.abs(vd),
        mat_abscissa_paper=abscissa(alpha_paper, theta_paper),
        mat_abscissa_sound=abscissa(alpha_sound, theta_sound),
        radius_abscissa=float(np.max(np.linalg.eigvals(m1).real)),
    )


def euler_radius_factor(p: float, theta: float, h: float) -> float:
    r"""What θ changes in the paper's Euler implementation: steady radius, Euler over exact.

    The paper integrates :math:`\dot z^r = (p - \theta)z^r + e^{-\theta t}w` by explicit Euler with step
    :math:`h`. Rescaled to :math:`\zeta = e^{\theta t}z` (no overflow) the recursion is
    :math:`\zeta_{k+1} = e^{\theta h}(1 + h(p - \theta))\zeta_k + he^{\theta h}w`, whose steady state for a
    constant :math:`w` is :math:`he^{\theta h}w/(1 - e^{\theta h}(1 + h(p - \theta)))`; the exact radius
    is :math:`w/|p|` whatever θ. A ratio below 1 means the Euler bounds are too narrow, i.e. unsound;
    :math:`1 + h(p - \theta) \le 0` (θ ≥ 1/h + p, e.g. θ = 1000 at h = 1e-3) even flips the sign of the
    radius recursion.

    Parameters
    ----------
    p : float
        Real part of an eigenvalue of :math:`A - L_1C` (negative).
    theta : float
        High-gain parameter.
    h : float
        Euler step.

    Returns
    -------
    float
        Euler steady radius divided by the exact one (``nan`` if the Euler recursion diverges).
    """
    a = np.exp(theta * h) * (1.0 + h * (p - theta))
    if abs(a) >= 1.0 or p >= 0:
        return float("nan")
    return float(h * np.exp(theta * h) * (-p) / (1.0 - a))
