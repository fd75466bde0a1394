"""Estimation: wheel odometry, UMBmark calibration, gyro fusion and the EKF."""

from abcwc.estimation.ekf import (
    ChairEkf,
    EkfNoise,
    FastEkf,
    FilterpyEkf,
    absolute_fixes,
    gyro_bias_prior,
    kalman_update,
    nees,
    nees_band,
    noise_from_models,
    run_ekf,
)
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
    SquareDriver,
    SquareRun,
    UmbmarkResult,
    alpha_beta,
    calibrate_distance_scale,
    centres_of_gravity,
    curve_radius,
    drive_square,
    e_max_syst,
    load_thesis_trials,
    model_return_error,
    run_square,
    run_umbmark,
    trial_covariance,
    umbmark_corrections,
    wheel_base_ratio,
    wheel_correction_factors,
    wheel_diameter_ratio,
)
from abcwc.geometry import wrap_tick_delta

__all__ = [
    "ChairEkf", "EkfNoise", "FastEkf", "FilterpyEkf", "GyroOdometry", "Odometry",
    "SquareDriver", "SquareRun", "UmbmarkResult", "absolute_fixes", "alpha_beta",
    "calibrate_distance_scale", "centres_of_gravity", "curve_radius",
    "drive_square", "e_max_syst", "encoder_ticks_to_wheel_distance", "estimate_gyro_bias",
    "gyro_bias_prior", "kalman_update",
    "gyro_odometry_from_log", "gyro_odometry_step", "allan_deviation",
    "integrate_gyro_heading", "integrate_odometry",
    "load_thesis_trials", "model_return_error", "nees", "nees_band", "noise_from_models",
    "odometry_from_log", "odometry_step", "run_ekf", "run_umbmark", "trial_covariance",
    "run_square", "umbmark_corrections", "validate_log", "wheel_base_ratio", "wheel_travel",
    "wheel_correction_factors", "wheel_diameter_ratio", "wrap_tick_delta",
]
