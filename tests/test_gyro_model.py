"""The simulated gyro against its model: datasheet conversion, white noise, bias walk."""

import math

import numpy as np
import pytest

from abcwc.estimation.gyro import allan_deviation
from abcwc.params import default_params, gyro_from_datasheet, load_params
from abcwc.sim.sensors import Gyro

PERIOD = 0.02  # s, the control period the simulator samples the gyro at


def test_the_datasheet_figures_convert_by_hand():
    """0.01 deg/s/sqrt(Hz) at 50 Hz -> 0.0707 deg/s per sample; 4.6 deg/h over 500 s ->
    4.6 / 3600 / sqrt(500) deg/s/sqrt(s)."""
    noise_std, walk = gyro_from_datasheet(0.01, 4.6, 500.0, 50.0)
    assert math.degrees(noise_std) == pytest.approx(0.01 * math.sqrt(50.0), rel=1e-12)
    assert math.degrees(walk) == pytest.approx(4.6 / 3600.0 / math.sqrt(500.0), rel=1e-12)
    with pytest.raises(ValueError, match="noise density"):
        gyro_from_datasheet(-0.01, 4.6, 500.0, 50.0)


def test_the_variants_and_a_bad_name():
    datasheet, pessimistic = default_params().gyro, load_params(gyro="pessimistic").gyro
    assert datasheet.variant == "datasheet" and pessimistic.variant == "pessimistic"
    assert pessimistic.bias_walk_std == pytest.approx(100 * datasheet.bias_walk_std, rel=0.01)
    assert pessimistic.bias_std == datasheet.bias_std  # only the noise and the walk differ
    with pytest.raises(ValueError, match="allowed: datasheet, pessimistic"):
        load_params(gyro="perfect")


def still_recording(params, seconds, seed):
    """``(rates, final bias)``: a gyro standing still for ``seconds``, and its bias then."""
    gyro = Gyro(params, PERIOD, np.random.default_rng(seed))
    start = gyro.bias
    rates = np.array([gyro.read(0.0) for _ in range(round(seconds / PERIOD))])
    return rates, gyro.bias - start


@pytest.mark.parametrize("variant", ["datasheet", "pessimistic"])
def test_white_noise_has_the_configured_std(variant):
    """Half the variance of successive differences is sigma^2 (+ walk^2 dt / 2): within
    5 % for 60,000 samples, where the estimate's own spread is 0.6 %."""
    params = load_params(gyro=variant).gyro
    rates, _ = still_recording(params, 1200.0, seed=1)
    half_diff_var = np.var(np.diff(rates)) / 2
    expected = params.noise_std**2 + params.bias_walk_std**2 * PERIOD / 2
    assert half_diff_var == pytest.approx(expected, rel=0.05)


def test_the_allan_deviation_reads_the_datasheet_density():
    """At tau = 1 s white noise dominates: adev = N (rad/s/sqrt(Hz) as rad/s at 1 s)."""
    params = default_params().gyro
    rates, _ = still_recording(params, 1200.0, seed=2)
    taus, adev = allan_deviation(rates, PERIOD, cluster_sizes=np.array([50]))
    assert taus[0] == pytest.approx(1.0)
    assert adev[0] == pytest.approx(math.radians(0.01), rel=0.05)


@pytest.mark.parametrize("variant", ["datasheet", "pessimistic"])
def test_the_bias_wanders_as_a_random_walk(variant):
    """Over 200 seeds the bias change after T s has variance walk^2 T (chi-square with
    200 degrees of freedom: 0.70..1.36 of it at 99.9 %)."""
    params = load_params(gyro=variant).gyro
    seconds = 40.0
    changes = np.array([still_recording(params, seconds, seed)[1] for seed in range(200)])
    ratio = np.mean(changes**2) / (params.bias_walk_std**2 * seconds)
    assert 0.70 < ratio < 1.36
