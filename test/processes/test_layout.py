"""After colcon build: executables and config where `ros2 run` and `ros2 launch` look."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ..support.node_process import run_to_exit, run_until_ready
from ..support.paths import CONFIG, ROOT

EXECUTABLES = ["id_node", "payload_check_node"]
IDENTIFICATION_TOOLS = ["identify", "excitation", "record"]
TOOLS = ["export_urdf", "calibrate_collision", *IDENTIFICATION_TOOLS]
URDF = ROOT / "urdf" / "irb140.urdf"


@pytest.fixture(scope="module")
def install(tmp_path_factory) -> Path:
    """colcon build of this package into a temporary workspace; its install folder."""
    colcon = shutil.which("colcon") or str(Path(sys.executable).parent / "colcon")
    work = tmp_path_factory.mktemp("colcon")
    result = subprocess.run(
        [
            colcon,
            "--log-base",
            str(work / "log"),
            "build",
            "--paths",
            str(ROOT),
            "--build-base",
            str(work / "build"),
            "--install-base",
            str(work / "install"),
        ],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    # compiled once, as scripts/setup.sh compiles its install/: under PYTHONDONTWRITEBYTECODE
    # each executable below would compile the modules it imports from source again
    subprocess.run(
        [sys.executable, "-m", "compileall", "-q", "-j", "0", str(work / "install" / "irb140_dynamics" / "lib")],
        capture_output=True,
        timeout=300,
    )
    return work / "install"


def sourced(install: Path, command: str) -> str:
    """Run a shell command in the environment of the workspace's setup.bash; its output."""
    script = f"source {install}/setup.bash && {command}"
    result = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr
    return result.stdout.strip()


def installed_env(install: Path) -> dict:
    keys = ("AMENT_PREFIX_PATH", "PYTHONPATH", "PATH", "LD_LIBRARY_PATH")
    env = dict(line.split("=", 1) for line in sourced(install, "env").splitlines() if "=" in line)
    return {key: env[key] for key in keys if key in env}


def test_executables_are_where_ros2_run_looks(install):
    prefix = Path(
        sourced(
            install,
            f"{sys.executable} -c "
            "'from ament_index_python import get_package_prefix as p; print(p(\"irb140_dynamics\"))'",
        )
    )
    assert prefix == install / "irb140_dynamics"
    for name in EXECUTABLES + TOOLS:
        executable = prefix / "lib" / "irb140_dynamics" / name
        assert executable.is_file() and os.access(executable, os.X_OK), executable


def test_config_is_in_the_share_directory(install):
    share = Path(
        sourced(
            install,
            f"{sys.executable} -c 'from ament_index_python import "
            'get_package_share_directory as s; print(s("irb140_dynamics"))\'',
        )
    )
    assert (share / "config" / "irb140.yaml").read_text() == CONFIG.read_text()
    assert (share / "urdf" / "irb140.urdf").read_text() == URDF.read_text()
    for launch_file in sorted((ROOT / "launch").glob("*.launch.py")):  # ros2 launch looks in share/<pkg>/launch
        assert (share / "launch" / launch_file.name).read_text() == launch_file.read_text()
    assert (share / "config" / "true_arm.yaml").is_file()  # sim_demo.launch.py's default
    assert (share / "package.xml").is_file()


@pytest.mark.slow
@pytest.mark.parametrize("name", EXECUTABLES)
def test_installed_nodes_run_on_the_installed_config(install, name):
    executable = str(install / "irb140_dynamics" / "lib" / "irb140_dynamics" / name)
    env = installed_env(install)
    code, output = run_until_ready([executable], env=env)
    assert "ready:" in output and str(install / "irb140_dynamics" / "share") in output, output
    assert code == 0, output
    code, output = run_to_exit([executable, "--ros-args", "-p", "joint_6.link.mass:=-1.0"], env=env)
    assert code == 1 and "joint_6.link.mass" in output, output


@pytest.mark.parametrize("name", IDENTIFICATION_TOOLS)
def test_installed_tools_run(install, name):
    executable = str(install / "irb140_dynamics" / "lib" / "irb140_dynamics" / name)
    code, output = run_to_exit([executable, "--help"], env=installed_env(install))
    assert code == 0 and f"usage: {name}" in output and "--out" in output, output


def test_installed_excitation_uses_the_installed_model(install, tmp_path):
    executable = str(install / "irb140_dynamics" / "lib" / "irb140_dynamics" / "excitation")
    out = tmp_path / "excitation.yaml"
    command = [executable, "--out", str(out), "--iterations", "0", "--period", "2", "--harmonics", "2", "--rate", "5"]
    code, output = run_to_exit(command, env=installed_env(install))
    assert code == 0 and f"model: {install / 'irb140_dynamics' / 'share'}" in output, output
    assert out.read_text().count("time_from_start") == 11


def test_installed_export_urdf_prints_the_installed_urdf(install):
    executable = str(install / "irb140_dynamics" / "lib" / "irb140_dynamics" / "export_urdf")
    code, output = run_to_exit([executable], env=installed_env(install))
    assert code == 0 and output == URDF.read_text(), output[:500]


# Run as the installed script runs, an audit hook noting each module imported until the
# executable's entry has its stop signals' handlers in place (then it stops the process).
BEFORE_THE_ENTRY = """
import os, signal, sys
script, out = sys.argv[1], sys.argv[2]
imported = []
def hook(event, args):
    if event == "import":
        if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
            imported.append(args[0])
        else:
            with open(out, "w") as stream:
                stream.write("\\n".join(imported))
            os._exit(0)
sys.addaudithook(hook)
sys.argv = [script, "--help"]
exec(compile(open(script).read(), script, "exec"), {"__name__": "__main__", "__file__": script})
"""
ENTRY_NEEDS = (
    "import os, signal, sys; known = set(sys.modules); import {module}; print(*sorted(set(sys.modules) - known))"
)


@pytest.mark.parametrize("name", ["identify", "excitation", "id_node"])
def test_an_installed_executable_notes_a_ctrl_c_from_its_first_import(install, tmp_path, name):
    """What the installed script imports before the entry notes stop signals is what the
    entry itself needs (the package's light modules): a Ctrl-C there, before the heavy
    imports, is noted (one line, exit 130) rather than a traceback. setuptools' own script
    scanned every installed distribution (importlib.metadata, 0.1 to 0.2 s) first."""
    executable = install / "irb140_dynamics" / "lib" / "irb140_dynamics" / name
    module = dict(re.findall(r'"([\w-]+) = ([\w.]+):\w+"', (ROOT / "setup.py").read_text()))[name]
    env = installed_env(install)
    run = subprocess.run(
        [sys.executable, "-c", ENTRY_NEEDS.format(module=module)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    needs = set(run.stdout.split())
    out = tmp_path / "imported.txt"
    run = subprocess.run(
        [sys.executable, "-c", BEFORE_THE_ENTRY, str(executable), str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0 and out.exists(), run.stdout + run.stderr
    imported = set(out.read_text().split())
    assert imported and imported <= needs, sorted(imported - needs)
    assert "importlib.metadata" not in imported and not any(m.startswith("irb140_dynamics.core") for m in imported)
