r"""Design quantities of Khajenejad & Yong's GSISIO: Theorems 1–2 and Lemmas 2–5, recomputed.

:func:`gsisio_design` computes the gains of Theorem 1, the existence condition (8), the correctness
radius :math:`\rho(K_1 + L_1)` (our addition), the decomposition matrices and Lipschitz constants of
Lemma 2 (the paper's formula and the sound one) and the four stability conditions of Theorem 2 with the
numbers behind them; :class:`GSISIODesign` holds them and the width bounds of Lemma 5. The observer that
uses them is :class:`~intervalobs.observers.gsisio.GSISIO`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import DesignError
from ..interval import inflate, neg, pos
from ..systems.bounds import Bounds
from ..systems.nonlinear import NonlinearSystem
from ..validation import as_box
from .lmi import solve_lmi, verify_definite
from .mixed_monotone import JacobianDecomposition, jacobian_bounds, lipschitz_bound, paper_lipschitz_constant

__all__ = ["GSISIODesign", "gsisio_design"]

FloatArray = NDArray[np.float64]

CERTIFICATE_MARGIN = 1e-9
"""Relative margin (:func:`~intervalobs.interval.inflate`) on the certified width sequences: they come from
norms, solves and geometric sums whose rounding is far below it."""
CERTIFICATE_FLOOR = 1e-12
"""Absolute part of that margin (keeps a zero width sequence strictly positive)."""
_SIGN_TOLERANCE = 1e-12
"""Entries of T_f, T_g above -1e-12 count as nonnegative in the reported condition (a report, not a pad)."""
BoxPair = tuple[FloatArray, FloatArray]


@dataclass(frozen=True)
class GSISIODesign:
    r"""Every design quantity of the simultaneous input and state observer, recomputed (no check raises here).

    Attributes
    ----------
    J, K, L : numpy.ndarray
        :math:`J = [G; H]^\dagger` and the observer gains.
    K1, K2, L1, L2 : numpy.ndarray
        Column blocks (first n columns: state part).
    rank_condition_8 : tuple of int
        :math:`(\mathrm{rk}(I - K_1 - L_1), \mathrm{rk}(I - K_1 + L_1))`; both must equal n for the state and input
        to be recoverable.
    correctness_radius : float
        :math:`\rho(K_1 + L_1)`; the bounds are correct iff it is < 1 (our addition).
    jacobian_f, jacobian_g : tuple of numpy.ndarray
        Jacobian bounds on the Jacobian domain (interval evaluation).
    C_f, C_g, W_f, W_g : numpy.ndarray
        Matrices of the decomposition and the width matrices.
    L_f, L_g : float
        Lipschitz bounds :math:`\sup\|Df\|`, :math:`\sup\|Dg\|` on the domain.
    L_fd, L_gd : float
        Sound Lemma-2 constants :math:`\|W_f\|`, :math:`\|W_g\|`.
    L_fd_paper, L_gd_paper : float
        The paper's formula :math:`L_q + 2\|C_q\|` (not a valid bound in general).
    T_f, T_g : numpy.ndarray
        :math:`(I - K_1 - L_1)^\dagger(I + K_1 + L_1)` and :math:`(I - K_1 - L_1)^\dagger(K_2 + L_2)`.
    script_L, script_L_paper : float
        :math:`\mathcal L = L_{f_d}\|T_f\| + L_{g_d}\|T_g\|` with the sound and the paper's constants.
    componentwise_radius : float
        :math:`\rho(T_fW_f + T_gW_g)`: the width recursion is a contraction in a weighted norm iff < 1
        (our condition (iv), valid when :math:`T_f, T_g \ge 0`).
    delta_z : float
        :math:`\|T_f\Delta w + T_g\Delta v\|`.
    conditions : dict
        Which of (i), (ii), (iii), (iv) hold, with the numbers behind them.

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): Theorems 1–2 (gains, stability), Lemmas 2–5 (constants and
    width bounds), the existence condition (8), the framers (9), the decomposition (2).
    """

    J: FloatArray
    K: FloatArray
    L: FloatArray
    K1: FloatArray
    K2: FloatArray
    L1: FloatArray
    L2: FloatArray
    rank_condition_8: tuple[int, int]
    correctness_radius: float
    jacobian_f: BoxPair
    jacobian_g: BoxPair
    C_f: FloatArray
    C_g: FloatArray
    W_f: FloatArray
    W_g: FloatArray
    L_f: float
    L_g: float
    L_fd: float
    L_gd: float
    L_fd_paper: float
    L_gd_paper: float
    T_f: FloatArray
    T_g: FloatArray
    script_L: float
    script_L_paper: float
    componentwise_radius: float
    delta_z: float
    conditions: dict[str, Any] = field(default_factory=dict)

    @property
    def condition_8(self) -> bool:
        """Whether the state and the unknown input can both be recovered (the existence condition).

        References
        ----------
        Khajenejad & Yong (:mod:`intervalobs.references`): the existence condition (8).
        """
        n = self.K1.shape[0]
        return self.rank_condition_8 == (n, n)

    @property
    def stability_condition(self) -> str | None:
        """The first stability condition that holds ('(i)', '(ii)', '(iii)', '(iv)') or None."""
        for name in ("(i)", "(ii)", "(iii)", "(iv)"):
            if self.conditions.get(name, {}).get("holds"):
                return name
        return None

    def delta_x(self, delta0: float, steps: int) -> FloatArray:
        r"""The state-width bound of the paper, in closed form.

        .. math:: \delta^x_k = \mathcal L^k\delta_0 + \|\Delta z\|\frac{1 - \mathcal L^k}{1 - \mathcal L}

        Uses the sound :math:`\mathcal L`; NaN everywhere unless :math:`\mathcal L < 1` (condition (i)).
        The steady state is :math:`\|\Delta z\|/(1 - \mathcal L)` (the paper prints
        :math:`\|\Delta z\|\mathcal L/(1 - \mathcal L)`, which its own recursion does not give).

        Parameters
        ----------
        delta0 : float
            :math:`\delta^x_0 = \|\overline x_0 - \underline x_0\|`.
        steps : int
            Number of samples.

        Returns
        -------
        numpy.ndarray, shape (steps,)

        References
        ----------
        Khajenejad & Yong (:mod:`intervalobs.references`): Lemma 5.
        """
        ell = self.script_L
        if not ell < 1.0:
            return np.full(steps, np.nan)
        k = np.arange(steps, dtype=float)
        sequence = ell**k * delta0 + self.delta_z * (1.0 - ell**k) / (1.0 - ell)
        return inflate(0.0, sequence, CERTIFICATE_MARGIN, floor=CERTIFICATE_FLOOR)[1]

    def delta_d(self, delta_x: FloatArray, dw: FloatArray, dv: FloatArray) -> FloatArray:
        r"""The paper's input-width bound, corrected to use :math:`\delta^x_k` and :math:`\delta^x_{k-1}`.

        :math:`\|\Delta^d_{k-1}\| \le \|\hat J_1\|\delta^x_k + (L_{f_d}\|\hat J_1\| + L_{g_d}\|\hat J_2\|)\delta^x_{k-1}
        + \|\hat J_1\Delta w + \hat J_2\Delta v\|`, :math:`\hat J = |J|`. Row k bounds the width of
        :math:`d_{k-1}` (NaN at k = 0).

        Parameters
        ----------
        delta_x : numpy.ndarray, shape (T,)
            The state sequence of :meth:`delta_x`.
        dw, dv : numpy.ndarray
            Noise widths :math:`\overline w - \underline w`, :math:`\overline v - \underline v`.

        Returns
        -------
        numpy.ndarray, shape (T,)

        References
        ----------
        Khajenejad & Yong (:mod:`intervalobs.references`): Lemma 5.
        """
        n = self.K1.shape[0]
        jh = np.abs(self.J)
        j1, j2 = np.linalg.norm(jh[:, :n], 2), np.linalg.norm(jh[:, n:], 2)
        const = float(np.linalg.norm(jh[:, :n] @ dw + jh[:, n:] @ dv))
        out = np.full_like(delta_x, np.nan)
        out[1:] = j1 * delta_x[1:] + (self.L_fd * j1 + self.L_gd * j2) * delta_x[:-1] + const
        return out * (1.0 + 1e-9)

    def as_dict(self) -> dict[str, Any]:
        """The design numbers for ``summary.json``.

        Returns
        -------
        dict
        """
        return {
            "J": self.J,
            "K": self.K,
            "L": self.L,
            "rank_condition_8": list(self.rank_condition_8),
            "condition_8_holds": self.condition_8,
            "correctness_radius_rho_K1_plus_L1": self.correctness_radius,
            "jacobian_f_lower": self.jacobian_f[0],
            "jacobian_f_upper": self.jacobian_f[1],
            "jacobian_g_lower": self.jacobian_g[0],
            "jacobian_g_upper": self.jacobian_g[1],
            "C_f": self.C_f,
            "C_g": self.C_g,
            "W_f": self.W_f,
            "W_g": self.W_g,
            "L_f": self.L_f,
            "L_g": self.L_g,
            "L_fd": self.L_fd,
            "L_gd": self.L_gd,
            "L_fd_paper_formula": self.L_fd_paper,
            "L_gd_paper_formula": self.L_gd_paper,
            "T_f": self.T_f,
            "T_g": self.T_g,
            "script_L": self.script_L,
            "script_L_paper_formula": self.script_L_paper,
            "componentwise_radius": self.componentwise_radius,
            "delta_z": self.delta_z,
            "conditions": self.conditions,
            "stability_condition": self.stability_condition or "none holds",
        }


def _condition_ii(T_f: FloatArray, T_g: FloatArray, L_fd: float, L_gd: float) -> dict[str, Any]:
    n = T_f.shape[0]
    Q = np.linalg.eigvalsh(T_f.T @ T_f).max() * L_fd**2 + np.linalg.eigvalsh(T_g.T @ T_g).max() * L_gd**2 - 1
    Z, gg, gf, ff, fg = np.zeros((n, n)), T_g.T @ T_g, T_g.T @ T_f, T_f.T @ T_f, T_f.T @ T_g
    upper = [
        [Q * np.eye(n), Z, Z, Z, Z],
        [Z, gg, gf, gf, gg],
        [Z, gf.T, ff, ff, fg],
        [Z, gf.T, ff.T, Z, fg],
        [Z, gg.T, fg.T, fg.T, Z],
    ]
    M = np.block(upper)
    M = 0.5 * (M + M.T)
    top = float(np.linalg.eigvalsh(M).max())
    return {
        "holds": bool(top <= 0.0),
        "max_eigenvalue": top,
        "note": "blocks (4,4), (5,5) are 0 with nonzero off-diagonal blocks T_f'T_f, T_f'T_g: never NSD",
    }


def _condition_iii(script_l: float, n: int) -> dict[str, Any]:
    P = cp.Variable((n, n), symmetric=True)
    Gam = cp.Variable((n, n), symmetric=True)
    eye, Z = np.eye(n), np.zeros((n, n))
    big = cp.bmat([[P + Gam - eye, Z, P], [Z, script_l**2 * eye - P, Z], [P, Z, P]])
    problem = cp.Problem(cp.Minimize(0), [P >> 1e-6 * eye, Gam >> 0, 0.5 * (big + big.T) << 0])
    note = "block (3,3) of the LMI is P, which must be NSD and positive definite at once: infeasible"
    try:
        solve_lmi(problem, "width stability of Khajenejad & Yong", "none: the LMI is infeasible for every system")
        Pv = np.asarray(P.value)
        check = np.block([[Pv + np.asarray(Gam.value) - eye, Z, Pv], [Z, script_l**2 * eye - Pv, Z], [Pv, Z, Pv]])
        verify_definite("(iii)", check, -1, "-", tol=1e-9)
        verify_definite("(iii): P", Pv, 1, "-")
    except DesignError:
        return {"holds": False, "status": str(problem.status), "note": note}
    return {"holds": True, "status": str(problem.status), "note": note}


def gsisio_design(
    system: NonlinearSystem, bounds: Bounds, jacobian_domain: tuple[ArrayLike, ArrayLike] | None = None
) -> GSISIODesign:
    r"""Recompute every design quantity of the simultaneous input and state observer for a system.

    Parameters
    ----------
    system : NonlinearSystem
        With both Jacobians.
    bounds : Bounds
        Boxes of the noises ``w``, ``v`` (their widths enter the width bounds).
    jacobian_domain : tuple of array_like, optional
        Box on which the Jacobian bounds (and so :math:`C_f, C_g`, the Lipschitz constants) hold;
        default the whole space (the bounds must then be finite, as for the paper's example).

    Returns
    -------
    GSISIODesign

    References
    ----------
    Khajenejad & Yong (:mod:`intervalobs.references`): Theorems 1–2 and Lemmas 2, 5; :math:`\delta_z` of Lemma 5.
    """
    n, p = system.n, system.p
    full = bounds.resolve(system)
    f_jac, g_jac = system.jacobians()
    if jacobian_domain is None:
        dom_lo, dom_hi = np.full(n, -np.inf), np.full(n, np.inf)
    else:
        dom_lo, dom_hi = as_box("jacobian_domain", jacobian_domain, n)
    J = np.linalg.pinv(np.vstack([system.G, system.H]))
    Gp, Gn, Jp, Jn = pos(system.G), neg(system.G), pos(J), neg(J)
    K = Gn @ Jn + Gp @ Jp
    L = Gn @ Jp + Gp @ Jn
    K1, K2, L1, L2 = K[:, :n], K[:, n:], L[:, :n], L[:, n:]
    eye = np.eye(n)
    ranks = (int(np.linalg.matrix_rank(eye - K1 - L1)), int(np.linalg.matrix_rank(eye - K1 + L1)))
    radius = float(np.max(np.abs(np.linalg.eigvals(K1 + L1))))
    jf = jacobian_bounds(f_jac, dom_lo, dom_hi, (n, n), "f_jacobian")
    jg = jacobian_bounds(g_jac, dom_lo, dom_hi, (p, n), "g_jacobian")
    dec_f = JacobianDecomposition(system.f, *jf)
    dec_g = JacobianDecomposition(system.g, *jg)
    L_f, L_g = float(lipschitz_bound(*jf)), float(lipschitz_bound(*jg))
    L_fd, L_gd = dec_f.lipschitz_width, dec_g.lipschitz_width
    L_fd_paper, L_gd_paper = paper_lipschitz_constant(L_f, dec_f.C), paper_lipschitz_constant(L_g, dec_g.C)
    inv = np.linalg.pinv(eye - K1 - L1)
    T_f, T_g = inv @ (eye + K1 + L1), inv @ (K2 + L2)
    nf, ng = np.linalg.norm(T_f, 2), np.linalg.norm(T_g, 2)
    script_l = float(L_fd * nf + L_gd * ng)
    script_l_paper = float(L_fd_paper * nf + L_gd_paper * ng)
    dw = full.w[1] - full.w[0]
    dv = full.v[1] - full.v[0]
    delta_z = float(np.linalg.norm(T_f @ dw + T_g @ dv))
    comp = float(np.max(np.abs(np.linalg.eigvals(T_f @ dec_f.W + T_g @ dec_g.W))))
    nonneg = bool(np.all(T_f >= -_SIGN_TOLERANCE) and np.all(T_g >= -_SIGN_TOLERANCE))
    conditions: dict[str, Any] = {
        "(i)": {"holds": bool(script_l <= 1.0), "script_L": script_l, "script_L_paper_formula": script_l_paper},
        "(ii)": _condition_ii(T_f, T_g, L_fd, L_gd),
        "(iii)": _condition_iii(script_l, n),
        "(iv)": {
            "holds": bool(comp < 1.0 and nonneg and radius < 1.0),
            "spectral_radius_TfWf_plus_TgWg": comp,
            "T_nonnegative": nonneg,
        },
    }
    return GSISIODesign(
        J, K, L, K1, K2, L1, L2, ranks, radius, jf, jg, dec_f.C, dec_g.C, dec_f.W, dec_g.W,
        L_f, L_g, L_fd, L_gd, L_fd_paper, L_gd_paper, T_f, T_g, script_l, script_l_paper, comp, delta_z,
        conditions,
    )  # fmt: skip
