r"""Centred complex intervals (the sampled-output high-gain paper, Section 2; Combastel & Raka 2011).

A complex interval vector in centred form is :math:`c \pm r = [c - r, c + r]` with
:math:`c \in \mathbb{C}^n` and a radius :math:`r` whose real and imaginary parts are both
nonnegative: it is the set of :math:`z` with :math:`|z^R - c^R| \le r^R` and
:math:`|z^I - c^I| \le r^I` elementwise (a product of rectangles), the sampled-output high-gain paper, eq. (1).

* :func:`cabs` — :math:`\operatorname{cabs}(a) = |a^R| + i|a^I|`;
* :func:`ctimes` — :math:`M \circ R = \operatorname{cabs}(M)\operatorname{cabs}(R) + 2|M^I||R^I|`;
* :func:`real_part_radius` — the real part :math:`|M^R|R^R + |M^I|R^I` of :math:`M \circ R` from
  precomputed magnitudes :math:`|M^R|, |M^I|` (the form observers' hot loops use);
* :func:`linear_image` — Theorem 2.1: :math:`M(c \pm R) \subseteq (Mc) \pm (M \circ R)`, and the
  bound is the exact rectangular hull of the image (attained at vertices of the box);
* :func:`delta_operator` — Proposition 2.2: :math:`z = z^c + \Delta(z^r)\sigma`,
  :math:`\sigma \in [-1, 1]^{2n}`, with :math:`\Delta(\eta) = [\operatorname{diag}(\eta^R),\;
  i\operatorname{diag}(\eta^I)]`;
* :func:`real_part_bounds` — the real box :math:`\operatorname{Re}(M(c \pm R))`, used to return from
  complex observer coordinates to the (real) state.

Every function accepts vectors with leading axes (time, Monte Carlo runs): shape ``(..., n)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import BoundsError, DimensionError

__all__ = ["cabs", "ctimes", "delta_operator", "linear_image", "real_part_bounds", "real_part_radius"]

ComplexArray = NDArray[np.complex128]
FloatArray = NDArray[np.float64]


def _radius(name: str, r: ArrayLike) -> ComplexArray:
    arr = np.asarray(r, dtype=complex)
    if not np.all(np.isfinite(arr)):
        raise BoundsError(f"{name}: expected a finite radius, got NaN or inf")
    if np.any(arr.real < 0) or np.any(arr.imag < 0):
        raise BoundsError(
            f"{name}: expected a radius with nonnegative real and imaginary parts (a box around each complex value)"
        )
    return arr


def cabs(a: ArrayLike) -> ComplexArray:
    r"""Componentwise absolute value of the real and imaginary parts, :math:`|a^R| + i|a^I|`.

    Parameters
    ----------
    a : array_like
        Complex (or real) array of any shape.

    Returns
    -------
    numpy.ndarray
        Complex array of the same shape (the sampled-output high-gain paper, Section 2, operator ``cabs``).
    """
    arr = np.asarray(a, dtype=complex)
    return np.abs(arr.real) + 1j * np.abs(arr.imag)


def ctimes(m: ArrayLike, r: ArrayLike) -> ComplexArray:
    r"""Radius of :math:`M(0 \pm R)`: :math:`M \circ R = \operatorname{cabs}(M)\operatorname{cabs}(R) + 2|M^I||R^I|`.

    Its real part is :math:`|M^R|R^R + |M^I|R^I` and its imaginary part :math:`|M^I|R^R + |M^R|R^I`.

    Parameters
    ----------
    m : array_like, shape (k, n)
        Complex matrix.
    r : array_like, shape (..., n)
        Radius vectors (nonnegative real and imaginary parts); leading axes are carried through.

    Returns
    -------
    numpy.ndarray, shape (..., k)
        Radius of the image, with nonnegative real and imaginary parts.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Theorem 2.1.
    """
    mat = np.asarray(m, dtype=complex)
    rad = _radius("r", r)
    if mat.ndim != 2 or rad.shape[-1] != mat.shape[1]:
        raise DimensionError(f"ctimes: expected m (k, n) and r (..., n), got {mat.shape} and {rad.shape}")
    mr, mi = np.abs(mat.real), np.abs(mat.imag)
    return real_part_radius(mr, mi, rad.real, rad.imag) + 1j * real_part_radius(mi, mr, rad.real, rad.imag)


def real_part_radius(m_real_abs: ArrayLike, m_imag_abs: ArrayLike, r_real: ArrayLike, r_imag: ArrayLike) -> FloatArray:
    r"""Real part of :math:`M \circ R`, :math:`|M^R|R^R + |M^I|R^I`, from precomputed magnitudes.

    The real radius of :math:`M(c \pm R)`. (Its imaginary part is the
    same expression with :math:`|M^R|` and :math:`|M^I|` swapped.) No validation: for hot loops whose
    magnitudes are computed once.

    Parameters
    ----------
    m_real_abs, m_imag_abs : array_like, shape (k, n)
        :math:`|M^R|` and :math:`|M^I|`.
    r_real, r_imag : array_like, shape (..., n)
        Real and imaginary parts of the radius (nonnegative); leading axes are carried through.

    Returns
    -------
    numpy.ndarray, shape (..., k)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Theorem 2.1.
    """
    mr, mi = np.asarray(m_real_abs, dtype=float), np.asarray(m_imag_abs, dtype=float)
    return np.asarray(r_real, dtype=float) @ mr.T + np.asarray(r_imag, dtype=float) @ mi.T


def linear_image(m: ArrayLike, c: ArrayLike, r: ArrayLike) -> tuple[ComplexArray, ComplexArray]:
    r"""Linear image of a centred complex interval, :math:`M(c \pm R) \subseteq Mc \pm M \circ R`.

    Each component of the image is a sum of terms involving distinct
    real variables, so the rectangle is the exact hull of :math:`\{Mz : z \in c \pm R\}`.

    Parameters
    ----------
    m : array_like, shape (k, n)
        Complex matrix.
    c : array_like, shape (..., n)
        Centres.
    r : array_like, shape (..., n)
        Radii.

    Returns
    -------
    centre, radius : numpy.ndarray, shape (..., k)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Theorem 2.1.
    """
    mat = np.asarray(m, dtype=complex)
    cen = np.asarray(c, dtype=complex)
    if cen.shape[-1:] != (mat.shape[1],):
        raise DimensionError(f"linear_image: expected c (..., {mat.shape[1]}), got {cen.shape}")
    return cen @ mat.T, ctimes(mat, r)


def real_part_bounds(m: ArrayLike, c: ArrayLike, r: ArrayLike) -> tuple[FloatArray, FloatArray]:
    r"""Lower and upper bounds of :math:`\operatorname{Re}(Mz)` for :math:`z \in c \pm R`.

    The real part of the linear image: :math:`\operatorname{Re}(Mc) \mp (|M^R|R^R + |M^I|R^I)`. This is
    how the bounds of a real state are recovered from complex observer coordinates.

    Parameters
    ----------
    m : array_like, shape (k, n)
        Complex matrix.
    c, r : array_like, shape (..., n)
        Centre and radius.

    Returns
    -------
    lower, upper : numpy.ndarray, shape (..., k)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Theorem 2.1; (25), (51).
    """
    centre, radius = linear_image(m, c, r)
    return centre.real - radius.real, centre.real + radius.real


def delta_operator(eta: ArrayLike) -> ComplexArray:
    r"""The matrix :math:`\Delta(\eta) = [\operatorname{diag}(\eta^R),\; i\operatorname{diag}(\eta^I)]`.

    With it a point of :math:`z^c \pm z^r` is :math:`z^c + \Delta(z^r)\sigma` for some
    :math:`\sigma \in [-1, 1]^{2n}`.

    Parameters
    ----------
    eta : array_like, shape (n,)
        A radius (nonnegative real and imaginary parts).

    Returns
    -------
    numpy.ndarray, shape (n, 2n)

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`), Proposition 2.2, eqs. (3)–(4).
    """
    rad = _radius("eta", eta)
    if rad.ndim != 1:
        raise DimensionError(f"delta_operator: expected a vector, got shape {rad.shape}")
    return np.hstack([np.diag(rad.real), 1j * np.diag(rad.imag)]).astype(complex)
