"""Benchmark of identification: the batch regressor, and `identify` on a long recording.

    .venv/bin/python bench/bench_identify.py [--minutes 60] [--rate 1000] [--bag DIR] [--repeats 2]

Prints one table and writes bench/results/identify.json. Sections:

- regressor: states per second of ``regressor_batch`` against a Python loop of
  ``pinocchio.computeJointTorqueRegressor`` over the same states (target >= 2x), after
  checking that both give the same rigid-body columns.
- recording: `identify` on a bag of ``--minutes`` of 1 kHz joint states (default 60: 3.6 M
  messages, about 1 GB; written once to ``--bag``, reused when it exists) against what
  rosbags alone takes to read and deserialise the same messages (target <= 1.5x), each in
  a process of its own, the two run in turn ``--repeats`` times (best and median: on a
  shared machine one run of either can lose a share of its core to other jobs); their CPU
  time (user + system, which other jobs disturb less); and the peak memory (resident set)
  of `identify` (target <= 1 GB).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
from common import REPO, Figure, Row, Target, machine_info, print_table, seconds_per_call, shown, write_results

from irb140_dynamics.core import irb140
from irb140_dynamics.core.regressor import regressor_batch
from test.support.pinocchio_model import build as pinocchio_model  # noqa: E402

SEED = 140
REGRESSOR_STATES = 20_000
REGRESSOR_REPEATS = 5
BLOCK_SECONDS = 60.0  # the bag is written a minute at a time

# Each measured process reports its own peak resident set at exit: VmHWM of /proc/self/status,
# which starts afresh at exec (ru_maxrss would include the benchmark's own size at the fork).
PEAK_AT_EXIT = """
import atexit, sys
def _peak():
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            print("peak_kb", line.split()[1], file=sys.stderr)
atexit.register(_peak)
"""
IDENTIFY = (
    PEAK_AT_EXIT
    + """
from irb140_dynamics.tools.identify import main
sys.exit(main(sys.argv[1:]))
"""
)
DESERIALISE_ONLY = (
    PEAK_AT_EXIT
    + """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
with AnyReader([Path(sys.argv[1])], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
    connections = [c for c in reader.connections if c.topic == "/joint_states"]
    deserialize, count = reader.typestore.deserialize_cdr, 0
    for connection, _, raw in reader.messages(connections=connections):
        deserialize(raw, connection.msgtype)
        count += 1
print(count, "messages")
"""
)


def regressor_rows() -> list[Row]:
    model = irb140()
    pm = pinocchio_model(model)
    data = pm.createData()
    lower, upper = np.array([j.position_limits for j in model.joints]).T
    rng = np.random.default_rng(SEED)
    Q = rng.uniform(lower, upper, (REGRESSOR_STATES, 6))
    QD, QDD = rng.uniform(-2, 2, Q.shape), rng.uniform(-5, 5, Q.shape)

    def loop(count=REGRESSOR_STATES):
        out = np.empty((count, 6, 60))
        for i in range(count):
            out[i] = pin.computeJointTorqueRegressor(pm, data, Q[i], QD[i], QDD[i])
        return out

    ours = regressor_batch(model, Q, QD, QDD)
    np.testing.assert_allclose(ours[:1000, :, :60], loop(1000), rtol=1e-9, atol=1e-9)
    rates = [
        Figure.rate(seconds_per_call(fn, blocks=REGRESSOR_REPEATS, number=1), REGRESSOR_STATES)
        for fn in (lambda: regressor_batch(model, Q, QD, QDD), loop)
    ]
    return [
        Row(
            f"regressor, {REGRESSOR_STATES:,} states",
            "regressor_batch vs loop of computeJointTorqueRegressor",
            *rates,
            Target(2, at_least=True),
        )
    ]


def write_long_bag(path: Path, minutes: float, rate: float) -> None:
    """``minutes`` of the synthetic arm along an excitation trajectory, a minute at a time."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    from irb140_dynamics.identification.excitation import optimise_excitation
    from test.support.synthetic_arm import drive, joint_state_messages, true_arm

    typestore = get_typestore(Stores.ROS2_JAZZY)
    trajectory = optimise_excitation(irb140(), iterations=5, seed=SEED).trajectory
    arm, names = true_arm(SEED), irb140().joint_names
    started = time.perf_counter()
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection("/joint_states", "sensor_msgs/msg/JointState", typestore=typestore)
        blocks = int(np.ceil(minutes * 60.0 / BLOCK_SECONDS))
        for block in range(blocks):
            duration = min(BLOCK_SECONDS, minutes * 60.0 - block * BLOCK_SECONDS)
            samples = drive(arm, trajectory, rate, duration, seed=block, start=block * BLOCK_SECONDS)
            for ns, raw in joint_state_messages(samples, names, with_velocity=True, typestore=typestore):
                writer.write(connection, ns, raw)
            print(
                f"\rwriting {path}: {block + 1}/{blocks} min, {time.perf_counter() - started:.0f} s",
                end="",
                file=sys.stderr,
                flush=True,
            )
    print(file=sys.stderr)


def run_measured(script: str, *args: str) -> tuple[float, float, float, str]:
    """(wall seconds, CPU seconds, peak resident memory in MB, output) of a Python script in
    its own process."""
    environment = {**os.environ, "PYTHONPATH": str(REPO)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", script, *args], env=environment, capture_output=True, text=True)
    elapsed = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        raise RuntimeError(f"{args} failed ({result.returncode}):\n{result.stdout}{result.stderr}")
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    peak_kb = int(re.search(r"^peak_kb (\d+)$", result.stderr, flags=re.M).group(1))
    return elapsed, cpu, peak_kb / 1024.0, result.stdout


def recording_rows(bag: Path, minutes: float, rate: float, repeats: int) -> tuple[list[Row], dict]:
    if not bag.exists():
        write_long_bag(bag, minutes, rate)
    for file in bag.iterdir():  # into the page cache, so that neither process pays the disk
        with open(file, "rb") as stream:
            while stream.read(1 << 24):
                pass
    baseline, ours = [], []  # (wall s, CPU s, peak MB, output) of each run
    with tempfile.TemporaryDirectory() as work:
        for _ in range(repeats):
            baseline.append(run_measured(DESERIALISE_ONLY, str(bag)))
            ours.append(run_measured(IDENTIFY, str(bag), "--out", str(Path(work) / "identified.yaml"), "--quiet"))
    messages = int(baseline[0][3].split()[0])
    group = f"recording: {messages:,} JointState messages ({minutes:g} min at {rate:g} Hz)"
    ours_mb, baseline_mb = max(run[2] for run in ours), max(run[2] for run in baseline)
    rows = [
        Row(
            group,
            "identify vs rosbags deserialisation alone",
            Figure.cost([run[0] for run in ours], "s"),
            Figure.cost([run[0] for run in baseline], "s"),
            Target(1.5),
        ),
        Row(
            group,
            "the same, CPU time (user + system)",
            Figure.cost([run[1] for run in ours], "s"),
            Figure.cost([run[1] for run in baseline], "s"),
        ),
        Row(
            group,
            "identify peak memory",
            Figure(ours_mb, ours_mb, "MB"),
            Figure(baseline_mb, baseline_mb, "MB"),
            Target(1024, absolute=True),
        ),
    ]
    return rows, {"messages": messages, "identify_output": ours[-1][3]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=60.0, help="length of the recording (default 60)")
    parser.add_argument("--rate", type=float, default=1000.0, help="joint states per second (default 1000)")
    parser.add_argument("--bag", type=Path, help="where the bag is kept (default bench/data/joint_states_<minutes>min)")
    parser.add_argument("--repeats", type=int, default=2, help="runs of each process, in turn (default 2)")
    parser.add_argument("--no-recording", action="store_true", help="the regressor section only")
    args = parser.parse_args()
    started = time.perf_counter()
    rows, details = regressor_rows(), {}
    if not args.no_recording:
        bag = args.bag or REPO / "bench" / "data" / f"joint_states_{args.minutes:g}min_{args.rate:g}hz"
        bag.parent.mkdir(parents=True, exist_ok=True)
        recording, details = recording_rows(bag, args.minutes, args.rate, max(args.repeats, 1))
        rows += recording
    print_table(rows, "irb140_dynamics identification (ratio = ours / baseline)")
    if details:
        print(details["identify_output"])
    path = write_results(
        "identify",
        {
            "benchmark": "identify",
            "machine": machine_info(("numpy", "scipy", "pinocchio", "rosbags")),
            "settings": {
                "minutes": args.minutes,
                "rate": args.rate,
                "repeats": args.repeats,
                "regressor_states": REGRESSOR_STATES,
                "seed": SEED,
            },
            "rows": [row.as_dict() for row in rows],
            "messages": details.get("messages"),
            "runtime_s": time.perf_counter() - started,
        },
    )
    print(f"raw figures: {shown(path)} ({time.perf_counter() - started:.0f} s)")


if __name__ == "__main__":
    main()
