"""The plug-in's modules live beside ssn-shadow.py (a folder name with a dash), so put it on sys.path."""

import sys
from pathlib import Path

PLUGIN_DIR = Path(__file__).resolve().parents[2] / "plugin_gimp" / "ssn-shadow"
if str(PLUGIN_DIR) not in sys.path:
    sys.path.insert(0, str(PLUGIN_DIR))
