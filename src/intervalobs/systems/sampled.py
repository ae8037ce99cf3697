r"""Continuous-time systems with a nonlinear term and sampled outputs (the sampled-output high-gain paper, eq. (8)).

.. math::

    \dot x(t) = Ax(t) + \varphi(t, u(t), x(t)) + d(t), \qquad y(t_k) = Cx(t_k) + V(t_k),

with :math:`d(t)` any measurable signal in a box (Assumption 3.1), :math:`|V| \le \delta`
(Assumption 3.2), :math:`x(0)` in a box (Assumption 3.3) and :math:`u` known (Assumption 3.4).
The boxes are given as :class:`~intervalobs.systems.lti.Bounds` with ``w`` the box of :math:`d`
and ``v`` the box of :math:`V`.

A sound observer needs an *enclosure* of :math:`\varphi` over boxes, not only :math:`\varphi`
itself: ``phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper)`` must return bounds of
:math:`\varphi(t, u, x)` valid for every :math:`t \in [t_0, t_1]` and every point of the boxes (e.g.
the range :math:`e^{-|x|} \in [e^{-\max|x|}, e^{-\operatorname{mig}|x|}] \subset (0, 1]` for the
paper's example). The constructor spot-checks it on random points and refuses an enclosure that
misses one.

A *state domain* ``domain=(lower, upper)`` (ends may be infinite, e.g. concentrations ``>= 0``) states
that every admissible trajectory stays in that box. Then ``phi`` and ``phi_bounds`` are only ever called
inside it (the spot check draws its boxes there, and the observers intersect every box with it before
bounding ``phi``), so they need not be defined, or clipped, outside it.

:func:`intervalobs.simulate.simulate_sampled` produces the truth for tests and reproductions.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError, DimensionError
from ..validation import as_matrix
from .dimensions import ModelDimensions

__all__ = ["PhiBounds", "PhiFunction", "SampledSystem"]

FloatArray = NDArray[np.float64]
PhiFunction = Callable[[float, FloatArray, FloatArray], FloatArray]
PhiBounds = Callable[[float, float, FloatArray, FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray]]

_SPOT_CHECKS = 256


def _as_domain(domain: tuple[ArrayLike, ArrayLike] | None, n: int) -> tuple[FloatArray, FloatArray]:
    """``(lower, upper)`` of the state domain as two (n,) vectors; infinite ends allowed, no NaN, lower <= upper."""
    if domain is None:
        return np.full(n, -np.inf), np.full(n, np.inf)
    if not isinstance(domain, tuple | list) or len(domain) != 2:
        raise BoundsError(f"domain: expected a (lower, upper) pair, got {type(domain).__name__}")
    try:
        lo, hi = (np.broadcast_to(np.asarray(v, dtype=float), (n,)).copy() for v in domain)
    except (TypeError, ValueError) as exc:
        raise DimensionError(f"domain: expected (lower, upper) of {n} numbers each or scalars ({exc})") from exc
    if np.any(np.isnan(lo) | np.isnan(hi)) or np.any(lo > hi) or np.any(lo == np.inf) or np.any(hi == -np.inf):
        raise BoundsError(f"domain: expected lower <= upper with no NaN and a nonempty box, got {lo}, {hi}")
    return lo, hi


class SampledSystem(ModelDimensions):
    """A continuous-time partially linear model whose outputs are measured only at sample times.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Linear part.
    C : array_like, shape (p, n)
        Output matrix.
    phi : callable, optional
        ``phi(t, u, x)`` with ``u`` of shape (..., m) and ``x`` of shape (..., n), returning (..., n).
        Default: no nonlinear term.
    phi_bounds : callable, optional
        ``phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper) -> (lower, upper)``: an enclosure of
        ``phi`` over ``[t0, t1]`` and the boxes (arrays (..., m) and (..., n)). Required with ``phi``.
    m : int
        Number of known inputs.
    sample_period : float
        Time between two output samples :math:`t_{k+1} - t_k`.
    domain : tuple of array_like, optional
        ``(lower, upper)``, shape (n,) or scalars, ends possibly infinite: a box that every admissible
        trajectory stays in (forward invariant; the user's claim, e.g. ``(0, inf)`` for concentrations).
        Default: the whole space.

    Attributes
    ----------
    n, m, p, nw, nv : int
        States, known inputs, outputs, disturbance channels (= n) and noise channels (= p).

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), eq. (8).
    """

    def __init__(
        self,
        A: ArrayLike,
        C: ArrayLike,
        phi: PhiFunction | None = None,
        phi_bounds: PhiBounds | None = None,
        m: int = 0,
        sample_period: float = 1.0,
        domain: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        self.A = as_matrix("A", A)
        n = self.A.shape[0]
        if self.A.shape != (n, n):
            raise DimensionError(f"A: expected a square matrix, got shape {self.A.shape}")
        self.C = as_matrix("C", C, (None, n))
        if not (isinstance(m, int | np.integer) and m >= 0):
            raise DimensionError(f"m: expected a nonnegative integer, got {m!r}")
        self._set_dimensions(n=n, m=m, p=self.C.shape[0], nw=n, nv=self.C.shape[0])
        if not (np.isfinite(sample_period) and sample_period > 0):
            raise BoundsError(f"sample_period: expected a positive number, got {sample_period!r}")
        self.sample_period = float(sample_period)
        if (phi is None) != (phi_bounds is None):
            raise AssumptionError(
                "phi_bounds: a sound observer needs an enclosure of phi over boxes; give both phi and phi_bounds "
                "or neither"
            )
        self.domain = _as_domain(domain, n)
        self.phi = phi
        self.phi_bounds = phi_bounds
        if phi is not None:
            self._spot_check()

    def nonlinearity(self, t: float, u: FloatArray, x: FloatArray) -> FloatArray:
        """``phi(t, u, x)``, zeros when the model has no nonlinear term.

        Parameters
        ----------
        t : float
            Time.
        u : numpy.ndarray, shape (..., m)
            Known input.
        x : numpy.ndarray, shape (..., n)
            State.

        Returns
        -------
        numpy.ndarray, shape (..., n)
        """
        if self.phi is None:
            return np.zeros_like(x)
        return np.asarray(self.phi(t, u, x), dtype=float)

    def nonlinearity_bounds(
        self, t0: float, t1: float, u_lower: FloatArray, u_upper: FloatArray, x_lower: FloatArray, x_upper: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Enclosure of ``phi`` over ``[t0, t1]`` and the boxes (zeros without a nonlinear term).

        Parameters
        ----------
        t0, t1 : float
            Time interval.
        u_lower, u_upper : numpy.ndarray, shape (..., m)
            Box of the known input.
        x_lower, x_upper : numpy.ndarray, shape (..., n)
            Box of the state.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., n)
        """
        if self.phi_bounds is None:
            zero = np.zeros_like(x_lower)
            return zero, zero
        lo, hi = self.phi_bounds(t0, t1, u_lower, u_upper, x_lower, x_upper)
        return np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)

    def _spot_check(self) -> None:
        """Evaluate ``phi`` at random points of random boxes and check ``phi_bounds`` encloses them."""
        assert self.phi is not None and self.phi_bounds is not None
        rng = np.random.default_rng(12345)
        n, m = self.n, self.m
        dom_lo, dom_hi = self.domain
        draw = rng.normal(scale=3.0, size=(_SPOT_CHECKS, n))
        radius = rng.uniform(0.0, 2.0, size=(_SPOT_CHECKS, n))
        # centres moved into the domain (reflected at a finite end, squashed into a bounded one), boxes cut to it
        with np.errstate(invalid="ignore"):  # inf - inf in the branches np.where does not take
            squashed = dom_lo + (dom_hi - dom_lo) * 0.5 * (1.0 + np.tanh(draw / 3.0))
            reflected = np.where(np.isfinite(dom_lo), dom_lo + np.abs(draw), dom_hi - np.abs(draw))
        bounded, unbounded = np.isfinite(dom_lo) & np.isfinite(dom_hi), ~np.isfinite(dom_lo) & ~np.isfinite(dom_hi)
        centre = np.where(bounded, squashed, np.where(unbounded, draw, reflected))
        box_lo, box_hi = np.maximum(centre - radius, dom_lo), np.minimum(centre + radius, dom_hi)
        centre, radius = 0.5 * (box_lo + box_hi), 0.5 * (box_hi - box_lo)
        u_c = rng.normal(scale=3.0, size=(_SPOT_CHECKS, m))
        u_r = rng.uniform(0.0, 1.0, size=(_SPOT_CHECKS, m))
        lo, hi = self.phi_bounds(0.0, 0.1, u_c - u_r, u_c + u_r, centre - radius, centre + radius)
        lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        if lo.shape != (_SPOT_CHECKS, n) or hi.shape != (_SPOT_CHECKS, n):
            raise DimensionError(
                f"phi_bounds: expected arrays of shape (..., {n}) for boxes of shape (..., {n}), got {lo.shape}"
            )
        for s in (-1.0, 1.0, 0.3):
            x = centre + s * radius * rng.choice([-1.0, 1.0], size=radius.shape)
            u = u_c + s * u_r
            value = np.asarray(self.phi(0.05, u, x), dtype=float)
            if value.shape != x.shape:
                raise DimensionError(f"phi: expected an array of shape (..., {n}), got {value.shape}")
            slack = 1e-9 * (1.0 + np.abs(value))
            if np.any(value < lo - slack) or np.any(value > hi + slack):
                raise AssumptionError("phi_bounds: does not enclose phi at a random point of a random box (spot check)")

    def in_domain(self, lower: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The box ``[lower, upper]`` intersected with the state domain (sound: the truth stays in both).

        Parameters
        ----------
        lower, upper : numpy.ndarray, shape (..., n)
            A box that contains the state.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., n)

        Raises
        ------
        AssumptionError
            If the domain empties a nonempty box: the data contradict the model (a trajectory left the domain).
        """
        lo, hi = np.maximum(lower, self.domain[0]), np.minimum(upper, self.domain[1])
        if np.any((lo > hi) & (lower <= upper)):  # only what the domain empties (not a box given empty)
            raise AssumptionError(
                "domain: a box that contains the state does not meet the state domain; the data contradict the "
                "model (noise or disturbance outside their boxes, or a trajectory that leaves the domain)"
            )
        return lo, hi

    def __repr__(self) -> str:
        return f"SampledSystem(n={self.n}, m={self.m}, p={self.p}, sample_period={self.sample_period:g})"
