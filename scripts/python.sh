# Sourced by env.sh and test_oldest.sh: find_python NAME prints the path of the interpreter
# NAME (python3.12, or a path), from PATH or else from pyenv's installed versions (whose shim
# refuses a version that is not the selected one); venv_dir says which venv an interpreter gets.
find_python() {
    local name=$1 found version
    if found=$(command -v "$name") && "$found" -c "" 2>/dev/null; then
        echo "$found"
        return 0
    fi
    if command -v pyenv >/dev/null; then
        for version in $(pyenv whence "$name" 2>/dev/null); do
            found="$(pyenv root)/versions/$version/bin/$name"
            if [ -x "$found" ]; then
                echo "$found"
                return 0
            fi
        done
    fi
    echo "error: $name not found: install it (Ubuntu 24.04: apt-get install $name python3-venv)" >&2
    return 1
}

# .venv for the default interpreter; .venv-python3.12 for PYTHON=python3.12, and so on.
venv_dir() {
    if [ -z "${PYTHON:-}" ]; then echo .venv; else echo ".venv-$(basename "$PYTHON")"; fi
}
