"""Identification of the dynamic parameters from recorded joint states. No ROS in here.

May import: ``core``. Never ``ros``, ``nodes``, ``tools``.

    base        the identifiable combinations (base parameters) of a model's structure
    excitation  periodic Fourier trajectories within the limits, optimised for them
    recording   ROS 2 bags (rosbags) and CSV files, read in chunks
    signals     zero-phase filtering, differentiation and decimation, chunk by chunk
    least_squares  normal equations; weighted least squares on the base parameters
    consistent  the physically consistent full set closest to the data (log-Cholesky)
    pipeline    all of it over a recording; report, plots, files: its outputs

The command-line tools (``irb140_dynamics.tools``) are thin wrappers; see
docs/identification.md for the workflow.
"""
