"""Command-line tools (``ros2 run irb140_dynamics <tool>``): thin wrappers of ``identification``
and ``core``: parse, call, print. May import every floor below (``ros`` only where ROS I/O is
the point: ``record``); never ``nodes``. Each starts through ``irb140_dynamics.entry``: its
console scripts are in ``programs``, and ``python -m irb140_dynamics.tools.<tool>`` calls
the entry at the top of the tool's module, before the heavy imports.
"""
