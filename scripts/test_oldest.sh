#!/usr/bin/env bash
# The tests that need no ROS, on the OLDEST versions requirements/ allow (each ">=" lower
# bound installed exactly: Ubuntu 24.04's numpy 1.26.4, SciPy 1.11.4, matplotlib 3.6.3,
# SymPy 1.12, PyYAML 6.0.1, ...), on Python 3.11, in a venv of its own (.venv-oldest; set up
# again only when the requirement files change). No ROS wheel is installed, so a test that
# imports rclpy cannot hide here. Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
# shellcheck source=scripts/python.sh
source scripts/python.sh
venv=.venv-oldest
python=$(find_python "${PYTHON_OLDEST:-python3.11}")
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
stamp="$venv/.requirements-oldest"
wanted=$(cat requirements/*.txt | sha256sum)
if [ "$(cat "$stamp" 2>/dev/null)" != "$wanted" ]; then
    "$venv/bin/python" scripts/oldest.py requirements requirements/run.txt requirements/test.txt >"$venv/oldest.txt"
    echo "installing the oldest versions into $venv: $(tr '\n' ' ' <"$venv/oldest.txt")" >&2
    # pip warns "Location ... is ignored" for every package of this machine's local indexes: filtered.
    { "$venv/bin/python" -m pip install -q --disable-pip-version-check -r "$venv/oldest.txt"; } 2>&1 \
        | { grep -v "is ignored" || true; } >&2
    echo "$wanted" >"$stamp"
fi
# shellcheck disable=SC1091
source "$venv/bin/activate"
python -m pip list --format=freeze 2>/dev/null \
    | grep -i -E '^(numpy|scipy|matplotlib|sympy|pyyaml|mujoco|rosbags)==' | tr '\n' ' ' >&2
echo >&2
# test/ros and test/processes (every test there is marked ros or process; their conftests
# import rclpy) are left out, and so is each other test module that imports ROS (or
# Pinocchio) when it is imported, directly or through test/support: named on stderr.
mapfile -t ignores < <(python scripts/oldest.py unimportable test --ignore=test/ros --ignore=test/processes)
exec python -m pytest -m "not ros and not process" -p no:cacheprovider "${ignores[@]}" "$@"
