"""Load identification on many arms, over noise seeds: how often it meets the issue's tolerances.

Not a test (it takes minutes): what `test/identification/test_load_any_arm.py` checks once
per arm on a few arms, here on every arm of ARMS and on ``--seeds`` draws of the effort
noise. Each arm: `excitation --payload`'s design (``optimise_payload_excitation`` at 1 %
effort noise, 500 Hz), one MuJoCo run of it with the 3.1 kg tool (``test.support.simulated_load``:
computed torque at 1 kHz, drive losses), then for each seed the recorded efforts plus white
noise of 1 % of each joint's torque limit, fitted as `identify --payload-only` fits them
(``fit_payload``). Printed per arm: the wrist's noise, the design's period and its promise
(the largest of the tool's principal moments' standard deviations, as a fraction of the
moment: the design's covariance carried through to the moments about the CoM at the true
tool), then over the seeds the largest mass, CoM and principal-moment
errors and the share of runs outside mass 2 %, CoM 5 mm, each moment 10 % (a refusal counts
as a failure). With --of-peak the noise is 1 % of each joint's peak effort along the run (the
tool's included), as docs/load.md's walkthrough adds it, instead of 1 % of its torque limit.

    .venv/bin/python bench/load_arms.py --seeds 30            # every arm, about 2 min
    .venv/bin/python bench/load_arms.py --arms gen3,fr3 --seeds 10
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from irb140_dynamics.core.io.urdf.reader import load_urdf  # noqa: E402
from irb140_dynamics.core.model.rigid_body import inertia_matrix  # noqa: E402
from irb140_dynamics.identification.effort_noise import EffortNoise  # noqa: E402
from irb140_dynamics.identification.payload import RecordingError, fit_payload, payload_of, payload_parameters  # noqa: E402
from irb140_dynamics.identification.payload_excitation import (  # noqa: E402
    information,
    optimise_payload_excitation,
    with_assumed_accelerations,
)
from test.support.paths import URDF_DATA  # noqa: E402
from test.support.simulated_load import run, tool, with_drive_losses, write_csv  # noqa: E402

NOISE = EffortNoise(0.01)
TOOL = tool(3.1, (0.03, -0.05, 0.08), (0.01, 0.016, 0.02), (0.5, -0.4, 0.8))
PANDA_ACCELERATIONS = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)  # rad/s^2, Franka's documented limits (FR3's too)


def _example_robot_data(relative: str) -> Path:
    import sysconfig

    return Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots" / relative


ARMS = {
    # name: (URDF, tip, acceleration limits stated or None)
    "panda": (URDF_DATA / "panda.urdf", "panda_link8", PANDA_ACCELERATIONS),
    "fr3": (URDF_DATA / "fr3.urdf", "fr3_link8", PANDA_ACCELERATIONS),
    "gen3": (URDF_DATA / "gen3.urdf", "end_effector_link", None),
    "xarm7": (URDF_DATA / "xarm7.urdf", None, None),
    "z1": (URDF_DATA / "z1.urdf", "link06", None),
    "ur5": (URDF_DATA / "ur5.urdf", "tool0", None),
    "ur5e": (URDF_DATA / "ur5e.urdf", "tool0", None),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0", None),
    "ur3": ("ur_description/urdf/ur3_robot.urdf", "tool0", None),
    "jaco2": ("kinova_description/robots/kinova.urdf", None, None),
}


def true_arm(name: str):
    path, tip, accelerations = ARMS[name]
    path = path if isinstance(path, Path) else _example_robot_data(path)
    model = with_drive_losses(load_urdf(path.read_text(), tip_link=tip).model)
    if accelerations:
        model = replace(
            model, joints=tuple(replace(j, acceleration_limit=a) for j, a in zip(model.joints, accelerations))
        )
    return model


def errors(found) -> tuple[float, float, float]:
    """(mass relative error, CoM error [m], worst principal moment's relative error)."""
    moments = np.linalg.eigvalsh(inertia_matrix(found.inertia))
    truth = np.linalg.eigvalsh(inertia_matrix(TOOL.inertia))
    return (
        abs(found.mass / TOOL.mass - 1.0),
        float(np.linalg.norm(np.subtract(found.com, TOOL.com))),
        float(np.abs(moments / truth - 1.0).max()),
    )


def _moments(phi) -> np.ndarray:
    return np.linalg.eigvalsh(inertia_matrix(payload_of(phi).inertia))


def promised_moments(arm, design) -> float:
    """The largest relative standard deviation of the tool's principal moments the design promises."""
    F, _, _ = information(with_assumed_accelerations(arm), design.trajectory, NOISE, design.rate, design.duration)
    phi, step = payload_parameters(TOOL), 1e-7
    J = np.array([(_moments(phi + step * e) - _moments(phi - step * e)) / (2 * step) for e in np.eye(10)]).T
    return float((np.sqrt(np.diag(J @ np.linalg.inv(F) @ J.T)) / _moments(phi)).max())


def check(name: str, seeds: int, work: Path, of_peak: bool = False, design_seed: int = 0) -> str:
    arm = true_arm(name)
    started = time.process_time()
    design = optimise_payload_excitation(arm, iterations=10, noise=NOISE, seed=design_seed)
    t, Q, QD, clean = run(arm.with_payload(TOOL), design.trajectory, design.duration, EffortNoise(1e-12))
    peak = np.abs(clean).max(axis=0)
    sigma = NOISE.value * peak if of_peak else NOISE.sigma(arm, peak)
    results, refused = [], []
    for seed in range(seeds):
        tau = clean + np.random.default_rng(1000 + seed).normal(size=clean.shape) * sigma
        path = write_csv(work / f"{name}.csv", arm.joint_names, t, Q, QD, tau)
        try:
            results.append(errors(fit_payload(arm, path).payload))
        except RecordingError as error:
            refused.append(str(error).split(": ", 1)[-1][:60])
    found = np.array(results).reshape(-1, 3)
    failed = len(refused) + int(np.sum((found[:, 0] > 0.02) | (found[:, 1] > 0.005) | (found[:, 2] > 0.1)))
    worst = lambda k: f"{found[:, k].max():.3g}" if len(found) else "-"  # noqa: E731
    return (
        f"{name:6s} wrist noise {np.round(sigma[-3:], 3)} N m  period {design.trajectory.period:g} s  "
        f"promised moment std {promised_moments(arm, design):.3f}  | mass {worst(0)}  CoM {worst(1)} m  moment {worst(2)}  "
        f"| failed {failed}/{seeds}{'  refused: ' + refused[0] if refused else ''}  "
        f"({time.process_time() - started:.0f} s CPU)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", default=",".join(ARMS))
    parser.add_argument("--seeds", type=int, default=30)
    parser.add_argument("--design-seed", type=int, default=0, help="the design's own --seed")
    parser.add_argument("--of-peak", action="store_true", help="noise of 1 %% of each joint's peak effort in the run")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as work:
        for name in args.arms.split(","):
            print(check(name, args.seeds, Path(work), args.of_peak, args.design_seed), flush=True)


if __name__ == "__main__":
    main()
