"""evpose: event-camera 6-DoF pose tracking against a prior 3D map, fused with an IMU.

Layers (each folder one layer, lower layers never import higher ones):

- ``evpose.core``      data types and pure maths (events, IMU, trajectories, cameras, recordings)
- ``evpose.io``        reading and writing recordings, trajectories and maps
- ``evpose.sim``       the event-camera simulator
- ``evpose.mapping``   contour maps from raw point clouds
- ``evpose.frontend``  per-event stages: noise filter, time surfaces, distance field
- ``evpose.tracker``   visible-map culling, registration and the steppable tracker
- ``evpose.fusion``    IMU preintegration, factor-graph fusion, polarity prediction
- ``evpose.slam``      map-free event(-inertial) SLAM
- ``evpose.eval``      metrics, benchmarks, sweeps
- ``evpose.cli``       thin command-line wrappers over the library

``evpose`` never imports viser; the viewer lives in the top-level ``app`` package.
"""

from evpose.blas_kernels import pin_blas_kernels as _pin_blas_kernels

_pin_blas_kernels()  # before anything loads numpy: one BLAS kernel set, so results reproduce across machines

__version__ = "0.1.0"
