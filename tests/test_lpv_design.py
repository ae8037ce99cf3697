"""Seed 001 on a system of our own: LMI design (Corollaries 3.1, 4.1), unmeasured states, bounded d,
generic between-sample enclosures, fault isolation; truth simulated independently (fine RK4)."""

from __future__ import annotations

import numpy as np
import pytest

from intervalobs import Bounds, DesignError, LPVIntervalObserver, LPVIntervalUIO, LPVSystem
from intervalobs.design.lpv_gains import design_lpv_observer, rotate_bounds
from intervalobs.diagnosis import isolate
from intervalobs.errors import AssumptionError, DataError
from intervalobs.simulate import runge_kutta_step

H = 0.02
SUB = 8
RHO = 2.0
X0 = np.array([0.5, -0.3, 0.2, -0.1])
X0_BOX = (X0 - 0.3, X0 + 0.3)
DA = np.array([[0.02, 0.02, 0, 0], [0.02, 0.02, 0, 0], [0.02, 0, 0.02, 0.02], [0, 0.02, 0.02, 0.02]])
D = 0.05
B = np.array([1.0, 0.0, 0.0, 0.5])
FAULT_ONSET = 6.0


def a_rows(th):
    t = th[0]
    return [
        [-1.0, 0.5 * t, 0.5, 0.0],
        [0.3, -2.0, 0.0, 0.4 + 0.2 * t],
        [0.2 * t, 0.0, -1.5, 0.3],
        [0.0, 0.5, 0.2 + 0.1 * t, -1.0],
    ]


def a_true(theta):
    """The same A(θ) written independently as arrays (for the truth)."""
    out = np.zeros((theta.size, 4, 4))
    out[:] = [[-1.0, 0, 0.5, 0], [0.3, -2.0, 0, 0.4], [0, 0, -1.5, 0.3], [0, 0.5, 0.2, -1.0]]
    out[:, 0, 1] += 0.5 * theta
    out[:, 1, 3] += 0.2 * theta
    out[:, 2, 0] += 0.2 * theta
    out[:, 3, 2] += 0.1 * theta
    return out


BOUNDS = Bounds(x0=X0_BOX, w=(-D, D))


def make_system(**over):
    args = dict(
        A=a_rows,
        B=lambda th: [[1.0], [0.0], [0.0], [0.5]],
        C=np.hstack([np.eye(2), np.zeros((2, 2))]),
        theta_box=([-1.0], [1.0]),
        B_un=lambda th: [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0], [0.0, 0.0]],
        dA=(-DA, DA),
    )
    args.update(over)
    return LPVSystem(**args)


@pytest.fixture(scope="module")
def system():
    return make_system()


@pytest.fixture(scope="module")
def observer(system):
    return LPVIntervalObserver.design(system, bounds=BOUNDS, h=H, theta_rate=RHO)


@pytest.fixture(scope="module")
def uio(system):
    return LPVIntervalUIO.design(
        system, bounds=BOUNDS, h=H, theta_rate=RHO, unknown_input=(-2 * np.ones(2), 2 * np.ones(2))
    )


def simulate(t, runs, seed, fault=None):
    """Fine RK4 (SUB steps per sample); ΔA at a random vertex of its box; d bang-bang and the slope of
    θ (|θ̇| = RHO) switching at random inside the sampling steps; u = sin t held per sample."""
    rng = np.random.default_rng(seed)
    hs = H / SUB
    x = np.tile(X0, (runs, 1))
    th = rng.uniform(-0.5, 0.5, runs)
    slope = RHO * rng.choice([-1.0, 1.0], runs)
    da = DA * rng.choice([-1.0, 1.0], size=(runs, 4, 4))
    d = D * rng.choice([-1.0, 1.0], size=(runs, 4))
    xs, ths = np.empty((runs, t.size, 4)), np.empty((runs, t.size, 1))

    def rate(x, th, u, d, tt):
        out = np.einsum("mij,mj->mi", a_true(th) + da, x) + B * u + d
        if fault is not None and tt >= FAULT_ONSET:
            out[:, :2] += fault
        return out

    for k, tk in enumerate(t):
        xs[:, k], ths[:, k, 0] = x, th
        u = np.sin(tk)
        for j in range(SUB):
            tt = tk + j * hs
            slope = np.where(rng.random(runs) < 0.2, -slope, slope)
            slope = np.where(np.abs(th) > 0.95, -np.sign(th) * RHO, slope)
            d = np.where(rng.random((runs, 4)) < 0.3, -d, d)

            def step_rate(s, z, slope=slope, u=u, d=d, tt=tt):  # z = (x, θ) with θ' = slope over the step
                return np.column_stack([rate(z[:, :4], z[:, 4], u, d, tt), slope])

            z = runge_kutta_step(step_rate, tt, np.column_stack([x, th]), hs)
            x, th = z[:, :4], np.clip(z[:, 4], -1.0, 1.0)
    return xs, ths, np.sin(t)[:, None]


def test_design_lmis_give_metzler_hurwitz_f_and_verified_certificates(system, observer, uio):
    obs, uio = observer.design_result, uio.design_result
    for des in (obs, uio):
        assert des.certificate.feasible and des.certificate.fine_margin < 0
        assert des.certificate.second_block_margin <= 0
        assert des.hurwitz_margin < 0
        theta = np.linspace(-1, 1, 7)[:, None]
        for f in des.f_matrices(des.R @ system.matrix_at("A", theta)):
            off = f[:, ~np.eye(4, dtype=bool)]
            assert off.min() >= 0
            assert np.max(np.linalg.eigvals(f).real) < 0
        # TC = I - R (36) and S from (37)-(42) reproduce RA - F = S1 C
        np.testing.assert_allclose(des.T @ system.C, np.eye(4) - des.R, atol=1e-12)
        s_lo, _ = des.s_matrices(system, theta)
        f_lo, _ = des.f_matrices(des.R @ system.matrix_at("A", theta))
        np.testing.assert_allclose(
            (s_lo - f_lo @ des.T) @ system.C, des.R @ system.matrix_at("A", theta) - f_lo, atol=1e-9
        )
    assert uio.certificate.subsets == 16  # all pairs (S1, S2) of the two measured columns (74)
    np.testing.assert_allclose(uio.H, np.vstack([np.eye(2), np.zeros((2, 2))]))
    f_lo, _ = uio.f_matrices(uio.R @ system.matrix_at("A", np.zeros((1, 1))))
    np.testing.assert_allclose(f_lo[0] @ uio.H, -uio.H, atol=1e-12)  # (103): F H = H Γ


def test_design_errors_name_the_failed_condition():
    bad_a12 = make_system(A=lambda th: [[-1.0, 0, -0.5, 0], [0, -2.0, 0, 0.4], [0, 0, -1.5, 0.3], [0, 0.5, 0.2, -1.0]])
    with pytest.raises(DesignError, match="push the measured ones up"):
        design_lpv_observer(bad_a12)
    bad_a22 = make_system(A=lambda th: [[-1.0, 0, 0.5, 0], [0, -2.0, 0, 0.4], [0, 0, -1.5, -0.3], [0, 0.5, 0.2, -1.0]])
    with pytest.raises(DesignError, match="must stay ordered"):
        design_lpv_observer(bad_a22)
    wide = make_system(dA=(-20 * DA, 20 * DA))
    with pytest.raises(DesignError, match="no gain keeps the widths bounded"):
        design_lpv_observer(wide)
    with pytest.raises(AssumptionError, match="measured states first"):
        design_lpv_observer(make_system(C=[[0, 0, 1.0, 0], [0, 0, 0, 1.0]], B_un=None))
    with pytest.raises(AssumptionError, match="exactly known terms"):
        LPVIntervalUIO.design(
            make_system(dA=(-np.ones((4, 4)) * 0.01, np.ones((4, 4)) * 0.01)),
            bounds=BOUNDS,
            h=H,
            theta_rate=RHO,
            unknown_input=(-np.ones(2), np.ones(2)),
        )


def test_rotate_bounds_contains_every_product():
    rng = np.random.default_rng(0)
    r = rng.standard_normal((4, 4))
    lo = rng.standard_normal((4, 3))
    hi = lo + rng.uniform(0, 1, (4, 3))
    blo, bhi = rotate_bounds(r, lo, hi)
    for _ in range(200):
        m = rng.uniform(lo, hi)
        assert np.all(r @ m >= blo - 1e-12) and np.all(r @ m <= bhi + 1e-12)


def test_observer_encloses_truth_with_unmeasured_states_and_disturbance(observer):
    t = np.arange(0.0, 10.0 + H / 2, H)
    x, th, u = simulate(t, runs=3, seed=1)
    obs = observer
    est = obs.run(t, x[..., :2], u, theta=th)
    rep = est.enclosure(x)
    assert rep.fraction == 1.0 and rep.max_violation == 0.0
    width = est.upper - est.lower
    late = width[:, t.size // 2 :]
    # bounded: the unmeasured widths settle well below the initial 0.6 (d alone, ±0.05, needs ≥ 0.05)
    assert late[..., 2:].max() < 0.3 and late[..., 2:].min() > 0.05
    state = obs.init()
    for k in range(4):
        state = obs.step(state, x[0, k, :2], u[k], theta=th[0, k])
        np.testing.assert_allclose(state.lower, est.lower[0, k], atol=1e-12)


def test_uio_isolates_a_fault_at_a_known_time(uio):
    t = np.arange(0.0, 9.0 + H / 2, H)
    x, th, u = simulate(t, runs=3, seed=2, fault=np.array([1.0, 0.0]))
    est, rec = isolate(uio, t, x[..., :2], u, theta=th)
    pre = t < FAULT_ONSET
    lo, hi = est.lower[:, pre], est.upper[:, pre]
    assert np.all(lo <= x[:, pre]) and np.all(hi >= x[:, pre])
    assert np.all(est.lower[..., 2:] <= x[..., 2:]) and np.all(est.upper[..., 2:] >= x[..., 2:])  # (27): H-free part
    flagged = (rec.signal_lower < 0) | (rec.signal_upper < 0)
    assert not flagged[:, pre].any()  # no false alarm before the fault
    assert not flagged[..., 1].any()  # never the wrong channel
    first = t[np.argmax(flagged[..., 0], axis=1)]
    assert flagged[..., 0].any(axis=1).all() and np.all((first >= FAULT_ONSET) & (first < FAULT_ONSET + 1.0))


def test_theta_is_required_and_checked(system, observer):
    obs = observer
    t = np.arange(0.0, 0.1, H)
    y = np.zeros((t.size, 2))
    with pytest.raises(DataError, match="theta"):
        obs.run(t, y, np.zeros((t.size, 1)))
    with pytest.raises(DataError, match="theta_box"):
        obs.run(t, y, np.zeros((t.size, 1)), theta=2 * np.ones((t.size, 1)))
    with pytest.raises(DataError, match="theta_rate"):
        LPVIntervalObserver.design(system, bounds=BOUNDS, h=H, theta_rate=-1.0)
    with pytest.raises(TypeError, match="unexpected keyword"):
        LPVIntervalObserver.design(system, bounds=BOUNDS, h=H, theta_rate=RHO, gird=3)
