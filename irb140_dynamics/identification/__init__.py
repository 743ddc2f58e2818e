"""Identification of the dynamic parameters from recorded joint states. No ROS in here.

May import: ``core``. Never ``ros``, ``nodes``, ``tools``.

    base        the identifiable combinations (base parameters) of a model's structure
    excitation  periodic Fourier trajectories within the limits, optimised for them
    recording   ROS 2 bags (rosbags) and CSV files, read in chunks
    bag_recording  a topic written to a new bag as it comes (the record tool's), and when it is complete
    signals     zero-phase filtering, differentiation and decimation, chunk by chunk
    least_squares  normal equations; weighted least squares on the base parameters
    correlation how correlated the residuals are: the estimate's covariance depends on it
    consistent  the physically consistent full set closest to the data (log-Cholesky);
                whether a physical arm is within the estimate's uncertainty
    pipeline    all of it over a recording; report, plots, files: its outputs
    payload     load identification: a payload's ten parameters, the arm known
                (payload_excitation: the wrist motion for it; payload_report: its outputs)

The command-line tools (``irb140_dynamics.tools``) are thin wrappers; see
docs/identification.md and docs/load.md for the workflows.
"""
