"""Every command block of README.md and docs/*.md, run as a user would type it (see doc_blocks)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ..support.doc_blocks import (
    Block,
    console_scripts,
    doc_files,
    first_word,
    is_synopsis,
    logical_lines,
    make_bin,
    read_blocks,
    synopsis_options,
)
from ..support.node_process import interrupt, wait_for_line
from ..support.paths import ROOT

pytestmark = [pytest.mark.process, pytest.mark.slow]

SCRIPTS = console_scripts(ROOT / "setup.py")
NODES = {name for name in SCRIPTS if name.endswith("_node")}
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINE_TIMEOUT = 300.0  # s: a foreground command (identify on a long recording included)
HELP_TIMEOUT = 60.0  # s: --help starts no ROS
READY_TIMEOUT = 60.0  # s: a node's "ready" on a loaded machine


def all_blocks() -> list[Block]:
    return [block for doc in DOCS for block in read_blocks(doc, set(SCRIPTS) | {"ros2"})]


def runnable(doc: Path) -> list[Block]:
    return [b for b in read_blocks(doc, set(SCRIPTS) | {"ros2"}) if b.kind in ("shell", "python")]


@pytest.fixture(scope="module")
def environment(tmp_path_factory) -> dict:
    bin_dir = make_bin(tmp_path_factory.mktemp("bin"), sys.executable, SCRIPTS)
    return {
        **os.environ,
        "PATH": f"{bin_dir}{os.pathsep}{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}",
        "PYTHONPATH": str(ROOT),
        "PYTHONUNBUFFERED": "1",
        "MPLBACKEND": "Agg",
        # a benchmark a doc shows writes its figures here, not over the clone's bench/results
        "IRB140_BENCH_RESULTS": str(tmp_path_factory.mktemp("bench_results")),
    }


def node_of(line: str) -> str | None:
    """The node a line starts (directly or through ros2 run), or None."""
    words = line.split()
    if words[:2] == ["ros2", "run"] and len(words) > 3:
        words = words[3:]
    if "--help" in words or "-h" in words:
        return None  # usage, not a node
    return words[0] if words and words[0] in NODES else None


def run_shell(script: str, cwd: Path, env: dict, timeout: float = LINE_TIMEOUT) -> tuple[int, str]:
    try:
        done = subprocess.run(
            ["bash", "-e", "-o", "pipefail", "-c", script],
            cwd=cwd,
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired as error:
        return -1, f"still running after {timeout:g} s: {error.output or ''}"
    return done.returncode, done.stdout + done.stderr


def check_synopsis(line: str, cwd: Path, env: dict) -> str | None:
    """A usage synopsis: its executable's --help exits 0 and names every option it shows."""
    program = line.split(" [", 1)[0].strip()  # what comes before the first optional part
    code, output = run_shell(f"{program} --help", cwd, env, timeout=HELP_TIMEOUT)
    if code != 0 or "Traceback" in output:
        return f"`{program} --help` exited {code}:\n{output}"
    missing = [option for option in synopsis_options(line) if option not in output and option not in ("-h",)]
    if missing:
        return f"`{program} --help` does not mention {missing} of the synopsis `{line}`"
    return None


def run_block(block: Block, cwd: Path, env: dict) -> str | None:
    """None when the block ran as the doc says, else what went wrong."""
    if block.kind == "python":
        done = subprocess.run(
            [sys.executable, "-c", block.text], cwd=cwd, env=env, capture_output=True, text=True, timeout=LINE_TIMEOUT
        )
        return None if done.returncode == 0 else f"exit {done.returncode}:\n{done.stdout}{done.stderr}"
    nodes, pending = [], []
    try:
        for line in logical_lines(block.text):
            if is_synopsis(line):
                problem = check_synopsis(line, cwd, env)
                if problem:
                    return problem
                continue
            if node_of(line) is None:
                pending.append(line)
                continue
            if pending:
                code, output = run_shell("\n".join(pending), cwd, env)
                if code != 0:
                    return f"exit {code} of:\n{chr(10).join(pending)}\n{output}"
                pending = []
            process = subprocess.Popen(
                ["bash", "-c", f"exec {line}"],
                cwd=cwd,
                env=env,
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
            lines: list[str] = []
            nodes.append((line, process, lines))
            if not wait_for_line(process, "ready", lines, READY_TIMEOUT):
                return f"`{line}` never said ready:\n{''.join(lines)}"
        if pending:
            code, output = run_shell("\n".join(pending), cwd, env)
            if code != 0:
                return f"exit {code} of:\n{chr(10).join(pending)}\n{output}"
    finally:
        stopped = [(line, *interrupt(process, lines)) for line, process, lines in reversed(nodes)]
    for line, code, output in stopped:
        if code != 0 or "Traceback" in output:
            return f"`{line}` exited {code} on Ctrl-C:\n{output}"
    return None


CLONE = (".venv", "config", "urdf", "bench", "test", "scripts")  # what a block may name as in the clone (linked)


def clone_view(directory: Path) -> Path:
    """A working directory where the doc's relative paths to the clone work (.venv, config, ...)."""
    for name in CLONE:
        target = Path(sys.prefix) if name == ".venv" else ROOT / name
        (directory / name).symlink_to(target, target_is_directory=True)
    return directory


def clone_files() -> dict[str, tuple[int, int]]:
    """path -> (size, mtime) of the clone's files a block can reach through its links."""
    files = {}
    for name in CLONE[1:]:
        for folder, subfolders, names in os.walk(ROOT / name):
            subfolders[:] = [d for d in subfolders if d != "__pycache__"]
            for file in names:
                stat = (Path(folder) / file).stat()
                files[os.path.join(folder, file)] = (stat.st_size, stat.st_mtime_ns)
    return files


@pytest.mark.parametrize("doc", DOCS, ids=lambda path: path.name)
def test_every_command_block_runs_as_typed(doc, environment, tmp_path):
    """Each block as typed; what it writes goes to the user's working folder, never into
    the clone (a second run would meet it, and git would see it)."""
    failures, ran = [], 0
    before = clone_files()
    clone_view(tmp_path)
    for name in doc_files(doc):
        shutil.copy(ROOT / name, tmp_path / Path(name).name)
    for block in runnable(doc):
        if block.skip:
            continue
        problem = run_block(block, tmp_path, environment)
        ran += 1
        if problem:
            failures.append(f"{block.where} ({first_word(block.text)} ...): {problem}")
    assert not failures, "\n\n".join(failures)
    after = clone_files()
    written = sorted(path for path in after if after[path] != before.get(path))
    assert not written, f"{doc.name}'s blocks wrote into the clone: {written}"


def test_most_command_blocks_really_run():
    """Skips are for what needs a full ROS install; each says why, and they stay few."""
    blocks = [b for b in all_blocks() if b.kind in ("shell", "python")]
    skipped = [b for b in blocks if b.skip]
    assert blocks and len(skipped) <= len(blocks) // 2, [f"{b.where}: {b.skip}" for b in skipped]
