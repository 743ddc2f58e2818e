"""The wrist force/torque sensor room: a sensor's reading freed of its tool.

- ``contact``: where the sensor sits (a link rigidly on the last link), the tool's own
  gravity and inertial wrench on it, and the contact wrench (the environment's on the tool);
- ``load_estimation``: the sensor's bias and the tool's mass and centre of mass from rest
  readings in a few poses (linear least squares);
- ``stream``: what a node runs: readings matched to the nearest joint state, accelerations
  from the velocities, rests collected for the estimate.

May import: ``core.payload``, ``core.monitoring`` and everything below them. Nothing of ROS.
"""
