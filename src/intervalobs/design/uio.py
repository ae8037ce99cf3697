r"""Unknown-input decoupling and cooperative coordinates of the aircraft UIO paper (Darouach-style UIO).

For :math:`\dot x = Ax + Bu + D\xi + \omega`, :math:`y = Cx + \delta` (the aircraft UIO paper, eq. (1)) the observer
matrices solve the algebraic constraints (21)–(22),

.. math:: N + KC - ECA = A, \qquad ECD = -D,

whose solutions are parametrised by (23)–(25):

.. math:: E = -D(CD)^\dagger + W\,(I_p - CD(CD)^\dagger), \qquad P = I_n + EC, \qquad N = PA - KC,

and :math:`L = K - NE` (eq. (14)). Hypothesis 4 (rank(CD) = rank(D) = q ≤ p) makes :math:`(CD)^\dagger`
a left inverse of :math:`CD`, so that :math:`PD = 0`; Hypothesis 5 asks :math:`I_p + CW` nonsingular and
:math:`(PA, C)` detectable; Hypothesis 6 asks coordinates :math:`z = Tx` in which :math:`TNT^{-1}` is
Metzler and Hurwitz. We design :math:`K` by pole placement and map :math:`N` onto a block-diagonal
Metzler matrix with the same spectrum (:func:`metzler_block_form`: diagonal for real, possibly repeated
poles; a 3×3 cyclic Metzler block for each complex pair with a real partner), by
:math:`T = UV^{-1}` (V, U the eigenvectors of N and of the block form), checked after the design.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import place_poles

from .._docstrings import shared_docs
from ..errors import AssumptionError, DesignError, DimensionError
from ..validation import as_matrix, as_vector
from .regions import canonical_eigenvectors

__all__ = [
    "UIOCoordinates",
    "UIODecoupling",
    "check_cooperative",
    "design_uio_coordinates",
    "metzler_block_form",
    "uio_constraint_matrices",
    "uio_decoupling",
    "uio_pole_candidates",
]

FloatArray = NDArray[np.float64]

_RANK_TOL = 1e-9
_DIAGONAL_TOL = 1e-9
# ``place_poles`` (Yang-Tits) branches on rounding-level differences of its input when PA is defective (the
# aircraft's PA has a triple zero eigenvalue): the same design gave Σρ_x 0.35 on one machine and 0.37 on another.
# Every pole set is placed on PA; the _REFINED_SETS best are placed again on _PLACEMENT_TRIALS copies of PA
# perturbed by _PLACEMENT_JITTER (relative, fixed pattern) and the best-scoring gain of all is kept, so that each
# machine tries the same branches (jittering every set made the design several times slower).
_REFINED_SETS = 2
_PLACEMENT_TRIALS = 4
_PLACEMENT_JITTER = 1e-13


@dataclass(frozen=True)
class UIODecoupling:
    """The decoupling matrices that remove the unknown input from the error, with the evidence of their conditions.

    Attributes
    ----------
    E : numpy.ndarray, shape (n, p)
        ``E = -D (CD)† + W (I - CD (CD)†)``.
    P : numpy.ndarray, shape (n, n)
        ``P = I + E C``; ``P D = 0`` up to rounding.
    W : numpy.ndarray, shape (n, p)
        The free parameter ``W``.
    M0 : numpy.ndarray, shape (q, p)
        ``(CD)†``, the left inverse of ``CD`` used for the unknown input.
    rank_CD, rank_D : int
        Ranks checked: the unknown input must be visible in the outputs.
    observability_margin : float
        Smallest singular value of the observability matrix of ``(PA, C)`` (0 when unobservable).
    decoupling_residual : float
        ``max |P D|`` (exactly 0 in exact arithmetic).

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): eqs. (11), (24), (25), (36); Hypothesis 4.
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
    r"""A gain ``K`` and coordinates ``z = T x`` with ``T N T⁻¹`` Metzler and Hurwitz: a cooperative, stable error.

    Attributes
    ----------
    K : numpy.ndarray, shape (n, p)
        Output-injection gain of ``N = PA - KC``.
    T, S : numpy.ndarray, shape (n, n)
        Coordinate change and its computed inverse ``S = T⁻¹``.
    N : numpy.ndarray, shape (n, n)
        ``PA - KC``.
    L : numpy.ndarray, shape (n, p)
        ``K - N E``.
    M : numpy.ndarray, shape (n, n)
        The Metzler, Hurwitz matrix the observer integrates: block diagonal (1×1 real poles, 3×3
        cyclic blocks for complex pairs, see :func:`metzler_block_form`), or ``T N T⁻¹`` with its
        rounding-level negative off-diagonal entries set to 0 for a given ``T``. ``T N T⁻¹ - M`` is
        rounding-level and bounded by the observer.
    poles : numpy.ndarray, shape (n,), complex
        Eigenvalues of ``M`` (the closed-loop poles of ``PA - KC``), real parts descending.
    J : numpy.ndarray, shape (n, n)
        ``T N T⁻¹`` as computed.
    metzler_check : float
        Smallest off-diagonal entry of ``J`` (≥ 0 up to rounding for a Metzler matrix).
    form_residual : float
        ``max |J - M|`` (rounding level).
    cond_T : float
        Condition number of ``T``.
    score : float
        Sum of the asymptotic state-width bound used to choose among candidates (inf if not scored).
    tried : dict
        Score of every candidate pole set.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): Hypothesis 6, eqs. (14), (31).
    """

    K: FloatArray
    T: FloatArray
    S: FloatArray
    N: FloatArray
    L: FloatArray
    M: FloatArray
    poles: NDArray[np.complex128]
    J: FloatArray
    metzler_check: float
    form_residual: float
    cond_T: float
    score: float = float("inf")
    tried: dict[str, float] = field(default_factory=dict)


def _state_and_output(A: ArrayLike, C: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``A`` and ``C`` as float matrices, ``C`` checked to have as many columns as ``A`` has rows."""
    a = as_matrix("A", A)
    return a, as_matrix("C", C, (None, a.shape[0]))


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


@shared_docs
def uio_decoupling(A: ArrayLike, C: ArrayLike, D: ArrayLike, W: ArrayLike | None = None) -> UIODecoupling:
    r"""Decoupling matrices ``E``, ``P`` that remove the unknown input from the error, their conditions checked.

    Parameters
    ----------
    %(state_output)s
    D : array_like, shape (n, q)
        Unknown-input matrix.
    W : array_like, shape (n, p), optional
        Free parameter ``W`` of ``E`` (default 0, as in the paper's example).

    Returns
    -------
    UIODecoupling

    Raises
    ------
    AssumptionError
        The unknown input is not visible in the outputs (rank(CD) ≠ rank(D), rank(D) ≠ q, or q > p) or the decoupled
        model is not usable (I_p + CW singular, or (PA, C) not detectable).

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): eqs. (11), (24)–(25); Hypotheses 4 (ranks) and 5
    (``I_p + CW`` nonsingular, ``(PA, C)`` detectable).
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
            f"D: the unknown inputs cannot be decoupled: expected q ≤ p (no more than outputs), got q = {q} > p = {p}"
        )
    if rank_d != q:
        raise AssumptionError(
            f"D: expected independent unknown-input directions, rank(D) = q = {q}, got rank(D) = {rank_d}"
        )
    if rank_cd != rank_d:
        raise AssumptionError(
            f"C, D: the outputs do not see every unknown input (rank(CD) = {rank_cd} but rank(D) = {rank_d}): "
            "the unknown inputs cannot be decoupled"
        )
    m0 = np.asarray(np.linalg.pinv(cd), dtype=float)
    e = -d @ m0 + w @ (np.eye(p) - cd @ m0)
    if _rank(np.eye(p) + c @ w) < p:
        raise AssumptionError(
            "W: expected I_p + C W nonsingular (the decoupled outputs must stay independent), got a singular matrix"
        )
    pmat = np.eye(n) + e @ c
    pa = pmat @ a
    bad = _undetectable_modes(pa, c)
    if bad:
        raise AssumptionError(
            "the state, decoupled from the unknown inputs, is not detectable: "
            f"(PA, C) has unobservable modes with Re ≥ 0 at {bad}"
        )
    residual = float(np.abs(pmat @ d).max()) if d.size else 0.0
    scale = max(1.0, float(np.abs(d).max()) * max(1.0, float(np.abs(e @ c).max())))
    if residual > 1e-10 * scale:
        raise DesignError(f"uio_decoupling: expected P D = 0, got max |P D| = {residual:.3g} (ill-conditioned CD)")
    return UIODecoupling(e, pmat, w, m0, rank_cd, rank_d, _observability_margin(pa, c), residual)


def uio_constraint_matrices(A: ArrayLike, C: ArrayLike, D: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    r"""The matrices of the compact constraint ``[N K E] Σ = Θ`` of the decoupling.

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
        The paper's left inverse; ``Sigma_pinv @ Sigma = I`` when the unknown input is visible in the outputs.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): eqs. (23)–(24); Hypothesis 4.
    """
    a, c = _state_and_output(A, C)
    n = a.shape[0]
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


_SQRT3 = float(np.sqrt(3.0))


def _pair_spectrum(poles: NDArray[np.complex128], scale: float) -> tuple[FloatArray, list[complex]]:
    """Split a conjugate-closed spectrum into its real poles and one member (Im > 0) of each pair."""
    tol = 1e-9 * scale
    real = np.sort(poles[np.abs(poles.imag) <= tol].real)[::-1]
    upper = sorted((complex(v) for v in poles[poles.imag > tol]), key=lambda v: (v.real, v.imag), reverse=True)
    lower = poles[poles.imag < -tol]
    if lower.size != len(upper) or (
        upper and np.max(np.abs(np.sort_complex(np.conj(lower)) - np.sort_complex(np.array(upper)))) > tol
    ):
        raise DesignError(f"poles: expected a set closed under complex conjugation, got {poles}")
    return np.asarray(real, dtype=float), upper


def metzler_block_form(poles: ArrayLike) -> FloatArray:
    r"""A block-diagonal Metzler matrix with the given spectrum (the cooperative error form we integrate).

    Real poles are 1×1 blocks. A 2×2 Metzler matrix has real eigenvalues, so each complex pair
    :math:`\sigma \pm i\omega` (:math:`\omega > 0`) shares a 3×3 cyclic block with a real pole :math:`r`:

    .. math:: M_3 = c_0 I + c_1 \Pi + c_2 \Pi^2, \qquad \Pi = \begin{bmatrix} 0&1&0\\0&0&1\\1&0&0
              \end{bmatrix}, \quad c_1 + c_2 = \tfrac23(r - \sigma), \quad c_1 - c_2 = \tfrac{2}{\sqrt3}\omega,
              \quad c_0 = r - c_1 - c_2,

    whose eigenvalues are :math:`c_0 + c_1\zeta^j + c_2\zeta^{2j}` (:math:`\zeta = e^{2\pi i/3}`), i.e.
    :math:`r` and :math:`\sigma \pm i\omega`. It is Metzler iff :math:`c_1, c_2 \ge 0`, i.e.
    :math:`r \ge \sigma + \sqrt3\,\omega` (the pair lies in the 60° sector left of :math:`r`; the
    spectrum of any 3×3 Metzler matrix with a complex pair obeys this bound). Pairs are matched to real
    poles greedily (each pair, least demanding first, takes the smallest real pole that suffices), which
    finds a matching whenever one exists.

    Parameters
    ----------
    poles : array_like, shape (n,)
        Closed-loop poles, real or in conjugate pairs, repetitions allowed.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Blocks in the order: 3×3 blocks (one per pair), then the remaining real poles, descending.

    Raises
    ------
    DesignError
        The set is not conjugate-closed, or a complex pair finds no real pole ``r ≥ σ + √3 ω``.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): the form of Hypothesis 6.
    """
    pl = np.asarray(poles, dtype=complex).ravel()
    if pl.size == 0 or not np.all(np.isfinite(pl)):
        raise DesignError(f"poles: expected finite poles, got {pl}")
    real, upper = _pair_spectrum(pl, max(1.0, float(np.abs(pl).max())))
    free = sorted(real.tolist())  # ascending
    blocks: list[FloatArray] = []
    cyclic = np.roll(np.eye(3), 1, axis=1)
    for pair in sorted(upper, key=lambda v: v.real + _SQRT3 * v.imag):
        need = pair.real + _SQRT3 * pair.imag
        fits = [r for r in free if r >= need]
        if not fits:
            raise DesignError(
                f"poles: the complex pair {pair.real:.4g} ± {pair.imag:.4g}i needs a real pole r ≥ σ + √3·ω = "
                f"{need:.4g} to share a 3×3 Metzler block (a Metzler matrix has no other form for it); "
                f"free real poles: {free}"
            )
        r = fits[0]
        free.remove(r)
        c_sum, c_diff = 2.0 * (r - pair.real) / 3.0, 2.0 * pair.imag / _SQRT3
        c1, c2 = 0.5 * (c_sum + c_diff), 0.5 * (c_sum - c_diff)
        blocks.append((r - c_sum) * np.eye(3) + c1 * cyclic + c2 * cyclic @ cyclic)
    blocks.extend(np.array([[r]]) for r in sorted(free, reverse=True))
    n = pl.size
    out = np.zeros((n, n))
    i = 0
    for blk in blocks:
        k = blk.shape[0]
        out[i : i + k, i : i + k] = np.maximum(blk, 0.0) * ~np.eye(k, dtype=bool) + np.diag(np.diag(blk))
        i += k
    return out


def _similarity_to(nmat: FloatArray, target: FloatArray) -> FloatArray:
    """A real ``T`` with ``T N T⁻¹ = M`` for diagonalisable ``N``, ``M`` with one spectrum: ``T = U V⁻¹``."""
    n = nmat.shape[0]
    vals, vecs = np.linalg.eig(nmat)
    tvals, tvecs = np.linalg.eig(target)
    vecs, tvecs = canonical_eigenvectors(vecs), canonical_eigenvectors(tvecs)
    order = np.empty(n, dtype=int)
    unused = list(range(n))
    for j, lam in enumerate(tvals):  # match each target eigenvalue to the nearest unused one of N
        k = min(unused, key=lambda i: abs(vals[i] - lam))
        order[j] = k
        unused.remove(k)
    scale = max(1.0, float(np.abs(vals).max()))
    if np.max(np.abs(vals[order] - tvals)) > 1e-6 * scale:
        raise DesignError(f"PA - KC has eigenvalues {np.sort_complex(vals)}, expected {np.sort_complex(tvals)}")
    t = tvecs @ np.linalg.inv(vecs[:, order])
    if np.abs(t.imag).max() > 1e-8 * np.abs(t).max():
        raise DesignError("PA - KC: its complex eigenvectors do not pair with the target form (not diagonalisable)")
    return np.asarray(t.real, dtype=float)


def _coordinates(
    pa: FloatArray, c: FloatArray, e: FloatArray, k: FloatArray, t: FloatArray | None, poles: ArrayLike | None = None
) -> UIOCoordinates:
    """Coordinates for gain ``k``: given ``t``, or ``T = U V⁻¹`` onto :func:`metzler_block_form`."""
    n = pa.shape[0]
    nmat = pa - k @ c
    mask = ~np.eye(n, dtype=bool)
    if t is None:
        target = metzler_block_form(np.linalg.eigvals(nmat) if poles is None else poles)
        t = _similarity_to(nmat, target)
        s = np.asarray(np.linalg.inv(t), dtype=float)
        j = t @ nmat @ s
    else:
        s = np.asarray(np.linalg.inv(t), dtype=float)
        j = t @ nmat @ s
        target = np.where(mask, np.maximum(j, 0.0), j)
    eig = np.linalg.eigvals(target)
    return UIOCoordinates(
        K=k,
        T=t,
        S=s,
        N=nmat,
        L=k - nmat @ e,
        M=target,
        poles=np.asarray(eig[np.lexsort((-eig.imag, -eig.real))], dtype=complex),
        J=j,
        metzler_check=float(j[mask].min()) if n > 1 else 0.0,
        form_residual=float(np.abs(j - target).max()),
        cond_T=float(np.linalg.cond(t)),
    )


def uio_pole_candidates(n: int) -> dict[str, NDArray[np.complex128]]:
    """Pole sets tried by :func:`design_uio_coordinates`.

    Real distinct sets ``-a·(1 … n)`` and ``-a·1.6^i``, and, for ``n ≥ 3``, sets with one complex pair
    ``-a(2 ± 0.5i)`` sharing a 3×3 Metzler block with the pole ``-a`` (the rest ``-a(3 … n-1)``).

    Parameters
    ----------
    n : int
        Number of states.

    Returns
    -------
    dict of str to numpy.ndarray
        Pole sets by name.
    """
    found: dict[str, NDArray[np.complex128]] = {}
    for scale in (0.5, 1.0, 2.0, 3.0):
        found[f"linear x{scale:g}"] = np.asarray(-scale * np.arange(1, n + 1), dtype=complex)
        found[f"geometric x{scale:g}"] = np.asarray(-scale * 1.6 ** np.arange(n), dtype=complex)
        if n >= 3:
            pair = np.concatenate([[1.0, 2 + 0.5j, 2 - 0.5j], np.arange(3, n)])
            found[f"complex pair x{scale:g}"] = np.asarray(-scale * pair, dtype=complex)
    return found


def asymptotic_state_width(
    decoupling: UIODecoupling, coords: UIOCoordinates, omega_radius: FloatArray, delta_radius: FloatArray
) -> FloatArray:
    r"""Asymptotic width of the state bounds (the aircraft UIO paper, eqs. (30), (34), for the exactly integrated
    observer).

    In coordinates :math:`w = T(x + E\psi)` the bounds obey
    :math:`\dot{\overline w} - \dot{\underline w} = M(\overline w - \underline w)
    + 2|TL|\bar\delta + 2|TP|\bar\omega` with :math:`M` Metzler and Hurwitz (so :math:`-M^{-1} \ge 0`),
    so :math:`\rho_w = -M^{-1}(2|TL|\bar\delta + 2|TP|\bar\omega)` and
    :math:`\rho_x = |T^{-1}|\rho_w + 2|E|\bar\delta`.

    Parameters
    ----------
    decoupling : UIODecoupling
        ``E`` and ``P``.
    coords : UIOCoordinates
        ``T``, ``L`` and the Metzler form ``M``.
    omega_radius : numpy.ndarray, shape (n,)
        Radius of the state-noise box (after its input matrix).
    delta_radius : numpy.ndarray, shape (p,)
        Radius of the measurement-noise box.

    Returns
    -------
    numpy.ndarray, shape (n,)
    """
    forcing = 2 * np.abs(coords.T @ coords.L) @ delta_radius + 2 * np.abs(coords.T @ decoupling.P) @ omega_radius
    rho_w = np.linalg.solve(-coords.M, forcing)
    return np.asarray(np.abs(coords.S) @ rho_w + 2 * np.abs(decoupling.E) @ delta_radius)


@shared_docs
def check_cooperative(
    A: ArrayLike, C: ArrayLike, decoupling: UIODecoupling, K: ArrayLike, T: ArrayLike | None = None
) -> UIOCoordinates:
    """Check that a given gain ``K`` (and coordinates ``T``) make the error cooperative and stable.

    Without ``T`` the coordinates map ``PA - KC`` onto its :func:`metzler_block_form` (diagonal for real
    poles, 3×3 cyclic blocks for complex pairs); ``PA - KC`` must then be diagonalisable.

    Parameters
    ----------
    %(uio_decoupled)s
    K : array_like, shape (n, p)
        Output-injection gain.
    T : array_like, shape (n, n), optional
        Coordinate change; default ``T = U V⁻¹`` onto the block form.

    Returns
    -------
    UIOCoordinates

    Raises
    ------
    AssumptionError
        ``T (PA - KC) T⁻¹`` is not Metzler (a negative off-diagonal entry beyond rounding) or not
        Hurwitz, ``T`` is singular, or no Metzler block form exists for the spectrum.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): Hypothesis 6.
    """
    a, c = _state_and_output(A, C)
    n = a.shape[0]
    k = as_matrix("K", K, (n, c.shape[0]))
    t = None if T is None else as_matrix("T", T, (n, n))
    if t is not None and np.linalg.cond(t) > 1e12:
        raise AssumptionError(f"T: expected an invertible change of coordinates, got cond(T) = {np.linalg.cond(t):.3g}")
    try:
        coords = _coordinates(decoupling.P @ a, c, decoupling.E, k, t)
    except DesignError as exc:
        raise AssumptionError(f"no coordinates make the observer error cooperative: {exc}") from exc
    scale = max(1.0, float(np.abs(coords.J).max()))
    if coords.metzler_check < -_DIAGONAL_TOL * scale:
        raise AssumptionError(
            "K, T: the error dynamics are not cooperative: expected T (PA - KC) T⁻¹ Metzler, "
            f"got smallest off-diagonal entry {coords.metzler_check:.4g}"
        )
    top = float(np.max(coords.poles.real))
    if top >= 0:
        raise AssumptionError(
            "K, T: the observer error does not decay: expected T (PA - KC) T⁻¹ Hurwitz, "
            f"got an eigenvalue with real part {top:.4g}"
        )
    if coords.form_residual > _DIAGONAL_TOL * scale:
        raise AssumptionError(
            "K, T: the error dynamics are not cooperative: T (PA - KC) T⁻¹ departs from its Metzler form "
            f"by {coords.form_residual:.3g}"
        )
    return coords


def _placed(
    model: FloatArray,
    pa: FloatArray,
    c: FloatArray,
    decoupling: UIODecoupling,
    poles: NDArray[np.complex128],
    omega_radius: FloatArray,
    delta_radius: FloatArray,
    failures: dict[str, str],
    name: str,
) -> UIOCoordinates | None:
    """Coordinates of the gain that places ``poles`` on ``model`` (``PA`` or a jittered copy), scored on ``PA``;
    None, with the reason in ``failures[name]``, when the placement or the checks fail."""
    placed = poles.real if np.all(poles.imag == 0) else poles
    try:
        k = np.asarray(place_poles(model.T, c.T, placed).gain_matrix.T).real
        coords = _coordinates(pa, c, decoupling.E, k, None, poles)
    except (ValueError, np.linalg.LinAlgError, DesignError) as exc:
        failures[name] = str(exc).splitlines()[0]
        return None
    scale = max(1.0, float(np.abs(coords.J).max()))
    if not (coords.cond_T < 1e6 and coords.form_residual <= _DIAGONAL_TOL * scale and np.all(coords.poles.real < 0)):
        failures[name] = f"cond(T) = {coords.cond_T:.3g}, |T N T⁻¹ - M| = {coords.form_residual:.3g}"
        return None
    score = float(np.sum(asymptotic_state_width(decoupling, coords, omega_radius, delta_radius)))
    return UIOCoordinates(**{**coords.__dict__, "score": score})


@shared_docs
def design_uio_coordinates(
    A: ArrayLike,
    C: ArrayLike,
    decoupling: UIODecoupling,
    omega_radius: ArrayLike,
    delta_radius: ArrayLike,
    poles: ArrayLike | None = None,
) -> UIOCoordinates:
    """Gain ``K`` and coordinates ``T`` of a cooperative, stable error with the smallest state-width bound.

    Each candidate places its poles on ``PA - KC`` (``scipy.signal.place_poles``; real, repeated up to
    ``p`` times, or complex pairs; the two best sets again on copies of ``PA`` jittered at 1e-13, because the
    placement branches on rounding when ``PA`` is defective, so that every machine tries the same branches) and
    maps it onto
    :func:`metzler_block_form` by ``T = U V⁻¹``; the candidate with the smallest ``sum(ρ_x)``
    (:func:`asymptotic_state_width`) wins. Every result is checked after the design: the placed spectrum,
    ``T N T⁻¹`` equal to the Metzler form to rounding, Hurwitz, ``cond(T) < 1e6``.

    Parameters
    ----------
    %(uio_decoupled)s
    omega_radius : array_like, shape (n,)
        Radius of the state-noise box, used to score candidates.
    delta_radius : array_like, shape (p,)
        Radius of the measurement-noise box.
    poles : array_like, shape (n,), optional
        Use these poles instead of searching: negative real parts, complex ones in conjugate pairs
        (each pair ``σ ± iω`` needs a free real pole ``r ≥ σ + √3 ω``, see :func:`metzler_block_form`).

    Returns
    -------
    UIOCoordinates

    Raises
    ------
    DesignError
        No candidate passes the checks, or the given poles are not admissible.

    References
    ----------
    The aircraft UIO paper (:mod:`intervalobs.references`): Hypothesis 6.
    """
    a, c = _state_and_output(A, C)
    n = a.shape[0]
    om = as_vector("omega_radius", omega_radius, n)
    de = as_vector("delta_radius", delta_radius, c.shape[0])
    pa = decoupling.P @ a
    if poles is not None:
        pl = np.asarray(poles, dtype=complex).ravel()
        if pl.size != n or not np.all(np.isfinite(pl)) or np.any(pl.real >= 0):
            raise DesignError(f"poles: expected {n} poles with negative real parts, got {pl}")
        metzler_block_form(pl)  # raises with the reason when no Metzler form exists
        candidates = {"given": pl}
    else:
        candidates = uio_pole_candidates(n)
    tried: dict[str, float] = {}
    failures: dict[str, str] = {}
    pattern = np.random.default_rng(0).standard_normal((_PLACEMENT_TRIALS, *pa.shape))
    jittered = [pa * (1.0 + _PLACEMENT_JITTER * d) for d in pattern]
    scored: dict[str, UIOCoordinates] = {}
    for name, pl in candidates.items():
        found = _placed(pa, pa, c, decoupling, pl, om, de, failures, name)
        tried[name] = float("inf") if found is None else found.score
        if found is not None:
            scored[name] = found
    for name in sorted(scored, key=lambda key: scored[key].score)[:_REFINED_SETS]:
        for model in jittered:
            found = _placed(model, pa, c, decoupling, candidates[name], om, de, failures, name)
            if found is not None and found.score < scored[name].score:
                scored[name] = found
                tried[name] = found.score
    best = min(scored.values(), key=lambda coords: coords.score, default=None)
    if best is None:
        raise DesignError(
            f"design_uio_coordinates: no pole set gave well-conditioned Metzler coordinates ({failures}); "
            "give other poles"
        )
    return UIOCoordinates(**{**best.__dict__, "tried": tried})
