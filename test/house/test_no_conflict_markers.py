"""No merge conflict markers committed in any tracked text file."""

import re
import subprocess

from ..support.paths import ROOT

MARKER = re.compile(r"^(<{7} |={7}$|>{7} )", re.M)


def test_no_conflict_markers():
    files = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    marked = []
    for name in files:
        path = ROOT / name
        if path.suffix not in {".py", ".md", ".txt", ".yaml", ".toml", ".cfg", ".sh", ".xml", ".urdf", ".json", ""}:
            continue
        try:
            text = path.read_text()
        except (UnicodeDecodeError, OSError):
            continue
        if MARKER.search(text):
            marked.append(name)
    assert marked == []
