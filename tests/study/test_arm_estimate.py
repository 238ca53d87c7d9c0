"""The operator's estimate of the arm: a Kalman filter held to closed forms and to its model.

- With white noise and the keys' authority known, the filter is the alpha-beta filter, whose
  steady-state gains have a closed form (Kalata 1984, the tracking index): its gains must
  converge to it.
- Under a blend it can identify (the keys switched on and off), it must find the blend's
  authority and drift.
- Its compiled propagation and update are the textbook formulas, bit for bit, written here
  in plain Python loops in the same order.
"""

import numpy as np
import pytest

from casa_core.study import arm_estimate
from casa_core.study.arm_estimate import REFERENCE_NOISE, ArmEstimate

TICK = 0.05


def kalata_gains(noise: float, period: float, tick: float) -> tuple[float, float]:
    """alpha and beta of the steady-state alpha-beta filter (Kalata 1984, eqs. for the
    discrete white-acceleration model): tracking index lambda = sigma_w tick^2 / sigma."""
    index = (REFERENCE_NOISE / period**2) * tick**2 / noise
    r = (4 + index - np.sqrt(8 * index + index**2)) / 4
    alpha = 1 - r**2
    return alpha, 2 * (2 - alpha) - 4 * np.sqrt(1 - alpha)


@pytest.mark.parametrize("noise", [0.003, 0.01, 0.02])
def test_with_white_noise_and_a_known_authority_it_is_the_alpha_beta_filter(noise):
    estimate = ArmEstimate(
        np.full(3, noise),
        noise_decay=0.0,
        period=1.0,
        key_speed=np.full(4, 0.05),
        authority_spread=0.0,
        authority_change=0.0,
    )
    for _ in range(3000):
        estimate.update(np.zeros(4), np.zeros(4), TICK)
    before_position, before_drift = estimate.position, estimate.drift
    kick = np.array([0.001, 0.0, 0.0, 0.0])
    estimate.update(kick, np.zeros(4), TICK)
    alpha, beta = kalata_gains(noise, 1.0, TICK)
    # The position moves by alpha of the surprise, the drift by beta / tick of it; within
    # 1e-4, the share of the filter's residual white noise (1e-5 m) in the variance.
    assert (estimate.position - before_position)[0] / 0.001 == pytest.approx(alpha, rel=1e-4)
    assert (estimate.drift - before_drift)[0] / 0.001 == pytest.approx(beta / TICK, rel=1e-4)


def test_under_a_blend_it_finds_the_authority_and_the_drift():
    # The arm makes 30% of the keys' motion and drifts at (2, -1, 0) cm/s; the keys go on
    # and off every half second on x and y; perception noise 1 mm, AR(1) over 0.5 s. After
    # 30 s the estimate holds the authority within 0.1 and the drift within 5 mm/s. (With
    # 1 cm of noise, the population's median, a half second of keys at 30% moves the arm
    # less than the noise, and the authority stays uncertain: measured 0.73.)
    rng = np.random.default_rng(7)
    decay = np.exp(-TICK / 0.5)
    sigma = np.array([0.001, 0.001, 0.001])
    estimate = ArmEstimate(sigma, noise_decay=decay, period=1.0, key_speed=np.full(4, 0.05))
    truth, noise = np.zeros(4), np.zeros(3)
    drift = np.array([0.02, -0.01, 0.0, 0.0])
    for step in range(600):
        on = (step // 10) % 2
        moved = np.array([0.05 * on, 0.05 * (1 - on), 0.0, 0.0]) * TICK
        truth = truth + 0.3 * moved + drift * TICK
        noise = decay * noise + rng.standard_normal(3) * sigma * np.sqrt(1 - decay**2)
        estimate.update(truth + np.append(noise, 0.0), moved, TICK)
    assert estimate.authority == pytest.approx(0.3, abs=0.1)
    assert np.abs(estimate.drift - drift).max() < 0.005, estimate.drift


def _plain_propagate(state, covariance, transition, change):
    n = len(state)
    new_state = [sum_in_order(transition[i, k] * state[k] for k in range(n)) for i in range(n)]
    left = [
        [sum_in_order(transition[i, k] * covariance[k, j] for k in range(n)) for j in range(n)]
        for i in range(n)
    ]
    new = [
        [
            sum_in_order(left[i][k] * transition[j, k] for k in range(n)) + change[i, j]
            for j in range(n)
        ]
        for i in range(n)
    ]
    return np.array(new_state), np.array(new)


def sum_in_order(terms) -> float:
    total = 0.0
    for term in terms:
        total += term
    return total


def test_the_compiled_propagation_and_update_are_the_formulas_bit_for_bit():
    rng = np.random.default_rng(3)
    n = 12
    for _ in range(20):
        state = rng.normal(size=n)
        root = rng.normal(size=(n, n))
        covariance = root @ root.T
        transition = np.eye(n) + 0.1 * rng.normal(size=(n, n))
        change = np.diag(rng.uniform(0, 0.1, size=n))
        expected_state, expected = _plain_propagate(state, covariance, transition, change)
        arm_estimate._propagate(state, covariance, transition, change)
        assert np.array_equal(state, expected_state)
        assert np.array_equal(covariance, expected)
        # The update: per axis, seen = position + noise (x, y, z) or position (rot).
        seen, residual = rng.normal(size=4), 1e-6
        plain_state, plain = state.copy(), covariance.copy()
        for axis in range(4):
            row = plain[axis] + (plain[9 + axis] if axis < 3 else 0.0)
            total = plain[axis, axis] + residual
            if axis < 3:
                total += 2 * plain[axis, 9 + axis] + plain[9 + axis, 9 + axis]
            gain = row / total
            predicted = plain_state[axis] + (plain_state[9 + axis] if axis < 3 else 0.0)
            plain_state = plain_state + gain * (seen[axis] - predicted)
            plain = plain - np.outer(gain, row)
        arm_estimate._observe(state, covariance, seen, residual)
        assert np.array_equal(state, plain_state)
        assert np.array_equal(covariance, plain)
