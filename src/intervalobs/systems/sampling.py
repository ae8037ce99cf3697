r"""The sound sampled model of a continuous-time interval system, tight for stiff dynamics.

For :math:`\dot x = (A + \Delta A)x + (B + \Delta B)u + Ew` with :math:`|\Delta A| \le D` (elementwise), :math:`u`
held over each step of length :math:`h` (zero-order hold of the known input) and :math:`w(t)` *any*
measurable signal in its box :math:`[w_c - w_r, w_c + w_r]`, the state at the sample times obeys

.. math:: x_{k+1} \in (\Phi \pm \delta\Phi)\,x_k + (\Gamma \pm \delta\Gamma)\,u_k + [c - r,\; c + r].

:math:`\Phi = e^{Ah}`, :math:`\Gamma = \int_0^h e^{As}ds\,B` and :math:`\Gamma_E = \int_0^h e^{As}ds\,E`
are the exact sampled matrices of the midpoint system (one exponential of the block matrix
:math:`X = [[A, B, E], [0, 0, 0]]`), :math:`c = \Gamma_E w_c`, and every radius is the elementwise
minimum of two sound bounds: a cheap one that is tight when :math:`\|A\|h` is small, and one that
keeps the decay of a stiff :math:`A` whatever :math:`\|A\|h`. No assumption is made on the noise
between samples. A discrete-time system is its own sampled model.

Notation: :math:`Y(s) = [e^{As},\ \Gamma_B(s),\ \Gamma_E(s)]` are the first :math:`n` rows of
:math:`e^{Xs}`, so :math:`Y'(s) = e^{As}X_1` with :math:`X_1 = [A, B, E]`; :math:`|\cdot|` and
:math:`\le` are elementwise.

**1. The cheap bounds** (the exponential series has nonnegative terms; they grow like
:math:`e^{\|A\|h}`):

* :math:`|e^{(X + \Delta)s} - e^{Xs}| \le e^{(|X| + D)s} - e^{|X|s}` for :math:`|\Delta| \le D`;
* :math:`|e^{A s}E| \le e^{|A|\delta}\,|e^{A s_i}E|` for :math:`s \in [s_i, s_i + \delta]`, which gives a
  left Riemann sum of :math:`\int_0^h|e^{As}E|\,ds` with the factor :math:`e^{|A|\delta}`.

**2. A majorant that keeps the decay** (Van Loan 1977 bounds :math:`\|e^{At}\|` the same way in norm).
Let :math:`A \approx VTW` with :math:`T` upper triangular and :math:`W` the computed inverse of
:math:`V`; two such forms are used, and every bound below is the elementwise minimum of the two:
the complex Schur form (:math:`V` unitary, always well conditioned) and the eigenbasis
(:math:`T = \Lambda` diagonal, when :math:`\operatorname{cond}(V) \le 10^8`). The eigenbasis keeps
every mode apart: its perturbation radius :math:`|V^{-1}|D|V|` has, on the diagonal, exactly the
largest first-order shift :math:`|w_i^H|D|v_i|` of each eigenvalue, while the Schur form feeds the
fast modes' :math:`\Delta A` into the slow ones through its non-normal part. With the measured
residuals :math:`R = AV - VT` and :math:`E = I - WV`, :math:`\|E\|_2 < 1/2` (each plus an allowance
:math:`2(n+2)\epsilon_{\mathrm{mach}}` times the norm of the moduli of its products),

.. math:: A = V(T + F)V^{-1},\quad F = (I - E)^{-1}WR,\quad
          |F_{ij}| \le \varepsilon = \frac{\|W\|_2\|R\|_2}{1 - \|E\|_2},\quad
          |V^{-1}| \le |W| + \eta,\ \ \eta = \frac{\|E\|_2\|W\|_2}{1 - \|E\|_2}

(:math:`V^{-1} = (I - E)^{-1}W`, and :math:`(I - E)^{-1}WAV - T = (I - E)^{-1}(WAV - (I - E)T) =
(I - E)^{-1}(WR + (WV - I + E)T)`; every entry is at most the spectral norm). Let :math:`M` be the
*Metzler majorant* :math:`M_{ii} = \operatorname{Re}T_{ii} + \varepsilon`,
:math:`M_{ij} = |T_{ij}| + \varepsilon`. Then for all :math:`t \ge 0`

.. math:: |e^{(T + F)t}| \le e^{Mt}, \qquad |e^{At}| \le |V|\,e^{Mt}\,(|W| + \eta).

*Proof.* Write :math:`T + F = \Lambda + N` with :math:`\Lambda` its diagonal. Variation of constants
gives :math:`e^{(\Lambda + N)t} = e^{\Lambda t} + \int_0^t e^{\Lambda(t-s)}Ne^{(\Lambda+N)s}ds`, and its
Picard iterates are the Dyson series :math:`\sum_k \int\!\cdots\!\int e^{\Lambda(t-s_1)}N\cdots N
e^{\Lambda s_k}`. Replacing :math:`e^{\Lambda\tau}` by :math:`|e^{\Lambda\tau}| =
e^{\operatorname{Re}\Lambda\,\tau}` and :math:`N` by :math:`|N|` majorises every term; the majorised
series is the Dyson series of :math:`e^{(\operatorname{Re}\Lambda + |N|)t} \le e^{Mt}` (the exponential of
a Metzler matrix is nonnegative and nondecreasing in every entry). :math:`\square` Since :math:`M` is
(up to :math:`\varepsilon`) triangular with diagonal :math:`\operatorname{Re}\lambda_i(A)`, the majorant
decays exactly as :math:`A` does; it only loses the mixing factor :math:`|V|\,|V^{-1}|` and the
cancellations of the non-normal part. With :math:`M^+ = M + \operatorname{diag}(\max(-M_{ii}, 0))
\ge 0`, monotonicity again gives :math:`\sup_{0 \le \sigma \le \delta}|e^{A\sigma}v| \le
|V|\,X(\delta)\,|V^{-1}v|` for any vector or matrix :math:`v`, for any :math:`X(\delta) \ge
\sup_{\sigma \le \delta}e^{M\sigma}`; three are used, elementwise minimum: :math:`e^{M^+\delta}` (it grows
only polynomially when :math:`\operatorname{Re}\lambda \le 0`, :math:`M^+` being nilpotent up to
:math:`\varepsilon`), and, with :math:`M = \Lambda + N` (:math:`\Lambda` diagonal),
:math:`G = \operatorname{diag}(e^{\max(\Lambda_{ii}, 0)\delta})` and :math:`\tilde\Lambda \ge
\operatorname{diag}\int_0^\delta e^{\Lambda_{ii} r}dr` (i.e. :math:`\min(\delta, 1/|\Lambda_{ii}|)` for
:math:`\Lambda_{ii} < 0`), the two Neumann bounds :math:`G(I - N\tilde\Lambda)^{-1}` and
:math:`(I - \tilde\Lambda N)^{-1}G` when their loop matrices have spectral radius below 1/2. *Proof.*
:math:`e^{M\sigma} = e^{\Lambda\sigma} + \int_0^\sigma e^{M(\sigma - r)}Ne^{\Lambda r}dr \le G + XN\tilde\Lambda`
for :math:`X = \sup_{\sigma\le\delta}e^{M\sigma}`; iterating :math:`X \le G + XK` with :math:`K \ge 0`,
:math:`\rho(K) < 1`, gives :math:`X \le G(I - K)^{-1}`; the other order is the same with
:math:`e^{\Lambda(\sigma - r)}Ne^{Mr}`. :math:`\square` These keep the decay of the fast modes that a
non-normal coupling :math:`N_{ij}` feeds (:math:`N_{ij}/|\lambda_j|` instead of :math:`N_{ij}\delta`).

**3. Quadrature with a decaying error term.** If :math:`g \ge 0` is Lipschitz on :math:`[a, b]`
(:math:`\delta = b - a`) with constant :math:`L` then :math:`g(s) \le \min(g(a) + L(s-a),\ g(b) + L(b-s))`
and :math:`\int_a^b g \le \tfrac{\delta}{2}(g(a) + g(b)) + \tfrac{L\delta^2}{4}`. For
:math:`g = |e^{As}E|` on :math:`[s_j, s_j + \delta_j]`, :math:`|g'| \le |Ae^{As}E| \le
|V|\,e^{M^+\delta_j}\,|V^{-1}Ae^{As_j}E| = L_j` by section 2: the error term carries the decay that is
actually present at :math:`s_j` (the factor :math:`e^{\lambda s_j}` of each mode), not
:math:`e^{|A|\delta}`. The nodes are geometric towards both ends of :math:`[0, h]` (eight per octave,
down to :math:`\|A\|_\infty s \le 1/16`), so every time scale of a stiff :math:`A` is resolved with a
relative error term of a few per cent; the node values :math:`e^{Xs_j}` are exact exponentials.

**4. The interval** :math:`\Delta A`. With :math:`\Delta` the block of :math:`\Delta A` in :math:`X`,
variation of constants twice gives

.. math:: e^{(X+\Delta)h} - e^{Xh} = \int_0^h e^{X(h-s)}\Delta e^{Xs}ds + R_2,

whose first rows are :math:`\int_0^h e^{A(h-s)}\Delta A\, Y(s)\,ds + R_2`. Entry :math:`(i, k)` of the
first-order term is :math:`\sum_{jl}\Delta A_{jl}K^{jl}_{ik}` with the sensitivities
:math:`K^{jl}_{ik} = \int_0^h e^{A(h-s)}_{ij}Y(s)_{lk}\,ds`, so it is at most
:math:`\sum_{jl}D_{jl}|K^{jl}_{ik}|` (attained to first order at a vertex of the box). Each
:math:`K^{jl}` is a trapezoid sum on the same symmetric nodes plus the error term of section 3, which
also holds for a signed Lipschitz integrand (:math:`|\int_a^b f - \tfrac{\delta}{2}(f(a) + f(b))| \le
L\delta^2/4`), with Lipschitz constants from section 2 (both factors at once: :math:`|(fg)'| \le
|f'|\sup|g| + \sup|f|\,|g'|`); summed with the weights :math:`D_{jl}` these error terms are
:math:`\sum_j \tfrac{\delta_j^2}{4}(L_P D\sup|Y| + \sup|P|\,D\,L_Y)`. The remainder :math:`R_2` is the
sum of the Dyson terms of order :math:`\ge 2`; in the coordinates of :math:`T` the perturbation is
:math:`V^{-1}\Delta A\,V`, bounded by :math:`D' = (|W| + \eta)\,D\,|V|`, and majorising as in section 2,

.. math:: |R_2^{\Phi}| \le |V|\,\rho_2(h)\,|V^{-1}|, \qquad
          \rho_2(t) = \int_0^t\!\!\int_0^{s_1} e^{M(t-s_1)}D'e^{M(s_1-s_2)}D'e^{(M+D')s_2}\,ds_2\,ds_1,

the (1,3) block of :math:`\exp([[M, D', 0], [0, M, D'], [0, 0, M+D']]\,t)` (Van Loan's block-triangular
exponential; all blocks are nonnegative, so nothing cancels). The input columns are
:math:`\int_0^h(\cdot)\,ds\,[B, E]`, so their remainder is :math:`|V|\int_0^h\rho_2\,|V^{-1}|\,|[B, E]|`
(one more block row). The noise sees :math:`\int_0^h|e^{(A+\Delta A)s} - e^{As}|\,ds \le
|V|\int_0^h(e^{(M+D')s} - e^{Ms})\,ds\,|V^{-1}|` (the Dyson majorant of all orders :math:`\ge 1`,
again a block exponential).

*Scope.* The remainder is small next to the first-order term while :math:`M + D'` keeps a margin of
stability, i.e. while no vertex of the :math:`\Delta A` box moves an eigenvalue by a sizeable
fraction of itself (to first order :math:`|w_i^H|D|v_i| \ll |\operatorname{Re}\lambda_i|`); on random
3-10 state systems with real eigenvalues or complex pairs over five decades and the largest such shift
10 % of :math:`|\lambda_i|`, :math:`\delta\Phi` is within 1.5x of the vertex lower bound for every
:math:`h` from :math:`10^{-3}` to 10 (``tests/test_sampling.py``). A box that lets some vertex
become unstable makes :math:`M + D'` unstable and :math:`R_2` grow like :math:`e^{\rho(M + D')h}`;
the minimum with the cheap bound keeps it sound, not tight.

**5. The noise box.** The noise enters through :math:`\int_0^h e^{(A+\Delta A)s}E\,w(t_{k+1} - s)\,ds`;
with :math:`w = w_c + \operatorname{diag}(w_r)\epsilon(s)`, :math:`|\epsilon| \le 1`, its centre is
:math:`\Gamma_E w_c` and its radius is at most

.. math:: \Big(\int_0^h |e^{As}E|\,ds + \int_0^h |e^{(A+\Delta A)s} - e^{As}|\,ds\,|E|\Big) w_r
          + \delta\Gamma_E|w_c|.

**6. The** :math:`\Delta A` **radius in other coordinates.** An observer that bounds its error in
coordinates :math:`z = Te` needs :math:`|T\,\Delta\Phi\,T^{-1}|`. The product :math:`|T|\,\delta\Phi\,|T^{-1}|`
bounds it, but loses the cancellations inside :math:`T K^{jl} T^{-1}` (in the modal basis of a slow,
lightly damped error mode these are what keeps the ΔA term below the mode's decay).
:meth:`SampledModel.dphi_in` bounds it directly: the first-order term of section 4 in the new
coordinates is :math:`\sum_{jl}\Delta A_{jl}\,TK^{jl}T^{-1}`, whose trapezoid sums on the same nodes
:math:`s_m` (weights :math:`\omega_m`) are :math:`\sum_m \omega_m\,(Te^{A(h-s_m)})_{:,j}\,(e^{As_m}T^{-1})_{l,:}`;
the quadrature error terms and the remainder :math:`R_2` (section 4, original coordinates; call their
sum :math:`S`, a bound of :math:`\sum_{jl}D_{jl}|K^{jl} - \tilde K^{jl}| + |R_2|`) enter as
:math:`|T|\,S\,|T^{-1}|`:

.. math:: |T\,\Delta\Phi\,T^{-1}| \le \sum_{jl} D_{jl}\,\Big|\sum_m \omega_m\,(Te^{A(h-s_m)})_{:,j}
          (e^{As_m}T^{-1})_{l,:}\Big| + |T|\,S\,|T^{-1}| + \gamma\,|T|\,Z\,|T^{-1}|,

where :math:`Z = \sum_m \omega_m|e^{A(h-s_m)}|\,D\,|e^{As_m}|` and :math:`\gamma = (2n + N + 4)\epsilon_{\mathrm{mach}}`
covers the rounding of the products and of the :math:`N + 1`-term sums (each computed entry is within
:math:`\gamma` of the magnitude of its terms). The elementwise minimum with :math:`|T|\,\delta\Phi\,|T^{-1}|`
is returned. In discrete time :math:`\Delta\Phi = \Delta A` and the box
:math:`\{T\Delta AT^{-1}\}` has radius exactly :math:`|T|\,D\,|T^{-1}|`.

**7. The interval** :math:`\Delta B`. With :math:`B + \Delta B`, :math:`\Delta B \in [\Delta B_c - B_r,
\Delta B_c + B_r]` (a motor's torque constant known to a few per cent), the input matrix of one step is
:math:`\Gamma(\Delta A, \Delta B) = \Gamma_I(\Delta A)(B_c + \beta)` with :math:`\Gamma_I(\Delta A) =
\int_0^h e^{(A+\Delta A)s}ds`, :math:`B_c = B + \Delta B_c` and :math:`|\beta| \le B_r`. The block
exponential is taken with the input columns :math:`[B_c, I]` (:math:`n` more unit columns), which gives
:math:`\Gamma_I(\Delta A) \in \Gamma_I \pm \delta\Gamma_I` and :math:`\Gamma_I(\Delta A)B_c \in \Gamma \pm
\delta\Gamma_{B_c}` by sections 1-4 applied to each column. Then

.. math:: |\Gamma(\Delta A, \Delta B) - \Gamma| \le \delta\Gamma_{B_c} + |\Gamma_I(\Delta A)|\,B_r
          \le \delta\Gamma_{B_c} + (|\Gamma_I| + \delta\Gamma_I)\,B_r,

which is the ``dGamma`` returned. Without :math:`\Delta A` (:math:`\delta\Gamma_I = 0`) each entry
:math:`\sum_j (\Gamma_I)_{ij}\beta_{jk}` reaches :math:`\pm(|\Gamma_I|B_r)_{ik}` at a vertex of the
:math:`\Delta B` box, so the radius is exact entry by entry. In discrete time :math:`\Gamma = B_c` and
:math:`\delta\Gamma = B_r` exactly. The recursive observers use :math:`(\Gamma \pm \delta\Gamma)u_k` at
every step as a box for that step alone, i.e. as if :math:`\Delta B` could change from one step to the next:
sound, but it forgets that the true :math:`\Delta B` is constant. A window estimator can keep one
:math:`\beta = \Delta B - \Delta B_c` for the whole window: step :math:`k` adds :math:`\Gamma_I(\Delta A)\beta
u_k`, linear in :math:`\beta` for known :math:`u`. For that the model also returns ``input_integral``
:math:`= \Gamma_I` (the identity in discrete time) and ``d_input_integral`` :math:`= \delta\Gamma_I` (zero
without :math:`\Delta A` and in discrete time), with :math:`|\Gamma_I(\Delta A) - \Gamma_I| \le
\delta\Gamma_I`, and ``dB_radius`` :math:`= B_r` (rounded up by the rounding of :math:`B_c`).

**Why not interval scaling and squaring.** The verified exponentials of interval matrices
(Oppenheimer & Michel 1988: Taylor series with a norm remainder; Goldsztejn & Neumaier 2014: scaling
and squaring of an interval Taylor enclosure; Althoff, Stursberg & Buss 2007 and CORA:
:math:`e^{[A]t} \subset \sum_{k \le p}[A]^kt^k/k! + E(t)` with :math:`E` from :math:`e^{\|A\|t}`) bound
their remainder by :math:`\|A\|`; scaled down to :math:`\|A\|h/2^s < 1` they are accurate, but
squaring an interval matrix :math:`s \approx \log_2\|A\|h` times widens it by the dependency effect
at every squaring (in a basis where :math:`e^{Ah/2^s}` has mixed signs every product
:math:`|\Phi|\,\delta` loses the cancellations of the true first-order term), and the steps' noise
integral still needs a quadrature. The majorants keep the eigenvalues on the diagonal, so their
bounds decay with :math:`A` for any :math:`h`, and the first-order term is computed exactly (up to
the quadrature error) in the original coordinates, so the basis only enters the second order.

**Floating point.** As everywhere in the library, the point matrices (``expm`` of the block matrix
and at the nodes) are taken as computed and the rounding is absorbed by the relative margin
``ROUNDING_MARGIN`` applied to every radius here (:func:`~intervalobs.interval.inflate`) and to the
observers' outputs; the residuals of the Schur form and of the eigenbasis are measured, not assumed.

**References.**

* Van Loan, "The sensitivity of the matrix exponential", SIAM J. Numer. Anal. 14 (1977).
* Van Loan, "Computing integrals involving the matrix exponential", IEEE TAC 23 (1978).
* Oppenheimer, Michel, "Application of interval analysis techniques to linear systems, Part II: the
  interval matrix exponential function", IEEE TCAS 35 (1988).
* Goldsztejn, Neumaier, "On the exponentiation of interval matrices", Reliable Computing 20 (2014),
  arXiv:0908.3954.
* Althoff, Stursberg, Buss, "Reachability analysis of linear systems with uncertain parameters and
  inputs", IEEE CDC 2007 (the interval exponential of CORA).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm, expm_frechet, schur

from ..errors import AssumptionError
from ..interval import inflate, interval_matvec_bounds, matvec_bounds
from ..validation import as_positive
from .bounds import Bounds
from .lti import LTISystem

__all__ = ["DeltaLinearisation", "SampledModel", "delta_linearisation", "sampled_model"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

_CHEAP_QUADRATURE_INTERVALS = 16
_NODES_PER_OCTAVE = 8
_FINEST_NORM_STEP = 1.0 / 16.0
_EPS = float(np.finfo(float).eps)
_MAX_EIGENBASIS_CONDITION = 1e8
_MODEL_PAD = 1e-13
"""Relative pad on the exponentials of :func:`delta_linearisation` (their own rounding: ``expm`` is accurate
to ~1e-15)."""


@dataclass(frozen=True)
class SampledModel:
    r"""The sound discrete-time interval model of one sampling step.

    .. math:: x_{k+1} \in (\Phi \pm \delta\Phi)x_k + (\Gamma \pm \delta\Gamma)u_k + [c \pm r]

    for every :math:`\Delta A` and :math:`\Delta B` in their boxes and every noise signal in its box,
    switching anywhere inside the step (see :mod:`intervalobs.systems.sampling` for the bounds and their proofs).

    Parameters
    ----------
    Phi, dPhi : numpy.ndarray, shape (n, n)
        Midpoint transition matrix :math:`e^{Ah}` and its elementwise radius under
        :math:`\Delta A` (``dPhi >= 0``).
    Gamma, dGamma : numpy.ndarray, shape (n, m)
        Midpoint input matrix :math:`\int_0^h e^{As}ds\,(B + \Delta B_c)` and its elementwise radius under
        :math:`\Delta A` and :math:`\Delta B` (section 7 of the module docstring).
    noise_center, noise_radius : numpy.ndarray, shape (n,)
        Centre and radius of the box that holds the process-noise contribution of one step.
    h : float
        Step length (1.0 for a discrete-time system).
    first_order : object, optional
        The first-order data behind :meth:`dphi_in` (set by :func:`sampled_model` for a
        continuous-time system with interval ``dA``; None otherwise).
    input_integral, d_input_integral : numpy.ndarray, shape (n, n), optional
        With an interval ``dB``: :math:`\Gamma_I = \int_0^h e^{As}ds` (the identity in discrete time) and its
        elementwise radius under :math:`\Delta A`, so that one step adds :math:`\Gamma_I(\Delta A)\beta u_k`
        for :math:`\beta = \Delta B - \Delta B_c` (section 7 of the module docstring); None without.
    dB_radius : numpy.ndarray, shape (n, m), optional
        With an interval ``dB``: the radius :math:`B_r` of :math:`\beta`, rounded up; None without.
    noise_generators : numpy.ndarray, shape (n, q), optional
        A matrix ``G`` whose image of the unit box is the exact set of the process-noise contribution,
        :math:`\{c + G\xi : |\xi| \le 1\}`: in discrete time ``E diag(w_r)`` (the noise is ``E w`` with
        ``w`` in its box, for every ``ΔA``), so ``noise_radius`` is ``|G| 1`` rounded up. None where only the
        box is known (continuous time: the noise integral over a step is bounded as a box); see
        :meth:`generators`.
    """

    Phi: FloatArray
    dPhi: FloatArray
    Gamma: FloatArray
    dGamma: FloatArray
    noise_center: FloatArray
    noise_radius: FloatArray
    h: float
    first_order: _FirstOrder | None = field(default=None, repr=False, compare=False)
    input_integral: FloatArray | None = field(default=None, repr=False, compare=False)
    d_input_integral: FloatArray | None = field(default=None, repr=False, compare=False)
    dB_radius: FloatArray | None = field(default=None, repr=False, compare=False)
    noise_generators: FloatArray | None = field(default=None, repr=False, compare=False)

    def generators(self) -> FloatArray:
        r"""Generators of the process-noise set of one step: ``noise_generators``, or the box ``diag(noise_radius)``.

        Either way the noise lies in :math:`\{c + G\xi : |\xi| \le 1\}`, independently from one step to the next.

        Returns
        -------
        numpy.ndarray, shape (n, q)
        """
        if self.noise_generators is not None:
            return self.noise_generators
        return np.diag(self.noise_radius)

    @property
    def uncertain(self) -> bool:
        """True when the transition or input matrix is an interval (not a point) matrix."""
        return bool(np.any(self.dPhi > 0) or np.any(self.dGamma > 0))

    def image(
        self,
        lower: FloatArray,
        upper: FloatArray,
        u: FloatArray,
        transition: tuple[FloatArray, FloatArray] | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        r"""Box of :math:`x_{k+1}` from a box of :math:`x_k`: one step of the model, rounded outward.

        :math:`(\Phi \pm \delta\Phi)[\underline x, \overline x] + (\Gamma \pm \delta\Gamma)u_k + [c \pm r]`,
        the products by :func:`~intervalobs.interval.interval_matvec_bounds` (exact ranges), the sum
        widened by :func:`~intervalobs.interval.inflate`.

        Parameters
        ----------
        lower, upper : numpy.ndarray, shape (..., n)
            Box of :math:`x_k`.
        u : numpy.ndarray, shape (..., m)
            Known input over the step.
        transition : tuple of numpy.ndarray, shape (n, n), optional
            An interval matrix inside :math:`\Phi \pm \delta\Phi` to use instead (e.g. the transition of
            a ``ΔA`` box identified from data, in discrete time).

        Returns
        -------
        lower, upper : numpy.ndarray, shape (..., n)
        """
        a_lo, a_hi = (self.Phi - self.dPhi, self.Phi + self.dPhi) if transition is None else transition
        x_lo, x_hi = interval_matvec_bounds(a_lo, a_hi, lower, upper)
        u_lo, u_hi = interval_matvec_bounds(self.Gamma - self.dGamma, self.Gamma + self.dGamma, u, u)
        return inflate(
            x_lo + u_lo + self.noise_center - self.noise_radius, x_hi + u_hi + self.noise_center + self.noise_radius
        )

    def dphi_in(self, T: FloatArray) -> FloatArray:
        r"""A bound of :math:`|T\,\Delta\Phi\,T^{-1}|` over the :math:`\Delta A` box (module docstring, section 6).

        Never above :math:`|T|\,\delta\Phi\,|T^{-1}|`; below it when the first-order term cancels in
        the coordinates ``T`` (continuous time).

        Parameters
        ----------
        T : numpy.ndarray, shape (n, n)
            Invertible coordinate change ``z = T x``.

        Returns
        -------
        numpy.ndarray, shape (n, n)
            Elementwise radius, rounded upward.
        """
        t_inv = np.asarray(np.linalg.inv(T), dtype=float)
        plain = np.abs(T) @ self.dPhi @ np.abs(t_inv)
        if self.first_order is None:
            return np.asarray(plain)
        return np.minimum(plain, self.first_order.radius_in(T, t_inv))


@dataclass(frozen=True)
class _FirstOrder:
    """The trapezoid data of the first-order ΔΦ term and its slack (module docstring, sections 4 and 6)."""

    weights: FloatArray  # trapezoid weights of the nodes s_j
    p: FloatArray  # e^{A s_j}, shape (N + 1, n, n)
    d: FloatArray  # the radius D of ΔA
    slack: FloatArray  # quadrature error terms + remainder R_2 of δΦ, original coordinates

    def radius_in(self, t: FloatArray, t_inv: FloatArray) -> FloatArray:
        """``Σ_jl D_jl |T K^jl T⁻¹| + |T|(S + γZ)|T⁻¹|``, rounded upward."""
        n = t.shape[0]
        rows, cols = np.nonzero(self.d)
        weights = self.weights[:, None, None]
        left = (weights * (t @ self.p[::-1]))[:, :, rows].transpose(2, 1, 0)  # ω_m (T e^{A(h - s_m)})_{:, j}
        right = (self.p @ t_inv)[:, cols, :].transpose(1, 0, 2)  # (e^{A s_m} T^{-1})_{l, :}
        first = np.einsum("q,qik->ik", self.d[rows, cols], np.abs(left @ right))
        magnitude = ((weights * np.abs(self.p[::-1])) @ self.d @ np.abs(self.p)).sum(axis=0)
        gamma = (2 * n + self.weights.size + 4) * _EPS
        pad = np.abs(t) @ (self.slack + gamma * magnitude) @ np.abs(t_inv)
        total = first + pad
        return np.asarray(inflate(-total, total, floor=0.0)[1])


@dataclass(frozen=True)
class _Majorant:
    """``|e^{At}| <= |V| e^{Mt} |V^{-1}|`` from ``A = V(T + F)V^{-1}`` (module docstring, section 2)."""

    v: ComplexArray
    w: ComplexArray  # computed inverse of ``v``
    pad: float  # ``|V^{-1} - W| <= pad`` entrywise
    m: FloatArray

    def sup_growth(self, delta: float) -> FloatArray:
        """``|V| X(δ)``, ``X(δ) >= sup_{σ ≤ δ} e^{Mσ}``: ``sup_{σ ≤ δ} |e^{Aσ} v| <= sup_growth(δ) @ rotate(v)``."""
        diag = np.diag(self.m)
        bound = expm((self.m + np.diag(np.maximum(-diag, 0.0))) * delta)
        off = self.m - np.diag(diag)
        growth = np.exp(np.maximum(diag, 0.0) * delta)
        settle = np.where(diag < 0, np.minimum(delta, 1.0 / np.abs(np.where(diag < 0, diag, -1.0))), delta * growth)
        eye = np.eye(len(diag))
        for loop, left in ((off * settle[None, :], False), (settle[:, None] * off, True)):
            if np.max(np.abs(np.linalg.eigvals(loop))) < 0.5:
                inverse = np.linalg.inv(eye - loop)
                candidate = inverse * growth[None, :] if left else growth[:, None] * inverse
                bound = np.minimum(bound, np.maximum(candidate, 0.0))
        return np.asarray(np.abs(self.v) @ bound)

    def rotate(self, x: FloatArray) -> FloatArray:
        """A bound of ``|V^{-1} x|`` for a real matrix ``x``."""
        return np.asarray(np.abs(self.w @ x) + self.pad * np.abs(x).sum(axis=0))

    def right(self) -> FloatArray:
        """A bound of ``|V^{-1}|``."""
        return np.asarray(np.abs(self.w) + self.pad)

    def back(self, x: FloatArray) -> FloatArray:
        """``|V| x |V^{-1}|`` (bounded) for a nonnegative matrix ``x`` in the coordinates of ``T``."""
        return np.asarray(np.abs(self.v) @ x @ self.right())


def _majorant(a: FloatArray, v: ComplexArray, t: ComplexArray) -> _Majorant | None:
    """The majorant of ``A ≈ V T V^{-1}`` (``T`` upper triangular), or None when ``V`` is too ill-conditioned."""
    n = a.shape[0]
    w = np.asarray(np.linalg.inv(v), dtype=complex)
    if not np.all(np.isfinite(w)):
        return None
    abs_v, abs_w = np.abs(v), np.abs(w)
    gamma = 2 * (n + 2) * _EPS  # rounding of the two residual products (n-term sums), with slack
    residual = np.linalg.norm(a @ v - v @ t, 2) + gamma * np.linalg.norm(np.abs(a) @ abs_v + abs_v @ np.abs(t), 2)
    defect = np.linalg.norm(np.eye(n) - w @ v, 2) + gamma * np.linalg.norm(abs_w @ abs_v, 2)
    if not defect < 0.5:
        return None
    norm_w = float(np.linalg.norm(w, 2))
    eps = norm_w * residual / (1 - defect)  # ||V^{-1}AV - T||_2 = ||(I - E)^{-1} W R||_2
    pad = defect * norm_w / (1 - defect)  # ||V^{-1} - W||_2 = ||(I - E)^{-1} E W||_2
    m = np.abs(t) + eps
    np.fill_diagonal(m, np.real(np.diag(t)) + eps)
    return _Majorant(v, w, pad, m)


def _majorants(a: FloatArray) -> list[_Majorant]:
    """The majorants of the complex Schur form and, when it is well conditioned, of the eigenbasis."""
    t, q = schur(a.astype(complex), output="complex")
    found = [_majorant(a, q, t)]
    lam, vec = np.linalg.eig(a)
    if np.all(np.isfinite(vec)) and np.linalg.cond(vec) < _MAX_EIGENBASIS_CONDITION:
        found.append(_majorant(a, vec.astype(complex), np.diag(lam).astype(complex)))
    return [major for major in found if major is not None]


def _nodes(h: float, norm: float) -> FloatArray:
    """Nodes on [0, h], geometric towards both ends and exactly symmetric: ``h - s_j`` is a node."""
    half = 0.5 * h
    finest = min(half, _FINEST_NORM_STEP / norm) if norm > 0 else half
    octaves = int(np.ceil(np.log2(half / finest))) + 1
    lower = half * 2.0 ** (-np.arange(octaves * _NODES_PER_OCTAVE + 1) / _NODES_PER_OCTAVE)
    lower = h - (h - lower)  # exact in floating point (Sterbenz): then h - node is a float too
    upper = h - lower
    return np.unique(np.concatenate(([0.0], lower, upper, [h])))


def _block_exp_row(blocks: list[list[FloatArray | None]], t: float) -> list[FloatArray]:
    """The blocks of the first block row of ``expm(t * [blocks])`` (``None`` is a zero block)."""
    size = next(block.shape[0] for line in blocks for block in line if block is not None)
    k = len(blocks)
    big = np.zeros((k * size, k * size))
    for i, line in enumerate(blocks):
        for j, block in enumerate(line):
            if block is not None:
                big[i * size : (i + 1) * size, j * size : (j + 1) * size] = block
    first = expm(big * t)[:size]
    return [np.asarray(first[:, j * size : (j + 1) * size]) for j in range(k)]


@dataclass(frozen=True)
class _DecayBounds:
    """The bounds of sections 3-4 of the module docstring (``None`` entries: no ΔA)."""

    noise_integral: FloatArray
    d_phi: FloatArray | None
    d_inputs: FloatArray | None
    spread_integral: FloatArray | None
    first_order: _FirstOrder | None


def _majorant_terms(
    major: _Majorant,
    a: FloatArray,
    x1: FloatArray,
    e: FloatArray,
    y: FloatArray,
    steps: FloatArray,
    d: FloatArray | None,
    h: float,
) -> list[FloatArray]:
    """The parts of sections 3-4 that rest on a majorant: quadrature error terms and Dyson remainders."""
    n = a.shape[0]
    # sup_growth is nondecreasing in δ: one factor per power-of-two class of steps.
    classes = np.ceil(np.log2(steps / steps.max())).astype(int)
    growth = {c: major.sup_growth(float(steps.max() * 2.0**c)) for c in np.unique(classes)}
    grow = np.stack([growth[c] for c in classes])  # (N, n, n)
    p = y[:, :, :n]
    lip_noise = grow @ np.stack([major.rotate(a @ pj @ e) for pj in p[:-1]])
    quad = 0.25 * steps[:, None, None] ** 2
    terms = [(quad * lip_noise).sum(axis=0)]
    if d is None:
        return terms
    mirror = p[::-1]  # e^{A(h - s_j)}
    lip_y = grow @ np.stack([major.rotate(pj @ x1) for pj in p[:-1]])
    lip_p = grow @ np.stack([major.rotate(a @ pm) for pm in mirror[1:]])
    sup_y = np.abs(y[:-1]) + steps[:, None, None] * lip_y
    sup_p = np.abs(mirror[1:]) + steps[:, None, None] * lip_p
    terms.append((quad * (lip_p @ d @ sup_y + sup_p @ d @ lip_y)).sum(axis=0))
    m, dq = major.m, major.right() @ d @ np.abs(major.v)  # bounds |V^{-1} ΔA V|
    eye = np.eye(n)
    rho2: list[list[FloatArray | None]] = [
        [m, dq, None, None],
        [None, m, dq, None],
        [None, None, m + dq, eye],
        [None, None, None, None],
    ]
    _, _, remainder, remainder_integral = _block_exp_row(rho2, h)
    spread = _block_exp_row([[m, dq, None], [None, m + dq, eye], [None, None, None]], h)[2]
    terms += [major.back(remainder), major.back(remainder_integral) @ np.abs(x1[:, n:]), major.back(spread)]
    return terms


def _decay_bounds(a: FloatArray, x1: FloatArray, n_noise: int, d: FloatArray | None, h: float) -> _DecayBounds:
    """Quadrature and majorant bounds; ``x1 = [A, B, E]`` (E its last ``n_noise`` columns)."""
    n, size = a.shape[0], x1.shape[1]
    nodes = _nodes(h, float(np.abs(a).sum(axis=1).max()))
    aug = np.zeros((size, size))
    aug[:n] = x1
    y = np.stack([expm(aug * s)[:n] for s in nodes])  # (N+1, n, size): [e^{As}, Γ_B(s), Γ_E(s)]
    steps = np.diff(nodes)
    # Every part below is a sound bound with either majorant: keep the smaller, part by part.
    e = x1[:, size - n_noise :]
    parts = [_majorant_terms(major, a, x1, e, y, steps, d, h) for major in _majorants(a)]
    best = [np.minimum.reduce([terms[i] for terms in parts]) for i in range(len(parts[0]))]
    g = np.abs(y[:, :, :n] @ e)  # |e^{As_j} E|
    noise_integral = (0.5 * steps[:, None, None] * (g[:-1] + g[1:])).sum(axis=0) + best[0]
    if d is None:
        return _DecayBounds(noise_integral, None, None, None, None)
    # First-order ΔA term: Σ_jl D_jl |∫ e^{A(h-s)}_{ij} Y(s)_{lk} ds| by trapezoid sums on the symmetric
    # nodes (mirror index N - j), plus the error term.
    weights = np.zeros(len(nodes))
    weights[:-1] += 0.5 * steps
    weights[1:] += 0.5 * steps
    sensitivity = np.einsum("t,tij,tlk->ijlk", weights, y[::-1, :, :n], y)
    first = np.einsum("jl,ijlk->ik", d, np.abs(sensitivity)) + best[1]
    slack = best[1][:, :n] + best[2]
    first_order = _FirstOrder(weights, y[:, :, :n], d, slack) if np.all(np.isfinite(slack)) else None
    return _DecayBounds(noise_integral, first[:, :n] + best[2], first[:, n:] + best[3], best[4], first_order)


def _finite_or_inf(x: FloatArray) -> FloatArray:
    return np.where(np.isfinite(x), x, np.inf)


def _cheap_bounds(
    aug: FloatArray, rad: FloatArray, a_mid: FloatArray, a_rad: FloatArray, e: FloatArray, h: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Section 1: spread of the block exponential, ∫|e^{As}E| and ∫(e^{(|A|+D)s} - e^{|A|s}) (inf on overflow)."""
    n = a_mid.shape[0]
    with np.errstate(over="ignore", invalid="ignore"):
        try:
            abs_aug = np.abs(aug)
            spread = np.maximum(expm((abs_aug + rad) * h) - expm(abs_aug * h), 0.0)
            delta = h / _CHEAP_QUADRATURE_INTERVALS
            step, growth = expm(a_mid * delta), expm(np.abs(a_mid) * delta)
            total, current = np.zeros_like(e), e.copy()
            for _ in range(_CHEAP_QUADRATURE_INTERVALS):
                total += np.abs(current)
                current = step @ current
            noise_integral = delta * (growth @ total)
            abs_a = np.abs(a_mid)
            block = np.zeros((2 * n, 2 * n))
            block[:n, n:] = np.eye(n)
            block[:n, :n] = abs_a + a_rad
            wide = expm(block * h)[:n, n:]
            block[:n, :n] = abs_a
            spread_integral = np.maximum(wide - expm(block * h)[:n, n:], 0.0)
        except (np.linalg.LinAlgError, OverflowError, ValueError):
            inf = np.full((n, aug.shape[0]), np.inf)
            return inf, np.full_like(e, np.inf), np.full((n, n), np.inf)
    return _finite_or_inf(spread[:n]), _finite_or_inf(noise_integral), _finite_or_inf(spread_integral)


def _check_finite(name: str, value: FloatArray, h: float, a: FloatArray) -> None:
    if not np.all(np.isfinite(value)):
        growth = h * float(np.max(np.real(np.linalg.eigvals(a))))
        raise AssumptionError(
            f"h: the sampled model's {name} is not finite for h = {h!r} "
            f"(h·max Re λ(A) = {growth:.3g}; e^(Ah) overflows); expected a shorter step or a stable A"
        )


def sampled_model(system: LTISystem, bounds: Bounds, h: float | None = None) -> SampledModel:
    """The sound sampled model of ``system`` with step ``h`` (see :mod:`intervalobs.systems.sampling`).

    Parameters
    ----------
    system : LTISystem
        Continuous- or discrete-time model; its interval ``dA`` and ``dB`` (if any) are the boxes of ``ΔA``
        and ``ΔB``.
    bounds : Bounds
        Noise boxes (``w`` is used; ``x0`` and ``v`` are not).
    h : float, optional
        Step length, required for continuous time; in discrete time ``None`` or ``dt``.

    Returns
    -------
    SampledModel
        All radii rounded upward by the relative margin ``ROUNDING_MARGIN``.

    Raises
    ------
    BoundsError
        When ``h`` is missing or not a positive number for a continuous-time system.
    AssumptionError
        When a quantity of the model is not finite (an unstable ``A`` with a step so long that
        :math:`e^{Ah}` overflows); it never happens for a stable ``A``.

    Examples
    --------
    >>> import numpy as np
    >>> from intervalobs import Bounds, LTISystem, sampled_model
    >>> stiff = LTISystem([[-1000.0, 0.0], [1.0, -0.01]], [[0.0, 1.0]], E=np.eye(2))
    >>> model = sampled_model(stiff, Bounds(x0=([-1, -1], [1, 1]), w=([-1, -1], [1, 1])), h=0.1)
    >>> bool(model.noise_radius[0] < 1.01e-3)
    True
    """
    full = bounds.resolve(system)
    w_center = full.centre("w")
    w_radius = full.radius("w")
    n, m, nw = system.n, system.m, system.nw
    if system.dA is None:
        a_mid, a_rad = system.A, np.zeros((n, n))
    else:
        a_mid = system.A + 0.5 * (system.dA[0] + system.dA[1])
        a_rad = 0.5 * (system.dA[1] - system.dA[0])
    if system.dB is None:
        b_mid, b_rad = system.B, np.zeros((n, m))
    else:
        b_mid = system.B + 0.5 * (system.dB[0] + system.dB[1])
        b_rad = 0.5 * (system.dB[1] - system.dB[0])
    # Section 7: with an interval ΔB, the unit columns [B_c, I] give ∫e^{(A+ΔA)s}ds as well.
    unit = n if np.any(b_rad > 0) and system.continuous else 0
    integral: tuple[FloatArray, FloatArray] | None = (np.eye(n), np.zeros((n, n))) if np.any(b_rad > 0) else None
    if not system.continuous:
        system.sampling_period(h)  # refuses an h other than dt
        first_order: _FirstOrder | None = None
        phi, gamma, d_phi, d_gamma = a_mid, b_mid, a_rad, b_rad
        center = system.E @ w_center
        radius = np.abs(system.E) @ w_radius
        generators: FloatArray | None = system.E * w_radius  # E diag(w_r): the exact noise set
        step = 1.0
    else:
        step = as_positive("h", h, "a positive step for a continuous-time system")
        generators = None  # the noise integral of a step is known as a box only (section 5)
        inputs = np.hstack([b_mid, np.eye(n)[:, :unit]])
        m = m + unit
        size = n + m + nw
        aug = np.zeros((size, size))
        aug[:n, :n], aug[:n, n : n + m], aug[:n, n + m :] = a_mid, inputs, system.E
        rad = np.zeros((size, size))
        rad[:n, :n] = a_rad
        with np.errstate(over="ignore", invalid="ignore"):
            exact = expm(aug * step)
        _check_finite("Phi, Gamma", exact[:n], step, a_mid)
        phi, gamma, gamma_e = exact[:n, :n], exact[:n, n : n + m], exact[:n, n + m :]
        uncertain = bool(np.any(a_rad > 0))
        cheap_spread, cheap_noise, cheap_spread_integral = _cheap_bounds(aug, rad, a_mid, a_rad, system.E, step)
        decay = _decay_bounds(a_mid, aug[:n], nw, a_rad if uncertain else None, step)
        noise_integral = np.minimum(cheap_noise, decay.noise_integral)
        first_order = decay.first_order
        if decay.d_phi is None or decay.d_inputs is None or decay.spread_integral is None:
            spread, spread_integral = np.zeros((n, size)), np.zeros((n, n))
        else:
            spread = np.minimum(cheap_spread, np.concatenate([decay.d_phi, decay.d_inputs], axis=1))
            spread_integral = np.minimum(cheap_spread_integral, decay.spread_integral)
        d_phi, d_gamma, d_gamma_e = spread[:, :n], spread[:, n : n + m], spread[:, n + m :]
        center = gamma_e @ w_center
        radius = (noise_integral + spread_integral @ np.abs(system.E)) @ w_radius + d_gamma_e @ np.abs(w_center)
        if unit:  # Γ(ΔA, ΔB) = Γ_I(ΔA)B_c + Γ_I(ΔA)(ΔB - ΔB_c), |Γ_I(ΔA)| <= |Γ_I| + δΓ_I (section 7)
            m = m - unit
            gamma_i, d_gamma_i = gamma[:, m:], d_gamma[:, m:]
            gamma, d_gamma = gamma[:, :m], d_gamma[:, :m] + (np.abs(gamma_i) + d_gamma_i) @ b_rad
            integral = (gamma_i, inflate(-d_gamma_i, d_gamma_i, floor=0.0)[1])
        _check_finite("dPhi", d_phi, step, a_mid)
        _check_finite("dGamma", d_gamma, step, a_mid)
        _check_finite("noise_radius", radius, step, a_mid)
    # Round the radii upward (exact zeros stay zero: a point model stays a point model); the rounding of
    # the point matrices is absorbed by the observers' output margin.
    d_phi = inflate(-d_phi, d_phi, floor=0.0)[1]
    d_gamma = inflate(-d_gamma, d_gamma, floor=0.0)[1]
    radius = inflate(-radius, radius, scale=radius + np.abs(center), floor=0.0)[1]
    if integral is None:
        return SampledModel(phi, d_phi, gamma, d_gamma, center, radius, step, first_order, noise_generators=generators)
    # β = ΔB - ΔB_c lies in ±b_rad up to the rounding of the centre B + ΔB_c: pad relative to its terms
    scale = np.abs(system.B) + np.abs(system.dB[0]) + np.abs(system.dB[1]) if system.dB is not None else b_rad
    dB_radius = inflate(-b_rad, b_rad, scale=scale, floor=0.0)[1]
    return SampledModel(phi, d_phi, gamma, d_gamma, center, radius, step, first_order, *integral, dB_radius, generators)


@dataclass(frozen=True)
class DeltaLinearisation:
    r"""The sampled model linearised in :math:`\delta = \Delta A - \Delta A_c` (:func:`delta_linearisation`).

    .. math::

        x_{k+1} = \Phi_c x_k + \Gamma_c u_k + \sum_{l} \delta_{a_lb_l}(M_l x_k + N_l u_k) + \varrho_k + q_k,
        \qquad |\varrho_k| \le R_x|x_k| + R_u|u_k|,\qquad q_k \in [\text{noise\_lo}, \text{noise\_hi}],

    for every :math:`\delta` with :math:`|\delta| \le` ``radius``, every ``ΔB`` in its box and every noise signal in
    its box;
    the measurement is :math:`y_k = Cx_k + \nu_k` with :math:`\nu_k \in [v_{lo}, v_{hi}]`.

    Attributes
    ----------
    Phi : numpy.ndarray, shape (n, n)
        Transition matrix :math:`\Phi_c` of the centre model :math:`A + \Delta A_c`.
    Gamma : numpy.ndarray, shape (n, m)
        Input matrix :math:`\Gamma_c` of the centre model.
    M : numpy.ndarray, shape (n_δ, n, n)
        Derivative of :math:`\Phi` in the uncertain entry ``entries[l]`` (discrete time: :math:`e_ae_b^\top`).
    N : numpy.ndarray, shape (n_δ, n, m)
        Derivative of :math:`\Gamma` in the uncertain entry ``entries[l]`` (discrete time: zero).
    R_x : numpy.ndarray, shape (n, n)
        Bound of the second-order remainder's state term (elementwise, nonnegative).
    R_u : numpy.ndarray, shape (n, m)
        Bound of the second-order remainder's input term.
    entries : tuple of tuple of int
        The uncertain entries ``(a, b)`` of ``ΔA`` (radius > 0), in row-major order.
    center : numpy.ndarray, shape (n, n)
        Centre :math:`\Delta A_c` of the box of ``ΔA``.
    radius : numpy.ndarray, shape (n, n)
        Radius of the box of ``ΔA``.
    noise_lo : numpy.ndarray, shape (n,)
        Lower end of the process-noise box of one step (the sound sampled model's).
    noise_hi : numpy.ndarray, shape (n,)
        Upper end of the process-noise box.
    C : numpy.ndarray, shape (p, n)
        Output matrix.
    v_lo : numpy.ndarray, shape (p,)
        Lower end of the box of the measurement noise :math:`F v`.
    v_hi : numpy.ndarray, shape (p,)
        Upper end of the box of :math:`F v`.
    """

    Phi: FloatArray
    Gamma: FloatArray
    M: FloatArray
    N: FloatArray
    R_x: FloatArray
    R_u: FloatArray
    entries: tuple[tuple[int, int], ...]
    center: FloatArray
    radius: FloatArray
    noise_lo: FloatArray
    noise_hi: FloatArray
    C: FloatArray
    v_lo: FloatArray
    v_hi: FloatArray


def _delta_remainder(
    aug: FloatArray,
    rad: FloatArray,
    base: FloatArray,
    M: FloatArray,
    N: FloatArray,
    weights: FloatArray,
    sampled: SampledModel,
) -> tuple[FloatArray, FloatArray]:
    r"""Bounds of the state and input terms of the second-order remainder of :func:`delta_linearisation`.

    Two sound bounds of :math:`|R|`, kept elementwise at their minimum:

    * the series bound :math:`e^{|\mathcal A|h + Dh} - e^{|\mathcal A|h} - L(|\mathcal A|h, Dh)` (tight for
      small :math:`\|A\|h`; it overflows, or is astronomically loose, for a stiff :math:`A`: about
      :math:`e^{1000}` for an eigenvalue of :math:`-1000` and :math:`h = 1`);
    * the triangle inequality :math:`|R| \le |\Phi(\delta) - \Phi_c| + \sum_l |\delta_l| |M_l|`, with the
      first term bounded by the sound sampled model's ``dPhi`` (which keeps the decay of a stiff :math:`A`)
      plus the difference of its midpoint matrix and ``base`` (both ``expm`` of the same matrix), and
      :math:`|\delta_l| \le` ``weights[l]``, the radius of entry :math:`l`; likewise for the input term
      with ``dGamma`` and :math:`N`.

    Both are padded by ``_MODEL_PAD`` of the largest finite exponential for the rounding of ``expm``.
    """
    linear_x = np.einsum("l,lij->ij", weights, np.abs(M))  # Σ_l |δ_l| |M_l| (zero without uncertain entries)
    linear_u = np.einsum("l,lij->ij", weights, np.abs(N))
    n = M.shape[1]
    triangle = np.concatenate(
        [
            sampled.dPhi + np.abs(sampled.Phi - base[:n, :n]) + linear_x,
            sampled.dGamma + np.abs(sampled.Gamma - base[:n, n:]) + linear_u,
        ],
        axis=1,
    )
    triangle = triangle + _MODEL_PAD * (np.abs(base[:n]) + triangle)
    with np.errstate(over="ignore", invalid="ignore"):
        abs_aug = np.abs(aug)
        top = expm(abs_aug + rad)
        _, first = expm_frechet(abs_aug, rad)
        series = (np.maximum(top - expm(abs_aug) - first, 0.0) + _MODEL_PAD * top)[:n]
    remainder = np.where(np.isfinite(series), np.minimum(series, triangle), triangle)
    return remainder[:, :n], remainder[:, n:]


def delta_linearisation(system: LTISystem, bounds: Bounds, h: float | None = None) -> DeltaLinearisation:
    r"""The sampled model of a system with interval ``ΔA`` as a linear function of :math:`\delta`.

    * **Discrete time**: :math:`\Phi_c = A + \Delta A_c`, :math:`M_{ab} = e_ae_b^\top`, :math:`N = 0`,
      :math:`R_x` the relative pad ``1e-13`` of :math:`|\Phi_c|`, :math:`R_u = 0`.
    * **Continuous time** (step ``h``, input held): with :math:`\mathcal A = [[A + \Delta A_c, B], [0, 0]]`
      and the direction :math:`\mathcal D = [[\delta, 0], [0, 0]]`, :math:`e^{(\mathcal A + \mathcal D)h} =
      e^{\mathcal A h} + L(\mathcal A h, \mathcal D h) + R` with :math:`L` the Fréchet derivative of the
      exponential (linear in :math:`\delta`: it gives :math:`M, N`) and :math:`|R| \le e^{(|\mathcal A| +
      D)h} - e^{|\mathcal A|h} - L(|\mathcal A|h, Dh)` (the terms of the series with at least two factors
      of :math:`\mathcal D`, bounded termwise; all nonnegative), padded by ``1e-13`` of the largest
      exponential for the rounding of ``expm``.

    The noise box is the sound sampled model's (:func:`sampled_model`, valid for every ``ΔA`` of the box).
    An interval ``dB`` (centre :math:`\Delta B_c`, radius :math:`B_r`): :math:`\Gamma_c, N` are those of
    :math:`B_c = B + \Delta B_c`, and :math:`\Gamma_I(\Delta A)(\Delta B - \Delta B_c)u_k`, with
    :math:`\Gamma_I(\Delta A) = \int_0^h e^{(A+\Delta A)s}ds` (the identity in discrete time), joins the
    remainder: :math:`R_u` grows by :math:`(|\Gamma_I| + \delta\Gamma_I)B_r` (module docstring, section 7),
    i.e. ``ΔB`` is treated as free at every step.

    Parameters
    ----------
    system : LTISystem
        Model with an interval ``dA``.
    bounds : Bounds
        Noise boxes (``w`` and ``v`` are used).
    h : float, optional
        Step length, required for continuous time; in discrete time ``None`` or ``dt``.

    Returns
    -------
    DeltaLinearisation

    Raises
    ------
    AssumptionError
        If the system has no interval ``dA``.
    """
    if system.dA is None:
        raise AssumptionError("system.dA: expected an interval ΔA (a point model needs no linearisation in ΔA)")
    full = bounds.resolve(system)
    n, m = system.n, system.m
    b_c, b_r = system.B, np.zeros((n, m))
    if system.dB is not None:
        b_c, b_r = system.B + 0.5 * (system.dB[0] + system.dB[1]), 0.5 * (system.dB[1] - system.dB[0])
    sampled = sampled_model(_with_inputs(system, b_c), full, h)  # centre B_c: ΔB - ΔB_c enters R_u below
    center = 0.5 * (system.dA[0] + system.dA[1])
    radius = 0.5 * (system.dA[1] - system.dA[0])
    entries = tuple((int(a), int(b)) for a, b in zip(*np.nonzero(radius > 0), strict=True))
    nd = len(entries)
    M = np.zeros((nd, n, n))
    N = np.zeros((nd, n, m))
    if system.continuous:
        step = sampled.h
        size = n + m
        aug = np.zeros((size, size))
        aug[:n, :n], aug[:n, n:] = system.A + center, b_c
        rad = np.zeros((size, size))
        rad[:n, :n] = radius
        base = expm(aug * step)
        phi, gamma = base[:n, :n], base[:n, n:]
        for index, (a, b) in enumerate(entries):
            direction = np.zeros((size, size))
            direction[a, b] = step
            _, derivative = expm_frechet(aug * step, direction)
            M[index], N[index] = derivative[:n, :n], derivative[:n, n:]
        weights = np.array([radius[a, b] for a, b in entries], dtype=float)  # |δ_l| ≤ radius of entry l
        R_x, R_u = _delta_remainder(aug * step, rad * step, base, M, N, weights, sampled)
    else:
        phi, gamma = system.A + center, b_c.copy()
        for index, (a, b) in enumerate(entries):
            M[index, a, b] = 1.0
        R_x = _MODEL_PAD * np.abs(phi)
        R_u = np.zeros((n, m))
    if np.any(b_r > 0):  # |Γ_I(ΔA)(ΔB - ΔB_c)u| <= (|Γ_I| + δΓ_I) B_r |u|: a further remainder term
        unit = sampled_model(_with_inputs(system, np.eye(n)), full, h)
        spread = (np.abs(unit.Gamma) + unit.dGamma) @ b_r
        R_u = R_u + inflate(-spread, spread, floor=0.0)[1]
    lo = sampled.noise_center - sampled.noise_radius
    hi = sampled.noise_center + sampled.noise_radius
    v_lo, v_hi = matvec_bounds(system.F, full.v[0], full.v[1])
    return DeltaLinearisation(phi, gamma, M, N, R_x, R_u, entries, center, radius, lo, hi, system.C, v_lo, v_hi)


def _with_inputs(system: LTISystem, B: FloatArray) -> LTISystem:
    """The model with input matrix ``B`` and no ``dB`` (same ``A``, ``dA``, noises and sampling)."""
    return LTISystem(system.A, system.C, B=B, E=system.E, F=system.F, dt=system.dt, dA=system.dA)
