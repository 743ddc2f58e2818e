"""Test session setup: DDS isolated to this machine and to this session's own domain."""

import os
import random

# Set before rclpy is imported anywhere: a domain of our own, discovery on localhost only.
os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 100))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("ROS_STATIC_PEERS", None)


import pytest  # noqa: E402


@pytest.fixture
def quick_proofs(monkeypatch):
    """A smaller budget for the proof of worst static torques: for tests of what is proven
    and reported, not of how far the proof gets. Proofs remembered are forgotten before and
    after, so that no other test sees one of these."""
    from irb140_dynamics.core.payload.proof import certify
    from irb140_dynamics.core.payload.family import forget_families

    monkeypatch.setattr(certify, "EVALUATIONS", 10_000)
    forget_families()
    yield
    forget_families()
