"""The paper's equations: closed forms, properties and guards.

Expected numbers are worked by hand from the equations cited in each test
(paper Sec. II; docs/paper-to-code.md), or come from an independent numerical
optimizer (scipy) rather than from the code under test.
"""

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from casa_core.model import _cores as cores
from casa_core.model._checks import require_positive
from casa_core.model.arbitration import alpha_belief, alpha_confidence, alpha_distance, blend
from casa_core.model.confidence import beta_hat, suboptimality
from casa_core.model.inference import log_likelihood, posterior


def test_suboptimality_is_prefix_plus_to_go_minus_optimal():
    # 3 + 2 - 4 = 1 (definition, denominator of eq. beta_mle)
    assert suboptimality(3.0, 2.0, 4.0) == 1.0
    np.testing.assert_array_equal(suboptimality([3.0, 1.0], [2.0, 2.0], [4.0, 4.0]), [1.0, 0.0])


def test_suboptimality_clamps_negative_values_at_zero():
    # a planner whose start cost overshoots the optimum must not give negative suboptimality
    assert suboptimality(1.0, 1.0, 2.5) == 0.0


@pytest.mark.parametrize(
    ("subopt", "t", "k", "lam", "expected"),
    [
        (3.0, 4, 7, 4.0, 2.0),  # 4*7 / (2*(4+3)) = 28/14
        (1.0, 2, 7, 0.0, 7.0),  # MLE: 2*7 / (2*1)
        (0.5, 10, 7, 4.0, 70 / 9),  # 70 / (2*4.5)
    ],
)
def test_beta_hat_closed_form(subopt, t, k, lam, expected):
    assert beta_hat(subopt, t, k, lam) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("lam", [0.0, 4.0])
@pytest.mark.parametrize("subopt", [0.3, 2.0, 25.0])
def test_beta_hat_maximizes_the_laplace_posterior(subopt, lam):
    # eq. beta_mle / beta_map: beta_hat is the argmax over beta of
    # log P(xi | theta, beta) + log Exp(beta; lam) = loglik - lam * beta (+ const).
    # Found here independently by scipy's bounded scalar optimizer.
    t, k = 6, 7
    result = minimize_scalar(
        lambda b: -(log_likelihood(subopt, b, t, k) - lam * b),
        bounds=(1e-6, 1e3),
        method="bounded",
        options={"xatol": 1e-9},
    )
    assert beta_hat(subopt, t, k, lam) == pytest.approx(result.x, rel=1e-5)


def test_beta_hat_is_zero_without_evidence_and_inf_only_for_zero_denominator():
    assert beta_hat(5.0, 0, 7, 4.0) == 0.0
    assert beta_hat(0.0, 0, 7, 0.0) == 0.0  # t = 0 wins: no evidence at all
    assert beta_hat(0.0, 3, 7, 0.0) == np.inf
    assert np.isfinite(beta_hat(0.0, 3, 7, 4.0))


def test_beta_hat_falls_as_suboptimality_rises():
    subopts = np.linspace(0.0, 100.0, 501)
    betas = beta_hat(subopts, t=8, k=7, lam=4.0)
    assert (np.diff(betas) < 0).all()
    assert (betas >= 0).all() and not np.isnan(betas).any()


def test_beta_hat_grows_with_evidence_at_fixed_suboptimality():
    betas = beta_hat(2.0, t=np.arange(0, 30), k=7, lam=4.0)
    assert (np.diff(betas) > 0).all()


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"subopt": -0.1, "t": 2, "k": 7}, "subopt must be >= 0"),
        ({"subopt": np.nan, "t": 2, "k": 7}, "subopt contains NaN"),
        ({"subopt": 1.0, "t": np.nan, "k": 7}, "t contains NaN"),
        ({"subopt": 1.0, "t": -1, "k": 7}, "t must be >= 0"),
        ({"subopt": 1.0, "t": 2, "k": 0}, "k must be a positive number, got 0"),
        ({"subopt": 1.0, "t": 2, "k": 7, "lam": -4.0}, "lam must be >= 0"),
    ],
)
def test_beta_hat_rejects_bad_input_with_a_clear_error(kwargs, message):
    with pytest.raises(ValueError, match=message):
        beta_hat(**kwargs)


def test_suboptimality_rejects_nan():
    with pytest.raises(ValueError, match="prefix_cost contains NaN"):
        suboptimality(np.nan, 1.0, 1.0)


def test_log_likelihood_closed_form():
    # -beta S + (t k / 2) log(beta / 2 pi) with S = 2, beta = 3, t = 4, k = 7
    expected = -3 * 2 + (4 * 7 / 2) * np.log(3 / (2 * np.pi))
    assert log_likelihood(2.0, 3.0, 4, 7) == pytest.approx(expected, rel=1e-12)


def test_log_likelihood_edge_cases():
    assert log_likelihood(5.0, 0.0, 0, 7) == 0.0  # no evidence: no information
    assert log_likelihood(0.0, np.inf, 3, 7) == np.inf  # a perfect prefix, infinite confidence
    assert log_likelihood(1.0, np.inf, 3, 7) == -np.inf
    assert log_likelihood(1.0, 0.0, 3, 7) == -np.inf


def test_posterior_known_values():
    # exp(0) : exp(log 3) = 1 : 3
    np.testing.assert_allclose(posterior([0.0, np.log(3.0)]), [0.25, 0.75], rtol=1e-12)
    np.testing.assert_allclose(posterior([1.0, 1.0, 1.0, 1.0]), [0.25] * 4)


def test_posterior_is_stable_for_very_negative_log_likelihoods():
    # naive exp() underflows to 0/0 here; the ratio 1 : 2 must survive
    probabilities = posterior([-10_000.0, -10_000.0 + np.log(2.0)])
    np.testing.assert_allclose(probabilities, [1 / 3, 2 / 3], rtol=1e-12)


def test_posterior_sums_to_one_and_matches_brute_force():
    rng = np.random.default_rng(0)
    logs = rng.normal(scale=5.0, size=(50, 4))
    probabilities = posterior(logs)
    np.testing.assert_allclose(probabilities.sum(axis=-1), 1.0, rtol=1e-12)
    brute = np.exp(logs) / np.exp(logs).sum(axis=-1, keepdims=True)
    np.testing.assert_allclose(probabilities, brute, rtol=1e-10)


def test_posterior_infinite_cases():
    np.testing.assert_array_equal(posterior([np.inf, 0.0, np.inf]), [0.5, 0.0, 0.5])
    np.testing.assert_array_equal(posterior([-np.inf, -np.inf]), [0.5, 0.5])
    with pytest.raises(ValueError, match="NaN"):
        posterior([0.0, np.nan])


def test_posterior_rows_are_independent():
    # A row with an intent at +inf must not change the other rows of a batch:
    # each row is the posterior of its own prefix (brute force for the finite one).
    batch = posterior([[np.inf, 0.0], [0.0, np.log(3.0)], [-np.inf, -np.inf]])
    np.testing.assert_array_equal(batch[0], [1.0, 0.0])
    np.testing.assert_allclose(batch[1], [0.25, 0.75], rtol=1e-12)
    np.testing.assert_array_equal(batch[2], [0.5, 0.5])


def test_alpha_confidence():
    np.testing.assert_array_equal(
        alpha_confidence([0.0, 0.5, 1.0, 4.0, np.inf]), [1, 1, 1, 0.25, 0]
    )


def test_alpha_distance():
    np.testing.assert_allclose(alpha_distance([0.0, 0.275, 0.55, 2.0], 0.55), [0, 0.5, 1, 1])
    with pytest.raises(ValueError, match="D must be a positive number"):
        alpha_distance(0.1, 0.0)


def test_alpha_belief_is_one_for_uniform_and_zero_for_certain_belief():
    # docs/departures.md: alpha = 1 - (P |Theta| - 1) / (|Theta| - 1), clipped
    assert alpha_belief(1 / 3, 3) == pytest.approx(1.0)
    assert alpha_belief(1.0, 3) == 0.0
    assert alpha_belief(2 / 3, 3) == pytest.approx(0.5)  # 1 - (2 - 1) / 2
    assert alpha_belief(0.1, 3) == 1.0  # below uniform: clipped


def test_alpha_belief_with_one_intent_leaves_the_user_in_control():
    # One intent: P* = 1 = 1/|Theta| is the uniform belief, which gives alpha = 1 (as in
    # the test above); the formula itself is 0/0. Documented in alpha_belief's docstring.
    assert alpha_belief(1.0, 1) == 1.0
    np.testing.assert_array_equal(alpha_belief([1.0, 1.0], 1), [1.0, 1.0])
    for bad in (0, -1, 2.5, np.nan, None, "3", True):
        with pytest.raises(ValueError, match="needs an integer >= 1 intents"):
            alpha_belief(1.0, bad)


def test_beta_hat_of_negative_zero_is_plus_infinity():
    # eq. beta_map with lam = 0 and subopt = 0, t > 0: t k / (2 * 0) = +inf; -0.0 is 0.
    assert beta_hat(-0.0, 1, 7, lam=-0.0) == np.inf
    assert beta_hat(0.0, 1, 7, lam=-0.0) == np.inf
    np.testing.assert_array_equal(beta_hat([-0.0, 0.0, 1.0], 1, 7, lam=-0.0), [np.inf, np.inf, 3.5])
    assert beta_hat(-0.0, 0, 7, lam=-0.0) == 0.0  # t = 0: no evidence yet


@pytest.mark.parametrize("arbitration", [alpha_confidence, lambda x: alpha_distance(x, 0.55)])
def test_alphas_stay_in_unit_interval(arbitration):
    values = np.concatenate([np.linspace(0, 50, 1001), [np.inf]])
    alphas = arbitration(values)
    assert ((alphas >= 0) & (alphas <= 1)).all()


def test_blend():
    user, robot = np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0, 0.5])
    np.testing.assert_allclose(blend(1.0, user, robot), user)
    np.testing.assert_allclose(blend(0.0, user, robot), robot)
    np.testing.assert_allclose(blend(0.25, user, robot), [0.25, 0.75, 0.0, 0.375])
    with pytest.raises(ValueError, match="alpha"):
        blend(1.5, user, robot)


def test_scalar_arbitration_cores_match_the_public_functions():
    # the assistant's unchecked per-step path (Python floats in) gives the same alphas, exactly
    for beta in (0.0, 0.3, 0.9999999999999999, 1.0, 1.0000000000000002, 2.5, np.inf):
        assert cores.alpha_confidence(beta) == alpha_confidence(beta)
    for d in (0.0, 0.2, 0.55, 3.0):
        assert cores.alpha_distance(d, 0.55) == alpha_distance(d, 0.55)
    for p in (0.0, 0.25, 1 / 3, 0.8, 1.0):
        assert cores.alpha_belief(p, 3) == alpha_belief(p, 3)
    # One intent: the rule lives in the core, so the assistant's path keeps it too.
    assert cores.alpha_belief(1.0, 1) == alpha_belief(1.0, 1) == 1.0


def test_suboptimality_core_is_the_public_formula():
    prefix, to_go, optimal = np.array([3.0, 1.0, 0.1]), np.array([2.0, 2.0, 0.2]), 4.0
    np.testing.assert_array_equal(
        cores.suboptimality(prefix, to_go, optimal), suboptimality(prefix, to_go, optimal)
    )


@pytest.mark.parametrize(
    ("owner", "values", "message"),
    [
        (None, {"k": 0}, "k must be a positive number, got 0"),
        (None, {"D": np.inf}, "D must be a positive number, got inf"),
        ("intent 'green'", {"speed": 0.05, "dt": -0.5}, "dt of intent 'green' must be a positive"),
        ("Assistant", {"tick": np.nan}, "tick of Assistant must be a positive number, got nan"),
        ("Assistant", {"horizon": None}, "horizon of Assistant must be a positive number"),
        ("Assistant", {"horizon": "15"}, "horizon of Assistant must be a positive number"),
    ],
)
def test_require_positive_names_the_parameter_and_its_owner(owner, values, message):
    with pytest.raises(ValueError, match=message):
        require_positive(owner, **values)


def test_require_positive_accepts_positive_numbers():
    require_positive("intent 'green'", speed=0.05, dt=0.5, scale=227, k=np.int64(7))
