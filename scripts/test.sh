#!/usr/bin/env bash
# The test command: sets up .venv (ROS 2 Jazzy wheels, NumPy, pytest, Pinocchio) and runs
# every test. Extra arguments go to pytest, e.g. ./scripts/test.sh -k payload
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh test
exec python -m pytest "$@"
