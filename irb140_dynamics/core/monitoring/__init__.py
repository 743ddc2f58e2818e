"""What measured signals say beyond the model: joint accelerations estimated from velocities
(``filters``), external joint torques from efforts (``observer``: the generalized momentum
observer), collisions where they exceed thresholds (``collision``), the wrench on the flange
they come from (``wrench``: a virtual force sensor) and where and how the markers draw the
arm's loads (``display``).

May import: ``core.model``, ``core.algorithms``, ``core.codegen``, the verbs (``core.dynamics``, ``core.kinematics``).
"""
