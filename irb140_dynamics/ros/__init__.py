"""The ROS floor: what the nodes share. ``runtime`` (spinning, guards, diagnostics),
``parameters`` (declared, validated whole, live), ``messages`` (joint messages <-> arrays),
``recorder`` (a topic to a bag). May import ``core``, ``identification``, ``sim``; never
``nodes`` or ``tools``.
"""
