"""The path a chain of LP solves took: which solver gave each objective its multipliers, and how many pivots.

Every window LP of the package (:mod:`~intervalobs.lp.window`, :mod:`~intervalobs.lp.condensed`,
:mod:`~intervalobs.lp.envelope`) solves a chain of objectives over one feasible set and tries its solvers in a
fixed order: the dense simplex of :mod:`~intervalobs.lp.dense_simplex`, then HiGHS from a basis (kept from the
previous window or reached by the dense simplex), then HiGHS on slightly widened rows, then HiGHS from scratch.
Which of them answered never decides soundness (every bound comes from weak duality,
:func:`~intervalobs.lp.certified.dual_bounds`), but it decides the cost, so each LP counts the routes in a
:class:`SolverPath` that the estimators copy into their :class:`~intervalobs.estimate.Estimate`'s ``meta``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Literal

__all__ = ["SOLVERS", "RecordsPath", "Solver", "SolverPath", "as_solver"]

Solver = Literal["auto", "highs"]
"""``"auto"``: the dense simplex first where an LP has one (the condensed window hull), HiGHS for the rest;
``"highs"``: HiGHS for every solve."""

SOLVERS: tuple[Solver, ...] = ("auto", "highs")


def as_solver(value: object) -> Solver:
    """Check a ``solver`` option.

    Parameters
    ----------
    value : object
        ``"auto"`` or ``"highs"``.

    Returns
    -------
    str

    Raises
    ------
    intervalobs.errors.DataError
        For any other value.
    """
    from ..errors import DataError

    if value not in SOLVERS:
        raise DataError(f"solver: expected one of {', '.join(map(repr, SOLVERS))}, got {value!r}")
    return value


@dataclass
class SolverPath:
    """How many objectives each route solved, and the pivots spent.

    Attributes
    ----------
    dense : int
        Solved to an optimum by the dense simplex.
    highs_warm : int
        Solved by HiGHS from a basis: one kept from the previous window, the dense simplex's, or its own last.
    widened : int
        Solved again by HiGHS on rows widened by ``ROW_RELAX`` after a run without an optimum.
    scratch : int
        Solved by HiGHS from scratch: after the widened rows failed too, or again because the multipliers of an
        optimum certified too little (``CERTIFICATE_GAP``).
    failed : int
        Solves that ended without an optimum after every fallback (their multipliers, when finite, still give a
        valid bound; a box then keeps its looser fallback).
    pivots : int
        Simplex pivots of every route (the dense simplex's pivots and bound flips, HiGHS's iterations).
    """

    dense: int = 0
    highs_warm: int = 0
    widened: int = 0
    scratch: int = 0
    failed: int = 0
    pivots: int = 0

    def add(self, other: SolverPath) -> None:
        """Add the counts of ``other`` to these.

        Parameters
        ----------
        other : SolverPath
        """
        for field in fields(self):
            setattr(self, field.name, getattr(self, field.name) + getattr(other, field.name))

    def as_dict(self) -> dict[str, int]:
        """The counts by name (JSON-ready).

        Returns
        -------
        dict
        """
        return {field.name: getattr(self, field.name) for field in fields(self)}


class RecordsPath:
    """The one interface of the package's chain LPs to the route of their solves: :attr:`path` counts them."""

    path: SolverPath
    """The routes of the solves since the last :meth:`take_path` (set by the subclass's constructor)."""

    def take_path(self) -> SolverPath:
        """The routes counted since the last call, and a fresh count.

        Returns
        -------
        SolverPath
        """
        path, self.path = self.path, SolverPath()
        return path
