r"""A user's vector field recorded once as a tape of elementary operations, replayed compiled over boxes.

The flow enclosure evaluates :math:`f` over boxes several times a step (the Picard iterations, then one
forward-mode pass for the Jacobians, :mod:`intervalobs.systems.flow_enclosure`); written with NumPy functions on
:class:`~intervalobs.interval.Interval` and :class:`~intervalobs.interval_dual.IntervalDual` objects, each pass
costs tens of microseconds of Python per operation. :func:`trace_field` calls ``f(x, u, p)`` once with
recording objects instead: each ``+ - * /``, unary minus, integer power and NumPy function of the list below
appends one instruction, the states and parameters entering as interval variables, the known inputs as points
(an operation on points only is done in plain floating point, as NumPy does on the input arrays). The tape is
then replayed by :func:`intervalobs.systems.tape_kernel.evaluate`, whose every operation is the Python one step
for step (the same ends bit for bit).

A field that the recording cannot follow is not traced: a Python branch or a conversion on a value
(``if x[0] > 0``, ``float(x[0])``, ``math.exp``), a function outside ``sin cos exp log sqrt arctan absolute
square negative`` (``tanh`` among them: NumPy's differs from the compiled library's by an ulp), a non-integer
power, an array constant, or any exception while recording. A tape is also refused when its replay on probe
boxes (the prior box, its centre, a sub-box; inputs 0 and 1) differs from the Python evaluation in one bit.
Then :func:`trace_field` returns None and the reason, and the caller keeps the Python evaluation: never
unsound, only slower.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import BoundsError
from ..inclusion import VectorFunction
from ..interval import Interval
from ..interval_dual import value_and_jacobian
from .continuous_nonlinear import ContinuousNonlinearSystem

__all__ = ["FieldTape", "kernel_batch", "trace_field"]

FloatArray = NDArray[np.float64]

OPERATIONS = (
    "variable", "input", "constant", "add", "sub", "mul", "div", "neg", "pow",
    "sin", "cos", "exp", "log", "sqrt", "arctan", "absolute",
)  # fmt: skip
"""The instructions of a tape, by code (their index; :mod:`intervalobs.systems.tape_kernel` names them)."""
_UNARY = {np.sin: "sin", np.cos: "cos", np.exp: "exp", np.log: "log", np.sqrt: "sqrt", np.arctan: "arctan"}
_UNARY[np.absolute] = "absolute"
_BINARY = {np.add: "add", np.subtract: "sub", np.multiply: "mul", np.true_divide: "div"}


class _Untraceable(TypeError):
    """An operation the tape cannot record (the field is then evaluated in Python)."""


class _Recorder:
    """The instructions, constants and kinds (interval or point) of the slots recorded so far."""

    def __init__(self) -> None:
        self.program: list[tuple[int, int, int]] = []
        self.constants: list[float] = []
        self.kinds: list[bool] = []

    def push(self, code: str, a: int, b: int, dual: bool, constant: float = 0.0) -> _Node:
        self.program.append((OPERATIONS.index(code), a, b))
        self.constants.append(constant)
        self.kinds.append(dual)
        return _Node(self, len(self.program) - 1)

    def operand(self, value: Any) -> _Node:
        """A recorded slot, or a number recorded as a constant (an array constant is refused)."""
        if isinstance(value, _Node):
            return value
        number = np.asarray(value)
        if number.ndim != 0 or number.dtype.kind not in "iuf":
            raise _Untraceable(f"a constant that is not a number: {type(value).__name__} of shape {number.shape}")
        return self.push("constant", 0, 0, False, float(number))

    def binary(self, code: str, a: Any, b: Any) -> _Node:
        first, second = self.operand(a), self.operand(b)
        return self.push(code, first.slot, second.slot, self.kinds[first.slot] or self.kinds[second.slot])

    def unary(self, code: str, a: _Node, b: int = 0) -> _Node:
        return self.push(code, a.slot, b, self.kinds[a.slot])


class _Node:
    """A recording object: one slot of the tape, with the arithmetic of an :class:`Interval`."""

    __array_priority__ = 3000.0

    def __init__(self, recorder: _Recorder, slot: int) -> None:
        self.recorder, self.slot = recorder, slot

    def __add__(self, other: Any) -> _Node:
        return self.recorder.binary("add", self, other)

    def __radd__(self, other: Any) -> _Node:
        return self.recorder.binary("add", other, self)

    def __sub__(self, other: Any) -> _Node:
        return self.recorder.binary("sub", self, other)

    def __rsub__(self, other: Any) -> _Node:
        return self.recorder.binary("sub", other, self)

    def __mul__(self, other: Any) -> _Node:
        return self.recorder.binary("mul", self, other)

    def __rmul__(self, other: Any) -> _Node:
        return self.recorder.binary("mul", other, self)

    def __truediv__(self, other: Any) -> _Node:
        return self.recorder.binary("div", self, other)

    def __rtruediv__(self, other: Any) -> _Node:
        return self.recorder.binary("div", other, self)

    def __neg__(self) -> _Node:
        return self.recorder.unary("neg", self)

    def __pos__(self) -> _Node:
        return self

    def __pow__(self, exponent: Any) -> _Node:
        if isinstance(exponent, bool) or not isinstance(exponent, (int, np.integer)) or exponent < 0:
            raise _Untraceable(f"a power that is not a nonnegative integer: {exponent!r}")
        return self.recorder.unary("pow", self, int(exponent))

    def __bool__(self) -> bool:
        raise _Untraceable("a branch on a value (a comparison or a truth test)")

    def __eq__(self, other: object) -> bool:
        raise _Untraceable("a comparison of values")

    __ne__ = __eq__
    __hash__ = None  # type: ignore[assignment]

    def __float__(self) -> float:
        raise _Untraceable("a conversion of a value to a float")

    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> _Node:
        if method != "__call__" or kwargs:
            raise _Untraceable(f"numpy.{ufunc.__name__}.{method} with options")
        if ufunc in _BINARY:
            return self.recorder.binary(_BINARY[ufunc], *inputs)
        if ufunc is np.negative:
            return -inputs[0]
        if ufunc is np.square:
            return inputs[0] ** 2
        if ufunc in _UNARY:
            return self.recorder.unary(_UNARY[ufunc], inputs[0])
        raise _Untraceable(f"numpy.{ufunc.__name__}, which the tape does not record")


def kernel_batch(array: Any, lead: tuple[int, ...], tail: tuple[int, ...]) -> FloatArray:
    """``array`` broadcast to ``lead + tail`` and flattened to one writable C-contiguous float batch ``(B, *tail)``:
    how the compiled kernels take sets, boxes and inputs.

    Parameters
    ----------
    array : array_like
        Broadcastable to ``lead + tail``.
    lead, tail : tuple of int
        The batch's leading axes and each item's shape.

    Returns
    -------
    numpy.ndarray, shape ``(prod(lead), *tail)``
    """
    flat = np.broadcast_to(array, (*lead, *tail)).reshape(int(np.prod(lead)), *tail)
    return np.require(flat, dtype=float, requirements=["C", "W"])  # a broadcast view is read-only: then a copy


@dataclass(frozen=True)
class FieldTape:
    """A recorded function of the augmented state and the inputs (the field or the output map), replayed compiled.

    Attributes
    ----------
    program : numpy.ndarray of int64, shape (K, 3)
        Instructions ``(code, a, b)`` (codes: :data:`OPERATIONS`).
    constants : numpy.ndarray, shape (K,)
        The number of each constant slot.
    kinds : numpy.ndarray of bool, shape (K,)
        Whether each slot is an interval (a function of the states and parameters) or a point.
    outputs : numpy.ndarray of int64, shape (q,)
        The slots of the function's components (``n + n_params`` for the augmented field, p for the outputs).
    """

    program: NDArray[np.int64]
    constants: FloatArray
    kinds: NDArray[np.bool_]
    outputs: NDArray[np.int64]

    @property
    def arrays(self) -> tuple[NDArray[np.int64], FloatArray, NDArray[np.bool_], NDArray[np.int64]]:
        """``(program, constants, kinds, outputs)``: the tape as the compiled kernels take it."""
        return self.program, self.constants, self.kinds, self.outputs

    def evaluate(
        self, lower: FloatArray, upper: FloatArray, u: FloatArray, derivative: bool = False
    ) -> tuple[Interval, Interval | None]:
        """The function's box over boxes (and its Jacobian's, with ``derivative``), as the Python path gives them.

        Parameters
        ----------
        lower, upper : numpy.ndarray, shape (..., n + n_params)
            Boxes of the augmented state.
        u : numpy.ndarray, shape (..., m)
            Known inputs (broadcast against the boxes' leading axes).
        derivative : bool
            Also the Jacobian (:func:`intervalobs.interval_dual.value_and_jacobian`'s).

        Returns
        -------
        value : Interval, shape (..., q)
        jacobian : Interval, shape (..., q, n + n_params), or None without ``derivative``

        Raises
        ------
        BoundsError
            Where the Python evaluation raises: a divisor containing 0, ``log`` or ``sqrt`` of a box below 0.
        """
        from . import tape_kernel  # Numba is imported only where a record is long enough to pay for it

        lead, size = lower.shape[:-1], lower.shape[-1]
        flat = (
            kernel_batch(lower, lead, (size,)),
            kernel_batch(upper, lead, (size,)),
            kernel_batch(u, lead, u.shape[-1:]),
        )
        value, jacobian, ok = tape_kernel.evaluate(
            self.program, (self.constants, self.kinds, self.outputs), flat, derivative
        )
        if not ok.all():
            raise BoundsError("the vector field is undefined on a box (a divisor containing 0, log or sqrt below 0)")
        rows = self.outputs.size
        box = Interval._raw(value[:, 0].reshape(*lead, rows), value[:, 1].reshape(*lead, rows))
        if not derivative:
            return box, None
        return box, Interval._raw(jacobian[:, 0].reshape(*lead, rows, size), jacobian[:, 1].reshape(*lead, rows, size))


def _record(function: Callable[[list[Any], list[Any]], Sequence[Any]], size: int, m: int) -> FieldTape:
    """Call ``function(z, u)`` once on recording objects (raises what the recording cannot follow)."""
    recorder = _Recorder()
    z = [recorder.push("variable", j, 0, True) for j in range(size)]
    u = [recorder.push("input", j, 0, False) for j in range(m)]
    with np.errstate(all="ignore"):
        outputs = [recorder.operand(c).slot for c in function(z, u)]
    return FieldTape(
        np.array(recorder.program, dtype=np.int64).reshape(-1, 3),
        np.array(recorder.constants),
        np.array(recorder.kinds, dtype=bool),
        np.array(outputs, dtype=np.int64),
    )


def _probe(
    tape: FieldTape, python: Callable[[FloatArray], VectorFunction], box: tuple[FloatArray, FloatArray], m: int
) -> str | None:
    """Why the tape's replay differs from ``python(u)``'s evaluation on probe boxes (None: identical, bit for bit)."""
    lower, upper = box
    middle = 0.5 * (lower + upper)
    boxes = (np.stack([lower, middle, lower + 0.25 * (upper - lower)]), np.stack([upper, middle, middle]))
    for level in (0.0, 1.0):
        u = np.full((3, m), level)
        try:
            with np.errstate(all="ignore"):
                expected = value_and_jacobian(python(u), *boxes, tape.outputs.size)
        except (BoundsError, ZeroDivisionError, FloatingPointError):
            expected = None
        try:
            replay = tape.evaluate(*boxes, u, derivative=True)
        except BoundsError:
            replay = None
        if expected is None or replay is None:
            if (expected is None) != (replay is None):
                return f"the replay and the Python evaluation disagree on whether it is defined (inputs {level})"
            continue
        for name, mine, theirs in zip(("value", "Jacobian"), replay, expected, strict=True):
            assert mine is not None
            pairs = ((mine.lower, theirs.lower), (mine.upper, theirs.upper))
            if not all(np.array_equal(a, b, equal_nan=True) for a, b in pairs):
                return f"the replay's {name} differs from the Python evaluation's (inputs {level})"
    return None


def trace_field(
    system: ContinuousNonlinearSystem, lower: FloatArray, upper: FloatArray, output: bool = False
) -> tuple[FieldTape | None, str]:
    """Record the system's augmented field (or output map) as a tape, checked against the Python evaluation.

    Parameters
    ----------
    system : ContinuousNonlinearSystem
    lower, upper : numpy.ndarray, shape (n + n_params,)
        The probe box of the augmented state (finite ends; the prior box of states and parameters).
    output : bool
        Record the output map :math:`g(x, u)` of the augmented state
        (:meth:`~intervalobs.systems.continuous_nonlinear.ContinuousNonlinearSystem.output_map`) instead of the
        field :math:`(f(x, u, \\theta), 0)`.

    Returns
    -------
    tape : FieldTape or None
        None where the function cannot be recorded or its replay differs (module docstring).
    reason : str
        ``"recorded"``, or why the Python evaluation is kept.
    """
    n, size = system.n, system.n + system.n_params

    def augmented(z: list[Any], u: list[Any]) -> list[Any]:
        rates = list(system.f(z[:n], u, z[n:]))
        if len(rates) != n:
            raise _Untraceable(f"f returned {len(rates)} components, not {n}")
        return rates + [0.0] * system.n_params

    def observed(z: list[Any], u: list[Any]) -> list[Any]:
        return list(system.g(z[:n], u))

    try:
        tape = _record(observed if output else augmented, size, system.m)
    except Exception as error:  # anything the recording cannot follow keeps the Python path
        return None, f"not recorded: {type(error).__name__}: {error}"
    python = system.output_map if output else system.augmented_field
    probe = (np.asarray(lower, dtype=float), np.asarray(upper, dtype=float))
    mismatch = _probe(tape, python, probe, system.m)
    return (None, f"not used: {mismatch}") if mismatch else (tape, "recorded")
