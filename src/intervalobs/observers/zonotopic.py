r"""The integrated-observer paper's zonotopic set-based observer (Prop. 3.1) and integrated observer (Theorem 5.3).

Model (the integrated-observer paper, (1)): :math:`x_{k+1} = (A_0 + \Delta A(\theta))x_k + Bu_k + E_\omega\omega_k`,
:math:`y_k = Cx_k + E_\upsilon\upsilon_k`, with :math:`\Delta A(\theta)` constant in the box ``system.dA``
and the noises in the boxes of ``bounds``. Substituting :math:`LCx_k = Ly_k - LE_\upsilon\upsilon_k`,

.. math:: x_{k+1} = A^*(\theta)x_k + Bu_k + Ly_k + E_\omega\omega_k - LE_\upsilon\upsilon_k,\qquad
          A^*(\theta) = A_0 + \Delta A(\theta) - LC,

holds *exactly* for the true state, for every admissible θ, ω, υ. Both observers here enclose the set
of such states:

* :class:`ZonotopicObserver` propagates a zonotope :math:`\langle c_k, R_k\rangle` with the
  interval-matrix inclusion of Properties 3–4 (made sound, see
  :func:`intervalobs.zonotope.interval_matrix_image`) and Combastel's reduction (Property 2):
  Prop. 3.1, (7).
* :class:`IntegratedObserver` is the integrated scheme (63)–(65): the centre follows the Luenberger
  recursion (63) and the segments (the radius) the interval recursion (64), with the uncertainty
  bounded soundly: :math:`|M|` instead of :math:`M` for the segments (any sign of
  :math:`M = A_0 - LC`) and Lemma A.1 for :math:`\Delta A(\theta)x` instead of the approximation of
  Lemma A.2. In this sound form it *is* the centre–radius framer of
  :class:`~intervalobs.observers.interval_observer.IntervalObserver` (so the recursion is reused),
  which is also the sound version of the interval observer (39)–(40) with one gain: Corollary 5.4
  (the schemes coincide) holds exactly. What the class adds is the gain design of Theorem 5.3
  (LMI (19) with (65), diagonal ``P``) and the explicit fallback when monotonicity is impossible.

Both treat θ as if it could vary from step to step (the set-based "time-varying" approach); that is
sound for a constant θ too.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._docstrings import shared_docs
from ..design.hinf import GainDesign, hinf_gain, zonotope_size_gain
from ..errors import ArgumentTypeError, AssumptionError, DesignError
from ..interval import inflate
from ..systems.bounds import Bounds
from ..systems.lti import LTISystem, refuse_uncertain_input
from ..systems.sampling import sampled_model
from ..validation import as_matrix, check_no_kwargs
from ..zonotope import hull_radius, interval_matrix_image, reduce_order
from .base import Observer, ObserverState, options_after_bounds
from .interval_observer import IntervalObserver

__all__ = ["IntegratedObserver", "ZonotopicObserver"]

FloatArray = NDArray[np.float64]

_EPS = float(np.finfo(float).eps)
_TINY = float(np.finfo(float).tiny)


class ZonotopicObserver(Observer):
    r"""Zonotopic set-based observer: the error set kept as a zonotope, whose box holds the state.

    For a discrete-time model with an uncertain ``dA`` (the set-based observer of the integrated-observer
    paper, with a sound inclusion of the interval matrix product).

    With :math:`A^* = A_0 + \Delta A - LC` an interval matrix (midpoint :math:`M`, radius :math:`D`),

    .. math::

        c_{k+1} &= M c_k + Bu_k + Ly_k + E_\omega\omega_c - LE_\upsilon\upsilon_c, \\
        R_{k+1} &= [\,M\check R_k,\ \mathrm{diag}(D(|c_k| + |\check R_k|\mathbf 1)),\
                   E_\omega\mathrm{diag}(\omega_r),\ -LE_\upsilon\mathrm{diag}(\upsilon_r)\,],

    :math:`\check R_k = \downarrow_q R_k` (the zonotope reduced to ``q`` generators); the diagonal
    block replaces the printed ``⋄(A*Ř)`` / ``diam(A*)/2 c`` terms by their sound form. The state bounds
    are the interval hull :math:`c_k \pm |R_k|\mathbf 1`. Each step also adds the floating-point error bound of its own
    dot products to the diagonal block, so the enclosure does not depend on a contraction argument.

    Stability certificate: the hull radius :math:`h_k = |R_k|\mathbf 1` obeys
    :math:`h_{k+1} \le (|M| + D)h_k + D|c_k| + \text{noise}`, and :math:`c_k` is a Luenberger
    estimate, so :math:`\rho(|M| + D) < 1` bounds the widths (``certified``). It is sufficient only:
    the zonotope's exact linear map :math:`M\check R` can contract when :math:`|M|` does not.
    With the same gain the zonotope's hull is never wider than the interval framer's.

    Parameters
    ----------
    system : LTISystem
        Discrete-time model (``dA`` optional).
    bounds : Bounds
        Boxes of ``x0``, ``w`` (ω) and ``v`` (υ).
    L : array_like, shape (n, p)
        Observer gain.
    order : int, optional
        Reduction order ``q`` (generators kept); default ``5 n``.
    allow_unstable : bool
        Accept a gain with :math:`\rho(M) \ge 1` (the bounds stay sound but diverge); only for
        showing the paper's failure modes.

    Raises
    ------
    AssumptionError
        For a continuous-time system.
    DesignError
        When :math:`\rho(A_0 + \mathrm{mid}\,\Delta A - LC) \ge 1` and not ``allow_unstable``.

    References
    ----------
    The integrated-observer paper (:mod:`intervalobs.references`): Proposition 3.1 (the observer),
    (7a)–(7b) (the reduction :math:`\downarrow_q`), (57) (the interval hull).
    """

    summary_fields = ("order", "spectral_radius", "width_spectral_radius")

    h: float

    def __init__(
        self,
        system: LTISystem,
        bounds: Bounds,
        L: ArrayLike,
        order: int | None = None,
        allow_unstable: bool = False,
    ) -> None:
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not isinstance(bounds, Bounds):
            raise ArgumentTypeError(f"bounds: expected a Bounds, got {type(bounds).__name__}")
        if system.continuous:
            raise AssumptionError("system: the zonotopic observer is for discrete time only (give dt), got dt=None")
        refuse_uncertain_input(system, "ZonotopicObserver")
        self.system = system
        self.bounds = bounds.resolve(system)
        self.n, self.p, self.m = system.n, system.p, system.m
        self.h = float(system.dt or 1.0)
        self.L = as_matrix("L", L, (self.n, self.p))
        self.order = 5 * self.n if order is None else int(order)
        if self.order < self.n:
            raise DesignError(f"order: expected at least n = {self.n}, got {self.order}")
        model = sampled_model(system, self.bounds)
        self.M = model.Phi - self.L @ system.C
        self.D = model.dPhi
        self.spectral_radius = float(np.max(np.abs(np.linalg.eigvals(self.M))))
        if self.spectral_radius >= 1 and not allow_unstable:
            raise DesignError(
                f"L: expected rho(A0 + mid dA - LC) < 1, got {self.spectral_radius:.6g}; the zonotopes would diverge"
            )
        width = np.abs(self.M) + self.D
        self.width_spectral_radius = float(np.max(np.abs(np.linalg.eigvals(width))))
        self.certified = self.width_spectral_radius < 1
        w_c = self.bounds.centre("w")
        w_r = self.bounds.radius("w")
        v_c = self.bounds.centre("v")
        v_r = self.bounds.radius("v")
        LF = self.L @ system.F
        self._B = model.Gamma
        self._offset = system.E @ w_c - LF @ v_c
        noise = np.hstack([system.E * w_r, -LF * v_r])
        self._noise = noise[:, np.any(noise != 0, axis=0)]
        self._a_lower = self.M - self.D
        self._a_upper = self.M + self.D
        self._abs_a = np.abs(self.M) + self.D
        self._dot_length = self.n + self.p + self.m + self.order + self._noise.shape[1] + 2
        self.gain_design: GainDesign | None = None

    @classmethod
    @shared_docs
    def design(cls, system: LTISystem, bounds: Bounds, **options: Any) -> ZonotopicObserver:
        """Gain that keeps the zonotope small (default) or bounds the noise-to-error gain, then the observer.

        Parameters
        ----------
        %(lti_system_bounds)s
        **options
            ``lmi`` (``"(26)"`` default: the zonotope-size LMI, or ``"(19)"``: the H∞ LMI), ``rho``
            (contraction factor the zonotope-size LMI asks of the error, default 0.9), ``E_theta``
            (directions in which ``dA`` moves the state, default identity), ``order`` (reduction order,
            default ``5 n``).

        Returns
        -------
        ZonotopicObserver
            With ``gain_design`` holding the verified :class:`~intervalobs.design.hinf.GainDesign`.

        References
        ----------
        The integrated-observer paper: LMI (26) and Theorem 3.5 (zonotope size), LMI (19) (H∞),
        Lemma A.2 (``E_theta``). The option values ``"(26)"`` and ``"(19)"`` are those equation labels.
        """
        check_no_kwargs("ZonotopicObserver.design", options, ("lmi", "rho", "E_theta", "order"))
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        lmi = options.get("lmi", "(26)")
        args = (system.A, system.C, system.E, system.F, options.get("E_theta"))
        if lmi == "(26)":
            result = zonotope_size_gain(*args, rho=float(options.get("rho", 0.9)))
        elif lmi == "(19)":
            result = hinf_gain(*args)
        else:
            raise DesignError(f"lmi: expected '(26)' or '(19)', got {lmi!r}")
        observer = cls(system, bounds, result.gain, order=options.get("order"))
        observer.gain_design = result
        return observer

    def init(self, x0_lower: ArrayLike | None = None, x0_upper: ArrayLike | None = None) -> ObserverState:
        """The initial zonotope: the box known to hold ``x(0)`` (default ``bounds.x0``).

        Parameters
        ----------
        x0_lower, x0_upper : array_like, shape (n,), optional

        Returns
        -------
        ObserverState
            ``internal`` holds ``center`` (n,) and ``generators`` (n, n).
        """
        lo, hi = self._prior_box(self.bounds.x0, x0_lower, x0_upper)
        center = 0.5 * (lo + hi)
        generators = np.diag(0.5 * (hi - lo))
        return ObserverState(lo.copy(), hi.copy(), internal={"center": center, "generators": generators})

    def _step(self, state: ObserverState, y: FloatArray, u: FloatArray) -> ObserverState:
        """Propagate the zonotope from ``k`` to ``k+1`` with ``y_k`` and ``u_k`` ((7a)–(7b)).

        ``internal`` holds ``center`` (..., n) and ``generators`` (..., n, r).
        """
        c, g = state.internal["center"], state.internal["generators"]
        lead = np.broadcast_shapes(c.shape[:-1], y.shape[:-1], u.shape[:-1])  # runs of a batched y or u
        if c.shape[:-1] != lead:  # the first step of a batch from the shared prior
            c, g = np.broadcast_to(c, (*lead, self.n)), np.broadcast_to(g, (*lead, *g.shape[-2:]))
        c, g = self._advance(c, g, y, u)
        lower, upper = self._hull(c, g)
        return ObserverState(lower, upper, internal={"center": c, "generators": g})

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            ``method``, ``L``, reduction ``order``, ``spectral_radius``, ``width_spectral_radius``,
            ``certified``, ``transient_s``, and ``gain_design`` when designed.
        """
        info: dict[str, Any] = {
            "method": "ZonotopicObserver (zonotopic set-based observer, the integrated-observer paper)",
            "L": self.L.tolist(),
            "order": self.order,
            "spectral_radius": self.spectral_radius,
            "width_spectral_radius": self.width_spectral_radius,
            "certified": self.certified,
            "transient_s": 0.0,
        }
        if self.gain_design is not None:
            info["gain_design"] = self.gain_design.as_dict()
        return info

    def _advance(self, c: FloatArray, g: FloatArray, y: FloatArray, u: FloatArray) -> tuple[FloatArray, FloatArray]:
        reduced = reduce_order(g, self.order)
        q = reduced.shape[-1]
        new_c, new_g = interval_matrix_image(self._a_lower, self._a_upper, c, reduced)
        new_c = new_c + y @ self.L.T + u @ self._B.T + self._offset
        # floating-point error of this step's dot products, added to the diagonal (box) block
        scale = (np.abs(c) + hull_radius(reduced)) @ self._abs_a.T + np.abs(y) @ np.abs(self.L).T
        scale = scale + np.abs(u) @ np.abs(self._B).T + np.abs(self._offset) + hull_radius(new_g)
        pad = 2 * self._dot_length * _EPS * scale + _TINY
        box = new_g[..., q:] + pad[..., :, None] * np.eye(self.n)
        noise = np.broadcast_to(self._noise, (*new_c.shape[:-1], *self._noise.shape))
        new_g = np.concatenate([new_g[..., :q], box, noise], axis=-1)
        return new_c, new_g

    def _hull(self, c: FloatArray, g: FloatArray) -> tuple[FloatArray, FloatArray]:
        r = hull_radius(g)
        return inflate(c - r, c + r)


@shared_docs
class IntegratedObserver(IntervalObserver):
    r"""Integrated interval observer: a centre and a radius propagated separately, sound for any gain.

    The integrated observer of the integrated-observer paper, made sound for any sign of the error
    matrix. Centre and radius follow

    .. math::

        c_{k+1} &= Mc_k + Bu_k + Ly_k + E_\omega\omega_c - LE_\upsilon\upsilon_c,\\
        r_{k+1} &= |M|r_k + |E_\omega|\omega_r + |LE_\upsilon|\upsilon_r + D(|c_k| + r_k),

    :math:`x_{\sup/\inf} = c \pm r`, with :math:`M = A_0 + \mathrm{mid}\,\Delta A - LC` and ``D`` the
    radius of ``ΔA`` (the exact bound of an interval matrix times an interval vector, in centre–radius
    form). For :math:`M \ge 0` this is the paper's recursion literally; for any sign it stays sound.
    The recursion is that of :class:`~intervalobs.observers.interval_observer.IntervalObserver` with
    ``T = I`` (inherited); stability is certified by :math:`\rho(|M| + D) < 1` (checked on construction).

    Parameters
    ----------
    %(lti_system_bounds)s
    L : array_like, shape (n, p)
        Gain; :meth:`design` computes it from the H∞ and monotonicity LMIs.

    References
    ----------
    The integrated-observer paper: Theorem 5.3 (the observer), (63) (centre), (64) (segments), Lemma
    A.1 (interval matrix product), LMIs (19) and (65) (the gain).
    """

    def __init__(self, system: LTISystem, bounds: Bounds, L: ArrayLike) -> None:
        if isinstance(system, LTISystem) and system.continuous:
            raise AssumptionError("system: the integrated observer is for discrete time only (give dt), got dt=None")
        super().__init__(system, bounds, L, method="framer")
        self.gain_design: GainDesign | None = None
        self.fallback: str | None = None

    @classmethod
    @options_after_bounds("h")
    @shared_docs
    def design(
        cls,
        system: LTISystem,
        bounds: Bounds,
        *,
        h: float | None = None,
        **options: Any,
    ) -> IntegratedObserver:
        """Gain bounding the noise-to-error gain with a monotone error (``A0 - LC ≥ 0``), then the observer.

        Parameters
        ----------
        %(lti_system_bounds)s
        h : float, optional
            None or the system's ``dt`` (discrete time); present for signature compatibility.
        **options
            ``E_theta`` (array, default identity): directions in which ``dA`` moves the state.
            ``fallback`` (``"raise"`` default, or ``"hinf"``): when :math:`A_0 - LC \\ge 0` is
            impossible, raise :class:`AssumptionError` or use the H∞ gain alone (the observer stays
            sound; ``fallback`` records why).

        Returns
        -------
        IntegratedObserver

        References
        ----------
        The integrated-observer paper: H∞ LMI (19) with the monotonicity LMI (65) (diagonal ``P``),
        Lemma A.2 (``E_theta``).
        """
        check_no_kwargs("IntegratedObserver.design", options, ("E_theta", "fallback"))
        if not isinstance(system, LTISystem):
            raise ArgumentTypeError(f"system: expected an LTISystem, got {type(system).__name__}")
        if not system.continuous:
            system.sampling_period(h)  # refuses an h other than dt
        fallback: Literal["raise", "hinf"] = options.get("fallback", "raise")
        if fallback not in ("raise", "hinf"):
            raise DesignError(f"fallback: expected 'raise' or 'hinf', got {fallback!r}")
        args = (system.A, system.C, system.E, system.F, options.get("E_theta"))
        reason: str | None = None
        try:
            result = hinf_gain(*args, monotone=True)
        except AssumptionError as exc:
            if fallback == "raise":
                raise
            reason = f"monotonicity dropped, the H∞ gain alone: {exc}"
            result = hinf_gain(*args, monotone=False)
        observer = cls(system, bounds, result.gain)
        observer.gain_design = result
        observer.fallback = reason
        return observer

    def meta(self) -> dict[str, Any]:
        """Design facts recorded in every :class:`~intervalobs.estimate.Estimate`.

        Returns
        -------
        dict
            Those of :meth:`ZonotopicObserver.meta`, plus ``gain_design`` and ``fallback`` when set.
        """
        info = super().meta()
        info["method"] = (
            "IntegratedObserver (zonotope of ΔA effects with an interval framer, the integrated-observer paper)"
        )
        if self.gain_design is not None:
            info["gain_design"] = self.gain_design.as_dict()
        if self.fallback is not None:
            info["fallback"] = self.fallback
        return info
