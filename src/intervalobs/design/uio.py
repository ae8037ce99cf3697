r"""Unknown-input decoupling and cooperative coordinates of seed 000 (Darouach-style UIO).

For :math:`\dot x = Ax + Bu + D\xi + \omega`, :math:`y = Cx + \delta` (seed 000, eq. (1)) the observer
matrices solve the algebraic constraints (21)–(22),

.. math:: N + KC - ECA = A, \qquad ECD = -D,

whose solutions are parametrised by (23)–(25):

.. math:: E = -D(CD)^\dagger + W\,(I_p - CD(CD)^\dagger), \qquad P = I_n + EC, \qquad N = PA - KC,

and :math:`L = K - NE` (eq. (14)). Hypothesis 4 (rank(CD) = rank(D) = q ≤ p) makes :math:`(CD)^\dagger`
a left inverse of :math:`CD`, so that :math:`PD = 0`; Hypothesis 5 asks :math:`I_p + CW` nonsingular and
:math:`(PA, C)` detectable; Hypothesis 6 asks coordinates :math:`z = Tx` in which :math:`TNT^{-1}` is
Metzler and Hurwitz. We design :math:`K` by placing real, distinct poles and take :math:`T = V^{-1}`
(V the eigenvectors of N), which makes :math:`TNT^{-1}` diagonal — Metzler in the strongest sense.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import place_poles

from ..errors import AssumptionError, DesignError, DimensionError
from ..validation import as_matrix, as_vector

__all__ = [
    "UIOCoordinates",
    "UIODecoupling",
    "check_cooperative",
    "design_uio_coordinates",
    "uio_constraint_matrices",
    "uio_decoupling",
    "uio_pole_candidates",
]

FloatArray = NDArray[np.float64]

_RANK_TOL = 1e-9
_DIAGONAL_TOL = 1e-9


@dataclass(frozen=True)
class UIODecoupling:
    """The decoupling matrices of seed 000, eqs. (11), (25), with the hypotheses' evidence.

    Attributes
    ----------
    E : numpy.ndarray, shape (n, p)
        ``E = -D (CD)† + W (I - CD (CD)†)`` (eq. (11)).
    P : numpy.ndarray, shape (n, n)
        ``P = I + E C``; ``P D = 0`` up to rounding.
    W : numpy.ndarray, shape (n, p)
        The free parameter of (24).
    M0 : numpy.ndarray, shape (q, p)
        ``(CD)†``, the left inverse of ``CD`` used for the unknown input (eq. (36)).
    rank_CD, rank_D : int
        Ranks checked by Hypothesis 4.
    observability_margin : float
        Smallest singular value of the observability matrix of ``(PA, C)`` (0 when unobservable).
    decoupling_residual : float
        ``max |P D|`` (exactly 0 in exact arithmetic).
    """

    E: FloatArray
    P: FloatArray
    W: FloatArray
    M0: FloatArray
    rank_CD: int
    rank_D: int
    observability_margin: float
    decoupling_residual: float


@dataclass(frozen=True)
class UIOCoordinates:
    r"""A gain ``K`` and coordinates ``z = T x`` with ``T N T⁻¹`` diagonal (Hypothesis 6).

    Attributes
    ----------
    K : numpy.ndarray, shape (n, p)
        Output-injection gain of ``N = PA - KC`` (eq. (14)).
    T, S : numpy.ndarray, shape (n, n)
        Coordinate change and its computed inverse ``S = T⁻¹`` (eq. (31)).
    N : numpy.ndarray, shape (n, n)
        ``PA - KC``.
    L : numpy.ndarray, shape (n, p)
        ``K - N E`` (eq. (14)).
    poles : numpy.ndarray, shape (n,)
        Diagonal of ``T N T⁻¹`` (real, negative, distinct).
    J : numpy.ndarray, shape (n, n)
        ``T N T⁻¹`` as computed.
    metzler_check : float
        Smallest off-diagonal entry of ``J`` (≥ 0 up to rounding for a Metzler matrix).
    offdiagonal : float
        Largest ``|J_ij|``, ``i ≠ j`` (rounding level for a diagonalising ``T``).
    cond_T : float
        Condition number of ``T``.
    score : float
        Sum of the asymptotic state-width bound used to choose among candidates (inf if not scored).
    tried : dict
        Score of every candidate pole set.
    """

    K: FloatArray
    T: FloatArray
    S: FloatArray
    N: FloatArray
    L: FloatArray
    poles: FloatArray
    J: FloatArray
    metzler_check: float
    offdiagonal: float
    cond_T: float
    score: float = float("inf")
    tried: dict[str, float] = field(default_factory=dict)


def _rank(m: FloatArray) -> int:
    if m.size == 0:
        return 0
    s = np.linalg.svd(m, compute_uv=False)
    return int(np.sum(s > _RANK_TOL * max(1.0, float(s[0]))))


def _observability_margin(a: FloatArray, c: FloatArray) -> float:
    n = a.shape[0]
    blocks = [c]
    for _ in range(n - 1):
        blocks.append(blocks[-1] @ a)
    s = np.linalg.svd(np.vstack(blocks), compute_uv=False)
    return float(s[n - 1]) if s.size >= n else 0.0


def _undetectable_modes(a: FloatArray, c: FloatArray) -> list[complex]:
    """Eigenvalues with Re ≥ 0 that the PBH test finds unobservable through ``c``."""
    n = a.shape[0]
    bad = []
    scale = max(1.0, float(np.abs(a).max()))
    for lam in np.linalg.eigvals(a):
        if lam.real >= -1e-9 * scale:
            pbh = np.vstack([lam * np.eye(n) - a, c.astype(complex)])
            s = np.linalg.svd(pbh, compute_uv=False)
            if s[-1] <= 1e-8 * scale:
                bad.append(complex(lam))
    return bad


def uio_decoupling(A: ArrayLike, C: ArrayLike, D: ArrayLike, W: ArrayLike | None = None) -> UIODecoupling:
    r"""Decoupling matrices ``E``, ``P`` of seed 000 (eqs. (11), (24)–(25)) with Hypotheses 4–5 checked.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    C : array_like, shape (p, n)
        Output matrix.
    D : array_like, shape (n, q)
        Unknown-input matrix.
    W : array_like, shape (n, p), optional
        Free parameter of (11) (default 0, as in the paper's example).

    Returns
    -------
    UIODecoupling

    Raises
    ------
    AssumptionError
        Hypothesis 4 fails (rank(CD) ≠ rank(D), rank(D) ≠ q, or q > p) or Hypothesis 5 fails
        (I_p + CW singular, or (PA, C) not detectable).
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    if a.shape != (n, n):
        raise DimensionError(f"A: expected a square matrix, got shape {a.shape}")
    c = as_matrix("C", C, (None, n))
    d = as_matrix("D", D, (n, None))
    p, q = c.shape[0], d.shape[1]
    w = np.zeros((n, p)) if W is None else as_matrix("W", W, (n, p))
    cd = c @ d
    rank_cd, rank_d = _rank(cd), _rank(d)
    if q > p:
        raise AssumptionError(
            f"Hypothesis 4 (seed 000, eq. (10)): expected q ≤ p unknown inputs, got q = {q} > p = {p} outputs"
        )
    if rank_d != q:
        raise AssumptionError(f"Hypothesis 4 (seed 000, eq. (10)): expected rank(D) = q = {q}, got rank(D) = {rank_d}")
    if rank_cd != rank_d:
        raise AssumptionError(
            f"Hypothesis 4 (seed 000, eq. (10)): rank(CD) = {rank_cd} but rank(D) = {rank_d}: "
            "the unknown inputs cannot be decoupled"
        )
    m0 = np.asarray(np.linalg.pinv(cd), dtype=float)
    e = -d @ m0 + w @ (np.eye(p) - cd @ m0)
    if _rank(np.eye(p) + c @ w) < p:
        raise AssumptionError("Hypothesis 5 (seed 000): expected I_p + C W nonsingular, got a singular matrix")
    pmat = np.eye(n) + e @ c
    pa = pmat @ a
    bad = _undetectable_modes(pa, c)
    if bad:
        raise AssumptionError(
            f"Hypothesis 5 (seed 000): expected (PA, C) detectable, got unobservable modes with Re ≥ 0 at {bad}"
        )
    residual = float(np.abs(pmat @ d).max()) if d.size else 0.0
    scale = max(1.0, float(np.abs(d).max()) * max(1.0, float(np.abs(e @ c).max())))
    if residual > 1e-10 * scale:
        raise DesignError(f"uio_decoupling: expected P D = 0, got max |P D| = {residual:.3g} (ill-conditioned CD)")
    return UIODecoupling(e, pmat, w, m0, rank_cd, rank_d, _observability_margin(pa, c), residual)


def uio_constraint_matrices(A: ArrayLike, C: ArrayLike, D: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""The matrices of the compact constraint ``[N K E] Σ = Θ`` (seed 000, eqs. (23)–(24)).

    .. math:: \Sigma = \begin{bmatrix} I_n & 0 \\ C & 0 \\ -CA & CD \end{bmatrix}, \qquad
              \Theta = [A \;\; -D], \qquad
              \Sigma^\dagger = \begin{bmatrix} I_n & 0 & 0 \\ (CD)^\dagger CA & 0 & (CD)^\dagger \end{bmatrix}

    Parameters
    ----------
    A, C, D : array_like
        System matrices as in :func:`uio_decoupling`.

    Returns
    -------
    Sigma : numpy.ndarray, shape (n + 2p, n + q)
    Theta : numpy.ndarray, shape (n, n + q)
    Sigma_pinv : numpy.ndarray, shape (n + q, n + 2p)
        The left inverse printed in (24); ``Sigma_pinv @ Sigma = I`` under Hypothesis 4.
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    c = as_matrix("C", C, (None, n))
    d = as_matrix("D", D, (n, None))
    p, q = c.shape[0], d.shape[1]
    cd = c @ d
    sigma = np.zeros((n + 2 * p, n + q))
    sigma[:n, :n] = np.eye(n)
    sigma[n : n + p, :n] = c
    sigma[n + p :, :n] = -c @ a
    sigma[n + p :, n:] = cd
    theta = np.hstack([a, -d])
    m0 = np.linalg.pinv(cd)
    sigma_pinv = np.zeros((n + q, n + 2 * p))
    sigma_pinv[:n, :n] = np.eye(n)
    sigma_pinv[n:, :n] = m0 @ c @ a
    sigma_pinv[n:, n + p :] = m0
    return sigma, theta, sigma_pinv


def _coordinates(pa: FloatArray, c: FloatArray, e: FloatArray, k: FloatArray, t: FloatArray | None) -> UIOCoordinates:
    n = pa.shape[0]
    nmat = pa - k @ c
    if t is None:
        vals, vecs = np.linalg.eig(nmat)
        if np.max(np.abs(vals.imag)) > 1e-9 * max(1.0, float(np.abs(vals).max())):
            raise DesignError(f"design_uio_coordinates: PA - KC has complex poles {vals}; place real ones")
        order = np.argsort(vals.real)[::-1]
        v = vecs[:, order].real
        t = np.linalg.inv(v)
    s = np.asarray(np.linalg.inv(t), dtype=float)
    j = t @ nmat @ s
    off = j - np.diag(np.diag(j))
    mask = ~np.eye(n, dtype=bool)
    metzler = float(j[mask].min()) if n > 1 else 0.0
    return UIOCoordinates(
        K=k,
        T=t,
        S=s,
        N=nmat,
        L=k - nmat @ e,
        poles=np.diag(j).copy(),
        J=j,
        metzler_check=metzler,
        offdiagonal=float(np.abs(off).max()) if n > 1 else 0.0,
        cond_T=float(np.linalg.cond(t)),
    )


def uio_pole_candidates(n: int) -> dict[str, FloatArray]:
    """Real, distinct pole sets tried by :func:`design_uio_coordinates`: ``-a·(1 … n)`` and ``-a·1.6^i``.

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    dict of str to numpy.ndarray
        Pole sets by name.
    """
    found: dict[str, FloatArray] = {}
    for scale in (0.5, 1.0, 2.0, 3.0):
        found[f"linear x{scale:g}"] = -scale * np.arange(1, n + 1, dtype=float)
        found[f"geometric x{scale:g}"] = -scale * 1.6 ** np.arange(n, dtype=float)
    return found


def asymptotic_state_width(
    decoupling: UIODecoupling, coords: UIOCoordinates, omega_radius: FloatArray, delta_radius: FloatArray
) -> FloatArray:
    r"""Asymptotic width of the state bounds (seed 000, eqs. (30), (34), for the exactly integrated observer).

    In coordinates :math:`w = T(x + E\psi)` the bounds obey
    :math:`\dot{\overline w} - \dot{\underline w} = \Lambda(\overline w - \underline w)
    + 2|TL|\bar\delta + 2|TP|\bar\omega`,
    so :math:`\rho_w = -\Lambda^{-1}(2|TL|\bar\delta + 2|TP|\bar\omega)` and
    :math:`\rho_x = |T^{-1}|\rho_w + 2|E|\bar\delta`.

    Parameters
    ----------
    decoupling : UIODecoupling
    coords : UIOCoordinates
    omega_radius : numpy.ndarray, shape (n,)
        Radius of the state-noise box (after its input matrix).
    delta_radius : numpy.ndarray, shape (p,)
        Radius of the measurement-noise box.

    Returns
    -------
    numpy.ndarray, shape (n,)
    """
    forcing = 2 * np.abs(coords.T @ coords.L) @ delta_radius + 2 * np.abs(coords.T @ decoupling.P) @ omega_radius
    rho_w = forcing / np.abs(coords.poles)
    return np.asarray(np.abs(coords.S) @ rho_w + 2 * np.abs(decoupling.E) @ delta_radius)


def check_cooperative(
    A: ArrayLike, C: ArrayLike, decoupling: UIODecoupling, K: ArrayLike, T: ArrayLike | None = None
) -> UIOCoordinates:
    """Check Hypothesis 6 for a given gain ``K`` (and coordinates ``T``; default ``T = V⁻¹``).

    Parameters
    ----------
    A, C : array_like
        System matrices.
    decoupling : UIODecoupling
        From :func:`uio_decoupling`.
    K : array_like, shape (n, p)
        Output-injection gain.
    T : array_like, shape (n, n), optional
        Coordinate change; default the inverse eigenvector matrix of ``PA - KC``.

    Returns
    -------
    UIOCoordinates

    Raises
    ------
    AssumptionError
        ``T (PA - KC) T⁻¹`` is not Metzler (a negative off-diagonal entry beyond rounding) or not Hurwitz.
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    c = as_matrix("C", C, (None, n))
    k = as_matrix("K", K, (n, c.shape[0]))
    t = None if T is None else as_matrix("T", T, (n, n))
    if t is not None and np.linalg.cond(t) > 1e12:
        raise AssumptionError(
            f"Hypothesis 6 (seed 000): expected an invertible T, got cond(T) = {np.linalg.cond(t):.3g}"
        )
    coords = _coordinates(decoupling.P @ a, c, decoupling.E, k, t)
    scale = max(1.0, float(np.abs(coords.J).max()))
    if coords.metzler_check < -_DIAGONAL_TOL * scale:
        raise AssumptionError(
            "Hypothesis 6 (seed 000): expected T (PA - KC) T⁻¹ Metzler, "
            f"got smallest off-diagonal entry {coords.metzler_check:.4g}"
        )
    top = float(np.max(np.linalg.eigvals(coords.J).real))
    if top >= 0:
        raise AssumptionError(
            f"Hypothesis 6 (seed 000): expected T (PA - KC) T⁻¹ Hurwitz, got an eigenvalue with real part {top:.4g}"
        )
    return coords


def design_uio_coordinates(
    A: ArrayLike,
    C: ArrayLike,
    decoupling: UIODecoupling,
    omega_radius: ArrayLike,
    delta_radius: ArrayLike,
    poles: ArrayLike | None = None,
) -> UIOCoordinates:
    """Gain ``K`` and diagonalising coordinates ``T`` (Hypothesis 6) with the smallest state-width bound.

    Each candidate places real, distinct poles of ``PA - KC`` (``scipy.signal.place_poles``) and takes
    ``T = V⁻¹``; the candidate with the smallest ``sum(ρ_x)`` (:func:`asymptotic_state_width`) wins.
    The result is verified: ``T N T⁻¹`` diagonal to rounding, poles real, negative and distinct.

    Parameters
    ----------
    A, C : array_like
        System matrices.
    decoupling : UIODecoupling
        From :func:`uio_decoupling`.
    omega_radius : array_like, shape (n,)
        Radius of the state-noise box, used to score candidates.
    delta_radius : array_like, shape (p,)
        Radius of the measurement-noise box.
    poles : array_like, shape (n,), optional
        Use these poles (real, negative, distinct) instead of searching.

    Returns
    -------
    UIOCoordinates

    Raises
    ------
    DesignError
        No candidate gives real distinct poles with a well-conditioned ``T``.
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    c = as_matrix("C", C, (None, n))
    om = as_vector("omega_radius", omega_radius, n)
    de = as_vector("delta_radius", delta_radius, c.shape[0])
    pa = decoupling.P @ a
    if poles is not None:
        pl = as_vector("poles", poles, n)
        if np.any(pl >= 0) or np.unique(pl).size != n:
            raise DesignError(f"poles: expected {n} distinct negative real poles, got {pl}")
        candidates = {"given": pl}
    else:
        candidates = uio_pole_candidates(n)
    best: UIOCoordinates | None = None
    tried: dict[str, float] = {}
    for name, pl in candidates.items():
        try:
            k = np.asarray(place_poles(pa.T, c.T, pl).gain_matrix.T)
            coords = _coordinates(pa, c, decoupling.E, k, None)
        except (ValueError, np.linalg.LinAlgError, DesignError):
            tried[name] = float("inf")
            continue
        scale = max(1.0, float(np.abs(coords.J).max()))
        ok = (
            coords.cond_T < 1e6
            and coords.offdiagonal <= _DIAGONAL_TOL * scale
            and np.all(coords.poles < 0)
            and np.allclose(np.sort(coords.poles), np.sort(pl), rtol=1e-6, atol=1e-9)
        )
        if not ok:
            tried[name] = float("inf")
            continue
        score = float(np.sum(asymptotic_state_width(decoupling, coords, om, de)))
        tried[name] = score
        if best is None or score < best.score:
            best = UIOCoordinates(**{**coords.__dict__, "score": score})
    if best is None:
        raise DesignError(
            f"design_uio_coordinates: no pole set in {list(candidates)} gave a diagonalising, "
            "well-conditioned T; give other real distinct poles"
        )
    return UIOCoordinates(**{**best.__dict__, "tried": tried})
