"""Estimation: wheel odometry, UMBmark calibration, gyro fusion and the EKF."""

from abcwc.estimation.ekf import (
    ChairEkf,
    EkfNoise,
    FastEkf,
    FilterpyEkf,
    absolute_fixes,
    nees,
    nees_band,
    noise_from_models,
    run_ekf,
)
from abcwc.estimation.gyro import (
    GyroOdometry,
    estimate_gyro_bias,
    gyro_odometry_from_log,
    integrate_gyro_heading,
)
from abcwc.estimation.odometry import (
    Odometry,
    encoder_ticks_to_wheel_distance,
    integrate_odometry,
    odometry_from_log,
    validate_log,
    wrap_tick_delta,
)
from abcwc.estimation.umbmark import (
    SquareDriver,
    UmbmarkResult,
    calibrate_distance_scale,
    drive_square,
    e_max_syst,
    load_thesis_trials,
    model_return_error,
    run_umbmark,
    trial_covariance,
    umbmark_corrections,
)

__all__ = [
    "ChairEkf", "EkfNoise", "FastEkf", "FilterpyEkf", "GyroOdometry", "Odometry",
    "SquareDriver", "UmbmarkResult", "absolute_fixes", "calibrate_distance_scale",
    "drive_square", "e_max_syst", "encoder_ticks_to_wheel_distance", "estimate_gyro_bias",
    "gyro_odometry_from_log", "integrate_gyro_heading", "integrate_odometry",
    "load_thesis_trials", "model_return_error", "nees", "nees_band", "noise_from_models",
    "odometry_from_log", "run_ekf", "run_umbmark", "trial_covariance",
    "umbmark_corrections", "validate_log", "wrap_tick_delta",
]
