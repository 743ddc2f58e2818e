# Sourced by setup.sh and test.sh: make .venv and install requirements/$1.txt into it (at the
# versions of requirements/pinned.txt; again only when the requirement files change) and the
# package itself (editable: its executables in .venv/bin), then activate it.
# PYTHON=python3.12 ./scripts/test.sh does the same with that interpreter, in a venv of its
# own (.venv-python3.12).
# shellcheck source=scripts/python.sh
source scripts/python.sh
venv=$(venv_dir)
if [ -n "${PYTHON:-}" ]; then
    python=$(find_python "$PYTHON") || exit 1
else
    python=$(command -v python3.11 || command -v python3)
fi
if [ ! -x "$venv/bin/python" ]; then
    if ! "$python" -m venv "$venv" >/dev/null 2>&1; then
        rm -rf "$venv"
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
            echo "python3 -m venv failed: installing python3-venv" >&2
            apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
            "$python" -m venv "$venv"
        else
            echo "error: '$python -m venv' failed; install python3-venv" >&2
            exit 1
        fi
    fi
fi
stamp="$venv/.requirements-$1"
wanted=$(cat requirements/*.txt | sha256sum)
# (the test requirements include the run ones: a .venv set up for tests serves run.sh too)
if [ "$(cat "$stamp" 2>/dev/null)" != "$wanted" ] \
    && ! { [ "$1" = run ] && [ "$(cat "$venv/.requirements-test" 2>/dev/null)" = "$wanted" ]; }; then
    echo "installing requirements/$1.txt into $venv (a minute or two the first time) ..." >&2
    # pip's steps shown (on a terminal its download bars with the time left) on stderr; its
    # warning "Location ... is ignored" for every ROS wheel is harmless, filtered.
    "$venv/bin/python" -m pip install --disable-pip-version-check -r "requirements/$1.txt" \
        -c requirements/pinned.txt >&2 2> >(grep -v "is ignored" >&2)
    echo "$wanted" >"$stamp"
fi
# The package itself, editable (the clone's source): its executables (load_diagram, identify,
# id_node, ...) become console scripts in $venv/bin, on PATH once the venv is activated.
# Again only when setup.py or the clone's place changes.
package_stamp="$venv/.package"
package_wanted="$(cat setup.py setup.cfg | sha256sum) $PWD"
if [ "$(cat "$package_stamp" 2>/dev/null)" != "$package_wanted" ]; then
    echo "installing the package into $venv (its executables in $venv/bin) ..." >&2
    "$venv/bin/python" -m pip install -q --disable-pip-version-check --no-deps -e . \
        >&2 2> >(grep -v "is ignored" >&2)
    echo "$package_wanted" >"$package_stamp"
fi
# shellcheck disable=SC1091
source "$venv/bin/activate"
# The clone's modules compiled to bytecode here, once: with PYTHONDONTWRITEBYTECODE set (as
# on many CI machines and containers) every node, tool and test process would compile them
# again from source when it starts (0.2 to 0.3 s of CPU each).
python -m compileall -q -j 0 irb140_dynamics test >/dev/null || true
