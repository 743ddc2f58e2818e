import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "irb140.yaml"
# The public robot descriptions beside the repository (shared/urdf, see its README): CI's
# clone has shared/ beside it; a git worktree elsewhere may point SHARED_URDF at it.
SHARED_URDF = ROOT.parent / "shared" / "urdf"
URDF_DATA = Path(os.environ.get("SHARED_URDF", SHARED_URDF))
