"""Test session setup: DDS isolated to this machine and to this session's own domain, a
cache of native kernels of the run's own, Ctrl-C as from a terminal, and the markers of the test
folders: test/ros/ spins nodes (``ros``), test/processes/ starts executables (``process``).

Under pytest-xdist (``-n 2``) each worker is a session of its own: a domain of its own (the
run's first domain plus the worker's number, the run's drawn once by the process that starts
the workers, which they inherit); the run's kernel cache is one, shared by its workers."""

import os
import random
import signal
import tempfile
from pathlib import Path

# Set before rclpy is imported anywhere: a domain of our own, discovery on localhost only.
WORKERS_AT_MOST = 8  # pytest-xdist workers: domains FIRST_DOMAIN to FIRST_DOMAIN + 7
FIRST_DOMAIN = int(  # drawn by the conftest.py at the root (the run's), else here
    os.environ.setdefault("IRB140_TEST_DOMAIN", str(random.SystemRandom().randint(1, 101 - WORKERS_AT_MOST)))
)
WORKER = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw"))
assert WORKER < WORKERS_AT_MOST, f"at most {WORKERS_AT_MOST} pytest-xdist workers (a DDS domain each)"
os.environ["ROS_DOMAIN_ID"] = str(FIRST_DOMAIN + WORKER)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("ROS_STATIC_PEERS", None)
# Participants announce themselves every 0.25 s, not 3 s (see the file): two processes meet
# within that on localhost, where a missed first announcement cost up to 3 s.
os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = str(Path(__file__).parent / "support" / "fastdds_discovery.xml")
# Native kernels (irb140_dynamics.native) compiled by this run into a folder of its own (the
# root conftest.py's, shared by the run's workers), not into the user's cache: nothing is
# left behind.
if "IRB140_TEST_CACHE" not in os.environ:
    _CACHE = tempfile.TemporaryDirectory(prefix="irb140_kernels_")
    os.environ["IRB140_TEST_CACHE"] = _CACHE.name
os.environ["IRB140_CACHE"] = os.environ["IRB140_TEST_CACHE"]
# A run started with SIGINT ignored (a background job of a script, nohup, some CI runners)
# passes the ignoring on to every process it starts: run.sh could not trap the tests'
# Ctrl-C, nor Python turn it into KeyboardInterrupt. A handler here is reset to the default
# in each child, as a terminal starts them.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


import pytest  # noqa: E402

TEST_ROOT = Path(__file__).resolve().parent
FOLDER_MARKERS = {"ros": "ros", "processes": "process"}


def pytest_collection_modifyitems(config, items):
    for item in items:
        folder = Path(str(item.fspath)).resolve().relative_to(TEST_ROOT).parts[0]
        marker = FOLDER_MARKERS.get(folder)
        if marker is not None:
            item.add_marker(marker)


@pytest.fixture
def quick_proofs(monkeypatch):
    """A smaller budget for the proof of worst static torques: for tests of what is proven
    and reported, not of how far the proof gets. Proofs remembered are forgotten before and
    after, so that no other test sees one of these."""
    from irb140_dynamics.core.payload.family import forget_families
    from irb140_dynamics.core.payload.proof import certify

    monkeypatch.setattr(certify, "EVALUATIONS", 10_000)
    forget_families()
    yield
    forget_families()
