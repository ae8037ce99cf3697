import numpy as np
import pytest

from intervalobs import ContinuousNonlinearSystem, IntervalObserverError, LPVSystem, LTISystem, NonlinearSystem
from intervalobs.errors import ArgumentError, BoundsError, DimensionError
from intervalobs.systems import ReactionSystem, SampledSystem
from intervalobs.systems.dimensions import ModelDimensions


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


def _models():
    """One small model of each class with known sizes (n, m, p, q, nw, nv)."""
    lti = LTISystem(np.eye(3), np.ones((2, 3)), B=np.ones((3, 1)), E=np.ones((3, 2)), F=np.ones((2, 4)))
    lpv = LPVSystem(
        A=lambda th: [[-1.0, th[0], 0.0], [0.0, -2.0, 0.0], [0.0, 0.0, -1.0]],
        B=lambda th: [[1.0], [0.0], [th[0]]],
        C=np.eye(3)[:2],
        theta_box=([-1.0], [1.0]),
        B_un=lambda th: [[0.0], [1.0], [0.0]],
    )
    nonlinear = NonlinearSystem(
        lambda x: (0.5 * x[0], np.sin(x[1])), lambda x: (x[0],), G=[[1.0], [0.0]], H=[[0.0]], B=[[1.0, 0.0], [0.0, 1.0]]
    )
    continuous = ContinuousNonlinearSystem(
        lambda x, u, p: (x[1], -p[0] * x[0] + u[0]), lambda x, u: (x[0], x[1], x[0]), n=2, m=1, n_params=1, E=np.eye(2)
    )
    sampled = SampledSystem(np.zeros((4, 4)), np.eye(4)[:1], m=2)
    reaction = ReactionSystem([[1.0, 0.0], [-2.0, 1.0], [0.0, -1.0]], measured=[1, 2], inlet=[0.0, 5.0, 1.0])
    return [
        ("lti", lti, (3, 1, 2, 0, 2, 4)),
        ("lpv", lpv, (3, 1, 2, 1, 3, 0)),
        ("nonlinear", nonlinear, (2, 2, 1, 1, 2, 1)),
        ("continuous-nonlinear", continuous, (2, 1, 3, 0, 2, 3)),
        ("sampled", sampled, (4, 2, 1, 0, 4, 1)),
        ("reaction", reaction, (3, 1, 2, 2, 0, 2)),
    ]


MODELS = _models()


@pytest.mark.parametrize(("name", "model", "sizes"), MODELS, ids=[m[0] for m in MODELS])
def test_every_model_class_states_its_sizes_through_one_base(name, model, sizes):
    assert isinstance(model, ModelDimensions)
    assert (model.n, model.m, model.p, model.q, model.nw, model.nv) == sizes
    assert all(type(v) is int for v in (model.n, model.m, model.p, model.q, model.nw, model.nv))
    for size in ("n", "m", "p", "q", "nw", "nv"):
        assert size not in vars(type(model)), f"{name} redeclares {size}"
        with pytest.raises(AttributeError):
            setattr(model, size, 7)
