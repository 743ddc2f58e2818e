"""What else ran on the machine during a measured window: other processes, and the hypervisor.

Each process's CPU time (utime + stime of /proc/<pid>/stat, all its threads) is exact: the
kernel scales it to the time the process really ran. The CPU lines of /proc/stat are not:
they charge each scheduler tick to whatever runs at that instant, and a load that wakes on
a 1 ms grid and sleeps again before the tick is mostly charged as idle (the "other
processes" of a 2 kHz stream came out at -1.1 cores that way). So busy time is summed over
the processes, and /proc/stat is read only for the hypervisor's steal, which has no other
source. Processes that start and end inside the window are not seen.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

OTHERS_WARNING = 0.25  # cores used by other processes during a run worth a note
STOLEN_WARNING = 1.0  # % of the CPUs' time taken by the hypervisor during a run worth a note


@dataclass(frozen=True)
class Snapshot:
    wall_s: float  # time.monotonic()
    cpu_s: dict  # pid -> CPU seconds so far
    jiffies: tuple[int, int]  # (all, stolen) of /proc/stat's cpu line


def snapshot() -> Snapshot:
    """The machine's counters now."""
    return Snapshot(time.monotonic(), processes_cpu(), _jiffies())


def load_between(before: Snapshot, after: Snapshot, ours: set[int]) -> dict:
    """The window's load: ``machine_busy_percent`` (all processes, of all cores),
    ``other_processes_cores`` (the processes not in ``ours``: pids), ``stolen_percent``
    (of the CPUs' time the hypervisor gave to other machines: stalls nobody here caused)."""
    seconds = max(1e-9, after.wall_s - before.wall_s)
    used = {pid: cpu - before.cpu_s[pid] for pid, cpu in after.cpu_s.items() if pid in before.cpu_s}
    others = sum(cpu for pid, cpu in used.items() if pid not in ours)
    all_jiffies, stolen = (b - a for a, b in zip(before.jiffies, after.jiffies))
    return {
        "machine_busy_percent": 100 * sum(used.values()) / seconds / (os.cpu_count() or 1),
        "other_processes_cores": others / seconds,
        "stolen_percent": 100 * stolen / max(1, all_jiffies),
    }


def processes_cpu() -> dict:
    """CPU seconds so far of every process alive, by pid."""
    cpu = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                cpu[int(entry)] = process_cpu_seconds(int(entry))
            except OSError:  # ended meanwhile
                continue
    return cpu


def process_cpu_seconds(pid: int) -> float:
    """User + system time of a process so far, all its threads (from /proc/<pid>/stat)."""
    with open(f"/proc/{pid}/stat") as stat:
        fields = stat.read().rsplit(")", 1)[1].split()  # after the command name, which may hold spaces
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime


def _jiffies() -> tuple[int, int]:
    with open("/proc/stat") as stat:
        values = [int(x) for x in stat.readline().split()[1:]]
    return sum(values), values[7] if len(values) > 7 else 0
