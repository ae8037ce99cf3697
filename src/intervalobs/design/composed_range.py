r"""Ranges of linear combinations of :math:`[f; g]` composed with a linear change of coordinates (Khajenejad & Yong).

The nonlinear simultaneous input and state observers (:mod:`intervalobs.observers.gsisio`,
:mod:`intervalobs.observers.null_space_gsisio`) need, at every step, bounds of
:math:`\psi(z) = \Phi\,[f(x); g(x)]` with :math:`x = Z^{-1}z` over a box of :math:`z`, for several
matrices :math:`\Phi` at once. :class:`ComposedRange` intersects three sound inclusions: the natural
interval extension, the mean-value form and the Jacobian-based decomposition of Khajenejad & Yong, eq. (2)
(:mod:`intervalobs.design.mixed_monotone`), with local Jacobian bounds on a split of the box and with
global Jacobian bounds on the whole box.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..errors import AssumptionError
from ..interval import inflate, interval_matvec_bounds, matvec_bounds, sandwich_bounds
from ..systems.nonlinear import NonlinearSystem
from .mixed_monotone import jacobian_bounds, jacobian_decomposition_parts

__all__ = ["ComposedRange"]

FloatArray = NDArray[np.float64]
BoxPair = tuple[FloatArray, FloatArray]


class ComposedRange:
    r"""Ranges of :math:`\psi(z) = \Phi\,[f(x); g(x)]` with :math:`x = Z^{-1}z` over boxes in z.

    ``bounds`` intersects the natural interval extension, the mean-value form and the
    Yang–Mickelin–Ozay decomposition built from *local* Jacobian bounds of :math:`\psi`, on a
    ``splits``-per-axis partition of the box (the hull of the pieces is returned), and, when the
    Jacobians of f and g are bounded on the whole space, the decomposition with those *global* bounds
    on the unsplit box — the one whose width the design-time certificate bounds
    (:meth:`~intervalobs.observers.null_space_gsisio.NullSpaceGSISIO.width_certificate`).

    Parameters
    ----------
    system : NonlinearSystem
        The model whose f and g are bounded (Jacobians automatic or given).
    Zinv : numpy.ndarray, shape (n, n)
        :math:`Z^{-1}`, mapping the coordinates z back to x.
    splits : int
        Sub-boxes per axis for the local ranges (1: the box itself).
    """

    def __init__(self, system: NonlinearSystem, Zinv: FloatArray, splits: int) -> None:
        self.system = system
        self.Zinv = Zinv
        self.splits = splits
        self.f_jac, self.g_jac = system.jacobians()
        self.n, self.p = system.n, system.p
        inf = np.full(self.n, np.inf)
        try:
            self.global_fg: BoxPair | None = self._fg_jacobian(-inf, inf)
        except AssumptionError:
            self.global_fg = None

    def point(self, Phi: FloatArray, z: FloatArray) -> FloatArray:
        r"""The value :math:`\psi(z)` at points.

        Parameters
        ----------
        Phi : numpy.ndarray, shape (..., r, n + p)
            Rows of the linear combination.
        z : numpy.ndarray, shape (..., n)
            Points in z.

        Returns
        -------
        numpy.ndarray, shape (..., r)
        """
        x = z @ self.Zinv.T
        fg = np.concatenate([self.system.evaluate_f(x), self.system.evaluate_g(x)], axis=-1)
        return np.einsum("...ij,...j->...i", Phi, fg)

    def _fg_jacobian(self, xlo: FloatArray, xhi: FloatArray) -> BoxPair:
        jf = jacobian_bounds(self.f_jac, xlo, xhi, (self.n, self.n), "f_jacobian")
        jg = jacobian_bounds(self.g_jac, xlo, xhi, (self.p, self.n), "g_jacobian")
        return np.concatenate([jf[0], jg[0]], axis=-2), np.concatenate([jf[1], jg[1]], axis=-2)

    def jacobian(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray) -> BoxPair:
        r"""Bounds of the Jacobian of :math:`\psi` with respect to z over a box.

        Parameters
        ----------
        Phi : numpy.ndarray, shape (..., r, n + p)
            Rows of the linear combination.
        zlo, zhi : numpy.ndarray, shape (..., n)
            The box in z.

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., r, n)
        """
        xlo, xhi = matvec_bounds(self.Zinv, zlo, zhi)
        jlo, jhi = self._fg_jacobian(xlo, xhi)
        return sandwich_bounds(Phi, jlo, jhi, self.Zinv)

    def global_jacobian(self, Phi: FloatArray) -> BoxPair | None:
        r"""Bounds of the Jacobian of :math:`\psi` with respect to z on the whole space.

        Parameters
        ----------
        Phi : numpy.ndarray, shape (..., r, n + p)
            Rows of the linear combination.

        Returns
        -------
        tuple of numpy.ndarray or None
            ``(lower, upper)``, shape (..., r, n); None when a Jacobian of f or g is unbounded.
        """
        if self.global_fg is None:
            return None
        return sandwich_bounds(Phi, *self.global_fg, self.Zinv)

    def _decomposition(
        self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray, jlo: FloatArray, jhi: FloatArray
    ) -> BoxPair:
        """Khajenejad & Yong, eq. (2) with Jacobian bounds ``(jlo, jhi)`` of psi valid on the box."""
        first, cmat = jacobian_decomposition_parts(jlo, jhi)
        zeta_hi = np.where(first, zhi[..., None, :], zlo[..., None, :])
        zeta_lo = np.where(first, zlo[..., None, :], zhi[..., None, :])
        spread = np.einsum("...ij,...j->...i", cmat, zhi - zlo)
        return inflate(self._rows(Phi, zeta_lo) - spread, self._rows(Phi, zeta_hi) + spread)

    def _single(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray) -> BoxPair:
        xlo, xhi = matvec_bounds(self.Zinv, zlo, zhi)
        flo, fhi = self.system.f_range(xlo, xhi)
        glo, ghi = self.system.g_range(xlo, xhi)
        low, high = matvec_bounds(Phi, np.concatenate([flo, glo], -1), np.concatenate([fhi, ghi], -1))
        low, high = inflate(low, high)
        jlo, jhi = self.jacobian(Phi, zlo, zhi)
        if not (np.all(np.isfinite(jlo)) and np.all(np.isfinite(jhi))):
            return low, high
        # mean-value form
        c = 0.5 * (zlo + zhi)
        centre = self.point(Phi, c)
        mlo, mhi = interval_matvec_bounds(jlo, jhi, zlo - c, zhi - c)
        mlo, mhi = inflate(centre + mlo, centre + mhi)
        low, high = np.maximum(low, mlo), np.minimum(high, mhi)
        dlo, dhi = self._decomposition(Phi, zlo, zhi, jlo, jhi)
        return np.maximum(low, dlo), np.minimum(high, dhi)

    def _rows(self, Phi: FloatArray, points: FloatArray) -> FloatArray:
        x = points @ self.Zinv.T
        fg = np.concatenate([self.system.evaluate_f(x), self.system.evaluate_g(x)], axis=-1)
        return np.einsum("...ij,...ij->...i", Phi, fg)

    def bounds(self, Phi: FloatArray, zlo: FloatArray, zhi: FloatArray, splits: int | None = None) -> BoxPair:
        r"""Bounds of the range of :math:`\psi` over boxes (leading axes of Phi and the boxes broadcast).

        Parameters
        ----------
        Phi : numpy.ndarray, shape (..., r, n + p)
            Rows of the linear combination.
        zlo, zhi : numpy.ndarray, shape (..., n)
            The boxes in z.
        splits : int, optional
            Sub-boxes per axis (default: the constructor's).

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., r)
        """
        s = self.splits if splits is None else splits
        if s <= 1:
            lo, hi = self._single(Phi, zlo, zhi)
        else:
            nz = zlo.shape[-1]
            frac = np.linspace(0.0, 1.0, s + 1)
            grids = np.stack(np.meshgrid(*([np.arange(s)] * nz), indexing="ij"), -1).reshape(-1, nz)
            width = (zhi - zlo)[..., None, :]
            sub_lo = zlo[..., None, :] + width * frac[grids]
            sub_hi = zlo[..., None, :] + width * frac[grids + 1]
            sub_hi = np.where(grids + 1 == s, zhi[..., None, :], sub_hi)
            lo, hi = self._single(Phi[..., None, :, :], sub_lo, sub_hi)
            lo, hi = lo.min(axis=-2), hi.max(axis=-2)
        glob = self.global_jacobian(Phi)
        if glob is not None:
            dlo, dhi = self._decomposition(Phi, zlo, zhi, *glob)
            lo, hi = np.maximum(lo, dlo), np.minimum(hi, dhi)
        return lo, hi
