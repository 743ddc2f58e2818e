"""The figures of one end-to-end run (bench/stream.py), from the raw times it recorded."""

from __future__ import annotations

import numpy as np


def percentiles(x_ns: np.ndarray) -> dict:
    """p50, p99, max (us) of delays in ns; None when there are none."""
    if x_ns.size == 0:
        return {"p50": None, "p99": None, "max": None}
    us = x_ns / 1e3
    return {"p50": float(np.percentile(us, 50)), "p99": float(np.percentile(us, 99)), "max": float(us.max())}


def summarize(kind, executor, rate, duration, stamps, first, lateness, records, cpu, own, load: dict, sent_s) -> dict:
    """``stamps``: of the messages sent, the measured window from index ``first``;
    ``records``: the Receiver's; ``cpu``, ``own``: the node's and this process's CPU seconds
    over the window; ``load``: machine_load.load_between over it."""
    measured = stamps[first:]
    sent = measured.size
    records = np.array(records, dtype=np.int64).reshape(-1, 5)
    if records.size:
        _, unique = np.unique(records[:, 0], return_index=True)
        records = records[np.sort(unique)]
    in_window = np.isin(records[:, 0], measured)
    window = records[in_window]
    stamp, source, received, taken, sequence = window.T
    received_count = int(window.shape[0])
    # outputs the node published in the window but that never arrived: gaps in its sequence
    published = int(sequence.max() - sequence.min() + 1) if received_count and sequence.min() > 0 else None
    warmup_stamps = stamps[:first]
    return {
        "node": kind,
        "executor": executor,
        "rate_hz": rate,
        "duration_s": duration,
        "sent": int(sent),
        "received": received_count,
        "lost": int(sent - received_count),
        # of the lost: published by the node (between the first and last received) but not
        # received here; the rest the node never published (dropped on the way in, or never taken)
        "lost_after_node_published": None if published is None else published - received_count,
        "lost_runs": lost_runs(measured, np.isin(measured, stamp), rate),
        # [time into the window (s), delay (ms)] of the outputs delayed most: where the stalls were
        "slowest": slowest(stamp, received, int(measured[0]) if sent else 0),
        "lost_in_warmup": int(first - np.isin(records[:, 0], warmup_stamps).sum()),
        # publish here -> DDS reception of the torques here: the figure of the table
        "delay_us": percentiles(received - stamp),
        # publish here -> taken by this process's receiving loop (what a Python consumer sees)
        "delay_taken_us": percentiles(taken - stamp),
        # publish here -> the node publishes the torques (its source timestamp)
        "delay_to_node_output_us": percentiles(source - stamp),
        "node_cpu_us_per_msg": cpu / sent * 1e6,
        "node_cpu_percent": cpu / duration * 100,
        "bench_cpu_percent": own / duration * 100,
        # machine_busy_percent, other_processes_cores (not the node's, not this process's), stolen_percent
        **load,
        "achieved_rate_hz": sent / sent_s if sent_s > 0 else None,
        "send_lateness_us": {
            "p50": float(np.percentile(lateness[first:], 50) * 1e6),
            "p99": float(np.percentile(lateness[first:], 99) * 1e6),
            "max": float(lateness[first:].max() * 1e6),
        },
    }


def slowest(stamp: np.ndarray, received: np.ndarray, window_start: int, most: int = 20) -> list[list]:
    """[time into the window (s), delay (ms)] of the ``most`` outputs delayed most, in time order."""
    delay = received - stamp
    worst = np.sort(np.argsort(delay)[-most:]) if delay.size else []
    return [[round((int(stamp[k]) - window_start) / 1e9, 4), round(int(delay[k]) / 1e6, 2)] for k in worst]


def lost_runs(measured: np.ndarray, arrived: np.ndarray, rate: float, most: int = 20) -> list[list]:
    """Runs of consecutive lost messages: [time into the window (s), how many], the first ``most``."""
    runs, i = [], 0
    missing = np.flatnonzero(~arrived)
    while i < missing.size and len(runs) < most:
        j = i
        while j + 1 < missing.size and missing[j + 1] == missing[j] + 1:
            j += 1
        runs.append([round(float(missing[i]) / rate, 4), int(j - i + 1)])
        i = j + 1
    return runs
