import numpy as np
import pytest

from intervalobs import IntervalObserverError, LTISystem
from intervalobs.errors import ArgumentError, BoundsError, DimensionError


def test_shapes_are_checked_with_the_argument_name():
    with pytest.raises(DimensionError, match="A: expected a square matrix"):
        LTISystem(np.ones((2, 3)), np.ones((1, 3)))
    with pytest.raises(DimensionError, match=r"C: expected shape any×2"):
        LTISystem(np.eye(2), np.ones((1, 3)))
    with pytest.raises(DimensionError, match="B: expected shape 2×any"):
        LTISystem(np.eye(2), np.ones((1, 2)), B=np.ones((3, 1)))


def test_model_bounds_are_checked():
    with pytest.raises(BoundsError, match="dA: expected bounds that contain 0"):
        LTISystem(np.eye(2), np.ones((1, 2)), dA=(np.ones((2, 2)), 2 * np.ones((2, 2))))
    with pytest.raises(ArgumentError, match="dt: expected a positive"):
        LTISystem(np.eye(2), np.ones((1, 2)), dt=-1.0)
    with pytest.raises(BoundsError, match="finite"):
        LTISystem(np.array([[np.nan]]), [[1.0]])


def test_errors_share_the_base_class_and_value_error():
    assert issubclass(DimensionError, IntervalObserverError) and issubclass(DimensionError, ValueError)


def test_defaults_and_from_control():
    control = pytest.importorskip("control")
    ss = control.ss([[0, 1], [-2, -3]], [[0], [1]], [[1, 0]], [[0]])
    system = LTISystem.from_control(ss)
    assert system.continuous and (system.n, system.m, system.p, system.nw, system.nv) == (2, 1, 1, 2, 1)
    discrete = LTISystem.from_control(control.ss(ss.A, ss.B, ss.C, ss.D, 0.1))
    assert discrete.dt == 0.1
    with pytest.raises(TypeError, match="unexpected keyword argument 'G'"):
        LTISystem.from_control(ss, G=1)
