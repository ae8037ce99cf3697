r"""The compiled per-step recursion of :class:`~intervalobs.observers.IntervalObserver` over whole records.

:func:`run_boxes` evaluates, for every Monte Carlo run and every sample, exactly the recursion of
``IntervalObserver._advance`` and ``_x_box`` (centres of every gain, their error tubes or the framer's
radius, the disturbance radius of an interval :math:`\Delta A`, the running drive, each gain's outward
margin and the intersection over the gains), one step after the other in a Numba loop. The framer is the
tube with horizon 1 (:math:`|M^0| = I`, :math:`|M^1| = |M|`), so one loop serves both methods.

Notes
-----
**Soundness.** The recursion is evaluated in round-to-nearest, as the NumPy path is, and its outputs are widened by the
same :func:`~intervalobs.interval.inflate` rule: ``pad = margin_g * scale + tiny`` with the same margin
``margin_g`` (:func:`~intervalobs.interval.recursion_margin`) and the same scale (the magnitude of the
centre, the radius and the drive, mapped back by :math:`|T^{-1}|`). Only the order of the sums differs
(a loop over the terms instead of BLAS or a modal filter). The margin's derivation (``interval.py``,
policy 2) bounds the error of a :math:`k`-term sum by :math:`\gamma_k\sum_i|a_i x_i|` for *any* order of
summation, and a direct step-by-step evaluation amplifies it by the condition number 1 of the identity
(the NumPy path's modal filter needs ``cond(V)``, already included in its margin, which is kept: the
kernel is never narrower than a sound bound of its own rounding). The block norms are rounded up by the
same 16 ulps as :class:`~intervalobs.design.tube.BlockNorms`. Each step's box therefore contains the exact
(real-arithmetic) box of the recursion, and that box contains the state for every admissible realisation
(the class docstring of :class:`~intervalobs.observers.IntervalObserver`).

Importing this module imports Numba; the first call of a fresh install compiles the kernel into Numba's
cache (``cache=True``), later processes load it.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["FRAMER", "POINT", "TUBE_COORDINATES", "TUBE_IDENTITY", "run_boxes"]

FloatArray = NDArray[np.float64]

POINT, FRAMER, TUBE_IDENTITY, TUBE_COORDINATES = 0, 1, 2, 3
"""How the disturbance radius is formed: point model; interval ΔA for the framer, the tube in the identity
coordinates (``|x|`` from the reported box), the tube in other coordinates (the coupling ``S``)."""


@numba.njit(cache=True, nogil=True, inline="always")
def _block_norms(v: FloatArray, sizes: NDArray[np.int64], rounding: float, out: FloatArray) -> None:
    """``out[b]`` = the 2-norm of block ``b`` of ``v`` (its absolute value for a block of size 1)."""
    i = 0
    for b in range(sizes.size):
        if sizes[b] == 1:
            out[b] = abs(v[i])
        else:
            out[b] = math.hypot(v[i], v[i + 1]) * (1.0 + rounding)
        i += sizes[b]


@numba.njit(cache=True, nogil=True, inline="always")
def _box(
    z_c: FloatArray,
    radii: FloatArray,
    drive: FloatArray,
    matrices: tuple[FloatArray, FloatArray, FloatArray],
    box: tuple[FloatArray, float, bool, bool],
    at: tuple[int, int],
    lower: FloatArray,
    upper: FloatArray,
) -> None:
    """The reported box of sample ``k`` of run ``r`` (``at``): every gain's box, widened by its margin, intersected
    (``_x_box``); ``radii`` (T, G, count) is read at ``k``. Scalars are indexed in place (no array views: at
    n = 2 their bookkeeping cost as much as the arithmetic)."""
    t_inv, abs_t_inv, back = matrices
    margin, tiny, identity, singleton = box
    r, k = at
    gains, n = z_c.shape
    for i in range(n):
        lower[r, k, i] = -np.inf
        upper[r, k, i] = np.inf
    for g in range(gains):
        for i in range(n):
            if identity:
                centre, radius = z_c[g, i], radii[k, g, i]
                scale = abs(z_c[g, i]) + radii[k, g, i] + drive[g, i]
            else:
                centre, radius, scale = 0.0, 0.0, 0.0
                for j in range(n):
                    centre += t_inv[i, j] * z_c[g, j]
                    scale += abs_t_inv[i, j] * (abs(z_c[g, j]) + drive[g, j] + (radii[k, g, j] if singleton else 0.0))
                for j in range(radii.shape[2]):
                    radius += (abs_t_inv[i, j] if singleton else back[i, j]) * radii[k, g, j]
                if not singleton:
                    scale += radius
            pad = margin[g] * scale + tiny
            lower[r, k, i] = max(lower[r, k, i], centre - radius - pad)
            upper[r, k, i] = min(upper[r, k, i], centre + radius + pad)


@numba.njit(cache=True, nogil=True, inline="always")
def _disturbance(
    mode: int,
    z_c: FloatArray,
    z_r: FloatArray,
    u: FloatArray,
    data: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray],
    sizes: NDArray[np.int64],
    rounding: float,
    work: FloatArray,
    out: FloatArray,
) -> None:
    """Data-dependent radius entering one step per gain, framer or tube outside the identity (``_data_radius``).

    ``work``: (4, n) scratch. The tube in the identity coordinates is in :func:`run_boxes`; a point model has none.
    """
    k_phi, k_gamma, t_inv, abs_t_inv, s_phi = data
    gains, n = z_c.shape
    count = z_r.shape[1]
    for g in range(gains):
        for b in range(count):
            out[g, b] = 0.0
    scratch, norms, inputs, x_abs = work[0], work[1, :count], work[2, :count], work[3]
    for i in range(n):
        scratch[i] = 0.0
        for j in range(u.size):
            scratch[i] += k_gamma[i, j] * abs(u[j])
    _block_norms(scratch, sizes, rounding, inputs)
    for g in range(gains):
        for j in range(n):
            centre, spread = 0.0, 0.0
            for l in range(n):
                centre += t_inv[j, l] * z_c[g, l]
                if mode == FRAMER:
                    spread += abs_t_inv[j, l] * z_r[g, l]
            x_abs[j] = abs(centre) + spread
        for i in range(n):
            scratch[i] = 0.0
            for j in range(n):
                scratch[i] += k_phi[i, j] * x_abs[j]
        if mode == FRAMER:
            for i in range(n):
                out[g, i] += scratch[i] + inputs[i]
            continue
        _block_norms(scratch, sizes, rounding, norms)
        _block_norms(z_c[g], sizes, rounding, x_abs[:count])
        for b in range(count):
            coupled, spread = 0.0, 0.0
            for c in range(count):
                coupled += s_phi[b, c] * x_abs[c]
                spread += s_phi[b, c] * z_r[g, c]
            out[g, b] += inputs[b] + min(norms[b], coupled) + spread


@numba.njit(cache=True, nogil=True, inline="always")
def _centres(
    z_c: FloatArray,
    drive: FloatArray,
    signals: tuple[FloatArray, FloatArray],
    at: tuple[int, int],
    linear: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    work: FloatArray,
) -> None:
    """``z_c ← M_g z_c + TL_g y + TΓu + offset_g`` and the running drive of every gain, in place, with ``y, u``
    (R, T, ·) of run ``r`` at sample ``k`` (``at``)."""
    ms, tl, t_gamma, offset = linear
    y, u = signals
    r, k = at
    gains, n = z_c.shape
    for i in range(n):
        work[0, i] = 0.0
        for j in range(u.shape[2]):
            work[0, i] += t_gamma[i, j] * u[r, k, j]
    for g in range(gains):
        for i in range(n):
            total, term = 0.0, 0.0
            for j in range(n):
                total += ms[g, i, j] * z_c[g, j]
            for j in range(y.shape[2]):
                total += tl[g, i, j] * y[r, k, j]
                term += abs(tl[g, i, j]) * abs(y[r, k, j])
            work[1, i] = total + work[0, i] + offset[g, i]
            drive[g, i] = max(drive[g, i], term + abs(work[0, i]) + abs(offset[g, i]))
        for i in range(n):
            z_c[g, i] = work[1, i]


@numba.njit(cache=True, nogil=True, inline="always")
def _tube_radius(
    k: int,
    tube: tuple[FloatArray, NDArray[np.int64], FloatArray],
    radii: FloatArray,
    disturbances: FloatArray,
    point: bool,
) -> None:
    """``ρ_{k+1} = |M^ℓ|ρ_{k+1-ℓ} + c_ℓ + Σ_{i<ℓ}|M^i| d_{k-i}``, ``ℓ = min(k+1, J_g)``, written into ``radii[k+1]``:
    ``c_ℓ`` the noise's constant part, ``d`` the data-dependent disturbances (none for a ``point`` model)."""
    powers, lags, sums = tube
    gains, count = radii.shape[1], radii.shape[2]
    for g in range(gains):
        lag = min(k + 1, lags[g])
        for b in range(count):
            total = sums[g, lag, b]
            for c in range(count):
                total += powers[g, lag, b, c] * radii[k + 1 - lag, g, c]
            if not point:
                for i in range(lag):
                    for c in range(count):
                        total += powers[g, i, b, c] * disturbances[k - i, g, c]
            radii[k + 1, g, b] = total


@numba.njit(cache=True, nogil=True)
def run_boxes(
    y: FloatArray,
    u: FloatArray,
    start: tuple[FloatArray, FloatArray],
    linear: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    tube: tuple[FloatArray, NDArray[np.int64], FloatArray],
    data: tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray],
    back: FloatArray,
    norms: tuple[NDArray[np.int64], float],
    box: tuple[FloatArray, float, bool, bool],
    mode: int,
) -> tuple[FloatArray, FloatArray]:
    """Boxes of every run and sample of the interval observer's recursion (see the module docstring).

    Parameters
    ----------
    y, u : numpy.ndarray, shape (R, T, p) and (R, T, m)
        Measurements and inputs of ``R`` runs.
    start : tuple
        Centres ``(G, n)`` and radii ``(G, count)`` of every gain at the first sample.
    linear : tuple
        ``M_g`` ``(G, n, n)``, ``TL_g`` ``(G, n, p)``, ``TΓ`` ``(n, m)``, offsets ``(G, n)``.
    tube : tuple
        ``|M_g^i|`` ``(G, J + 1, count, count)`` (zero beyond ``J_g``), horizons ``J_g`` ``(G,)`` and the noise's
        part ``c_ℓ`` ``(G, J + 1, count)`` (``IntervalObserver._noise_sums``; the framer's ``[0, d]``).
    data : tuple
        ``|T|δΦ``, ``|T|δΓ``, ``T⁻¹``, ``|T⁻¹|``, ``S``.
    back : numpy.ndarray, shape (n, count)
        Radius in x of a unit block radius in z (``BlockNorms.cols(|T⁻¹|)``).
    norms : tuple
        Block sizes ``(count,)`` and their rounding.
    box : tuple
        Margin of every gain ``(G,)``, the absolute floor of the pad, identity coordinates, blocks of size 1.
    mode : int
        :data:`POINT`, :data:`FRAMER`, :data:`TUBE_IDENTITY` or :data:`TUBE_COORDINATES`.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (R, T, n)
    """
    runs, steps = y.shape[0], y.shape[1]
    z_c0, z_r0 = start
    gains, n = z_c0.shape
    count = z_r0.shape[1]
    sizes, rounding = norms
    mapping = (data[2], data[3], back)
    lower = np.empty((runs, steps, n))
    upper = np.empty((runs, steps, n))
    radii = np.empty((steps, gains, count))
    disturbances = np.empty((steps, gains, count))
    work = np.empty((4, n))
    z_c, drive = np.empty((gains, n)), np.empty((gains, n))
    for r in range(runs):  # the run's state in place: no allocation per run
        for g in range(gains):
            for i in range(n):
                z_c[g, i], drive[g, i] = z_c0[g, i], 0.0
            for b in range(count):
                radii[0, g, b] = z_r0[g, b]
        for k in range(steps):
            _box(z_c, radii, drive, mapping, box, (r, k), lower, upper)
            if k + 1 == steps:
                break
            if mode == TUBE_IDENTITY:  # indexed in place: no views of this step's arrays
                k_phi, k_gamma = data[0], data[1]
                for i in range(count):
                    total = 0.0  # |x_k| from the reported box, the same for every gain
                    for j in range(u.shape[2]):
                        total += k_gamma[i, j] * abs(u[r, k, j])
                    for j in range(n):
                        total += k_phi[i, j] * max(abs(lower[r, k, j]), abs(upper[r, k, j]))
                    for g in range(gains):
                        disturbances[k, g, i] = total
            elif mode != POINT:
                _disturbance(
                    mode,
                    z_c,
                    radii[k],
                    u[r, k],
                    data,
                    sizes,
                    rounding,
                    work,
                    disturbances[k],
                )
            _centres(z_c, drive, (y, u), (r, k), linear, work)
            _tube_radius(k, tube, radii, disturbances, mode == POINT)
    return lower, upper
