"""A node's command line before ROS starts: ``--help``, and what rcl would silently ignore.

A node takes no arguments of its own: everything comes after ``--ros-args``. ``--help``
prints its parameters (irb140_dynamics.node_help) without starting ROS. A ROS argument typed before ``--ros-args`` (``id_node -p
payload.mass:=2.0``) would leave the default in force without a word: it is refused, with
the line to type instead; so is a params file rcl should not be given (a folder, /dev/zero).
"""

from __future__ import annotations

from pathlib import Path

from irb140_dynamics.core.io.text_files import InputFileError, read_text_file

ROS_ARGS = "--ros-args"
HELP = ("-h", "--help")
ROS_FLAGS = (  # what rcl reads after --ros-args (design.ros2.org "ROS command line arguments")
    *("-p", "--param", "--params-file", "-r", "--remap", "-e", "--enclave", "--log-level", "--log-config-file"),
    *(f"--{switch}-{logs}-logs" for logs in ("rosout", "stdout", "external-lib") for switch in ("enable", "disable")),
)


def split_arguments(argv: list[str]) -> tuple[list[str], list[str]]:
    """(the arguments outside every ``--ros-args ... [--]`` span, those inside), without the program."""
    own, ros, inside = [], [], False
    for argument in argv[1:]:
        if argument == ROS_ARGS or (inside and argument == "--"):
            inside = argument == ROS_ARGS
        else:
            (ros if inside else own).append(argument)
    return own, ros


_given: list[str] = []  # the params files of the running node's command line (set by ``before_start``)


def params_files_given() -> list[str]:
    """The params files the running node was started with (empty in-process)."""
    return list(_given)


def before_start(name: str, argv: list[str], usage) -> tuple[int, str] | None:
    """What to do before ROS starts: (exit code, text) for ``--help`` (0, ``usage().text()``),
    an argument outside ``--ros-args`` (2) or a params file rcl should not read (1); None to
    start. ``usage`` None: a tool, which parses its own arguments (only its params files checked)."""
    own, ros = split_arguments(list(argv))
    if usage is not None and any(a in HELP for a in own):
        return 0, usage().text()
    if usage is not None and own:
        first, rest = own[0], " ".join(own)
        if first in ROS_FLAGS or ":=" in first or first.startswith("__"):
            return 2, (
                f"cannot start: '{rest}' is a ROS argument and would be ignored: add --ros-args before it, "
                f"e.g. {name} --ros-args {rest}"
            )
        return (
            2,
            f"cannot start: unknown argument '{first}': {name} takes only ROS arguments, after --ros-args (see --help)",
        )
    files = [path for flag, path in zip(ros, ros[1:]) if flag == "--params-file"]
    for path in files:
        try:
            read_text_file(path, "params file")  # missing, not a regular file, too large, not text
        except InputFileError as error:
            where = "" if Path(path).is_absolute() else f" (relative paths are read from {Path.cwd()})"
            return 1, f"cannot start: {error}{where}"
    _given[:] = files
    return None
