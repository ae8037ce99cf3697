r"""Error tubes: the exact elementwise bound of a Luenberger estimate's error under box disturbances.

For :math:`\hat x_{k+1} = \Phi\hat x_k + \Gamma u_k + L(y_k - C\hat x_k) + \dots` the error
:math:`e = x - \hat x` obeys :math:`e_{k+1} = Me_k + \eta_k` with :math:`M = \Phi - LC` and
:math:`\eta_k` in a box of radius :math:`d_k` (process noise, :math:`LFv`, and
:math:`\delta\Phi x_k + \delta\Gamma u_k` for interval models). Hence, exactly for independent boxes,

.. math:: |e_k| \le |M^k|\,\rho_0 + \sum_{i<k} |M^i|\, d_{k-1-i},

which is never wider than the framer bound :math:`\sum_i |M|^i d` (since :math:`|M^i| \le |M|^i`) and
needs only :math:`\rho(M) < 1`, not a stable :math:`|M|`. For data-dependent :math:`d_k` the sum is cut
after :math:`J` terms without loss of soundness,
:math:`\rho_k = |M^J|\rho_{k-J} + \sum_{i<J}|M^i| d_{k-1-i}`, where :math:`J` is chosen so that
:math:`|M^J|` is a strong contraction. With :math:`d_k = d^0 + \delta\Phi(|\hat x_k| + \rho_k)`, the
tube is bounded iff :math:`\rho(|M^J| + G\,\delta\Phi) < 1` with :math:`G = \sum_{i<J}|M^i|` (a positive
system with delays).

**Noise generators.** The noise part of :math:`\eta_k` is often a fixed linear image of a box,
:math:`G\xi_k` with :math:`|\xi_k| \le 1` independent from step to step (:math:`G = [E\,\mathrm{diag}(w_r),
-LF\,\mathrm{diag}(v_r)]` in discrete time). Its share of the sum is bounded by
:math:`c_\ell = \sum_{i<\ell}|M^iG|\,1 \le \sum_{i<\ell}|M^i|\,|G|\,1` (:func:`noise_sums`): the box
:math:`|G|1` forgets that every channel of :math:`\xi` moves all the states it drives at once. For a constant
noise box :math:`c_\ell` is a constant, computed once; the recursion keeps only the data-dependent terms
(:math:`\delta\Phi`, :math:`\delta\Gamma`) in its history. The design still scores gains with the box.

The same recursion holds in coordinates :math:`z = Te` (:math:`M_z = TMT^{-1}`, disturbance radius
:math:`|T|d_k`, :math:`\delta\Phi_z = |T|\,\delta\Phi\,|T^{-1}|`, :math:`|e| \le |T^{-1}|\rho^z`). A slow
error mode of a dense :math:`M` (a stiff model sampled fast: :math:`\rho(M) = 1 - 10^{-4}`) needs
:math:`J \approx \ln(4\,|w|^T|v|)/(1 - \rho(M))` steps before :math:`|M^J|` contracts, far beyond any
affordable horizon; in the real modal basis of :math:`M` (:math:`M_z` block diagonal) every mode is its
own recursion, :math:`|M_z^i| = |M_z|^i` on the 1×1 blocks, so a short :math:`J` cuts nothing. The
design uses these coordinates for a gain whose identity-coordinate tube is not bounded.

**Block norms.** A slow, lightly damped complex pair :math:`re^{\pm i\theta}` is a 2×2 rotation block
of :math:`M_z`, and a box does not contract under a rotation: the row sums of :math:`|M_z^i|` are
:math:`r^i(|\cos i\theta| + |\sin i\theta|)`, so the per-step rate is :math:`\approx r(1 + \theta)`, above
1 when the pair rotates as fast as it decays. The Euclidean norm of the block contracts exactly by
:math:`r`. With a partition of :math:`z` into blocks :math:`b` (sizes 1 or 2) and
:math:`\|X\|_{bc}` the spectral norm of block :math:`(b, c)` of a matrix, the triangle inequality on
:math:`e_{k+1} = M^\ell e_{k+1-\ell} + \sum_{i<\ell}M^i\eta_{k-i}` gives the same recursion for the vector
of block norms :math:`\rho_b \ge \|z_b\|_2`,

.. math:: \rho_{k+1} = \|M^{\ell}\|\,\rho_{k+1-\ell} + \sum_{i<\ell}\|M^i\|\,d_{k-i},
          \qquad d_b \ge \|(T\eta)_b\|_2,\qquad |x_i| \le \sum_b \|(T^{-1})_{i,b}\|_2\,\rho_b,

(the last by Cauchy–Schwarz), with :math:`\|\cdot\|` the matrix of block norms; with blocks of size 1 it
is the tube above. The :math:`\Delta\Phi` part of :math:`T\eta` is :math:`T\Delta\Phi T^{-1}z`, bounded per
block column by :math:`\min(\|\,|T|\,\delta\Phi\,|T^{-1}|\,\|_{bc}, \|B\|_{bc})` with
:math:`B \ge |T\Delta\Phi T^{-1}|` from :meth:`~intervalobs.systems.sampling.SampledModel.dphi_in` (which
keeps the cancellations of the first-order term in the modal coordinates). For a gain whose tube is
not bounded in the identity coordinates, the design tries the modal coordinates both as a box and
with the 2×2 blocks of its complex pairs, and keeps the smaller steady radius.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import solve_discrete_are
from scipy.optimize import minimize

from .._docstrings import shared_docs
from ..errors import ArgumentError
from ..interval import ROUNDING_MARGIN, inflate
from ..systems.sampling import SampledModel
from .cooperative import real_modal_form

__all__ = ["BlockNorms", "TubeDesign", "design_tube_gain", "noise_sums", "tube_horizon", "tube_stability"]

FloatArray = NDArray[np.float64]

_KALMAN_REGULARISATION = 1e-12
"""Added to the Kalman-type design covariances so they are positive definite (a design choice, not a
rounding pad: the gain is only a candidate, its tube is computed and verified afterwards)."""

_HORIZON_CONTRACTION = 0.25
_MAX_HORIZON = 4000
_SHORT_HORIZON = 256
_SMALL_GAIN_ENTRIES = 16
"""Gains with more entries are neither refined (the pattern search costs a few evaluations per entry and level)
nor given companions (every companion adds a tube, ``|M^i|`` for ``i ≤ J``, to every step)."""
_REFINE_LEVELS = 9
_REFINE_SIGNIFICANT = 1e-9
"""A refinement step must lower the score by this relative amount (far above its rounding): the search
then takes the same path on any machine."""
_DESCENT_SMOOTHING = (1e-2, 1e-3, 1e-4, 1e-6, 0.0)
"""Smoothing stages of the gradient refinement (relative to each matrix's largest entry; 0: the exact bound)."""
_DESCENT_ITERATIONS = 300
"""Quasi-Newton iterations per smoothing stage."""
_DESCENT_PENALTY = 10.0
"""Extra weight of a state's steady radius above the winner's during the descent (the result must not exceed it)."""
_DESCENT_UNBOUNDED = 1e3
"""Objective of a gain whose tube is unbounded, in units of the winner's radius sum (the line search backs off)."""
_EPS = float(np.finfo(float).eps)
_NORM_ROUNDING = 16 * _EPS
"""Relative upward rounding of a computed 2-norm of a block of size 2 (a few rounded operations each)."""


class BlockNorms:
    """Euclidean norms of the diagonal blocks (sizes 1 or 2, in order) of the tube coordinates ``z``.

    With every block of size 1 each map is the elementwise absolute value (no rounding); a block of size 2
    is measured by its 2-norm (a matrix block by its spectral norm, from the closed form
    ``(|(a + d) + i(c - b)| + |(a - d) + i(c + b)|)/2`` of a 2×2 matrix ``[[a, b], [c, d]]``), rounded up
    by 16 ulps.

    Parameters
    ----------
    sizes : sequence of int
        Block sizes, each 1 or 2.
    """

    rounding: float = _NORM_ROUNDING
    """Relative upward rounding of a block of size 2's norm."""

    def __init__(self, sizes: Sequence[int]) -> None:
        self.sizes = tuple(int(size) for size in sizes)
        if any(size not in (1, 2) for size in self.sizes):
            raise ArgumentError(f"sizes: expected block sizes 1 or 2, got {self.sizes}")
        self.count = len(self.sizes)
        self.n = sum(self.sizes)
        self.singleton = self.count == self.n
        # position of each coordinate in a padded layout of 2 slots per block
        self._slots = np.concatenate([2 * b + np.arange(size) for b, size in enumerate(self.sizes)]).astype(int)

    def _pad(self, x: FloatArray, axis: int) -> FloatArray:
        shape = list(x.shape)
        shape[axis] = 2 * self.count
        out = np.zeros(shape)
        index: list[slice | NDArray[np.int_]] = [slice(None)] * x.ndim
        index[axis] = self._slots
        out[tuple(index)] = x
        return out

    def vector(self, v: FloatArray) -> FloatArray:
        """Block norms of vectors along the last axis: shape (..., n) to (..., count).

        Parameters
        ----------
        v : numpy.ndarray, shape (..., n)
            Vectors.

        Returns
        -------
        numpy.ndarray, shape (..., count)
        """
        if self.singleton:
            return np.abs(v)
        padded = self._pad(np.asarray(v, dtype=float), -1)
        return np.asarray(np.hypot(padded[..., 0::2], padded[..., 1::2]) * (1 + _NORM_ROUNDING))

    def rows(self, x: FloatArray) -> FloatArray:
        """2-norms of the pieces of each column of ``x`` within each block of rows: (n, k) to (count, k).

        Parameters
        ----------
        x : numpy.ndarray, shape (n, k)
            Matrix.

        Returns
        -------
        numpy.ndarray, shape (count, k)
        """
        return np.asarray(self.vector(np.asarray(x).T).T)

    def cols(self, x: FloatArray) -> FloatArray:
        """2-norms of the pieces of each row of ``x`` within each block of columns: (k, n) to (k, count).

        Parameters
        ----------
        x : numpy.ndarray, shape (k, n)
            Matrix.

        Returns
        -------
        numpy.ndarray, shape (k, count)
        """
        return self.vector(np.asarray(x))

    def matrix(self, x: FloatArray) -> FloatArray:
        """Spectral norms of the blocks of square matrices: shape (..., n, n) to (..., count, count).

        Parameters
        ----------
        x : numpy.ndarray, shape (..., n, n)
            Matrices.

        Returns
        -------
        numpy.ndarray, shape (..., count, count)
        """
        if self.singleton:
            return np.abs(x)
        padded = self._pad(self._pad(np.asarray(x, dtype=float), -1), -2)
        a, b = padded[..., 0::2, 0::2], padded[..., 0::2, 1::2]
        c, d = padded[..., 1::2, 0::2], padded[..., 1::2, 1::2]
        norm = 0.5 * (np.hypot(a + d, c - b) + np.hypot(a - d, c + b))
        return np.asarray(norm * (1 + _NORM_ROUNDING))


@dataclass(frozen=True)
class TubeDesign:
    """A verified error-tube design.

    Attributes
    ----------
    L : numpy.ndarray, shape (n, p)
        Observer gain.
    T : numpy.ndarray, shape (n, n)
        Coordinates ``z = Te`` of the tube (identity, or the real modal basis of ``Φ - LC``).
    horizon : int
        Number ``J`` of exact terms kept in the tube recursion.
    gain_radius : float
        ``ρ(|M^J| + G δΦ)``, verified < 1.
    steady_radius : numpy.ndarray, shape (n,)
        Steady-state error radius of ``x`` from the noise alone (zero state magnitude).
    candidate : str
        Which candidate gain (and coordinates) won.
    blocks : tuple of int
        Sizes of the blocks of ``z`` whose Euclidean norms the tube bounds (empty: all of size 1, a box).
    companions : tuple of numpy.ndarray
        Further gains, in the same coordinates, whose tubes the observer runs next to this one and
        intersects with it at every step (:func:`design_tube_gain`: the other candidates bounded in the
        identity coordinates, by increasing steady radius sum).
    """

    L: FloatArray
    T: FloatArray
    horizon: int
    gain_radius: float
    steady_radius: FloatArray
    candidate: str
    blocks: tuple[int, ...] = ()
    companions: tuple[FloatArray, ...] = ()


def tube_horizon(m: FloatArray, norms: BlockNorms | None = None) -> int | None:
    """The horizon ``J`` of the tube recursion, or None when ``M`` is not Schur stable.

    The smallest ``J`` with ``‖|M^J|‖∞ ≤ 1/4``; when no ``J`` up to 4000 contracts that much (a slow
    error mode), the ``J ≤ 256`` with the smallest per-step rate ``ρ(|M^J|)^(1/J)``, provided it is
    below 1 (for a block-diagonal ``M`` that rate is ``ρ(M)`` already at ``J = 1``). With block norms,
    ``|M^J|`` is the matrix of block norms of ``M^J``.

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M = Φ - LC`` (in the tube's coordinates).
    norms : BlockNorms, optional
        Blocks of the tube coordinates (default: every block of size 1).

    Returns
    -------
    int or None
        The horizon ``J``; None when ``ρ(M) ≥ 1`` or no ``J`` qualifies.
    """
    if np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    norms = BlockNorms((1,) * m.shape[0]) if norms is None else norms
    signed = _powers(m, _SHORT_HORIZON + 1)[1:]  # M^1 … M^256, then 256 more at a time
    chunk = signed[-1]
    short = norms.matrix(signed)
    block, offset = short, 0
    while offset < _MAX_HORIZON:
        hit = np.flatnonzero(block.sum(axis=-1).max(axis=-1) <= _HORIZON_CONTRACTION)
        if hit.size and offset + hit[0] + 1 <= _MAX_HORIZON:
            return int(offset + hit[0] + 1)
        signed, offset = signed @ chunk, offset + _SHORT_HORIZON
        block = norms.matrix(signed)
    rates = [float(np.max(np.abs(np.linalg.eigvals(p)))) ** (1.0 / j) for j, p in enumerate(short, start=1)]
    best = int(np.argmin(rates))
    return best + 1 if rates[best] < 1 else None


def _powers(m: FloatArray, count: int) -> FloatArray:
    """``M^i`` for ``i = 0 … count-1`` by doubling (log2(count) batched products), shape (count, n, n)."""
    powers = np.empty((count, *m.shape))
    powers[0] = np.eye(m.shape[0])
    filled, step = 1, m  # step = M^filled: the next block is M^i M^filled, i < filled
    while filled < count:
        size = min(filled, count - filled)
        powers[filled : filled + size] = powers[:size] @ step
        filled, step = filled + size, step @ step
    return powers


def abs_powers(m: FloatArray, count: int, norms: BlockNorms | None = None) -> FloatArray:
    """``|M^i|`` (the block norms of ``M^i`` with ``norms``) for ``i = 0 … count-1``.

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Matrix.
    count : int
        Number of powers.
    norms : BlockNorms, optional
        Blocks (default: every block of size 1, elementwise absolute values).

    Returns
    -------
    numpy.ndarray, shape (count, nb, nb)
    """
    powers = _powers(m, count)
    return np.abs(powers) if norms is None else norms.matrix(powers)


def noise_sums(
    m: FloatArray, generators: FloatArray, box: FloatArray, horizon: int, norms: BlockNorms | None = None
) -> FloatArray:
    r"""The noise part of the tube, :math:`c_\ell \ge \sum_{i<\ell}\|M^i G\|\,1`, for :math:`\ell = 0 \dots J`.

    The part of a step's disturbance that is a fixed linear image :math:`G\xi_k` of a unit box, independent
    from step to step (``G`` holds the process-noise generators and :math:`-LF\,\mathrm{diag}(v_r)`, in the
    tube's coordinates), enters :math:`\ell` steps of the error as :math:`\sum_{i<\ell}M^iG\xi_{k-i}`, whose
    block ``b`` has a norm of at most :math:`\sum_{i<\ell}\sum_j\|(M^iG)_{bj}\|_2` (a column's block norm
    times :math:`|\xi_j| \le 1`). With blocks of size 1 that is never above the box term
    :math:`|M^i|\,d` of the tube with :math:`d \ge |G|1` the box of :math:`G\xi`: the generators keep the
    cancellations between the columns of :math:`M^iG` that the box forgets. (For a block of size 2 the columns'
    norms can sum to more than the norm of the box's corner; each term is the smaller of the two bounds.) The
    sums are rounded up by :math:`(n + q + J + 4)\varepsilon` (at least ``ROUNDING_MARGIN``) of the sum of the
    magnitudes their rounding is relative to (:math:`|M^i||G|1`, or the box term where it is kept), whatever
    the order of the sums.

    Parameters
    ----------
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M`` in the tube's coordinates.
    generators : numpy.ndarray, shape (n, q)
        Generators ``G`` in the tube's coordinates (columns scaled by their radii).
    box : numpy.ndarray, shape (nb,)
        The box term's per-step radius ``d`` (block norms), at least the block norms of ``|G| 1``.
    horizon : int
        Horizon ``J``: sums for ``ℓ = 0 … J``.
    norms : BlockNorms, optional
        Blocks of the coordinates (default: every block of size 1).

    Returns
    -------
    numpy.ndarray, shape (J + 1, nb)
        ``c_ℓ``, row 0 zero (no step yet).
    """
    n, q = generators.shape
    norms = BlockNorms((1,) * n) if norms is None else norms
    powers = _powers(m, horizon)  # M^0 … M^{J-1}
    images = powers @ generators  # (J, n, q)
    columns = norms.rows(images.transpose(1, 0, 2).reshape(n, -1)).reshape(norms.count, horizon, q)
    found = columns.sum(axis=-1).T  # (J, nb): the block norms of each M^i G, summed over the columns
    starts = np.cumsum((0, *norms.sizes[:-1]))
    magnitude = np.add.reduceat(np.abs(powers) @ np.abs(generators).sum(axis=1), starts, axis=-1)  # (J, nb)
    boxed = norms.matrix(powers) @ box  # the box term's (J, nb); below the columns' for some 2-blocks
    use_box = boxed < found
    terms, scale = np.where(use_box, boxed, found), np.where(use_box, boxed, magnitude)
    margin = max(ROUNDING_MARGIN, (n + q + horizon + 4) * _EPS)
    total = np.cumsum(terms, axis=0)
    sums = inflate(-total, total, margin, scale=np.cumsum(scale, axis=0))[1]
    return np.vstack([np.zeros((1, norms.count)), sums])


def coupling(model: SampledModel, T: FloatArray | None, norms: BlockNorms | None = None) -> FloatArray:
    """The matrix ``S`` with ``‖(TΔΦx)_b‖ ≤ (S ρ)_b`` for ``x = T⁻¹z``, ``ρ_c ≥ ‖z_c‖`` (module docstring).

    ``S = min(‖|T|δΦ|T⁻¹|‖, ‖B‖)`` blockwise, ``B`` from ``model.dphi_in(T)``; ``δΦ`` itself for the
    identity.

    Parameters
    ----------
    model : SampledModel
        Sampled interval model.
    T : numpy.ndarray, shape (n, n) or None
        Coordinates (None: identity).
    norms : BlockNorms, optional
        Blocks (default: every block of size 1).

    Returns
    -------
    numpy.ndarray, shape (nb, nb)
    """
    n = model.Phi.shape[0]
    norms = BlockNorms((1,) * n) if norms is None else norms
    if T is None or (norms.singleton and np.array_equal(T, np.eye(n))):
        return norms.matrix(model.dPhi)
    plain = norms.matrix(np.abs(T) @ model.dPhi @ np.abs(np.linalg.inv(T)))
    return np.asarray(np.minimum(plain, norms.matrix(model.dphi_in(T))))


def tube_stability(
    model: SampledModel,
    m: FloatArray,
    disturbance: FloatArray,
    horizon: int,
    T: FloatArray | None = None,
    norms: BlockNorms | None = None,
) -> tuple[float, FloatArray]:
    """Gain ``ρ(|M^J| + GS)`` and the steady radius ``(I - |M^J| - GS)⁻¹ G d`` (inf when unstable).

    Here ``G = Σ_{i<J} |M^i|`` and ``S`` is :func:`coupling` (``δΦ`` in the identity coordinates); in
    coordinates ``z = Te`` every quantity is the z one, with block norms in place of ``|·|`` when
    ``norms`` has blocks of size 2 (``disturbance`` and the steady radius are then block norms).

    Parameters
    ----------
    model : SampledModel
        Sampled interval model (its ``δΦ``).
    m : numpy.ndarray, shape (n, n)
        Error matrix ``M = Φ - LC``.
    disturbance : numpy.ndarray, shape (nb,)
        Per-step radius ``d⁰`` of the box disturbance entering the error (without the ``δΦ`` term).
    horizon : int
        Tube horizon ``J``.
    T : numpy.ndarray, shape (n, n), optional
        Coordinates of ``m`` and ``disturbance`` (default identity).
    norms : BlockNorms, optional
        Blocks of the coordinates (default: every block of size 1).

    Returns
    -------
    rho : float
        Spectral radius of ``|M^J| + GS``.
    steady_radius : numpy.ndarray, shape (nb,)
        Steady-state radius bound (``inf`` entries when ``rho ≥ 1``).
    """
    return _loop_and_steady(abs_powers(m, horizon + 1, norms), coupling(model, T, norms), disturbance)


def _loop_and_steady(powers: FloatArray, coupling: FloatArray, disturbance: FloatArray) -> tuple[float, FloatArray]:
    """``ρ(|M^J| + GS)`` and ``(I - |M^J| - GS)⁻¹ G d`` from ``powers = |M^i|``, ``i = 0 … J``."""
    horizon = powers.shape[0] - 1
    g = powers[:horizon].sum(axis=0)
    loop = powers[horizon] + g @ coupling
    radius = float(np.max(np.abs(np.linalg.eigvals(loop))))
    if radius >= 1:
        return radius, np.full(loop.shape[0], np.inf)
    return radius, np.linalg.solve(np.eye(loop.shape[0]) - loop, g @ disturbance)


def _kalman_gain(model: SampledModel, C: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray | None:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            p = solve_discrete_are(model.Phi.T, C.T, q, r)
    except (ValueError, np.linalg.LinAlgError):
        return None
    return np.asarray(model.Phi @ p @ C.T @ np.linalg.inv(C @ p @ C.T + r))


@shared_docs
def design_tube_gain(
    model: SampledModel,
    C: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    extra: dict[str, FloatArray] | None = None,
) -> TubeDesign | None:
    """Pick the gain with the smallest steady error tube among Kalman-type and given candidates.

    Candidates are steady-state Kalman gains of the sampled model whose covariances are the squared
    box radii (process noise, plus the ``δΦ`` spread scaled by unit state magnitude), with the
    measurement covariance scaled by 0.1, 1 and 10, and any ``extra`` gains (e.g. framer gains). Each
    runs in the original coordinates, or, when its tube is not bounded there, in the real modal
    basis of ``Φ - LC``, as a box and in block norms, the smaller steady radius kept (see the module
    docstring). A winner in the original coordinates is then refined locally for a smaller steady radius
    sum with no state's steady radius larger (a pattern search on its entries when there are at most 16,
    a smoothed quasi-Newton descent with the exact gradient of the bound beyond: many outputs); the
    refined gain is kept only when its verified tube is never wider in any state. A result in the original
    coordinates (at most 16 entries) carries every other candidate bounded there as a companion, the
    unrefined winner first: a smaller steady radius does not make every step narrower (the transient from
    the prior box), and estimates of different gains err differently, so the observer intersects all their
    tubes at every step.

    Parameters
    ----------
    %(sampled_model)s
    extra : dict of str to numpy.ndarray, optional
        More gains to compare.

    Returns
    -------
    TubeDesign or None
        None when no candidate gives a bounded tube.
    """
    n = model.Phi.shape[0]
    spread = model.dPhi.sum(axis=1)
    if not (np.all(np.isfinite(model.noise_radius)) and np.all(np.isfinite(spread))):
        return None
    scale = max(1.0, float(np.max(model.noise_radius)))
    q = np.diag(np.square(model.noise_radius / scale) + np.square(spread / scale)) + _KALMAN_REGULARISATION * np.eye(n)
    r0 = np.diag((np.abs(F) @ v_radius) ** 2) + _KALMAN_REGULARISATION * np.eye(C.shape[0])
    candidates: dict[str, FloatArray] = {}
    for factor in (0.1, 1.0, 10.0):
        gain = _kalman_gain(model, C, q, r0 * factor / scale / scale)
        if gain is not None:
            candidates[f"kalman-{factor:g}"] = gain
    candidates.update(extra or {})
    best: TubeDesign | None = None
    plain: list[TubeDesign] = []  # the candidates bounded in the identity coordinates
    for name, gain in candidates.items():
        error = model.Phi - gain @ C
        found = _tube_in(model, gain, error, np.eye(n), (1,) * n, F, v_radius, name)
        plain += [] if found is None else [found]
        form = real_modal_form(error) if found is None else None
        if form is not None:
            modal, sizes = form
            m_z = modal @ error @ np.linalg.inv(modal)
            found = _tube_in(model, gain, m_z, modal, (1,) * n, F, v_radius, f"{name}/modal")
            if max(sizes) > 1:
                blocks = _tube_in(model, gain, m_z, modal, sizes, F, v_radius, f"{name}/modal-blocks")
                if blocks is not None and (found is None or blocks.steady_radius.sum() < found.steady_radius.sum()):
                    found = blocks
        if found is not None and (best is None or found.steady_radius.sum() < best.steady_radius.sum()):
            best = found
    if best is None:
        return None
    refined = _refined(model, C, F, v_radius, best)
    if refined is None:
        refined = _descended(model, C, F, v_radius, best)
    winner = best if refined is None else refined
    if winner.L.size > _SMALL_GAIN_ENTRIES or winner.blocks or not np.array_equal(winner.T, np.eye(n)):
        return winner
    others = sorted((found for found in plain if found is not winner), key=lambda found: found.steady_radius.sum())
    return replace(winner, companions=tuple(found.L for found in others))


def _refined(
    model: SampledModel, C: FloatArray, F: FloatArray, v_radius: FloatArray, start: TubeDesign
) -> TubeDesign | None:
    """A local refinement of the winning identity-coordinate gain, or None when it finds nothing better.

    A pattern search on the entries of ``L`` (steps ``±δ·max|L|``, ``δ`` halved from 1/4 to 1/1024
    whenever no step helps) minimises the steady radius sum at the winner's horizon, with every state's
    steady radius at most the winner's; a step is taken only when it lowers the sum by more than a relative
    ``1e-9``, so rounding does not steer the search. The result is verified by :func:`_tube_in` and kept only
    when its verified steady radius is nowhere above the winner's and smaller in sum. The Kalman-type
    candidates minimise a variance, not this box bound, so the refinement typically gains several per cent.
    """
    n = model.Phi.shape[0]
    if start.L.size > _SMALL_GAIN_ENTRIES or start.blocks or not np.array_equal(start.T, np.eye(n)):
        return None
    limit = start.steady_radius

    def score(gain: FloatArray) -> float:
        steady = _steady_estimate(model, gain, C, F, v_radius, start.horizon)
        return float(steady.sum()) if steady is not None and np.all(steady <= limit) else np.inf

    gain, best = start.L.copy(), score(start.L)
    scale = float(np.max(np.abs(start.L)))
    for level in range(_REFINE_LEVELS):
        step = scale * 0.25 * 0.5**level
        improved = True
        while improved:
            improved = False
            for index in np.ndindex(gain.shape):
                for sign in (1.0, -1.0):
                    trial = gain.copy()
                    trial[index] += sign * step
                    value = score(trial)
                    if value < best * (1 - _REFINE_SIGNIFICANT):
                        gain, best, improved = trial, value, True
                        break
    if best >= score(start.L):
        return None
    found = _tube_in(model, gain, model.Phi - gain @ C, np.eye(n), (1,) * n, F, v_radius, f"{start.candidate}+refined")
    if found is None or np.any(found.steady_radius > limit) or found.steady_radius.sum() >= limit.sum():
        return None
    return found


def _descended(
    model: SampledModel, C: FloatArray, F: FloatArray, v_radius: FloatArray, start: TubeDesign
) -> TubeDesign | None:
    """A gradient refinement of a winning identity-coordinate gain with more entries than the pattern search
    takes, or None when it finds nothing better.

    Quasi-Newton descent (L-BFGS) of the steady radius sum of :func:`tube_stability` at the winner's
    horizon, with the exact gradient of :func:`_steady_gradient`; every state whose radius exceeds the
    winner's counts ``1 + _DESCENT_PENALTY`` times. The absolute values are smoothed
    (``sqrt(x² + (εs)²)``, ``s`` the largest entry of the matrix) for ``ε`` in ``_DESCENT_SMOOTHING``,
    each stage starting where the previous ended: the winner often sits on a kink (a framer LP gain
    zeroes entries of ``Φ - LC``), where the unsmoothed descent stops at once. (A smoothed radius is above
    the exact one, so the first stages weigh nearly every state alike and move freely; the later ones
    hold each state near the winner's.) The cost is ``O(J n³)`` per evaluation, a few hundred
    evaluations per stage, where the pattern search needs ``O(np)`` evaluations per sweep. Of every gain evaluated,
    the one with the smallest exact steady radius sum (by a relative ``1e-9``) and no state above the
    winner is verified by :func:`_tube_in` and kept under the rule of :func:`_refined`.
    """
    n = model.Phi.shape[0]
    if start.L.size <= _SMALL_GAIN_ENTRIES or start.blocks or not np.array_equal(start.T, np.eye(n)):
        return None
    limit, shape = start.steady_radius, start.L.shape
    kept = [(float(limit.sum()) * (1 - _REFINE_SIGNIFICANT), start.L)]  # the best exact sum within the limit

    def objective(flat: FloatArray, floors: tuple[FloatArray, float] | None) -> tuple[float, FloatArray]:
        gain = flat.reshape(shape)
        exact = _steady_estimate(model, gain, C, F, v_radius, start.horizon)
        if exact is not None and np.all(exact <= limit) and exact.sum() < kept[0][0]:
            kept[0] = (float(exact.sum()), gain.copy())
        found = None if exact is None else _steady_gradient(model, C, F, v_radius, gain, start.horizon, floors)
        if found is None:
            return _DESCENT_UNBOUNDED * float(limit.sum()), np.zeros_like(flat)
        weights = np.where(found[0] > limit, 1 + _DESCENT_PENALTY, 1.0)
        return float(weights @ found[0]), found[1](weights).ravel()

    flat = start.L.ravel()
    for smoothing in _DESCENT_SMOOTHING:
        floors = _smoothing_floors(
            model.Phi - flat.reshape(shape) @ C, flat.reshape(shape) @ F, start.horizon, smoothing
        )
        options = {"maxiter": _DESCENT_ITERATIONS}
        flat = minimize(objective, flat, args=(floors,), jac=True, method="L-BFGS-B", options=options).x
    gain = kept[0][1]
    if gain is start.L:
        return None
    found = _tube_in(
        model, gain, model.Phi - gain @ C, np.eye(n), (1,) * n, F, v_radius, f"{start.candidate}+descended"
    )
    if found is None or np.any(found.steady_radius > limit) or found.steady_radius.sum() >= limit.sum():
        return None
    return found


def _steady_gradient(
    model: SampledModel,
    C: FloatArray,
    F: FloatArray,
    v_radius: FloatArray,
    gain: FloatArray,
    horizon: int,
    floors: tuple[FloatArray, float] | None = None,
) -> tuple[FloatArray, Callable[[FloatArray], FloatArray]] | None:
    r"""The identity-coordinate steady radius ``s`` at a horizon, and the gradient of ``wᵀs`` with respect to ``L``.

    ``s = (I - Λ)⁻¹ G d`` with ``Λ = |M^J| + G δΦ``, ``G = Σ_{i<J}|M^i|``, ``d = r + |LF| v`` (as
    :func:`tube_stability`); with ``a = (I - Λ)⁻ᵀ w``, ``d(wᵀs) = aᵀ dG (d + δΦ s) + aᵀ d|M^J| s + aᵀ G dd``,
    and ``d|M^i| = sign(M^i) ∘ dM^i``. The sum over ``i`` of ``⟨X_i, dM^i⟩`` is back-propagated through
    ``M^i = M M^{i-1}`` (adjoints ``Λ_i = X_i + Mᵀ Λ_{i+1}``, gradient ``Σ_i Λ_i (M^{i-1})ᵀ``): ``2J``
    products of ``n × n`` matrices, ``dM = -dL C`` — the cost of the forward pass, ``O(J n³)``. With
    ``floors`` (``f_i`` for ``M^i``, ``i ≤ J``, and one for ``LF``, from :func:`_smoothing_floors`) every
    ``|x|`` is ``sqrt(x² + f²)`` (a smooth upper bound, for the descent only). None when ``Φ - LC`` or the
    loop ``Λ`` is not Schur stable; otherwise ``s`` and the map from ``w`` to the gradient.
    """
    n = model.Phi.shape[0]
    m = model.Phi - gain @ C
    if np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    powers = _powers(m, horizon + 1)
    noise_gain = gain @ F
    magnitude, sign = _smoothed_abs(powers, None if floors is None else floors[0][:, None, None])
    magnitude[0], sign[0] = np.eye(n), 0.0
    noise_magnitude, noise_sign = _smoothed_abs(noise_gain, None if floors is None else floors[1])
    disturbance = model.noise_radius + noise_magnitude @ v_radius
    total = magnitude[:horizon].sum(axis=0)
    loop = magnitude[horizon] + total @ model.dPhi
    if np.max(np.abs(np.linalg.eigvals(loop))) >= 1:
        return None
    system = np.eye(n) - loop
    steady = np.linalg.solve(system, total @ disturbance)

    def gradient(weights: FloatArray) -> FloatArray:
        adjoint = np.linalg.solve(system.T, weights)
        inner = np.outer(adjoint, disturbance + model.dPhi @ steady)
        back = sign[horizon] * np.outer(adjoint, steady)
        grad_m = back @ powers[horizon - 1].T
        for i in range(horizon - 1, 0, -1):
            back = sign[i] * inner + m.T @ back
            grad_m += back @ powers[i - 1].T
        return np.asarray(-grad_m @ C.T + ((total.T @ adjoint)[:, None] * noise_sign * v_radius[None, :]) @ F.T)

    return steady, gradient


def _smoothing_floors(
    m: FloatArray, noise_gain: FloatArray, horizon: int, smoothing: float
) -> tuple[FloatArray, float] | None:
    """Floors ``smoothing·max|M^i|`` (``i ≤ J``) and ``smoothing·max|LF|`` of :func:`_steady_gradient`, or None for 0.

    They are fixed for a stage of the descent (taken at its starting gain), so the smoothed bound is one
    function of ``L`` whose gradient is exact.
    """
    if smoothing == 0 or np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    powers = np.abs(_powers(m, horizon + 1)).max(axis=(1, 2))
    return smoothing * powers, smoothing * float(np.max(np.abs(noise_gain), initial=0.0))


def _smoothed_abs(x: FloatArray, floor: FloatArray | float | None) -> tuple[FloatArray, FloatArray]:
    """``|x|`` and ``sign(x)``, or with a floor ``sqrt(x² + floor²)`` and its derivative ``x / sqrt(x² + floor²)``."""
    if floor is None:
        return np.abs(x), np.sign(x)
    magnitude = np.sqrt(x * x + np.square(floor))
    return magnitude, np.divide(x, magnitude, out=np.zeros_like(x), where=magnitude > 0)


def _steady_estimate(
    model: SampledModel, gain: FloatArray, C: FloatArray, F: FloatArray, v_radius: FloatArray, horizon: int
) -> FloatArray | None:
    """The identity-coordinate steady radius of :func:`tube_stability` at a given horizon, None when unbounded."""
    m = model.Phi - gain @ C
    if np.max(np.abs(np.linalg.eigvals(m))) >= 1:
        return None
    disturbance = model.noise_radius + np.abs(gain @ F) @ v_radius
    radius, steady = _loop_and_steady(abs_powers(m, horizon + 1), model.dPhi, disturbance)
    return steady if radius < 1 else None


def _tube_in(
    model: SampledModel,
    gain: FloatArray,
    m_z: FloatArray,
    T: FloatArray,
    sizes: tuple[int, ...],
    F: FloatArray,
    v_radius: FloatArray,
    name: str,
) -> TubeDesign | None:
    """The tube of ``gain`` in coordinates ``T`` (``m_z = T(Φ - LC)T⁻¹``) and blocks ``sizes``, or None when
    it is not bounded."""
    norms = BlockNorms(sizes)
    horizon = tube_horizon(m_z, norms)
    if horizon is None:
        return None
    disturbance = norms.vector(np.abs(T) @ (model.noise_radius + np.abs(gain @ F) @ v_radius))
    radius, steady = tube_stability(model, m_z, disturbance, horizon, T, norms)
    if not radius < 1:
        return None
    x_radius = norms.cols(np.abs(np.linalg.inv(T))) @ steady
    return TubeDesign(gain, T, horizon, radius, x_radius, name, () if norms.singleton else sizes)
