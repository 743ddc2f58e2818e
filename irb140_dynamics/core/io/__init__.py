"""File formats, each read AND written in one place: ROS 2 parameter files (``params_file``),
URDF (``urdf/``), JointTrajectory YAML (``trajectory_file``); numbers as YAML text
(``yaml_numbers``) and files written whole or not at all (``atomic``).

May import: ``core.model`` and the other core rooms. Nothing of ROS.
"""
