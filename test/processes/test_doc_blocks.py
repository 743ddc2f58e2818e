"""Every command block of README.md and docs/*.md, run as a user would type it (see doc_blocks)."""

from __future__ import annotations

import hashlib
import itertools
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from ..support.doc_blocks import (
    Block,
    console_scripts,
    doc_files,
    first_word,
    is_synopsis,
    logical_lines,
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


SETUP = ROOT / "scripts" / "setup.sh"
SETUP_TIMEOUT = 1800.0  # s: the README's set-up on a fresh clone (pip downloads, colcon build)
SHELL_ONLY = ("PWD", "OLDPWD", "SHLVL", "_")  # what bash sets for itself


def users_shell() -> dict:
    """The environment of a new terminal: the test's own, less what puts its interpreter
    or a workspace on the paths (a user's shell has neither before the set-up)."""
    own = {str(Path(sys.executable).parent), os.path.join(sys.prefix, "bin")}
    if os.environ.get("VIRTUAL_ENV"):
        own.add(os.path.join(os.environ["VIRTUAL_ENV"], "bin"))
    shell = {
        key: value
        for key, value in os.environ.items()
        if key not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "AMENT_PREFIX_PATH", "COLCON_PREFIX_PATH")
    }
    shell["PATH"] = os.pathsep.join(d for d in os.environ["PATH"].split(os.pathsep) if d and d not in own)
    return shell


@pytest.fixture(scope="module")
def environment(tmp_path_factory) -> dict:
    """The shell the README leaves: its set-up run (scripts/setup.sh, what run.sh runs
    first), then `source .venv/bin/activate && source install/setup.bash`. The harness adds
    settings of no executable, nothing to PATH: a command the set-up does not install (the
    ros2 CLI included) is not found."""
    shell = users_shell()
    done = subprocess.run([str(SETUP)], cwd=ROOT, env=shell, capture_output=True, text=True, timeout=SETUP_TIMEOUT)
    assert done.returncode == 0, f"scripts/setup.sh exited {done.returncode}:\n{done.stdout}{done.stderr}"
    sourced = subprocess.run(
        ["bash", "-c", "source .venv/bin/activate && source install/setup.bash && env -0"],
        cwd=ROOT,
        env=shell,
        capture_output=True,
        timeout=60,
    )
    assert sourced.returncode == 0, sourced.stderr.decode(errors="replace")
    env = dict(item.split("=", 1) for item in sourced.stdout.decode().split("\0") if "=" in item)
    for key in SHELL_ONLY:
        env.pop(key, None)
    return {
        **env,
        "PYTHONUNBUFFERED": "1",
        "MPLBACKEND": "Agg",
        # a benchmark a doc shows writes its figures here, not over the clone's bench/results
        "IRB140_BENCH_RESULTS": str(tmp_path_factory.mktemp("bench_results")),
    }


def node_of(line: str) -> str | None:
    """The node a line starts, or None."""
    words = line.split()
    if "--help" in words or "-h" in words:
        return None  # usage, not a node
    return words[0] if words and words[0] in NODES else None


NOT_FOUND = 127  # bash's exit status for a command not found


def run_shell(script: str, cwd: Path, env: dict, timeout: float = LINE_TIMEOUT) -> tuple[int, str]:
    """Run ``script`` in bash, in a session of its own: on a timeout the whole session is
    killed (a command it started, e.g. a ``python - <<EOF`` waiting on a topic, included),
    so that nothing of a hung block lives on into the next ones (its DDS participant would)."""
    shell = subprocess.Popen(
        ["bash", "-e", "-o", "pipefail", "-c", script],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        stdout, stderr = shell.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(shell.pid, signal.SIGKILL)
        stdout, stderr = shell.communicate()
        return -1, f"still running after {timeout:g} s: {stdout}{stderr}"
    if shell.returncode == NOT_FOUND:
        return NOT_FOUND, f"command not found (exit 127) after the README's set-up:\n{stdout}{stderr}"
    return shell.returncode, stdout + stderr


HELPS: dict[tuple[str, Path], tuple[int, str]] = {}  # (program, clone): its --help, run once per doc


def check_synopsis(line: str, cwd: Path, env: dict) -> str | None:
    """A usage synopsis: its executable's --help exits 0 and names every option it shows
    (a doc showing a program's synopsis twice: its --help run once)."""
    program = line.split(" [", 1)[0].strip()  # what comes before the first optional part
    if (program, cwd) not in HELPS:
        HELPS[program, cwd] = run_shell(f"{program} --help", cwd, env, timeout=HELP_TIMEOUT)
    code, output = HELPS[program, cwd]
    if code != 0 or "Traceback" in output:
        return f"`{program} --help` exited {code}:\n{output}"
    missing = [option for option in synopsis_options(line) if option not in output and option not in ("-h",)]
    if missing:
        return f"`{program} --help` does not mention {missing} of the synopsis `{line}`"
    return None


HEREDOC_JOB = re.compile(r"<<-?\s*'?(\w+)'?\s*&$")  # COMMAND <<'EOF' &: a here-document's command in the background


def shell_commands(text: str) -> list[str]:
    """logical_lines, with a here-document run in the background (``COMMAND <<'EOF' &``,
    its lines, ``EOF``) joined into one command (``COMMAND <<'EOF'``, lines, ``EOF``, ``&``)."""
    commands, lines = [], iter(logical_lines(text))
    for line in lines:
        heredoc = HEREDOC_JOB.search(line)
        if heredoc:
            body = list(itertools.takewhile(lambda body_line, end=heredoc[1]: body_line != end, lines))
            line = "\n".join([line[:-1].rstrip(), *body, heredoc[1]]) + " &"
        commands.append(line)
    return commands


def background_job(line: str) -> str | None:
    """The command of a line run in the background (``COMMAND &``), or None."""
    return line[:-1].strip() if line.endswith("&") and not line.endswith("&&") else None


def waits_for_the_last_job(line: str) -> bool:
    """``wait $!`` (a comment after it allowed)."""
    return line.split("#", 1)[0].split() == ["wait", "$!"]


def wait_for_job(job: tuple, timeout: float = LINE_TIMEOUT) -> str | None:
    """``wait $!`` on a job started by run_block: None when it exits 0, else what went wrong."""
    line, process, output = job
    try:
        code = process.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"`{line}` still running after {timeout:g} s"
    output.seek(0)
    return None if code == 0 else f"`{line}` exited {code}:\n{output.read()}"


def run_block(block: Block, cwd: Path, env: dict) -> str | None:
    """None when the block ran as the doc says, else what went wrong. A node runs as in a
    terminal of its own (until its 'ready'); ``COMMAND &`` (a here-document's included)
    runs in the background, and ``wait $!`` waits for the last one, as in the user's shell;
    the lines between, in a shell, one after the other."""
    if block.kind == "python":
        done = subprocess.run(  # the python of the user's shell: .venv's
            ["python", "-c", block.text], cwd=cwd, env=env, capture_output=True, text=True, timeout=LINE_TIMEOUT
        )
        return None if done.returncode == 0 else f"exit {done.returncode}:\n{done.stdout}{done.stderr}"
    nodes, jobs, pending = [], [], []
    try:
        for line in shell_commands(block.text):
            job = background_job(line)
            if job is None and is_synopsis(line):
                problem = check_synopsis(line, cwd, env)
                if problem:
                    return problem
                continue
            if node_of(line) is None and job is None and not waits_for_the_last_job(line):
                pending.append(line)
                continue
            if pending:
                code, output = run_shell("\n".join(pending), cwd, env)
                if code != 0:
                    return f"exit {code} of:\n{chr(10).join(pending)}\n{output}"
                pending = []
            if job is not None:
                output = tempfile.TemporaryFile("w+")  # noqa: SIM115  (closed in the finally below)
                process = subprocess.Popen(
                    ["bash", "-c", f"exec {job}"], cwd=cwd, env=env, stdout=output, stderr=subprocess.STDOUT, text=True
                )
                jobs.append((line.split("\n", 1)[0], process, output))
                continue
            if waits_for_the_last_job(line):
                problem = wait_for_job(jobs[-1]) if jobs else "`wait $!` with no job started"
                if problem:
                    return problem
                continue
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
        for line, process, output in jobs:  # one still running (not waited for): Ctrl-C, as to the nodes
            code = process.returncode if process.poll() is not None else interrupt(process)[0]
            output.seek(0)
            stopped.append((line, code, output.read()))
            output.close()
    for line, code, output in stopped:
        if code != 0 or "Traceback" in output:
            return f"`{line}` exited {code} on Ctrl-C:\n{output}"
    return None


def tracked_files() -> list[str]:
    """The clone's files, as its developer has them: tracked, and new ones not ignored (those
    present: one deleted in the working tree is not copied)."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        check=True,
        timeout=60,
    )
    return [name for name in listed.stdout.decode().split("\0") if name and (ROOT / name).is_file()]


def digest(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def clone_copy(directory: Path) -> dict[str, str | None]:
    """The user's clone, in ``directory``: a copy of the tracked files as they are now (so
    that what a walkthrough writes cannot reach this clone), with the set-up's .venv and
    install/ linked. Returns each tracked file's digest."""
    digests = {}
    for name in tracked_files():
        target = directory / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, target)
        digests[name] = digest(target)
    for name in (".venv", "install"):
        (directory / name).symlink_to(ROOT / name, target_is_directory=True)
    return digests


@pytest.mark.parametrize("doc", DOCS, ids=lambda path: path.name)
def test_every_command_block_runs_as_typed(doc, environment, tmp_path):
    """Each block as typed, in the clone's folder (a copy of it); what it writes goes beside
    the tracked files, never over one (git would see it, and the next user meet it)."""
    failures, ran = [], 0
    clone = tmp_path / "clone"
    tracked = clone_copy(clone)
    for name in doc_files(doc):
        shutil.copy(ROOT / name, clone / Path(name).name)
    for block in runnable(doc):
        if block.skip:
            continue
        problem = run_block(block, clone, environment)
        ran += 1
        if problem:
            failures.append(f"{block.where} ({first_word(block.text)} ...): {problem}")
    assert not failures, "\n\n".join(failures)
    changed = sorted(name for name, before in tracked.items() if digest(clone / name) != before)
    assert not changed, f"{doc.name}'s blocks wrote over tracked files: {changed}"


def test_most_command_blocks_really_run():
    """Skips are for what needs a full ROS install; each says why, and they stay few."""
    blocks = [b for b in all_blocks() if b.kind in ("shell", "python")]
    skipped = [b for b in blocks if b.skip]
    assert blocks and len(skipped) <= len(blocks) // 2, [f"{b.where}: {b.skip}" for b in skipped]
