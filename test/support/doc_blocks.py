"""The command blocks of the docs, run as a user would type them (see test_doc_blocks.py).

A block is a fenced block (```lang) or an indented one (4 spaces after a blank line).
What it is:

- ``python`` fences: Python, run with this environment's interpreter;
- ``bash``/``sh``/``shell``/``console`` fences: shell commands;
- unlabelled fences and indented blocks: shell commands when their first word is a
  command (an executable of the package, ``ros2``, ``python``, ``./...``, one on PATH),
  else output or a formula (not run);
- any other language (``yaml``, ``text``): data, not run.

An HTML comment on the line(s) just before a block steers it:
``<!-- doc-test: skip (REASON) -->`` leaves it out, the reason required and shown;
``<!-- doc-test: output -->`` marks a block that looks like a command as output.
``<!-- doc-test: files PATH ... -->`` anywhere in a doc: files of the repository (e.g. a
URDF of test/data) the doc's blocks use, copied into its directory first, as the user has
them in theirs.

A shell block is run as a user who followed the README types it: in the shell the set-up
leaves (``scripts/setup.sh`` run, ``.venv`` activated, ``install/setup.bash`` sourced:
nothing else on PATH: no ``ros2`` CLI, which the PyPI wheels lack, so a ``ros2 ...`` block
needs a skip naming the ROS 2 install), in the clone's folder (a copy of its tracked files
per doc, the doc's blocks in order, so that a walkthrough's files carry over). A command not
found fails the block (exit 127), and so does a tracked file the blocks changed. A line starting a node
is run in the background, as in a terminal of its own: the next line waits for its
``ready``; at the end of the block every node is stopped with Ctrl-C and must exit 0
without a traceback. A usage synopsis (a line with ``[--option ...]``) is checked against
the executable's ``--help``: it must exit 0 and know every option the synopsis names.
"""

from __future__ import annotations

import ast
import re
import shlex
import shutil
from dataclasses import dataclass
from pathlib import Path

DIRECTIVE = re.compile(r"<!--\s*doc-test:\s*(?P<what>skip|output)\b\s*(?:\((?P<reason>[^)]*)\))?\s*-->")
SHELL_LANGUAGES = ("bash", "sh", "shell", "console")
COMMAND_STARTS = ("./", ".venv/", "ros2", "python", "python3", "colcon", "cd", "export", "source", "echo")


@dataclass
class Block:
    path: Path
    line: int  # 1-based line of the block's first line
    kind: str  # "python", "shell", "data", "output"
    text: str
    skip: str | None = None  # the reason, when skipped

    @property
    def where(self) -> str:
        return f"{self.path.name}:{self.line}"


FILES = re.compile(r"<!--\s*doc-test:\s*files\s+(?P<paths>[^>]*?)\s*-->")


def doc_files(path: Path) -> list[str]:
    """The repository files a doc's blocks use (its ``doc-test: files`` comments)."""
    return [name for found in FILES.finditer(path.read_text()) for name in found["paths"].split()]


def console_scripts(setup_py: Path) -> dict[str, str]:
    """name -> 'module:function' of setup.py's console_scripts (read, not run)."""
    tree = ast.parse(setup_py.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.Dict):
            for key, value in zip(node.keys, node.values):
                if isinstance(key, ast.Constant) and key.value == "console_scripts":
                    entries = ast.literal_eval(value)
                    return dict((part.strip() for part in entry.split("=", 1)) for entry in entries)
    raise ValueError(f"{setup_py}: no console_scripts")


def read_blocks(path: Path, commands: set[str]) -> list[Block]:
    """The blocks of a Markdown file, classified (see the module)."""
    lines = path.read_text().split("\n")
    blocks, i = [], 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):
            language = line[3:].strip().lower()
            end = i + 1
            while end < len(lines) and not lines[end].startswith("```"):
                end += 1
            text = "\n".join(lines[i + 1 : end])
            if language == "python":
                kind = "python"
            elif language in SHELL_LANGUAGES:
                kind = "shell"
            elif language:
                kind = "data"
            else:
                kind = "shell" if is_command(text, commands) else "output"
            blocks.append(_directed(Block(path, i + 2, kind, text), lines, i))
            i = end + 1
            continue
        if line.startswith("    ") and line.strip() and (i == 0 or not lines[i - 1].strip()) and not _in_list(lines, i):
            end = i
            while end < len(lines) and (
                lines[end].startswith("    ")
                or (not lines[end].strip() and end + 1 < len(lines) and lines[end + 1].startswith("    "))
            ):
                end += 1
            text = "\n".join(x[4:] for x in lines[i:end])
            kind = "shell" if is_command(text, commands) else "output"
            blocks.append(_directed(Block(path, i + 1, kind, text), lines, i))
            i = end
            continue
        i += 1
    return blocks


def _in_list(lines: list[str], i: int) -> bool:
    """An indented paragraph continuing a list item, not a code block."""
    j = i - 1
    while j >= 0 and not lines[j].strip():
        j -= 1
    return j >= 0 and re.match(r"\s*([-*+]|\d+\.)\s", lines[j]) is not None and not lines[j].startswith("    ")


def _directed(block: Block, lines: list[str], start: int) -> Block:
    """The block with the directive of the comment just before it, if any."""
    j = start - 1
    while j >= 0 and not lines[j].strip():
        j -= 1
    found = DIRECTIVE.search(lines[j]) if j >= 0 else None
    if found:
        if found["what"] == "skip":
            reason = (found["reason"] or "").strip()
            if not reason:
                raise ValueError(f"{block.path.name}:{j + 1}: doc-test: skip needs a reason in parentheses")
            block.skip = reason
        else:
            block.kind = "output"
    return block


def first_word(text: str) -> str:
    for line in text.splitlines():
        line = line.strip()
        if line and not line.startswith("#"):
            try:
                words = shlex.split(line, comments=True)
            except ValueError:
                words = line.split()
            return words[0] if words else ""
    return ""


def is_command(text: str, commands: set[str]) -> bool:
    word = first_word(text)
    if not word or word.startswith("[") or word.endswith(":"):
        return False
    return word in commands or word.startswith(COMMAND_STARTS) or shutil.which(word) is not None


def logical_lines(text: str) -> list[str]:
    """Shell lines with their continuations (a trailing backslash) joined; comments and blanks out."""
    joined, current = [], ""
    for line in text.splitlines():
        if line.rstrip().endswith("\\"):
            current += line.rstrip()[:-1] + " "
            continue
        if line.startswith((" ", "\t")) and line.strip().startswith("[") and joined and not current:
            joined[-1] += " " + line.strip()  # a synopsis continued on an indented line
            continue
        current += line
        if current.strip() and not current.strip().startswith("#"):
            joined.append(current.strip())
        current = ""
    return joined


SYNOPSIS = re.compile(r"\[-{1,2}[A-Za-z]")


def is_synopsis(line: str) -> bool:
    """A usage synopsis (``[--option VALUE]``), not a command to run as written."""
    return SYNOPSIS.search(line) is not None


def synopsis_options(line: str) -> list[str]:
    return sorted(set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*|-[a-zA-Z])\b", line)))
