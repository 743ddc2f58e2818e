"""Times as ROS messages carry them (builtin_interfaces Time and Duration): whole seconds
and nanoseconds. One conversion each way, for scalars and NumPy arrays alike."""

from __future__ import annotations

NANOSECONDS_PER_SECOND = 1_000_000_000


def seconds(sec, nanosec):
    """(sec, nanosec) -> seconds [s]."""
    return sec + nanosec * 1e-9


def nanoseconds(sec, nanosec) -> int:
    """(sec, nanosec) -> whole nanoseconds, exact."""
    return sec * NANOSECONDS_PER_SECOND + nanosec


def sec_nanosec(t: float) -> tuple[int, int]:
    """seconds [s] -> (sec, nanosec), rounded to the nanosecond."""
    return divmod(int(round(float(t) * 1e9)), NANOSECONDS_PER_SECOND)
