"""Every executable is reachable in one line and starts through the entry
(irb140_dynamics.entry): the console scripts of setup.py (a tool's plain name for ``ros2
run`` and its ``irb140-<name>`` for a PyPI install; a node's name), ``python -m`` of each
tool and node; and every tool answers --help / -h with its usage (exit 0), called here
in-process as its console script calls it. test/processes/test_tool_command_lines.py
starts two of them as processes."""

import ast
import importlib
import re
import sys
import types

import pytest

from irb140_dynamics import programs

from ..support.paths import ROOT

TOOLS = {
    "identify": "identify",
    "record": "record",
    "excitation": "excitation",
    "export_urdf": "export-urdf",
    "equations": "equations",
    "retime": "retime",
    "load_diagram": "load-diagram",
    "calibrate_collision": "calibrate-collision",
}
NODES = ("id_node", "payload_check_node", "sim_node", "demo_node", "trajectory_check_node")
FULL_ARGV = {"record", "export_urdf"}  # their main() takes argv with the program first (ROS arguments)


def entry_points() -> dict[str, str]:
    text = (ROOT / "setup.py").read_text()
    return dict(re.findall(r'"([\w-]+) = ([\w.]+:\w+)"', text))


def test_every_tool_has_both_console_scripts_through_the_entry():
    scripts = entry_points()
    for module, name in TOOLS.items():
        target = f"irb140_dynamics.programs:{module}"
        assert scripts.get(module) == target and scripts.get(f"irb140-{name}") == target, scripts
        assert callable(getattr(programs, module))
    for node in NODES:
        assert scripts.get(node) == f"irb140_dynamics.programs:{node}", scripts
        assert callable(getattr(programs, node))
    targets = {target for target in scripts.values()}
    assert len(scripts) == 2 * len(TOOLS) + len(NODES) and len(targets) == len(TOOLS) + len(NODES), scripts


def test_a_node_starts_through_the_entry_before_its_imports(monkeypatch):
    """The node's console script starts the entry (its stop signals noted) before it
    imports the node's module, then runs that module's main()."""
    name = "irb140_dynamics.nodes.sim_node.node"
    node_module = types.SimpleNamespace(main=lambda: 0)
    monkeypatch.setitem(sys.modules, name, node_module)  # undone after the test, as it was
    monkeypatch.delitem(sys.modules, name)
    calls = []

    def start(program, kind):
        calls.append(("start", program, kind, name in sys.modules))
        sys.modules[name] = node_module  # what the import then finds

    monkeypatch.setattr(programs, "start", start)
    monkeypatch.setattr(programs, "finish", lambda main: calls.append(("finish", main)))
    programs.sim_node()
    assert calls == [("start", "sim_node", programs.NODE, False), ("finish", node_module.main)], calls


def main_guards(path) -> list[str]:
    """The source of each ``if __name__ == "__main__":`` block of a module, in order."""
    source = path.read_text()
    tree = ast.parse(source)
    return [
        ast.get_source_segment(source, node)
        for node in tree.body
        if isinstance(node, ast.If) and ast.unparse(node.test) == "__name__ == '__main__'"
    ]


@pytest.mark.parametrize("module", sorted(TOOLS))
def test_python_m_of_a_tool_starts_the_entry_before_its_imports(module):
    """First statement after the docstring: the entry started; last: finish(main)."""
    path = ROOT / "irb140_dynamics" / "tools" / f"{module}.py"
    tree = ast.parse(path.read_text())
    body = [n for n in tree.body if not (isinstance(n, ast.Expr) and isinstance(n.value, ast.Constant))]
    body = [n for n in body if not (isinstance(n, ast.ImportFrom) and n.module == "__future__")]
    first, last = main_guards(path)[0], main_guards(path)[-1]
    kind = "RECORDER" if module == "record" else "TOOL"
    assert isinstance(body[0], ast.If) and f'start("{module}", {kind})' in first, first
    assert body[-1] is tree.body[-1] and "finish(main)" in last, last


@pytest.mark.parametrize(
    "module",
    # record's arguments are read by rcl first: it needs ROS even for --help
    [pytest.param(module, marks=pytest.mark.ros) if module == "record" else module for module in sorted(TOOLS)],
)
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_prints_usage_and_exits_0(capsys, module, flag):
    main = importlib.import_module(f"irb140_dynamics.tools.{module}").main
    argv = [module, flag] if module in FULL_ARGV else [flag]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert out.startswith(f"usage: {module}") and err == "", (out, err)


def test_record_without_rclpy_says_what_it_needs_in_one_line(monkeypatch, capsys, tmp_path):
    """record subscribes through ROS 2: where rclpy cannot be imported it says so (exit 1),
    not an internal error, and writes nothing."""
    import builtins

    from irb140_dynamics.tools import record

    real_import = builtins.__import__

    def without_rclpy(name, *args, **kwargs):
        if name == "rclpy" or name.startswith("rclpy."):
            raise ModuleNotFoundError("No module named 'rclpy'", name="rclpy")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", without_rclpy)
    for module in [m for m in sys.modules if m.startswith(("rclpy", "irb140_dynamics.ros"))]:
        monkeypatch.delitem(sys.modules, module)
    assert record.main(["record", "--out", str(tmp_path / "run")]) == 1
    err = capsys.readouterr().err
    assert err == "record: error: needs ROS 2 Jazzy's rclpy (rclpy cannot be imported: see the README's set-up)\n"
    assert list(tmp_path.iterdir()) == []
