r"""Design tools of the LPV interval observer and interval UIO (Rotondo et al.).

Two things live here.

**Sound elementwise bounds over a parameter box, with a proof** (Rotondo et al., (11)–(15), (23)–(24)).
An uncertain entry :math:`g(p, s)` depends on parameters :math:`p` in a box :math:`P` (e.g. the
manipulator's :math:`\tilde a, \tilde b, \tilde c`) and on a scalar scheduling feature :math:`s`
(e.g. :math:`\cos(x_2 - x_1)`). :func:`certify_vertex_extremes` proves that, for every :math:`s`, the
range of :math:`g(\cdot, s)` over :math:`P` is the range over the :math:`2^{n_p}` vertices of
:math:`P`, up to a certified slack:

1. The :math:`s` axis is cut into cells; in each cell and for each parameter :math:`k` the other
   parameters are cut into slabs, and every *line* (cell × slab, the whole range of :math:`p_k`) into
   pieces along :math:`p_k`. Interval forward-mode differentiation
   (:class:`~intervalobs.interval_dual.IntervalDual`, outward rounded) encloses
   :math:`\partial g / \partial p_k` on every piece: :math:`[d^-_j, d^+_j]`.
2. Along a line, moving :math:`p_k` to its upper end decreases :math:`g` by at most the negative mass
   :math:`\sum_j w_j \max(-d^-_j, 0)`, to its lower end by at most the positive mass
   :math:`\sum_j w_j \max(d^+_j, 0)`; the line's *slack* is the smaller one. It is 0 when the
   derivative has a certified sign on the whole line (monotone).
3. Coordinate ascent: from a maximiser of :math:`g(\cdot, s)` over :math:`P`, move each coordinate in
   turn to the end of its range that does not decrease :math:`g` (or decreases it by at most the
   slack). After :math:`n_p` moves the point is a vertex, so
   :math:`\max_P g \le \max_{\text{vertices}} g + \sum_k \text{slack}_k` (and the mirror for the min).

Where every slab is sign-certified the vertex range is *exact*. The certificate also encloses
:math:`|\partial g/\partial s|` over :math:`P \times` cell, so bounds over a small interval of
:math:`s` (the scheduling variable over one sampling step) stay sound:
:class:`CertifiedVertexBounds`.

**Boundedness analysis** (Rotondo et al., LMI (43) of Theorem 3.1 and (74) of Lemma 4.1 with
(75)–(79) read as (95)–(100)): :func:`boundedness_lmi` solves it with CVXPY on a coarse grid of
:math:`\Theta` and :func:`verify_boundedness` checks the inequality on a fine grid with vectorised
eigenvalue computations, for all subsets :math:`S_1, S_2`.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import cvxpy as cp
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import AssumptionError, BoundsError, DesignError, DimensionError
from ..interval import Interval, inflate, neg, pos, round_outward
from ..interval_dual import IntervalDual
from ..validation import as_box, as_matrix
from .lmi import solve_lmi

__all__ = [
    "BoundednessCertificate",
    "CertifiedVertexBounds",
    "RationalForm",
    "boundedness_lmi",
    "certify_vertex_extremes",
    "eta_and_generator",
    "uio_observer_matrix",
    "verify_boundedness",
]

FloatArray = NDArray[np.float64]

_FAST_TOLERANCE = 1e-12
"""Largest relative difference a user's vectorised closed form may have from the certified rational form
(a check that it computes the same entries, not a rounding pad: their bounds come from the certificate)."""


def _round_up_nonnegative(x: FloatArray, roundings: int) -> FloatArray:
    """Round up a nonnegative result of ``roundings`` rounded operations; exact zeros stay exact certificates.

    A value computed by k rounded operations on nonnegative terms is within k half-ulps of its exact value
    relative, and one ulp is at least half an ulp relative, so k ulps up cover it (:func:`round_outward`).
    A zero is exact here: every term was an exact zero.
    """
    return np.where(x > 0, round_outward(x, x, roundings)[1], x)


def _as_dual(entry: Any, like: IntervalDual) -> IntervalDual:
    """An entry as a dual: one that depends on no variable (a number) gets a zero derivative shaped like ``like``."""
    if isinstance(entry, IntervalDual):
        return entry
    value = Interval._wrap(entry)
    zero = np.zeros((*np.broadcast_shapes(value.shape, like.value.shape), like.derivative.shape[-1]))
    return IntervalDual(value, Interval._raw(zero, zero))


RationalForm = Callable[..., Sequence[tuple[Any, ...]]]
"""``rational(q_1, …, q_r, s) -> [(numerator coefficients, denominator coefficients[, factor]), …]``.

An entry is ``factor(s) * numerator / denominator``; the optional factor depends on ``s`` only (it
keeps sign-certification sharp where an entry vanishes with ``s``; cell edges should include its
zeros).

The coefficients multiply the monomials of the *affine* parameters (all subsets, in
``itertools.product`` order of inclusion bits: for affine ``(p_a, p_c)`` the monomials are
``1, p_c, p_a, p_a p_c``); ``q`` are the remaining parameters. Coefficients are written with
``+ - * /`` and ``**2`` so that they work on arrays and on
:class:`~intervalobs.interval_dual.IntervalDual`.
"""


def _monomials(values: Sequence[Any]) -> list[Any]:
    out: list[Any] = []
    for bits in itertools.product((0, 1), repeat=len(values)):
        term: Any = 1.0
        for bit, v in zip(bits, values):
            if bit:
                term = v * term
        out.append(term)
    return out


def _combine(coefficients: Sequence[Any], mono: Sequence[Any]) -> Any:
    """``sum_i coefficients[i] * mono[i]``, summed from the first term."""
    total: Any = 0.0
    for c, m in zip(coefficients, mono):
        total = total + c * m
    return total


def _entries_from_rational(
    rational: RationalForm, n_p: int, affine: tuple[int, ...], with_factor: bool = True
) -> Callable[..., list[Any]]:
    general = [j for j in range(n_p) if j not in affine]

    def entries(*args: Any) -> list[Any]:
        params, s = args[:n_p], args[n_p]
        mono = _monomials([params[j] for j in affine])
        # a denominator list shared by several entries (the same object) is evaluated once: the same numbers
        shared: dict[int, tuple[Sequence[Any], Any]] = {}
        out = []
        for form in rational(*[params[j] for j in general], s):
            num, den = form[0], form[1]
            if id(den) not in shared:
                d_val = _combine(den, mono)
                # over boxes, the numerator times the reciprocal: the derivative enclosure n'/d - n d'/d^2 of the
                # product rule (the quotient rule's (n' - (n/d) d')/d is neither inside nor around it); at points, n/d
                shared[id(den)] = (den, 1.0 / d_val if isinstance(d_val, IntervalDual) else d_val)
            n_val, d_term = _combine(num, mono), shared[id(den)][1]
            value = n_val * d_term if isinstance(d_term, IntervalDual) else n_val / d_term
            if with_factor and len(form) > 2:
                value = form[2] * value
            out.append(value)
        return out

    return entries


@dataclass(frozen=True)
class CertifiedVertexBounds:
    r"""Sound elementwise bounds of uncertain entries over a parameter box, as functions of ``s``.

    Built by :func:`certify_vertex_extremes`; :meth:`evaluate` returns, for scheduling values in
    ``[s_lo, s_hi]``, lower and upper bounds of every entry over the parameter box:

    .. math:: [\min_{v} g(v, s_c) - \text{slack} - L r,\; \max_{v} g(v, s_c) + \text{slack} + L r]

    with :math:`v` the parameter vertices, :math:`s_c, r` the centre and radius of the interval,
    ``slack`` the certified vertex slack of the cell of :math:`s_c` and :math:`L` the certified bound
    of :math:`|\partial g/\partial s|`. All bounds are widened by
    :func:`~intervalobs.interval.inflate`.

    Attributes
    ----------
    names : tuple of str
        Entry names.
    vertices : numpy.ndarray, shape (2**np, np)
        Parameter vertices.
    cell_edges : numpy.ndarray, shape (cells + 1,)
        Cells of the scheduling feature.
    slack : numpy.ndarray, shape (entries, cells)
        Certified vertex slack per entry and cell (0 where the derivative sign is certified).
    lipschitz : numpy.ndarray, shape (entries,)
        Certified bound of :math:`|\partial g / \partial s|` over the whole box.
    certified_fraction : numpy.ndarray, shape (entries, np)
        Fraction of lines (cell × slab) with zero slack, per entry and parameter (1 for the affine
        parameters, monotone by the linear-fractional lemma).
    affine : tuple of int
        The parameters in which numerators and denominators are affine.
    entries : callable
        ``entries(p_1, ..., p_np, s)``: the entries built from the rational form.
    """

    names: tuple[str, ...]
    vertices: FloatArray
    cell_edges: FloatArray
    slack: FloatArray
    lipschitz: FloatArray
    certified_fraction: FloatArray
    affine: tuple[int, ...]
    entries: Callable[..., list[Any]] = field(repr=False)

    @property
    def exact(self) -> bool:
        """True when every slack is zero (the vertex ranges are the exact ranges)."""
        return bool(np.all(self.slack == 0.0))

    def vertex_values(self, s: ArrayLike) -> FloatArray:
        """Entry values at every parameter vertex.

        Parameters
        ----------
        s : array_like
            Scheduling values.

        Returns
        -------
        numpy.ndarray, shape ``(entries, 2**np, *s.shape)``
        """
        sv = np.asarray(s, dtype=float)
        shape = (self.vertices.shape[0],) + (1,) * sv.ndim
        params = [self.vertices[:, k].reshape(shape) for k in range(self.vertices.shape[1])]
        vals = self.entries(*params, sv[None])
        return np.stack(
            [np.broadcast_to(np.asarray(v, dtype=float), (self.vertices.shape[0], *sv.shape)) for v in vals]
        )

    def evaluate(
        self,
        s_lo: ArrayLike,
        s_hi: ArrayLike | None = None,
        select: Sequence[int] | None = None,
        fast: Callable[..., FloatArray] | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """Bounds of the entries for all parameters in the box and all ``s`` in ``[s_lo, s_hi]``.

        Parameters
        ----------
        s_lo, s_hi : array_like
            Ends of the scheduling interval (same shape); ``s_hi=None`` means a point.
        select : sequence of int, optional
            Entries to return (default all).
        fast : callable, optional
            ``fast(p_1, ..., p_np, s) -> array (len(select), ...)``: a vectorised closed form of the
            selected entries, used instead of the rational form for speed. The caller must have
            checked it against :attr:`entries` (see :meth:`check_fast`).

        Returns
        -------
        lower, upper : numpy.ndarray, shape ``(entries, *s.shape)``
        """
        lo_s = np.asarray(s_lo, dtype=float)
        hi_s = lo_s if s_hi is None else np.asarray(s_hi, dtype=float)
        centre = 0.5 * (lo_s + hi_s)
        radius = 0.5 * (hi_s - lo_s)
        edges = self.cell_edges
        if np.any(centre < edges[0]) or np.any(centre > edges[-1]):
            raise BoundsError(
                f"s: expected values in [{edges[0]:g}, {edges[-1]:g}] (the certified range), "
                f"got [{centre.min():g}, {centre.max():g}]"
            )
        rows = list(range(len(self.names))) if select is None else list(select)
        if fast is None:
            vals = self.vertex_values(centre)[rows]
        else:
            shape = (self.vertices.shape[0],) + (1,) * centre.ndim
            params = [self.vertices[:, k].reshape(shape) for k in range(self.vertices.shape[1])]
            vals = fast(*params, centre[None])
        cell = np.clip(np.searchsorted(edges, centre, side="right") - 1, 0, edges.size - 2)
        pad = self.slack[rows][:, cell] + self.lipschitz[rows].reshape((-1,) + (1,) * centre.ndim) * radius
        return inflate(vals.min(axis=1) - pad, vals.max(axis=1) + pad)

    def check_fast(self, fast: Callable[..., FloatArray], select: Sequence[int], points: int = 201) -> float:
        """Largest relative difference of ``fast`` from the certified rational form (vertices × s grid).

        Parameters
        ----------
        fast : callable
            As in :meth:`evaluate`.
        select : sequence of int
            The entries ``fast`` computes.
        points : int
            Scheduling values checked.

        Returns
        -------
        float

        Raises
        ------
        DesignError
            If it exceeds ``_FAST_TOLERANCE`` (1e-12; then ``fast`` does not compute the certified entries).
        """
        s = np.linspace(self.cell_edges[0], self.cell_edges[-1], points)
        ref = self.vertex_values(s)[list(select)]
        params = [self.vertices[:, k][:, None] for k in range(self.vertices.shape[1])]
        got = np.asarray(fast(*params, s[None]))
        diff = float(np.max(np.abs(got - ref) / (1.0 + np.abs(ref))))
        if not diff <= _FAST_TOLERANCE:
            raise DesignError(
                f"fast: expected the certified entries to {_FAST_TOLERANCE:g}, got a relative difference {diff:.3g}"
            )
        return diff


def certify_vertex_extremes(
    rational: RationalForm,
    names: Sequence[str],
    p_lower: ArrayLike,
    p_upper: ArrayLike,
    s_range: tuple[float, float],
    affine: Sequence[int] = (),
    cells: int = 64,
    splits: int = 8,
    pieces: int = 8,
) -> CertifiedVertexBounds:
    r"""Prove that entry ranges over a parameter box are attained at its vertices (up to a slack).

    Each entry is :math:`g = n/d` with :math:`n, d` affine in each *affine* parameter separately
    (the form of ``rational`` makes this true by construction). Then:

    * **affine parameters** — :math:`\partial g/\partial p_k = (n_k d - n d_k)/d^2` and
      :math:`\partial_k(n_k d - n d_k) = 0`, so the sign is constant along every :math:`p_k`-line
      once :math:`d` has one sign on the box (checked here by interval arithmetic on every cell):
      :math:`g` is monotone along those lines, slack 0;
    * **other parameters** — interval forward-mode derivatives on pieces of every line (module
      docstring, steps 1–2) give the slack (0 where the sign is certified).

    Coordinate ascent (step 3) then bounds the range over the box by the vertex range ± the summed
    slacks. The LPV observer needs this for the uncertainties in its coordinates,
    :math:`\Delta A_R = R\Delta A`, :math:`\Delta B_R`, :math:`\Delta B_{un,R}`.

    Parameters
    ----------
    rational : callable
        See :data:`RationalForm`.
    names : sequence of str
        One name per entry.
    p_lower, p_upper : array_like, shape (np,)
        Parameter box.
    s_range : tuple of float
        Range of the scheduling feature.
    affine : sequence of int
        Indices of the parameters in which numerators and denominators are affine.
    cells : int
        Number of cells of ``s_range``.
    splits : int
        Slabs per other parameter.
    pieces : int
        Pieces of each line along the parameter it moves.

    Returns
    -------
    CertifiedVertexBounds

    Raises
    ------
    AssumptionError
        If a denominator may vanish on the box.

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): :math:`\Delta A_R`, :math:`\Delta B_R`, :math:`\Delta B_{un,R}`
    of (14), (15), (24).
    """
    plo, phi = as_box("parameter box", (p_lower, p_upper))
    n_p = plo.size
    aff = tuple(sorted(int(j) for j in affine))
    if any(j < 0 or j >= n_p for j in aff):
        raise DimensionError(f"affine: expected indices in 0..{n_p - 1}, got {list(affine)}")
    if min(cells, splits, pieces) < 1:
        raise DimensionError(f"cells, splits, pieces: expected positive integers, got {cells}, {splits}, {pieces}")
    s0, s1 = float(s_range[0]), float(s_range[1])
    if not s0 < s1:
        raise BoundsError(f"s_range: expected s_lo < s_hi, got ({s0:g}, {s1:g})")
    entries = _entries_from_rational(rational, n_p, aff)
    cores = _entries_from_rational(rational, n_p, aff, with_factor=False)
    edges = np.linspace(s0, s1, cells + 1)
    general = [j for j in range(n_p) if j not in aff]
    *box_duals, s_cells = IntervalDual.variables(
        np.column_stack([np.broadcast_to(plo, (cells, n_p)), edges[:-1]]),
        np.column_stack([np.broadcast_to(phi, (cells, n_p)), edges[1:]]),
    )
    factor_max = _factor_bounds(rational, names, box_duals, s_cells, aff, general, cells)
    n_e = len(names)
    slack = np.zeros((n_e, cells))
    certified = np.ones((n_e, n_p))
    grid = [np.linspace(plo[k], phi[k], splits + 1) for k in range(n_p)]
    along = [np.linspace(plo[k], phi[k], pieces + 1) for k in range(n_p)]
    for k in general:
        cell, line_slacks = _line_slacks(cores, k, edges, grid, along, splits, pieces)
        for e, line_slack in enumerate(line_slacks):
            certified[e, k] = float(np.mean(line_slack == 0.0))
            per_cell = np.zeros(cells)
            np.maximum.at(per_cell, cell, line_slack)
            slack[e] = _round_up_nonnegative(slack[e] + factor_max[e] * per_cell, 2)
    # |dg/ds| over the full parameter box, per cell (the maximum over cells is used)
    vals = entries(*box_duals, s_cells)
    lipschitz = np.zeros(n_e)
    for e, v in enumerate(vals):
        ds = _as_dual(v, s_cells).derivative[..., n_p]
        lipschitz[e] = float(np.max(np.maximum(np.abs(ds.lower), np.abs(ds.upper))))
    if not np.all(np.isfinite(slack)) or not np.all(np.isfinite(lipschitz)):
        raise DesignError("certify_vertex_extremes: non-finite derivative enclosure; refine cells/splits")
    vertices = np.array(list(itertools.product(*[(plo[k], phi[k]) for k in range(n_p)])))
    return CertifiedVertexBounds(
        names=tuple(names),
        vertices=vertices,
        cell_edges=edges,
        slack=slack,
        lipschitz=lipschitz,
        certified_fraction=certified,
        affine=aff,
        entries=entries,
    )


def _factor_bounds(
    rational: RationalForm,
    names: Sequence[str],
    box_duals: list[IntervalDual],
    s_cells: IntervalDual,
    aff: tuple[int, ...],
    general: list[int],
    cells: int,
) -> FloatArray:
    """Check that every denominator keeps one sign on every cell × the whole box; the bound of each factor.

    Returns the upper bound of ``|factor|`` per entry and cell (1 for an entry without a factor).
    """
    mono = _monomials([box_duals[j] for j in aff])
    forms = rational(*[box_duals[j] for j in general], s_cells)
    if len(forms) != len(names):
        raise DimensionError(f"names: expected {len(forms)} names (one per entry), got {len(names)}")
    factor_max = np.ones((len(names), cells))
    for e, form in enumerate(forms):
        if len(form) > 2:
            factor_max[e] = np.absolute(_as_dual(form[2], s_cells).value).upper  # |.| is exact
        den = form[1]
        d_val: Any = 0.0
        for cd, mv in zip(den, mono):
            d_val = d_val + cd * mv
        d_box = _as_dual(d_val, s_cells).value
        if not (np.all(d_box.lower > 0) or np.all(d_box.upper < 0)):
            raise AssumptionError(f"entry {names[e]!r}: its denominator may vanish on the parameter box")
    return factor_max


def _line_slacks(
    cores: Callable[..., Sequence[Any]],
    k: int,
    edges: FloatArray,
    grid: list[FloatArray],
    along: list[FloatArray],
    splits: int,
    pieces: int,
) -> tuple[NDArray[np.intp], list[FloatArray]]:
    """The slack of coordinate ascent along parameter ``k`` on every line (cell × slab of the other parameters).

    Returns the cell of each line and, per entry, the slack of each line: the smaller of the
    negative and positive masses of the derivative enclosure along the line (steps 1–2 of the
    module docstring).
    """
    n_p = len(grid)
    cells = len(edges) - 1
    others = [j for j in range(n_p) if j != k]
    # boxes: (cell, other-parameter slab..., piece of p_k); one line = (cell, slab)
    idx = np.array(list(itertools.product(range(cells), *[range(splits)] * len(others), range(pieces))))
    lo_vars: list[FloatArray] = []
    hi_vars: list[FloatArray] = []
    for j in range(n_p):
        if j == k:
            lo_vars.append(along[k][idx[:, -1]])
            hi_vars.append(along[k][idx[:, -1] + 1])
        else:
            col = 1 + others.index(j)
            lo_vars.append(grid[j][idx[:, col]])
            hi_vars.append(grid[j][idx[:, col] + 1])
    s_lo_c, s_hi_c = edges[idx[:, 0]], edges[idx[:, 0] + 1]
    # only the partial derivative along p_k is used: seeding it alone gives the same numbers (interval_dual.py)
    *duals, s_dual = IntervalDual.variables(
        np.column_stack([*lo_vars, s_lo_c]), np.column_stack([*hi_vars, s_hi_c]), along=k
    )
    piece_width = (Interval(hi_vars[k]) - lo_vars[k]).upper
    lines = idx.shape[0] // pieces
    slacks = []
    for v in cores(*duals, s_dual):
        dk = _as_dual(v, s_dual).derivative[..., 0]
        dlo = np.broadcast_to(dk.lower, s_lo_c.shape)
        dhi = np.broadcast_to(dk.upper, s_lo_c.shape)
        # moving p_k to its upper end loses at most the negative mass, to its lower end the positive
        # each mass: ``pieces`` products and ``pieces - 1`` sums
        neg_mass = (piece_width * np.maximum(-dlo, 0.0)).reshape(lines, pieces).sum(axis=1)
        pos_mass = (piece_width * np.maximum(dhi, 0.0)).reshape(lines, pieces).sum(axis=1)
        neg_mass = _round_up_nonnegative(neg_mass, 2 * pieces)
        pos_mass = _round_up_nonnegative(pos_mass, 2 * pieces)
        slacks.append(np.minimum(neg_mass, pos_mass))
    return idx[::pieces, 0], slacks


# --------------------------------------------------------------------------------------------------
# Boundedness analysis: LMI (43) / (74)
# --------------------------------------------------------------------------------------------------


def uio_observer_matrix(r: ArrayLike, h: ArrayLike, b_un: ArrayLike, gamma: ArrayLike, h_star: ArrayLike) -> FloatArray:
    r"""The observer matrix of the interval UIO, vectorised over grid points.

    .. math:: F(\vartheta) = R(\vartheta)^{-1}\big[H\Gamma B_{un}(\vartheta)^\dagger
              + H^*(\vartheta)\,(I - B_{un}(\vartheta)B_{un}(\vartheta)^\dagger)\big],

    which makes the columns of H eigenvectors of F, :math:`FH = H\Gamma` (each unknown input moves the error along
    its own direction), whenever :math:`RB_{un} = H`.

    Parameters
    ----------
    r : array_like, shape (..., n, n)
        :math:`R(\vartheta)` at grid points (invertible).
    h : array_like, shape (n, q)
        H, the unknown inputs' directions in the observer's coordinates.
    b_un : array_like, shape (..., n, q)
        :math:`B_{un}(\vartheta)` at the same points.
    gamma : array_like, shape (q, q)
        :math:`\Gamma` (diagonal).
    h_star : array_like, shape (..., n, n)
        :math:`H^*`.

    Returns
    -------
    numpy.ndarray, shape (..., n, n)

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): Theorem 4.1, (101)–(102); the eigenvector condition (103)–(104);
    H of (26).
    """
    rr = np.asarray(r, dtype=float)
    bu = np.asarray(b_un, dtype=float)
    hh = np.asarray(h, dtype=float)
    n = rr.shape[-1]
    pinv = np.linalg.pinv(bu)
    inner = hh @ np.asarray(gamma, dtype=float) @ pinv + np.asarray(h_star, dtype=float) @ (np.eye(n) - bu @ pinv)
    return np.asarray(np.linalg.solve(rr, inner))


def _masked(m: FloatArray, cols: FloatArray) -> FloatArray:
    """:math:`M^{(\\mathcal N)}`: columns outside the set zeroed; ``cols`` is a 0/1 mask (..., n)."""
    return m * cols[..., None, :]


def eta_and_generator(
    f_lower: FloatArray,
    f_upper: FloatArray,
    da_lower: FloatArray,
    da_upper: FloatArray,
    s1: FloatArray,
    s2: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    r"""The matrix :math:`G` and scalar :math:`\eta` of the switching boundedness LMI per column set (vectorised).

    As the paper's proof reads them (the printed form swaps :math:`S_1` and :math:`S_2`):

    .. math::
        G = \operatorname{diag}\big(\underline F + \underline{\Delta A_R^{(S_1\cup S_3)}}^{+},\;
            \overline F + \overline{\Delta A_R^{(S_2\cup S_3)}}^{+}\big),

        \eta = \|\underline{\Delta A_R^{(S_1)}}^{+} - \overline{\Delta A_R^{(S_1)}}^{+}\|_2
             + \|\underline{\Delta A_R^{(S_2)}}^{-}\|_2 + \|\overline{\Delta A_R^{(S_2)}}^{-}\|_2
             + \|\overline{\Delta A_R^{(S_2)}}^{+} - \underline{\Delta A_R^{(S_2)}}^{+}\|_2
             + \|\overline{\Delta A_R^{(S_1)}}^{-}\|_2 + \|\underline{\Delta A_R^{(S_1)}}^{-}\|_2 .

    With :math:`S_1 = S_2 =` all columns this is the observer's (non-switching) form (η with its factor 2).

    Parameters
    ----------
    f_lower, f_upper : numpy.ndarray, shape (n, n) or (..., n, n)
        Metzler matrices of the lower and upper observer (constant or per grid point).
    da_lower, da_upper : numpy.ndarray, shape (..., n, n)
        Bounds of :math:`\Delta A_R` at grid points.
    s1, s2 : numpy.ndarray, shape (..., n)
        0/1 masks of :math:`S_1 \cup S_3` and :math:`S_2 \cup S_3`.

    Returns
    -------
    G : numpy.ndarray, shape (..., 2n, 2n)
    eta : numpy.ndarray, shape (...)

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): (74) read with the proof's (95)–(100) (the printed (79) swaps
    :math:`S_1` and :math:`S_2`); (44)–(45) of Theorem 3.1.
    """
    l1, u1 = _masked(da_lower, s1), _masked(da_upper, s1)
    l2, u2 = _masked(da_lower, s2), _masked(da_upper, s2)

    def norm(m: FloatArray) -> FloatArray:
        return np.asarray(np.linalg.norm(m, ord=2, axis=(-2, -1)))

    eta = (
        norm(pos(l1) - pos(u1))
        + norm(neg(l2))
        + norm(neg(u2))
        + norm(pos(u2) - pos(l2))
        + norm(neg(u1))
        + norm(neg(l1))
    )
    n = f_lower.shape[-1]
    lead = np.broadcast_shapes(l1.shape[:-2], l2.shape[:-2], f_lower.shape[:-2], f_upper.shape[:-2])
    g = np.zeros((*lead, 2 * n, 2 * n))
    g[..., :n, :n] = f_lower + pos(l1)
    g[..., n:, n:] = f_upper + pos(u2)
    return g, eta


def _active_switchable(switchable: Sequence[int], da_lower: FloatArray, da_upper: FloatArray) -> list[int]:
    """Switchable columns that are not identically zero on the grid (others give identical subsets)."""
    return [j for j in switchable if np.any(da_lower[..., j] != 0) or np.any(da_upper[..., j] != 0)]


def _subset_masks(n: int, switchable: Sequence[int]) -> FloatArray:
    """All 0/1 column masks that keep the non-switchable columns and any subset of the switchable ones."""
    masks = []
    for bits in itertools.product((0.0, 1.0), repeat=len(switchable)):
        m = np.ones(n)
        for j, b in zip(switchable, bits):
            m[j] = b
        masks.append(m)
    return np.array(masks)


@dataclass(frozen=True)
class BoundednessCertificate:
    r"""Solution of the boundedness LMI and its verification: a certificate that the bounds stay bounded.

    Attributes
    ----------
    P, Q : numpy.ndarray, shape (2n, 2n)
        Lyapunov matrix and the decay matrix of the LMI.
    gamma, eps1, eps2 : float
        Scalars of the LMI.
    solver_status : str
        CVXPY status of the coarse-grid solve.
    coarse_margin : float
        Largest eigenvalue of the LMI's (1,1) block over the coarse grid (negative = satisfied;
        :math:`\operatorname{tr}P = 2n`, so it is comparable with a decay rate).
    second_block_margin : float
        Largest eigenvalue of :math:`\varepsilon_1^{-1}P - \gamma I` (must be ≤ 0).
    fine_margin : float or None
        Same as ``coarse_margin`` over the fine grid (from :func:`verify_boundedness`).
    fine_points : int
        Points of the fine grid.
    subsets : int
        Pairs :math:`(S_1, S_2)` checked.

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): the boundedness LMI (43) (observer) and (74) (UIO).
    """

    P: FloatArray
    Q: FloatArray
    gamma: float
    eps1: float
    eps2: float
    solver_status: str
    coarse_margin: float
    second_block_margin: float
    fine_margin: float | None = None
    fine_points: int = 0
    subsets: int = 0

    @property
    def feasible(self) -> bool:
        """True when both blocks of the boundedness LMI are negative semidefinite on the verified grid.

        References
        ----------
        Rotondo et al. (:mod:`intervalobs.references`): (43)/(74).
        """
        margin = self.coarse_margin if self.fine_margin is None else self.fine_margin
        return bool(margin < 0 and self.second_block_margin <= 1e-9)

    def as_dict(self) -> dict[str, Any]:
        """Scalars for ``summary.json``.

        Returns
        -------
        dict
        """
        return {
            "solver_status": self.solver_status,
            "gamma": self.gamma,
            "eps1": self.eps1,
            "eps2": self.eps2,
            "coarse_margin": self.coarse_margin,
            "fine_margin": self.fine_margin,
            "fine_points": self.fine_points,
            "subset_pairs": self.subsets,
            "second_block_margin": self.second_block_margin,
            "feasible": self.feasible,
        }


def _block_max_eig(
    p: FloatArray, q: FloatArray, gamma: float, eps_sum: float, g: FloatArray, eta: FloatArray
) -> FloatArray:
    n2 = p.shape[0]
    pg = p @ g
    block = pg + np.swapaxes(pg, -1, -2) + eps_sum * p + q + gamma * (eta**2)[..., None, None] * np.eye(n2)
    return np.asarray(np.linalg.eigvalsh(block)[..., -1])


def boundedness_lmi(
    f_lower: ArrayLike,
    f_upper: ArrayLike,
    da_lower: ArrayLike,
    da_upper: ArrayLike,
    switchable: Sequence[int] = (),
    eps1_candidates: Sequence[float] = (0.25, 0.5, 1.0, 2.0),
    eps2: float = 0.01,
    q_scale: float = 1e-3,
) -> BoundednessCertificate:
    r"""Solve the boundedness LMI on a grid of :math:`\Theta` (observer, or UIO with ``switchable``).

    For fixed :math:`\varepsilon_1, \varepsilon_2` it is an LMI in :math:`P, Q, \gamma`. We fix
    :math:`Q = q I`, normalise :math:`\operatorname{tr} P = 2n`, :math:`P \succeq 10^{-3} I`, and
    minimise :math:`t` subject to
    the (1,1) block :math:`\preceq tI` at every grid point and subset pair, and
    :math:`P \preceq \varepsilon_1\gamma I` (the (2,2) block); the best :math:`\varepsilon_1` of the
    candidates is kept. Feasible means :math:`t < 0`. The result is re-checked with eigenvalues.

    Parameters
    ----------
    f_lower, f_upper : array_like, shape (n, n)
        Metzler observer matrices :math:`\underline F, \overline F` (constant).
    da_lower, da_upper : array_like, shape (N, n, n)
        Bounds of :math:`\Delta A_R` at the N coarse grid points.
    switchable : sequence of int
        Columns whose terms switch with the isolation signals (the measured columns
        :math:`1..n_y` for the UIO); empty for the observer.
    eps1_candidates : sequence of float
        Values of :math:`\varepsilon_1` tried.
    eps2 : float
        :math:`\varepsilon_2`.
    q_scale : float
        :math:`Q = q I`.

    Returns
    -------
    BoundednessCertificate

    Raises
    ------
    DesignError
        If no candidate has a verified solution (:func:`~intervalobs.design.lmi.solve_lmi`).

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): (43) (Theorem 3.1, ``switchable=()``) and (74) (the UIO).
    """
    fl = as_matrix("f_lower", f_lower)
    n = fl.shape[0]
    fu = as_matrix("f_upper", f_upper, (n, n))
    dl = np.asarray(da_lower, dtype=float).reshape(-1, n, n)
    du = np.asarray(da_upper, dtype=float).reshape(-1, n, n)
    if dl.shape != du.shape:
        raise DimensionError(f"da_upper: expected shape {dl.shape}, got {du.shape}")
    masks = _subset_masks(n, _active_switchable(switchable, dl, du))
    s1 = masks[:, None, None, :]
    s2 = masks[None, :, None, :]
    g, eta = eta_and_generator(fl, fu, dl[None, None], du[None, None], s1, s2)
    g = g.reshape(-1, 2 * n, 2 * n)
    eta = eta.reshape(-1)
    # drop duplicate constraints (zero columns make many subsets identical)
    key = np.round(np.concatenate([g.reshape(len(g), -1), eta[:, None]], axis=1), 12)
    _, keep = np.unique(key, axis=0, return_index=True)
    g, eta = g[np.sort(keep)], eta[np.sort(keep)]
    n2 = 2 * n
    q = q_scale * np.eye(n2)
    best: tuple[float, Any] | None = None
    failures = []
    relax = "increase lambda or tighten the ΔA_R bounds"
    for eps1 in eps1_candidates:
        p_var = cp.Variable((n2, n2), symmetric=True)
        gamma = cp.Variable(nonneg=True)
        t = cp.Variable()
        cons = [p_var >> 1e-3 * np.eye(n2), cp.trace(p_var) == n2, p_var << eps1 * gamma * np.eye(n2)]
        for gi, ei in zip(g, eta):
            blk = gi.T @ p_var + p_var @ gi + (eps1 + eps2) * p_var + q + gamma * float(ei) ** 2 * np.eye(n2)
            cons.append(0.5 * (blk + blk.T) << t * np.eye(n2))
        prob = cp.Problem(cp.Minimize(t), cons)
        try:
            solution = solve_lmi(prob, f"(43)/(74) with eps1 = {eps1:g}", relax)
        except DesignError as exc:
            failures.append(str(exc))
            continue
        pv = np.asarray(p_var.value, dtype=float)
        pv = 0.5 * (pv + pv.T)
        # make the (2,2) block exactly ≤ 0 (the solver meets it only to its tolerance)
        gv = max(float(np.asarray(gamma.value)), float(inflate(0.0, np.linalg.eigvalsh(pv)[-1] / eps1, floor=0.0)[1]))
        margin = float(np.max(_block_max_eig(pv, q, gv, eps1 + eps2, g, eta)))
        if best is None or margin < best[0]:
            best = (margin, (pv, gv, eps1, solution.status))
    if best is None:
        raise DesignError(
            f"no certificate that the interval widths stay bounded over the scheduling box, for any eps1 "
            f"(widen the decay rate or shrink the uncertainty): {' | '.join(failures)}"
        )
    margin, (pv, gv, eps1, status) = best
    second = float(np.max(np.linalg.eigvalsh(pv / eps1 - gv * np.eye(n2))))
    return BoundednessCertificate(
        P=pv,
        Q=q,
        gamma=gv,
        eps1=eps1,
        eps2=eps2,
        solver_status=status,
        coarse_margin=margin,
        second_block_margin=second,
        subsets=len(masks) ** 2,
    )


def verify_boundedness(
    cert: BoundednessCertificate,
    f_lower: ArrayLike,
    f_upper: ArrayLike,
    da_lower: ArrayLike,
    da_upper: ArrayLike,
    switchable: Sequence[int] = (),
    chunk: int = 2000,
) -> BoundednessCertificate:
    r"""Check the boundedness LMI with a solved :math:`P, Q, \gamma` at many grid points (vectorised eigenvalues).

    Parameters
    ----------
    cert : BoundednessCertificate
        From :func:`boundedness_lmi`.
    f_lower, f_upper : array_like, shape (n, n) or (N, n, n)
        Observer matrices (constant or at each grid point).
    da_lower, da_upper : array_like, shape (N, n, n)
        Bounds of :math:`\Delta A_R` at the fine grid points (e.g. the paper's 10 000).
    switchable : sequence of int
        As in :func:`boundedness_lmi`; every pair of subsets is checked (columns that are zero on
        the whole grid are skipped: their subsets give identical inequalities).
    chunk : int
        Grid points per vectorised batch.

    Returns
    -------
    BoundednessCertificate
        ``cert`` with ``fine_margin`` (largest eigenvalue of the (1,1) block over all points and
        subset pairs) and ``fine_points`` filled in.

    References
    ----------
    Rotondo et al. (:mod:`intervalobs.references`): (43)/(74).
    """
    fl = np.asarray(f_lower, dtype=float)
    n = fl.shape[-1]
    dl = np.asarray(da_lower, dtype=float).reshape(-1, n, n)
    du = np.asarray(da_upper, dtype=float).reshape(-1, n, n)
    fl = np.broadcast_to(fl, dl.shape)
    fu = np.broadcast_to(np.asarray(f_upper, dtype=float), dl.shape)
    masks = _subset_masks(n, _active_switchable(switchable, dl, du))
    worst = -np.inf
    for start in range(0, dl.shape[0], chunk):
        sl = slice(start, start + chunk)
        g, eta = eta_and_generator(
            fl[sl], fu[sl], dl[sl][None, None], du[sl][None, None], masks[:, None, None, :], masks[None, :, None, :]
        )
        worst = max(worst, float(np.max(_block_max_eig(cert.P, cert.Q, cert.gamma, cert.eps1 + cert.eps2, g, eta))))
    return replace(cert, fine_margin=worst, fine_points=int(dl.shape[0]), subsets=len(masks) ** 2)


def __getattr__(name: str) -> Any:
    """``IntervalJet``, the former interval forward-mode type of this module: :class:`IntervalDual`, with a warning.

    .. deprecated:: 0.2.0
       ``IntervalJet`` goes in the next release; use :class:`intervalobs.interval_dual.IntervalDual`
       (``IntervalDual.variables(lower, upper)`` gives one dual per variable; derivatives are on the last axis).
    """
    if name != "IntervalJet":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    warnings.warn(
        "intervalobs.design.lpv.IntervalJet is deprecated and goes in the next release: use "
        "intervalobs.interval_dual.IntervalDual (IntervalDual.variables(lower, upper) gives one dual per variable; "
        "derivatives are on the last axis)",
        FutureWarning,
        stacklevel=2,
    )
    return IntervalDual
