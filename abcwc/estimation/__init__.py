"""Estimation: wheel odometry, UMBmark calibration, gyro fusion and the EKF.

Estimators depend on nothing above them (no body, behaviour or experiment): they turn
frames and logs into estimates. Every estimator fed frame by frame has one shape,
:class:`PoseEstimator`: ``observe(frame)`` with every frame, then ``pose``. Driving the
UMBmark squares lives in :class:`abcwc.behaviours.SquareDriver` and
:mod:`abcwc.experiments.umbmark_trials`; the NEES Monte Carlo in
:mod:`abcwc.experiments.nees`."""

from abcwc.estimation.ekf import (
    ChairEkf,
    EkfEstimator,
    EkfNoise,
    FastEkf,
    FilterpyEkf,
    gyro_bias_prior,
    kalman_update,
    nees,
    nees_band,
    noise_from_models,
    run_ekf,
)
from abcwc.estimation.estimator import PoseEstimator
from abcwc.estimation.gyro import (
    GyroOdometry,
    allan_deviation,
    estimate_gyro_bias,
    gyro_odometry_from_log,
    gyro_odometry_step,
    integrate_gyro_heading,
)
from abcwc.estimation.odometry import (
    Odometry,
    encoder_ticks_to_wheel_distance,
    integrate_odometry,
    odometry_from_log,
    odometry_step,
    validate_log,
    wheel_travel,
)
from abcwc.estimation.umbmark import (
    UmbmarkResult,
    alpha_beta,
    cancelling_wheel_ratio,
    centres_of_gravity,
    curve_radius,
    e_max_syst,
    load_thesis_trials,
    model_return_error,
    trial_covariance,
    umbmark_corrections,
    wheel_base_ratio,
    wheel_correction_factors,
    wheel_diameter_ratio,
)
from abcwc.geometry import wrap_tick_delta

__all__ = [
    "ChairEkf", "EkfEstimator", "EkfNoise", "FastEkf", "FilterpyEkf", "GyroOdometry",
    "Odometry", "PoseEstimator",
    "UmbmarkResult", "alpha_beta",
    "centres_of_gravity", "curve_radius",
    "e_max_syst", "encoder_ticks_to_wheel_distance", "estimate_gyro_bias",
    "gyro_bias_prior", "kalman_update",
    "gyro_odometry_from_log", "gyro_odometry_step", "allan_deviation",
    "integrate_gyro_heading", "integrate_odometry",
    "load_thesis_trials", "model_return_error", "nees", "nees_band", "noise_from_models",
    "odometry_from_log", "odometry_step", "run_ekf", "trial_covariance",
    "cancelling_wheel_ratio", "umbmark_corrections", "validate_log", "wheel_base_ratio",
    "wheel_travel",
    "wheel_correction_factors", "wheel_diameter_ratio", "wrap_tick_delta",
]
