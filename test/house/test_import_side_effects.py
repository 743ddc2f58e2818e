"""Importing any module of the package changes nothing: no environment variable, no signal
handler, no exception hook, and no reading of ``sys.argv`` by the package's code. Only an
executable's entry (irb140_dynamics.entry) does such things, when it is called. Checked in a
process of its own, with sys.argv as a tool's console script has it; and the check shown
to catch a module that does each of them."""

import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from ..support.paths import ROOT

# Run in a fresh interpreter: imports every module under the given packages (the package
# itself, or a planted one), then prints what changed and who read sys.argv.
CHECK = textwrap.dedent(
    """
    import importlib, json, os, pkgutil, signal, sys

    packages, roots = sys.argv[1].split(","), sys.argv[2].split(",")
    readers = []

    class Watched(list):
        '''sys.argv, noting each read made from a file under one of ``roots``.'''

        def _note(self):
            frame = sys._getframe(2)
            if any(frame.f_code.co_filename.startswith(root) for root in roots):
                readers.append(f"{frame.f_code.co_filename}:{frame.f_lineno}")

    for name in ("__getitem__", "__iter__", "__len__", "__contains__", "index", "count", "copy", "__reversed__"):
        def reader(self, *args, _name=name):
            self._note()
            return getattr(list, _name)(self, *args)
        setattr(Watched, name, reader)

    def handlers():
        return {int(s): repr(signal.getsignal(s)) for s in signal.valid_signals()}

    environ, before, hook = dict(os.environ), handlers(), sys.excepthook
    sys.argv = Watched(["identify", "--help"])
    imported = []
    for package in packages:
        module = importlib.import_module(package)
        imported.append(package)
        for info in pkgutil.walk_packages(module.__path__, package + "."):
            importlib.import_module(info.name)
            imported.append(info.name)
    after = handlers()
    print(json.dumps({
        "imported": imported,
        "environment": sorted(k for k in set(environ) | set(os.environ) if environ.get(k) != os.environ.get(k)),
        "signals": sorted(s for s in before if before[s] != after[s]),
        "excepthook": sys.excepthook is not hook,
        "argv_readers": readers,
    }))
    """
)


def changes(packages: list[str], roots: list[str], path: str) -> dict:
    command = [sys.executable, "-c", CHECK, ",".join(packages), ",".join(roots)]
    environment = {**os.environ, "PYTHONPATH": path}
    done = subprocess.run(command, cwd=path, capture_output=True, text=True, timeout=300, env=environment)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.ros  # every module, the nodes' too: needs ROS's messages
def test_importing_every_module_of_the_package_changes_nothing():
    found = changes(["irb140_dynamics"], [str(ROOT / "irb140_dynamics")], str(ROOT))
    imported = set(found["imported"])
    # every floor, every executable's module and its python -m form were imported
    for name in (
        "irb140_dynamics.entry",
        "irb140_dynamics.tools.identify",
        "irb140_dynamics.tools.record",
        "irb140_dynamics.programs",
        "irb140_dynamics.nodes.id_node.node",
        "irb140_dynamics.ros.runtime.spin",
        "irb140_dynamics.core.dynamics",
    ):
        assert name in imported, name
    assert found["environment"] == [], found
    assert found["signals"] == [], found
    assert found["excepthook"] is False, found
    assert found["argv_readers"] == [], found


def test_the_check_finds_a_module_that_changes_each_of_them(tmp_path):
    planted = tmp_path / "planted"
    planted.mkdir()
    (planted / "__init__.py").write_text("")
    (planted / "meddling.py").write_text(
        "import os, signal, sys\n"
        "os.environ['PLANTED_THREADS'] = '1'\n"
        "signal.signal(signal.SIGUSR1, lambda *_: None)\n"
        "sys.excepthook = print\n"
        "PROGRAM = os.path.basename(sys.argv[0])\n"
    )
    found = changes(["planted"], [str(planted)], str(tmp_path))
    assert found["imported"] == ["planted", "planted.meddling"], found
    assert found["environment"] == ["PLANTED_THREADS"], found
    assert found["signals"] == [int(signal.SIGUSR1)], found
    assert found["excepthook"] is True, found
    assert found["argv_readers"] == [f"{planted / 'meddling.py'}:5"], found
