"""Distributions on intervals and the ξ ↔ κ maps, against closed forms."""
import math

import numpy as np
import pytest
from numpy.polynomial.hermite_e import hermegauss
from numpy.polynomial.legendre import leggauss
from scipy import special

from uqflight import parameters
from uqflight.parameters import DISTRIBUTIONS, Parameter, make_parameter

SMOOTH = [name for name, law in DISTRIBUTIONS.items() if law.polynomial]  # a seed's law: test_registries, test_seeds

# The paper's Table 1 intervals; the nominals are illustrative (Cm0 and Cmq negative, as in the model).
TABLE_1 = {
    "CL0": (0.25, 23.05),
    "CLalpha": (5.2, 5.27),
    "CD0": (0.027, 12.4),
    "k1": (0.02, 89.16),
    "k2": (0.045, 379.74),
    "Cm0": (-0.06, 10.46),
    "Cmq": (-14.0, 0.53),
}
P_THREE_SIGMA = special.ndtr(3.0) - special.ndtr(-3.0)  # 0.9973


def table_1(distribution="normal"):
    return [
        make_parameter(name, f"aero/uq/{name}", distribution, nominal, interval_pct=pct)
        for name, (nominal, pct) in TABLE_1.items()
    ]


def expectation(parameter, function):
    """E[function(κ)] by a 100-point Gauss rule in ξ: exact to rounding for these smooth maps."""
    if parameter.germ == "normal":
        nodes, weights = hermegauss(100)
        weights = weights / math.sqrt(2 * math.pi)
    else:
        nodes, weights = leggauss(100)
        weights = weights / 2
    return float(weights @ function(parameter.to_physical(nodes)))


def example(distribution, lower=-2.0, upper=5.0):
    return Parameter("p", "aero/uq/p", distribution, 0.5 * (lower + upper), lower, upper)


@pytest.mark.parametrize("name", TABLE_1)
def test_normal_table_1_interval_is_three_sigma_about_the_nominal(name):
    nominal, pct = TABLE_1[name]
    p = make_parameter(name, f"aero/uq/{name}", "normal", nominal, interval_pct=pct)
    half_width = abs(nominal) * pct / 100
    assert p.lower < p.upper  # also for the negative nominals
    assert p.mean == pytest.approx(nominal, rel=1e-14)
    assert p.std == pytest.approx(half_width / 3, rel=1e-14)
    xi_bounds = p.to_standard(np.array([p.lower, p.upper]))
    assert xi_bounds == pytest.approx([-3.0, 3.0], rel=1e-12)
    assert np.diff(special.ndtr(xi_bounds))[0] == pytest.approx(0.9973, abs=5e-5)  # P(κ in interval)


def test_normal_map_is_affine():
    p = example("normal")
    xi = np.array([-1.0, 0.0, 2.0])
    assert p.to_physical(xi) == pytest.approx(1.5 + 7 / 6 * xi, rel=1e-14)


def test_uniform_maps_the_germ_interval_onto_the_parameter_interval():
    p = example("uniform")
    assert p.germ == "uniform"
    assert p.to_physical(np.array([-1.0, 0.0, 1.0])) == pytest.approx([-2.0, 1.5, 5.0], rel=1e-14)
    assert p.std == pytest.approx(3.5 / math.sqrt(3), rel=1e-14)


def test_truncated_normal_follows_its_cdf_and_stays_in_the_interval():
    p = example("truncated_normal")
    xi = np.linspace(-6, 6, 41)
    kappa = p.to_physical(xi)
    assert np.all((kappa >= p.lower) & (kappa <= p.upper))
    # Closed-form CDF of N(μ, σ) truncated at ±3σ, independent of scipy.stats.truncnorm.
    mu, sigma = 1.5, 7 / 6
    cdf = (special.ndtr((kappa - mu) / sigma) - special.ndtr(-3)) / P_THREE_SIGMA
    assert cdf == pytest.approx(special.ndtr(xi), abs=1e-12)


def test_truncated_normal_std_matches_closed_form():
    p = example("truncated_normal")
    sigma = 7 / 6
    variance = sigma**2 * (1 - 2 * 3 * math.exp(-4.5) / math.sqrt(2 * math.pi) / P_THREE_SIGMA)
    assert p.std == pytest.approx(math.sqrt(variance), rel=1e-12)


@pytest.mark.parametrize("lower, upper", [(0.5, 8.0), (-8.0, -0.5)])
def test_lognormal_interval_is_three_log_sigma_and_map_increases(lower, upper):
    p = example("lognormal", lower, upper)
    assert p.to_physical(np.array([-3.0, 3.0])) == pytest.approx([lower, upper], rel=1e-12)
    median = math.copysign(math.sqrt(lower * upper), lower)
    assert p.to_physical(np.array([0.0]))[0] == pytest.approx(median, rel=1e-12)
    kappa = p.to_physical(np.linspace(-5, 5, 21))
    assert np.all(np.diff(kappa) > 0)
    assert np.all(np.sign(kappa) == np.sign(lower))
    # The ±3σ log interval holds Φ(3) − Φ(−3) of the mass.
    inside = special.ndtr(p.to_standard(upper)) - special.ndtr(p.to_standard(lower))
    assert inside == pytest.approx(P_THREE_SIGMA, rel=1e-12)


@pytest.mark.parametrize("distribution", SMOOTH)
@pytest.mark.parametrize("lower, upper", [(0.5, 8.0), (-8.0, -0.5)])
def test_mean_and_std_match_quadrature_of_the_map(distribution, lower, upper):
    p = example(distribution, lower, upper)
    mean = expectation(p, lambda k: k)
    # 1e-10: a 100-point Gauss rule on these smooth maps is exact to rounding.
    assert p.mean == pytest.approx(mean, rel=1e-10)
    assert p.std == pytest.approx(math.sqrt(expectation(p, lambda k: (k - mean) ** 2)), rel=1e-10)


@pytest.mark.parametrize("distribution", SMOOTH)
def test_to_standard_inverts_to_physical(distribution):
    p = example(distribution, 0.5, 8.0)
    xi = np.linspace(-1, 1, 21) if p.germ == "uniform" else np.linspace(-4.5, 4.5, 37)
    # 1e-8: the truncated normal's tails pass through Φ and its inverse near 0.
    assert p.to_standard(p.to_physical(xi)) == pytest.approx(xi, abs=1e-8)


def test_vectorised_maps_over_the_table_1_campaign():
    params = table_1()
    xi = np.random.default_rng(0).standard_normal((50, 7))
    kappa = parameters.to_physical(params, xi)
    assert kappa.shape == (50, 7)
    assert kappa[:, 5] == pytest.approx(params[5].to_physical(xi[:, 5]))
    assert parameters.to_standard(params, kappa) == pytest.approx(xi, abs=1e-12)
    with pytest.raises(ValueError, match=r"xi: expected shape \(N, 7\), got \(50, 6\)"):
        parameters.to_physical(params, xi[:, :6])


def test_germs_follow_distributions():
    params = [example(d, 0.5, 8.0) for d in SMOOTH]
    assert parameters.germs_of(params) == ["normal", "uniform", "normal", "normal"]


def test_absolute_bounds_form():
    p = make_parameter("Cmq", "aero/uq/Cmq", "uniform", -14.0, lower=-15.0, upper=-13.5)
    assert (p.lower, p.upper, p.nominal) == (-15.0, -13.5, -14.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(interval_pct=10, lower=0.0, upper=1.0), "not both"),
        (dict(), "got neither"),
        (dict(lower=0.0), "lower and upper must be given together"),
        (dict(interval_pct=-5), "interval_pct must be > 0, got -5"),
        (dict(interval_pct=0), "interval_pct must be > 0, got 0"),
        (dict(interval_pct="10%"), "interval_pct must be a number"),
        (dict(lower=1.0, upper=1.0), r"lower \(1.0\) must be below upper \(1.0\)"),
        (dict(lower=2.0, upper=1.0), "must be below upper"),
    ],
)
def test_make_parameter_rejects_bad_intervals(kwargs, message):
    with pytest.raises(ValueError, match=message):
        make_parameter("CL0", "aero/uq/CL0", "normal", 0.5, **kwargs)


def test_lognormal_needs_a_one_signed_interval():
    # k2's ±379.74 % reaches below zero.
    with pytest.raises(ValueError, match="'k2': a lognormal interval must lie entirely above or"):
        make_parameter("k2", "aero/uq/k2", "lognormal", 0.045, interval_pct=379.74)


def test_unknown_distribution_and_zero_nominal_percentage():
    with pytest.raises(ValueError, match="unknown distribution 'gamma'; expected one of normal"):
        make_parameter("CL0", "aero/uq/CL0", "gamma", 0.25, interval_pct=10)
    with pytest.raises(ValueError, match="percentage of the nominal, which is 0"):
        make_parameter("CL0", "aero/uq/CL0", "normal", 0.0, interval_pct=10)
