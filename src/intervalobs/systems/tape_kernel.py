r"""The compiled replay of a recorded vector field (:mod:`intervalobs.systems.field_tape`) over boxes.

:func:`evaluate` runs a tape, one instruction per elementary operation, for a batch of boxes: the natural
interval extension and, when asked, the forward-mode interval derivative (the rules of
:mod:`intervalobs.interval_dual`). Each operation here is the one of :class:`~intervalobs.interval.Interval`
or :class:`~intervalobs.interval_dual.IntervalDual`, step for step: the same products (the hull of the four
products of the ends, ``0 * inf = 0``), the same sums, the same library functions, each end moved outward by
the same number of floating-point numbers (``nextafter``), the same exact zeros kept in the derivative. So the
replay gives the Python evaluation's ends bit for bit wherever Numba's library functions are NumPy's
(``tests/test_field_tape.py`` checks it, and :func:`intervalobs.systems.field_tape.trace_field` checks it on
probe boxes before a tape is used); where they are not, each end is still within the policy of
:mod:`intervalobs.interval` (a function accurate to one ulp, moved two), so the replay is sound on its own.

An operation the Python path refuses (a divisor containing 0, ``log`` or ``sqrt`` below 0) sets the box's
status instead of raising; the caller raises or widens as the Python path does.

Importing this module imports Numba; the first call of a fresh install compiles it into Numba's cache
(``cache=True``), later processes load it. :mod:`intervalobs.systems.flow_kernel` and
:mod:`intervalobs.observers.correction_kernel` compile this interpreter into their own cached code, which Numba
does not invalidate when only this file changes: remove the caches after editing it (``make clean``).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic
from numpy.typing import NDArray

from .field_tape import OPERATIONS

__all__ = ["evaluate"]

FloatArray = NDArray[np.float64]

(VARIABLE, INPUT, CONSTANT, ADD, SUB, MUL, DIV, NEG, POW, SIN, COS, EXP, LOG, SQRT, ARCTAN, ABS) = range(
    len(OPERATIONS)
)
"""The codes of :data:`intervalobs.systems.field_tape.OPERATIONS`, in its order, for an instruction ``(code, a,
b)``: ``a``, ``b`` are earlier slots (``a`` the variable or input index for ``VARIABLE``/``INPUT``, ``b`` the
exponent for ``POW``)."""

_EPS = float(np.finfo(float).eps)
_TWO_PI = 2.0 * np.pi
_PERIOD_SLACK = 1e-9


def _bitcast(source: Any, target: Any) -> Any:
    """A Numba intrinsic reinterpreting the 64 bits of a ``source`` value as a ``target`` one (no conversion)."""

    def typed(typingctx: Any, x: Any) -> Any:
        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            return builder.bitcast(args[0], context.get_value_type(target))

        return target(source), codegen

    return intrinsic(typed)


_bits: Any = _bitcast(types.float64, types.int64)
"""The IEEE 754 bits of a float64 as an int64."""
_float: Any = _bitcast(types.int64, types.float64)
"""The float64 of IEEE 754 bits (the inverse of ``_bits``)."""


@numba.njit(cache=True, nogil=True, inline="always")
def _up(x: float) -> float:
    """``np.nextafter(x, inf)`` by the bits: the next float64 up (NaN and +inf kept, ±0 to the smallest subnormal)."""
    if x != x or x == np.inf:
        return x
    if x == 0.0:
        return _float(1)
    return _float(_bits(x) + 1) if x > 0.0 else _float(_bits(x) - 1)


@numba.njit(cache=True, nogil=True, inline="always")
def _down(x: float) -> float:
    """``np.nextafter(x, -inf)``: the next float64 down (:func:`_up` mirrored)."""
    return -_up(-x)


@numba.njit(cache=True, nogil=True)
def _mul(a_lo: float, a_hi: float, b_lo: float, b_hi: float) -> tuple[float, float]:
    """``Interval.__mul__``: the hull of the four products (a NaN product counted as 0), one ulp outward."""
    low, high = np.inf, -np.inf
    for p in (a_lo * b_lo, a_lo * b_hi, a_hi * b_lo, a_hi * b_hi):
        q = 0.0 if math.isnan(p) else p
        low, high = min(low, q), max(high, q)
    return _down(low), _up(high)


@numba.njit(cache=True, nogil=True)
def _power(x: float, k: int) -> float:
    """``x ** k`` as NumPy computes it on an array (a square by multiplication, other powers by ``pow``)."""
    if k == 2:
        return x * x
    if k == 1:
        return x
    return math.pow(x, float(k))


@numba.njit(cache=True, nogil=True)
def _pow(lo: float, hi: float, k: int) -> tuple[float, float]:
    """``Interval.__pow__`` for an integer ``k >= 0``."""
    if k == 0:
        return 1.0, 1.0
    lo_p, hi_p = _power(lo, k), _power(hi, k)
    if k % 2 == 1:
        return _down(_down(lo_p)), _up(_up(hi_p))
    low = 0.0 if lo <= 0.0 <= hi else min(lo_p, hi_p)
    return max(_down(_down(low)), 0.0), _up(_up(max(lo_p, hi_p)))


@numba.njit(cache=True, nogil=True)
def _contains_point(lo: float, hi: float, offset: float) -> bool:
    """``interval._contains_point`` with the period :math:`2\\pi`."""
    slack = _PERIOD_SLACK * (1.0 + abs(lo))
    k = np.ceil((lo - slack - offset) / _TWO_PI)
    return offset + k * _TWO_PI <= hi + slack


@numba.njit(cache=True, nogil=True)
def _trig(lo: float, hi: float, cosine: bool) -> tuple[float, float]:
    """``interval._trig``: sin (or cos) at the ends, widened to ±1 where an extremum lies inside."""
    finite = math.isfinite(lo) and math.isfinite(hi)
    lo_f, hi_f = (lo, hi) if finite else (0.0, 0.0)
    f_lo, f_hi = (np.cos(lo_f), np.cos(hi_f)) if cosine else (np.sin(lo_f), np.sin(hi_f))
    top, bottom = (0.0, np.pi) if cosine else (0.5 * np.pi, -0.5 * np.pi)
    low, high = min(f_lo, f_hi), max(f_lo, f_hi)
    full = (not finite) or (hi_f - lo_f >= _TWO_PI)
    if full or _contains_point(lo_f, hi_f, top):
        high = 1.0
    if full or _contains_point(lo_f, hi_f, bottom):
        low = -1.0
    return max(_down(_down(low)) - _EPS, -1.0), min(_up(_up(high)) + _EPS, 1.0)


@numba.njit(cache=True, nogil=True)
def _monotone(lo: float, hi: float, code: int) -> tuple[float, float]:
    """``interval._monotone``: an increasing function at the ends, two ulps outward."""
    if code == EXP:
        f_lo, f_hi = np.exp(lo), np.exp(hi)
    elif code == LOG:
        f_lo, f_hi = np.log(lo), np.log(hi)
    elif code == SQRT:
        f_lo, f_hi = np.sqrt(lo), np.sqrt(hi)
    else:
        f_lo, f_hi = np.arctan(lo), np.arctan(hi)
    return _down(_down(f_lo)), _up(_up(f_hi))


@numba.njit(cache=True, nogil=True)
def _reciprocal_nonnegative(lo: float, hi: float) -> tuple[float, float]:
    """``interval_dual._reciprocal_nonnegative``: ``1/x`` for ``x >= 0``, upper end ``+inf`` where x reaches 0."""
    low = max(_down(1.0 / hi), 0.0)
    return low, (_up(1.0 / lo) if lo > 0 else np.inf)


@numba.njit(cache=True, nogil=True)
def _point(code: int, a: float, b: float, k: int) -> float:
    """An operation on points (known inputs, constants): plain floating point, as NumPy on arrays."""
    if code == ADD:
        return a + b
    if code == SUB:
        return a - b
    if code == MUL:
        return a * b
    if code == DIV:
        return a / b
    if code == NEG:
        return -a
    if code == POW:
        return 1.0 if k == 0 else _power(a, k)
    if code == SIN:
        return np.sin(a)
    if code == COS:
        return np.cos(a)
    if code == EXP:
        return np.exp(a)
    if code == LOG:
        return np.log(a)
    if code == SQRT:
        return np.sqrt(a)
    if code == ARCTAN:
        return np.arctan(a)
    return abs(a)


@numba.njit(cache=True, nogil=True)
def _binary(code: int, a_lo: float, a_hi: float, b_lo: float, b_hi: float) -> tuple[float, float, bool]:
    """``+ - * /`` of :class:`~intervalobs.interval.Interval` (a point as the interval of itself); False: refused."""
    if code == ADD:
        return _down(a_lo + b_lo), _up(a_hi + b_hi), True
    if code == SUB:
        return _down(a_lo - b_hi), _up(a_hi - b_lo), True
    if code == MUL:
        low, high = _mul(a_lo, a_hi, b_lo, b_hi)
        return low, high, True
    if b_lo <= 0.0 <= b_hi:  # Interval.reciprocal refuses a divisor containing 0
        return 0.0, 0.0, False
    low, high = _mul(a_lo, a_hi, _down(1.0 / b_hi), _up(1.0 / b_lo))
    return low, high, True


@numba.njit(cache=True, nogil=True, inline="always")
def _keep_zeros(d: FloatArray, k: int, j: int, sources: tuple[int, int]) -> None:
    """``interval_dual._keep_zeros``: entry ``j`` of slot ``k``'s derivative an exact 0 where both sources' are."""
    a, b = sources
    if d[0, a, j] == 0.0 and d[1, a, j] == 0.0 and d[0, b, j] == 0.0 and d[1, b, j] == 0.0:
        d[0, k, j], d[1, k, j] = 0.0, 0.0


@numba.njit(cache=True, nogil=True)
def _binary_derivative(
    code: int, slots: tuple[int, int, int], kinds: NDArray[np.bool_], lo: FloatArray, hi: FloatArray, d: FloatArray
) -> None:
    """The derivative rule of :class:`~intervalobs.interval_dual.IntervalDual` for ``+ - * /`` (into ``d[:, k]``).

    ``d`` has shape ``(2, slots, n)``: lower and upper ends of each slot's derivative box.
    """
    k, a, b = slots
    dual_a, dual_b = kinds[a], kinds[b]
    src = a if dual_a else b  # the dual operand (the first where both are)
    other = b if dual_a and dual_b else src
    for j in range(d.shape[2]):
        if code == ADD or code == SUB:
            if dual_a and dual_b:
                low, high, _ = _binary(code, d[0, a, j], d[1, a, j], d[0, b, j], d[1, b, j])
            elif dual_a or code == ADD:
                low, high = d[0, src, j], d[1, src, j]
            else:  # point - dual: the derivative negated
                low, high = -d[1, src, j], -d[0, src, j]
        elif code == MUL:
            if dual_a and dual_b:
                p_lo, p_hi = _mul(d[0, a, j], d[1, a, j], lo[b], hi[b])
                q_lo, q_hi = _mul(lo[a], hi[a], d[0, b, j], d[1, b, j])
                low, high = _down(p_lo + q_lo), _up(p_hi + q_hi)
            else:
                c = b if dual_a else a
                low, high = _mul(d[0, src, j], d[1, src, j], lo[c], hi[c])
        elif dual_a:  # dual / dual, dual / point: (u' - Q v') / V
            r_lo, r_hi = _down(1.0 / hi[b]), _up(1.0 / lo[b])
            low, high = d[0, src, j], d[1, src, j]
            if dual_b:
                p_lo, p_hi = _mul(lo[k], hi[k], d[0, b, j], d[1, b, j])
                low, high = _down(low - p_hi), _up(high - p_lo)
            low, high = _mul(low, high, r_lo, r_hi)
        else:  # point / dual: -(v' (Q / V))
            s_lo, s_hi = _mul(lo[k], hi[k], _down(1.0 / hi[b]), _up(1.0 / lo[b]))
            p_lo, p_hi = _mul(d[0, src, j], d[1, src, j], s_lo, s_hi)
            low, high = -p_hi, -p_lo
        d[0, k, j], d[1, k, j] = low, high
        if (code != ADD and code != SUB) or (dual_a and dual_b):
            _keep_zeros(d, k, j, (src, other))


@numba.njit(cache=True, nogil=True)
def _unary(code: int, lo: float, hi: float, k: int) -> tuple[float, float, float, float, bool]:
    """The value and the slope box (derivative of the function) of a unary operation; False: refused."""
    if code == POW:
        v_lo, v_hi = _pow(lo, hi, k)
        if k == 0:
            return v_lo, v_hi, 0.0, 0.0, True
        s_lo, s_hi = _pow(lo, hi, k - 1)
        s_lo, s_hi = _mul(s_lo, s_hi, float(k), float(k))
        return v_lo, v_hi, s_lo, s_hi, True
    if code == SIN or code == COS:
        v_lo, v_hi = _trig(lo, hi, code == COS)
        s_lo, s_hi = _trig(lo, hi, code == SIN)
        return (v_lo, v_hi, s_lo, s_hi, True) if code == SIN else (v_lo, v_hi, -s_hi, -s_lo, True)
    if code == ABS:
        a, b = abs(lo), abs(hi)
        low = 0.0 if lo <= 0.0 <= hi else min(a, b)
        return low, max(a, b), (1.0 if lo > 0 else -1.0), (-1.0 if hi < 0 else 1.0), True
    if (code == LOG or code == SQRT) and lo < 0.0:
        return 0.0, 0.0, 0.0, 0.0, False
    v_lo, v_hi = _monotone(lo, hi, code)
    if code == EXP:
        return v_lo, v_hi, v_lo, v_hi, True
    if code == LOG:
        s_lo, s_hi = _reciprocal_nonnegative(lo, hi)
    elif code == SQRT:
        s_lo, s_hi = _reciprocal_nonnegative(v_lo, v_hi)
        s_lo, s_hi = _mul(s_lo, s_hi, 0.5, 0.5)
    else:  # arctan: 1 / (1 + U^2)
        q_lo, q_hi = _pow(lo, hi, 2)
        s_lo, s_hi = _down(1.0 / _up(q_hi + 1.0)), _up(1.0 / _down(q_lo + 1.0))
    return v_lo, v_hi, s_lo, s_hi, True


@numba.njit(cache=True, nogil=True)
def _run(
    program: NDArray[np.int64],
    tape: tuple[FloatArray, NDArray[np.bool_]],
    box: tuple[FloatArray, FloatArray, FloatArray],
    work: tuple[FloatArray, FloatArray, FloatArray],
    derivative: bool,
) -> bool:
    """One box through the tape: every slot's value (``lo``, ``hi``) and derivative ``d``; False: refused."""
    constants, kinds = tape
    lower, upper, inputs = box
    lo, hi, d = work
    for k in range(program.shape[0]):
        code, a, b = program[k, 0], program[k, 1], program[k, 2]
        if code == VARIABLE:
            lo[k], hi[k] = lower[a], upper[a]
            if derivative:
                d[:, k] = 0.0
                d[:, k, a] = 1.0
        elif code == INPUT:
            lo[k] = hi[k] = inputs[a]
        elif code == CONSTANT:
            lo[k] = hi[k] = constants[k]
        elif not kinds[k]:  # every operand a point: plain floating point
            lo[k] = hi[k] = _point(code, lo[a], lo[b] if code <= DIV else 0.0, b)
        elif code == ADD or code == SUB or code == MUL or code == DIV:
            lo[k], hi[k], ok = _binary(code, lo[a], hi[a], lo[b], hi[b])
            if not ok:
                return False
            if derivative:
                _binary_derivative(code, (k, a, b), kinds, lo, hi, d)
        elif code == NEG:
            lo[k], hi[k] = -hi[a], -lo[a]
            if derivative:
                d[0, k], d[1, k] = -d[1, a], -d[0, a]
        else:
            lo[k], hi[k], s_lo, s_hi, ok = _unary(code, lo[a], hi[a], b)
            if not ok:
                return False
            if derivative:
                for j in range(d.shape[2]):
                    if code == POW and b == 0:
                        d[0, k, j], d[1, k, j] = 0.0, 0.0
                        continue
                    d[0, k, j], d[1, k, j] = _mul(d[0, a, j], d[1, a, j], s_lo, s_hi)
                    _keep_zeros(d, k, j, (a, a))
    return True


@numba.njit(cache=True, nogil=True)
def replay(
    program: NDArray[np.int64],
    tape: tuple[FloatArray, NDArray[np.bool_], NDArray[np.int64]],
    box: tuple[FloatArray, FloatArray, FloatArray],
    work: tuple[FloatArray, FloatArray, FloatArray],
    out: tuple[FloatArray, FloatArray],
) -> bool:
    """One box through the tape (see :func:`evaluate`): the outputs' ends into ``out[0]`` (shape (2, p)) and, where
    ``work[2]`` has columns, their Jacobian's into ``out[1]`` (shape (2, p, n)); False where an operation was refused.
    """
    constants, kinds, outputs = tape
    d = work[2]
    derivative = d.shape[2] > 0
    ok = _run(program, (constants, kinds), box, work, derivative)
    for r in range(outputs.size):
        s = outputs[r]
        out[0][0, r], out[0][1, r] = work[0][s], work[1][s]
        if derivative:
            if kinds[s]:
                out[1][:, r] = d[:, s]
            else:
                out[1][:, r] = 0.0
    return ok


@numba.njit(cache=True, nogil=True)
def evaluate(
    program: NDArray[np.int64],
    tape: tuple[FloatArray, NDArray[np.bool_], NDArray[np.int64]],
    box: tuple[FloatArray, FloatArray, FloatArray],
    derivative: bool,
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Replay a tape over a batch of boxes: the value boxes and, with ``derivative``, the Jacobian boxes.

    Parameters
    ----------
    program : numpy.ndarray of int64, shape (K, 3)
        The instructions ``(code, a, b)``; instruction ``k`` writes slot ``k``.
    tape : tuple
        ``(constants, kinds, outputs)``: the constant of each ``CONSTANT`` slot (shape (K,)), whether each slot is
        an interval (True) or a point, and the slots returned (shape (p,)).
    box : tuple of numpy.ndarray
        ``(lower, upper, inputs)``: the boxes, shape (B, n) each, and the known inputs, shape (B, m).
    derivative : bool
        Also the derivative boxes (forward mode, seeded with the identity).

    Returns
    -------
    value : numpy.ndarray, shape (B, 2, p)
        Lower and upper ends of the outputs.
    jacobian : numpy.ndarray, shape (B, 2, p, n)
        Lower and upper ends of their Jacobians (zeros without ``derivative``).
    ok : numpy.ndarray of bool, shape (B,)
        False where an operation was refused (a divisor containing 0, ``log``/``sqrt`` below 0).
    """
    outputs = tape[2]
    lower, upper, inputs = box
    batch, size = lower.shape
    count = program.shape[0]
    value = np.zeros((batch, 2, outputs.size))
    jacobian = np.zeros((batch, 2, outputs.size, size))
    ok = np.ones(batch, dtype=np.bool_)
    work = (np.empty(count), np.empty(count), np.zeros((2, count, size if derivative else 0)))
    for i in range(batch):
        ok[i] = replay(program, tape, (lower[i], upper[i], inputs[i]), work, (value[i], jacobian[i]))
    return value, jacobian, ok
