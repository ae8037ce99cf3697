"""UnknownInputIntervalObserver on the aircraft model of seed 000: enclosure, run == step, errors."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs.design.differentiator import HOSMDifferentiator, levant_gains
from intervalobs.errors import AssumptionError, DataError, DimensionError
from intervalobs.examples import aircraft as ac
from intervalobs.interval import ROUNDING_MARGIN
from intervalobs.observers.unknown_input import UnknownInputIntervalObserver

H = ac.TE


def _design(**kwargs) -> UnknownInputIntervalObserver:
    options = {"noise_rate": np.full(4, ac.DELTA_DOT_BAR), "output_accel": np.full(4, ac.OUTPUT_ACCEL)}
    options.update(kwargs)
    return UnknownInputIntervalObserver.design(ac.aircraft_system(), ac.aircraft_bounds(), D=ac.D, h=H, **options)


@pytest.fixture(scope="module")
def observer() -> UnknownInputIntervalObserver:
    return _design()


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(
    ("delta_kind", "omega_kind"),
    [("sine", "sine"), ("plateau", "vertex"), ("sine", "vertex"), ("plateau", "sine")],
    ids=["sine-sine", "plateau-vertex", "sine-vertex", "plateau-sine"],
)
def test_encloses_state_and_input_under_smooth_extreme_noise(observer, seed, delta_kind, omega_kind) -> None:
    t = np.arange(15001) * H
    rec = ac.simulate_aircraft(t, seed=seed, delta_kind=delta_kind, omega_kind=omega_kind)
    est = observer.run(t, rec.y)
    state = est.enclosure(rec.x, transient=0.0)
    assert state.fraction == 1.0 and state.max_violation == 0.0
    inputs = est.input_enclosure(rec.xi, transient=0.0)
    assert inputs.fraction == 1.0 and inputs.max_violation == 0.0
    assert np.all(est.input_lower[0] == -np.inf) and np.all(est.input_upper[0] == np.inf)  # no bound yet
    assert np.all(np.isfinite(est.input_lower[1:]))
    assert np.abs(rec.psi_ddot).max() <= ac.OUTPUT_ACCEL  # the assumption behind the derivative bound


def test_encloses_from_box_vertices_with_runs(observer) -> None:
    t = np.arange(5001) * H
    rng = np.random.default_rng(7)
    vertices = rng.choice([-1.0, 1.0], size=(6, 5))
    recs = [
        ac.simulate_aircraft(t, seed=i, x0=v, delta_kind="plateau", omega_kind="vertex") for i, v in enumerate(vertices)
    ]
    y = np.stack([r.y for r in recs])
    est = observer.run(t, y)
    assert est.lower.shape == (6, t.size, 5) and est.input_lower.shape == (6, t.size, 2)
    assert est.enclosure(np.stack([r.x for r in recs]), transient=0.0).max_violation == 0.0
    xi = np.broadcast_to(recs[0].xi, (6, *recs[0].xi.shape))
    assert est.input_enclosure(xi, transient=0.0).max_violation == 0.0


@pytest.mark.parametrize("derivative", ["difference", "hosm"])
def test_run_equals_repeated_step(derivative) -> None:
    obs = _design(derivative=derivative, hosm=HOSMDifferentiator(1, levant_gains(1, ac.OUTPUT_ACCEL)))
    t = np.arange(400) * H
    y = np.stack([ac.simulate_aircraft(t, seed=s).y for s in range(2)])
    est = obs.run(t, y)
    assert est.meta["rows"] == obs.rows == "filtered"  # step consumes y_k and returns the box at t_k
    state = obs.init()
    for k in range(t.size):
        state = obs.step(state, y[:, k])
        np.testing.assert_allclose(state.lower, est.lower[:, k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[:, k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.input_lower, est.input_lower[:, k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.input_upper, est.input_upper[:, k], rtol=0, atol=1e-12)


def test_widths_converge_to_rho(observer) -> None:
    t = np.arange(120001) * H
    rec = ac.simulate_aircraft(t, seed=3)
    est = observer.run(t, rec.y)
    w = est.width()
    wi = est.input_upper - est.input_lower
    assert np.all(w[-1] <= observer.rho_x * (1 + 1e-3)) and np.all(w[-1] >= observer.rho_x * (1 - 1e-9))
    assert np.all(wi[-1] <= observer.rho_xi * (1 + 1e-3))
    assert np.all(w[-1] < 0.1 * 2.0)  # well below the initial box
    # The exact width is data-independent and decreasing after the first samples; the computed one adds
    # data-dependent outward pads, relative margins r (ROUNDING_MARGIN, 2·step_tolerance/h for the sampling
    # times, 8u in the recursion) of magnitudes <= cond(T)·max|bound|, accumulated by the w recursion with gain
    # <= 1/min|λ| per unit time: two widths can differ by twice that, whatever the LAPACK build.
    r = ROUNDING_MARGIN + 2 * observer.step_tolerance / observer.h + 8 * np.finfo(float).eps
    magnitude = np.max(np.maximum(np.abs(est.lower), np.abs(est.upper)))
    cond = np.linalg.norm(np.abs(observer.coords.S), np.inf) * np.linalg.norm(np.abs(observer.coords.T), np.inf)
    pad = 2 * r * cond * magnitude / np.min(np.abs(observer.coords.poles))
    assert np.all(np.diff(w[1000:], axis=0) <= pad)
    assert pad < 1e-5 * np.min(w[-1])  # the allowance is far below the width it tests
    paper_x, paper_xi = observer.paper_rho()
    assert np.all(observer.rho_x < paper_x) and np.all(observer.rho_xi < paper_xi)


def test_paper_hosm_setting_violates_its_claimed_input_bounds() -> None:
    obs = _design(derivative="hosm", hosm=HOSMDifferentiator(1, [100.0, 100.0]), mu1=1.1)
    t = np.arange(50001) * H
    rec = ac.simulate_aircraft(t, seed=0)
    est = obs.run(t, rec.y)
    assert est.enclosure(rec.x, transient=0.0).max_violation == 0.0  # the state does not use ẏ
    # once the state bounds have contracted (t > 3 s), the HOSM error 0.25 > β = 0.12 shows through
    assert est.input_enclosure(rec.xi, transient=3.0).max_violation > 0.01


def test_bad_input_is_rejected(observer) -> None:
    t = np.arange(100) * H
    y = ac.simulate_aircraft(t).y
    with pytest.raises(DataError, match="t: expected uniform spacing"):
        observer.run(t * 1.5, y)
    with pytest.raises(DataError):
        observer.run(t, y[:, :3])
    with pytest.raises(AssumptionError, match="Metzler"):
        _design(K=np.array(ac.PAPER["K_printed"]).T, T=np.array(ac.PAPER["T"]))
    with pytest.raises(DimensionError, match="derivative"):
        _design(derivative="spline")
    with pytest.raises(DimensionError, match="hosm"):
        _design(derivative="hosm")


def test_given_triangular_metzler_coordinates_are_used() -> None:
    obs = _design()
    mix = np.eye(5) + 0.1 * np.tril(np.ones((5, 5)), -1)  # T' N T'^-1 lower triangular, Metzler
    tri = _design(K=obs.coords.K, T=mix @ obs.coords.T)
    assert tri.coords.M[np.tril_indices(5, -1)].min() > 0.05 and tri.coords.metzler_check > -1e-12
    t = np.arange(8001) * H
    rec = ac.simulate_aircraft(t, seed=5, delta_kind="plateau", omega_kind="vertex")
    est = tri.run(t, rec.y)
    assert est.enclosure(rec.x, transient=0.0).max_violation == 0.0
    assert est.input_enclosure(rec.xi, transient=0.0).max_violation == 0.0
    with pytest.raises(AssumptionError, match="Metzler"):
        _design(K=obs.coords.K, T=(np.eye(5) + 0.1 * np.triu(np.ones((5, 5)), 1)) @ obs.coords.T)


def test_complex_poles_on_the_aircraft_enclose() -> None:
    obs = _design(poles=[-1, -2 + 0.5j, -2 - 0.5j, -3, -4])
    assert np.count_nonzero(obs.coords.M[~np.eye(5, dtype=bool)] > 0.01) == 6  # the 3×3 cyclic block
    t = np.arange(10001) * H
    rec = ac.simulate_aircraft(t, seed=6, delta_kind="plateau", omega_kind="sine")
    est = obs.run(t, rec.y)
    assert est.enclosure(rec.x, transient=0.0).max_violation == 0.0
    assert est.input_enclosure(rec.xi, transient=0.0).max_violation == 0.0


@pytest.mark.parametrize("control", ["held", "continuous"])
def test_aircraft_known_commands_enclose_with_no_input_widths(control) -> None:
    system = ac.aircraft_system(known_inputs=True)
    options = {"noise_rate": np.full(4, ac.DELTA_DOT_BAR), "output_accel": np.full(4, ac.OUTPUT_ACCEL)}
    obs = UnknownInputIntervalObserver.design(system, ac.aircraft_bounds(), D=ac.D, h=H, **options)
    t = np.arange(25001) * H  # spans the rudder step at 2.00005 s (inside a sampling step)
    rec = ac.simulate_aircraft(t, seed=8, delta_kind="plateau", omega_kind="vertex", control=control)
    assert np.abs(rec.psi_ddot).max() <= ac.OUTPUT_ACCEL
    est = obs.run(t, rec.y, rec.u if control == "held" else ac.control_box(t))
    assert est.enclosure(rec.x, transient=0.0).max_violation == 0.0
    assert est.input_enclosure(rec.xi, transient=0.0).max_violation == 0.0
    free = _design().run(t, ac.simulate_aircraft(t, seed=8, delta_kind="plateau", omega_kind="vertex").y)
    np.testing.assert_allclose(est.width()[-1], free.width()[-1], rtol=1e-5)
    ratio = (est.input_upper - est.input_lower)[-1] / (free.input_upper - free.input_lower)[-1]
    assert np.all(ratio < 1.001)
