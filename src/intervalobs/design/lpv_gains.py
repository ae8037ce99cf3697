r"""Design of the LPV interval observer and interval UIO from LMIs (Rotondo et al., Corollaries 3.1 and 4.1).

Coordinates: :math:`C = (\tilde C\ 0)` (9), measured states first. The coordinate matrix is constant,

.. math:: R = \begin{pmatrix} R_{11} & 0 \\ R_{21} & I \end{pmatrix},\qquad
          T = \begin{pmatrix} (I - R_{11})\tilde C^{-1} \\ -R_{21}\tilde C^{-1}\end{pmatrix}
          \quad (TC = I - R,\ (36)).

The paper's (16) has :math:`R_{21} = 0`; the proof of Theorem 3.1 uses only (36) and (39)–(40),
which are solvable for any :math:`R_{21}` (a reduced-order injection: the unmeasured block becomes
:math:`A_{R22} = R_{21}A_{12} + A_{22}`), so a user may pass one. (39)–(40) force the right block
columns of :math:`F` to equal those of :math:`A_R = RA` ((35), (67)); the left block columns are
designed. For the interval UIO, :math:`B_{un}` must be constant and :math:`R` is built so that
:math:`RB_{un} = H = (I_q; 0)` (26): :math:`R_{11} = (B_1\ N)^{-1}` with :math:`N` completing a basis,
:math:`R_{21} = -B_2B_1^\dagger`.

**LMI.** With diagonal :math:`\underline P, \overline P` the change of variables (68)
:math:`W = P\,F_{\text{left}}` makes the Metzler property (64) exact and linear (off-diagonal entries
of :math:`W` nonnegative; the paper's :math:`W + P\Sigma \ge 0` with a "sufficiently large"
:math:`\Sigma` is not a condition on :math:`F`), and (63)/(109) linear in :math:`P, W, \gamma, Q` for
fixed :math:`\varepsilon_1, \varepsilon_2`. For the UIO the eigenvector condition (105)–(106),
:math:`FH = H\Gamma`, is imposed as the linear equality :math:`W_{:,j} = \gamma_j p_j e_j` — the same
set of :math:`F` as the parametrisation (101)–(102), (115)–(116), without :math:`R^{-1}`. The switching
terms of (74) are covered for every pair of subsets :math:`S_1, S_2` of the measured columns
(``eta_and_generator``, read with (95)–(100)). :math:`W` is constant, so
:math:`F(\vartheta)` is defined between grid points: left columns constant, right columns
:math:`A_R(\vartheta)`. Everything is re-checked after the solve on a finer grid: (17)–(18), Metzler,
Hurwitz and the (1,1)/(2,2) blocks of (63)/(74) by eigenvalues.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass
from typing import Any

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, DesignError, DimensionError
from ..interval import inflate
from ..systems.lpv import LPVSystem
from ..validation import as_matrix
from .lmi import solve_lmi
from .lpv import (
    BoundednessCertificate,
    _active_switchable,
    _block_max_eig,
    _subset_masks,
    eta_and_generator,
    verify_boundedness,
)

__all__ = ["LPVObserverDesign", "design_lpv_observer", "rotate_bounds", "scheduling_grid"]

FloatArray = NDArray[np.float64]

_STRUCTURE_TOLERANCE = 1e-12
"""Relative tolerance of the structural checks (equal input columns, zero entries of H): decides which
structure is used, not a rounding pad (the design is verified afterwards)."""


def rotate_bounds(r: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Bounds of :math:`R M` for a point matrix :math:`R` and an interval matrix :math:`[M]`.

    .. math:: R^+\underline M - R^-\overline M \le RM \le R^+\overline M - R^-\underline M

    (exact hull per entry: every entry of :math:`RM` is a sum of terms in distinct entries of M).

    Parameters
    ----------
    r : array_like, shape (..., n, n)
        Point matrix.
    lower, upper : array_like, shape (..., n, k)
        Interval matrix.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., n, k)

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): (14), (15), (24).
    """
    rr = np.asarray(r, dtype=float)
    rp, rn = np.maximum(rr, 0.0), np.maximum(-rr, 0.0)
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    return rp @ lo - rn @ hi, rp @ hi - rn @ lo


def scheduling_grid(theta_box: tuple[FloatArray, FloatArray], points: int) -> FloatArray:
    """A regular grid of ``points`` values per scheduling axis (ends included).

    Parameters
    ----------
    theta_box : tuple of numpy.ndarray
        ``(lower, upper)`` of Θ.
    points : int
        Values per axis (≥ 2).

    Returns
    -------
    numpy.ndarray, shape (points**n_theta, n_theta)
    """
    if points < 2:
        raise DimensionError(f"grid: expected at least 2 points per axis, got {points}")
    axes = [np.linspace(lo, hi, points) for lo, hi in zip(*theta_box)]
    return np.array(list(itertools.product(*axes)), dtype=float).reshape(-1, len(axes))


@dataclass(frozen=True)
class LPVObserverDesign:
    r"""Matrices of a designed LPV interval observer / UIO (read-only).

    Attributes
    ----------
    R, T : numpy.ndarray, shapes (n, n), (n, p)
        Coordinates :math:`v = Rx` and :math:`TC = I - R`.
    C_tilde_inv : numpy.ndarray, shape (p, p)
        :math:`\tilde C^{-1}`.
    f_left_lower, f_left_upper : numpy.ndarray, shape (n, p)
        Designed left block columns of :math:`\underline F, \overline F`.
    H : numpy.ndarray or None, shape (n, q)
        :math:`RB_{un}`, the unknown inputs' directions (UIO only).
    gamma_lower, gamma_upper : numpy.ndarray or None, shape (q,)
        Diagonals of :math:`\underline\Gamma, \overline\Gamma` (UIO only).
    certificate : BoundednessCertificate
        The solved boundedness LMI with its fine-grid verification.
    hurwitz_margin : float
        Largest real part of the eigenvalues of :math:`\underline F(\vartheta), \overline F(\vartheta)`
        on the fine grid (negative).
    coarse_points, fine_points : int
        Grid sizes of the solve and of the verification.

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): R, T of (36); F of (66)/(101); H of (26); the boundedness LMI
    (63)/(109).
    """

    R: FloatArray
    T: FloatArray
    C_tilde_inv: FloatArray
    f_left_lower: FloatArray
    f_left_upper: FloatArray
    H: FloatArray | None
    gamma_lower: FloatArray | None
    gamma_upper: FloatArray | None
    certificate: BoundednessCertificate
    hurwitz_margin: float
    coarse_points: int
    fine_points: int

    @property
    def p(self) -> int:
        """Number of measured states (outputs)."""
        return int(self.T.shape[1])

    def f_matrices(self, a_r: ArrayLike) -> tuple[FloatArray, FloatArray]:
        r""":math:`\underline F, \overline F` given :math:`A_R = RA` at points.

        Parameters
        ----------
        a_r : array_like, shape (..., n, n)
            :math:`R A(\vartheta)`.

        Returns
        -------
        F_lower, F_upper : numpy.ndarray, shape (..., n, n)

        References
        ----------
        Rotondo et al. (:mod:`intervalobs.references`): (35), (67).
        """
        ar = np.asarray(a_r, dtype=float)
        p = self.p
        fl, fu = ar.copy(), ar.copy()
        fl[..., :, :p] = self.f_left_lower
        fu[..., :, :p] = self.f_left_upper
        return fl, fu

    def s_matrices(self, system: LPVSystem, theta: ArrayLike) -> tuple[FloatArray, FloatArray]:
        r""":math:`\underline S, \overline S` at scheduling points (for reporting; the sampled
        observer uses the equivalent rate of :math:`v = Rx` directly).

        Parameters
        ----------
        system : LPVSystem
            The designed system.
        theta : array_like, shape (N, n_theta)
            Points.

        Returns
        -------
        S_lower, S_upper : numpy.ndarray, shape (N, n, p)

        References
        ----------
        Rotondo et al. (:mod:`intervalobs.references`): (37)–(42).
        """
        ar = self.R @ system.matrix_at("A", theta)
        out = []
        for f in self.f_matrices(ar):
            s1 = (ar - f)[..., :, : self.p] @ self.C_tilde_inv  # (39)-(40)
            out.append(s1 + f @ self.T)  # (41)-(42)
        return out[0], out[1]


def _partition(system: LPVSystem) -> FloatArray:
    """Check C = (C̃ 0) (9) and return C̃⁻¹."""
    p = system.p
    c = system.C
    if np.any(c[:, p:] != 0.0):
        raise AssumptionError(
            f"C: expected the measured states first, C = (C̃ 0) (reorder the states), got nonzero columns "
            f"{sorted(set(np.nonzero(c[:, p:])[1] + p))}"
        )
    ct = c[:, :p]
    if np.linalg.cond(ct) > 1e12:
        raise AssumptionError(
            f"C: expected the outputs to determine the measured states (an invertible C̃), got condition number "
            f"{np.linalg.cond(ct):.3g}"
        )
    return np.asarray(np.linalg.inv(ct))


def _uio_coordinates(system: LPVSystem, points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """R with R B_un = H = (I_q; 0) (26) for a constant B_un; returns (R, H)."""
    p, n, q = system.p, system.n, system.q
    bu = system.matrix_at("B_un", points)
    if not np.allclose(bu, bu[0], rtol=0.0, atol=_STRUCTURE_TOLERANCE * max(1.0, float(np.abs(bu).max()))):
        raise AssumptionError(
            "B_un: expected unknown-input directions B_un(θ) that do not vary with θ (the decoupling is designed once)"
        )
    b1, b2 = bu[0][:p], bu[0][p:]
    u, _, _ = np.linalg.svd(b1)
    basis = np.hstack([b1, u[:, q:]])
    r11 = np.linalg.inv(basis)
    r21 = -b2 @ np.linalg.pinv(b1)
    r = np.zeros((n, n))
    r[:p, :p], r[p:, :p], r[p:, p:] = r11, r21, np.eye(n - p)
    h = r @ bu[0]
    return r, np.where(np.abs(h) < _STRUCTURE_TOLERANCE, 0.0, h)


def _check_r(r: FloatArray, p: int) -> None:
    n = r.shape[0]
    if np.any(r[:p, p:] != 0.0) or not np.array_equal(r[p:, p:], np.eye(n - p)):
        raise AssumptionError("R: expected the form ((R11, 0), (R21, I)), the identity on the unmeasured states")


def _first_negative(block: FloatArray, points: FloatArray, offset: tuple[int, int]) -> str | None:
    """``"got <value> at entry (i, j), theta = [...]"`` of the first negative entry over the points, or None."""
    if not np.any(block < 0):
        return None
    k, i, j = np.argwhere(block < 0)[0]
    return f"got {block[k, i, j]:.3g} at entry ({i + offset[0]}, {j + offset[1]}), theta = {points[k].tolist()}"


def _structure_check(a_r: FloatArray, points: FloatArray, p: int) -> None:
    """(17) A_R12 ≥ 0 and (18) A_R22 Metzler at every point."""
    found = _first_negative(a_r[:, :p, p:], points, (0, p))
    if found:
        raise DesignError(
            "coordinates R: the unmeasured states must push the measured ones up, expected (RA)[:p, p:] >= 0, "
            f"{found}; choose R (R11) so that R11 A12 >= 0"
        )
    a22 = a_r[:, p:, p:].copy()
    m = a22.shape[-1]
    a22[:, np.arange(m), np.arange(m)] = 0.0
    found = _first_negative(a22, points, (p, p))
    if found:
        raise DesignError(
            f"coordinates R: the unmeasured states must stay ordered, expected (RA)[p:, p:] Metzler, {found}; "
            "choose R21 so that R21 A12 + A22 is Metzler"
        )


def _rotated(system: LPVSystem, r: FloatArray, points: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    a_r = r @ system.matrix_at("A", points)
    bounds = system.bounds_at("dA", points)
    if bounds is None:
        zero = np.zeros_like(a_r)
        return a_r, zero, zero
    lo, hi = rotate_bounds(r, *bounds)
    return a_r, lo, hi


def design_lpv_observer(
    system: LPVSystem,
    uio: bool = False,
    R: ArrayLike | None = None,
    decay: float = 1.0,
    grid: int = 5,
    fine_grid: int = 41,
    eps2: float = 0.01,
    q_scale: float = 1e-3,
    gain_bound: float | None = None,
) -> LPVObserverDesign:
    r"""Design :math:`R, T, \underline F, \overline F` (and :math:`H, \Gamma` for the UIO) from the LMIs.

    The gains make the error system cooperative and its bounds bounded on the whole scheduling box (for
    the UIO with :math:`\underline\Gamma = \overline\Gamma = -\lambda I`, ``decay``). See the module
    docstring for the parametrisation. :math:`\varepsilon_1` is searched over multiples of the
    largest :math:`\eta` on the grid; the candidate with the most negative (1,1) block wins.

    Parameters
    ----------
    system : LPVSystem
        Model with :math:`C = (\tilde C\ 0)` (measured states first).
    uio : bool
        Design the interval UIO (needs ``B_un``, constant).
    R : array_like, shape (n, n), optional
        Coordinates for the observer, of the form ((R11, 0), (R21, I)) (default I). Ignored for the UIO
        (built from :math:`B_{un}`).
    decay : float
        :math:`\lambda` of :math:`\Gamma = -\lambda I` (UIO).
    grid : int
        Values per scheduling axis of the LMI grid.
    fine_grid : int
        Values per scheduling axis of the verification grid.
    eps2 : float
        :math:`\varepsilon_2`, a margin of the boundedness LMI.
    q_scale : float
        :math:`Q = qI`.
    gain_bound : float, optional
        Bound of the entries of the designed columns of F (default 10 (1 + max of the entries of RA)).

    Returns
    -------
    LPVObserverDesign

    Raises
    ------
    AssumptionError
        Outputs not the first states, R not block triangular (module docstring), B_un missing/not constant (UIO).
    DesignError
        Naming the failed condition (coordinates, boundedness LMI, or its check on the fine grid).

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): observer: Corollary 3.1, (61)–(66); UIO: Corollary 4.1,
    (107)–(117), with :math:`\Gamma = -\lambda I` as in Section 5; C of the form (9), R of the form (16), conditions
    (17), (18), the LMIs (63)/(109) and the blocks of (63)/(74); :math:`\varepsilon_2` of (63).
    """
    n, p = system.n, system.p
    ct_inv = _partition(system)
    if not (np.isfinite(decay) and decay > 0):
        raise DimensionError(f"decay: expected a positive λ, got {decay!r}")
    coarse = scheduling_grid(system.theta_box, grid)
    fine = scheduling_grid(system.theta_box, fine_grid)
    r, h_mat, gamma = _design_coordinates(system, uio, R, decay, np.vstack([coarse, fine]))
    t_mat = np.vstack([(np.eye(p) - r[:p, :p]) @ ct_inv, -r[p:, :p] @ ct_inv])
    a_r, dl, du = _rotated(system, r, coarse)
    _structure_check(a_r, coarse, p)
    switch = list(range(p)) if uio else []
    masks = _subset_masks(n, _active_switchable(switch, dl, du))
    terms = _switching_terms(dl, du, masks, coarse.shape[0])
    kappa = 10.0 * (1.0 + float(np.abs(a_r).max())) if gain_bound is None else float(gain_bound)
    eta_max = float(terms.eta.max())
    eps1_candidates = sorted({max(eta_max, 0.05) * f for f in (0.5, 1.0, 2.0)})
    best: _Candidate | None = None
    failures = []
    lmi_name = "bounded-width LMI of the interval UIO" if uio else "bounded-width LMI of the interval observer"
    relax = f"reduce the ΔA bounds, change R{' or increase decay' if uio else ''}"
    for eps1 in eps1_candidates:
        problem = _LMIProblem(a_r, p, terms, gamma, kappa, eps1, eps2, q_scale)
        try:
            candidate = problem.solve(f"{lmi_name} with eps1 = {eps1:g}", relax)
        except DesignError as exc:
            failures.append(str(exc))
            continue
        fl, fu = candidate.f_left_lower, candidate.f_left_upper
        candidate.margin = _lmi_margin(candidate.P, q_scale, candidate.gamma, eps1 + eps2, fl, fu, a_r, dl, du, masks)
        if best is None or candidate.margin < best.margin:
            best = candidate
    if best is None or best.margin >= 0:
        detail = f"best (1,1)-block eigenvalue {best.margin:+.3g}" if best is not None else " | ".join(failures)
        raise DesignError(
            f"{lmi_name}: no gain keeps the widths bounded on the {coarse.shape[0]}-point grid ({detail}); {relax}"
        )
    n2 = 2 * n
    cert = BoundednessCertificate(
        P=best.P,
        Q=q_scale * np.eye(n2),
        gamma=best.gamma,
        eps1=best.eps1,
        eps2=eps2,
        solver_status=best.status,
        coarse_margin=best.margin,
        second_block_margin=float(np.max(np.linalg.eigvalsh(best.P / best.eps1 - best.gamma * np.eye(n2)))),
        subsets=len(masks) ** 2,
    )
    design = LPVObserverDesign(
        R=r,
        T=t_mat,
        C_tilde_inv=ct_inv,
        f_left_lower=best.f_left_lower,
        f_left_upper=best.f_left_upper,
        H=h_mat,
        gamma_lower=gamma,
        gamma_upper=gamma,
        certificate=cert,
        hurwitz_margin=0.0,
        coarse_points=int(coarse.shape[0]),
        fine_points=int(fine.shape[0]),
    )
    return _verify(system, design, fine, switch)


def _design_coordinates(
    system: LPVSystem, uio: bool, R: ArrayLike | None, decay: float, points: FloatArray
) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
    """The coordinates R, and for the UIO H = R B_un (26) and the diagonal of Γ = -λ I; returns (R, H, Γ)."""
    n, p = system.n, system.p
    if not uio:
        r = np.eye(n) if R is None else as_matrix("R", R, (n, n))
        _check_r(r, p)
        return r, None, None
    if system.B_un is None:
        raise AssumptionError("B_un: the interval UIO needs unknown-input directions, got None")
    r, h_mat = _uio_coordinates(system, points)
    if np.linalg.cond(r) > 1e12:
        raise DesignError("R: the coordinates that decouple the unknown inputs (R B_un = H) are singular")
    return r, h_mat, -decay * np.ones(system.q)


@dataclass
class _SwitchingTerms:
    r"""The ΔA terms of (74) for every pair of subsets (S1, S2) and grid point, duplicates dropped.

    ``lower``/``upper`` are the positive parts of ΔA's lower bound on S1 and upper bound on S2,
    ``eta`` the matching :math:`\eta` of (95)-(100), ``point`` the index of the grid point.
    """

    lower: FloatArray
    upper: FloatArray
    eta: FloatArray
    point: NDArray[np.intp]


def _switching_terms(dl: FloatArray, du: FloatArray, masks: FloatArray, points: int) -> _SwitchingTerms:
    """One constraint's ΔA terms per (S1, S2, grid point), with the duplicates dropped."""
    n = dl.shape[-1]
    s1 = masks[:, None, None, :]
    s2 = masks[None, :, None, :]
    _, eta = eta_and_generator(np.zeros((n, n)), np.zeros((n, n)), dl[None, None], du[None, None], s1, s2)
    l1 = np.maximum(dl[None, None] * s1[..., None, :], 0.0) * np.ones((1, len(masks), 1, 1, 1))
    u2 = np.maximum(du[None, None] * s2[..., None, :], 0.0) * np.ones((len(masks), 1, 1, 1, 1))
    l1, u2, eta = l1.reshape(-1, n, n), u2.reshape(-1, n, n), eta.reshape(-1)
    pts = np.tile(np.arange(points), len(masks) ** 2)
    key = np.round(
        np.concatenate([l1.reshape(len(l1), -1), u2.reshape(len(u2), -1), eta[:, None], pts[:, None]], 1), 12
    )
    _, keep = np.unique(key, axis=0, return_index=True)
    keep = np.sort(keep)
    return _SwitchingTerms(l1[keep], u2[keep], eta[keep], pts[keep])


@dataclass
class _Candidate:
    r"""The solution of the LMI for one :math:`\varepsilon_1`, with its (1,1)-block margin once measured."""

    P: FloatArray
    gamma: float
    eps1: float
    status: str
    f_left_lower: FloatArray
    f_left_upper: FloatArray
    margin: float = np.inf


class _LMIProblem:
    r"""The LMI (63) (observer) or (109) (UIO) in :math:`P, W, \gamma, t` for a fixed :math:`\varepsilon_1`."""

    def __init__(
        self,
        a_r: FloatArray,
        p: int,
        terms: _SwitchingTerms,
        gamma: FloatArray | None,
        kappa: float,
        eps1: float,
        eps2: float,
        q_scale: float,
    ) -> None:
        n = a_r.shape[-1]
        self.off = ~np.eye(n, p, dtype=bool)
        self.eps1, self.gamma_diag = eps1, gamma
        self.pl, self.pu = cp.Variable(n), cp.Variable(n)
        self.wl, self.wu = cp.Variable((n, p)), cp.Variable((n, p))
        self.gam, self.t = cp.Variable(nonneg=True), cp.Variable()
        cons = [self.pl >= 1e-3, self.pu >= 1e-3, cp.sum(self.pl) + cp.sum(self.pu) == 2 * n]
        cons += [self.pl <= eps1 * self.gam, self.pu <= eps1 * self.gam]  # (2,2) block: P ≤ ε1 γ I
        for w, pv in ((self.wl, self.pl), (self.wu, self.pu)):
            cons += self._gain_constraints(w, pv, kappa)
        for k in range(len(terms.eta)):
            right = a_r[terms.point[k]][:, p:]
            for w, pv, extra in ((self.wl, self.pl, terms.lower[k]), (self.wu, self.pu, terms.upper[k])):
                pg = cp.hstack([w, cp.multiply(cp.reshape(pv, (n, 1), order="F") @ np.ones((1, n - p)), right)])
                pg = pg + cp.multiply(cp.reshape(pv, (n, 1), order="F") @ np.ones((1, n)), extra)
                blk = pg + pg.T + (eps1 + eps2) * cp.diag(pv) + (q_scale + 0.0) * np.eye(n)
                blk = blk + self.gam * float(terms.eta[k]) ** 2 * np.eye(n)
                cons.append(0.5 * (blk + blk.T) << self.t * np.eye(n))
        self.problem = cp.Problem(cp.Minimize(self.t), cons)

    def _gain_constraints(self, w: Any, pv: Any, kappa: float) -> list[Any]:
        """(64) F Metzler, the bound of the designed entries, and for the UIO (105)-(106)."""
        n, p = w.shape
        cons = [w[self.off] >= 0]  # (64): F Metzler (P diagonal)
        cons += [cp.abs(w) <= kappa * cp.reshape(pv, (n, 1), order="F") @ np.ones((1, p))]
        if self.gamma_diag is not None:
            for j in range(len(self.gamma_diag)):
                col = np.zeros(n)
                col[j] = 1.0
                cons += [w[:, j] == self.gamma_diag[j] * cp.multiply(pv, col)]  # (105)-(106)
        return cons

    def solve(self, name: str, relax: str) -> _Candidate:
        """Solve; the designed columns of F from W = P F with (105)-(106) and the Metzler signs imposed exactly."""
        solution = solve_lmi(self.problem, name, relax)
        pld, pud = np.maximum(np.asarray(self.pl.value), 1e-3), np.maximum(np.asarray(self.pu.value), 1e-3)
        fl_left = np.asarray(self.wl.value) / pld[:, None]
        fu_left = np.asarray(self.wu.value) / pud[:, None]
        if self.gamma_diag is not None:  # impose (105)-(106) exactly (the solver meets them to its tolerance)
            q = len(self.gamma_diag)
            for fleft in (fl_left, fu_left):
                fleft[:, :q] = 0.0
                fleft[np.arange(q), np.arange(q)] = self.gamma_diag
        for fleft in (fl_left, fu_left):
            fleft[self.off & (fleft < 0)] = 0.0
        pmat = np.diag(np.concatenate([pld, pud]))
        eps1 = self.eps1
        gv = max(float(np.asarray(self.gam.value)), float(inflate(0.0, float(pmat.max()) / eps1, floor=0.0)[1]))
        return _Candidate(pmat, gv, eps1, solution.status, fl_left, fu_left)


def _lmi_margin(
    pmat: FloatArray,
    q_scale: float,
    gamma: float,
    eps_sum: float,
    fl_left: FloatArray,
    fu_left: FloatArray,
    a_r: FloatArray,
    dl: FloatArray,
    du: FloatArray,
    masks: FloatArray,
) -> float:
    p = fl_left.shape[1]
    fl, fu = a_r.copy(), a_r.copy()
    fl[..., :p], fu[..., :p] = fl_left, fu_left
    g, eta = eta_and_generator(fl, fu, dl[None, None], du[None, None], masks[:, None, None, :], masks[None, :, None, :])
    q = q_scale * np.eye(pmat.shape[0])
    return float(np.max(_block_max_eig(pmat, q, gamma, eps_sum, g, eta)))


def _verify(system: LPVSystem, design: LPVObserverDesign, fine: FloatArray, switch: list[int]) -> LPVObserverDesign:
    """Re-check the design on the fine grid: (17)-(18), Metzler, Hurwitz, (63)/(74) by eigenvalues."""
    a_r, dl, du = _rotated(system, design.R, fine)
    _structure_check(a_r, fine, design.p)
    fl, fu = design.f_matrices(a_r)
    n = fl.shape[-1]
    off = ~np.eye(n, dtype=bool)
    for name, f in (("F_lower", fl), ("F_upper", fu)):
        if np.any(f[:, off] < 0):
            raise DesignError(
                f"{name}: expected a Metzler matrix (bounds that stay ordered) on the fine grid, "
                f"got min off-diagonal {f[:, off].min():.3g}"
            )
    abscissa = float(np.max(np.linalg.eigvals(np.concatenate([fl, fu])).real))
    if not abscissa < 0:
        raise DesignError(f"F: expected Hurwitz F(θ) on the fine grid, got spectral abscissa {abscissa:+.3g}")
    cert = verify_boundedness(design.certificate, fl, fu, dl, du, switchable=switch)
    if not cert.feasible:
        raise DesignError(
            f"the bounded-width certificate{' with sign switching' if switch else ''} fails on the "
            f"{fine.shape[0]}-point grid: "
            f"(1,1)-block eigenvalue {cert.fine_margin:+.3g}, (2,2)-block {cert.second_block_margin:+.3g}; refine grid"
        )
    return dataclasses.replace(design, certificate=cert, hurwitz_margin=abscissa, fine_points=int(fine.shape[0]))
