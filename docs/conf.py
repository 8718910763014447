# Sphinx's settings for nhdyn's documentation site: `make docs` builds it into
# $(BUILD)/docs/html (docs/install.md, "The documentation site"). The pages are the Markdown files
# of docs/ (MyST); the C++ API reference comes from the installed headers through Doxygen and
# Breathe, the Python API from the built module's docstrings (autodoc). The machinery of our own
# (Doxygen's run, links to files outside docs/, the check that every header has its place) is in
# docs/sphinx/nhdyn_docs.py.
import os
import re
import sys
from pathlib import Path

docs_dir = Path(__file__).resolve().parent
repository = docs_dir.parent
# The build directory whose Python module the Python API is read from (make docs: $(BUILD)).
build_dir = Path(os.environ.get("NHDYN_BUILD_DIR", repository / "build")).resolve()
# No __pycache__ beside the extension: docs/ is installed as it is (cmake/install.cmake).
sys.dont_write_bytecode = True
sys.path.insert(0, str(docs_dir / "sphinx"))
sys.path.insert(0, str(build_dir / "python"))

project = "nhdyn"
author = "the nhdyn authors"
copyright = "the nhdyn authors"
_version = re.search(r"project\(nhdyn VERSION ([0-9.]+)", (repository / "CMakeLists.txt").read_text())
release = version = _version.group(1) if _version else "unknown"

extensions = [
    "myst_parser",
    "breathe",
    "sphinx.ext.autodoc",
    "nhdyn_docs",
]

# Markdown only; the scripts and notes beside the derivations are files, not pages.
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["Doxyfile", "sphinx", "gallery/make_reports.sh"]

# GitHub-style anchors for the headings (cli.md#the-csv), as the pages already link them.
myst_heading_anchors = 4
myst_enable_extensions = ["colon_fence"]
# Only these schemes are external links; `file.toml` and `../examples/x.toml` are files.
myst_url_schemes = ["http", "https", "mailto"]

breathe_projects = {"nhdyn": str(build_dir / "docs" / "doxygen" / "xml")}
breathe_default_project = "nhdyn"
breathe_domain_by_extension = {"hpp": "cpp"}
breathe_show_include = True
breathe_show_define_initializer = True
breathe_show_enumvalue_initializer = True
primary_domain = "cpp"
highlight_language = "text"

autodoc_default_options = {"members": True, "undoc-members": False}
autodoc_member_order = "bysource"
autodoc_typehints = "signature"

# The site is the same for the same tree: no dates, no build information.
html_theme = "alabaster"
html_title = f"nhdyn {release}"
html_last_updated_fmt = None
html_show_sphinx = False
html_copy_source = False
html_show_sourcelink = False
html_theme_options = {
    "description": "Constrained mechanical systems, holonomic and nonholonomic: the Do Sanh equations",
    "fixed_sidebar": True,
    "page_width": "1240px",
    "sidebar_width": "260px",
}
html_sidebars = {"**": ["about.html", "navigation.html", "relations.html", "searchbox.html"]}
