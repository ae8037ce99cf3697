r"""Pole placement of :math:`A - LC` in disk LMI regions (the sampled-output high-gain paper, Section 4.1).

A disk with centre :math:`c = c_1 + ic_2` and radius :math:`r` is the :math:`\mathbb{D}_R`-region of
degree one (the sampled-output high-gain paper, eqs. (6), (7), (14))

.. math:: \{s : R_{00} + R_{10}s + \overline{R_{10}s} + R_{11}|s|^2 < 0\},\quad
          R_{00} = |c|^2 - r^2,\; R_{10} = -c_1 + ic_2,\; R_{11} = 1,

i.e. :math:`|s - c| < r`. Theorem 4.1 (by duality with Maamri et al. 2006) moves *one* eigenvalue
:math:`\lambda_j` of the current matrix into its disk with a gain acting along its right eigenvector
:math:`u_j`: with :math:`L_j = u_j\ell` every other eigenvalue is kept (their left eigenvectors are
orthogonal to :math:`u_j`) and :math:`\lambda_j` becomes :math:`\lambda_j - \ell Cu_j`. The LMI (15)
for this scalar modal subsystem, with :math:`X > 0`, :math:`S = \ell X` and
:math:`Y = \lambda_j X - S\,Cu_j`, reads

.. math:: \begin{bmatrix} R_{00}X + R_{10}Y + \overline{R_{10}Y} & \bar Y \\ Y & -X \end{bmatrix} \prec 0.

Algorithm 1 repeats this for every disk. A complex eigenvalue and its conjugate are moved together
with the real gain :math:`2\operatorname{Re}(u_j\ell)` (the disks must come in conjugate pairs); a real
eigenvalue uses a real :math:`\ell`. Among the feasible gains we take the one of least norm (or, with
``objective="center"``, the one that puts the eigenvalue closest to the disk centre).

Everything is verified afterwards from the eigenvalues of :math:`A - LC` itself, not from the solver:
each lies strictly in its disk, they are distinct, and the eigenvector matrix (the
C-diagonalisation :math:`A - LC = v_1^{-1}\operatorname{diag}(p_1 + i\omega_1)v_1`, eq. (13)) has its
condition number reported and bounded.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment
from scipy.signal import place_poles

from .._docstrings import shared_docs
from ..errors import AssumptionError, BoundsError, DesignError, DimensionError
from ..validation import as_choice, as_matrix
from .lmi import solve_lmi

__all__ = [
    "Disk",
    "HalfPlane",
    "HorizontalStrip",
    "ModalDecomposition",
    "Region",
    "RegionPlacement",
    "Sector",
    "VerticalStrip",
    "canonical_eigenvectors",
    "in_region",
    "modal_decomposition",
    "place_in_disks",
    "radius_matrix",
]

FloatArray = NDArray[np.float64]

_CONJUGATE_TOLERANCE = 1e-12
"""Absolute tolerance of the check that disk centres come in conjugate pairs (a check on user data, not a
rounding pad: the pairing only selects which LMI is solved, and every result is verified)."""
ComplexArray = NDArray[np.complex128]

_MAX_CONDITION = 1e8
_LMI_MARGIN = 1e-7
_MARGIN = 0.02


@dataclass(frozen=True)
class Disk:
    """An open disk of the complex plane, an LMI region in which an eigenvalue is placed.

    Parameters
    ----------
    center : complex
        Centre :math:`c_1 + ic_2`.
    radius : float
        Radius, positive.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (14).
    """

    center: complex
    radius: float

    def __post_init__(self) -> None:
        c = complex(self.center)
        if not (np.isfinite(c.real) and np.isfinite(c.imag)):
            raise BoundsError(f"Disk.center: expected a finite complex number, got {self.center!r}")
        if not (np.isfinite(self.radius) and self.radius > 0):
            raise BoundsError(f"Disk.radius: expected a positive radius, got {self.radius!r}")
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "radius", float(self.radius))

    @property
    def R(self) -> tuple[float, complex, float]:
        """``(R00, R10, R11)`` of the disk's LMI: ``|c|^2 - r^2``, ``-c1 + i c2``, ``1``.

        References
        ----------
        The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (14).
        """
        c = complex(self.center)
        return abs(c) ** 2 - self.radius**2, complex(-c.real, c.imag), 1.0

    @shared_docs
    def characteristic(self, s: complex | ComplexArray) -> Any:
        """The region's function :math:`R_{00} + 2\\operatorname{Re}(R_{10}s) + |s|^2`; negative inside.

        %(complex_value)s
        """
        r00, r10, r11 = self.R
        s_arr = np.asarray(s, dtype=complex)
        return r00 + 2 * (r10 * s_arr).real + r11 * np.abs(s_arr) ** 2

    @shared_docs
    def margin(self, s: complex | ComplexArray) -> Any:
        """Distance from ``s`` to the disk's boundary, positive inside: ``r - |s - c|``.

        %(complex_value)s
        """
        return self.radius - np.abs(np.asarray(s, dtype=complex) - complex(self.center))

    @property
    def is_real(self) -> bool:
        """True when the centre is on the real axis (the disk is its own conjugate)."""
        return complex(self.center).imag == 0.0


class _LinearRegion:
    r"""Shared part of the :math:`R_{11} = 0` regions: :math:`\{s : R_{00} + R_{10}s + (R_{10}s)^H \prec 0\}`."""

    def matrices(self) -> tuple[FloatArray, ComplexArray]:
        """``(R00, R10)`` of eq. (6) (``R11 = 0``).

        Returns
        -------
        R00 : numpy.ndarray, shape (d, d)
        R10 : numpy.ndarray, shape (d, d), complex
        """
        raise NotImplementedError

    @shared_docs
    def characteristic(self, s: complex | ComplexArray) -> Any:
        """Largest eigenvalue of :math:`R_{00} + R_{10}s + (R_{10}s)^H` (eq. (6)); negative inside.

        %(complex_value)s
        """
        r00, r10 = self.matrices()
        s_arr = np.asarray(s, dtype=complex)
        term = r10 * s_arr[..., None, None]
        value = r00 + term + np.conj(np.swapaxes(term, -1, -2))
        return np.linalg.eigvalsh(value)[..., -1]

    @shared_docs
    def contains(self, s: complex | ComplexArray) -> Any:
        """True strictly inside the region.

        %(complex_inside)s
        """
        return self.characteristic(s) < 0


@dataclass(frozen=True)
class HalfPlane(_LinearRegion):
    r"""The half-plane :math:`\operatorname{Re}s < -\sigma` (decay rate at least :math:`\sigma`), degree 1:
    :math:`R_{00} = 2\sigma`, :math:`R_{10} = 1`.

    Parameters
    ----------
    shift : float
        :math:`\sigma`, nonnegative.
    """

    shift: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.shift) and self.shift >= 0):
            raise BoundsError(f"HalfPlane.shift: expected a nonnegative decay rate, got {self.shift!r}")

    def matrices(self) -> tuple[FloatArray, ComplexArray]:
        """``(R00, R10)``: ``[[2σ]]``, ``[[1]]``.

        Returns
        -------
        R00 : numpy.ndarray, shape (d, d)
        R10 : numpy.ndarray, shape (d, d), complex
        """
        return np.array([[2.0 * self.shift]]), np.array([[1.0 + 0j]])


@dataclass(frozen=True)
class VerticalStrip(_LinearRegion):
    r"""The strip :math:`a < \operatorname{Re}s < b`, degree 2: :math:`R_{00} = \operatorname{diag}(-2b, 2a)`,
    :math:`R_{10} = \operatorname{diag}(1, -1)`.

    Parameters
    ----------
    left, right : float
        :math:`a < b`.
    """

    left: float
    right: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.left) and np.isfinite(self.right) and self.left < self.right):
            raise BoundsError(f"VerticalStrip: expected finite left < right, got {self.left!r}, {self.right!r}")

    def matrices(self) -> tuple[FloatArray, ComplexArray]:
        """``(R00, R10)``: ``diag(-2b, 2a)``, ``diag(1, -1)``.

        Returns
        -------
        R00 : numpy.ndarray, shape (d, d)
        R10 : numpy.ndarray, shape (d, d), complex
        """
        return np.diag([-2.0 * self.right, 2.0 * self.left]), np.diag([1.0 + 0j, -1.0 + 0j])


@dataclass(frozen=True)
class HorizontalStrip(_LinearRegion):
    r"""The strip :math:`|\operatorname{Im}s| < \omega` (oscillation frequency below :math:`\omega`), degree 2:
    :math:`R_{00} = -2\omega I`, :math:`R_{10} = \operatorname{diag}(-i, i)`.

    Parameters
    ----------
    bound : float
        :math:`\omega`, positive.
    """

    bound: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.bound) and self.bound > 0):
            raise BoundsError(f"HorizontalStrip.bound: expected a positive frequency, got {self.bound!r}")

    def matrices(self) -> tuple[FloatArray, ComplexArray]:
        """``(R00, R10)``: ``-2ω I``, ``diag(-i, i)``.

        Returns
        -------
        R00 : numpy.ndarray, shape (d, d)
        R10 : numpy.ndarray, shape (d, d), complex
        """
        return -2.0 * self.bound * np.eye(2), np.diag([-1j, 1j])


@dataclass(frozen=True)
class Sector(_LinearRegion):
    r"""The conic sector of half-angle :math:`\beta` about the negative real axis (damping ratio at least
    :math:`\cos\beta`), degree 2: :math:`R_{00} = 0`,
    :math:`R_{10} = [\sin\beta,\ \cos\beta;\ -\cos\beta,\ \sin\beta]`.

    Parameters
    ----------
    angle : float
        :math:`\beta` in radians, in :math:`(0, \pi/2)`.
    """

    angle: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.angle) and 0 < self.angle < np.pi / 2):
            raise BoundsError(f"Sector.angle: expected a half-angle in (0, pi/2) rad, got {self.angle!r}")

    def matrices(self) -> tuple[FloatArray, ComplexArray]:
        """``(R00, R10)``: ``0``, ``[[sin β, cos β], [-cos β, sin β]]``.

        Returns
        -------
        R00 : numpy.ndarray, shape (d, d)
        R10 : numpy.ndarray, shape (d, d), complex
        """
        sb, cb = np.sin(self.angle), np.cos(self.angle)
        return np.zeros((2, 2)), np.array([[sb, cb], [-cb, sb]], dtype=complex)


Region = Disk | HalfPlane | VerticalStrip | HorizontalStrip | Sector
r"""Any of the LMI (:math:`\mathbb{D}_R`) regions of the sampled-output high-gain paper, Section 2 (eq. (6))."""


def in_region(region: Region, s: complex | ComplexArray) -> Any:
    """True where ``s`` lies strictly inside ``region`` (its characteristic function is negative).

    Parameters
    ----------
    region : Disk, HalfPlane, VerticalStrip, HorizontalStrip or Sector
        The region.
    s : complex or numpy.ndarray
        Point(s) of the complex plane.

    Returns
    -------
    bool or numpy.ndarray

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (6).
    """
    return np.asarray(region.characteristic(s)) < 0


@dataclass(frozen=True)
class ModalDecomposition:
    r"""The C-diagonalisation :math:`A - LC = v_1^{-1}\operatorname{diag}(p_1 + i\omega_1)v_1`.

    Attributes
    ----------
    eigenvalues : numpy.ndarray, shape (n,), complex
        :math:`p_1 + i\omega_1`.
    v1 : numpy.ndarray, shape (n, n), complex
        Inverse of the eigenvector matrix in the canonical normalisation of :func:`canonical_eigenvectors`
        (unit 2-norm columns, largest-modulus entry real positive). The paper's printed :math:`v_1`
        (MATLAB's LAPACK output) equals it up to a unit complex factor per row.
    v1_inv : numpy.ndarray, shape (n, n), complex
        The eigenvector matrix.
    condition : float
        2-norm condition number of ``v1``.
    separation : float
        Smallest distance between two eigenvalues.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (13).
    """

    eigenvalues: ComplexArray
    v1: ComplexArray
    v1_inv: ComplexArray
    condition: float
    separation: float

    @property
    def p1(self) -> FloatArray:
        """Real parts of the eigenvalues."""
        return np.asarray(self.eigenvalues.real, dtype=float)

    @property
    def omega1(self) -> FloatArray:
        """Imaginary parts of the eigenvalues."""
        return np.asarray(self.eigenvalues.imag, dtype=float)


def canonical_eigenvectors(vectors: ArrayLike) -> ComplexArray:
    r"""Eigenvectors in one normalisation that does not depend on the LAPACK build.

    LAPACK returns each eigenvector up to an arbitrary factor :math:`e^{i\varphi}` (and scale), and
    everything computed from :math:`v_1` in a fixed basis (the modal box of the observer, the complex
    logarithm in the paper's high-gain design) inherits that phase. Here each column is scaled to unit 2-norm and
    multiplied by the unit complex number that makes its *pivot* real and positive; the pivot is the
    first entry whose modulus is at least :math:`1 - 10^{-6}` times the column's largest modulus (the
    tolerance makes near-ties resolve the same way whatever the rounding of the eigensolver, whose
    relative error is of order :math:`n\varepsilon\kappa`, far below :math:`10^{-6}` for the condition
    numbers :func:`modal_decomposition` accepts). Conjugate eigenvalues get conjugate eigenvectors, so
    real eigenvalues get real eigenvectors.

    Parameters
    ----------
    vectors : array_like, shape (n, n)
        Eigenvectors as columns, any phase and nonzero scale.

    Returns
    -------
    numpy.ndarray, shape (n, n), complex
        The same eigenvectors, normalised.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (43) (the complex logarithm).
    """
    vecs = np.asarray(vectors, dtype=complex)
    vecs = vecs / np.linalg.norm(vecs, axis=0, keepdims=True)
    moduli = np.abs(vecs)
    pivot = np.argmax(moduli >= (1.0 - 1e-6) * np.max(moduli, axis=0, keepdims=True), axis=0)
    columns = np.arange(vecs.shape[1])
    entry = vecs[pivot, columns]
    vecs = vecs * (np.conj(entry) / np.abs(entry))[None, :]
    vecs[pivot, columns] = np.abs(entry)  # exactly real (the product above leaves a rounding-sized imaginary part)
    return np.asarray(vecs, dtype=complex)


@shared_docs
def modal_decomposition(
    A: ArrayLike, C: ArrayLike, L: ArrayLike, order: Sequence[complex] | None = None
) -> ModalDecomposition:
    """Diagonalise ``A - L C`` and check that it is C-diagonalisable and Hurwitz.

    Parameters
    ----------
    %(state_output)s
    L : array_like, shape (n, p)
        Gain.
    order : sequence of complex, optional
        Targets (e.g. disk centres): eigenvalue ``j`` is the one matched to ``order[j]``.

    Returns
    -------
    ModalDecomposition

    Raises
    ------
    DesignError
        If ``A - LC`` is not Hurwitz, has repeated eigenvalues or an ill-conditioned eigenbasis.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (13).
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    c = as_matrix("C", C, (None, n))
    gain = as_matrix("L", L, (n, c.shape[0]))
    closed = a - gain @ c
    vals, vecs = np.linalg.eig(closed)
    vecs = canonical_eigenvectors(vecs)
    if order is not None:
        targets = np.asarray(list(order), dtype=complex)
        if targets.size != n:
            raise DimensionError(f"order: expected {n} targets, got {targets.size}")
        rows, cols = linear_sum_assignment(np.abs(targets[:, None] - vals[None, :]))
        perm = cols[np.argsort(rows)]
        vals, vecs = vals[perm], vecs[:, perm]
    if np.max(vals.real) >= 0:
        raise DesignError(
            f"A - LC: expected a Hurwitz matrix, got an eigenvalue with real part {np.max(vals.real):.4g}"
        )
    gaps = np.abs(vals[:, None] - vals[None, :]) + np.diag(np.full(n, np.inf))
    separation = float(np.min(gaps)) if n > 1 else np.inf
    condition = float(np.linalg.cond(vecs))
    if not np.isfinite(condition) or condition > _MAX_CONDITION or separation < 1e-9 * (1 + np.max(np.abs(vals))):
        raise DesignError(
            f"A - LC: expected distinct eigenvalues and a well-conditioned eigenbasis (a diagonalisable loop), "
            f"got separation {separation:.3g} and condition number {condition:.3g}"
        )
    return ModalDecomposition(
        vals.astype(complex), np.linalg.inv(vecs).astype(complex), vecs.astype(complex), condition, separation
    )


def radius_matrix(modal: ModalDecomposition, L: ArrayLike, C: ArrayLike) -> FloatArray:
    r"""The Metzler matrix :math:`[\operatorname{diag}(p_1) + P_1,\, P_1;\; P_1,\, \operatorname{diag}(p_1) + P_1]`.

    With :math:`P_1 = |v_1 L C v_1^{-1}|` (elementwise modulus). It bounds, uniformly in time, the
    radius dynamics of real and imaginary parts when the output injection :math:`LCx` is bounded from
    the observer's own box. Hurwitz is the condition under which those radii stay bounded.

    Parameters
    ----------
    modal : ModalDecomposition
        Decomposition of ``A - LC``.
    L : array_like, shape (n, p)
        Gain.
    C : array_like, shape (p, n)
        Output matrix.

    Returns
    -------
    numpy.ndarray, shape (2n, 2n)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Proposition 4.3 with :math:`a = 0`,
    Algorithm 1 step 8, the known part :math:`M_1` of (36).
    """
    p1 = np.abs(modal.v1 @ np.asarray(L, dtype=float) @ np.asarray(C, dtype=float) @ modal.v1_inv)
    diag = np.diag(modal.p1) + p1
    return np.block([[diag, p1], [p1, diag]])


@dataclass(frozen=True)
class RegionPlacement:
    """Result of :func:`place_in_disks`, verified from the eigenvalues of ``A - L C``.

    Attributes
    ----------
    L : numpy.ndarray, shape (n, p)
        The gain :math:`L_1`.
    disks : tuple of Disk
        Disk ``j`` holds eigenvalue ``j``.
    modal : ModalDecomposition
        :math:`A - L_1C = v_1^{-1}\\operatorname{diag}(p_1 + i\\omega_1)v_1`, eigenvalues in disk order.
    margins : numpy.ndarray, shape (n,)
        ``r_j - |λ_j - c_j|`` (all positive).
    radius_abscissa : float
        Largest real eigenvalue of :func:`radius_matrix` (negative: the observer's radii stay bounded).
    steps : list of dict
        For each LMI solve: the disk, the eigenvalue before and after, the solver status.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Algorithm 1 (the radius check is its step
    8).
    """

    L: FloatArray
    disks: tuple[Disk, ...]
    modal: ModalDecomposition
    margins: FloatArray
    radius_abscissa: float
    steps: list[dict[str, Any]] = field(default_factory=list)

    @property
    def eigenvalues(self) -> ComplexArray:
        """Eigenvalues of ``A - L C`` in disk order."""
        return self.modal.eigenvalues


def _mode_gain(lam: complex, b: ComplexArray, disk: Disk, real: bool, objective: str) -> tuple[ComplexArray, str]:
    """Solve LMI (15) for the scalar modal subsystem ``λ - ℓ b``; return ``ℓ`` (p,) and the status."""
    p = b.size
    r00, r10, _ = disk.R
    x = cp.Variable()
    s_re = cp.Variable(p)
    s_im = np.zeros(p) if real else cp.Variable(p)
    # Y = λX - S b  (S = ℓ X, a row), split into real and imaginary parts
    y_re = lam.real * x - (b.real @ s_re - b.imag @ s_im)
    y_im = lam.imag * x - (b.real @ s_im + b.imag @ s_re)
    h11 = r00 * x + 2 * (r10.real * y_re - r10.imag * y_im)
    # Hermitian [[h11, conj(Y)], [Y, -X]] ≺ 0 as the real symmetric 4×4 [[Re, -Im], [Im, Re]] ≺ 0
    zero = cp.Constant(0.0)
    real_block = cp.bmat(
        [
            [cp.reshape(h11, (1, 1), order="F"), cp.reshape(y_re, (1, 1), order="F")],
            [cp.reshape(y_re, (1, 1), order="F"), cp.reshape(-x, (1, 1), order="F")],
        ]
    )
    imag_block = cp.bmat(
        [
            [cp.reshape(zero, (1, 1), order="F"), cp.reshape(-y_im, (1, 1), order="F")],
            [cp.reshape(y_im, (1, 1), order="F"), cp.reshape(zero, (1, 1), order="F")],
        ]
    )
    big = cp.bmat([[real_block, -imag_block], [imag_block, real_block]])
    sym = 0.5 * (big + big.T)
    constraints = [x >= 1.0, sym << -_LMI_MARGIN * np.eye(4)]
    if objective == "min_gain":
        cost = cp.norm(cp.hstack([s_re, s_im]) if not real else s_re)
    else:
        cost = cp.norm(cp.hstack([y_re - disk.center.real * x, y_im - disk.center.imag * x]))
    problem = cp.Problem(cp.Minimize(cost), constraints)
    solution = solve_lmi(
        problem,
        f"pole placement in the disk of centre {disk.center} and radius {disk.radius}",
        "enlarge the disk or move it (the mode may be unobservable)",
    )
    xv = float(np.asarray(x.value, dtype=float))
    ell = (np.asarray(s_re.value, dtype=float) + 1j * (0.0 if real else np.asarray(s_im.value, dtype=float))) / xv  # type: ignore[union-attr]
    return np.asarray(ell, dtype=complex).reshape(p), solution.status


def _is_real(lam: complex) -> bool:
    """True for an eigenvalue of a real matrix that LAPACK returned on the real axis (up to rounding)."""
    return abs(lam.imag) <= 1e-9 * (1 + abs(lam))


def _mixed_block(region: tuple[Disk, ...], assigned: ComplexArray) -> NDArray[np.bool_]:
    """Disks whose matched eigenvalue is of the other kind (a real one in a non-real disk or the reverse).

    The set is closed under conjugation of the disks and of the eigenvalues, so its eigenvalues span a real
    invariant subspace and its centres are a conjugate-closed set of targets (:func:`_place_block`).
    """
    centres = np.array([d.center for d in region])
    block = np.array([d.is_real != _is_real(complex(lam)) for d, lam in zip(region, assigned)])
    while True:
        grown = block.copy()
        for j in np.flatnonzero(block):
            grown |= np.abs(centres - np.conj(centres[j])) < _CONJUGATE_TOLERANCE
            grown |= np.abs(assigned - np.conj(assigned[j])) <= 1e-9 * (1 + np.abs(assigned[j]))
        if np.array_equal(grown, block):
            return block
        block = grown


def _subspace_gain(closed: FloatArray, c: FloatArray, basis: FloatArray, targets: Sequence[complex]) -> FloatArray:
    """Real gain that gives the restriction of ``closed`` to the invariant subspace ``basis`` the ``targets``.

    The gain acts along ``basis`` only, so every eigenvalue outside the subspace is kept (its left
    eigenvector annihilates the subspace); ``targets`` must be closed under conjugation.
    """
    block = np.linalg.lstsq(basis, closed @ basis, rcond=None)[0]
    # place_poles wants an input matrix of full column rank: (C basis)ᵀ = U S Vᵀ, placed through U S
    u, sv, vt = np.linalg.svd((c @ basis).T, full_matrices=False)
    rank = int(np.sum(sv > 1e-10 * max(1.0, float(sv[0]) if sv.size else 1.0)))
    try:
        if rank == 0:
            raise DesignError("C sees none of these modes")
        placed = place_poles(block.T, u[:, :rank] * sv[:rank], np.asarray(targets, dtype=complex))
    except (ValueError, DesignError) as exc:
        raise DesignError(
            f"place_in_disks: the eigenvalues {np.round(np.linalg.eigvals(block), 6)} cannot be moved to "
            f"{np.round(np.asarray(targets), 6)} by output injection (the modes may be unobservable from C: {exc})"
        ) from exc
    return np.asarray(basis @ (vt[:rank].T @ placed.gain_matrix).T, dtype=float)


def _place_block(
    a: FloatArray, c: FloatArray, region: tuple[Disk, ...], vals: ComplexArray, vecs: ComplexArray, match: NDArray[Any]
) -> tuple[FloatArray, NDArray[np.bool_], list[dict[str, Any]]]:
    """Move the eigenvalues of :func:`_mixed_block` to their disk centres at once (a real gain cannot move
    one of a conjugate pair into a real disk alone, nor two real eigenvalues into a conjugate pair of disks
    one by one); duplicate centres are spread over half the radius so that the targets are distinct.

    Returns the gain, the disks it placed, and one entry of ``RegionPlacement.steps`` per disk.
    """
    block = _mixed_block(region, vals[match])
    gain = np.zeros((a.shape[0], c.shape[0]))
    if not block.any():
        return gain, block, []
    columns: list[FloatArray] = []
    targets: list[complex] = []
    for j in np.flatnonzero(block):
        u, lam, disk = vecs[:, match[j]], complex(vals[match[j]]), region[j]
        if _is_real(lam):
            columns.append(u.real)
        elif lam.imag > 0:
            columns.extend((u.real, u.imag))
        earlier = sum(abs(region[i].center - disk.center) == 0 for i in np.flatnonzero(block) if i < j)
        targets.append(disk.center + 0.5 * disk.radius * earlier / (earlier + 1))
    basis = np.column_stack(columns)
    if basis.shape[1] != len(targets):
        raise DesignError(
            f"place_in_disks: the eigenvalues {np.round(vals[match[block]], 6)} do not form a conjugate-closed set "
            "(verification failed before the placement)"
        )
    gain = _subspace_gain(a, c, basis, targets)
    steps = [
        {
            "disk": int(j),
            "before": complex(vals[match[j]]),
            "after": target,
            "status": "placed with its block",
            "gain_norm": float(np.linalg.norm(gain)),
        }
        for j, target in zip(np.flatnonzero(block), targets)
    ]
    return gain, block, steps


@shared_docs
def place_in_disks(
    A: ArrayLike, C: ArrayLike, disks: Sequence[Disk | tuple[complex, float]], objective: str = "min_gain"
) -> RegionPlacement:
    r"""Place every eigenvalue of :math:`A - LC` in its own disk.

    Eigenvalues of :math:`A` are matched to disks by least total distance; disk by disk (a conjugate
    pair of disks at once) an LMI places the modal subsystem's eigenvalues in the disk and the gains
    are summed, :math:`L_1 = \sum_j L_{1j}`. Eigenvalues are recomputed after each disk. Where the
    matching puts a real eigenvalue in a non-real disk or one of a conjugate pair in a real disk (the
    paper's one-mode gain cannot do either with a real :math:`L`), those eigenvalues
    (closed under conjugation) are moved together, by pole placement on their real invariant subspace,
    to their disk centres. The result is verified from the eigenvalues of :math:`A - L_1C`.

    Parameters
    ----------
    %(state_output)s
    disks : sequence of Disk or (centre, radius)
        ``n`` disks, closed under complex conjugation, each in the open left half-plane
        (``Re c + r <= 0``).
    objective : {"min_gain", "center"}
        Least-norm gain among the feasible ones, or the eigenvalue closest to the disk centre.

    Returns
    -------
    RegionPlacement

    Raises
    ------
    AssumptionError
        If the disks are not ``n``, not conjugate-symmetric or not in the left half-plane.
    DesignError
        If an LMI is infeasible, modes that must move together cannot be moved by output injection
        (unobservable), or the verification fails.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Theorem 4.1 and Algorithm 1: LMI (15) per
    disk, gains summed (step 6, step 10), eigenvalues recomputed (steps 3 and 7).
    """
    a = as_matrix("A", A)
    n = a.shape[0]
    if a.shape != (n, n):
        raise DimensionError(f"A: expected a square matrix, got shape {a.shape}")
    c = as_matrix("C", C, (None, n))
    as_choice("objective", objective, ("min_gain", "center"))
    region = tuple(d if isinstance(d, Disk) else Disk(complex(d[0]), float(d[1])) for d in disks)
    if len(region) != n:
        raise AssumptionError(f"disks: expected one disk per state ({n}), got {len(region)}")
    for d in region:
        if d.center.real + d.radius > 0:
            raise AssumptionError(
                f"disks: expected disks in the left half-plane (Re c + r <= 0), got centre {d.center} radius {d.radius}"
            )
    centres = np.array([d.center for d in region])
    if not np.allclose(np.sort_complex(centres), np.sort_complex(centres.conj()), atol=_CONJUGATE_TOLERANCE):
        raise AssumptionError(
            "disks: expected disks closed under complex conjugation (a real gain places conjugate pairs)"
        )
    vals, vecs = np.linalg.eig(a)
    vals, vecs = vals.astype(complex), vecs.astype(complex)  # complex even when every eigenvalue is real
    rows, cols = linear_sum_assignment(np.abs(centres[:, None] - vals[None, :]))
    match = cols[np.argsort(rows)]
    assigned = vals[match]
    gain, done, steps = _place_block(a, c, region, vals, vecs, match)
    for j, disk in enumerate(region):
        if done[j]:
            continue
        done[j] = True
        if not disk.is_real:
            partner = [
                i
                for i in range(n)
                if not done[i] and abs(region[i].center - disk.center.conjugate()) < _CONJUGATE_TOLERANCE
            ]
            if not partner:
                raise AssumptionError(f"disks: the disk {disk.center} has no conjugate partner")
            done[partner[0]] = True
        # Algorithm 1, steps 3-6: LMI (15) on the modal subsystem of the eigenvalue matched to the disk.
        cur_vals, cur_vecs = np.linalg.eig(a - gain @ c)
        k = int(np.argmin(np.abs(cur_vals - assigned[j])))
        lam = complex(cur_vals[k])
        if objective == "min_gain" and disk.margin(lam) > _MARGIN * disk.radius:
            steps.append({"disk": j, "before": lam, "after": lam, "status": "already inside", "gain_norm": 0.0})
            continue
        target = Disk(disk.center, disk.radius * (1.0 - _MARGIN))
        u = cur_vecs[:, k]
        b = c @ u
        ell, status = _mode_gain(complex(lam.real) if disk.is_real else lam, b, target, disk.is_real, objective)
        wanted = lam - complex(ell @ b)
        if disk.is_real:
            step_gain = np.outer(u.real, ell.real)
        else:
            # A real gain along the real invariant plane [Re u, Im u] moves the pair to (wanted, conj)
            # exactly and keeps every other eigenvalue (their left eigenvectors annihilate the plane).
            step_gain = _subspace_gain(a - gain @ c, c, np.column_stack([u.real, u.imag]), [wanted, wanted.conjugate()])
        gain = gain + step_gain
        new = np.linalg.eigvals(a - gain @ c)
        after = complex(new[np.argmin(np.abs(new - wanted))])
        assigned[j] = after
        steps.append(
            {"disk": j, "before": lam, "after": after, "status": status, "gain_norm": float(np.linalg.norm(step_gain))}
        )
    modal = modal_decomposition(a, c, gain, order=list(centres))
    margins = np.array([d.margin(lam) for d, lam in zip(region, modal.eigenvalues)], dtype=float)
    if np.any(margins <= 0):
        j = int(np.argmin(margins))
        raise DesignError(
            f"place_in_disks: eigenvalue {modal.eigenvalues[j]:.6g} lies outside its disk (centre {region[j].center}, "
            f"radius {region[j].radius}) after the LMI steps; verification failed"
        )
    abscissa = float(np.max(np.linalg.eigvals(radius_matrix(modal, gain, c)).real))
    return RegionPlacement(gain, region, modal, margins, abscissa, steps)
