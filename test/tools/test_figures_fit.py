"""Every picture the package writes reads at a glance: each figure saved by the load
diagram, the demo's plot, identify's plots, retime's plot and the docs' marker preview
passes ``figures.figure_problems`` as savefig is called (at least 1000 px wide, a title,
every text inside the figure and its axes, none over another or upside down, round ticks),
names what it drew in its title, and keys its colours (a legend, a colour bar)."""

import runpy
from types import SimpleNamespace

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from irb140_dynamics.core import RigidBody, irb140  # noqa: E402
from irb140_dynamics.core.io.trajectory_file import read_joint_trajectory  # noqa: E402
from irb140_dynamics.core.monitoring.tracking import TrackingLog  # noqa: E402
from irb140_dynamics.core.payload.diagram import DiagramPoint, LoadDiagram  # noqa: E402
from irb140_dynamics.core.regressor import inertial_parameters  # noqa: E402
from irb140_dynamics.core.trajectories.limits import trajectory_limits  # noqa: E402
from irb140_dynamics.core.trajectories.message import Trajectory  # noqa: E402
from irb140_dynamics.figures import clear_legend, figure_problems, fit_text, texts_outside  # noqa: E402
from irb140_dynamics.identification.plots import write_plots  # noqa: E402
from irb140_dynamics.nodes.demo_node.node import DemoNode  # noqa: E402
from irb140_dynamics.tools.load_diagram_plot import diagram_png  # noqa: E402
from irb140_dynamics.tools.retime_plot import limit_use_png, what_was_drawn  # noqa: E402

from ..support.paths import ROOT  # noqa: E402

LONG = "/home/someone/a/rather/deep/folder/of/recordings/" + "x" * 40 + "/config/true_arm.yaml"
LABEL = f"id_node on {LONG}, sim_node a 'true' IRB-140 (config/true_arm.yaml)"  # as run.sh --demo gives it


@pytest.fixture
def saved(monkeypatch):
    """Each figure saved from now on: its problems (one list per figure), and the figure."""
    checked, save = [], Figure.savefig

    def checking(figure, *args, **kwargs):
        checked.append(figure_problems(figure, kwargs.get("dpi")))
        figures.append(figure)
        return save(figure, *args, **kwargs)

    figures = []
    monkeypatch.setattr(Figure, "savefig", checking)
    checking.figures = figures
    return SimpleNamespace(problems=checked, figures=figures)


def titles_of(figure) -> str:
    return " ".join([figure.get_suptitle()] + [a.get_title() for a in figure.axes])


def legends_of(figure) -> list[str]:
    legends = figure.legends + [a.get_legend() for a in figure.axes if a.get_legend() is not None]
    return [t.get_text() for legend in legends for t in legend.get_texts()]


def test_the_check_finds_each_defect():
    """The defects of the pictures before this check, each found; a clean figure passes."""
    figure, axis = plt.subplots(figsize=(6.4, 4.8))
    axis.set_title("a title")
    axis.plot([7.932, 8.297, 8.662], [1.0, 1.25, 2.0])
    axis.set_xticks([7.932, 8.297, 8.662])
    axis.set_yticks([1.0, 1.25, 1.5, 2.0])  # uneven, as the colour bar's steps were
    axis.text(8.3, 1.5, "8.66268 kg", rotation=170)
    axis.text(8.3, 1.5, "over it")
    axis.text(8.66, 2.0, "cut by the axes", clip_on=True)
    problems = figure_problems(figure, dpi=80)
    assert "512 px wide, under 1000" in problems
    assert any(p.startswith("ticks not round") and "(x): [7.932, 8.297, 8.662]" in p for p in problems)
    assert any(p.startswith("ticks not round") and "(y): [1.0, 1.25, 1.5, 2.0]" in p for p in problems)
    assert "upside down: '8.66268 kg'" in problems
    assert "over each other: '8.66268 kg' and 'over it'" in problems
    assert "cut by its axes: 'cut by the axes'" in problems
    plt.close(figure)
    clean, axis = plt.subplots(figsize=(10, 5))
    axis.plot([0.0, 0.3], [2.5, 2.75])
    assert figure_problems(clean) == ["no title"]
    axis.set_title("clean")
    assert figure_problems(clean) == []
    plt.close(clean)


def test_the_check_finds_a_legend_over_data_and_negative_ticks_of_positive_data():
    """A legend over a line's trough, over bars, over a scatter point, over a contour line
    (real_arm.png's, the load diagram's), and negative ticks beside a quantity >= 0 (a
    one-point load diagram's axes), each found; the same figures with the legend beside
    the data and the view from 0 pass."""
    t = np.linspace(0.0, 25.0, 500)
    figure, (line, bars, points, contours) = plt.subplots(1, 4, figsize=(16, 4))
    line.plot(t, 35 * np.sin(t), label="measured")
    line.legend(loc="lower left")  # over the trough at t = 4.7 s
    bars.bar([1, 2, 3], [40.0, 3.0, 25.0], label="URDF prior")
    bars.legend(loc="upper left")  # over the first bar
    points.plot([0.0, 0.29], [0.0, 0.29], "x", label="unproven")
    points.legend(loc="upper right")  # over the crossed point in the corner
    x, y = np.meshgrid(np.linspace(0, 1, 20), np.linspace(0, 1, 20))
    contours.contour(x, y, x + y, levels=[1.0, 1.9])
    contours.plot([], [], "k", label="a contour")
    contours.legend(loc="upper right")  # over the level 1.9
    for axis in (line, bars, points, contours):
        axis.set_title(axis.get_legend().get_texts()[0].get_text())
    legends = [p for p in figure_problems(figure) if p.startswith("legend over data")]
    assert legends == [
        "legend over data: 'measured'",
        "legend over data: 'URDF prior'",
        "legend over data: 'unproven'",
        "legend over data: 'a contour'",
    ], legends
    for axis in (line, bars, points, contours):
        axis.get_legend().remove()
    figure.legend(*line.get_legend_handles_labels(), loc="upper right")  # over no axes
    assert not [p for p in figure_problems(figure) if p.startswith("legend over data")]
    plt.close(figure)
    single, axis = plt.subplots(figsize=(10, 5))
    axis.set_title("one point at L = 0, Z = 0")
    axis.scatter([0.0], [0.0])  # matplotlib centres the view on it, either side of 0
    assert [p for p in figure_problems(single) if p.startswith("negative ticks")] == [
        "negative ticks [-0.04, -0.02] on one point at L = 0, Z = 0 (x), its data all >= 0",
        "negative ticks [-0.04, -0.02] on one point at L = 0, Z = 0 (y), its data all >= 0",
    ]
    axis.set_xlim(-0.004, 0.104)
    axis.set_ylim(-0.004, 0.104)
    assert figure_problems(single) == []
    axis.plot([0.0, 1.0], [-0.5, 0.5])  # a signed quantity: its negative ticks are fine
    axis.relim()
    axis.autoscale()
    assert figure_problems(single) == []
    plt.close(single)


def test_a_legend_is_put_where_it_covers_no_data():
    """Lines along the top and the bottom and a dashed line across the middle (the spec-sheet
    form's rated payload): matplotlib's "best" still covers one; clear_legend finds a free
    place inside, else puts it beside the axes."""
    x = np.linspace(0.0, 1.0, 50)
    for middle in (True, False):
        figure, axis = plt.subplots(figsize=(10, 5))
        axis.set_title("lines at the top and the bottom" + (", one across the middle" if middle else ""))
        axis.plot(x, 0.1 + 0.1 * x, "o-", label="low")
        axis.plot(x, 0.9 - 0.1 * x, "o-", label="high")
        if middle:
            axis.axhline(0.5, color="tab:red", linestyle="--", label="rated")
        axis.legend(loc="lower center")
        assert [p for p in figure_problems(figure) if p.startswith("legend over data")], "the check misses it"
        fit_text(figure)
        legend = clear_legend(axis)
        assert figure_problems(figure) == []
        inside = legend.get_window_extent().x1 <= axis.get_window_extent().x1
        assert inside is not middle  # free places inside when nothing crosses the middle
        plt.close(figure)


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
    log = TrackingLog()
    for k, x in enumerate(t):
        log.state(k, np.full(6, np.sin(x) + 0.01))
        log.error(x, k, np.full(6, -0.01))
    demo = SimpleNamespace(log=log, label=LABEL, plot_file=str(tmp_path / "demo.png"))
    assert DemoNode.write_plot(demo) == demo.plot_file
    assert saved.problems == [[]]
    figure = saved.figures[0]
    assert "tracking" in titles_of(figure) and "error" in titles_of(figure)
    assert sum("error [mrad]" in a.get_ylabel() for a in figure.axes) == 6  # the error over time, per joint
    assert {"reference", "actual"} <= set(legends_of(figure))


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
        held_out_source="the last 20 % of the moving fit points of the recording",
        tallies=[SimpleNamespace(path=LONG)],
    )
    points.tau[10, 0] = 3.5  # a point above the rest: shown, not cut, not under the legend
    assert write_plots(result, tmp_path, "ur5 from ur5.urdf (world -> tool0)") == ["torques.png", "residuals.png"]
    assert saved.problems == [[], []]
    for figure in saved.figures:
        title = figure.get_suptitle().replace("\n", " ")  # (wrapped at spaces to fit)
        assert "of ur5 from ur5.urdf (world -> tool0) on held-out data" in title, title  # the arm
        assert f"of the recording {LONG}" in title, title  # the recording, by its path
        top = figure.axes[0]
        assert top.get_ylim()[1] >= 3.5 - 0.0  # (the residuals: 3.5 less a prediction, within the view)
        legend = legends_of(figure)
        assert legend and all(a.get_legend() is None for a in figure.axes)  # one legend, above the panels


def test_the_real_arm_picture(saved, tmp_path):
    """docs/real_arm.py's picture (drawn on the arm's torques, here a sine with a trough
    where its legend stood): the arm and the recordings in the title, one legend over no data."""
    model, count = irb140(), 400
    time = np.linspace(0.0, 25.0, count)
    q = np.column_stack([np.sin(time + k) for k in range(6)])
    tau = np.column_stack([35 * np.sin(time)] * 6)
    points = SimpleNamespace(time=time, q=q, qd=np.cos(q), qdd=-q, tau=tau)
    result = SimpleNamespace(prior=model, plot_points=points, fit=SimpleNamespace(pi=inertial_parameters(model)))
    pi = inertial_parameters(model)
    moving = {
        label: np.array([0.4, 0.04, 0.25, 0.06, 0.5, 0.9]) * k
        for k, label in enumerate(("URDF prior", "plain LS", "ours"), 1)
    }
    script = runpy.run_path(str(ROOT / "docs" / "real_arm.py"))
    script["plot"](result, pi, pi, moving, np.ones(6), tmp_path / "real_arm.png")
    assert saved.problems == [[]]
    title = titles_of(saved.figures[0])
    assert all(name in title for name in ("KUKA LWR4+", "kuka_lwr4.urdf", "traj1", "traj3")), title
    assert legends_of(saved.figures[0]) == ["measured", "URDF prior", "plain LS", "ours"]


def test_retime_plot(saved):
    model = irb140()
    trajectory = Trajectory.from_message(
        read_joint_trajectory(ROOT / "docs" / "trajectory_example.yaml"), model.joint_names
    )
    title = what_was_drawn("trajectory_example.yaml", "irb140.yaml", RigidBody(2.0, (0.0, 0.0, 0.1)))
    assert limit_use_png(model, trajectory_limits(model), trajectory, trajectory, title)[:4] == b"\x89PNG"
    assert saved.problems == [[]]
    assert "trajectory_example.yaml on irb140.yaml, payload 2 kg, CoM (0, 0, 0.1) m" in titles_of(saved.figures[0])
    assert {"torque (% of its limit)", "velocity (% of its limit)"} <= set(legends_of(saved.figures[0]))


def test_the_marker_preview(saved, tmp_path):
    script = ROOT / "docs" / "marker_preview.py"
    recording = ROOT / "docs" / "examples" / "markers.json"
    preview = runpy.run_path(str(script))
    out = tmp_path / "preview.png"
    preview["draw"](recording, out)
    assert out.stat().st_size > 0 and saved.problems == [[]]
    figure = saved.figures[0]
    assert "markers.json" in titles_of(figure)
    assert any("payload" in text for text in legends_of(figure))  # what each colour means
    assert any(a.get_label() == "<colorbar>" for a in figure.axes)  # the load's colour scale


def synthetic_diagram(z, l, low, high, unproven=()):
    """A diagram whose masses fall from ``high`` at the flange to ``low`` at the far corner,
    as an arm's do (the figure's checks need not wait for proofs)."""
    points = []
    for zi in z:
        for li in l:
            share = np.hypot(zi / max(z[-1], 1e-9), li / max(l[-1], 1e-9)) / np.sqrt(2)
            mass = high - (high - low) * share**0.7
            points.append(DiagramPoint(zi, li, mass, (zi, li) not in unproven, 3, "", mass * 1.005))
    names = tuple(f"joint_{k}" for k in range(1, 7))
    return LoadDiagram(names, np.ones(6), np.asarray(z), np.asarray(l), tuple(points))


ARMS = {  # the mass ranges of the arms whose pictures read badly: UR5 7.932-8.663 kg, Panda 2.5985-2.7276 kg
    "irb140.yaml": (1.0, 5.97, 6.0),
    "ur5.urdf (world -> tool0)": (7.932, 8.66268, None),
    "panda.urdf (panda_link0 -> panda_hand_tcp)": (2.5985, 2.7276, 3.0),
}


@pytest.mark.parametrize("arm", sorted(ARMS))
def test_the_load_diagram(saved, arm):
    low, high, rated = ARMS[arm]
    z, l = np.arange(31) * 0.01, np.arange(21) * 0.01
    png = diagram_png(synthetic_diagram(z, l, low, high, unproven={(0.3, 0.2)}), arm, rated)
    assert png[:4] == b"\x89PNG"
    assert saved.problems == [[]]
    figure = saved.figures[0]
    assert arm in titles_of(figure) and "spec-sheet form" in titles_of(figure)
    if rated is None:  # marked only where the arm states one
        assert "no rated payload stated" in titles_of(figure)
        assert not any("rated" in text for text in legends_of(figure))
    else:
        assert f"rated {rated:g} kg" in legends_of(figure)
    assert "unproven (the mass a pose found)" in legends_of(figure)
    assert sum(t.startswith("L = ") for t in legends_of(figure)) == 5  # the spec-sheet form: a few L
    assert any(a.get_label() == "<colorbar>" for a in figure.axes)
    contour_labels = [t.get_text() for t in figure.axes[0].texts if t.get_text().endswith(" kg")]
    assert len(contour_labels) >= 3, contour_labels


def test_a_load_diagram_of_one_row_and_of_one_point(saved):
    shapes = (([0.0, 0.1, 0.2], [0.0]), ([0.1], [0.05]), ([0.0], [0.0]))
    for z, l in shapes:
        diagram_png(synthetic_diagram(z, l, 2.0, 3.0), "arm.urdf", 6.0)
    assert saved.problems == [[]] * len(shapes)  # no negative Z or L, no legend over a point
    for figure in saved.figures:
        plane, sheet = figure.axes[:2]  # (then the colour bar)
        for low, high in (plane.get_xlim(), plane.get_ylim(), sheet.get_xlim()):  # L and Z: from 0
            assert -0.05 * high < low <= 0.0 < high


class _Sized:
    """The plot points: arrays by name, and a length."""

    def __init__(self, points, count):
        self.__dict__.update(points.__dict__)
        self._count = count

    def __len__(self):
        return self._count
