"""What a process that does not end is doing: for it and its descendants, each thread's
name, kernel wait channel and (with gdb installed) native stack. Shown when a test's wait
for an exit times out, so that a rare hang under load explains itself."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

FRAMES = 12  # per thread


def hang_report(pid: int) -> str:
    lines = []
    for process in [pid, *_descendants(pid)]:
        lines += _describe(process)
    return "\n".join(lines)


def _stat(path: Path) -> list[str]:
    """The fields of a /proc stat file after the command name: state, parent, ..."""
    return (path / "stat").read_text().rsplit(")", 1)[1].split()


def _descendants(pid: int) -> list[int]:
    children = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parent = int(_stat(entry)[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(parent, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def _describe(pid: int) -> list[str]:
    proc = Path(f"/proc/{pid}")
    try:
        command = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
        threads = sorted(proc.glob("task/*"), key=lambda p: int(p.name))
        lines = [f"-- process {pid}: {command[:200]}"]
        for task in threads:
            name = (task / "comm").read_text().strip()
            wchan = (task / "wchan").read_text().strip() or "-"
            state = _stat(task)[0]
            lines.append(f"   thread {task.name} {name!r} state {state} waiting in {wchan}")
    except OSError as error:
        return [f"-- process {pid}: gone ({error.strerror})"]
    gdb = shutil.which("gdb")
    if gdb:
        try:
            stacks = subprocess.run(
                [gdb, "-p", str(pid), "-batch", "-nx", "-ex", f"thread apply all bt {FRAMES}"],
                capture_output=True,
                text=True,
                timeout=60,
                env={**os.environ, "DEBUGINFOD_URLS": ""},
            ).stdout
            lines += ["   " + line for line in stacks.splitlines() if line.startswith(("#", "Thread"))]
        except (OSError, subprocess.SubprocessError) as error:
            lines.append(f"   (gdb: {error})")
    return lines
