r"""The compiled array part of one validated flow step (:mod:`intervalobs.systems.flow_enclosure`, steps 3-4).

:func:`advance` takes what the user's vector field gave (the interval Jacobian over the a priori boxes and the
box of the centre's trajectory) and does the rest of the step in one Numba loop per set: the box of the
fundamental matrix, :math:`[\Phi]`, the new generators :math:`\mathrm{mid}[\Phi]G`, the remainder box and the
reduction to ``order`` generators (the leading ``persistent`` kept as they are). :func:`strip_update` is the
observer's contraction of a zonotope by a strip (:func:`intervalobs.observers.continuous_nonlinear._strip_update`,
with its hull-keeping gain). Both evaluate the same formulas, in the same order, as the NumPy paths of
:func:`intervalobs.systems.flow_enclosure._step` and of the observer (which stay the reference and are used for
short records), so the two agree up to the order of a few sums.

:func:`propagate` is the whole of :func:`intervalobs.systems.flow_enclosure.propagate` in one call where the
user's field is recorded as a tape (:mod:`intervalobs.systems.field_tape`, replayed by
:mod:`intervalobs.systems.tape_kernel`): per step the sets' hulls, the Picard search on the whole batch (the
iterations of ``flow_enclosure._picard``, its a priori boxes bit for bit), the forward-mode pass, the centre's
box (step 2) and :func:`advance`'s steps 3-4, with the Python loop's halvings.

Notes
-----
**Soundness.** Every interval operation is the one of :class:`~intervalobs.interval.Interval`: the hull of the four
products of the ends (``0 * inf = 0``), sums in round-to-nearest, and each end moved one floating-point number
outward (``nextafter``, computed on the bits: ``tape_kernel._up``), a matrix product's row sums first padded by the
dot-product bound :math:`\gamma_k\sum|t|` with :math:`\gamma_k = (k + 2)\varepsilon` and the smallest normal number,
as ``Interval.__matmul__`` does (policy 1 of :mod:`intervalobs.interval`). That bound holds for any order of
summation, so the loop's order (not BLAS's or NumPy's pairwise one) changes no guarantee. The point products
(:math:`\mathrm{mid}[\Phi]G` and the centres) need no rounding: whatever they miss is in the remainder box,
which is computed in interval arithmetic from them. The reduction boxes the smallest generators with the
row sums of their magnitudes widened by :math:`2m\varepsilon` relative and rounded up, as
:func:`intervalobs.systems.flow_enclosure._reduce`, or (``frame``) in a frame with the verified inverse bound of
:func:`intervalobs.systems.flow_enclosure._reduce_in_frame` (the same formulas; the floating inverse is LAPACK's
in both, and the frame's 26-bit rounding can turn a last-bit difference of a sum into one of :math:`2^{-26}`).

Importing this module imports Numba; the first call of a fresh install compiles it into Numba's cache
(``cache=True``), later processes load it.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from .flow_enclosure import _INFLATION, _PICARD_ITERATIONS, MAX_HALVINGS
from .tape_kernel import _down, _up, replay

__all__ = ["advance", "propagate", "strip_update"]

FloatArray = NDArray[np.float64]
Tape = tuple[NDArray[np.int64], FloatArray, NDArray[np.bool_], NDArray[np.int64]]
"""``(program, constants, kinds, outputs)`` of a :class:`~intervalobs.systems.field_tape.FieldTape`."""

_EPS = float(np.finfo(float).eps)
_TINY = float(np.finfo(float).tiny)
_FRAME_BITS, _FRAME_ACCEPT, _FRAME_RESIDUAL = 26, 0.25, 0.25  # flow_enclosure's constants (tested equal)
_FRAME_FLOOR, _FRAME_TINY = 2.0**-500, 2.0**-60


@numba.njit(cache=True, nogil=True, inline="always")
def _hull(a_lo: float, a_hi: float, b_lo: float, b_hi: float) -> tuple[float, float]:
    """The hull of the four products of the ends, a NaN product (``0 * inf``) counted as 0."""
    low, high = np.inf, -np.inf
    for p in (a_lo * b_lo, a_lo * b_hi, a_hi * b_lo, a_hi * b_hi):
        q = 0.0 if math.isnan(p) else p
        low, high = min(low, q), max(high, q)
    return low, high


@numba.njit(cache=True, nogil=True)
def _product(a_lo: FloatArray, a_hi: FloatArray, b_lo: FloatArray, b_hi: FloatArray, out: FloatArray) -> None:
    """``out[0], out[1]`` = the ends of the interval matrix product ``[a] @ [b]`` (``Interval.__matmul__``'s rule)."""
    rows, inner = a_lo.shape
    cols = b_lo.shape[1]
    gamma = (inner + 2) * _EPS
    for i in range(rows):
        for j in range(cols):
            s_lo, s_hi, m_lo, m_hi = 0.0, 0.0, 0.0, 0.0
            for k in range(inner):
                t_lo, t_hi = _hull(a_lo[i, k], a_hi[i, k], b_lo[k, j], b_hi[k, j])
                s_lo += t_lo
                s_hi += t_hi
                m_lo += abs(t_lo)
                m_hi += abs(t_hi)
            low = s_lo - (gamma * m_lo + _TINY)
            high = s_hi + (gamma * m_hi + _TINY)
            out[0, i, j] = -np.inf if math.isnan(low) else _down(low)
            out[1, i, j] = np.inf if math.isnan(high) else _up(high)


@numba.njit(cache=True, nogil=True)
def _fundamental(j_lo: FloatArray, j_hi: FloatArray, n: int, tau: float, out: FloatArray) -> None:
    """The box of :math:`\\Phi(s)`, :math:`s \\in [0, \\tau]` (``flow_enclosure._fundamental_a_priori``), in ``out``."""
    size = j_lo.shape[0]
    lipschitz = 0.0
    for i in range(n):
        row = 0.0
        for j in range(n):
            row += max(-j_lo[i, j], j_hi[i, j])
        lipschitz = max(lipschitz, row)
    growth = _up(math.expm1(tau * lipschitz) * (1.0 + 1e-12))
    for i in range(size):
        for j in range(size):
            radius = 0.0
            if i < n and j < n:
                radius = growth
            elif i < n:
                column = 0.0
                for r in range(n):
                    column = max(column, max(-j_lo[r, j], j_hi[r, j]))
                radius = _up(column * tau * (1.0 + growth) * (1.0 + 1e-12))
            eye = 1.0 if i == j else 0.0
            out[0, i, j], out[1, i, j] = eye - radius, eye + radius
    sweep = np.empty((2, size, size))
    _product(j_lo, j_hi, out[0], out[1], sweep)
    for i in range(size):
        for j in range(size):
            eye = 1.0 if i == j else 0.0
            low = _down(_down(min(0.0, tau * sweep[0, i, j])) + eye)
            high = _up(_up(max(0.0, tau * sweep[1, i, j])) + eye)
            out[0, i, j], out[1, i, j] = max(out[0, i, j], low), min(out[1, i, j], high)


@numba.njit(cache=True, nogil=True)
def _reduce(generators: FloatArray, order: int, frame: bool, persistent: int, out: FloatArray) -> None:
    """``order`` generators (``flow_enclosure.StateZonotope.with_box``'s reduction): the first ``persistent`` as
    they are, then, of the others, the ``order - persistent - N`` of largest Euclidean norm and the box of the rest
    (rounded up), in the axes or (``frame``) in the frame of the largest (:func:`_box_in_frame`)."""
    size = generators.shape[0]
    out[:] = 0.0
    out[:, :persistent] = generators[:, :persistent]
    rest, slots, reduced = generators[:, persistent:], order - persistent, out[:, persistent:]
    count = rest.shape[1]
    if count <= slots:
        reduced[:, :count] = rest
        return
    keep = slots - size
    norms = np.empty(count)
    for j in range(count):
        total = 0.0
        for i in range(size):
            total += rest[i, j] * rest[i, j]
        norms[j] = -math.sqrt(total)
    ranked = np.argsort(norms, kind="mergesort")
    for c in range(keep):
        reduced[:, c] = rest[:, ranked[c]]
    if frame:
        ordered = np.empty((size, count))
        for c in range(count):
            ordered[:, c] = rest[:, ranked[c]]
        columns = min(2 * size, count)
        leading = np.empty((size, size + columns))
        turn = np.argsort(norms[slots - size : slots], kind="mergesort")
        for c in range(size):  # the previous reduction's box, as the step left it, then the largest
            leading[:, c] = rest[:, slots - size + turn[c]]
        leading[:, size:] = ordered[:, :columns]
        if _box_in_frame(ordered, keep, leading, reduced[:, keep:]):
            return
    for i in range(size):
        box = 0.0
        for c in range(keep, count):
            box += abs(rest[i, ranked[c]])
        reduced[i, keep:] = 0.0
        reduced[i, keep + i] = _up(box * (1.0 + 2 * count * _EPS))


@numba.njit(cache=True, nogil=True, inline="always")
def _round_bits(value: float, up: bool) -> float:
    """``value`` with ``_FRAME_BITS`` significant bits, to nearest or (``up``, nonnegative) upward."""
    mantissa, exponent = math.frexp(value)
    scaled = mantissa * 2.0**_FRAME_BITS
    rounded = math.ceil(scaled) if up else math.floor(scaled + 0.5)
    return math.ldexp(rounded * 2.0**-_FRAME_BITS, exponent)


@numba.njit(cache=True, nogil=True)
def _frame(leading: FloatArray) -> FloatArray:
    """The frame of ``flow_enclosure._frame``: candidates accepted by Gram-Schmidt, kept normalised, rounded."""
    size, columns = leading.shape
    basis = np.zeros((size, size))
    frame = np.zeros((size, size))
    found = 0
    vector = np.empty(size)
    residual = np.empty(size)
    coefficients = np.empty(size)
    for j in range(columns + size):
        if found == size:
            break
        for i in range(size):
            vector[i] = leading[i, j] if j < columns else (1.0 if i == j - columns else 0.0)
            residual[i] = vector[i]
        for _ in range(2):  # classical Gram-Schmidt twice
            for k in range(size):
                total = 0.0
                for i in range(size):
                    total += basis[i, k] * residual[i]
                coefficients[k] = total
            for i in range(size):
                total = 0.0
                for k in range(size):
                    total += basis[i, k] * coefficients[k]
                residual[i] = residual[i] - total
        norm, length = 0.0, 0.0
        for i in range(size):
            norm += residual[i] * residual[i]
            length += vector[i] * vector[i]
        norm, length = math.sqrt(norm), math.sqrt(length)
        share = _FRAME_ACCEPT if j < columns else min(_FRAME_ACCEPT, 0.5 / math.sqrt(size))
        if norm > share * length:
            for i in range(size):
                basis[i, found] = residual[i] / norm
                frame[i, found] = vector[i] / length
            found += 1
    for i in range(size):
        for k in range(size):
            value = _round_bits(frame[i, k], False)
            frame[i, k] = 0.0 if abs(value) < _FRAME_TINY else value
    return frame


@numba.njit(cache=True, nogil=True)
def _row_times_column(a: NDArray[np.floating[Any]], b: FloatArray, i: int, j: int) -> tuple[float, float]:
    """The floating sum of :math:`a_{ik}b_{kj}` and of its terms' magnitudes (the product's error scale)."""
    s, m = 0.0, 0.0
    for k in range(a.shape[1]):
        s += a[i, k] * b[k, j]
        m += abs(a[i, k]) * abs(b[k, j])
    return s, m


@numba.njit(cache=True, nogil=True)
def _box_in_frame(ordered: FloatArray, keep: int, leading: FloatArray, out: FloatArray) -> bool:
    """The columns ``keep:`` of ``ordered`` boxed in a frame (``flow_enclosure._reduce_in_frame``), into ``out``.

    Returns False (``out`` untouched) where the frame's verified residual is above ``_FRAME_RESIDUAL`` or a bound
    is not finite: the caller boxes them in the axes.
    """
    size, count = ordered.shape
    frame = _frame(leading)
    for i in range(size):
        for k in range(size):
            if not math.isfinite(frame[i, k]):
                return False
    inverse = np.linalg.inv(frame)
    gamma = (size + 2) * _EPS
    spread = (count - keep) * 2 * _EPS
    total = np.zeros(size)
    reach = 0.0
    for j in range(keep, count):
        largest = 0.0
        for i in range(size):
            s, m = _row_times_column(inverse, ordered, i, j)
            image = _up(abs(s) + (gamma * m + _TINY))
            total[i] += image
            largest = max(largest, image)
        reach += largest
    reach = _up(reach * (1.0 + spread))
    rows = np.empty(size)
    beta = 0.0
    for i in range(size):
        row = 0.0
        for j in range(size):
            s, m = _row_times_column(inverse, frame, i, j)
            loss = _up(abs((1.0 if i == j else 0.0) - s))
            row += _up((loss + (gamma * m + _TINY)) * (1.0 + 2 * _EPS))
        rows[i] = _up(row * (1.0 + 2 * size * _EPS))
        beta = max(beta, rows[i])
    factor = _up(1.0 / _down(1.0 - min(beta, 0.5)))
    scaled = _up(reach * factor)
    radius = np.empty(size)
    for i in range(size):
        bound = _up(_up(total[i] * (1.0 + spread)) + _up(rows[i] * scaled))
        radius[i] = _round_bits(max(bound, _FRAME_FLOOR), True)
        if not math.isfinite(radius[i]):
            return False
    if not beta <= _FRAME_RESIDUAL:
        return False
    for i in range(size):
        for k in range(size):
            out[i, k] = frame[i, k] * radius[k]  # exact: 26-bit factors
    return True


@numba.njit(cache=True, nogil=True)
def _advance_one(
    centre: FloatArray,
    generators: FloatArray,
    centre_end: tuple[FloatArray, FloatArray],
    jacobian: tuple[FloatArray, FloatArray],
    step: tuple[float, int, int, int, int],
    new_centre: FloatArray,
    new_generators: FloatArray,
) -> None:
    """Steps 3-4 of the flow enclosure for one set (see :func:`advance`)."""
    tau, n, order, persistent, frame = step
    j_lo, j_hi = jacobian
    size, count = generators.shape
    half_square = 0.5 * tau * tau
    spread = np.empty((2, size, size))
    _fundamental(j_lo, j_hi, n, tau, spread)
    inner = np.empty((2, size, size))
    _product(j_lo, j_hi, spread[0], spread[1], inner)
    outer = np.empty((2, size, size))
    _product(j_lo, j_hi, inner[0], inner[1], outer)
    phi = np.empty((2, size, size))
    for i in range(size):
        for j in range(size):
            eye = 1.0 if i == j else 0.0
            a_lo, a_hi = min(j_lo[i, j] * tau, j_hi[i, j] * tau), max(j_lo[i, j] * tau, j_hi[i, j] * tau)
            b_lo = min(outer[0, i, j] * half_square, outer[1, i, j] * half_square)
            b_hi = max(outer[0, i, j] * half_square, outer[1, i, j] * half_square)
            low = _down(_down(_down(a_lo) + _down(b_lo)) + eye)
            high = _up(_up(_up(a_hi) + _up(b_hi)) + eye)
            phi[0, i, j], phi[1, i, j] = low, high
    mid = 0.5 * (phi[0] + phi[1])
    moved = np.zeros((size, count))  # in round-to-nearest: what it misses is in the remainder box
    for i in range(size):
        for k in range(size):
            for j in range(count):
                moved[i, j] += mid[i, k] * generators[k, j]
    exact = np.empty((2, size, count))
    _product(mid, mid, generators, generators, exact)
    all_generators = np.zeros((size, count + size))
    all_generators[:, :count] = moved
    gamma_m = (count + 2) * _EPS
    gamma_n = (size + 2) * _EPS
    reach = np.empty(size)  # the unit cube's image under |G| (the set's hull radius), rounded up
    for k in range(size):
        total = 0.0
        for j in range(count):
            total += abs(generators[k, j])
        reach[k] = _up(total + (gamma_m * total + _TINY))
    for i in range(size):
        total = 0.0  # the box of (exact - moved) @ [-1, 1]^m
        for j in range(count):
            total += max(abs(_down(exact[0, i, j] - moved[i, j])), abs(_up(exact[1, i, j] - moved[i, j])))
        exact_reach = _up(total + (gamma_m * total + _TINY))
        s_lo, s_hi, m_lo, m_hi = 0.0, 0.0, 0.0, 0.0  # ([phi] - mid) @ [-reach, reach]
        for k in range(size):
            t_lo, t_hi = _hull(_down(phi[0, i, k] - mid[i, k]), _up(phi[1, i, k] - mid[i, k]), -reach[k], reach[k])
            s_lo, s_hi, m_lo, m_hi = s_lo + t_lo, s_hi + t_hi, m_lo + abs(t_lo), m_hi + abs(t_hi)
        term_lo = _down(s_lo - (gamma_n * m_lo + _TINY))
        term_hi = _up(s_hi + (gamma_n * m_hi + _TINY))
        low = _down(_down(_down(centre_end[0][i] - centre[i]) + term_lo) - exact_reach)
        high = _up(_up(_up(centre_end[1][i] - centre[i]) + term_hi) + exact_reach)
        low, high = _down(low + centre[i]), _up(high + centre[i])  # the box's centre joins the set's centre
        middle = 0.5 * (low + high)
        new_centre[i] = middle
        all_generators[i, count + i] = _up(max(high - middle, middle - low))
    _reduce(all_generators, order, frame == 1, persistent, new_generators)


@numba.njit(cache=True, nogil=True)
def advance(
    centre: FloatArray,
    generators: FloatArray,
    centre_end: tuple[FloatArray, FloatArray],
    jacobian: tuple[FloatArray, FloatArray],
    step: tuple[float, int, int, int, int],
) -> tuple[FloatArray, FloatArray]:
    """Steps 3-4 of :mod:`intervalobs.systems.flow_enclosure` for a batch of sets.

    Parameters
    ----------
    centre : numpy.ndarray, shape (B, N)
        The sets' centres.
    generators : numpy.ndarray, shape (B, N, m)
        Their generators.
    centre_end : tuple of numpy.ndarray, shape (B, N) each
        Lower and upper ends of the box of the centre's trajectory at the end of the step.
    jacobian : tuple of numpy.ndarray, shape (B, N, N) each
        The interval Jacobian over both a priori boxes.
    step : tuple
        ``(tau, n, order, persistent, frame)``: step length, number of states (the rest are parameters), generators
        kept, leading generators never reduced (mapped like the others, then copied as they are), and 1 to box the
        small generators in the frame of the largest (``reduction="frame"``), 0 in the axes.

    Returns
    -------
    centre, generators : numpy.ndarray, shapes (B, N) and (B, N, order)
    """
    batch, size, _ = generators.shape
    order = step[2]
    new_centre = np.empty((batch, size))
    new_generators = np.empty((batch, size, order))
    for b in range(batch):
        _advance_one(
            centre[b],
            generators[b],
            (centre_end[0][b], centre_end[1][b]),
            (jacobian[0][b], jacobian[1][b]),
            step,
            new_centre[b],
            new_generators[b],
        )
    return new_centre, new_generators


@numba.njit(cache=True, nogil=True)
def _dot(a: FloatArray, x: FloatArray) -> tuple[float, float]:
    """Ends of ``a @ x`` for point vectors, padded as ``Interval.__matmul__`` pads a row (outward)."""
    total, magnitude = 0.0, 0.0
    for i in range(a.size):
        term = a[i] * x[i]
        total += term
        magnitude += abs(term)
    pad = (a.size + 2) * _EPS * magnitude + _TINY
    return _down(total - pad), _up(total + pad)


@numba.njit(cache=True, nogil=True)
def _weighted_median(points: FloatArray, weights: FloatArray) -> float:
    """The smallest point at which the cumulative weight (points sorted) reaches half the total."""
    ranked = np.argsort(points)
    total = 0.0
    for r in range(ranked.size):  # summed in the sorted order, as the running sum below
        total += weights[ranked[r]]
    cumulative = 0.0
    for r in range(ranked.size):
        cumulative += weights[ranked[r]]
        if cumulative >= 0.5 * total:
            return points[ranked[r]]
    return points[ranked[-1]]


@numba.njit(cache=True, nogil=True)
def _strip_one(
    centre: FloatArray,
    generators: FloatArray,
    a: FloatArray,
    strip: tuple[float, float],
    out: tuple[FloatArray, FloatArray],
    frame: bool,
) -> bool:
    """The strip update of one set (see :func:`strip_update`); returns whether the intersection is empty."""
    size, count = generators.shape
    image = np.empty((2, count))
    for j in range(count):
        image[0, j], image[1, j] = _dot(a, generators[:, j])
    level_lo, level_hi = _dot(a, centre)
    reach = 0.0
    for j in range(count):
        reach += max(-image[0, j], image[1, j])
    reach = _up(reach * (1.0 + 2 * count * _EPS))
    low, high = max(strip[0], level_lo - reach), min(strip[1], level_hi + reach)
    empty = not (low <= high)
    if empty:
        low, high = level_lo, level_hi
    target = 0.5 * (low + high)
    sigma = _up(max(high - target, target - low))
    row = 0.5 * (image[0] + image[1])
    weights = np.empty(count + 1)
    points = np.zeros(count + 1)
    for j in range(count):
        weights[j] = abs(row[j]) if abs(row[j]) > 0 else 0.0
    weights[count] = sigma
    new = np.zeros((size, count + 1 + size))
    box = np.empty((2, size))
    shift_lo, shift_hi = _down(target - level_hi), _up(target - level_lo)
    for i in range(size):
        for j in range(count):
            points[j] = generators[i, j] / (row[j] if abs(row[j]) > 0 else 1.0)
        points[count] = 0.0
        gain = _weighted_median(points, weights)
        c_lo = _down(_down(min(gain * shift_lo, gain * shift_hi)) + centre[i])
        c_hi = _up(_up(max(gain * shift_lo, gain * shift_hi)) + centre[i])
        slack = 0.0
        for j in range(count):
            p_lo, p_hi = _hull(gain, gain, image[0, j], image[1, j])
            m_lo, m_hi = _down(generators[i, j] - _up(p_hi)), _up(generators[i, j] - _down(p_lo))
            new[i, j] = 0.5 * (m_lo + m_hi)
            slack += 0.5 * (m_hi - m_lo)
        e_lo, e_hi = _down(min(sigma * gain, sigma * gain)), _up(max(sigma * gain, sigma * gain))
        new[i, count] = 0.5 * (e_lo + e_hi)
        slack = _up((slack + 0.5 * (e_hi - e_lo)) * (1.0 + 2 * (count + 1) * _EPS))
        middle = 0.5 * (c_lo + c_hi)
        box[0, i], box[1, i] = c_lo - middle - slack, c_hi - middle + slack
        box[0, i], box[1, i] = _down(box[0, i] + middle), _up(box[1, i] + middle)
    for i in range(size):  # the box joins as one generator per coordinate, its centre moves the centre
        middle = 0.5 * (box[0, i] + box[1, i])
        out[0][i] = middle
        new[i, count + 1 + i] = _up(max(box[1, i] - middle, middle - box[0, i]))
    _reduce(new, out[1].shape[1], frame, 0, out[1])
    return empty


@numba.njit(cache=True, nogil=True)
def strip_update(
    centre: FloatArray,
    generators: FloatArray,
    a: FloatArray,
    strip: tuple[FloatArray, FloatArray],
    order: int,
    frame: bool,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """A zonotope containing each set's intersection with the strip :math:`a^\\top x \\in [s]`, for a batch of sets.

    Parameters
    ----------
    centre : numpy.ndarray, shape (B, N)
    generators : numpy.ndarray, shape (B, N, m)
    a : numpy.ndarray, shape (B, N)
        The strip's normal, per set.
    strip : tuple of numpy.ndarray, shape (B,) each
        Lower and upper ends of :math:`[s]`.
    order : int
        Generators kept.
    frame : bool
        Box the small generators in the frame of the largest (``reduction="frame"``), not in the axes.

    Returns
    -------
    centre, generators : numpy.ndarray, shapes (B, N) and (B, N, order)
    empty : numpy.ndarray of bool, shape (B,)
        The set misses the strip (its centre and generators are then those of the set cut to its own support).
    """
    batch, size, _ = generators.shape
    new_centre = np.empty((batch, size))
    new_generators = np.empty((batch, size, order))
    empty = np.zeros(batch, dtype=np.bool_)
    for b in range(batch):
        empty[b] = _strip_one(
            centre[b], generators[b], a[b], (strip[0][b], strip[1][b]), (new_centre[b], new_generators[b]), frame
        )
    return new_centre, new_generators, empty


@numba.njit(cache=True, nogil=True)
def _field(
    tape: Tape,
    boxes: FloatArray,
    inputs: FloatArray,
    disturbance: tuple[FloatArray, bool],
    rates: FloatArray,
) -> bool:
    """:math:`F = \\tilde f + E[w]` over boxes ``(2, S, N)`` by the tape (``flow_enclosure._Flow.rates``); False
    where the field is undefined on some box (the caller then has no enclosure, as from infinite rates)."""
    program, constants, kinds, outputs = tape
    count, size = program.shape[0], boxes.shape[2]
    work = (np.empty(count), np.empty(count), np.zeros((2, count, 0)))
    out = (np.empty((2, size)), np.zeros((2, size, 0)))
    box, added = disturbance
    for s in range(boxes.shape[1]):
        if not replay(program, (constants, kinds, outputs), (boxes[0, s], boxes[1, s], inputs[s]), work, out):
            return False
        for i in range(size):
            low, high = out[0][0, i], out[0][1, i]
            if added:
                low, high = _down(low + box[0, i]), _up(high + box[1, i])
            rates[0, s, i], rates[1, s, i] = low, high
    return True


@numba.njit(cache=True, nogil=True)
def _motion(start: FloatArray, rates: FloatArray, tau: float, out: FloatArray) -> None:
    """``start + [0, tau] * rates`` (outward rounded, as ``Interval``), into ``out``."""
    for s in range(start.shape[1]):
        for i in range(start.shape[2]):
            low, high = _hull(0.0, tau, rates[0, s, i], rates[1, s, i])
            out[0, s, i], out[1, s, i] = _down(start[0, s, i] + _down(low)), _up(start[1, s, i] + _up(high))


@numba.njit(cache=True, nogil=True)
def _within(box: FloatArray, domain: FloatArray, rows: int, out: FloatArray) -> None:
    """``flow_enclosure._within``: each box cut to its domain (row ``s // rows`` of ``domain``), kept non-empty."""
    for s in range(box.shape[1]):
        for i in range(box.shape[2]):
            low = max(box[0, s, i], domain[0, s // rows, i])
            high = min(box[1, s, i], domain[1, s // rows, i])
            if low <= high:
                out[0, s, i], out[1, s, i] = low, high
            else:
                out[0, s, i], out[1, s, i] = box[0, s, i], box[1, s, i]


@numba.njit(cache=True, nogil=True)
def _picard(
    tape: Tape,
    start: FloatArray,
    inputs: FloatArray,
    field: tuple[tuple[FloatArray, bool], FloatArray, float],
    out: FloatArray,
) -> bool:
    """``flow_enclosure._picard`` for the boxes ``start`` (2, S, N), the same iterations on the whole batch.

    ``field`` is ``((E[w], whether there is one), domains (2, 2, N): the sets' row 0 and the centres' row 1, tau)``;
    the first half of the boxes are the sets', the second the centres'. False: no a priori box found.
    """
    disturbance, domain, tau = field
    rates, guess, candidate, source = np.empty(start.shape), np.empty(start.shape), np.empty(start.shape), start.copy()
    rows = start.shape[1] // 2
    for iteration in range(_PICARD_ITERATIONS + 1):  # iteration 0: the first guess, start + [0, tau] F(start)
        if iteration > 0:
            if not np.all(np.isfinite(guess)):
                return False
            for s in range(start.shape[1]):
                for i in range(start.shape[2]):
                    motion = max(guess[1, s, i] - start[1, s, i], start[0, s, i] - guess[0, s, i])
                    pad = _INFLATION * motion + 1e-12 * (1.0 + abs(0.5 * (guess[0, s, i] + guess[1, s, i])))
                    candidate[0, s, i], candidate[1, s, i] = guess[0, s, i] - pad, guess[1, s, i] + pad
            _within(candidate, domain, rows, source)
        if not _field(tape, source, inputs, disturbance, rates):
            return False
        _motion(start, rates, tau, guess)
        if iteration > 0 and np.all(guess[0] > candidate[0]) and np.all(guess[1] < candidate[1]):
            _within(guess, domain, rows, out)
            return True
    return False


@numba.njit(cache=True, nogil=True)
def _centre_end(
    rates: tuple[FloatArray, FloatArray], jacobian: FloatArray, centre: FloatArray, tau: float, out: FloatArray
) -> None:
    """``c + tau F(c) + tau^2/2 [J_hat] F(hat)`` (``flow_enclosure._step``, step 2), outward rounded, into ``out``.

    ``rates``: the ends (2, N) of :math:`F` over the centre's a priori box and at the centre.
    """
    over, at = rates
    size = centre.size
    half_square = 0.5 * tau * tau
    column = np.empty((2, size, 1))
    _product(jacobian[0], jacobian[1], over[0].reshape((size, 1)), over[1].reshape((size, 1)), column)
    for i in range(size):
        a_lo, a_hi = _hull(at[0, i], at[1, i], tau, tau)
        b_lo, b_hi = _hull(column[0, i, 0], column[1, i, 0], half_square, half_square)
        low = _down(_down(centre[i] + _down(a_lo)) + _down(b_lo))
        high = _up(_up(centre[i] + _up(a_hi)) + _up(b_hi))
        out[0, i], out[1, i] = low, high


@numba.njit(cache=True, nogil=True)
def hull_box(centre: FloatArray, generators: FloatArray, out: FloatArray) -> None:
    """``flow_enclosure.hull_box`` of one set (the row sums in order), into ``out`` (2, N)."""
    count = generators.shape[1]
    for i in range(centre.size):
        total = 0.0
        for j in range(count):
            total += abs(generators[i, j])
        reach = total + ((count + 2) * _EPS * total + _TINY)
        out[0, i], out[1, i] = _down(_down(-reach) + centre[i]), _up(_up(reach) + centre[i])


@numba.njit(cache=True, nogil=True)
def _taped_step(
    tape: Tape,
    zset: tuple[FloatArray, FloatArray, FloatArray],
    field: tuple[tuple[FloatArray, bool], FloatArray, float],
    step: tuple[float, int, int, int, int],
    out: tuple[FloatArray, FloatArray, FloatArray],
) -> int:
    """``flow_enclosure._step`` with the field's tape: 0, or 1 (no a priori box), 2 (a Jacobian undefined)."""
    centre, generators, inputs = zset
    disturbance, _, tau = field
    batch, size = centre.shape
    start = np.empty((2, 2 * batch, size))
    for b in range(batch):
        hull_box(centre[b], generators[b], start[:, b])
        start[0, batch + b], start[1, batch + b] = centre[b], centre[b]
    both_inputs = np.concatenate((inputs, inputs))
    boxes = np.empty(start.shape)
    if not _picard(tape, start, both_inputs, field, boxes):
        return 1
    program, constants, kinds, outputs = tape
    count = program.shape[0]
    work = (np.empty(count), np.empty(count), np.zeros((2, count, size)))
    values, slopes = np.empty((3, 2, size)), np.empty((3, 2, size, size))
    ends = np.empty((2, size))
    for b in range(batch):
        out[2][0, b], out[2][1, b] = boxes[0, b], boxes[1, b]
        lows = (np.minimum(boxes[0, b], boxes[0, batch + b]), boxes[0, batch + b], centre[b])
        highs = (np.maximum(boxes[1, b], boxes[1, batch + b]), boxes[1, batch + b], centre[b])
        for r in range(3):  # the Jacobians over both boxes and over the centre's, the rates over it and at it
            box = (lows[r], highs[r], inputs[b])
            if not replay(program, (constants, kinds, outputs), box, work, (values[r], slopes[r])):
                return 2
            if disturbance[1]:
                for i in range(size):
                    values[r, 0, i] = _down(values[r, 0, i] + disturbance[0][0, i])
                    values[r, 1, i] = _up(values[r, 1, i] + disturbance[0][1, i])
        _centre_end((values[1], values[2]), slopes[1], centre[b], tau, ends)
        jacobian = (slopes[0, 0], slopes[0, 1])
        _advance_one(centre[b], generators[b], (ends[0], ends[1]), jacobian, step, out[0][b], out[1][b])
    return 0


@numba.njit(cache=True, nogil=True)
def propagate(
    tape: Tape,
    zset: tuple[FloatArray, FloatArray, FloatArray],
    field: tuple[tuple[FloatArray, bool], FloatArray],
    interval: tuple[float, int],
    step: tuple[int, int, int, int],
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """:func:`intervalobs.systems.flow_enclosure.propagate` with the field's tape: every step in one call.

    Parameters
    ----------
    tape : tuple
        ``(program, constants, kinds, outputs)`` of a :class:`~intervalobs.systems.field_tape.FieldTape`.
    zset : tuple of numpy.ndarray
        ``(centre, generators, inputs)``, shapes (B, N), (B, N, m), (B, m'): the sets and their held inputs.
    field : tuple
        ``((E[w] (2, N), whether there is one), domains (2, 2, N))``: the ends of the sets' domain (row 0) and of the
        centres' (row 1).
    interval : tuple
        ``(h, substeps)``.
    step : tuple
        ``(n, order, persistent, frame)``: number of states, generators kept, leading generators never reduced, and
        1 to reduce in the frame of the largest generators (``reduction="frame"``), 0 in the axes.

    Returns
    -------
    centre, generators : numpy.ndarray, shapes (B, N) and (B, N, order)
    hull : numpy.ndarray, shape (2, B, N)
        The ends of the hull of the a priori boxes.
    status : int
        0; 1 when no a priori box was found even after ``MAX_HALVINGS`` halvings; 2 when the field's Jacobian is
        undefined on a box.
    """
    centre, generators, inputs = zset
    disturbance, domain = field
    h, substeps = interval
    n, order, persistent, frame = step
    batch, size = centre.shape
    hull = np.empty((2, batch, size))
    out = (np.empty((batch, size)), np.empty((batch, size, order)), np.empty((2, batch, size)))
    remaining, tau, halvings, first = h, h / substeps, 0, True
    while remaining > 0.0:
        tau = min(tau, remaining)
        status = _taped_step(
            tape, (centre, generators, inputs), (disturbance, domain, tau), (tau, n, order, persistent, frame), out
        )
        if status == 2:
            return centre, generators, hull, 2
        if status == 1:
            halvings += 1
            if halvings > MAX_HALVINGS:
                return centre, generators, hull, 1
            tau *= 0.5
            continue
        centre, generators = out[0].copy(), out[1].copy()
        if first:
            hull[:] = out[2]
        else:
            hull[0], hull[1] = np.minimum(hull[0], out[2][0]), np.maximum(hull[1], out[2][1])
        first = False
        remaining = 0.0 if tau >= remaining else remaining - tau
    return centre, generators, hull, 0
