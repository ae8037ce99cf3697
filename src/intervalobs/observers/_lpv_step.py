r"""The between-sample step of the LPV interval observers: sampled Metzler matrices, a generic model's enclosure.

:func:`metzler_step_matrices` gives :math:`e^{Fh}` and :math:`\int_0^h e^{Fs}\,ds` (both nonnegative for a
Metzler :math:`F`); :class:`GenericStepEnclosure` bounds :math:`\psi` over a step of an
:class:`~intervalobs.systems.lpv.LPVSystem` from the a-priori enclosure of the state on the step
(:mod:`intervalobs.observers.lpv`, "Generic models", gives the argument).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from ..design.lpv_gains import LPVObserverDesign, rotate_bounds
from ..errors import DataError, DesignError
from ..interval import inflate, interval_matvec_bounds, matvec_bounds
from ..systems.lpv import LPVSystem

__all__ = ["GenericStepEnclosure", "metzler_step_matrices", "metzler_step_matrices_batch"]

FloatArray = NDArray[np.float64]


def metzler_step_matrices(f: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """``expm(F h)`` and ``∫_0^h expm(F s) ds`` (both ≥ 0 for Metzler F; rounding noise clipped)."""
    n = f.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = f
    block[:n, n:] = np.eye(n)
    ex = expm(block * h)
    e, phi = ex[:n, :n], ex[:n, n:]
    for name, m in (("expm(F h)", e), ("integral of expm(F s)", phi)):
        if np.any(m < -1e-14 * max(1.0, float(np.abs(m).max()))):
            raise DesignError(f"{name}: expected a nonnegative matrix for Metzler F, got min {m.min():g}")
    return np.maximum(e, 0.0), np.maximum(phi, 0.0)


def metzler_step_matrices_batch(f: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """:func:`metzler_step_matrices` for a stack of Metzler matrices (M, n, n)."""
    m, n = f.shape[0], f.shape[-1]
    block = np.zeros((m, 2 * n, 2 * n))
    block[:, :n, :n] = f
    block[:, :n, n:] = np.eye(n)
    ex = expm(block * h)
    e, phi = ex[:, :n, :n], ex[:, :n, n:]
    scale = max(1.0, float(np.abs(ex).max()))
    if np.any(e < -1e-14 * scale) or np.any(phi < -1e-14 * scale):
        raise DesignError(
            f"expm(F h): expected a nonnegative matrix for Metzler F, got min {min(e.min(), phi.min()):g}"
        )
    return np.maximum(e, 0.0), np.maximum(phi, 0.0)


class GenericStepEnclosure:
    """The between-sample enclosure of a generic :class:`LPVSystem` (observers/lpv.py, "Generic models")."""

    def __init__(
        self,
        system: LPVSystem,
        design: LPVObserverDesign,
        theta_rate: ArrayLike,
        h: float,
        unknown_input: tuple[FloatArray, FloatArray] | None,
        disturbance: tuple[FloatArray, FloatArray],
    ) -> None:
        self.system, self.design, self.h = system, design, h
        rate = np.asarray(theta_rate, dtype=float).reshape(-1)
        rate = np.broadcast_to(rate, (system.n_theta,)) if rate.size == 1 else rate
        if rate.shape != (system.n_theta,) or np.any(np.isnan(rate)) or np.any(rate < 0):
            raise DataError(
                f"theta_rate: expected {system.n_theta} nonnegative bounds of |dθ/dt| (inf allowed), got {theta_rate!r}"
            )
        self.theta_rate = rate
        self.u_un = unknown_input
        self.R = design.R
        pts = system.test_points()
        right = (self.R @ system.matrix_at("A", pts))[..., design.p :]
        self.constant_f = bool(np.allclose(right, right[0], rtol=0.0, atol=0.0))
        self._cache: tuple[FloatArray, ...] | None = None
        d = disturbance
        rd_lo, rd_hi = matvec_bounds(self.R, *d)
        self.rc_lo, self.rc_hi = rd_lo + self.R @ system.c, rd_hi + self.R @ system.c
        self.d = d

    def theta_box(self, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        lo, hi = self.system.theta_box
        with np.errstate(invalid="ignore"):
            pad = np.where(np.isinf(self.theta_rate), np.inf, self.theta_rate * self.h)
        return np.maximum(theta - pad, lo), np.minimum(theta + pad, hi)

    def _sum(self, name: str, bound: str, th_lo: FloatArray, th_hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        lo, hi = self.system.matrix_box(name, th_lo, th_hi)
        extra = self.system.bounds_box(bound, th_lo, th_hi)
        if extra is not None:
            lo, hi = lo + extra[0], hi + extra[1]
        return lo, hi

    def flow_box(
        self,
        s_lo: FloatArray,
        s_hi: FloatArray,
        a: tuple[FloatArray, FloatArray],
        bu: tuple[FloatArray, FloatArray],
        fault: tuple[FloatArray, FloatArray] | None,
    ) -> tuple[FloatArray, FloatArray]:
        """A box containing x(t) on the step (Picard–Lindelöf a-priori enclosure, outward inflated)."""
        const_lo, const_hi = bu[0] + self.d[0] + self.system.c, bu[1] + self.d[1] + self.system.c
        if fault is not None:
            const_lo, const_hi = const_lo + fault[0], const_hi + fault[1]
        h = self.h

        def image(x_lo: FloatArray, x_hi: FloatArray) -> tuple[FloatArray, FloatArray]:
            r_lo, r_hi = interval_matvec_bounds(a[0], a[1], x_lo, x_hi)
            return inflate(s_lo + h * np.minimum(r_lo + const_lo, 0.0), s_hi + h * np.maximum(r_hi + const_hi, 0.0))

        x_lo, x_hi = image(s_lo, s_hi)
        for _ in range(30):
            grow = 0.1 * (x_hi - x_lo) + 1e-9 * (1.0 + np.abs(x_lo) + np.abs(x_hi))
            x_lo, x_hi = x_lo - grow, x_hi + grow
            n_lo, n_hi = image(x_lo, x_hi)
            if np.all(n_lo >= x_lo) and np.all(n_hi <= x_hi):
                return n_lo, n_hi
            x_lo, x_hi = np.minimum(x_lo, n_lo), np.maximum(x_hi, n_hi)
        raise DataError(f"h: the a-priori enclosure over a step of h = {h:g} s did not converge; use a smaller h")

    def step(
        self, x_lo: FloatArray, x_hi: FloatArray, x_meas: FloatArray, u: FloatArray, theta: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """ψ bounds and the step matrices: returns psi_lo, psi_hi, E_lower, Phi_lower, E_upper, Phi_upper."""
        sysm, r, p = self.system, self.R, self.design.p
        th_lo, th_hi = self.theta_box(theta)
        a = self._sum("A", "dA", th_lo, th_hi)
        b = self._sum("B", "dB", th_lo, th_hi)
        bu = interval_matvec_bounds(b[0], b[1], u, u)
        fault = None
        dbun = None
        if self.u_un is not None:
            bun = self._sum("B_un", "dB_un", th_lo, th_hi)
            fault = interval_matvec_bounds(bun[0], bun[1], *self.u_un)
            extra = sysm.bounds_box("dB_un", th_lo, th_hi)
            if extra is not None:
                dbun = interval_matvec_bounds(*rotate_bounds(r, *extra), *self.u_un)
        s_lo, s_hi = x_lo.copy(), x_hi.copy()
        s_lo[:, :p] = s_hi[:, :p] = x_meas
        f_lo, f_hi = self.flow_box(s_lo, s_hi, a, bu, fault)
        ra = rotate_bounds(r, *a)
        fl, fu = self._f_matrices(theta)
        k_lo = ra[0] - fl @ r
        k_hi = ra[1] - fu @ r
        psi_lo = interval_matvec_bounds(k_lo, ra[1] - fl @ r, f_lo, f_hi)[0]
        psi_hi = interval_matvec_bounds(ra[0] - fu @ r, k_hi, f_lo, f_hi)[1]
        rb = interval_matvec_bounds(*rotate_bounds(r, *b), u, u)
        psi_lo, psi_hi = psi_lo + rb[0] + self.rc_lo, psi_hi + rb[1] + self.rc_hi
        if dbun is not None:
            psi_lo, psi_hi = psi_lo + dbun[0], psi_hi + dbun[1]
        return (psi_lo, psi_hi, *self._matrices(fl, fu))

    def _f_matrices(self, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        fl, fu = self.design.f_matrices(self.R @ self.system.matrix_at("A", theta))
        n = fl.shape[-1]
        off = ~np.eye(n, dtype=bool)
        for f in (fl, fu):
            f[:, off] = np.maximum(f[:, off], 0.0)
        return fl, fu

    def _matrices(self, fl: FloatArray, fu: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        if self.constant_f:
            if self._cache is None:
                el, pl = metzler_step_matrices_batch(fl[:1], self.h)
                eu, pu = metzler_step_matrices_batch(fu[:1], self.h)
                self._cache = (el, pl, eu, pu)
            el, pl, eu, pu = self._cache
            m = fl.shape[0]
            return (
                np.broadcast_to(el, (m, *el.shape[1:])),
                np.broadcast_to(pl, (m, *pl.shape[1:])),
                np.broadcast_to(eu, (m, *eu.shape[1:])),
                np.broadcast_to(pu, (m, *pu.shape[1:])),
            )
        return (*metzler_step_matrices_batch(fl, self.h), *metzler_step_matrices_batch(fu, self.h))
