#!/usr/bin/env bash
# Run pytest N times while two busy loops keep both cores busy: the check for flaky tests
# (docs/development.md, "Flakiness"). Stops at the first failing run.
#
#   ./scripts/under_load.sh N [PYTEST ARGUMENTS ...]
#   ./scripts/under_load.sh 20 test/ros test/processes -m "not slow"
set -euo pipefail
if [ "${1:-}" = -h ] || [ "${1:-}" = --help ] || [ $# -lt 1 ]; then
    sed -n '2,6p' "$0" | sed 's/^# \{0,1\}//'
    exit 0
fi
runs=$1
shift
cd "$(dirname "$0")/.."
# shellcheck source=scripts/python.sh
source scripts/python.sh
python=$(venv_dir)/bin/python  # .venv, or PYTHON=python3.12's venv
"$python" -c "while True: pass" &
busy1=$!
"$python" -c "while True: pass" &
busy2=$!
trap 'kill $busy1 $busy2 2>/dev/null || true' EXIT
for i in $(seq "$runs"); do
    mkdir -p build
    if "$python" -m pytest -q -p no:cacheprovider "$@" >"build/under_load_$i.log" 2>&1; then
        echo "run $i of $runs: $(tail -1 "build/under_load_$i.log")"
    else
        echo "run $i of $runs FAILED: see build/under_load_$i.log"
        grep -E "^(FAILED|ERROR)" "build/under_load_$i.log" || true
        exit 1
    fi
done
