"""What measured signals say beyond the model: joint accelerations estimated from velocities
(``filters``) and external joint torques from efforts (``observer``: the generalized momentum
observer behind id_node's collision detection).

May import: ``core.model``, ``core.algorithms``, ``core.codegen``, ``core.dynamics``.
"""
