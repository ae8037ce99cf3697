"""The sizes of a model's signals, stated once for every model class."""

from __future__ import annotations

__all__ = ["ModelDimensions"]


class ModelDimensions:
    """Numbers of states, known inputs, outputs, unknown inputs and noise channels of a model.

    The model classes (:class:`~intervalobs.systems.lti.LTISystem`,
    :class:`~intervalobs.systems.lpv.LPVSystem`, :class:`~intervalobs.systems.nonlinear.NonlinearSystem`,
    :class:`~intervalobs.systems.continuous_nonlinear.ContinuousNonlinearSystem`,
    :class:`~intervalobs.systems.sampled.SampledSystem`,
    :class:`~intervalobs.systems.reaction.ReactionSystem`) derive from it: each constructor validates its
    matrices or functions, then states the sizes once with :meth:`_set_dimensions`. They are read-only
    afterwards; the boxes of :class:`~intervalobs.systems.bounds.Bounds` are checked against ``n``, ``nw``
    and ``nv``. What each size counts in a given model (``nw = n`` where the disturbance enters every
    state, ``nv = 0`` where the outputs are noise-free, ...) is said in that class's docstring.
    """

    _n: int
    _m: int
    _p: int
    _q: int
    _nw: int
    _nv: int

    def _set_dimensions(self, *, n: int, m: int, p: int, nw: int, nv: int, q: int = 0) -> None:
        """State the sizes (called once, by the constructor, after validation).

        Parameters
        ----------
        n, m, p : int
            Numbers of states, known inputs and outputs.
        nw, nv : int
            Numbers of process-noise (disturbance) and measurement-noise channels.
        q : int
            Number of unknown inputs (0 for a model without them).
        """
        self._n, self._m, self._p = int(n), int(m), int(p)
        self._nw, self._nv, self._q = int(nw), int(nv), int(q)

    @property
    def n(self) -> int:
        """Number of states."""
        return self._n

    @property
    def m(self) -> int:
        """Number of known inputs."""
        return self._m

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self._p

    @property
    def q(self) -> int:
        """Number of unknown inputs (0 for a model without them)."""
        return self._q

    @property
    def nw(self) -> int:
        """Number of process-noise (disturbance) channels: the length of the ``w`` box."""
        return self._nw

    @property
    def nv(self) -> int:
        """Number of measurement-noise channels: the length of the ``v`` box."""
        return self._nv
