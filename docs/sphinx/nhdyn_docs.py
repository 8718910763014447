"""The Sphinx extension of nhdyn's documentation site (docs/conf.py).

- Runs Doxygen on the installed headers before Sphinx reads a page (the C++ API reference: Breathe
  reads its XML). The headers' plain `//` comments are turned into Doxygen's first, all in this
  one process (docs/sphinx/doxygen_filter.py; as Doxygen's INPUT_FILTER it would start Python once
  per header: 20 s). A Doxygen warning fails the build, as a Sphinx one does.
- Checks that the C++ API (docs/api/cpp.md, docs/api/cpp/LAYER.md) gives every installed header
  its place (and names no other), so a new header cannot go missing from the reference and a
  removed one cannot leave a stale entry.
- Links from the pages to what is not a page: the pages link the repository's files as they sit
  in a checkout (`../examples/sled.toml`, `checks/impact.py`, `../CONTRIBUTING.md`). A file
  becomes a download (Sphinx copies it into the site: the site stands alone, in the build tree
  as installed); a folder (`../bench/`), which a site cannot show, becomes its name as text.
- Drops a rule that ends a page (docutils refuses a document that ends with one).
- Works around three things of Sphinx 5.3 and Breathe 4.34 (Debian 12's): the namespace every
  header opens, the C++ domain's cost on a large namespace, the search index's order (below).
- Turns the Python docstrings, written as plain text for help(), into reStructuredText that
  says the same (an indented example is a literal block, `x` is code, a trailing `_` or a `*`
  is a character, not markup).
"""

import re
import subprocess
from pathlib import Path

from docutils import nodes
from docutils.transforms import Transform
from sphinx import addnodes
from sphinx.errors import ExtensionError
from sphinx.util import logging

import doxygen_filter

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parent.parent
REPOSITORY = DOCS.parent
# The installed headers (cmake/install.cmake): src/nhdyn but optimize/, resources/ and every
# module's detail/ folder (the library's own headers).
HEADERS_ROOT = REPOSITORY / "src"
NOT_INSTALLED = ("nhdyn/optimize/", "nhdyn/io/resources/")


def installed_headers():
    headers = []
    for path in sorted((HEADERS_ROOT / "nhdyn").rglob("*.hpp")):
        name = path.relative_to(HEADERS_ROOT).as_posix()
        if not name.startswith(NOT_INSTALLED) and "/detail/" not in name:
            headers.append(name)
    return headers


def run_doxygen(app):
    """Filtered copies of the headers, then Doxygen over them: XML for Breathe."""
    out = Path(app.config.breathe_projects["nhdyn"]).parent
    include = out / "include"
    for name in installed_headers():
        target = include / name
        target.parent.mkdir(parents=True, exist_ok=True)
        text = doxygen_filter.filter_header((HEADERS_ROOT / name).read_text(encoding="utf-8"))
        if not target.exists() or target.read_text(encoding="utf-8") != text:
            target.write_text(text, encoding="utf-8")
    stale = {p for p in include.rglob("*.hpp")} - {include / name for name in installed_headers()}
    for path in stale:
        path.unlink()
    settings = (DOCS / "Doxyfile").read_text(encoding="utf-8") + "\n".join([
        "",
        f'INPUT = "{include / "nhdyn"}"',
        "EXCLUDE =",
        f'STRIP_FROM_PATH = "{include}"',
        f'STRIP_FROM_INC_PATH = "{include}"',
        f'OUTPUT_DIRECTORY = "{out}"',
        "",
    ])
    try:
        result = subprocess.run(["doxygen", "-"], input=settings, text=True, cwd=out,
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    except FileNotFoundError:
        raise ExtensionError("doxygen not found: the C++ API needs it (apt-get install doxygen, or "
                             "scripts/install-deps)") from None
    for line in result.stdout.splitlines():
        # Doxygen names the filtered copy: name the header itself (the line numbers are the same).
        logger.warning("doxygen: %s", line.replace(str(include), str(HEADERS_ROOT)))
    if result.returncode != 0 and not result.stdout.strip():
        raise ExtensionError(f"doxygen failed (exit {result.returncode})")


def check_cpp_page(app):
    """Every installed header has its `doxygenfile` in api/cpp.md or its layer's page
    api/cpp/LAYER.md, and no other file has one."""
    listed = {}
    for page in [DOCS / "api" / "cpp.md"] + sorted((DOCS / "api" / "cpp").glob("*.md")):
        for name in re.findall(r"^```\{doxygenfile\}\s+(\S+)", page.read_text(encoding="utf-8"), re.M):
            listed[name] = page.relative_to(DOCS).as_posix()
    headers = installed_headers()
    for name in headers:
        if name not in listed:
            layer = name.split("/")[1]
            logger.warning("the installed header %s has no {doxygenfile} entry in the C++ API: add one "
                           "to docs/api/cpp/%s.md", name, layer)
    for name, page in listed.items():
        if name not in headers:
            logger.warning("docs/%s: {doxygenfile} %s names no installed header (src/%s): remove or "
                           "rename the entry", page, name, name)


class RepositoryLinks(Transform):
    """Links to files and folders of the repository that are not pages (module docstring)."""

    default_priority = 200

    def apply(self):
        env = self.document.settings.env
        here = Path(env.doc2path(env.docname)).parent
        for node in list(self.document.findall(addnodes.pending_xref)):
            if node.get("reftype") != "myst":
                continue
            target = node["reftarget"].split("#")[0]
            if not target or "://" in target:
                continue
            path = (here / target).resolve()
            if path.is_dir():
                # A folder: its name, as the link's text says it (a site cannot list a folder).
                node.replace_self(nodes.literal("", node.astext()))
            elif path.is_file() and not _is_inside(path, DOCS):
                # A Markdown file outside docs/ (../CONTRIBUTING.md) is not a page: a download.
                download = addnodes.download_reference(
                    "", "", refdoc=env.docname, reftarget=node["reftarget"], reftype="myst",
                    refdomain=None, refexplicit=True, refwarn=False)
                download += nodes.inline("", "", *node[0].children, classes=["xref", "download", "myst"])
                node.replace_self(download)


class FinalRule(Transform):
    """A page may end with a horizontal rule (`---`, as performance-history.md does, a record closed
    by a rule): docutils refuses a document that ends with a transition, so drop that last rule
    (it separates nothing on a page of the site)."""

    default_priority = 820  # before docutils' Transitions check (830)

    def apply(self):
        last = self.document.children[-1] if self.document.children else None
        while isinstance(last, nodes.section) and last.children:
            last = last.children[-1]
        if isinstance(last, nodes.transition):
            last.parent.remove(last)


def _is_inside(path, folder):
    try:
        path.relative_to(folder)
        return True
    except ValueError:
        return False


_WORD_UNDERSCORE = re.compile(r"(\w)_(?=\W|$)")
_STAR = re.compile(r"(?<![\\`])\*")


def docstring_as_rst(app, what, name, obj, options, lines):
    """Plain-text docstrings as reStructuredText (module docstring)."""
    out = []
    in_literal = False
    base = None
    for line in lines:
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if base is None and stripped:
            base = indent
        deeper = stripped and base is not None and indent >= base + 4
        if deeper and not in_literal:
            # An indented example: a literal block after its paragraph.
            if out and out[-1].strip():
                out[-1] = out[-1] if out[-1].endswith("::") else out[-1] + " ::"
                out.append("")
            else:
                out.append("::")
                out.append("")
            in_literal = True
        elif stripped and not deeper and in_literal:
            in_literal = False
            if out and out[-1].strip():
                out.append("")
        if in_literal or not stripped:
            out.append(line)
            continue
        # Prose: `code` stays code (as a literal); markup characters outside it are characters.
        parts = line.split("`")
        if len(parts) % 2 == 0:
            parts = [line]
        text = []
        for k, part in enumerate(parts):
            if k % 2:
                text.append("``" + part + "``")
            else:
                text.append(_STAR.sub(r"\\*", _WORD_UNDERSCORE.sub(r"\1\\_", part.replace("|", "\\|"))))
        out.append("".join(text))
    lines[:] = out


def _namespace_as_scope(original):
    """Breathe's doxygenfile renders the namespace a header opens as a declaration of its own, so
    the second header that opens `nhdyn` declares it again (a duplicate C++ declaration and ID).
    In a file's entry the namespace is only the members' scope: make it the C++ domain's current
    scope, as `.. cpp:namespace-push::` does, and render the members in it (declared and linked
    as nhdyn::..., as before), without declaring the namespace."""
    from breathe.renderer.sphinxrenderer import WithContext
    from sphinx.domains import cpp

    def visit_namespace(self, node):
        if self.context.directive_args[0] != "doxygenfile":
            return original(self, node)
        file_data = self.compound_parser.parse(node.refid)
        env = self.state.document.settings.env
        parser = cpp.DefinitionParser(file_data.compounddef.compoundname,
                                      location=(env.docname, self.context.directive_args[4]), config=env.config)
        ast = parser.parse_namespace_object()
        parser.assert_end()
        # The full name from the root: a nested namespace (nhdyn::symbolic) is rendered inside nhdyn's.
        symbol = env.domaindata["cpp"]["root_symbol"].add_name(ast.nestedName, ast.templatePrefix)
        old_parent = env.temp_data.get("cpp:parent_symbol")
        old_key = env.ref_context.get("cpp:parent_key")
        env.temp_data["cpp:parent_symbol"] = symbol
        env.ref_context["cpp:parent_key"] = symbol.get_lookup_key()
        parent_context = self.context.create_child_context(file_data)
        new_context = parent_context.create_child_context(file_data.compounddef)
        # Nested, as inside the namespace's declaration: a class is named in the scope
        # (Trajectory in nhdyn), not with its full name again (nhdyn::nhdyn::Trajectory).
        self.nesting_level += 1
        try:
            with WithContext(self, new_context):
                return self.render(file_data, parent_context)
        finally:
            self.nesting_level -= 1
            for store, key, old in ((env.temp_data, "cpp:parent_symbol", old_parent),
                                    (env.ref_context, "cpp:parent_key", old_key)):
                if old is None:
                    store.pop(key, None)
                else:
                    store[key] = old

    return visit_namespace


def _sorted_titles():
    """Sphinx 5.3 writes the search index's entries in the order the parallel readers finished
    their pages: sorted (each table by its keys, each title's pages), the same tree gives the same
    searchindex.js, byte for byte."""
    from sphinx.search import IndexBuilder

    original = IndexBuilder.freeze
    if getattr(original, "_nhdyn_sorted", False):
        return

    def by_key(value):
        if isinstance(value, dict):
            return {key: by_key(value[key]) for key in sorted(value, key=str)}
        return value

    def freeze(self):
        data = original(self)
        for pages in data.get("alltitles", {}).values():
            # (page, anchor or None): a title on a section and on an id-less element mixes them.
            pages.sort(key=lambda page: tuple("" if part is None else part for part in page))
        return by_key(data)

    freeze._nhdyn_sorted = True
    IndexBuilder.freeze = freeze


def _cache_newest_id():
    """Sphinx 5.3's C++ domain computes a declaration's id again at every comparison of a lookup
    (Symbol.direct_lookup compares the id of every sibling), and a namespace of a thousand
    declarations made resolving the reference's 4000 links 30 s of the build. Later Sphinx caches
    it on the declaration (ASTDeclaration._newest_id_cache, Sphinx 7), as here: a declaration
    does not change once it is in the symbol table."""
    from sphinx.domains import cpp

    declaration = cpp.ASTDeclaration
    if getattr(declaration, "_nhdyn_cached_id", False):
        return

    def get_newest_id(self):
        cached = self.__dict__.get("_nhdyn_newest_id")
        if cached is None:
            cached = self.get_id(cpp._max_id, True)
            self.__dict__["_nhdyn_newest_id"] = cached
        return cached

    declaration.get_newest_id = get_newest_id
    declaration._nhdyn_cached_id = True


def setup(app):
    from breathe.renderer.sphinxrenderer import SphinxRenderer

    _cache_newest_id()
    _sorted_titles()

    SphinxRenderer.visit_namespace = _namespace_as_scope(SphinxRenderer.visit_namespace)
    app.connect("builder-inited", run_doxygen)
    app.connect("builder-inited", check_cpp_page)
    app.connect("autodoc-process-docstring", docstring_as_rst)
    app.add_transform(RepositoryLinks)
    app.add_transform(FinalRule)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
