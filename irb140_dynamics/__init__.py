"""irb140_dynamics: a robot arm's dynamics (``core``), identification, simulation, and the
ROS 2 nodes and tools on them (docs/architecture.md).

Importing the package imports nothing else of it: it only tells the core where native
code comes from (``native_hook.loader``), the compile room (``native``) imported the first
time the core asks for it.
"""

from irb140_dynamics import native_hook


def _load_compile_room() -> None:
    import irb140_dynamics.native  # noqa: F401  installs its compiler in native_hook


native_hook.loader = _load_compile_room
