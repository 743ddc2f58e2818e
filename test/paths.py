from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "irb140.yaml"
URDF_DATA = ROOT / "test" / "data" / "urdf"
