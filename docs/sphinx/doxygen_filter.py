#!/usr/bin/env python3
"""The headers as Doxygen reads them for the C++ API reference (docs/api/cpp.md): their plain `//`
comments turned into Doxygen comments, so that the reference shows the contracts the headers
already state, without a second comment syntax in the sources (docs/design.md, "Build and CI").
docs/sphinx/nhdyn_docs.py writes the filtered copies Doxygen reads; by hand:
doxygen_filter.py HEADER > what Doxygen reads instead.

- The paragraph that opens a header (before `#pragma once`) becomes the file's description.
- A block of `//` lines directly above a declaration (no blank line between) documents it.
- A `//` comment after code on the same line (`double t_end = 10.0;  // end time [s]`) documents
  that member; `//` lines right below it, at the same column, continue it.
- Any other comment (a section rule, a note followed by a blank line) stays a plain comment.

The comments are prose, not Doxygen markup: the characters Doxygen would read as commands or HTML
are escaped; `code` in backticks stays code; a line indented deeper than its block (a formula, a
table) is kept as it stands, in a verbatim block. Line count is preserved, so Doxygen's
file:line in a warning points at the header's own line.
"""

import re
import sys

_SPECIAL = re.compile(r"([\\@<>&#%$*_|]|-{2,3})")
_TRAILING = re.compile(r'^(?P<code>[^"\'/]*?\S)(?P<gap>\s+)//(?P<text>(?!/).*)$')


def _escape(text):
    """Prose for Doxygen: special characters escaped outside `code` spans."""
    parts = text.split("`")
    if len(parts) % 2 == 0:  # an unpaired backtick: no code span at all
        return _SPECIAL.sub(r"\\\1", text)
    return "`".join(part if i % 2 else _SPECIAL.sub(r"\\\1", part) for i, part in enumerate(parts))


def _comment_text(line):
    """The text of a whole-line `//` comment, without the slashes and one space."""
    body = line.lstrip()[2:]
    return body[1:] if body.startswith(" ") else body


def _doc_block(lines):
    """A block of whole-line comments as one Doxygen comment /** ... */ over the same lines; lines
    indented deeper than the block's prose in a verbatim block. (Not ///: Doxygen keeps the
    slashes of /// lines inside a verbatim block.)"""
    indent = lines[0][: len(lines[0]) - len(lines[0].lstrip())]
    texts = [_comment_text(line) for line in lines]
    prose = [t for t in texts if t.strip()]
    base = min((len(t) - len(t.lstrip()) for t in prose), default=0)
    out = []
    in_verbatim = False
    for text in texts:
        deeper = text.strip() != "" and len(text) - len(text.lstrip()) >= base + 4
        if deeper:
            text = text.replace("*/", "* /")
            if not in_verbatim and out:
                # Opened at the end of the line before, so that this line keeps its indentation.
                out[-1] += " \\verbatim"
            elif not in_verbatim:
                text = "\\verbatim " + text
            in_verbatim = True
            out.append(text)
        else:
            if in_verbatim:
                out[-1] += " \\endverbatim"
            in_verbatim = False
            out.append(_escape(text).replace("*/", "* /"))
    if in_verbatim:
        out[-1] += " \\endverbatim"
    first, rest = out[0], out[1:]
    # No leading * on the lines after the first: Doxygen keeps it inside a verbatim block.
    block = [f"{indent}/** {first}"] + [f"{indent}    {text}" for text in rest]
    block[-1] += " */"
    return [line.rstrip() if not line.endswith(" */") else line for line in block]


def _is_comment(line):
    return line.lstrip().startswith("//")


def filter_header(text):
    lines = text.split("\n")
    out = []
    i = 0
    seen_code = False
    trailing_column = None  # the column of the last trailing comment, for its continuation lines
    while i < len(lines):
        line = lines[i]
        if _is_comment(line):
            j = i
            while j < len(lines) and _is_comment(lines[j]):
                j += 1
            block = lines[i:j]
            following = lines[j] if j < len(lines) else ""
            column = len(line) - len(line.lstrip())
            if trailing_column is not None and column == trailing_column:
                out.extend(line[:column] + "///< " + _escape(_comment_text(line)) for line in block)
            elif not seen_code:
                # \file at the end of the block: at its start, it would read the first word as a file name.
                doc = _doc_block(block)
                doc[-1] = doc[-1][: -len(" */")] + " \\file */"
                out.extend(doc)
            elif following.strip() and not following.lstrip().startswith(("#", "}", "namespace")):
                out.extend(_doc_block(block))
            else:
                out.extend(block)
            trailing_column = None
            i = j
            continue
        match = _TRAILING.match(line)
        if match and seen_code and not match.group("code").lstrip().startswith(("}", "#", "namespace", "public:", "private:", "protected:")):
            column = len(match.group("code")) + len(match.group("gap"))
            text = match.group("text")
            out.append(match.group("code") + match.group("gap") + "///< " + _escape(text[1:] if text.startswith(" ") else text))
            trailing_column = column
        else:
            out.append(line)
            trailing_column = None
        if line.strip():
            seen_code = True
        i += 1
    return "\n".join(out)


if __name__ == "__main__":
    with open(sys.argv[1], encoding="utf-8") as f:
        sys.stdout.write(filter_header(f.read()))
