r"""Continuous-time nonlinear systems with uncertain constant parameters and sampled outputs.

.. math::

    \dot x(t) = f(x(t), u_k, \theta) + E\,w(t),\qquad y_k = g(x(t_k), u_k) + v_k,
    \qquad t \in [t_k, t_{k+1}),

with a known input held over each sampling interval (:math:`u_k`), constant parameters
:math:`\theta` in a box, a disturbance :math:`w(t)` that is only known to be measurable and to stay
in a box (it may switch any number of times inside a sampling interval), measurement noise
:math:`v_k` in a box, and optionally a *state domain*: a box (ends may be infinite) that the true state
never leaves, e.g. concentrations :math:`\ge 0`. The boxes live in
:class:`~intervalobs.systems.bounds.Bounds` (``x0``, ``w``, ``v`` and ``p`` for :math:`\theta`).

``f`` and ``g`` follow the component convention of :mod:`intervalobs.inclusion` and are written with
NumPy functions: ``f(x, u, p)`` takes the sequences of the n state, m input and ``n_params`` parameter
components and returns n components; ``g(x, u)`` returns the p output components. The same definition
is evaluated at points, over boxes (:class:`~intervalobs.interval.Interval`) and, for Jacobians, by
interval forward-mode differentiation (:mod:`intervalobs.interval_dual`): no derivative is written by
hand. Bounds over a sampling interval come from :mod:`intervalobs.systems.flow_enclosure`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..errors import BoundsError, DimensionError
from ..inclusion import MatrixFunction, VectorFunction, evaluate_function
from ..interval_dual import automatic_jacobian
from ..validation import as_matrix, as_names
from .dimensions import ModelDimensions

__all__ = ["ContinuousNonlinearSystem"]

FloatArray = NDArray[np.float64]
DynamicsFunction = Callable[[Sequence[Any], Sequence[Any], Sequence[Any]], Sequence[Any]]
OutputFunction = Callable[[Sequence[Any], Sequence[Any]], Sequence[Any]]


class ContinuousNonlinearSystem(ModelDimensions):
    r"""A continuous-time nonlinear system with sampled outputs (``dt`` is None, as for :class:`LTISystem`).

    Parameters
    ----------
    f : callable
        ``f(x, u, p)``: the vector field, component convention (n components).
    g : callable
        ``g(x, u)``: the output map, component convention (p components).
    n : int
        Number of states.
    E : array_like, shape (n, nw), optional
        Disturbance matrix (default: no disturbance, nw = 0).
    m : int
        Number of known inputs (default 0).
    n_params : int
        Number of uncertain constant parameters (default 0); their box is ``Bounds(p=...)``.
    domain : tuple of array_like, optional
        ``(lower, upper)`` of the state domain, a box the true state never leaves (ends may be
        infinite), e.g. ``([0, 0], [np.inf, np.inf])`` for concentrations. Default: the whole space.
    state_names, output_names, input_names : sequence of str, optional
        Channel names (for labelled data and plots).

    Attributes
    ----------
    n, m, p, nw, nv, n_params : int
        States, known inputs, outputs, disturbance channels, noise channels (= p), parameters.
    dt : None
        Always None: the model is continuous-time.
    domain : tuple of numpy.ndarray
        The state domain (``-inf``/``inf`` where unbounded).

    Raises
    ------
    DimensionError
        Sizes disagree, or ``f``/``g`` return the wrong number of components.
    BoundsError
        The domain has lower > upper or NaN ends.

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import ContinuousNonlinearSystem
    >>> pendulum = ContinuousNonlinearSystem(
    ...     lambda x, u, p: (x[1], -p[0] * np.sin(x[0]) - 0.2 * x[1]), lambda x, u: (x[0],), n=2, n_params=1
    ... )
    >>> pendulum
    ContinuousNonlinearSystem(n=2, m=0, p=1, nw=0, n_params=1)
    """

    dt = None

    def __init__(
        self,
        f: DynamicsFunction,
        g: OutputFunction,
        n: int,
        *,
        E: ArrayLike | None = None,
        m: int = 0,
        n_params: int = 0,
        domain: tuple[ArrayLike, ArrayLike] | None = None,
        state_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
    ) -> None:
        if not callable(f) or not callable(g):
            raise DimensionError("f, g: expected callables f(x, u, p) and g(x, u) (component convention)")
        for name, value in (("n", n), ("m", m), ("n_params", n_params)):
            if not isinstance(value, (int, np.integer)) or value < (1 if name == "n" else 0):
                raise DimensionError(f"{name}: expected an integer >= {1 if name == 'n' else 0}, got {value!r}")
        self._n_params = int(n_params)
        self.E = np.zeros((n, 0)) if E is None else as_matrix("E", E, (n, None))
        self.f, self.g = f, g
        self.domain = self._domain(domain, n)
        zero_x, zero_u, zero_p = np.zeros(n), np.zeros(m), np.ones(self._n_params)
        p = int(evaluate_function(lambda x: g(x, list(zero_u)), zero_x, None, "g").shape[-1])
        self._set_dimensions(n=n, m=m, p=p, nw=self.E.shape[1], nv=p)
        self.evaluate_f(zero_x, zero_u, zero_p)
        self.state_names = as_names("state_names", state_names, self.n, "x")
        self.output_names = as_names("output_names", output_names, p, "y")
        self.input_names = as_names("input_names", input_names, self.m, "u")

    @staticmethod
    def _domain(domain: tuple[ArrayLike, ArrayLike] | None, n: int) -> tuple[FloatArray, FloatArray]:
        if domain is None:
            return np.full(n, -np.inf), np.full(n, np.inf)
        if not isinstance(domain, (tuple, list)) or len(domain) != 2:
            raise BoundsError(f"domain: expected a (lower, upper) pair, got {type(domain).__name__}")
        lower = np.broadcast_to(np.asarray(domain[0], dtype=float), (n,)).copy()
        upper = np.broadcast_to(np.asarray(domain[1], dtype=float), (n,)).copy()
        if np.any(np.isnan(lower) | np.isnan(upper)) or np.any(lower > upper):
            raise BoundsError(f"domain: expected lower <= upper without NaN, got {lower.tolist()}, {upper.tolist()}")
        return lower, upper

    @property
    def n_params(self) -> int:
        """Number of uncertain constant parameters."""
        return self._n_params

    def augmented_field(self, u: ArrayLike) -> VectorFunction:
        r"""The vector field of the augmented state :math:`z = (x, \theta)` for a held input ``u``.

        :math:`\dot z = (f(x, u, \theta), 0)`: constant parameters become states that do not move, so
        one flow enclosure bounds the state for every parameter of the box and keeps the dependence
        on the parameters (the disturbance is added by the caller).

        Parameters
        ----------
        u : array_like, shape (..., m)
            Known input held over the interval (leading axes broadcast against the state's).

        Returns
        -------
        callable
            Component-convention function of ``n + n_params`` components.
        """
        ua = np.asarray(u, dtype=float)
        inputs = [ua[..., j] for j in range(self.m)]
        n = self.n

        def field(z: Sequence[Any]) -> list[Any]:
            rates = list(self.f(list(z[:n]), inputs, list(z[n:])))
            if len(rates) != n:
                raise DimensionError(f"f: expected {n} components, got {len(rates)}")
            return rates + [0.0] * self.n_params

        return field

    def output_map(self, u: ArrayLike) -> VectorFunction:
        """``g(., u)`` of the augmented state (the parameters do not enter the output).

        Parameters
        ----------
        u : array_like, shape (..., m)
            Known input at the sample.

        Returns
        -------
        callable
            Component-convention function of ``n + n_params`` components with p outputs.
        """
        ua = np.asarray(u, dtype=float)
        inputs = [ua[..., j] for j in range(self.m)]
        n = self.n
        return lambda z: self.g(list(z[:n]), inputs)

    def jacobians(self, u: ArrayLike) -> tuple[MatrixFunction, MatrixFunction]:
        """Interval Jacobians of the augmented field and output map (:func:`automatic_jacobian`).

        Parameters
        ----------
        u : array_like, shape (..., m)
            Known input.

        Returns
        -------
        field_jacobian, output_jacobian : callable
        """
        size = self.n + self.n_params
        return automatic_jacobian(self.augmented_field(u), size), automatic_jacobian(self.output_map(u), size)

    @shared_docs
    def evaluate_f(self, x: ArrayLike, u: ArrayLike, p: ArrayLike) -> FloatArray:
        """:math:`f(x, u, \\theta)` at points.

        Parameters
        ----------
        %(states_inputs)s
        p : array_like, shape (..., n_params)
            Parameters.

        Returns
        -------
        numpy.ndarray, shape (..., n)
        """
        xa, ua, pa = (np.asarray(a, dtype=float) for a in (x, u, p))
        out = self.f(
            [xa[..., j] for j in range(xa.shape[-1])],
            [ua[..., j] for j in range(self.m)],
            [pa[..., j] for j in range(self.n_params)],
        )
        if len(out) != self.n:
            raise DimensionError(f"f: expected {self.n} components, got {len(out)}")
        lead = np.broadcast_shapes(xa.shape[:-1], ua.shape[:-1], pa.shape[:-1])
        return np.stack([np.broadcast_to(np.asarray(c, dtype=float), lead) for c in out], axis=-1)

    @shared_docs
    def evaluate_g(self, x: ArrayLike, u: ArrayLike) -> FloatArray:
        """:math:`g(x, u)` at points.

        Parameters
        ----------
        %(states_inputs)s

        Returns
        -------
        numpy.ndarray, shape (..., p)
        """
        ua = np.asarray(u, dtype=float)
        return evaluate_function(lambda x: self.g(x, [ua[..., j] for j in range(self.m)]), x, None, "g")

    def __repr__(self) -> str:
        return f"ContinuousNonlinearSystem(n={self.n}, m={self.m}, p={self.p}, nw={self.nw}, n_params={self.n_params})"
