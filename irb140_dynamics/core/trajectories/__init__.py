"""Joint trajectories: reference motions and computed-torque control (``reference``).

May import: ``core.model``, the verbs in ``core.dynamics``, ``core.payload`` (limits).
"""
