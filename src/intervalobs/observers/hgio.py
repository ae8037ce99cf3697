r"""High-gain interval observer with sampled outputs (the sampled-output high-gain paper, Theorems 4.2 and 4.5), made
sound.

Model (eq. (8)): :math:`\dot x = Ax + \varphi(t, u, x) + d`, :math:`y(t_k) = Cx(t_k) + V(t_k)`.
With :math:`A - L_1C = v_1^{-1}\operatorname{diag}(p_1 + i\omega_1)v_1` (eq. (13)) the truth obeys
:math:`\dot x = (A - L_1C)x + g`, :math:`g = \varphi + d + L_1Cx`. The paper's coordinates
:math:`z = T_1(t)x`, :math:`T_1 = \operatorname{diag}(e^{-(\theta + i\omega_1)t})v_1` (eqs. (17), (18),
(44)) make the linear part the *real* diagonal :math:`\operatorname{diag}(p_1 - \theta)`, so real and
imaginary parts of a centred complex interval evolve without wrapping. Since :math:`e^{-\theta t}` is
a positive scalar it passes through :math:`|\cdot|` and cancels in :math:`x = T_1^{-1}z`: we use
:math:`\zeta = e^{\theta t}z = \operatorname{diag}(e^{-i\omega_1t})v_1x` (θ = 0), which cannot overflow
(with θ = 1000, :math:`e^{\theta t}` overflows after 0.7 s) and gives the same bounds in exact arithmetic.

Two observers run together, as in the paper:

* **output-bound observer** (Theorem 4.2, gain ``output_gain``): :math:`g_w = \varphi + d + L_wCx`
  with :math:`Cx` bounded by the observer's own box (eq. (20)–(22)), and the *intersample predictor*
  (12c)–(12d) in interval form: the box of :math:`Cx(t)` is propagated with
  :math:`C\dot x \in C F(B_k)` and intersected with the measurement box
  :math:`[y(t_k) - \overline V, y(t_k) - \underline V]` at each sample (eqs. (27)–(29));
* **state-bound observer** (Theorem 4.5, gain ``L``): :math:`g = \varphi + d + L_1Cx` with :math:`Cx`
  bounded by the output bounds of the first observer over the step (eqs. (46)–(51)).

Sound discretisation on a grid of step :math:`h` (the truth may have disturbances that switch inside
the steps and is only sampled every few steps):

1. an a-priori enclosure :math:`B_k \ni x(s)`, :math:`s \in [t_k, t_{k+1}]`, by the Picard
   self-map test :math:`X_k + [0, h]F(B_k) \subseteq B_k`, :math:`F(B) = AB + \varphi(B) + [d]`;
2. every input bounded over the whole step: :math:`\varphi` by its enclosure over :math:`B_k`
   (the range, not a Lipschitz radius), :math:`u` by ``u_k ± input_rate·h``;
3. the exact solution of :math:`\dot\zeta_j = p_j\zeta_j + e^{-i\omega_jt}(v_1g)_j`:
   :math:`\zeta^c_{k+1} = e^{p h}\zeta^c_k + e^{-i\omega t_k}\Psi\,v_1g^c` with
   :math:`\Psi = (e^{ph} - e^{-i\omega h})/(p + i\omega)`, and for the real (imaginary) radius
   :math:`\zeta^r_{k+1} = e^{ph}\zeta^r_k + \phi_1(|\operatorname{Re}(e^{-i\omega t_k}v_1)| + |\omega|h|v_1|)g^r`,
   :math:`\phi_1 = (e^{ph} - 1)/p` — the :math:`|\omega|h|v_1|` term covers the rotation inside the step;
4. :math:`x \in \operatorname{Re}(v_1^{-1}\operatorname{diag}(e^{i\omega t})\zeta)` by Theorem 2.1
   (:func:`intervalobs.complex_interval.real_part_bounds`), widened by the rounding margin.

``step(state, y_k, u_k)`` consumes the sample at :math:`t_k` (NaN = no sample at this grid point) and
returns the state at :math:`t_{k+1}`; ``run`` gives the same numbers.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..complex_interval import real_part_radius
from ..errors import AssumptionError, BoundsError, DesignError, DimensionError
from ..estimate import Estimate
from ..interval import inflate, matvec_bounds, neg, pos
from ..systems.bounds import Bounds
from ..systems.sampled import SampledSystem
from ..validation import as_choice, as_matrix, as_positive
from .base import Observer, ObserverState, options_after_bounds

if TYPE_CHECKING:
    from ..design.high_gain import ThetaDesign
    from ..design.regions import Disk, Region, RegionPlacement
    from ..design.width import WidthDesign

__all__ = ["HighGainIntervalObserver"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

_PICARD_TRIES = 6
_STEP_MARGIN = 8 * np.finfo(float).eps
"""Relative margin of :func:`~intervalobs.interval.inflate` on each modal step's radii: one step is a dot
product over the modes plus the centre's update, whose rounding is below 8 eps of the magnitudes involved.
Applied every step, so it does not accumulate (the radius recursion absorbs it)."""
_PICARD_SLACK = 1e-12
"""Relative growth of a rejected Picard candidate beyond the enclosure it failed (not a rounding pad: any
candidate is accepted only after the self-map check, so its size only affects how fast one is found)."""


class _Split:
    """A point matrix with its parts ``A⁺``, ``A⁻`` precomputed once: :func:`~intervalobs.interval.matvec_bounds`
    for the hot loop (same formula, tested equal; recomputing the parts every step costs 5-10 % of a run)."""

    def __init__(self, a: FloatArray) -> None:
        self.pos_t = pos(a).T.copy()
        self.neg_t = neg(a).T.copy()

    def bounds(self, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Exact bounds of ``a x`` for ``lo <= x <= hi``."""
        return lo @ self.pos_t - hi @ self.neg_t, hi @ self.pos_t - lo @ self.neg_t


class _Modal:
    """Precomputed exact-discretisation data of one observer (gain ``L``)."""

    def __init__(
        self,
        system: SampledSystem,
        L: FloatArray,
        h: float,
        order: list[complex] | None,
        scheme: str = "exact",
        theta: float = 0.0,
    ) -> None:
        from ..design.regions import modal_decomposition

        self.L = L
        self.ca = system.C @ system.A
        self.decomposition = modal_decomposition(system.A, system.C, L, order=order)
        lam = self.decomposition.eigenvalues
        p, w = lam.real, lam.imag
        self.omega = w
        self.v1 = self.decomposition.v1
        self.v1_inv = self.decomposition.v1_inv
        self.eph = np.exp(p * h)
        self.phi1 = np.expm1(p * h) / p
        self.psi = (self.eph - np.exp(-1j * w * h)) / (p + 1j * w)
        self.slack = (np.abs(w) * h)[:, None] * np.abs(self.v1)
        if scheme == "paper-euler":
            # explicit Euler on z = e^{-θt} ζ, rescaled to ζ: ζ+ = e^{θh}(1 + h(p - θ)) ζ + h e^{θh} R v1 g
            self.eph = np.exp(theta * h) * (1.0 + h * (p - theta))
            self.phi1 = np.full_like(p, h * np.exp(theta * h))
            self.psi = self.phi1.astype(complex)
            self.slack = np.zeros_like(self.slack)

    def rotations(self, t: FloatArray) -> dict[str, Any]:
        """Per-time matrices (leading axis = times), computed elementwise (same numbers in run/step)."""
        rot = np.exp(-1j * self.omega[None, :] * t[:, None])  # (T, n)
        rv = rot[:, :, None] * self.v1[None, :, :]  # diag(e^{-iωt}) v1
        back = self.v1_inv[None, :, :] * np.conj(rot)[:, None, :]  # v1^{-1} diag(e^{iωt})
        ca_back = self.ca[None, :, :] @ back  # C A x = Re(C A v1^{-1} diag(e^{iωt}) ζ)
        return {
            "in_centre": rv * self.psi[None, :, None],
            "in_re": self.phi1[None, :, None] * (np.abs(rv.real) + self.slack[None]),
            "in_im": self.phi1[None, :, None] * (np.abs(rv.imag) + self.slack[None]),
            "rv": rv,
            "back": back,
            "back_re": np.abs(back.real),
            "back_im": np.abs(back.imag),
            "rv_re": np.abs(rv.real),
            "rv_im": np.abs(rv.imag),
            "ca_back": ca_back,
            "ca_back_re": np.abs(ca_back.real),
            "ca_back_im": np.abs(ca_back.imag),
        }

    def to_box(
        self, back: ComplexArray, b_re: FloatArray, b_im: FloatArray, zc: ComplexArray, zr: FloatArray, zi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Real box of ``Re(back ζ)`` for ``ζ ∈ zc ± (zr + i zi)`` (Theorem 2.1), widened for rounding."""
        centre = np.real(zc @ back.T)
        radius = real_part_radius(b_re, b_im, zr, zi)
        return inflate(centre - radius, centre + radius)

    def rewrap(
        self,
        rot: dict[str, Any],
        k: int,
        lo: FloatArray,
        hi: FloatArray,
        zc: ComplexArray,
        zr: FloatArray,
        zi: FloatArray,
    ) -> tuple[ComplexArray, FloatArray, FloatArray]:
        """``ζ ∈ zc ± (zr + i zi)`` intersected with the rectangle of ``diag(e^{-iωt_k}) v1 [lo, hi]``.

        Both rectangles contain ζ(t_k) (Theorem 2.1 for the second), so their intersection, per real and
        imaginary part, does too; centre and radius are rounded outward.
        """
        xc, xr = 0.5 * (lo + hi), 0.5 * (hi - lo)
        image = xc @ rot["rv"][k].T
        image_r = xr @ rot["rv_re"][k].T
        image_i = xr @ rot["rv_im"][k].T
        re_lo = np.maximum(zc.real - zr, image.real - image_r)
        re_hi = np.minimum(zc.real + zr, image.real + image_r)
        im_lo = np.maximum(zc.imag - zi, image.imag - image_i)
        im_hi = np.minimum(zc.imag + zi, image.imag + image_i)
        scale = np.abs(re_lo) + np.abs(re_hi) + np.abs(im_lo) + np.abs(im_hi)
        centre = 0.5 * (re_lo + re_hi) + 1j * (0.5 * (im_lo + im_hi))
        _, new_r = inflate(0.0, 0.5 * (re_hi - re_lo), _STEP_MARGIN, scale=scale, floor=0.0)
        _, new_i = inflate(0.0, 0.5 * (im_hi - im_lo), _STEP_MARGIN, scale=scale, floor=0.0)
        return centre, new_r, new_i

    def output_derivative_part(
        self, rot: dict[str, Any], k: int, zc: ComplexArray, zr: FloatArray, zi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds of ``C A x(t_k)`` over the modal enclosure (Theorem 2.1 with ``C A v1^{-1} diag(e^{iωt_k})``)."""
        return self.to_box(rot["ca_back"][k], rot["ca_back_re"][k], rot["ca_back_im"][k], zc, zr, zi)

    def advance(
        self,
        rot: dict[str, Any],
        k: int,
        zc: ComplexArray,
        zr: FloatArray,
        zi: FloatArray,
        g_lo: FloatArray,
        g_hi: FloatArray,
    ) -> tuple[ComplexArray, FloatArray, FloatArray]:
        """One exact step of ``ζ' = diag(p) ζ + e^{-iωt} v1 g`` with ``g`` anywhere in its box."""
        gc = 0.5 * (g_lo + g_hi)
        gr = 0.5 * (g_hi - g_lo)
        new_c = self.eph * zc + gc @ rot["in_centre"][k].T
        centre_size = np.abs(new_c.real) + np.abs(new_c.imag)
        new_r = self.eph * zr + gr @ rot["in_re"][k].T
        new_i = self.eph * zi + gr @ rot["in_im"][k].T
        _, new_r = inflate(0.0, new_r, _STEP_MARGIN, scale=new_r + centre_size, floor=0.0)
        _, new_i = inflate(0.0, new_i, _STEP_MARGIN, scale=new_i + centre_size, floor=0.0)
        return new_c, new_r, new_i


class HighGainIntervalObserver(Observer):
    """Continuous–discrete high-gain interval observer: state bounds between sampled, noisy outputs.

    Two observers run together, as in the sampled-output high-gain paper: one bounds the noise-free
    output between samples and is corrected at each sample, the other bounds the state from those
    output bounds.

    Parameters
    ----------
    system : SampledSystem
        The partially linear model ``ẋ = Ax + φ(t, u, x) + d`` with outputs sampled at ``t_k``.
    bounds : Bounds
        ``x0`` (default initial box), ``w`` the box of the disturbance ``d``, ``v`` the box of ``V``.
    L : array_like, shape (n, p)
        Gain :math:`L_1 = \\theta\\Delta_\\theta^{-1}K` of the state-bound observer;
        ``A - L C`` must be Hurwitz and C-diagonalisable.
    h : float
        Grid step of the observer (the paper's Euler step; here an exact step).
    output_gain : array_like, shape (n, p), optional
        Gain of the output-bound observer; default ``L``. Its radius system must be
        stable (checked), which fails for large gains: the θ = 1000 design of Thabet et al. (2021)
        needs a small output gain here.
    theta : float
        The high-gain parameter, recorded only: it cancels from the bounds (module docstring).
    input_rate : float
        Bound of ``|du/dt|``, used to bound ``u`` inside a step (0: ``u`` is held over each step).
    order : list of complex, optional
        Eigenvalue order of the modal coordinates (e.g. the disk centres).
    refine : bool
        Report the intersection of the state-bound observer's box, the output-observer box and the
        slab ``{x : Cx ∈ output bounds}`` (all three enclose ``x(t_k)``) instead of the state-bound box
        alone (kept in ``Estimate.meta['theorem45_lower'/'theorem45_upper']``: the state-bound
        observer's own box, tightened by ``rewrap`` when that is on). Without ``rewrap`` this changes
        only what is reported and the a-priori boxes.
    predictor : {"modal", "box"}
        Bound of ``C ẋ`` over a step for the intersample output predictor: ``"box"`` is ``C F(B)`` over
        the a-priori box (the paper's predictor in interval form); ``"modal"`` (default) intersects it
        with ``CA x(t_k) + [0, h] CA F(B) + C(φ(B) + [d])``, ``CA x(t_k)`` bounded over both modal
        enclosures, which keep the correlations between the states that a box loses.
    rewrap : bool
        Intersect each observer's modal enclosure, after every step, with the rectangle of the
        reported box in its modal coordinates (both contain ζ; default True). With ``False`` the two
        observers run as the paper's and only the report is refined.
    scheme : {"exact", "paper-euler"}
        ``"exact"`` (sound, default) or the paper's explicit Euler step in the θ-shifted coordinates
        (evaluated rescaled, so it cannot overflow), with every input bounded at ``t_k`` only. The
        latter is NOT sound; it exists to measure what θ and the Euler step do to the paper's bounds.

    References
    ----------
    The sampled-output high-gain paper (:mod:`intervalobs.references`): model (8), the output-bound
    observer of Theorem 4.2 with the intersample predictor (12c), the state-bound observer of Theorem
    4.5 (meta keys ``theorem45_*``).
    """

    summary_fields = ("theta", "predictor", "rewrap", "scheme")
    missing_samples = True

    h: float

    def __init__(
        self,
        system: SampledSystem,
        bounds: Bounds,
        L: ArrayLike,
        h: float,
        *,
        output_gain: ArrayLike | None = None,
        theta: float = 0.0,
        input_rate: float = 0.0,
        order: list[complex] | None = None,
        refine: bool = True,
        predictor: str = "modal",
        rewrap: bool = True,
        scheme: str = "exact",
    ) -> None:
        if not isinstance(system, SampledSystem):
            raise DimensionError(f"system: expected a SampledSystem, got {type(system).__name__}")
        self.system = system
        self.n, self.p, self.m = system.n, system.p, system.m
        full = bounds.resolve(system)
        self.bounds = full
        self.h = as_positive("h", h, "a positive step")
        if not (np.isfinite(input_rate) and input_rate >= 0):
            raise BoundsError(f"input_rate: expected a nonnegative bound of |du/dt|, got {input_rate!r}")
        self.input_rate = float(input_rate)
        self.theta = float(theta)
        self.refine = bool(refine)
        self.predictor = as_choice("predictor", predictor, ("box", "modal"))
        self.rewrap = bool(rewrap)
        gain = as_matrix("L", L, (self.n, self.p))
        out_gain = gain if output_gain is None else as_matrix("output_gain", output_gain, (self.n, self.p))
        self.scheme = as_choice("scheme", scheme, ("exact", "paper-euler"))
        self.state_modal = _Modal(system, gain, self.h, order, scheme, self.theta)
        self.output_modal = _Modal(system, out_gain, self.h, order, scheme, self.theta)
        self.L = gain
        self.output_gain = out_gain
        self.output_radius_abscissa = self._output_radius_abscissa()
        if self.output_radius_abscissa >= 0:
            raise DesignError(
                f"output_gain ({'the placed gain L' if output_gain is None else 'as given'}): the output-bound "
                "observer with this gain diverges: the worst case of its error radii, fed back "
                f"through the gain from its own box, grows like exp({self.output_radius_abscissa:.3g} t) (its radius "
                "system is not Hurwitz), so its bounds of y between samples, and every state bound built on them, "
                "would grow without bound on this system. Give a smaller output_gain (zeros: the model's own modes) "
                "or disks nearer the eigenvalues of A"
            )
        self.d_lower, self.d_upper = full.w
        self._A = _Split(system.A)
        self._C = _Split(system.C)
        self._CA = _Split(system.C @ system.A)
        self._L = _Split(self.L)
        self._Lw = _Split(self.output_gain)
        self.v_lower, self.v_upper = full.v
        self.placement: RegionPlacement | None = None
        self.theta_design: ThetaDesign | None = None
        self.width_design: WidthDesign | None = None

    @classmethod
    @options_after_bounds("disks", "h")
    @shared_docs
    def design(
        cls,
        system: SampledSystem,
        bounds: Bounds,
        *,
        disks: Sequence[Disk | tuple[complex, float]],
        h: float,
        objective: str = "min_gain",
        alpha_d: float | None = None,
        alpha_n: float | None = None,
        input_rate: float = 0.0,
        refine: bool = True,
        output_gain: ArrayLike | None = None,
        predictor: str = "modal",
        rewrap: bool = True,
    ) -> HighGainIntervalObserver:
        """Place the error's eigenvalues in the given disks, then (optionally) compute the high gain θ.

        The constructive design of the sampled-output high-gain paper.

        Parameters
        ----------
        %(sampled_system_bounds)s
        disks : sequence of Disk or (centre, radius)
            One disk per eigenvalue of ``A - L1 C`` (conjugate pairs for complex ones).
        h : float
            Grid step.
        objective : {"min_gain", "center"}
            Passed to :func:`~intervalobs.design.regions.place_in_disks`.
        alpha_d, alpha_n : float, optional
            The margins θ must leave for the disturbance and the noise; when both are given θ is
            computed (both readings of the paper, in
            ``theta_design``) and recorded — it does not change the bounds.
        input_rate : float
            Bound of ``|du/dt|``.
        refine : bool
            See the class parameters.
        output_gain : array_like, shape (n, p), optional
            Gain of the output-bound observer (default: the placed ``L1``; give a small one, e.g.
            zeros, when the placed gain makes its radius system unstable).
        predictor, rewrap : see the class parameters (``"box"`` and ``False``: the paper's observer).

        Returns
        -------
        HighGainIntervalObserver
            With ``placement`` (and ``theta_design``) set.

        Raises
        ------
        DesignError
            If no gain places the eigenvalues in the disks, or the output-bound observer with
            ``output_gain`` (default: the placed gain) diverges (its radius system is not Hurwitz).

        References
        ----------
        The sampled-output high-gain paper: Algorithm 1 (the gain ``L1``), Theorem 4.4 with the
        scalars of (34) (θ), model (8).
        """
        from ..design.high_gain import theta_design
        from ..design.regions import place_in_disks

        placement = place_in_disks(system.A, system.C, disks, objective=objective)
        full = bounds.resolve(system)
        design = None
        if alpha_d is not None and alpha_n is not None:
            d_radius = full.radius("w")
            v_radius = np.maximum(np.abs(full.v[0]), np.abs(full.v[1]))
            design = theta_design(placement.modal, placement.L, system.C, d_radius, v_radius, alpha_d, alpha_n)
        observer = cls(
            system,
            full,
            placement.L,
            h,
            theta=0.0 if design is None else design.theta_sound,
            input_rate=input_rate,
            order=[d.center for d in placement.disks],
            refine=refine,
            output_gain=output_gain,
            predictor=predictor,
            rewrap=rewrap,
        )
        observer.placement = placement
        observer.theta_design = design
        return observer

    @classmethod
    @options_after_bounds("h")
    @shared_docs
    def design_for_width(
        cls,
        system: SampledSystem,
        bounds: Bounds,
        *,
        h: float,
        phi_radius: ArrayLike,
        input_rate: float,
        weights: ArrayLike | None = None,
        regions: Sequence[Region] = (),
        output_radius: ArrayLike | None = None,
        output_gain: ArrayLike | None = None,
        max_condition: float = 100.0,
    ) -> HighGainIntervalObserver:
        """Gain and LMI regions chosen for width (:func:`~intervalobs.design.width.design_for_width`).

        Parameters
        ----------
        %(sampled_system_bounds)s
        h : float
            Grid step.
        phi_radius : array_like, shape (n,)
            Radius of the range of φ over any box and the input over one step (design value).
        input_rate : float
            Bound of ``|du/dt|`` (the observer's soundness depends on it: no default).
        weights : array_like, shape (n,), optional
            Weights of the mean widths in the objective.
        regions : sequence of Disk, HalfPlane, VerticalStrip, HorizontalStrip, Sector
            Constraint regions for every eigenvalue of ``A - L1 C``.
        output_radius : array_like, shape (p,), optional
            Output radius of the bound (default: the noise radius δ).
        output_gain : array_like, shape (n, p), optional
            Gain of the output-bound observer (default zero; its radius system must be stable).
        max_condition : float
            Largest accepted ``cond(v1)``.

        Returns
        -------
        HighGainIntervalObserver
            With ``width_design`` and ``placement`` set.
        """
        from ..design.width import design_for_width

        full = bounds.resolve(system)
        d_radius = full.radius("w")
        v_radius = np.maximum(np.abs(full.v[0]), np.abs(full.v[1]))
        result = design_for_width(
            system.A,
            system.C,
            h,
            d_radius=d_radius,
            phi_radius=phi_radius,
            output_radius=v_radius if output_radius is None else output_radius,
            weights=weights,
            regions=regions,
            max_condition=max_condition,
        )
        observer = cls(
            system,
            full,
            result.L,
            h,
            input_rate=input_rate,
            output_gain=np.zeros_like(result.L) if output_gain is None else output_gain,
            order=[d.center for d in result.disks],
        )
        observer.placement = result.placement
        observer.width_design = result
        return observer

    def _output_radius_abscissa(self) -> float:
        """Spectral abscissa of the worst-case radius system of the output observer (Prop. 4.3, a = 0)."""
        mod = self.output_modal
        k = np.abs(mod.v1) @ np.abs(self.output_gain) @ np.abs(self.system.C) @ np.abs(mod.v1_inv)
        diag = np.diag(mod.decomposition.p1) + k
        return float(np.max(np.linalg.eigvals(np.block([[diag, k], [k, diag]])).real))

    # ------------------------------------------------------------------ protocol
    def init(
        self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None, t0: float = 0.0
    ) -> ObserverState:
        """State at ``t0`` from the prior box, in modal coordinates: ``z^c(0) = v1 x^c(0)``, ``z^r(0) = v1 ∘ x^r(0)``.

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,) or (M, n), optional
            Prior box of ``x(t0)`` (default: ``bounds.x0``).
        t0 : float
            Initial time.

        Returns
        -------
        ObserverState
        """
        lo, hi = self._prior_boxes(self.bounds.x0, x0_lower, x0_upper)
        return self._initial(lo, hi, float(t0))

    def _initial(self, lo: FloatArray, hi: FloatArray, t0: float) -> ObserverState:
        lo, hi = self.system.in_domain(lo, hi)
        internal: dict[str, Any] = {"t": t0}
        xc, xr = 0.5 * (lo + hi), 0.5 * (hi - lo)
        for key, mod in (("s", self.state_modal), ("w", self.output_modal)):
            rv = mod.rotations(np.array([t0]))["rv"][0]
            internal[key + "c"] = xc @ rv.T
            internal[key + "r"] = xr @ np.abs(rv.real).T
            internal[key + "i"] = xr @ np.abs(rv.imag).T
        internal["xw_lower"], internal["xw_upper"] = lo.copy(), hi.copy()
        internal["xs_lower"], internal["xs_upper"] = lo.copy(), hi.copy()
        internal["y_lower"], internal["y_upper"] = matvec_bounds(self.system.C, lo, hi)
        return ObserverState(lo.copy(), hi.copy(), internal=internal)

    def _refined(
        self, lo: FloatArray, hi: FloatArray, y_lo: FloatArray, y_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Box ∩ ``{x : y_lo <= Cx <= y_hi}``: one pass of constraint propagation per output row."""
        c = self.system.C
        terms_lo = np.minimum(c * lo[..., None, :], c * hi[..., None, :])  # (..., p, n)
        terms_hi = np.maximum(c * lo[..., None, :], c * hi[..., None, :])
        rest_lo = terms_lo.sum(axis=-1, keepdims=True) - terms_lo
        rest_hi = terms_hi.sum(axis=-1, keepdims=True) - terms_hi
        num_lo = y_lo[..., :, None] - rest_hi  # c_ji x_i ∈ [num_lo, num_hi]
        num_hi = y_hi[..., :, None] - rest_lo
        with np.errstate(divide="ignore", invalid="ignore"):
            q1, q2 = num_lo / c, num_hi / c
        active = c != 0
        cand_lo = np.where(active, np.minimum(q1, q2), -np.inf)
        cand_hi = np.where(active, np.maximum(q1, q2), np.inf)
        cand_lo, cand_hi = inflate(cand_lo, cand_hi)
        new_lo = np.maximum(lo, cand_lo.max(axis=-2))
        new_hi = np.minimum(hi, cand_hi.min(axis=-2))
        return new_lo, new_hi

    def _step(
        self, state: ObserverState, y: FloatArray, u: FloatArray, times: FloatArray | None = None
    ) -> ObserverState:
        """Consume ``y(t_k)`` (all-NaN: no sample at this grid point) and ``u_k``; return the state at ``t_{k+1}``.

        ``times`` is ``(t_k, t_{k+1})`` from the record's grid (default: the state's time and one step
        ``h`` later). ``internal`` of the result holds the box of ``Cx(t_k)`` with the sample taken into
        account (``output_lower``/``output_upper``).
        """
        t = float(state.internal["t"]) if times is None else float(times[0])
        pair = np.array([t, t + self.h]) if times is None else np.asarray(times, dtype=float)
        rot_s = self.state_modal.rotations(pair)
        rot_w = self.output_modal.rotations(pair)
        new, (y_lo, y_hi) = self._advance(state, y, u, t, rot_s, rot_w, 0)
        new.internal["output_lower"], new.internal["output_upper"] = y_lo, y_hi
        return new

    def run(self, t: ArrayLike, y: ArrayLike, u: ArrayLike | None = None) -> Estimate:
        """Bounds on a uniform grid of step ``h``; ``y`` is NaN where no sample was taken.

        Parameters
        ----------
        t : array_like, shape (T,)
            Grid, step ``h``.
        y : array_like, shape (T, p) or (M, T, p)
            Measurements at the sample times, all-NaN rows elsewhere.
        u : array_like, shape (T, m) or (M, T, m), optional
            Known input on the grid.

        Returns
        -------
        Estimate
            State bounds; ``meta`` holds the output bounds (``output_lower``/``output_upper``: bounds
            of the noise-free output ``Cx(t_k)``, with the sample at ``t_k`` taken into account) and
            the state-bound observer's own box (``theorem45_lower``/``theorem45_upper``).
        """
        times, ys, us = self._signals(t, y, u)
        state = self._initial(*self.bounds.x0, float(times[0]))
        grid = np.stack([times, np.append(times[1:], times[-1] + self.h)], axis=-1)
        estimate, rows = self._loop(
            times, ys, us, state, {"times": grid}, ("xs_lower", "xs_upper", "y_lower", "y_upper")
        )
        out_lo, out_hi = self._measured_output(rows["y_lower"], rows["y_upper"], ys)
        estimate.meta.update(
            output_lower=out_lo, output_upper=out_hi, theorem45_lower=rows["xs_lower"], theorem45_upper=rows["xs_upper"]
        )
        return estimate

    def meta(self) -> dict[str, Any]:
        """Facts recorded in every :class:`~intervalobs.estimate.Estimate` of :meth:`run`.

        Returns
        -------
        dict
            ``method``, ``L``, ``output_gain``, ``theta``, ``eigenvalues`` and ``refined``.
        """
        return {
            "method": "high-gain interval observer with sampled outputs (the sampled-output high-gain paper), "
            + ("sound exact discretisation" if self.scheme == "exact" else "paper's Euler step (not sound)"),
            "L": self.L,
            "output_gain": self.output_gain,
            "theta": self.theta,
            "eigenvalues": self.state_modal.decomposition.eigenvalues,
            "refined": self.refine,
        }

    # ------------------------------------------------------------------ internals
    def _measured_output(self, lo: FloatArray, hi: FloatArray, yk: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Box of ``Cx(t_k)``: the predicted one ``[lo, hi]`` (27) intersected with the measurement box (28)–(29)."""
        if np.isnan(yk).all():
            return lo, hi
        have = ~np.isnan(yk).any(axis=-1, keepdims=True)
        meas_lo, meas_hi = inflate(
            np.where(have, yk - self.v_upper, -np.inf), np.where(have, yk - self.v_lower, np.inf)
        )
        new_lo, new_hi = np.maximum(lo, meas_lo), np.minimum(hi, meas_hi)
        if self.scheme == "paper-euler":  # unsound scheme: keep the measurement box where they disagree
            empty = new_lo > new_hi
            return np.where(empty, meas_lo, new_lo), np.where(empty, meas_hi, new_hi)
        if np.any(new_lo > new_hi):
            raise AssumptionError(
                "y: a measurement is inconsistent with the output bounds (noise or disturbance outside their boxes, "
                "or a wrong model)"
            )
        return new_lo, new_hi

    def _enclosure(
        self,
        lo: FloatArray,
        hi: FloatArray,
        t: float,
        u_lo: FloatArray,
        u_hi: FloatArray,
        guess: tuple[FloatArray, FloatArray] | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """A-priori box ``B ⊇ {x(s) : s ∈ [t, t+h]}`` (Picard self-map) and the bounds of φ and ẋ over it.

        The first candidate widens the box by twice the previous step's bound of ``h ẋ`` (``guess``);
        whatever the candidate, it is accepted only if ``X + [0, h] F(B) ⊆ B``. Every candidate is cut to
        the state domain ``D`` first: the trajectory stays in ``D`` (the model's claim), so as long as it
        stays in ``B`` its derivative lies in ``F(B ∩ D)`` and the trajectory in ``(X + [0, h] F(B ∩ D)) ∩ D``;
        that set inside ``B ∩ D`` keeps it in ``B ∩ D`` over the whole step by the same argument as without a
        domain.
        """
        h = self.h
        sys = self.system
        if guess is not None and guess[0].shape == lo.shape:
            b_lo = lo + 2.0 * h * np.minimum(guess[0], 0.0)
            b_hi = hi + 2.0 * h * np.maximum(guess[1], 0.0)
        else:
            b_lo, b_hi = lo, hi
        grow = 1.0
        for _ in range(_PICARD_TRIES):
            b_lo, b_hi = sys.in_domain(b_lo, b_hi)
            f_lo, f_hi, p_lo, p_hi = self._field(b_lo, b_hi, t, u_lo, u_hi)
            cand_lo, cand_hi = sys.in_domain(lo + np.minimum(0.0, h * f_lo), hi + np.maximum(0.0, h * f_hi))
            if np.all(cand_lo >= b_lo) and np.all(cand_hi <= b_hi):
                return b_lo, b_hi, p_lo, p_hi, f_lo, f_hi
            pad = grow * (cand_hi - cand_lo - (hi - lo)) + _PICARD_SLACK * (1 + np.abs(lo) + np.abs(hi))
            b_lo, b_hi = np.minimum(b_lo, cand_lo - pad), np.maximum(b_hi, cand_hi + pad)
            grow *= 2.0
        raise AssumptionError(
            f"h: no a-priori enclosure over a step of {h:g} s (the vector field grows too fast over the box); "
            f"use a smaller step ({sys!r})"
        )

    def _field(
        self, lo: FloatArray, hi: FloatArray, t: float, u_lo: FloatArray, u_hi: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        sys = self.system
        p_lo, p_hi = sys.nonlinearity_bounds(t, t + self.h, u_lo, u_hi, lo, hi)
        p_lo, p_hi = inflate(p_lo, p_hi)
        a_lo, a_hi = self._A.bounds(lo, hi)
        f_lo, f_hi = a_lo + p_lo + self.d_lower, a_hi + p_hi + self.d_upper
        return f_lo, f_hi, p_lo, p_hi

    def _output_derivative(
        self,
        internal: dict[str, Any],
        k: int,
        rots: tuple[dict[str, Any], dict[str, Any]],
        box: tuple[FloatArray, FloatArray],
        field: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    ) -> tuple[FloatArray, FloatArray]:
        """Bound of ``C ẋ(s)`` over the step: ``CA x(t_k) + [0, h] CA F(B) + C(φ(B) + [d])``.

        ``x(s) = x(t_k) + ∫ ẋ`` with ``ẋ ∈ F(B)`` gives ``CA x(s) ∈ CA x(t_k) + τ CA F(B)``, ``τ ∈ [0, h]``;
        ``CA x(t_k)`` is bounded over the box ``box`` at ``t_k`` and over both modal enclosures (Theorem
        2.1), which keep the correlations a box loses. ``field`` is ``(F_lo, F_hi, φ_lo, φ_hi)`` over B.
        """
        f_lo, f_hi, p_lo, p_hi = field
        ca_lo, ca_hi = self._CA.bounds(*box)
        for key, mod, rot in zip(("s", "w"), (self.state_modal, self.output_modal), rots):
            zeta = (internal[key + "c"], internal[key + "r"], internal[key + "i"])
            m_lo, m_hi = mod.output_derivative_part(rot, k, *zeta)
            ca_lo, ca_hi = np.maximum(ca_lo, m_lo), np.minimum(ca_hi, m_hi)
        caf_lo, caf_hi = self._CA.bounds(f_lo, f_hi)
        rest_lo, rest_hi = self._C.bounds(p_lo + self.d_lower, p_hi + self.d_upper)
        return inflate(
            ca_lo + self.h * np.minimum(0.0, caf_lo) + rest_lo, ca_hi + self.h * np.maximum(0.0, caf_hi) + rest_hi
        )

    def _advance(
        self,
        state: ObserverState,
        yk: FloatArray,
        uk: FloatArray,
        t: float,
        rot_s: dict[str, Any],
        rot_w: dict[str, Any],
        k: int,
    ) -> tuple[ObserverState, tuple[FloatArray, FloatArray]]:
        internal = state.internal
        # every box below encloses x(t_k): the a-priori enclosure starts from their intersection
        y_lo, y_hi = self._measured_output(internal["y_lower"], internal["y_upper"], yk)
        if self.refine and np.all(np.isnan(yk)):
            x_lo, x_hi = state.lower, state.upper  # already the refined intersection at t_k
        else:
            x_lo, x_hi = self._refined(
                np.maximum(internal["xs_lower"], internal["xw_lower"]),
                np.minimum(internal["xs_upper"], internal["xw_upper"]),
                y_lo,
                y_hi,
            )
            x_lo, x_hi = self.system.in_domain(x_lo, x_hi)
        u_lo, u_hi = uk - self.input_rate * self.h, uk + self.input_rate * self.h
        if self.scheme == "paper-euler":  # the paper: inputs evaluated on the box at t_k only
            b_lo, b_hi = x_lo, x_hi
            f_lo, f_hi, p_lo, p_hi = self._field(x_lo, x_hi, t, uk, uk)
        else:
            b_lo, b_hi, p_lo, p_hi, f_lo, f_hi = self._enclosure(x_lo, x_hi, t, u_lo, u_hi, internal.get("f"))
        cb_lo, cb_hi = self._C.bounds(b_lo, b_hi)
        cf_lo, cf_hi = self._C.bounds(f_lo, f_hi)
        if self.predictor == "modal":
            md_lo, md_hi = self._output_derivative(internal, k, (rot_s, rot_w), (x_lo, x_hi), (f_lo, f_hi, p_lo, p_hi))
            cf_lo, cf_hi = np.maximum(cf_lo, md_lo), np.minimum(cf_hi, md_hi)
        # intersample predictor (12c)-(12d): Cx(s) ∈ Cx(t_k) + [0, h]·C F(B), intersected with C B
        step_lo = np.maximum(cb_lo, y_lo + np.minimum(0.0, self.h * cf_lo))
        step_hi = np.minimum(cb_hi, y_hi + np.maximum(0.0, self.h * cf_hi))
        base_lo = p_lo + self.d_lower
        base_hi = p_hi + self.d_upper
        lw_lo, lw_hi = self._Lw.bounds(cb_lo, cb_hi)
        ls_lo, ls_hi = self._L.bounds(step_lo, step_hi)
        new: dict[str, Any] = {"t": t + self.h, "f": (f_lo, f_hi)}
        boxes = {}
        for key, mod, rot, g_lo, g_hi in (
            ("w", self.output_modal, rot_w, base_lo + lw_lo, base_hi + lw_hi),
            ("s", self.state_modal, rot_s, base_lo + ls_lo, base_hi + ls_hi),
        ):
            zc, zr, zi = mod.advance(rot, k, internal[key + "c"], internal[key + "r"], internal[key + "i"], g_lo, g_hi)
            new[key + "c"], new[key + "r"], new[key + "i"] = zc, zr, zi
            boxes[key] = mod.to_box(rot["back"][k + 1], rot["back_re"][k + 1], rot["back_im"][k + 1], zc, zr, zi)
        new["xw_lower"], new["xw_upper"] = boxes["w"]
        new["xs_lower"], new["xs_upper"] = boxes["s"]
        nx_lo = np.maximum(boxes["s"][0], boxes["w"][0])
        nx_hi = np.minimum(boxes["s"][1], boxes["w"][1])
        pc_lo, pc_hi = self._C.bounds(nx_lo, nx_hi)
        new["y_lower"] = np.maximum(pc_lo, y_lo + self.h * cf_lo)
        new["y_upper"] = np.minimum(pc_hi, y_hi + self.h * cf_hi)
        new["y_lower"], new["y_upper"] = inflate(new["y_lower"], new["y_upper"])
        if self.refine:
            out_lo, out_hi = self._refined(nx_lo, nx_hi, new["y_lower"], new["y_upper"])
        else:
            out_lo, out_hi = boxes["s"]
        out_lo, out_hi = self.system.in_domain(out_lo, out_hi)
        if self.rewrap:
            for key, mod, rot in (("s", self.state_modal, rot_s), ("w", self.output_modal, rot_w)):
                new[key + "c"], new[key + "r"], new[key + "i"] = mod.rewrap(
                    rot, k + 1, out_lo, out_hi, new[key + "c"], new[key + "r"], new[key + "i"]
                )
        return ObserverState(out_lo, out_hi, internal=new), (y_lo, y_hi)
