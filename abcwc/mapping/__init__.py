"""Mapping: occupancy grids, map files, scan matching and pose graphs (thesis 3.3.3, 4.3.7-4.3.8).

Like the estimators, mapping depends only on messages, geometry, logs and parameters: it
turns scans and poses into maps and trajectories, and never drives a chair. Import from
the submodules:

* :mod:`~abcwc.mapping.raytrace` and :mod:`~abcwc.mapping.grid`: every cell each beam
  crosses (Amanatides and Woo, vectorised) and the log-odds occupancy grid (Thrun,
  Burgard and Fox 2005, ch. 9);
* :mod:`~abcwc.mapping.map_io`: map_server YAML + PGM; :mod:`~abcwc.mapping.truth`:
  a world's walls as cells, and a map's precision and recall against them;
* :mod:`~abcwc.mapping.carmen` and :mod:`~abcwc.mapping.relations`: real robot logs and
  the relation metric of Kuemmerle et al. (2009); :mod:`~abcwc.mapping.slam_data`: the
  benchmark data in ``data/slam`` and its reference figures;
* :mod:`~abcwc.mapping.icp` and :mod:`~abcwc.mapping.correlative`: point-to-line ICP
  (Censi 2008) and correlative scan matching (Olson 2009);
* :mod:`~abcwc.mapping.g2o`, :mod:`~abcwc.mapping.posegraph` and
  :mod:`~abcwc.mapping.grid_graph`: pose-graph files, the sparse Levenberg-Marquardt
  over SE(2), and simulated graphs with known truth;
* :mod:`~abcwc.mapping.slam`: graph SLAM over a laser log (keyframes, scan-matched
  edges, verified loop closures, the solve, the map).
"""
