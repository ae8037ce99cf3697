r"""The boxes of a model's unknowns: initial state, process disturbance, measurement noise.

Every model of the package has the same three kinds of bounded unknowns,

.. math::

    \underline{x}_0 \le x(t_0) \le \overline{x}_0,\qquad
    \underline{w} \le w(t) \le \overline{w},\qquad
    \underline{v} \le v(t_k) \le \overline{v},

with :math:`w` the additive disturbance of the state equation (the ``w`` of :class:`LTISystem` and
:class:`NonlinearSystem`, the ``d`` of Rotondo et al. and of the sampled-output high-gain paper) and :math:`v` the
noise of the measurements. The user writes them once as :class:`Bounds` (scalars are broadcast, absent noises are zero);
:meth:`Bounds.resolve` checks them against a model *once*, at the boundary of a design or a
simulation, and returns :class:`ResolvedBounds`, whose three boxes are always present, have the
model's sizes and give their centres and radii. Everything behind the boundary takes the resolved
object.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import BoundsError, DimensionError

__all__ = ["Bounds", "BoxPair", "ResolvedBounds"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]
"""``(lower, upper)`` arrays of one box."""
BoxName = Literal["x0", "w", "v", "p"]

_SIZE_OF = {"x0": "n", "w": "nw", "v": "nv", "p": "n_params"}


class _UnknownSizes(Protocol):
    """What :meth:`Bounds.resolve` reads of a model: the sizes of its unknowns."""

    @property
    def n(self) -> int:
        """Number of states (length of ``x0``)."""

    @property
    def nw(self) -> int:
        """Number of disturbance channels (length of ``w``)."""

    @property
    def nv(self) -> int:
        """Number of measurement-noise channels (length of ``v``)."""


def _describe(value: object) -> str:
    text = repr(value) if isinstance(value, (list, tuple, int, float, str)) else type(value).__name__
    return text if len(text) <= 60 else text[:57] + "..."


def _size(system: _UnknownSizes, name: str, length: int | None) -> int:
    """The model's length of box ``name``; a given ``length`` must equal it."""
    size = int(getattr(system, _SIZE_OF[name], 0))
    if length is not None and length != size:
        raise DimensionError(f"bounds.{name}: expected length {size} (the model's {_SIZE_OF[name]}), got {length}")
    return size


def _pair(name: str, value: object) -> BoxPair:
    """``(lower, upper)`` as float arrays: scalars or vectors, finite, broadcastable, lower <= upper."""
    if not isinstance(value, (tuple, list)) or len(value) != 2:
        raise BoundsError(f"{name}: expected a (lower, upper) pair, got {_describe(value)}")
    arrays = []
    for side, part in zip(("lower", "upper"), value):
        try:
            arr = np.array(part, dtype=float)
        except (TypeError, ValueError) as exc:
            raise DimensionError(f"{name} {side}: expected a number or a vector, got {_describe(part)}") from exc
        if arr.ndim > 1:
            raise DimensionError(f"{name} {side}: expected a number or a vector, got shape {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise BoundsError(f"{name} {side}: expected finite entries, got {arr.tolist()}")
        arrays.append(arr)
    lower, upper = arrays
    if lower.ndim == upper.ndim == 1 and lower.size != upper.size:
        raise DimensionError(f"{name}: expected lower and upper of equal length, got {lower.size} and {upper.size}")
    lower, upper = np.broadcast_arrays(lower, upper)
    bad = np.flatnonzero(np.atleast_1d(lower > upper))
    if bad.size:
        i = int(bad[0])
        lo, hi = np.atleast_1d(lower)[i], np.atleast_1d(upper)[i]
        where = f"[{i}]" if lower.ndim else ""
        raise BoundsError(f"{name}: expected lower <= upper, got lower{where}={lo:g} > upper{where}={hi:g}")
    return np.array(lower), np.array(upper)


@dataclass(frozen=True, init=False, eq=False)
class Bounds:
    """Boxes of the unknowns as the user states them: the initial state and the noises.

    A scalar bound applies to every component; the sizes are checked against a model by
    :meth:`resolve`.

    Parameters
    ----------
    x0 : tuple of array_like
        ``(lower, upper)`` of the initial state.
    w : tuple of array_like, optional
        ``(lower, upper)`` of the process disturbance (default: zero).
    v : tuple of array_like, optional
        ``(lower, upper)`` of the measurement noise (default: zero).
    p : tuple of array_like, optional
        ``(lower, upper)`` of the uncertain constant parameters of a model that has them
        (:class:`~intervalobs.systems.continuous_nonlinear.ContinuousNonlinearSystem`); refused by
        :meth:`resolve` for a model without parameters.

    Raises
    ------
    BoundsError
        A box is not a pair, has a NaN or infinite entry, or has lower > upper.
    DimensionError
        Lower and upper are not numbers or vectors of one length.

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import Bounds, LTISystem
    >>> system = LTISystem(-np.eye(2), [[1.0, 0.0]])
    >>> full = Bounds(x0=(-1.0, 1.0), w=(-0.1, 0.1)).resolve(system)
    >>> full.x0[1], full.v[1], full.radius("w")
    (array([1., 1.]), array([0.]), array([0.1, 0.1]))
    """

    x0: BoxPair
    w: BoxPair | None
    v: BoxPair | None
    p: BoxPair | None

    def __init__(
        self,
        x0: tuple[ArrayLike, ArrayLike],
        w: tuple[ArrayLike, ArrayLike] | None = None,
        v: tuple[ArrayLike, ArrayLike] | None = None,
        p: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        object.__setattr__(self, "x0", _pair("x0", x0))
        object.__setattr__(self, "w", None if w is None else _pair("w", w))
        object.__setattr__(self, "v", None if v is None else _pair("v", v))
        object.__setattr__(self, "p", None if p is None else _pair("p", p))

    @shared_docs
    def resolve(self, system: _UnknownSizes) -> ResolvedBounds:
        """The boxes for ``system``: scalars broadcast, absent noises zero, every size checked.

        %(resolve)s

        Raises
        ------
        DimensionError
            A box's length differs from the model's, or a parameter box is given for a model without
            parameters.
        """
        boxes = []
        for name, box in (("x0", self.x0), ("w", self.w), ("v", self.v), ("p", self.p)):
            if box is None:
                size = _size(system, name, None)
                boxes.append((np.zeros(size), np.zeros(size)))
            else:
                size = _size(system, name, box[0].size if box[0].ndim else None)
                if size == 0 and (np.any(box[0] != 0) or np.any(box[1] != 0)):
                    raise DimensionError(
                        f"bounds.{name}: expected no box or zeros (the model's {_SIZE_OF[name]} is 0), "
                        f"got ({box[0].tolist()}, {box[1].tolist()})"
                    )
                boxes.append((np.broadcast_to(box[0], (size,)).copy(), np.broadcast_to(box[1], (size,)).copy()))
        return ResolvedBounds(*boxes)

    def __repr__(self) -> str:
        def show(box: BoxPair | None) -> str:
            return "None" if box is None else f"({box[0].tolist()}, {box[1].tolist()})"

        extra = "" if self.p is None or self.p[0].size == 0 else f", p={show(self.p)}"
        return f"{type(self).__name__}(x0={show(self.x0)}, w={show(self.w)}, v={show(self.v)}{extra})"


@dataclass(frozen=True, init=False, eq=False)
class ResolvedBounds(Bounds):
    """:class:`Bounds` checked against one model: every box present, with the model's sizes.

    Made by :meth:`Bounds.resolve`; accepted wherever a :class:`Bounds` is (resolving it again only
    checks the sizes).

    Parameters
    ----------
    x0, w, v : tuple of numpy.ndarray
        ``(lower, upper)`` vectors of the initial state, the disturbance and the measurement noise.
    p : tuple of numpy.ndarray, optional
        ``(lower, upper)`` of the parameters (default: empty, a model without parameters).
    """

    x0: BoxPair
    w: BoxPair
    v: BoxPair
    p: BoxPair

    def __init__(self, x0: BoxPair, w: BoxPair, v: BoxPair, p: BoxPair | None = None) -> None:
        empty = (np.zeros(0), np.zeros(0))
        for name, box in (("x0", x0), ("w", w), ("v", v), ("p", empty if p is None else p)):
            lower, upper = _pair(name, box)
            if lower.ndim != 1:
                raise DimensionError(f"{name}: expected vectors for a resolved box, got shape {lower.shape}")
            object.__setattr__(self, name, (lower, upper))

    @shared_docs
    def resolve(self, system: _UnknownSizes) -> ResolvedBounds:
        """Check the sizes against ``system`` and return ``self``.

        %(resolve)s
        """
        for name, box in (("x0", self.x0), ("w", self.w), ("v", self.v), ("p", self.p)):
            _size(system, name, box[0].size)
        return self

    @shared_docs
    def centre(self, name: BoxName) -> FloatArray:
        """Midpoint ``(lower + upper) / 2`` of one box.

        %(box_name)s
        """
        lower, upper = getattr(self, name)
        return np.asarray(0.5 * (lower + upper))

    @shared_docs
    def radius(self, name: BoxName) -> FloatArray:
        """Half-width ``(upper - lower) / 2`` of one box.

        %(box_name)s
        """
        lower, upper = getattr(self, name)
        return np.asarray(0.5 * (upper - lower))
