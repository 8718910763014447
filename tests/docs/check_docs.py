#!/usr/bin/env python3
"""Keeps the docs true to the program: quoted outputs are checked against real runs, and the
example commands of the README and docs/ are run.

Quoted outputs. A fenced block that shows what a command prints is preceded by a marker naming
the command, on the line right before the fence (indented like it):

    <!-- check: nhdyn simulate sled --t-end 2 --output-step 0.1 -o sled.csv -->
    ```text
    nhdyn simulate sled: method sanh (D: qr), ...
    ```

The command runs in bash (with pipefail, so `| grep ...` may cut an excerpt out of the output) in
an empty temporary directory holding only `examples`, a link to the source tree's examples/, with
the nhdyn under test first on PATH and XDG_CACHE_HOME inside that directory. Its stdout and stderr
together (stderr is unbuffered, so its lines come first) must equal the block, and it must exit
with 0, or with N when the command ends with the comment `# exit N`. Each marker gets its own
directory; a marker may hold several commands (`a; b`).

Placeholders: the only parts of an output allowed to differ from the block are those that
measure the machine rather than the program. They are masked on both sides before comparing:

    wall time <number> ms|s        (the summary of simulate)

Python. With --python-path DIR (ctest gives the build's package folder when the Python package is
built), the commands run with PYTHONPATH=DIR, so a marker may quote what `/usr/bin/python3 -c ...`
prints, and the one-line Python examples (lines `/usr/bin/python3 -c ...`) run with the others.
Without it, markers whose command runs python3 are skipped, and said to be.

Trailing blanks of a line are ignored too. Nothing else varies: the runs are deterministic, so every other figure, path and count is
compared as written. Commands that take long (more than about a second on a loaded 2-core
machine) are not marked: the whole check must stay well under a minute of CPU.

Example commands. With --examples, the example commands of the README and docs/ run in order, in
one empty temporary directory per README block or docs page (with `examples` linked as above),
and must exit with 0: the README's lines `build/apps/nhdyn/nhdyn ...` (run as `nhdyn ...`) and
`mkdir ...` of its indented blocks; in docs/, the lines `nhdyn ...` and `mkdir ...` of indented
blocks and of ```text blocks that hold commands only (see docs_examples). Left out: synopsis lines
(MODEL, FILE, [--option], <name>, ...), commands writing into the source tree's docs/ (the
figures), the ```sh blocks of docs/cli.md (tests/cli runs those, with their exit codes), and
lines with --plot when gnuplot is not installed.

Usage:
    check_docs.py --nhdyn build/apps/nhdyn/nhdyn              # check the quoted outputs
    check_docs.py --nhdyn build/apps/nhdyn/nhdyn --update     # rewrite them from real runs
    check_docs.py --nhdyn build/apps/nhdyn/nhdyn --examples   # run the example commands
`make docs-update` runs the second; ctest runs the first and the third (label `docs`).
"""

import argparse
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

MARKER = re.compile(r"^(\s*)<!-- check: (.*) -->\s*$")
EXIT_COMMENT = re.compile(r"#\s*exit\s+(\d+)\s*$")
# The placeholders of the module docstring: (pattern, what it becomes on both sides).
PYTHON_COMMAND = re.compile(r"(^|[\s;|&(])(/usr/bin/)?python3\b")
PYTHON_EXAMPLE = "/usr/bin/python3 -c "
PYTHON_PATH = None  # --python-path: the folder that holds the package nhdyn, or None
MASKS = [(re.compile(r"wall time [0-9]+(\.[0-9]+)?(e[-+]?[0-9]+)? (ms|s)\b"), "wall time <time>")]
TIMEOUT_S = 120


def doc_files(source):
    files = [source / "README.md"] + sorted((source / "docs").rglob("*.md"))
    return [f for f in files if f.is_file()]


class Block:
    """A marked fenced block: the marker's line (1-based), the command, the content lines."""

    def __init__(self, path, line, command, indent, first, last):
        self.path, self.line, self.command, self.indent = path, line, command, indent
        self.first, self.last = first, last  # 0-based indices of the content lines [first, last)


def find_blocks(path, lines):
    blocks, errors = [], []
    for i, text in enumerate(lines):
        m = MARKER.match(text)
        if not m:
            continue
        indent = m.group(1)
        fence = lines[i + 1] if i + 1 < len(lines) else ""
        if not fence.startswith(indent + "```"):
            errors.append(f"{path}:{i + 1}: a check marker must be followed at once by a ``` fence "
                          f"indented like it")
            continue
        end = i + 2
        while end < len(lines) and lines[end].strip() != "```":
            end += 1
        if end == len(lines):
            errors.append(f"{path}:{i + 2}: the fence after the check marker is not closed")
            continue
        blocks.append(Block(path, i + 1, m.group(2).strip(), indent, i + 2, end))
    return blocks, errors


def environment(nhdyn, workdir):
    env = dict(os.environ)
    env["PATH"] = str(Path(nhdyn).resolve().parent) + os.pathsep + env.get("PATH", "/usr/bin:/bin")
    env["XDG_CACHE_HOME"] = str(workdir / ".cache")
    env["LC_ALL"] = "C"
    if PYTHON_PATH:
        env["PYTHONPATH"] = PYTHON_PATH
    return env


def fresh_directory(source):
    workdir = Path(tempfile.mkdtemp(prefix="nhdyn-docs-"))
    (workdir / "examples").symlink_to(source / "examples")
    return workdir


def run(command, workdir, nhdyn):
    """Runs one shell command; returns (exit code, stdout and stderr together)."""
    try:
        r = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=workdir,
                           env=environment(nhdyn, workdir), stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return None, f"(no answer within {TIMEOUT_S} s)\n"
    return r.returncode, r.stdout.decode("utf-8", "replace")


def masked(text):
    for pattern, replacement in MASKS:
        text = pattern.sub(replacement, text)
    return "\n".join(line.rstrip() for line in text.split("\n"))  # Markdown keeps no trailing blanks


def expected_exit(command):
    m = EXIT_COMMENT.search(command)
    return int(m.group(1)) if m else 0


def check_outputs(source, nhdyn, update):
    failures, count, skipped = [], 0, 0
    for path in doc_files(source):
        lines = path.read_text(encoding="utf-8").split("\n")
        blocks, errors = find_blocks(path.relative_to(source), lines)
        failures += errors
        changed = False
        # Last block first, so that rewriting one keeps the line numbers of those before it.
        for block in reversed(blocks):
            if PYTHON_PATH is None and PYTHON_COMMAND.search(block.command):
                skipped += 1
                continue
            count += 1
            workdir = fresh_directory(source)
            try:
                code, out = run(block.command, workdir, nhdyn)
            finally:
                shutil.rmtree(workdir, ignore_errors=True)
            want_code = expected_exit(block.command)
            where = f"{block.path}:{block.line}: {block.command}"
            if code != want_code:
                failures.append(f"{where}\n  exit code {code}, expected {want_code}; it printed:\n{out}")
                continue
            actual = out.rstrip("\n").split("\n") if out.strip() else []
            quoted = [l[len(block.indent):] if l.startswith(block.indent) else l.lstrip()
                      for l in lines[block.first:block.last]]
            if masked("\n".join(actual)) == masked("\n".join(quoted)):
                continue
            if update:
                lines[block.first:block.last] = [(block.indent + l).rstrip() if l else "" for l in actual]
                changed = True
                print(f"updated {where}")
            else:
                diff = difflib.unified_diff(masked("\n".join(quoted)).split("\n"),
                                            masked("\n".join(actual)).split("\n"),
                                            "quoted", "printed", lineterm="")
                failures.append(f"{where}\n  the quoted output differs from what the command prints "
                                f"(make docs-update rewrites it):\n" + "\n".join(diff))
        if changed:
            path.write_text("\n".join(lines), encoding="utf-8")
    if skipped:
        print(f"{skipped} quoted outputs of Python commands skipped (no --python-path: the package is not built)")
    return count, failures


# A synopsis line, not a command: placeholders (MODEL, FILE.csv, [--opt], <name>, ...) or a line
# continued on the next. And commands that write into the source tree's docs/ (the figures).
SYNOPSIS = re.compile(r"\[|<[A-Za-z]|\.\.\.|\b(MODEL|FILE|NAME|N|R|A,A)\b|my_model|\\$|docs/")


def readme_examples(source):
    """The README's example commands: [(line, command)] per indented code block."""
    blocks, current = [], []

    def flush():
        if any(command.startswith(("nhdyn ", PYTHON_EXAMPLE)) for _, command in current):
            blocks.append(list(current))
        current.clear()

    for number, text in enumerate((source / "README.md").read_text(encoding="utf-8").split("\n"), 1):
        if text.startswith("    "):
            command = text[4:]
            if command.startswith("build/apps/nhdyn/nhdyn "):
                current.append((number, "nhdyn " + command[len("build/apps/nhdyn/nhdyn "):]))
            elif command.startswith("mkdir ") or (PYTHON_PATH and command.startswith(PYTHON_EXAMPLE)):
                current.append((number, command.split("   #")[0].rstrip()))
        elif text.strip():  # a paragraph ends the block; blank lines do not
            flush()
    flush()
    return blocks


def docs_examples(path):
    """The commands of a page of docs/: the lines `nhdyn ...` and `mkdir ...` of its indented code
    blocks and of its ```text blocks that hold commands only (not the quoted outputs after a check
    marker), synopsis lines left out. The ```sh blocks of docs/cli.md are run by the test
    CliDocs.EveryExampleInCliMdRunsAsDocumented (tests/cli/cli_test.cpp), with their exit codes."""
    lines = path.read_text(encoding="utf-8").split("\n")
    commands, i = [], 0
    while i < len(lines):
        text = lines[i]
        if text.strip().startswith("```"):
            end = i + 1
            while end < len(lines) and lines[end].strip() != "```":
                end += 1
            body = [(n + 1, lines[n]) for n in range(i + 1, min(end, len(lines))) if lines[n].strip()]
            marked = i > 0 and MARKER.match(lines[i - 1])
            if (text.strip() == "```text" and not marked and body and
                    all(l.startswith(("nhdyn ", "mkdir ")) for _, l in body)):
                commands += [(n, l) for n, l in body if not SYNOPSIS.search(l)]
            i = end + 1
            continue
        command = text[4:] if text.startswith("    ") else ""
        if command.startswith(("nhdyn ", "mkdir ")) and not SYNOPSIS.search(command):
            commands.append((i + 1, command))
        elif PYTHON_PATH and command.startswith(PYTHON_EXAMPLE):
            commands.append((i + 1, command))
        i += 1
    return commands


def check_examples(source, nhdyn):
    failures, count = [], 0
    have_gnuplot = shutil.which("gnuplot") is not None
    blocks = [("README.md", block) for block in readme_examples(source)]
    for path in sorted((source / "docs").rglob("*.md")):
        commands = docs_examples(path)
        if any(c.startswith(("nhdyn ", PYTHON_EXAMPLE)) for _, c in commands):
            blocks.append((str(path.relative_to(source)), commands))
    for name, block in blocks:
        workdir = fresh_directory(source)
        try:
            for line, command in block:
                if "--plot" in command and not have_gnuplot:
                    continue
                count += 1
                code, out = run(command, workdir, nhdyn)
                if code != 0:
                    failures.append(f"{name}:{line}: {command}\n  exit code {code}; it printed:\n{out}")
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
    return count, failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--nhdyn", required=True, help="the nhdyn binary to run")
    parser.add_argument("--source", default=str(Path(__file__).resolve().parents[2]),
                        help="the source tree (default: the one holding this script)")
    parser.add_argument("--update", action="store_true", help="rewrite the quoted outputs that differ")
    parser.add_argument("--examples", action="store_true", help="run the example commands of the README and docs/")
    parser.add_argument("--python-path", help="PYTHONPATH for the commands: the folder holding the package nhdyn "
                        "(without it, Python's quoted outputs and examples are left out)")
    args = parser.parse_args()
    global PYTHON_PATH
    PYTHON_PATH = str(Path(args.python_path).resolve()) if args.python_path else None
    source = Path(args.source).resolve()
    if not Path(args.nhdyn).is_file():
        print(f"check_docs.py: no nhdyn binary at '{args.nhdyn}': build the target nhdyn_cli first",
              file=sys.stderr)
        return 2
    if args.examples:
        count, failures = check_examples(source, args.nhdyn)
        what = "example commands"
    else:
        count, failures = check_outputs(source, args.nhdyn, args.update)
        what = "quoted outputs"
    for failure in failures:
        print(failure, file=sys.stderr)
    print(f"{count} {what} checked, {len(failures)} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
