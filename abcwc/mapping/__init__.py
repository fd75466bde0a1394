"""Mapping: occupancy grids, map files, scan matching and graph SLAM (thesis 3.3.3, 4.3.7-4.3.8).

Like the estimators, mapping depends only on messages, geometry and parameters: it turns
scans and poses into maps and trajectories, and never drives a chair. Import from the
submodules.
"""
