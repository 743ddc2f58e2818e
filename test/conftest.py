"""Test session setup: DDS isolated to this machine and to this session's own domain."""

import os
import random

# Set before rclpy is imported anywhere: a domain of our own, discovery on localhost only.
os.environ["ROS_DOMAIN_ID"] = str(random.SystemRandom().randint(1, 100))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.pop("ROS_STATIC_PEERS", None)
