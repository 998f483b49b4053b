"""Finds the built module: $IPHONG_BUILD_DIR/python (default build/python) unless PYTHONPATH has it."""
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"

try:
    import iphong  # noqa: F401
except ImportError:
    build = pathlib.Path(os.environ.get("IPHONG_BUILD_DIR", ROOT / "build"))
    sys.path.insert(0, str(build / "python"))
    try:
        import iphong  # noqa: F401
    except ImportError as error:
        raise ImportError(
            f"cannot import iphong from {build / 'python'}: build it first "
            "(cmake -S . -B build && cmake --build build) or set IPHONG_BUILD_DIR / PYTHONPATH"
        ) from error
