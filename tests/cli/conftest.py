"""The command-line tests need only the iphong binary ($IPHONG_BUILD_DIR/iphong, default
build/iphong), not the Python module, so they also run against a sanitizer build
(scripts/sanitize.sh)."""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
