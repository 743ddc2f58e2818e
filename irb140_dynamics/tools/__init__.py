"""Command-line tools (``ros2 run irb140_dynamics <tool>``): thin wrappers of ``identification``."""
