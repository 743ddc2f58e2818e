"""The whole workflow on a synthetic arm: excitation, a recorded bag, identify, the nodes load it.

The 'true' arm (``synthetic_arm``) follows the trajectory the `excitation` command wrote;
its torques, with 1 % noise and 1e-5 rad position quantisation, are recorded as an .mcap
bag; `identify` must give a held-out RMS torque error of at most 2 % of each joint's peak,
every base parameter within 3 sigma of the truth, a physically consistent arm, and a
parameter file id_node and payload_check_node start on.
"""

import contextlib
import io
import re

import numpy as np
import pytest
import yaml
from rosbags.typesys import Stores, get_typestore

from irb140_dynamics.core import RobotModel, irb140, rnea, rnea_batch
from irb140_dynamics.core.io.params_file import read_parameter_file
from irb140_dynamics.core.regressor import inertial_parameters
from irb140_dynamics.identification import pipeline
from irb140_dynamics.identification.base import find_base_parameters
from irb140_dynamics.identification.consistent import is_consistent
from irb140_dynamics.identification.pipeline import identify
from irb140_dynamics.tools import excitation as excitation_tool
from irb140_dynamics.tools import identify as identify_tool
from irb140_dynamics.tools.cli import shown

from ..support.synthetic_arm import Samples, joint_state_messages, true_arm, write_bag, write_csv

pytestmark = pytest.mark.slow  # the workflow fixture records, identifies and plots a synthetic arm

RATE, PERIOD, PERIODS = 250.0, 4.0, 3  # 12 s of data, 3000 messages
NAMES = irb140().joint_names


def load_trajectory(path):
    document = yaml.load(path.read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    points = document["points"]
    t = np.array([p["time_from_start"]["sec"] + 1e-9 * p["time_from_start"]["nanosec"] for p in points])
    return (
        document,
        t,
        *(np.array([p[field] for p in points]) for field in ("positions", "velocities", "accelerations")),
    )


@pytest.fixture(scope="module")
def workflow(tmp_path_factory):
    """excitation -> the true arm along it -> .mcap bag -> identify, run as the commands."""
    work = tmp_path_factory.mktemp("identify")
    trajectory_file = work / "excitation.yaml"
    assert (
        excitation_tool.main(
            [
                "--out",
                str(trajectory_file),
                "--period",
                str(PERIOD),
                "--harmonics",
                "4",
                "--periods",
                str(PERIODS),
                "--rate",
                str(RATE),
                "--iterations",
                "3",
                "--seed",
                "2",
            ]
        )
        == 0
    )
    document, t, Q, QD, QDD = load_trajectory(trajectory_file)
    arm = true_arm(3)
    tau = rnea_batch(arm, Q, QD, QDD)
    peak = np.abs(tau).max(axis=0)
    # With 52 base parameters, about 1 noise draw in 8 puts one beyond 3 sigma however honest
    # the sigmas (1 - 0.9973^52); this seed's draw is a typical one (rms z ~ 1, max 2.6).
    measured = tau + np.random.default_rng(5).normal(size=tau.shape) * 0.01 * peak
    samples = Samples(t, np.round(Q / 1e-5) * 1e-5, QD, measured, tau)
    typestore = get_typestore(Stores.ROS2_JAZZY)
    bag = write_bag(work / "bag", joint_state_messages(samples, NAMES, with_velocity=False, typestore=typestore))
    out, plots = work / "identified.yaml", work / "plots"
    printed = io.StringIO()
    results = []  # identify's result, kept for the tests of what the tool does with one

    def kept(*args, **kwargs):
        results.append(identify(*args, **kwargs))
        return results[-1]

    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stdout(printed):
        patch.setattr(pipeline, "identify", kept)
        status = identify_tool.main([str(bag), "--out", str(out), "--plots", str(plots), "--quiet"])
    return dict(
        work=work,
        trajectory=trajectory_file,
        document=document,
        trajectory_arrays=(t, Q, QD, QDD),
        samples=samples,
        arm=arm,
        QDD=QDD,
        bag=bag,
        out=out,
        plots=plots,
        status=status,
        printed=printed.getvalue(),
        result=results[0] if results else None,
    )


@pytest.fixture(scope="module")
def identified(workflow):
    assert workflow["status"] == 0
    return RobotModel.from_params(read_parameter_file(workflow["out"]))


def held_out(workflow):
    """The last 20 % of the samples."""
    samples = workflow["samples"]
    k = int(0.8 * len(samples.time))
    return samples.position[k:], samples.velocity[k:], workflow["QDD"][k:], samples.effort[k:], samples.true_effort[k:]


def test_the_excitation_file_is_a_trajectory_within_the_limits(workflow):
    text = workflow["trajectory"].read_text()
    condition = float(re.search(r"# condition number of the base regressor: ([\d.]+)", text).group(1))
    assert 1.0 < condition < 1000.0
    document = workflow["document"]
    assert document["joint_names"] == list(NAMES) and len(document["points"]) == RATE * PERIOD * PERIODS + 1
    _, Q, QD, QDD = workflow["trajectory_arrays"]  # the file as load_trajectory read it
    for j, joint in enumerate(irb140().joints):
        lower, upper = joint.position_limits
        assert lower <= Q[:, j].min() and Q[:, j].max() <= upper
        assert np.abs(QD[:, j]).max() <= joint.velocity_limit and np.abs(QDD[:, j]).max() <= joint.acceleration_limit
    np.testing.assert_allclose(QD[0], 0.0, atol=1e-12)  # starts at rest
    np.testing.assert_allclose(Q[-1], Q[0], atol=1e-9)  # and comes back


def test_identified_torques_within_2_percent_of_peak_on_held_out_data(workflow, identified):
    q, qd, qdd, measured, true = held_out(workflow)
    peak = np.abs(measured).max(axis=0)
    for model, bound in ((identified, 0.02), (workflow["arm"], 0.02)):
        error = np.sqrt(np.mean((rnea_batch(model, q, qd, qdd) - measured) ** 2, axis=0)) / peak
        assert np.all(error <= bound), error
    # against the noise-free torques: the model's own error, well below the noise
    assert np.all(np.sqrt(np.mean((rnea_batch(identified, q, qd, qdd) - true) ** 2, axis=0)) / peak < 0.006)
    # the report's model on the same data: 8 % to 70 % of peak
    prior_error = np.sqrt(np.mean((rnea_batch(irb140(), q, qd, qdd) - measured) ** 2, axis=0)) / peak
    assert np.all(prior_error > 0.05), prior_error


def test_summary_reports_counts_errors_and_consistency(workflow):
    printed = workflow["printed"]
    assert workflow["status"] == 0, printed
    assert f"{workflow['bag']}: 3,001 samples read, " in printed
    used, left_out, edges = (
        int(x.replace(",", ""))
        for x in re.search(
            r"samples read, ([\d,]+) used, ([\d,]+) left out \(0 invalid \(a value missing, not finite or beyond 1e6\), ([\d,]+) at gaps",
            printed,
        ).groups()
    )
    assert used + left_out == 3001 and left_out == edges > 0
    assert "torque rows too slow for Coulomb friction, left out: joint_1 " in printed
    assert "base parameters: 52 of 78; condition number of the base regressor: " in printed
    assert "held out: the last 20 % of the moving fit points of the recording" in printed
    table = re.findall(r"^(joint_\d) +(\S+) +(\S+) +\((\S+) %\) +(\S+) +\((\S+) %\)$", printed, flags=re.M)
    assert [row[0] for row in table] == list(NAMES)
    for _name, peak, _prior, prior_percent, identified, identified_percent in table:
        assert float(identified_percent) <= 2.0 and float(prior_percent) > 5.0
        assert float(identified) == pytest.approx(float(identified_percent) / 100 * float(peak), rel=0.01, abs=1e-3)
    assert "physically consistent: yes" in printed and "the data agree with a physical arm" in printed
    assert f"wrote {workflow['out']}" in printed


def test_base_parameters_within_3_sigma_of_the_truth(workflow):
    text = workflow["out"].read_text()
    rows = re.findall(r"^# b(\d+) = +(\S+) \+- (\S+): ", text, flags=re.M)
    base = find_base_parameters(irb140())
    assert [int(r[0]) for r in rows] == list(range(1, base.count + 1))
    estimate, std = np.array([[float(r[1]), float(r[2])] for r in rows]).T
    z = (estimate - base.of(inertial_parameters(workflow["arm"]))) / std
    assert np.abs(z).max() <= 3.0, dict(zip(base.labels(), z.round(2)))
    assert 0.6 < np.sqrt(np.mean(z**2)) < 1.5  # the standard deviations are honest, not inflated


def test_identified_model_is_physically_consistent(workflow, identified):
    assert is_consistent(inertial_parameters(identified), identified.n)
    assert "# physically consistent: yes" in workflow["out"].read_text()
    prior = irb140()
    for mine, theirs in zip(identified.joints, prior.joints):  # kinematics and limits are the prior's
        assert (mine.dh, mine.position_limits, mine.velocity_limit) == (
            theirs.dh,
            theirs.position_limits,
            theirs.velocity_limit,
        )


def test_plots_are_written(workflow):
    for name in ("torques.png", "residuals.png"):
        assert (workflow["plots"] / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.ros
def test_id_node_publishes_the_identified_torques(workflow, identified):
    from sensor_msgs.msg import JointState

    from irb140_dynamics.nodes.id_node.node import IdNode

    from ..support.ros_harness import running

    args = ["--ros-args", "--params-file", str(workflow["out"])]
    with running(IdNode, cli_args=args) as harness:
        feedforward = harness.listen(JointState, "feedforward_torques")
        publisher = harness.publisher(JointState, "joint_states")
        samples = workflow["samples"]
        for k in (2500, 2700, 2900):
            q, qd = samples.position[k], samples.velocity[k]
            publisher.publish(JointState(name=list(NAMES), position=q.tolist(), velocity=qd.tolist()))
            assert harness.spin_until(lambda: len(feedforward) > 0)
            torque = np.array(feedforward.pop().effort)
            np.testing.assert_allclose(torque, rnea(identified, q, qd, np.zeros(6)), rtol=1e-9, atol=1e-9)
            truth = rnea(workflow["arm"], q, qd, np.zeros(6))
            assert np.all(np.abs(torque - truth) <= 0.02 * np.abs(samples.true_effort).max(axis=0))


@pytest.mark.ros
def test_payload_check_node_starts_on_the_identified_file(workflow, identified):
    from irb140_dynamics.nodes.payload_check_node.node import PayloadCheckNode

    from ..support.ros_harness import running

    with running(PayloadCheckNode, cli_args=["--ros-args", "--params-file", str(workflow["out"])]) as harness:
        for name in ("joint_2.link.mass", "joint_4.friction.coulomb", "joint_6.armature"):
            assert harness.node.get_parameter(name).value == identified.to_params()[name]


def test_validation_on_a_second_recording(workflow, tmp_path, capsys):
    samples = workflow["samples"]
    half = slice(len(samples.time) // 2, None)  # another recording: a CSV of the second half, with velocities
    second = Samples(
        samples.time[half],
        samples.position[half],
        samples.velocity[half],
        samples.effort[half],
        samples.true_effort[half],
    )
    csv = write_csv(tmp_path / "second.csv", second, NAMES, with_velocity=True)
    status = identify_tool.main(
        [str(workflow["bag"]), "--validate", str(csv), "--out", str(tmp_path / "o.yaml"), "--quiet"]
    )
    out = capsys.readouterr().out
    assert status == 0, out
    assert f"held out: {csv}" in out and "qd from measured velocities" in out
    table = re.findall(r"^joint_\d +\S+ +\S+ +\((\S+) %\) +\S+ +\((\S+) %\)$", out, flags=re.M)
    assert len(table) == 6 and all(float(identified) <= 2.0 < float(prior) for prior, identified in table), out


@pytest.mark.parametrize(
    "args, problem",
    [
        (["missing.mcap", "--out", "{tmp}/o.yaml"], "missing.mcap: no such file or directory"),
        (["{bag}", "--out", "{tmp}/o.yaml", "--topic", "/other"], "no topic /other"),
        (
            ["{bag}", "--out", "{tmp}/o.yaml", "--params-file", "{tmp}/none.yaml"],
            "none.yaml: no such file or directory",
        ),
        (["{bag}", "--out", "{tmp}/o.yaml", "--params-file", "{bad}"], "joint_2.link.mass: must be >= 0"),
    ],
)
def test_identify_errors_are_one_line_and_write_nothing(workflow, tmp_path, capsys, args, problem):
    bad = tmp_path / "bad.yaml"
    text = workflow["out"].read_text()
    mass = re.search(r"    joint_2:\n(?:.*\n)*?        mass: (\S+)\n", text).group(1)  # joint_2's link mass
    bad.write_text(text.replace(f"mass: {mass}", "mass: -1.0", 1))
    args = [a.format(tmp=tmp_path, bag=workflow["bag"], bad=bad) for a in args]
    assert identify_tool.main(args + ["--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("identify: error: ") and problem in err[0], err
    assert not (tmp_path / "o.yaml").exists()


def test_excitation_refuses_bad_options(tmp_path, capsys):
    assert excitation_tool.main(["--out", str(tmp_path / "t.yaml"), "--rate", "0"]) == 2
    assert "excitation: error: argument --rate: must be > 0, got 0" in capsys.readouterr().err
    for payload, harmonics in (([], 5), (["--payload"], 3)):  # one point 'over 0 s', or too few for the top harmonic
        for rate in ("0.01", "1"):
            assert excitation_tool.main(["--out", str(tmp_path / "t.yaml"), "--rate", rate, *payload]) == 1
            err = capsys.readouterr().err.strip().splitlines()
            expected = f"points per period, fewer than {4 * harmonics} (4 per cycle of harmonic {harmonics})"
            assert len(err) == 1 and expected in err[0], err
    locked = ["-p", "joint_1.position_limits:=[0.0,0.0]", "--iterations", "0"]  # a condition number of inf
    assert excitation_tool.main(["--out", str(tmp_path / "t.yaml"), *locked]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "joint_1: no position range to move in" in err[0], err
    assert not (tmp_path / "t.yaml").exists()


class _ReaderGoneAfterOneLine(io.StringIO):
    """A standard output whose reader has read one line and gone (`tool | head -1`)."""

    def write(self, text):
        if "\n" in self.getvalue():
            raise BrokenPipeError(32, "Broken pipe")
        return super().write(text)


@pytest.mark.parametrize("payload", [[], ["--payload"]])
def test_excitation_piped_to_head_writes_nothing(tmp_path, payload):
    """`excitation ... | head -1`: ended as SIGPIPE ends a program (141), its file not written."""
    with contextlib.redirect_stdout(_ReaderGoneAfterOneLine()):
        status = excitation_tool.main(["--out", str(tmp_path / "t.yaml"), "--iterations", "0", *payload])
    assert status == 141 and not (tmp_path / "t.yaml").exists()


def test_reading_progress_names_the_file_and_ends_at_100_percent(capsys):
    """Off a terminal (here: captured), a line per 10 % of the samples read, the file named."""
    from irb140_dynamics.tools.common import reading_progress

    show = reading_progress("identify")
    for done in (0, 400, 700, 1000):
        show("/data/run.mcap", done, 1000)
    lines = capsys.readouterr().err.splitlines()
    assert [line.split(" (")[0] for line in lines] == [f"identify: reading run.mcap: {p} %" for p in (40, 70, 100)]
    assert lines[-1].startswith("identify: reading run.mcap: 100 % (1,000/1,000 samples), done in ")


def test_plots_and_result_are_written_together_or_not_at_all(workflow, tmp_path, monkeypatch, capsys):
    """A plot that cannot be written (here: the second fails) leaves neither the result nor
    the first plot, nor a temporary file or the plots folder made for them. The fit is the
    workflow's own (the recording read and fitted once for the module)."""
    import irb140_dynamics.identification.plots as plots

    assert workflow["result"] is not None
    monkeypatch.setattr(pipeline, "identify", lambda *a, **k: workflow["result"])

    real = plots.write_plots

    def failing(result, save, *rest):
        calls = []

        def second_fails(name, write):
            calls.append(name)
            if len(calls) == 2:
                raise OSError(28, "No space left on device")
            save(name, write)

        return real(result, second_fails, *rest)

    monkeypatch.setattr(plots, "write_plots", failing)
    out, folder = tmp_path / "o.yaml", tmp_path / "new" / "plots"
    assert identify_tool.main([str(workflow["bag"]), "--out", str(out), "--plots", str(folder), "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("identify: error: ") and "No space left" in err[0], err
    assert list(tmp_path.iterdir()) == [], list(tmp_path.rglob("*"))


def test_arguments_and_outputs_are_checked_before_the_recording_is_read(workflow, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(pipeline, "identify", lambda *a, **k: pytest.fail("the recording was read"))
    afile = tmp_path / "afile"
    afile.write_text("")
    cases = [
        (["--out", "/proc/o.yaml"], "identify: error: /proc/o.yaml: cannot write in /proc"),
        (
            ["--out", f"{afile}/o.yaml"],
            f"identify: error: {shown(f'{afile}/o.yaml')}: {shown(afile)} is not a directory",
        ),
        (["--out", str(tmp_path)], f"identify: error: {shown(tmp_path)}: is a directory"),
        (
            ["--out", f"{tmp_path}/o.yaml", "--plots", f"{afile}/p"],
            f"{shown(f'{afile}/p')}: {shown(afile)} is not a directory",
        ),
        (["--out", f"{tmp_path}/o.yaml", "--cutoff", "inf"], "argument --cutoff: must be a finite number, got 'inf'"),
        (["--out", f"{tmp_path}/o.yaml", "--held-out", "1"], "--held-out: must be < 1, got 1"),
        (["--out", f"{tmp_path}/o.yaml", "--prior-weight", "-1"], "argument --prior-weight: must be > 0, got -1"),
        (["--out", f"{tmp_path}/o.yaml", "--min-speed", "nan"], "argument --min-speed: must be a finite number"),
    ]
    for args, problem in cases:
        assert identify_tool.main([str(workflow["bag"]), *args, "--quiet"]) in (1, 2)
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and problem in err[0], (args, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


@pytest.mark.parametrize("mode", [[], ["--payload-only"]])
def test_an_input_reached_by_another_path_is_not_overwritten(tmp_path, capsys, mode):
    """--out naming an input through a linked folder or a hard link: refused, the input kept."""
    from ..support.paths import ROOT

    arm = tmp_path / "arms" / "arm.yaml"
    arm.parent.mkdir()
    arm.write_text((ROOT / "config" / "true_arm.yaml").read_text())
    (tmp_path / "linked").symlink_to(arm.parent)
    recording = tmp_path / "run.csv"
    recording.write_text("time\n")
    (tmp_path / "hard.csv").hardlink_to(recording)
    before = arm.read_text()
    cases = [
        (["--params-file", str(tmp_path / "linked" / "arm.yaml"), str(recording), "--out", str(arm)], "arm.yaml"),
        (["--params-file", str(arm), str(recording), "--out", str(tmp_path / "hard.csv")], "run.csv"),
    ]
    for args, given in cases:
        assert identify_tool.main([*mode, *args, "--quiet"]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "would replace the input" in err[0], err
        assert err[0].split("would replace the input")[1].split(";")[0].endswith(given), err
    assert arm.read_text() == before and recording.read_text() == "time\n"
