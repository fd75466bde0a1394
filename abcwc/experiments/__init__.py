"""Seeded studies that drive a chair: UMBmark trials and the EKF's NEES Monte Carlo.

They sit above the bodies and the behaviours (they drive the simulator), so the
estimators they measure depend on nothing up here.
"""
