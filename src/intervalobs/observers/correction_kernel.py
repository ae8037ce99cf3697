r"""The compiled correction of :class:`~intervalobs.observers.continuous_nonlinear.ContinuousNonlinearObserver` at one
sample, with the output map recorded as a tape (:mod:`intervalobs.systems.field_tape`).

:func:`correct` is ``ContinuousNonlinearObserver._correct`` (with ``_domain_contract``) for a batch of sets in one
call: the contraction by the state domain and the parameter box, then for each output the mean-value strip
:math:`a^\top z \in [y_i] - [v_i] - g_i(c) - [J - a]G\xi + a^\top c` and the strip update
(:func:`intervalobs.systems.flow_kernel.strip_update`'s), in the same order and with the same batch-wide decisions
(a domain end is used for every set where it cuts one). Its interval operations are those of
:class:`~intervalobs.interval.Interval` (outward rounded, the dot-product bound on row sums); the tape replays
:math:`g` and its Jacobian with the Python evaluation's ends. Sums run in order, where NumPy sums pairwise: the
sets agree with the Python path's to the order of a few sums (``tests/test_field_tape.py``).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from ..systems.flow_kernel import _EPS, Tape, _dot, _down, _product, _strip_one, _up, hull_box
from ..systems.tape_kernel import replay

__all__ = ["correct"]

FloatArray = NDArray[np.float64]


@numba.njit(cache=True, nogil=True)
def _contract_domain(
    zset: tuple[FloatArray, FloatArray],
    empty: NDArray[np.bool_],
    limits: tuple[FloatArray, FloatArray, NDArray[np.int64], float],
    frame: bool,
) -> None:
    """``_domain_contract``: each limited coordinate's strip ``[low_i, high_i]``, on every set where one set crosses
    it by more than ``negligible`` of its width; a set found empty keeps its last zonotope (in place)."""
    centre, generators = zset
    low, high, limited, negligible = limits
    batch, size = centre.shape
    hull = np.empty((batch, 2, size))
    stale = True
    new_centre, new_generators = np.empty(size), np.empty(generators.shape[1:])
    for i in limited:
        if stale:
            for b in range(batch):
                hull_box(centre[b], generators[b], hull[b])
            stale = False
        crossing = False
        for b in range(batch):
            slack = negligible * (hull[b, 1, i] - hull[b, 0, i])
            crossing = crossing or hull[b, 0, i] < low[i] - slack or hull[b, 1, i] > high[i] + slack
        if not crossing:
            continue
        row = np.zeros(size)
        row[i] = 1.0
        for b in range(batch):
            now = _strip_one(centre[b], generators[b], row, (low[i], high[i]), (new_centre, new_generators), frame)
            empty[b] = empty[b] or now
            if not empty[b]:
                centre[b] = new_centre
                generators[b] = new_generators
        stale = True


@numba.njit(cache=True, nogil=True)
def _strip(
    values: FloatArray, slopes: FloatArray, zset: tuple[FloatArray, FloatArray], measured: tuple[float, float, float]
) -> tuple[FloatArray, float, float]:
    """The mean-value strip of one output of one set: its normal ``a`` and the ends of ``[s]`` (``_correct``).

    ``values`` (2, 2): the output's ends over the hull (row 0) and at the centre (row 1); ``slopes`` (2, N): its
    gradient's ends over the hull; ``measured``: ``(y_i, v_lo, v_hi)``.
    """
    centre, generators = zset
    size, count = generators.shape
    a = 0.5 * (slopes[0] + slopes[1])
    spread = np.empty((2, 1, size))
    for k in range(size):
        spread[0, 0, k], spread[1, 0, k] = _down(slopes[0, k] - a[k]), _up(slopes[1, k] - a[k])
    image = np.empty((2, 1, count))
    _product(spread[0], spread[1], generators, generators, image)
    reach = 0.0
    for j in range(count):
        reach += max(-image[0, 0, j], image[1, 0, j])
    reach = _up(reach * (1.0 + 2 * count * _EPS))
    level_lo, level_hi = _dot(a, centre)
    y, v_lo, v_hi = measured
    low, high = _down(_down(y - v_hi) - values[1, 1]), _up(_up(y - v_lo) - values[1, 0])
    low, high = _down(_down(low - reach) + level_lo), _up(_up(high + reach) + level_hi)
    return a, low, high


@numba.njit(cache=True, nogil=True)
def correct(
    tape: Tape,
    zset: tuple[FloatArray, FloatArray],
    data: tuple[FloatArray, FloatArray, FloatArray],
    limits: tuple[FloatArray, FloatArray, NDArray[np.int64], float],
    frame: bool,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_], bool]:
    """The observer's correction at one sample for a batch of sets (module docstring).

    Parameters
    ----------
    tape : tuple
        ``(program, constants, kinds, outputs)`` of the output map's :class:`~intervalobs.systems.field_tape.FieldTape`.
    zset : tuple of numpy.ndarray
        ``(centre, generators)``, shapes (B, N) and (B, N, order).
    data : tuple of numpy.ndarray
        ``(y, u, v)``: the measurements (B, p), the inputs (B, m) and the noise box's ends (2, p).
    limits : tuple
        ``(low, high, limited, negligible)``: the domain and parameter box (N,) each, the coordinates with a finite
        end, and the fraction of a set's width below which a crossing is left.
    frame : bool
        Reduce the generators in the frame of the largest (``reduction="frame"``), not in the axes.

    Returns
    -------
    centre, generators : numpy.ndarray
        The contracted sets (a set found empty keeps its last zonotope).
    empty : numpy.ndarray of bool, shape (B,)
        The sets that the data or the domain contradict.
    ok : bool
        False where the output map is undefined on a set's hull (the Python path raises there).
    """
    program, constants, kinds, outputs = tape
    y, u, noise = data
    centre, generators = zset[0].copy(), zset[1].copy()
    batch, size = centre.shape
    empty = np.zeros(batch, dtype=np.bool_)
    _contract_domain((centre, generators), empty, limits, frame)
    count, rows = program.shape[0], outputs.size
    work = (np.empty(count), np.empty(count), np.zeros((2, count, size)))
    values, slopes = np.empty((2, 2, rows)), np.empty((2, 2, rows, size))
    hull = np.empty((2, size))
    new_centre, new_generators = np.empty(size), np.empty(generators.shape[1:])
    for i in range(rows):
        for b in range(batch):
            hull_box(centre[b], generators[b], hull)
            boxes = ((hull[0], hull[1], u[b]), (centre[b], centre[b], u[b]))
            for r in range(2):  # the Jacobian over the hull, the value at the centre
                if not replay(program, (constants, kinds, outputs), boxes[r], work, (values[r], slopes[r])):
                    return centre, generators, empty, False
            row = values[:, :, i].copy()
            a, low, high = _strip(row, slopes[0, :, i], (centre[b], generators[b]), (y[b, i], noise[0, i], noise[1, i]))
            now = _strip_one(centre[b], generators[b], a, (low, high), (new_centre, new_generators), frame)
            empty[b] = empty[b] or now
            if not empty[b]:
                centre[b] = new_centre
                generators[b] = new_generators
        _contract_domain((centre, generators), empty, limits, frame)
    return centre, generators, empty, True
