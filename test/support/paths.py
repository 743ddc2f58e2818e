from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "config" / "irb140.yaml"
DATA = ROOT / "test" / "data"
# Public robot descriptions, copied into the repository with their licences (see its README).
URDF_DATA = DATA / "urdf"
