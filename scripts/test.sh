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
# Bytecode kept, as Python and pytest keep it by default (a machine may set
# PYTHONDONTWRITEBYTECODE): each worker would otherwise rewrite and compile every test
# module again, and each process the tests start compile what env.sh did not.
unset PYTHONDONTWRITEBYTECODE
# OpenBLAS on one thread, as the package's executables run it (entry.py): three workers on
# two cores, with small matrices, where more threads only spin while they wait.
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
# Three workers (pytest-xdist), a test file each at a time, on two cores: the suite's
# processes and nodes wait on each other (a start, DDS discovery, a simulated arm in real
# time), and two workers left the cores idle a fifth of the run; a third fills those waits
# (2026-11-29, 2 cores: 287 s with two, 256 s with three, 266 s with four). `-n 0` after
# the script's name runs it in one process.
exec python -m pytest -n 3 --dist loadfile "$@"
