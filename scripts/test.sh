#!/usr/bin/env bash
# The test command: sets up .venv (ROS 2 Jazzy wheels, NumPy, pytest, Pinocchio, ruff),
# checks the code with ruff (lint and format), then runs the tests. Extra arguments go to
# pytest, e.g. ./scripts/test.sh -k payload, or ./scripts/test.sh -m "not process"
# (groups: docs/development.md).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh test
ruff check --quiet . || { echo "ruff check found problems (ruff check --fix . mends most)" >&2; exit 1; }
ruff format --check --quiet . || { echo "files not formatted: run ruff format ." >&2; exit 1; }
exec python -m pytest "$@"
