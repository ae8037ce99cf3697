"""Seed 001: LPV model, certified ΔA_R bounds, boundedness LMI, LPV interval observer / UIO."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, DesignError
from intervalobs.design.lpv import boundedness_lmi, uio_observer_matrix, verify_boundedness
from intervalobs.diagnosis import isolate
from intervalobs.errors import AssumptionError, BoundsError, DimensionError
from intervalobs.examples.manipulator import (
    FAULT_BOUND,
    NOMINAL,
    TRUE_PARAMETERS,
    X0,
    ManipulatorModel,
    controller,
    rk4_step,
    simulate_closed_loop,
)
from intervalobs.interval_dual import IntervalDual
from intervalobs.observers.lpv import LPVIntervalObserver, LPVIntervalUIO
from intervalobs.systems.lpv import LPVSystem


@pytest.fixture(scope="module")
def model() -> ManipulatorModel:
    return ManipulatorModel(cells=32, splits=4, pieces=4)


def _direct_entries(at, bt, ct, k):
    a, b, c = NOMINAL
    d = at * ct - bt**2 * k**2
    m11, m12 = (a * ct - b * bt * k**2) / d, k * (b * at - a * bt) / d
    m21, m22 = k * (b * ct - c * bt) / d, (c * at - b * bt * k**2) / d
    return np.array([m11 - 1, m12, m21, m22 - 1, -bt * m12, b - bt * m22, bt * m11 - b, bt * m21])


# --- interval forward-mode AD (the one type: intervalobs.interval_dual) ----------------------------


def test_the_former_interval_jet_is_interval_dual_with_a_future_warning():
    import intervalobs.design.lpv as lpv_design

    with pytest.warns(FutureWarning, match="IntervalJet is deprecated.*IntervalDual"):
        assert lpv_design.IntervalJet is IntervalDual
    assert "IntervalJet" not in lpv_design.__all__


# --- certified bounds ----------------------------------------------------------------------------


def test_rotated_bounds_are_exact_and_contain_every_parameter(model):
    b = model.bounds
    assert np.all(b.slack[4:8] == 0.0), "ΔA_R coefficients must be certified exact (vertex ranges)"
    assert np.all(b.certified_fraction[:, [0, 2]] == 1.0)
    rng = np.random.default_rng(1)
    samples = rng.uniform(model.p_lower, model.p_upper, size=(2000, 3))
    for k in np.linspace(-1.0, 1.0, 41):
        lo, hi = b.evaluate(np.array(k), select=range(8))
        vals = _direct_entries(samples[:, 0], samples[:, 1], samples[:, 2], k)
        assert np.all(vals >= lo[:, None]) and np.all(vals <= hi[:, None])
        # exactness: the bounds are attained (at vertices) up to the rounding margin
        verts = _direct_entries(b.vertices[:, 0], b.vertices[:, 1], b.vertices[:, 2], k)
        np.testing.assert_allclose(verts.min(axis=1)[4:], lo[4:], atol=1e-10)
        np.testing.assert_allclose(verts.max(axis=1)[4:], hi[4:], atol=1e-10)


def test_bounds_over_a_scheduling_interval_are_sound(model):
    rng = np.random.default_rng(2)
    for _ in range(20):
        k0 = rng.uniform(-1, 0.98)
        k1 = k0 + rng.uniform(0, 0.02)
        lo, hi = model.bounds.evaluate(np.array(k0), np.array(k1), select=range(8))
        p = rng.uniform(model.p_lower, model.p_upper, size=(300, 3))
        ks = rng.uniform(k0, k1, size=300)
        vals = _direct_entries(p[:, 0], p[:, 1], p[:, 2], ks)
        assert np.all(vals >= lo[:, None]) and np.all(vals <= hi[:, None])


def test_naive_rotation_is_sound_but_wider(model):
    th = np.array([[0.0, 0.3, 1.0, -1.0], [0.2, -1.0, 0.5, 0.5]])
    lo, hi, _, _ = model.rotated_bounds_at(th)
    nlo, nhi = model.naive_rotated_bounds_at(th)
    assert np.all(nlo <= lo + 1e-12) and np.all(nhi >= hi - 1e-12)
    assert np.sum(nhi - nlo) > 1.5 * np.sum(hi - lo)


def test_fast_form_must_match_the_certified_form(model):
    with pytest.raises(DesignError, match="certified entries"):
        model.bounds.check_fast(lambda at, bt, ct, k: 1.01 * model._fast(at, bt, ct, k), range(8))


def test_a_shared_denominator_gives_the_certificate_of_separate_ones(model):
    """A denominator list shared by entries is evaluated once (issue 36): the certificate is the same to the bit."""
    from intervalobs.design.lpv import certify_vertex_extremes
    from intervalobs.examples.manipulator import ENTRY_NAMES, _rational_factory

    shared = _rational_factory(NOMINAL)

    def separate(bt, k):
        return [(form[0], list(form[1]), *form[2:]) for form in shared(bt, k)]

    args = (ENTRY_NAMES, model.p_lower, model.p_upper, (-1.0, 1.0))
    options = {"affine": (0, 2), "cells": 32, "splits": 4, "pieces": 4}
    one, other = certify_vertex_extremes(shared, *args, **options), certify_vertex_extremes(separate, *args, **options)
    for name in ("slack", "lipschitz", "certified_fraction"):
        assert np.array_equal(getattr(one, name), getattr(other, name))
    assert np.array_equal(one.slack, model.bounds.slack)
    theta = np.linspace(-1.0, 1.0, 9)
    assert np.array_equal(one.vertex_values(theta), other.vertex_values(theta))


def test_parameter_box_with_vanishing_determinant_is_rejected():
    with pytest.raises(AssumptionError, match="cos"):
        ManipulatorModel(delta=(4.0, 1.0, 1.0))


# --- LPV system validation -------------------------------------------------------------------------


def _lpv(**over):
    args = dict(
        A=lambda th: [[-1.0, 0.0], [0.0, -1.0]],
        B=lambda th: [[1.0], [0.0]],
        C=np.eye(2),
        theta_box=([-1.0], [1.0]),
    )
    args.update(over)
    return LPVSystem(**args)


def test_lpv_system_validates_shapes_bounds_and_ranks():
    sys_ = _lpv()
    assert (sys_.n, sys_.m, sys_.p, sys_.n_theta) == (2, 1, 2, 1)
    with pytest.raises(DimensionError, match="square"):
        _lpv(A=lambda th: [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(AssumptionError, match="full row rank"):
        _lpv(C=[[1.0, 0.0], [2.0, 0.0]])
    with pytest.raises(BoundsError, match="lower <= upper"):
        _lpv(dA=(np.ones((2, 2)), np.zeros((2, 2))))
    with pytest.raises(DimensionError, match="shape"):
        _lpv(dA=(np.zeros((3, 2)), np.zeros((3, 2))))
    with pytest.raises(AssumptionError, match="rank"):
        _lpv(B_un=lambda th: [[0.0], [0.0]])
    with pytest.raises(BoundsError, match="finite"):
        _lpv(A=lambda th: [[np.nan, 0.0], [0.0, -1.0]])


def test_manipulator_lpv_system_is_consistent(model):
    th = np.array([[0.1, -0.4, 0.3, -0.2]])
    # A, B of the LPV form reproduce the nominal dynamics
    u = np.array([[1.0, -2.0]])
    nominal = np.tile(NOMINAL, (1, 1))
    x = th.copy()
    from intervalobs.examples.manipulator import _true_rate

    rate = _true_rate(x, u, nominal[:, 0], nominal[:, 1], nominal[:, 2])
    lpv_rate = model.a_matrix(th)[0] @ x[0] + model.b_matrix(th)[0] @ u[0]
    np.testing.assert_allclose(rate[0], lpv_rate, rtol=1e-12)
    # R B_un = H = [I; 0] (26)
    np.testing.assert_allclose(
        model.r_matrix(th)[0] @ model.b_matrix(th)[0], np.vstack([np.eye(2), np.zeros((2, 2))]), atol=1e-14
    )


# --- boundedness LMI ---------------------------------------------------------------------------------


def _grid(points: int) -> np.ndarray:
    phis = np.linspace(-np.pi, np.pi, points, endpoint=False)
    return np.array([[0.0, p, a, b] for p in phis for a in (-1.0, 0.0, 1.0) for b in (-1.0, 0.0, 1.0)])


def test_lmi_74_feasible_at_lambda_1_with_exact_bounds_only(model):
    f = -np.eye(4)
    lo, hi, _, _ = model.rotated_bounds_at(_grid(4))
    cert = boundedness_lmi(f, f, lo, hi, switchable=range(4), eps1_candidates=(1.0,))
    rng = np.random.default_rng(3)
    fine = np.column_stack([rng.uniform(-np.pi, np.pi, (500, 2)), rng.uniform(-1, 1, (500, 2))])
    flo, fhi, _, _ = model.rotated_bounds_at(fine)
    cert = verify_boundedness(cert, f, f, flo, fhi, switchable=range(4))
    assert cert.subsets == 16  # columns 1-2 of ΔA_R vanish
    assert cert.fine_margin is not None and cert.fine_margin < -0.05
    assert cert.second_block_margin <= 0.0
    assert cert.feasible


def test_lmi_74_has_no_certificate_at_lambda_1_with_naive_bounds(model):
    f = -np.eye(4)
    # R·[ΔA] by interval arithmetic: no certificate at λ = 1 (a grid of 12 φ values hits the worst ones)
    nlo, nhi = model.naive_rotated_bounds_at(_grid(12))
    naive = boundedness_lmi(f, f, nlo, nhi, switchable=range(4), eps1_candidates=(1.0, 2.0))
    assert naive.coarse_margin > 0.5 and not naive.feasible


# --- observer ------------------------------------------------------------------------------------------

H = 1e-3
X0_BOX = (np.asarray(X0) - 0.1, np.asarray(X0) + 0.1)


def _uio(model, f=None):
    f = -np.eye(4) if f is None else f
    return LPVIntervalUIO(
        model, H, f, bounds=Bounds(x0=X0_BOX), unknown_input=(-FAULT_BOUND * np.ones(2), FAULT_BOUND * np.ones(2))
    )


def test_observer_rejects_bad_gains(model):
    with pytest.raises(AssumptionError, match="Metzler"):
        LPVIntervalObserver(model, H, -np.eye(4) - 0.1 * (np.ones((4, 4)) - np.eye(4)))
    with pytest.raises(DesignError, match="Hurwitz"):
        LPVIntervalObserver(model, H, 0.1 * np.eye(4))
    with pytest.raises(AssumptionError, match="lower <= 0 <= upper"):
        LPVIntervalUIO(model, H, -np.eye(4), unknown_input=(np.ones(2), 2 * np.ones(2)))
    f = -np.eye(4)
    f[0, 1] = 0.5  # Metzler and Hurwitz, but H's columns are not eigenvectors
    with pytest.raises(AssumptionError, match="F H = H"):
        LPVIntervalUIO(model, H, f, unknown_input=(-np.ones(2), np.ones(2)))


def test_run_equals_repeated_step(model):
    t = np.arange(0, 0.3 + H / 2, H)
    x, u = simulate_closed_loop(t, np.array([TRUE_PARAMETERS]), np.zeros(2))
    obs = _uio(model)
    est = obs.run(t, x[0], u[0])
    state = obs.init()
    for k in range(t.size):
        state = obs.step(state, x[0, k], u[0, k])
        np.testing.assert_allclose(state.lower, est.lower[k], rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.upper, est.upper[k], rtol=0, atol=1e-12)


@pytest.mark.parametrize("box_free", [True, False], ids=["enclosures-at-once", "sample-after-sample"])
def test_advance_many_gives_the_numbers_of_advance(model, box_free):
    """advance_many over a block of samples (issue 36) is advance sample after sample, to the last bit, whether
    the model's enclosures are evaluated at once (the manipulator's ignore the box) or one sample at a time."""
    t = np.arange(0, 0.2 + H / 2, H)
    params = model.bounds.vertices[:3]
    x, u = simulate_closed_loop(t, params, np.array([FAULT_BOUND, -FAULT_BOUND]), onset=0.1)
    obs = _uio(model)
    xs, us = x.transpose(1, 0, 2), u.transpose(1, 0, 2)  # (samples, runs, ·)
    z0 = np.tile(obs.init().internal["z_lower"], (3, 1)), np.tile(obs.init().internal["z_upper"], (3, 1))
    model.box_free = box_free
    try:
        *block, zl_many, zu_many = obs.advance_many(*z0, xs, us)
    finally:
        del model.box_free
    zl, zu = z0
    for k in range(t.size):
        *step, zl, zu = obs.advance(zl, zu, xs[k], us[k])
        for got, want in zip(block, step):
            np.testing.assert_array_equal(got[k], want)
    np.testing.assert_array_equal(zl_many, zl)
    np.testing.assert_array_equal(zu_many, zu)


def test_compiled_recursion_with_a_coupled_gain_is_the_numpy_one_to_rounding_and_encloses(model):
    """With a non-diagonal Metzler F (no UIO term) the compiled z recursion may sum e^{Fh} z in another order than
    BLAS: it stays within a few ulps (of the terms, |x| <= 1) of advance sample after sample, and the boxes contain
    the truth at every parameter vertex."""
    f = -np.eye(4) + 0.2 * (np.ones((4, 4)) - np.eye(4))
    obs = LPVIntervalObserver(model, H, f, bounds=Bounds(x0=X0_BOX))
    t = np.arange(0, 0.4 + H / 2, H)
    params = model.bounds.vertices
    x, u = simulate_closed_loop(t, params, np.zeros(2))
    xs, us = x.transpose(1, 0, 2), u.transpose(1, 0, 2)
    z0 = [np.tile(obs.init().internal[key], (len(params), 1)) for key in ("z_lower", "z_upper")]
    lo_many, hi_many, *_ = obs.advance_many(*z0, xs, us)
    zl, zu = z0
    for k in range(t.size):
        lo, hi, _, _, zl, zu = obs.advance(zl, zu, xs[k], us[k])
        np.testing.assert_allclose(lo_many[k], lo, rtol=0, atol=1e-14)  # terms of magnitude <= 1: a few ulps
        np.testing.assert_allclose(hi_many[k], hi, rtol=0, atol=1e-14)
    assert np.all(lo_many <= xs) and np.all(xs <= hi_many)


def test_compiled_truth_is_the_numpy_closed_loop_to_the_last_bit():
    """closed_loop_block (the campaign's truth, compiled) gives the states and inputs of controller + rk4_step
    sample after sample, faults switching on inside the block."""
    from intervalobs.examples.manipulator import _KD, _KP, FAULT_ONSET
    from intervalobs.examples.manipulator_kernel import closed_loop_block

    rng = np.random.default_rng(3)
    params = np.array([TRUE_PARAMETERS, *rng.uniform(0.9, 1.1, (2, 3)) * np.asarray(NOMINAL)])
    faults = np.array([[0.0, 0.0], [FAULT_BOUND, 0.0], [-1.0, 2.0]])
    t = FAULT_ONSET - 0.1 + np.arange(120) * 2e-3
    x0 = np.asarray(X0) + rng.uniform(-0.1, 0.1, (3, 4))
    x, xs, us = x0.copy(), np.empty((t.size, 3, 4)), np.empty((t.size, 3, 2))
    closed_loop_block(x, t, faults, FAULT_ONSET, params, np.asarray(NOMINAL), np.array([_KP, _KD]), 1e-3, 2, xs, us)
    ref = x0.copy()
    for k, tk in enumerate(t):
        np.testing.assert_array_equal(xs[k], ref)
        u = controller(ref, float(tk))
        np.testing.assert_array_equal(us[k], u)
        for _ in range(2):
            ref = rk4_step(ref, u + faults if tk >= FAULT_ONSET else u, params, 1e-3)
    np.testing.assert_array_equal(x, ref)


CAMPAIGN_OUTCOMES = {
    (0.02, 0.25): [
        [0, 0, True, False, [None, None]], [1, 0, True, False, [None, None]],
        [0, 1, False, False, [None, None]], [1, 1, False, False, [None, None]],
        [0, 2, True, False, [None, 24.338]], [1, 2, True, False, [None, 24.23]],
        [0, 3, False, False, [None, 24.2]], [1, 3, False, False, [None, 24.096]],
    ],
    (0.2, 5.0): [
        [0, 0, True, False, [None, None]], [1, 0, True, False, [None, None]],
        [0, 1, True, False, [24.588, None]], [1, 1, True, False, [24.526, None]],
        [0, 2, True, False, [None, 21.568]], [1, 2, True, False, [None, 21.64]],
        [0, 3, False, False, [None, None]], [1, 3, False, False, [None, None]],
    ],
}  # fmt: skip
"""campaign_task's rows for runs 0 and 1 of two cells (seed 0), computed sample after sample before issue 36."""


@pytest.mark.parametrize("cell", list(CAMPAIGN_OUTCOMES), ids=["level-0.02-fault-0.25", "level-0.2-fault-5"])
def test_campaign_outcomes_are_those_of_the_sample_by_sample_loop(cell):
    """The campaign's blocks of samples (issue 36) keep every outcome and detection time of the former loop."""
    from intervalobs.reproduce.manipulator_lpv import campaign_task

    rows = campaign_task(*cell, [0, 1], 0)
    assert [[r, s, ok, fa, fn] for r, s, ok, fa, fn in rows] == CAMPAIGN_OUTCOMES[cell]


def test_enclosure_and_no_false_alarm_at_parameter_vertices(model):
    """Fault-free runs at the 8 vertices of the parameter box (extreme uncertainty): violation exactly 0,
    isolation signals never negative."""
    t = np.arange(0, 2.5 + H / 2, H)
    params = model.bounds.vertices
    x, u = simulate_closed_loop(t, params, np.zeros(2))
    est, rec = isolate(_uio(model), t, x, u)
    report = est.enclosure(x)
    assert report.fraction == 1.0 and report.max_violation == 0.0
    assert rec.signal_lower.min() >= 0.0 and rec.signal_upper.min() >= 0.0


def test_bang_bang_fault_in_channel_1_never_flags_channel_2(model):
    """(27): with u_un(2) = 0, the channel-2 signals stay nonnegative whatever fault 1 does (±5,
    switching inside the sampling steps)."""
    rng = np.random.default_rng(4)
    h_true = H / 4
    t = np.arange(0, 2.0 + H / 2, H)
    params = model.bounds.vertices[[0, 3, 5, 6]]
    runs = params.shape[0]
    x = np.tile(np.asarray(X0), (runs, 1))
    xs, us = np.empty((runs, t.size, 4)), np.empty((runs, t.size, 2))
    fault = np.zeros((runs, 2))
    fault[:, 0] = FAULT_BOUND
    for k in range(t.size):
        xs[:, k] = x
        us[:, k] = controller(x, float(t[k]))
        for _ in range(4):
            if rng.random() < 0.3:
                fault[:, 0] = -fault[:, 0]
            x = rk4_step(x, us[:, k] + fault, params, h_true)
    _, rec = isolate(_uio(model), t, xs, us)
    assert rec.signal_lower[..., 1].min() >= 0.0 and rec.signal_upper[..., 1].min() >= 0.0


def test_step_enclosure_contains_the_intersample_state(model):
    rng = np.random.default_rng(5)
    params = model.sample_parameters(16, rng)
    x0 = np.column_stack([rng.uniform(-np.pi, np.pi, (16, 2)), rng.uniform(-1, 1, (16, 2))])
    u = rng.uniform(-5, 5, (16, 2))
    fault = rng.uniform(-FAULT_BOUND, FAULT_BOUND, (16, 2))
    enc = model.step_enclosure(x0 - 0.1, x0 + 0.1, x0, u, 1e-2)
    x = x0.copy()
    for _ in range(20):
        x = rk4_step(x, u + fault, params, 5e-4)
        assert np.all(x >= enc.flow_lower) and np.all(x <= enc.flow_upper)


def test_observer_input_validation(model):
    obs = _uio(model)
    t = np.arange(0, 0.01, H)
    with pytest.raises(Exception, match="expected shape"):
        obs.run(t, np.zeros((t.size, 3)))
    with pytest.raises(Exception, match="t: expected uniform spacing"):
        obs.run(np.array([0.0, 0.002, 0.003]), np.zeros((3, 4)))


@pytest.mark.slow
def test_manipulator_reproduction_meets_the_issue(tmp_path):
    import json

    from intervalobs.cli import main
    from paper_notes import misquoted

    assert main(["reproduce", "manipulator-lpv", "--full", "--out", str(tmp_path)]) == 0
    folder = tmp_path / "manipulator-lpv"
    s = json.loads((folder / "summary.json").read_text())
    sc = s["design"]["scenarios"]
    assert s["enclosure"]["state"] == {"fraction": 1.0, "max_violation": 0.0}
    assert sc["1"]["false_alarm"] is False and sc["1"]["isolated"] == []
    assert sc["1"]["state_enclosure_no_fault"]["max_violation"] == 0.0
    for name, isolated in (("2", [1]), ("3", [2]), ("4", [1, 2])):
        assert sc[name]["false_alarm"] is False and sc[name]["isolated"] == isolated
        assert all(20.0 < t_det < 23.0 for t_det in sc[name]["detection_time_s"])
    assert s["design"]["lmi_74_exact_lambda_1"]["feasible"] is True
    assert s["design"]["lmi_74_exact_lambda_1"]["fine_points"] == 10000
    assert s["design"]["lmi_74_naive_lambda_1"]["feasible"] is False
    # only the joint angles measured: sound velocity bounds in every scenario, isolation by the hypothesis bank
    angles = s["angles_only"]
    assert angles["C_B_un_max_abs"] == 0.0
    for name, isolated in (("1", []), ("2", [1]), ("3", [2]), ("4", [1, 2])):
        sa = angles["scenarios"][name]
        assert sa["state_enclosure"] == {"fraction": 1.0, "max_violation": 0.0}
        assert max(sa["velocity_width_max"]) < 0.05
        assert sa["false_alarm"] is False and sa["isolated"] == isolated and sa["success"] is True
        assert all(20.0 < t_det < 20.1 for t_det in sa["detection_time_s"])
    assert misquoted("manipulator-lpv", s)[0] == []
    for png in ("scenario1_isolation.png", "scenario4_isolation.png", "scenario1_state_bounds.png", "angles_only.png"):
        assert (folder / png).exists()


def test_theorem_4_1_choice_gives_minus_lambda_identity(model):
    """(101) with Γ = −λI and the paper's H* gives F = −λI at every scheduling point (Section 5)."""
    th = np.column_stack([np.random.default_rng(6).uniform(-np.pi, np.pi, (50, 2)), np.zeros((50, 2))])
    lam = 1.7
    h_star = np.zeros((4, 4))
    h_star[2:, :2] = -lam * np.eye(2)
    h = np.vstack([np.eye(2), np.zeros((2, 2))])
    f = uio_observer_matrix(model.r_matrix(th), h, model.b_matrix(th), -lam * np.eye(2), h_star)
    np.testing.assert_allclose(f, np.broadcast_to(-lam * np.eye(4), f.shape), atol=1e-12)
    np.testing.assert_allclose(f @ h, np.broadcast_to(h @ (-lam * np.eye(2)), (50, 4, 2)), atol=1e-12)  # (103)
