r"""H∞ and zonotope-size LMI gains of the integrated-observer paper, with the paper's errors corrected and every result
verified.

The observer error of the integrated-observer paper (Proposition 3.3, (15)) is :math:`e_{k+1} = (A_0 - LC)e_k + E_d
d_k`,
:math:`E_d = [E_\theta\ E_\omega\ -LE_\upsilon]`. The functions here compute the gain ``L``:

* :func:`hinf_gain` — the H∞ LMI (19) (bounded real lemma, minimise γ), and with ``monotone=True``
  the LMIs (54)–(55) (upper and lower observers; they are the same LMI, so one gain serves both) and
  (19) + (65) of the integrated scheme (the same constraint again).
* :func:`zonotope_size_gain` — the zonotope-size LMI (26) of Theorem 3.5.

Corrections to the printed LMIs (docs/paper-notes.md, the integrated-observer paper):

* (19), (54a), (55a) print ``+γI`` diagonal blocks; with them the matrix can never be negative
  definite. The bounded real lemma needs ``-γI`` — implemented.
* (54b)/(55b)/(65) ``PA_0 - MC ≥ 0`` (elementwise) with a full ``P`` does not imply
  :math:`A_0 - LC = P^{-1}(PA_0 - MC) \ge 0`. With a *diagonal* positive ``P`` it does — implemented
  (``p_structure="diagonal"``, the default); the full-``P`` version is available to show the failure.
* When no gain can make :math:`A_0 - LC` nonnegative (a negative entry of :math:`A_0` in a column
  that ``C`` does not see), the monotone design raises :class:`~intervalobs.errors.AssumptionError`.
* (26) is homogeneous in :math:`(W, Y, \Gamma, \Upsilon, \Omega)`: scaling them down drives the
  objective to 0 without changing ``L``. It is normalised here by :math:`W \succeq I`.

:math:`E_\theta` is not printed; the default :math:`E_\theta = I_n` reproduces the printed interval gain
of example (68), ``L = [0.3 0.2 0.8]ᵀ`` (γ ≈ 6.44). Lemma A.2 (:math:`\Delta A(\theta)x \approx E_\theta\theta`)
is an approximation: the gains are only a design heuristic; the observers bound :math:`\Delta A(\theta)x`
soundly by interval arithmetic and are certified separately (``ρ(|M| + D) < 1``).

Every solve is verified numerically afterwards (DESIGN.md): the LMI matrix is rebuilt from the solver's
``P`` and ``M`` and its eigenvalues checked, :math:`\rho(A_0 - LC) < 1`, the H∞ norm of the error system
is evaluated on a frequency grid, and for monotone designs :math:`A_0 - LC \ge 0` is checked exactly
(after projecting ``L`` onto that polyhedron by a small LP to remove the solver's 1e-9 violations).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from ..errors import AssumptionError, DesignError, DimensionError
from ..lp.certified import LP_OPTIONS
from ..validation import as_matrix
from .lmi import solve_lmi, verify_definite

__all__ = [
    "GainDesign",
    "gain_properties",
    "hinf_gain",
    "hinf_norm",
    "monotone_gain_exists",
    "zonotope_size_gain",
]

FloatArray = NDArray[np.float64]

_LMI_MARGIN = 1e-7
"""Strictness margin of the LMIs (``X ≺ 0`` is solved as ``X ⪯ -margin·I``)."""

_VERIFY_TOL = 1e-6
"""Relative tolerance of the a-posteriori checks."""

_RELAX = "relax the constraints (e.g. drop monotone=True) or rescale the noise matrices"


@dataclass(frozen=True)
class GainDesign:
    """Result of an LMI gain design, verified after the solve.

    Attributes
    ----------
    gain : numpy.ndarray, shape (n, p)
        Observer gain ``L``.
    lmi : str
        Which LMIs were solved, by the paper's equation labels (``"(19)"``: H∞, ``"(26)"``: zonotope size, ...).
    gamma : float or None
        Optimal γ of the H∞ LMI (None for the zonotope-size LMI).
    hinf_norm : float
        H∞ norm of :math:`(A_0 - LC, E_d)` computed on a frequency grid (a lower bound of the true norm,
        checked against γ).
    spectral_radius : float
        :math:`\\rho(A_0 - LC)`.
    abs_spectral_radius : float
        :math:`\\rho(|A_0 - LC|)`, the growth rate of the width of an interval framer without ΔA.
    monotone : bool
        Whether :math:`A_0 - LC \\ge 0` holds exactly.
    min_entry : float
        Smallest entry of :math:`A_0 - LC`.
    status : str
        Solver status.
    extra : dict
        Method-specific numbers (e.g. the objective of the zonotope-size LMI).

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`): LMIs (19), (54)–(55), (26); the ``method`` values
    are those equation labels.
    """

    gain: FloatArray
    lmi: str
    gamma: float | None
    hinf_norm: float
    spectral_radius: float
    abs_spectral_radius: float
    monotone: bool
    min_entry: float
    status: str
    extra: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """Plain-JSON form for ``summary.json``.

        Returns
        -------
        dict
            The fields, arrays as (nested) lists.
        """
        return {
            "gain": self.gain.ravel().tolist(),
            "lmi": self.lmi,
            "gamma": self.gamma,
            "hinf_norm": self.hinf_norm,
            "spectral_radius": self.spectral_radius,
            "abs_spectral_radius": self.abs_spectral_radius,
            "monotone": self.monotone,
            "min_entry": self.min_entry,
            "status": self.status,
            **self.extra,
        }


def hinf_norm(a: ArrayLike, b: ArrayLike, points: int = 4096) -> float:
    r"""H∞ norm of :math:`(zI - A)^{-1}B` on a grid of the unit circle (a lower bound; exact at the peak).

    Parameters
    ----------
    a : array_like, shape (n, n)
        Schur matrix.
    b : array_like, shape (n, k)
    points : int
        Grid points on :math:`[0, \pi]` (the response is conjugate-symmetric).

    Returns
    -------
    float
        ``inf`` when ``a`` is not Schur.
    """
    am = np.asarray(a, dtype=float)
    bm = np.asarray(b, dtype=float)
    if np.max(np.abs(np.linalg.eigvals(am))) >= 1.0:
        return float("inf")
    n = am.shape[0]
    z = np.exp(1j * np.linspace(0.0, np.pi, points))
    resp = np.linalg.solve(z[:, None, None] * np.eye(n) - am, bm.astype(complex))
    return float(np.linalg.norm(resp, ord=2, axis=(1, 2)).max())


def monotone_gain_exists(a: ArrayLike, c: ArrayLike) -> tuple[bool, str]:
    r"""Whether some gain ``L`` makes :math:`A - LC` elementwise nonnegative (an LP).

    Parameters
    ----------
    a : array_like, shape (n, n)
    c : array_like, shape (p, n)

    Returns
    -------
    ok : bool
    reason : str
        When not ok, the entries that no gain can fix (columns of ``A`` that ``C`` does not see).
    """
    am = as_matrix("A", a)
    cm = as_matrix("C", c, (None, am.shape[0]))
    blind = np.all(cm == 0, axis=0)
    bad = np.argwhere((am < 0) & blind[None, :])
    if bad.size:
        i, j = (int(v) for v in bad[0])
        return False, (
            f"A[{i},{j}] = {am[i, j]:g} < 0 lies in column {j}, which C does not measure (C[:,{j}] = 0): "
            "L changes only the columns of A seen by C, so A - LC >= 0 is impossible"
        )
    res = _monotone_projection(am, cm, np.zeros((am.shape[0], cm.shape[0])))
    if res is None:
        return False, "the LP {L : A - LC >= 0} is infeasible"
    return True, ""


def hinf_gain(
    A: ArrayLike,
    C: ArrayLike,
    E_w: ArrayLike,
    E_v: ArrayLike,
    E_theta: ArrayLike | None = None,
    *,
    monotone: bool = False,
    p_structure: Literal["diagonal", "full"] = "diagonal",
    solver: str = "CLARABEL",
) -> GainDesign:
    r"""Gain minimising γ, the bound of the noise-to-error gain, optionally with a monotone error ``A0 - LC ≥ 0``.

    Solves, for :math:`P = P^\top \succ 0`, ``M`` and γ (``-γI`` blocks: the printed ``+γI`` is an error)

    .. math::

        \begin{bmatrix} -P & PA_0 - MC & PE_\theta & PE_\omega & -ME_\upsilon & 0\\
        * & -P & 0 & 0 & 0 & I\\ * & * & -\gamma I & 0 & 0 & 0\\ * & * & * & -\gamma I & 0 & 0\\
        * & * & * & * & -\gamma I & 0\\ * & * & * & * & * & -\gamma I\end{bmatrix} \prec 0,

    and :math:`L = P^{-1}M`. With ``monotone=True`` adds :math:`PA_0 - MC \ge 0` elementwise with
    ``P`` diagonal, so that :math:`A_0 - LC \ge 0` follows.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Nominal state matrix :math:`A_0`.
    C : array_like, shape (p, n)
    E_w : array_like, shape (n, nw)
        Process-noise matrix :math:`E_\omega`.
    E_v : array_like, shape (p, nv)
        Measurement-noise matrix :math:`E_\upsilon`.
    E_theta : array_like, shape (n, ntheta), optional
        Direction of the parameter disturbance of Lemma A.2 (default :math:`I_n`).
    monotone : bool
        Add the monotonicity constraint (the error matrix stays nonnegative).
    p_structure : {"diagonal", "full"}
        Structure of ``P`` when ``monotone``; ``"full"`` is the paper's printed form, which does not imply
        :math:`A_0 - LC \ge 0` (the result's ``monotone`` flag says whether it holds).
    solver : str
        CVXPY solver (Clarabel by default, SCS as fallback on failure).

    Returns
    -------
    GainDesign

    Raises
    ------
    AssumptionError
        ``monotone`` and no gain can make :math:`A_0 - LC \ge 0`.
    DesignError
        The LMI is infeasible or its solution fails verification.

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`): H∞ LMI (19), Theorem 3.4, :math:`L = P^{-1}M`
    (20); monotonicity (54)–(55), (65), with the printed (54b) for ``p_structure="full"``.
    """
    a, c, ew, ev, et = _matrices(A, C, E_w, E_v, E_theta)
    n, p = c.shape[1], c.shape[0]
    if p_structure not in ("diagonal", "full"):
        raise DesignError(f"p_structure: expected 'diagonal' or 'full', got {p_structure!r}")
    if monotone and p_structure == "diagonal":
        ok, reason = monotone_gain_exists(a, c)
        if not ok:
            raise AssumptionError(f"monotone H∞ design: no gain makes the error system nonnegative: {reason}")
    diagonal = monotone and p_structure == "diagonal"
    p_var = cp.diag(cp.Variable(n)) if diagonal else cp.Variable((n, n), symmetric=True)
    m_var = cp.Variable((n, p))
    gamma = cp.Variable()
    lmi = _hinf_lmi(p_var, m_var, gamma, a, c, ew, ev, et)
    size = lmi.shape[0]
    constraints = [0.5 * (lmi + lmi.T) << -_LMI_MARGIN * np.eye(size), p_var >> _LMI_MARGIN * np.eye(n)]
    if monotone:
        constraints.append(p_var @ a - m_var @ c >= 0)
    problem = cp.Problem(cp.Minimize(gamma), constraints)
    name = "(19)" if not monotone else f"(54)-(55)/(65), {p_structure} P"
    status = solve_lmi(problem, name, _RELAX, solver=solver).label
    pv = np.asarray(p_var.value, dtype=float)
    mv = np.asarray(m_var.value, dtype=float)
    g = float(np.asarray(gamma.value))
    check = _hinf_lmi_value(pv, mv, g, a, c, ew, ev, et)
    worst = verify_definite(name, check, -1, _RELAX, tol=_VERIFY_TOL * max(1.0, g))
    verify_definite(f"{name}: P", pv, 1, _RELAX)
    gain = np.linalg.solve(pv, mv)
    extra: dict[str, Any] = {"lmi_max_eig": worst, "E_theta": et.tolist()}
    if diagonal:
        projected = _monotone_projection(a, c, gain)
        if projected is None:
            raise DesignError(f"{name}: the solver's gain cannot be projected onto A0 - LC >= 0")
        extra["projection_shift"] = float(np.abs(projected - gain).max())
        gain = projected
    return _verified(a, c, ew, ev, et, gain, name, g, status, extra)


def zonotope_size_gain(
    A: ArrayLike,
    C: ArrayLike,
    E_w: ArrayLike,
    E_v: ArrayLike,
    E_theta: ArrayLike | None = None,
    *,
    rho: float = 0.9,
    solver: str = "CLARABEL",
) -> GainDesign:
    r"""Gain that keeps the zonotope of the error small (the zonotope-size LMI), normalised by :math:`W \succeq I`.

    Minimises :math:`\mathrm{tr}\,\Gamma + \mathrm{tr}\,\Upsilon + \mathrm{tr}\,\Omega` (the error zonotope's size)
    subject to

    .. math::

        \begin{bmatrix} \rho W & * & * & * & *\\ 0 & \Gamma & * & * & *\\ 0 & 0 & \Upsilon & * & *\\
        0 & 0 & 0 & \Omega & *\\ WA_0 - YC & WE_\omega & -YE_\upsilon & WE_\theta & W\end{bmatrix} \succ 0,

    Γ, Υ, Ω diagonal positive, and :math:`L = W^{-1}Y`. Without a normalisation the problem is
    homogeneous (its infimum 0 is approached by scaling every variable down), so :math:`W \succeq I`
    is imposed; the LMI implies :math:`(A_0 - LC)^\top W (A_0 - LC) \prec \rho W`, i.e.
    :math:`\rho(A_0 - LC) < \sqrt{\rho}`.

    Parameters
    ----------
    A, C, E_w, E_v, E_theta : array_like
        As in :func:`hinf_gain`.
    rho : float
        Contraction factor ρ asked of the error, in (0, 1).
    solver : str
        CVXPY solver.

    Returns
    -------
    GainDesign

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`): zonotope-size LMI (26), Theorem 3.5; ε of (26c);
    ρ of (25).
    """
    a, c, ew, ev, et = _matrices(A, C, E_w, E_v, E_theta)
    if not 0.0 < rho < 1.0:
        raise DesignError(f"rho: expected a value in (0, 1), got {rho!r}")
    n, p = c.shape[1], c.shape[0]
    nw, nv, nt = ew.shape[1], ev.shape[1], et.shape[1]
    w = cp.Variable((n, n), symmetric=True)
    y = cp.Variable((n, p))
    gam, ups, om = cp.Variable(nw), cp.Variable(nv), cp.Variable(nt)
    top = cp.bmat(
        [
            [rho * w, np.zeros((n, nw)), np.zeros((n, nv)), np.zeros((n, nt))],
            [np.zeros((nw, n)), cp.diag(gam), np.zeros((nw, nv)), np.zeros((nw, nt))],
            [np.zeros((nv, n)), np.zeros((nv, nw)), cp.diag(ups), np.zeros((nv, nt))],
            [np.zeros((nt, n)), np.zeros((nt, nw)), np.zeros((nt, nv)), cp.diag(om)],
        ]
    )
    r = cp.hstack([w @ a - y @ c, w @ ew, -y @ ev, w @ et])
    big = cp.bmat([[top, r.T], [r, w]])
    size = big.shape[0]
    constraints = [
        0.5 * (big + big.T) >> _LMI_MARGIN * np.eye(size),
        w >> np.eye(n),
        gam >= _LMI_MARGIN,
        ups >= _LMI_MARGIN,
        om >= _LMI_MARGIN,
    ]
    objective = cp.sum(gam) + cp.sum(ups) + cp.sum(om)
    problem = cp.Problem(cp.Minimize(objective), constraints)
    status = solve_lmi(problem, "(26)", _RELAX, solver=solver).label
    wv = np.asarray(w.value, dtype=float)
    gain = np.linalg.solve(wv, np.asarray(y.value, dtype=float))
    # verification: the Schur complement of (26a) with the recovered gain
    closed = a - gain @ c
    rm = np.hstack([closed, ew, -gain @ ev, et])
    d = np.diag(np.concatenate([np.asarray(gam.value), np.asarray(ups.value), np.asarray(om.value)]))
    lhs = np.block([[rho * wv, np.zeros((n, d.shape[0]))], [np.zeros((d.shape[0], n)), d]]) - rm.T @ wv @ rm
    least = verify_definite("(26) with L = W⁻¹Y", lhs, 1, _RELAX, tol=_VERIFY_TOL * max(1.0, float(np.abs(lhs).max())))
    extra = {"rho": rho, "epsilon": float(objective.value), "lmi_min_eig": least, "E_theta": et.tolist()}
    return _verified(a, c, ew, ev, et, gain, f"(26), rho={rho:g}", None, status, extra)


def _matrices(
    A: ArrayLike, C: ArrayLike, E_w: ArrayLike, E_v: ArrayLike, E_theta: ArrayLike | None
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    a = as_matrix("A", A)
    n = a.shape[0]
    if a.shape != (n, n):
        raise DimensionError(f"A: expected a square matrix, got shape {a.shape}")
    c = as_matrix("C", C, (None, n))
    ew = as_matrix("E_w", E_w, (n, None))
    ev = as_matrix("E_v", E_v, (c.shape[0], None))
    et = np.eye(n) if E_theta is None else as_matrix("E_theta", E_theta, (n, None))
    return a, c, ew, ev, et


def _hinf_lmi(
    p: Any, m: Any, gamma: Any, a: FloatArray, c: FloatArray, ew: FloatArray, ev: FloatArray, et: FloatArray
) -> Any:
    n, nt, nw, nv = a.shape[0], et.shape[1], ew.shape[1], ev.shape[1]
    z = np.zeros
    rows = [
        [-p, p @ a - m @ c, p @ et, p @ ew, -m @ ev, z((n, n))],
        [None, -p, z((n, nt)), z((n, nw)), z((n, nv)), np.eye(n)],
        [None, None, -gamma * np.eye(nt), z((nt, nw)), z((nt, nv)), z((nt, n))],
        [None, None, None, -gamma * np.eye(nw), z((nw, nv)), z((nw, n))],
        [None, None, None, None, -gamma * np.eye(nv), z((nv, n))],
        [None, None, None, None, None, -gamma * np.eye(n)],
    ]
    for i in range(6):
        for j in range(i):
            rows[i][j] = rows[j][i].T
    return cp.bmat(rows)


def _hinf_lmi_value(
    p: FloatArray,
    m: FloatArray,
    gamma: float,
    a: FloatArray,
    c: FloatArray,
    ew: FloatArray,
    ev: FloatArray,
    et: FloatArray,
) -> FloatArray:
    n, nt, nw, nv = a.shape[0], et.shape[1], ew.shape[1], ev.shape[1]
    z = np.zeros
    top = np.hstack([-p, p @ a - m @ c, p @ et, p @ ew, -m @ ev, z((n, n))])
    second = np.hstack([z((n, n)), -p, z((n, nt + nw + nv)), np.eye(n)])
    k = nt + nw + nv + n
    rest = np.hstack([z((k, 2 * n)), -gamma * np.eye(k)])
    upper = np.vstack([top, second, rest])
    lower_part = np.triu(upper, 1)
    return np.triu(upper) + lower_part.T


def _monotone_projection(a: FloatArray, c: FloatArray, gain: FloatArray) -> FloatArray | None:
    """The gain closest (max-norm) to ``gain`` with ``A - LC >= 0`` exactly, or None when impossible.

    An LP in (vec L, t): minimise t subject to |L - gain| <= t and (LC)_ij <= A_ij - δ_ij, where δ is a
    small tightening (only on the columns that C sees) raised until the floating-point check passes.
    """
    n, p = c.shape[1], c.shape[0]
    nv = n * p
    kron = np.zeros((n * n, nv))
    for i in range(n):
        for j in range(n):
            kron[i * n + j, i * p : (i + 1) * p] = c[:, j]
    seen = np.tile(np.any(c != 0, axis=0), n).astype(float)
    a_ub = np.vstack(
        [
            np.hstack([kron, np.zeros((n * n, 1))]),
            np.hstack([np.eye(nv), -np.ones((nv, 1))]),
            np.hstack([-np.eye(nv), -np.ones((nv, 1))]),
        ]
    )
    scale = max(1.0, float(np.abs(a).max()))
    for delta in (0.0, 1e-13, 1e-11, 1e-9, 1e-7):
        b_ub = np.concatenate([a.ravel() - delta * scale * seen, gain.ravel(), -gain.ravel()])
        res = linprog(
            np.r_[np.zeros(nv), 1.0], A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * nv + [(0, None)], options=LP_OPTIONS
        )
        if res.status != 0:
            return None
        out = np.asarray(res.x[:nv], dtype=float).reshape(n, p)
        if (a - out @ c).min() >= 0.0:
            return out
    return None


def _verified(
    a: FloatArray,
    c: FloatArray,
    ew: FloatArray,
    ev: FloatArray,
    et: FloatArray,
    gain: FloatArray,
    name: str,
    gamma: float | None,
    status: str,
    extra: dict[str, Any],
) -> GainDesign:
    gain = gain + 0.0  # no negative zeros in reports
    closed = a - gain @ c
    rho = float(np.max(np.abs(np.linalg.eigvals(closed))))
    if rho >= 1.0:
        raise DesignError(f"{name}: the gain gives rho(A0 - LC) = {rho:.6g} >= 1 (status {status})")
    norm = hinf_norm(closed, np.hstack([et, ew, -gain @ ev]))
    if gamma is not None and norm > gamma * (1.0 + 1e-4):
        raise DesignError(f"{name}: H∞ norm {norm:.6g} exceeds the certified γ = {gamma:.6g}")
    return GainDesign(
        gain=gain,
        lmi=name,
        gamma=gamma,
        hinf_norm=norm,
        spectral_radius=rho,
        abs_spectral_radius=float(np.max(np.abs(np.linalg.eigvals(np.abs(closed))))),
        monotone=bool(closed.min() >= 0.0),
        min_entry=float(closed.min()),
        status=status,
        extra=extra,
    )


def gain_properties(A: ArrayLike, C: ArrayLike, L: ArrayLike, dA_radius: ArrayLike | None = None) -> dict[str, Any]:
    r"""What a gain does to :math:`M = A - LC`: sign pattern and the spectral radii an observer needs.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Nominal (midpoint) state matrix.
    C : array_like, shape (p, n)
    L : array_like, shape (n, p) or (n,) for one output
    dA_radius : array_like, shape (n, n), optional
        Elementwise radius ``D`` of the interval uncertainty of ``A``.

    Returns
    -------
    dict
        ``gain``, ``min_entry`` and ``monotone`` (:math:`M \ge 0`), ``spectral_radius``
        (:math:`\rho(M)`, Luenberger / zonotope centre), ``abs_spectral_radius`` (:math:`\rho(|M|)`,
        interval framer without ΔA) and ``width_spectral_radius`` (:math:`\rho(|M| + D)`, the sound
        framer's certificate with ΔA; ``< 1`` means certified).
    """
    a = as_matrix("A", A)
    c = as_matrix("C", C, (None, a.shape[0]))
    gain = as_matrix("L", L, (a.shape[0], c.shape[0]))
    d = np.zeros_like(a) if dA_radius is None else as_matrix("dA_radius", dA_radius, a.shape)
    closed = a - gain @ c

    def rho(x: FloatArray) -> float:
        return float(np.max(np.abs(np.linalg.eigvals(x))))

    return {
        "gain": gain.ravel().tolist(),
        "min_entry": float(closed.min()),
        "monotone": bool(closed.min() >= 0),
        "spectral_radius": rho(closed),
        "abs_spectral_radius": rho(np.abs(closed)),
        "width_spectral_radius": rho(np.abs(closed) + d),
    }
