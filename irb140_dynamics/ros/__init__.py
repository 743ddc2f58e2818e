"""The ROS floor: what the nodes share (``runtime``, ``parameters``, ``messages``) and the
record tool's node (``recorder``). Imports ``core``, ``identification``, ``sim``; never
``nodes`` or ``tools``."""
