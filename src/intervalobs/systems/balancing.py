r"""Diagonal balancing of a linear model whose states are in very different units.

A model written in pascals and kilometres, or any coordinates :math:`z = Dx` with :math:`D` spread over
many decades, is the same estimation problem as the model in units of order one, but not for the
solvers: the LPs of the framer and hull designs work with absolute tolerances (1e-9) and bounded gains,
so a state of size 1e-6 is solved to no digit and a gain that must be 1e12 is clipped (hull boxes 7–157×
wider per component and a framer design that did not return at :math:`D` over
:math:`10^{\pm 6}`).

The estimators that solve LPs therefore design, and the hull solves, in balanced coordinates
:math:`x_b = Sx` with :math:`S = \operatorname{diag}(s)` and every :math:`s_i` a **power of two**: then
:math:`SAS^{-1}`, :math:`SB`, :math:`SE`, :math:`CS^{-1}` and the scaled boxes are computed *exactly*
in floating point (an exponent change, barring overflow and underflow, which :func:`state_scales`
rules out), and so are the boxes mapped back, :math:`x = S^{-1}x_b`. The balanced model is therefore
the same model, not an approximation of it: every bound computed for it is a bound for the original,
with nothing to round. For a box :math:`[\ell, u]` of :math:`x_b`, :math:`[\ell/s, u/s]` is the exact
box of :math:`x` because :math:`S^{-1}` is diagonal and positive. That is how
:class:`~intervalobs.HullEstimator` solves its LPs.

:class:`~intervalobs.IntervalObserver` only *designs* in balanced coordinates and is then built, and
verified, on the original model with the gain and coordinates mapped back (:math:`L = S^{-1}L_b`,
:math:`T = T_bS`), so its scales need not be exact: it takes :math:`s_i = 1/\text{size}_i` itself, which
balances a model and every rescaling :math:`z = Dx` of it to the same coordinates (up to rounding), and so
gives the same observer in the original coordinates (tested to 1e-9 at :math:`D` over
:math:`10^{\pm 3}` and :math:`10^{\pm 6}`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .bounds import Bounds, ResolvedBounds
from .lti import LTISystem

__all__ = ["BALANCE_SPREAD", "balanced", "state_scales"]

FloatArray = NDArray[np.float64]

BALANCE_SPREAD = 2.0**8
"""Largest ratio of two states' magnitudes left as it is: a model within it is designed unchanged."""

_EXPONENT_LIMIT = 400
"""Largest magnitude of the base-2 logarithm of a scale: far from the exponent range (±1022), so no
scaled entry over- or underflows unless the model's own entries were within 2^±600 of it."""


def state_scales(system: LTISystem, bounds: ResolvedBounds, powers_of_two: bool = True) -> FloatArray | None:
    """Scales ``s`` with ``s_i x_i`` of order one, or None when the states need no balancing.

    A state's magnitude is the radius of its prior box (the user's own statement of its size); where the
    prior is a point, the radius of the process noise that enters it (``|E| r_w``); where both are zero,
    the size of the other states (no information, no scaling).

    Parameters
    ----------
    system : LTISystem
        The model whose states are measured.
    bounds : ResolvedBounds
        Its boxes (the prior and the process noise give the magnitudes).
    powers_of_two : bool
        Round the scales to powers of two (default), so that the balanced model is exactly the original
        (module docstring). False gives ``1 / magnitude`` itself (relative to the median state): a model and
        any rescaling of it then balance to the same coordinates up to rounding, which is what a design
        that is verified afterwards in the original coordinates wants (:class:`~intervalobs.IntervalObserver`).

    Returns
    -------
    numpy.ndarray of shape (n,) or None
        None when the magnitudes are within :data:`BALANCE_SPREAD` of each other.
    """
    radius = bounds.radius("x0")
    noise = np.abs(system.E) @ bounds.radius("w")
    size = np.where(radius > 0, radius, noise)
    known = (size > 0) & np.isfinite(size)
    if np.count_nonzero(known) < 2:
        return None
    exponents = np.zeros(system.n)
    exponents[known] = -np.log2(size[known])
    exponents[~known] = np.median(exponents[known])
    exponents = np.clip(exponents - np.median(exponents), -_EXPONENT_LIMIT, _EXPONENT_LIMIT)
    if exponents.max() - exponents.min() <= np.log2(BALANCE_SPREAD):
        return None
    if powers_of_two:
        return np.ldexp(1.0, np.round(exponents).astype(int))
    return np.asarray(np.exp2(exponents))


def balanced(system: LTISystem, bounds: ResolvedBounds, scales: FloatArray) -> tuple[LTISystem, ResolvedBounds]:
    """The model in coordinates ``x_b = diag(scales) x`` (exact for powers of two; module docstring).

    Parameters
    ----------
    system : LTISystem
        The model to rewrite.
    bounds : ResolvedBounds
        Its boxes.
    scales : numpy.ndarray, shape (n,)
        Positive scales, e.g. from :func:`state_scales` (exact for powers of two; otherwise the balanced
        model carries the rounding of one product per entry).

    Returns
    -------
    LTISystem, ResolvedBounds
        The balanced model (same outputs, inputs and noises) and its boxes (only ``x0`` changes).
    """
    s = scales[:, None]
    dA = None if system.dA is None else (s * system.dA[0] / scales, s * system.dA[1] / scales)
    dB = None if system.dB is None else (s * system.dB[0], s * system.dB[1])
    model = LTISystem(
        s * system.A / scales,
        system.C / scales,
        B=s * system.B,
        E=s * system.E,
        F=system.F,
        dt=system.dt,
        dA=dA,
        dB=dB,
        state_names=system.state_names,
        output_names=system.output_names,
        input_names=system.input_names,
    )
    prior = (bounds.x0[0] * scales, bounds.x0[1] * scales)
    return model, Bounds(x0=prior, w=bounds.w, v=bounds.v).resolve(model)
