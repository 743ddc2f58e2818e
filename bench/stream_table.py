"""The table of bench_nodes' end-to-end runs: id_node against the relay, per rate and executor.

With several runs of each pair (``--repeat``; relay and id_node alternate, each run in a
fresh process), a delay or CPU row holds the median over the runs of each node, and the
ratio is that of the medians: on a shared 2-core VM one run's p99 moves by 2-3x with the
host's stalls, the relay's as much as id_node's. Lost is the total over the runs: the
target, 0 lost, holds for every run.
"""

from __future__ import annotations

from statistics import median

from common import Figure, NotMeasured, Row, Target, Value
from node_processes import QOS_DEPTH

P99_TARGET = Target(1.1)  # id_node's p99 delay at most 1.1x the relay's
CPU_TARGET = Target(1.1)  # id_node's CPU per message at most 1.1x the relay's
LOST_TARGET = Target(0, absolute=True)  # no message lost


def stream_rows(runs: list[dict]) -> list[Row]:
    groups: dict[tuple, list[dict]] = {}
    for run in runs:
        groups.setdefault(_key(run, run["node"]), []).append(run)
    rows = []
    for (executor, rate, change_period, kind), ours in groups.items():
        if kind != "id_node":
            continue
        base = groups[(executor, rate, change_period, "relay")]
        lean = "" if ours[0]["qos_event_handlers"] else ", no QoS event handlers"
        changes = "" if change_period is None else f", payload.mass set every {change_period * 1e3:g} ms"
        repeats = f", {len(ours)} runs each, medians" if len(ours) > 1 else ""
        depth = ours[0].get("qos_depth", QOS_DEPTH)
        lean += "" if depth == QOS_DEPTH else f", qos.depth {depth}"
        group = (
            f"id_node end to end, {rate:g} Hz for {ours[0]['duration_s']:g} s{changes}{repeats}, "
            f"executor {executor}{lean} (baseline: relay" + (", the same parameter calls)" if changes else ")")
        )
        p99_target = P99_TARGET if change_period is None else None  # with changes the target is 0 lost
        for stat, target in (("p50", None), ("p99", p99_target), ("max", None)):
            rows.append(Row(group, f"delay {stat}", _delay(ours, stat), _delay(base, stat), target))
        sent = sum(run["sent"] for run in ours)
        rows.append(
            Row(
                group,
                f"lost (of {sent} sent)",
                Value.of(sum(run["lost"] for run in ours), "msgs"),
                Value.of(sum(run["lost"] for run in base), "msgs"),
                LOST_TARGET,
            )
        )
        rows.append(
            Row(
                group,
                "node CPU per message",
                _median(ours, "node_cpu_us_per_msg", "us/msg"),
                _median(base, "node_cpu_us_per_msg", "us/msg"),
                CPU_TARGET if change_period is None else None,
            )
        )
        if change_period is not None:
            ours_c, base_c = [r["parameter_changes"] for r in ours], [r["parameter_changes"] for r in base]
            calls = sum(c["accepted"] + c["refused"] + c["unanswered"] for c in ours_c)
            rows.append(
                Row(
                    group,
                    f"changes accepted (of {calls})",
                    Value.of(sum(c["accepted"] for c in ours_c), "calls"),
                    Value.of(sum(c["accepted"] for c in base_c), "calls"),
                )
            )
            for stat in ("p50", "p99"):
                rows.append(Row(group, f"SetParameters reply {stat}", _reply(ours_c, stat), _reply(base_c, stat)))
    return rows


def _key(run: dict, kind: str) -> tuple:
    changes = run["parameter_changes"]
    return run["executor"], run["rate_hz"], None if changes is None else changes["period_s"], kind


def _median(runs: list[dict], field: str, unit: str) -> Figure:
    return Value.of(median(run[field] for run in runs), unit)


def _reply(changes: list[dict], stat: str) -> Figure:
    values = [c["reply_ms"][stat] for c in changes if c["reply_ms"][stat] is not None]
    return Value.of(median(values), "ms") if values else NotMeasured(None, None, "ms", "no reply")


def _delay(runs: list[dict], stat: str) -> Figure:
    values = [run["delay_us"][stat] for run in runs if run["delay_us"][stat] is not None]
    if len(values) < len(runs):  # a run that received nothing has no delays: no median hides it
        return NotMeasured(None, None, "us", "nothing received in a run")
    return Value.of(median(values), "us")
