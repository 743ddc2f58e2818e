"""What measured signals say beyond the model: joint accelerations estimated from velocities
(``filters``), external joint torques from efforts (``observer``: the generalized momentum
observer), collisions where they exceed thresholds (``collision``), the wrench on the flange
they come from (``wrench``: a virtual force sensor), collision thresholds set from a
recording of normal work and the flange force they detect (``sensitivity``), where and how
the markers draw the arm's loads (``display``) and a controller's tracking error over time
(``tracking``).

May import: ``core.model``, ``core.algorithms``, ``core.codegen``, the verbs (``core.dynamics``, ``core.kinematics``).
"""
