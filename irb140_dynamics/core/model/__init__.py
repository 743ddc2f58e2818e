"""The model room: what an arm is. ``RobotModel`` (a validated serial chain), its ``Joint``s
(DH rows or URDF form, limits, friction, rotor inertia), ``RigidBody`` inertials, the
friction law, what a state is, joints matched by name, what is derived from a model and
kept apart from it while it lives (``per_model``), and the default model: the IRB-140 of
the report (``irb140``).

SI units throughout: m, rad, kg, kg m^2, m/s^2, N m. May import: nothing of the package
outside this room (it is the ground floor); NumPy only.
"""
