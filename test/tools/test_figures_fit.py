"""Every picture the package writes shows its whole title and labels: each figure saved by
the demo's plot, identify's plots, retime's plot and the docs' marker preview has every
text's tight bounding box inside the figure's (checked as savefig is called)."""

import runpy
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from irb140_dynamics.core import irb140  # noqa: E402
from irb140_dynamics.core.io.trajectory_file import read_joint_trajectory  # noqa: E402
from irb140_dynamics.core.regressor import inertial_parameters  # noqa: E402
from irb140_dynamics.core.trajectories.limits import trajectory_limits  # noqa: E402
from irb140_dynamics.core.trajectories.message import Trajectory  # noqa: E402
from irb140_dynamics.figures import fit_text, texts_outside  # noqa: E402
from irb140_dynamics.identification.plots import write_plots  # noqa: E402
from irb140_dynamics.nodes.demo_node.node import DemoNode  # noqa: E402
from irb140_dynamics.tools.retime_plot import limit_use_png  # noqa: E402

from ..support.paths import ROOT  # noqa: E402

LONG = "/home/someone/a/rather/deep/folder/of/recordings/" + "x" * 40 + "/config/true_arm.yaml"
LABEL = f"id_node on {LONG}, sim_node a 'true' IRB-140 (config/true_arm.yaml)"  # as run.sh --demo gives it


@pytest.fixture
def saved(monkeypatch):
    """The texts outside each figure saved from now on (one list per figure)."""
    checked, save = [], Figure.savefig

    def checking(figure, *args, **kwargs):
        checked.append(texts_outside(figure))
        return save(figure, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", checking)
    return checked


def test_the_check_fails_on_a_title_wider_than_its_figure():
    figure, axis = plt.subplots(figsize=(4, 3))
    figure.suptitle(LABEL)
    axis.set_ylabel("q [rad]")
    figure.tight_layout()
    assert texts_outside(figure) == [LABEL]
    fit_text(figure)
    assert texts_outside(figure) == []
    plt.close(figure)


def test_the_demo_plot(saved, tmp_path):
    t = np.linspace(0.0, 8.0, 200)
    history = [(x, np.full(6, np.sin(x)), np.full(6, np.sin(x) + 0.01)) for x in t]
    demo = SimpleNamespace(_history=history, _recent=[1], label=LABEL, plot_file=str(tmp_path / "demo.png"))
    assert DemoNode.write_plot(demo) == demo.plot_file
    assert saved == [[]]


def test_identify_plots(saved, tmp_path):
    model, rng = irb140(), np.random.default_rng(0)
    count = 300
    points = SimpleNamespace(
        time=np.linspace(0.0, 3.0, count),
        q=rng.uniform(-1, 1, (count, 6)),
        qd=rng.uniform(-1, 1, (count, 6)),
        qdd=rng.uniform(-1, 1, (count, 6)),
        tau=rng.normal(0, 10, (count, 6)),
    )
    result = SimpleNamespace(
        plot_points=_Sized(points, count),
        prior=model,
        fit=SimpleNamespace(pi=inertial_parameters(model)),
        held_out_source=LONG,
    )
    assert write_plots(result, tmp_path) == ["torques.png", "residuals.png"]
    assert saved == [[], []]


def test_retime_plot(saved):
    model = irb140()
    trajectory = Trajectory.from_message(
        read_joint_trajectory(ROOT / "docs" / "trajectory_example.yaml"), model.joint_names
    )
    assert limit_use_png(model, trajectory_limits(model), trajectory, trajectory)[:4] == b"\x89PNG"
    assert saved == [[]]


def test_the_marker_preview(saved, tmp_path):
    script = ROOT / "docs" / "marker_preview.py"
    recording = ROOT / "docs" / "examples" / "markers.json"
    preview = runpy.run_path(str(script))
    out = tmp_path / "preview.png"
    preview["draw"](recording, out)
    assert out.stat().st_size > 0 and saved == [[]]


class _Sized:
    """The plot points: arrays by name, and a length."""

    def __init__(self, points, count):
        self.__dict__.update(points.__dict__)
        self._count = count

    def __len__(self):
        return self._count
