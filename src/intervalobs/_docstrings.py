"""Parameter descriptions that many signatures share, written once and placed into docstrings.

A docstring names a shared description by a line holding only ``%(name)s``; :func:`shared_docs`
replaces that line, at its indentation, by the text of :data:`DESCRIPTIONS` (SciPy's ``doccer`` habit).
Only whole lines are replaced, so a ``%`` elsewhere in a docstring is left as it is, and an unknown
name fails at import rather than rendering as a placeholder.
"""

from __future__ import annotations

import re
from typing import TypeVar

T = TypeVar("T")

DESCRIPTIONS: dict[str, str] = {
    "lti_system_bounds": (
        "system : LTISystem\n    Discrete-time model.\nbounds : Bounds\n    Boxes of ``x0``, ``w``, ``v``."
    ),
    "uncertain_system_bounds": (
        "system : LTISystem\n    Discrete- or continuous-time model with an interval ``dA``.\n"
        "bounds : Bounds\n    Boxes of ``x0``, ``w``, ``v``."
    ),
    "sampled_system_bounds": (
        "system : SampledSystem\n    The partially linear model with sampled outputs.\n"
        "bounds : Bounds\n    Boxes of ``x0``, ``d`` (``w``) and ``V`` (``v``)."
    ),
    "model_bounds": (
        "system : LTISystem, LPVSystem or NonlinearSystem\n    The model.\n"
        "bounds : Bounds\n    Boxes of the initial state and the noises."
    ),
    "record": (
        "t : array_like, shape (T,)\n    Sample times.\n"
        "y : array_like, shape (T, p)\n    Measurements of one run.\n"
        "u : array_like, shape (T, m), optional\n    Known inputs."
    ),
    "runs": (
        "t : array_like, shape (T,)\n    Sample times (spacing ``h`` for a continuous-time system).\n"
        "y : array_like, shape (T, p) or (M, T, p)\n    Measurements; a leading axis holds Monte Carlo runs."
    ),
    "prior_box": (
        "Parameters\n----------\n"
        "x0_lower, x0_upper : array_like, shape (n,), optional\n"
        "    Prior box of ``x(t_0)`` (default: the bounds' ``x0``).\n\n"
        "Returns\n-------\nObserverState"
    ),
    "state_output": "A : array_like, shape (n, n)\n    State matrix.\nC : array_like, shape (p, n)\n    Output matrix.",
    "boxes": "lower, upper : array_like, shape (..., n)\n    Boxes; leading axes are carried through.",
    "complex_value": (
        "Parameters\n----------\ns : complex or numpy.ndarray\n    Point(s) of the complex plane.\n\n"
        "Returns\n-------\nfloat or numpy.ndarray"
    ),
    "complex_inside": (
        "Parameters\n----------\ns : complex or numpy.ndarray\n    Point(s) of the complex plane.\n\n"
        "Returns\n-------\nbool or numpy.ndarray"
    ),
    "boxes_range": (
        "Parameters\n----------\n"
        "lower, upper : array_like, shape (..., n)\n    Boxes; leading axes are carried through.\n\n"
        "Returns\n-------\nlower, upper : numpy.ndarray, shape (..., m)"
    ),
    "natural_extension": (
        "Parameters\n----------\nlower, upper : array_like, shape (..., n)\n    Boxes.\n\n"
        "Returns\n-------\nlower, upper : numpy.ndarray"
    ),
    "resolve": (
        "Parameters\n----------\nsystem : LTISystem, SampledSystem, NonlinearSystem or LPVSystem\n"
        "    Any model with the sizes ``n``, ``nw`` and ``nv`` of its unknowns.\n\nReturns\n-------\nResolvedBounds"
    ),
    "shape_name": "shape : tuple of int, optional\n    Expected (m, n).\nname : str\n    Name used in error messages.",
    "points": "Parameters\n----------\nx : array_like, shape (..., n)\n    Points.\n\nReturns\n-------\nnumpy.ndarray",
    "box_name": 'Parameters\n----------\nname : {"x0", "w", "v", "p"}\n    Which box.\n\n'
    "Returns\n-------\nnumpy.ndarray",
    "any_array": "Parameters\n----------\na : array_like\n    Matrix or vector (any shape).",
    "weight": (
        "Parameters\n----------\nweight : array_like, shape (n, n), optional\n"
        "    Symmetric positive definite :math:`W` (default identity).\n\nReturns\n-------\nfloat"
    ),
    "size_name": (
        "size : int, optional\n    Expected number of returned components.\n"
        "name : str\n    Name used in error messages."
    ),
    "window": (
        "Parameters\n----------\nmodel : WindowModel\nhorizon : int\n    Window length ``H`` (steps).\n"
        "points : int\n    Points of the prior's convex hull (0: the prior is a box)."
    ),
    "sampled_model": (
        "model : SampledModel\n    Sampled interval model.\n"
        "C, F : numpy.ndarray\n    Output and measurement-noise matrices.\n"
        "v_radius : numpy.ndarray\n    Radius of the measurement-noise box."
    ),
    "states_inputs": "x : array_like, shape (..., n)\n    States.\nu : array_like, shape (..., m)\n    Inputs.",
    "argument_name": "Parameters\n----------\nname : str\n    Argument name used in error messages.",
    "not_real": (
        "Returns\n-------\nfloat\n\nRaises\n------\nArgumentTypeError\n    When ``value`` is not a real number."
    ),
    "uio_decoupled": (
        "A, C : array_like\n    System matrices.\ndecoupling : UIODecoupling\n    From :func:`uio_decoupling`."
    ),
    "pair_arguments": (
        "Parameters\n----------\nx, y : array_like, shape (..., n)\n    The two arguments.\n\n"
        "Returns\n-------\nnumpy.ndarray, shape (..., m)"
    ),
    "samples": "Parameters\n----------\nsteps : int\n    Number of samples.",
    "step_inputs": (
        "Parameters\n----------\nu : numpy.ndarray, shape (..., m)\n    The known inputs of the steps.\n\n"
        "Returns\n-------\nlower, upper : numpy.ndarray, shape (..., n) or (..., nw)"
    ),
}
"""Shared descriptions by name; a value is numpydoc text without indentation."""

_REPRODUCTION_RUN = (
    "Parameters\n----------\n"
    "out_dir : pathlib.Path\n    Output folder for this example.\n"
    "seed : int\n    Seed of the noise realisations.\n"
    "plots : bool\n    Also write the PNG figures."
)
_SUMMARY = "Returns\n-------\ndict\n    The summary written to ``summary.json``."
DESCRIPTIONS["reproduction_run"] = _REPRODUCTION_RUN
DESCRIPTIONS["reproduction_summary"] = _SUMMARY
DESCRIPTIONS["tightness_run"] = (
    f"{_REPRODUCTION_RUN}\n"
    "full : bool\n    Also write the tightness report (window LPs, the ΔA lower bound, the IntersectionObserver).\n\n"
    f"{_SUMMARY}"
)

_PLACEHOLDER = re.compile(r"^([ \t]*)%\((\w+)\)s[ \t]*$", re.MULTILINE)


def _indented(match: re.Match[str]) -> str:
    indent, name = match.group(1), match.group(2)
    return "\n".join(indent + line if line else line for line in DESCRIPTIONS[name].splitlines())


def shared_docs(obj: T) -> T:
    """Replace each ``%(name)s`` line of ``obj``'s docstring by :data:`DESCRIPTIONS` ``[name]``.

    Parameters
    ----------
    obj : function or class
        Object whose docstring names shared descriptions.

    Returns
    -------
    function or class
        ``obj`` itself, its docstring completed.
    """
    if obj.__doc__:
        obj.__doc__ = _PLACEHOLDER.sub(_indented, obj.__doc__)
    return obj
