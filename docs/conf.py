# Sphinx configuration of iphong's documentation site. Build it, after `cmake --build build`:
#   /usr/bin/python3 -m sphinx -W -b html docs build/docs
# The command-line reference is generated from the built program's own --help (IPHONG_BUILD_DIR,
# default ../build), the Python reference from the built module, the C++ reference from the
# public headers' own comments: none of them can drift from the code.
import os
import pathlib
import re
import sys

DOCS = pathlib.Path(__file__).resolve().parent
ROOT = DOCS.parent
BUILD = pathlib.Path(os.environ.get("IPHONG_BUILD_DIR", ROOT / "build")).resolve()
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(BUILD / "python"))

project = "iphong"
author = "The iphong developers"
copyright = "2026, The iphong developers"
release = re.search(r"project\(iphong VERSION ([0-9.]+)",
                    (ROOT / "CMakeLists.txt").read_text()).group(1)
version = release

extensions = ["myst_parser", "sphinx.ext.autodoc", "iphong_reference"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
master_doc = "index"
exclude_patterns = ["_build"]
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]
autodoc_member_order = "bysource"

try:
    import sphinx_rtd_theme  # noqa: F401  (Debian's python3-sphinx-rtd-theme)
    html_theme = "sphinx_rtd_theme"
except ImportError:
    html_theme = "alabaster"
html_title = f"iphong {release}"
iphong_build_dir = str(BUILD)
html_static_path = ["_static"]
html_css_files = ["iphong.css"]
