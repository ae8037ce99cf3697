r"""Framer gains: an observer gain :math:`L` and coordinates :math:`z = Tx` whose width system is stable.

For the sampled model :math:`x^+ \in (\Phi \pm \delta\Phi)x + \dots` and the observer
:math:`\hat x^+ = \Phi\hat x + L(y - C\hat x) + \dots`, the box radius in coordinates :math:`z = Tx`
obeys :math:`r^+ \le N r + b` with

.. math:: N = |T(\Phi - LC)T^{-1}| + |T|\,\delta\Phi\,|T^{-1}|, \qquad
          b = |T|\,(r_w + |LF|\,v_r) + |T|\,\delta\Phi\,|\hat x|.

(The midpoint of the box is an ordinary Luenberger estimate, so the :math:`\delta\Phi` term enters
:math:`N` once, without a factor 2.) The framer is stable iff :math:`\rho(N) < 1`. For a fixed
:math:`T` and a positive weight :math:`p`, the conditions :math:`G \ge \pm T(\Phi - LC)T^{-1}`,
:math:`(G + K)p \le (1 - h\sigma)p` are linear in :math:`(L, G, \sigma)`; alternating the LP with the
Perron vector of the achieved :math:`N` drives :math:`\rho(N)` down. A second LP, at a fixed rate,
minimises the noise gain :math:`\beta` with :math:`b \le \beta p`, which bounds the steady-state radius by
:math:`\beta p / (h\sigma)`. Coordinates are searched over a few choices (identity, the real modal
basis, eigenvectors of pole-placed loops with spread real poles), as in the references of the aircraft UIO
paper and the sampled-output high-gain paper; the best steady-state bound wins, and the result is verified by an
eigenvalue computation.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import sparse
from scipy.optimize import linprog
from scipy.signal import place_poles

from .._docstrings import shared_docs
from ..errors import DesignError
from ..lp.certified import LP_OPTIONS
from ..systems.sampling import SampledModel

__all__ = [
    "FramerDesign",
    "coordinate_candidates",
    "design_framer",
    "framer_matrices",
    "is_detectable",
    "real_modal_basis",
    "real_modal_form",
    "unstable_vertex",
]

FloatArray = NDArray[np.float64]

_EIGENVALUE_TOLERANCE = 1e-12
"""Tolerance of the eigenvalue classifications (on the unit circle or outside; real), relative: it only
decides which test or basis is tried, and every design result is verified by eigenvalues."""

_VERTEX_ASCENTS = 8
"""Eigenvalue-following steps of :func:`unstable_vertex` from each eigenvalue (a search, not a bound)."""

_GAIN_LIMIT = 1e6
_PERRON_ITERATIONS = 4
_RATE_FRACTIONS = (0.25, 0.5, 0.8)
_POLE_SCALES = (0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
_POLE_SPREADS = (1.3, 2.0, 3.0)
_PLACED_KEPT = 3
_PRUNE_MARGIN = 1e-9
"""Relative margin by which a candidate's noise floor must exceed the best sum for its LPs to be skipped."""


@dataclass(frozen=True)
class FramerDesign:
    """A verified framer design.

    Parameters
    ----------
    L : numpy.ndarray, shape (n, p)
        Observer gain (of the sampled model).
    T : numpy.ndarray, shape (n, n)
        Coordinate change ``z = T x``.
    spectral_radius : float
        ``ρ(N)`` of the width system, verified < 1 by eigenvalues.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state bound of the x-radius for zero state magnitude (noise only).
    coordinates : str
        Which candidate coordinates won.
    tried : dict of str to float
        Smallest sum of steady-state radius bounds reached in each candidate coordinates (``inf``: no gain,
        or skipped because no gain in those coordinates can beat the best sum found before them).
    """

    L: FloatArray
    T: FloatArray
    spectral_radius: float
    steady_radius: FloatArray
    coordinates: str
    tried: dict[str, float] = field(default_factory=dict)


def framer_matrices(model: SampledModel, C: FloatArray, L: FloatArray, T: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The width-system matrix ``N`` and the z-coordinate observer matrix ``T(Φ - LC)T⁻¹``.

    Parameters
    ----------
    model : SampledModel
        Sampled interval model (``Φ``, ``δΦ``).
    C : numpy.ndarray, shape (p, n)
        Output matrix.
    L : numpy.ndarray, shape (n, p)
        Observer gain.
    T : numpy.ndarray, shape (n, n)
        Invertible coordinate change ``z = T x``.

    Returns
    -------
    N : numpy.ndarray, shape (n, n)
        ``|T(Φ - LC)T⁻¹| + |T| δΦ |T⁻¹|``; the framer is stable iff ``ρ(N) < 1``.
    M : numpy.ndarray, shape (n, n)
        ``T(Φ - LC)T⁻¹``.
    """
    t_inv = np.linalg.inv(T)
    m_z = T @ (model.Phi - L @ C) @ t_inv
    return np.abs(m_z) + np.abs(T) @ model.dPhi @ np.abs(t_inv), m_z


def is_detectable(model: SampledModel, C: FloatArray) -> bool:
    """PBH test: every eigenvalue of ``Φ`` with modulus ≥ 1 is observable through ``C``.

    Parameters
    ----------
    model : SampledModel
        Sampled model (its ``Φ`` is tested).
    C : numpy.ndarray, shape (p, n)
        Output matrix.

    Returns
    -------
    bool
        True when some gain ``L`` makes ``Φ - LC`` Schur stable.
    """
    n = model.Phi.shape[0]
    for lam in np.linalg.eigvals(model.Phi):
        if abs(lam) >= 1 - _EIGENVALUE_TOLERANCE:
            pbh = np.vstack([lam * np.eye(n) - model.Phi, C.astype(complex)])
            if np.linalg.matrix_rank(pbh, tol=1e-9 * max(1.0, np.abs(pbh).max())) < n:
                return False
    return True


def unstable_vertex(
    a: FloatArray, lower: FloatArray, upper: FloatArray, continuous: bool
) -> tuple[FloatArray, float] | None:
    """A vertex of the interval matrix ``[A + lower, A + upper]`` that is not stable, if a search finds one.

    From each eigenvalue ``λ`` of the midpoint matrix (right and left eigenvectors ``v``, ``w``, with
    ``w v = 1``) the vertex that moves ``λ`` furthest to first order (``ΔA_jl`` at the end of its
    interval given by the sign of ``Re(ū w_j v_l)``, ``u = 1`` in continuous time and ``λ/|λ|`` in
    discrete time) is taken; the eigenvalue that has moved most is followed in the same way, a few
    times; the least stable vertex met is returned. A search, not a proof: ``None`` does not certify a
    robustly stable box; a vertex that it returns is a matrix of the box whose instability is computed.

    Parameters
    ----------
    a : numpy.ndarray, shape (n, n)
        Nominal matrix.
    lower, upper : numpy.ndarray, shape (n, n)
        Elementwise bounds of ``ΔA``.
    continuous : bool
        Stability in the Hurwitz sense (spectral abscissa ``< 0``) or the Schur sense (spectral radius ``< 1``).

    Returns
    -------
    (numpy.ndarray, float) or None
        ``A + ΔA`` at the vertex found and its spectral abscissa (continuous) or spectral radius
        (discrete), when that is ``≥ 0`` (resp. ``≥ 1``); otherwise None.
    """
    centre, radius = a + 0.5 * (lower + upper), 0.5 * (upper - lower)
    limit = 0.0 if continuous else 1.0

    def growth(vals: NDArray[Any]) -> FloatArray:
        return np.asarray(vals.real if continuous else np.abs(vals))

    worst: tuple[FloatArray, float] | None = None
    for start in range(centre.shape[0]):
        matrix, index = centre, start
        for _ in range(_VERTEX_ASCENTS):
            vals, vecs = np.linalg.eig(matrix)
            lam = vals[index]
            phase = 1.0 if continuous or lam == 0 else np.conj(lam) / abs(lam)
            slope = np.real(phase * np.outer(np.linalg.inv(vecs)[index], vecs[:, index]))
            vertex = centre + radius * np.where(slope >= 0, 1.0, -1.0)
            moved = growth(np.linalg.eigvals(vertex))
            if moved.max() >= limit and (worst is None or moved.max() > worst[1]):
                worst = vertex, float(moved.max())
            if np.array_equal(vertex, matrix):
                break
            matrix, index = vertex, int(np.argmax(moved))
    return worst


def real_modal_basis(a: FloatArray) -> FloatArray | None:
    """``T = V⁻¹`` for the real modal basis ``V`` of ``a`` (real parts and imaginary parts of its eigenvectors).

    Parameters
    ----------
    a : numpy.ndarray, shape (n, n)
        Matrix to block-diagonalise: ``T a T⁻¹`` is block diagonal with 1×1 and 2×2 blocks.

    Returns
    -------
    numpy.ndarray or None
        ``T``, or None when ``cond(V) > 1e8`` (a defective or nearly defective ``a``).
    """
    form = real_modal_form(a)
    return None if form is None else form[0]


def real_modal_form(a: FloatArray) -> tuple[FloatArray, tuple[int, ...]] | None:
    """:func:`real_modal_basis` and the sizes of the diagonal blocks of ``T a T⁻¹``, in order.

    Parameters
    ----------
    a : numpy.ndarray, shape (n, n)
        Matrix to block-diagonalise.

    Returns
    -------
    (numpy.ndarray, tuple of int) or None
        ``T`` and the block sizes (1 for a real eigenvalue, 2 for a complex pair), or None when
        ``cond(V) > 1e8``.
    """
    vals, vecs = np.linalg.eig(a)
    columns: list[FloatArray] = []
    sizes: list[int] = []
    used = np.zeros(vals.size, dtype=bool)
    for i in np.argsort(-vals.real):
        if used[i]:
            continue
        used[i] = True
        if abs(vals[i].imag) < _EIGENVALUE_TOLERANCE * max(1.0, abs(vals[i])):
            columns.append(vecs[:, i].real)
            sizes.append(1)
        else:
            j = int(np.argmin(np.abs(vals - vals[i].conj()) + used * 1e300))
            used[j] = True
            columns += [vecs[:, i].real, vecs[:, i].imag]
            sizes.append(2)
    v = np.column_stack(columns)
    if np.linalg.cond(v) > 1e8:
        return None
    return np.asarray(np.linalg.inv(v)), tuple(sizes)


def coordinate_candidates(
    model: SampledModel, C: FloatArray, F: FloatArray, v_radius: FloatArray
) -> dict[str, FloatArray]:
    """Coordinate changes ``T`` to try: identity, real modal basis of Φ, pole-placed loops.

    Pole-placed candidates place the eigenvalues of ``Φ - L₀C`` at real, distinct values spread
    geometrically (continuous-time rates ``a·s·r^i`` for a grid of scales ``s`` and spreads ``r``, mapped
    through ``exp(-·h)``) and take ``T = V⁻¹``, which makes ``T(Φ - L₀C)T⁻¹`` diagonal; the
    ``_PLACED_KEPT`` with the smallest steady-state radius bound at ``L₀`` are kept.

    Parameters
    ----------
    model : SampledModel
        Sampled interval model.
    C : numpy.ndarray, shape (p, n)
        Output matrix.
    F : numpy.ndarray, shape (p, nv)
        Measurement-noise matrix.
    v_radius : numpy.ndarray, shape (nv,)
        Radius of the measurement-noise box.

    Returns
    -------
    dict of str to numpy.ndarray
        Named coordinate changes ``T``, shape (n, n), ``"identity"`` first.
    """
    n = model.Phi.shape[0]
    found: dict[str, FloatArray] = {"identity": np.eye(n)}
    modal = real_modal_basis(model.Phi)
    if modal is not None:
        found["modal"] = modal
    rates = np.abs(np.log(np.abs(np.linalg.eigvals(model.Phi)) + 1e-300)) / model.h
    base = max(float(np.max(rates)), 1.0 if model.h < 1.0 else 0.5)
    placed: list[tuple[float, str, FloatArray]] = []
    for scale in _POLE_SCALES:
        for spread in _POLE_SPREADS:
            if model.h == 1.0:  # discrete time: real poles spread inside (0, 1)
                poles = np.clip(np.exp(-scale * spread ** np.arange(n) / 4), 1e-3, 0.95)
            else:
                poles = np.exp(-base * scale * spread ** np.arange(n) * model.h)
            try:
                with warnings.catch_warnings():  # place_poles warns when its optional refinement stalls
                    warnings.simplefilter("ignore", UserWarning)
                    gain = place_poles(model.Phi.T, C.T, poles).gain_matrix.T
            except (ValueError, np.linalg.LinAlgError):
                continue
            vals, vecs = np.linalg.eig(model.Phi - gain @ C)
            if np.max(np.abs(vals.imag)) > 1e-9 or np.linalg.cond(vecs.real) > 1e8:
                continue
            t_mat = np.asarray(np.linalg.inv(vecs.real))
            rho, radius = _steady_radius(model, C, F, v_radius, gain, t_mat)
            score = float(np.sum(radius)) if rho < 1 else np.inf
            placed.append((score, f"placed-{scale:g}x{spread:g}", t_mat))
    placed.sort(key=lambda item: item[0])
    for _, name, t_mat in placed[:_PLACED_KEPT]:
        found[name] = t_mat
    return found


def _solve_lp(
    model: SampledModel,
    C: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    T: FloatArray,
    p: FloatArray,
    rate: float | None,
) -> tuple[FloatArray, float] | None:
    """One LP: maximise the rate (``rate=None``) or minimise the noise gain at a fixed rate."""
    ny, n = C.shape
    t_inv = np.linalg.inv(T)
    h = model.h
    k_mat = np.abs(T) @ model.dPhi @ np.abs(t_inv)
    phi_z = T @ model.Phi @ t_inv
    c_z = C @ t_inv
    nl, ng = n * ny, n * n
    nh = n * F.shape[1]
    # variables: vec(L) (row-major), vec(G), vec(H) (H >= |L F|), scalar s
    nvar = nl + ng + nh + 1
    # The four blocks of n² and n·nv rows are stored sparse (dense, they are O(n⁴) numbers at n² + 2np columns).
    rows: list[sparse.csr_array | FloatArray] = []
    rhs: list[float] = []
    lc = sparse.kron(sparse.csr_array(T), sparse.csr_array(c_z.T), format="csr")  # vec(T L C T^-1) = lc @ vec(L)
    for sign in (1.0, -1.0):  # sign*(phi_z - T L C T^-1) <= G
        rows.append(sparse.hstack([-sign * lc, -sparse.eye_array(ng), sparse.csr_array((ng, nh + 1))], format="csr"))
        rhs.extend(-sign * phi_z.ravel())
    lf = sparse.kron(sparse.eye_array(n), sparse.csr_array(F.T), format="csr")  # vec(L F) = lf @ vec(L)
    for sign in (1.0, -1.0):
        zeros = sparse.csr_array((nh, ng))
        rows.append(sparse.hstack([sign * lf, zeros, -sparse.eye_array(nh), sparse.csr_array((nh, 1))], format="csr"))
        rhs.extend(np.zeros(nh))
    # rate rows, scaled by 1/h: ((G - I) p + K p)/h + s p <= 0   (s = rate when maximised)
    rate_rows = np.zeros((n, nvar))
    for i in range(n):
        rate_rows[i, nl + i * n : nl + (i + 1) * n] = p / h
    constant = ((k_mat - np.eye(n)) @ p) / h
    if rate is None:
        rate_rows[:, -1] = p
        rows.append(rate_rows)
        rhs.extend(-constant)
        cost = np.zeros(nvar)
        cost[-1] = -1.0
    else:
        rows.append(rate_rows)
        rhs.extend(-constant - rate * p)
        # noise gain rows: |T| (r_w + H v_r) <= s p   (s = beta, in units of h)
        gain_rows = np.zeros((n, nvar))
        hv = np.zeros((n, nh))
        for i in range(n):
            hv[i, i * F.shape[1] : (i + 1) * F.shape[1]] = v_radius
        gain_rows[:, nl + ng : nl + ng + nh] = np.abs(T) @ hv / h
        gain_rows[:, -1] = -p
        rows.append(gain_rows)
        rhs.extend(-(np.abs(T) @ model.noise_radius) / h)
        cost = np.zeros(nvar)
        cost[-1] = 1.0
    a_ub = sparse.vstack(rows, format="csc")
    a_ub.eliminate_zeros()  # the same matrix HiGHS gets from the dense one
    scale = _GAIN_LIMIT
    bounds = [(-scale, scale)] * nl + [(0, None)] * (ng + nh) + [(None, 1e6 / h if rate is None else None)]
    res = linprog(cost, A_ub=a_ub, b_ub=np.asarray(rhs), bounds=bounds, method="highs", options=LP_OPTIONS)
    if res.status != 0:
        return None
    return res.x[:nl].reshape(n, ny), float(res.x[-1])


def _perron(nmat: FloatArray) -> FloatArray:
    n = nmat.shape[0]
    vals, vecs = np.linalg.eig(nmat + 1e-9 * np.ones((n, n)))
    v = np.abs(vecs[:, int(np.argmax(vals.real))].real)
    return np.asarray(np.maximum(v / v.max(), 1e-6))


def _steady_radius(
    model: SampledModel, C: FloatArray, F: FloatArray, v_radius: FloatArray, L: FloatArray, T: FloatArray
) -> tuple[float, FloatArray]:
    nmat, _ = framer_matrices(model, C, L, T)
    rho = float(np.max(np.abs(np.linalg.eigvals(nmat))))
    if rho >= 1:
        return rho, np.full(C.shape[1], np.inf)
    b = np.abs(T) @ (model.noise_radius + np.abs(L @ F) @ v_radius)
    z_radius = np.linalg.solve(np.eye(nmat.shape[0]) - nmat, b)
    return rho, np.abs(np.linalg.inv(T)) @ z_radius


def _noise_floor(model: SampledModel, T: FloatArray) -> float:
    """A lower bound of the steady radius sum of every gain in coordinates ``T``: ``Σ |T⁻¹| |T| r_w``.

    The steady z-radius ``(I - N)⁻¹ b`` is at least ``b ≥ |T| r_w`` (``N ≥ 0``, ``|LF| v_r ≥ 0``), so the
    x-radius ``|T⁻¹|(I - N)⁻¹ b`` is at least ``|T⁻¹||T| r_w`` whatever ``L``. A candidate whose floor is
    not below the best sum found (by a relative ``_PRUNE_MARGIN``, far above the rounding of either sum)
    cannot win, and its LPs are skipped: the design is the same, at the cost of the LPs that can win.
    """
    return float(np.sum(np.abs(np.linalg.inv(T)) @ (np.abs(T) @ model.noise_radius)))


@shared_docs
def design_framer(
    model: SampledModel,
    C: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    candidates: dict[str, FloatArray] | None = None,
) -> FramerDesign:
    """Find ``L`` and ``T`` with ``ρ(N) < 1`` and the smallest steady-state radius bound.

    Parameters
    ----------
    %(sampled_model)s
    candidates : dict of str to numpy.ndarray, optional
        Coordinate changes to try (default :func:`coordinate_candidates`).

    Returns
    -------
    FramerDesign

    Raises
    ------
    DesignError
        When the pair (Φ, C) is not detectable, or no candidate gives a stable width system.
    """
    if not is_detectable(model, C):
        raise DesignError("system: the pair (A, C) is not detectable, so no interval observer gain exists")
    candidates = coordinate_candidates(model, C, F, v_radius) if candidates is None else candidates
    best: FramerDesign | None = None
    tried: dict[str, float] = {}
    for name, T in candidates.items():
        if best is not None and _noise_floor(model, T) >= float(np.sum(best.steady_radius)) * (1 + _PRUNE_MARGIN):
            tried[name] = np.inf  # no gain in these coordinates can beat the best (see _noise_floor)
            continue
        p = np.ones(T.shape[0])
        top_rate, gain = -np.inf, None
        for _ in range(_PERRON_ITERATIONS):
            found = _solve_lp(model, C, F, v_radius, T, p, rate=None)
            if found is None:
                break
            if found[1] > top_rate:
                top_rate, gain = found[1], found[0]
            p = _perron(framer_matrices(model, C, found[0], T)[0])
        if gain is None or top_rate <= 0:
            tried[name] = np.inf
            continue
        options = [gain]
        for fraction in _RATE_FRACTIONS:
            tuned = _solve_lp(model, C, F, v_radius, T, p, rate=fraction * top_rate)
            if tuned is not None:
                options.append(tuned[0])
        for L in options:
            rho, radius = _steady_radius(model, C, F, v_radius, L, T)
            score = float(np.sum(radius))
            if rho < 1 and (best is None or score < float(np.sum(best.steady_radius))):
                best = FramerDesign(L, T, rho, radius, name)
            tried[name] = min(tried.get(name, np.inf), score)
    if best is None:
        raise DesignError(
            "IntervalObserver.design: no gain gives a stable width system in any tried coordinates "
            f"({', '.join(candidates)}); reduce the dA bounds or give a gain and coordinates explicitly"
        )
    return FramerDesign(best.L, best.T, best.spectral_radius, best.steady_radius, best.coordinates, tried)
