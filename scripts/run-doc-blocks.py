#!/usr/bin/env python3
"""Runs the shell blocks of the documentation that are marked runnable (CTest `Docs.RunnableBlocks`).

A block is runnable when the line just before its ```sh fence is an HTML comment (invisible
where the Markdown is rendered) of the form

    <!-- runnable -->
    <!-- runnable; in CI 'OLD' becomes 'NEW'; 'OLD2' becomes 'NEW2' -->
    <!-- runnable; needs mpirun -->

The second form says where CI runs a smaller size than the reader would (e.g. a shorter
duration): each quoted OLD text of the block is replaced by NEW before it runs, and the marker
says so where the block is written. "needs X" names a program (on PATH) or a path (from the
project root: build/python) that a build may lack (an optional dependency): without it the block
is reported as skipped, not run. Each block runs as one bash script (so `export` carries to the
lines after it) in a scratch folder that holds `problems/` and `experiments/` (links into the
source tree) and `build/bin/hooke` and `build/python` (links to the build), so the commands run as
written from the project root and write their output (`out/`) into the scratch folder. A command
must exit 0, or the code its trailing comment names as "(exit N)". The first failure stops the
script with the file, line, command and the end of its output; it exits 1 then, 2 when it cannot
run at all.

Usage: run-doc-blocks.py SOURCE_DIR BUILD_DIR HOOKE SCRATCH_DIR
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import time

MARKER = re.compile(r"^<!--\s*runnable(?P<rest>[^>]*)-->\s*$")
REPLACE = re.compile(r"'([^']*)'\s+becomes\s+'([^']*)'")
NEEDS = re.compile(r"needs\s+([^\s;]+)")
EXPECTED_EXIT = re.compile(r"#.*\(exit (\d+)\)")


def blocks(path):
    """(first line number, lines, replacements, needs) of every runnable block of one file."""
    lines = open(path, encoding="utf-8").read().splitlines()
    found = []
    for i, line in enumerate(lines):
        m = MARKER.match(line.strip())
        if not m or i + 1 >= len(lines) or not re.match(r"^```(sh|bash)\s*$", lines[i + 1]):
            if m:
                sys.exit(f"run-doc-blocks: {path}:{i + 1}: a runnable marker not followed by ```sh")
            continue
        end = next((j for j in range(i + 2, len(lines)) if lines[j].startswith("```")), None)
        if end is None:
            sys.exit(f"run-doc-blocks: {path}:{i + 2}: the block never closes")
        rest = m.group("rest")
        found.append((i + 3, lines[i + 2:end], REPLACE.findall(rest), NEEDS.findall(rest)))
    return found


def commands(first_line, body):
    """(line number, command) per logical line: continuations joined, blank and comment lines left out."""
    out, pending, start = [], "", None
    for n, line in enumerate(body, first_line):
        if start is None:
            start = n
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        text = (pending + line).strip()
        pending = ""
        if text and not text.startswith("#"):
            out.append((start, text))
        start = None
    return out


def script(path, cmds):
    """A bash script that runs cmds and stops at the first one with an unexpected exit code."""
    parts = ["set -u"]
    for n, cmd in cmds:
        m = EXPECTED_EXIT.search(cmd)
        want = int(m.group(1)) if m else 0
        where = f"{os.path.relpath(path)}:{n}".replace("'", "")
        parts.append(f"echo '+ {where}' >&2")
        parts.append(cmd)
        parts.append(f"rc=$?; if [ $rc -ne {want} ]; then echo \"run-doc-blocks: {where}: exit $rc, "
                     f"expected {want}\" >&2; exit 1; fi")
    return "\n".join(parts) + "\n"


def scratch(source, build, hooke, folder):
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(os.path.join(folder, "build", "bin"))
    for name in ("problems", "experiments"):
        os.symlink(os.path.join(source, name), os.path.join(folder, name))
    os.symlink(hooke, os.path.join(folder, "build", "bin", "hooke"))
    if os.path.isdir(os.path.join(build, "python")):
        os.symlink(os.path.join(build, "python"), os.path.join(folder, "build", "python"))


def main():
    if len(sys.argv) != 5:
        print(__doc__, file=sys.stderr)
        return 2
    source, build, hooke, folder = (os.path.abspath(a) for a in sys.argv[1:])
    os.chdir(source)
    files = ["README.md"] + sorted(glob.glob("docs/*.md"))
    count = skipped = 0
    for path in files:
        for first, body, replacements, needs in blocks(path):
            scratch(source, build, hooke, folder)
            missing = [n for n in needs
                       if not (shutil.which(n) or os.path.exists(os.path.join(folder, n)))]
            if missing:
                print(f"{path}:{first}: skipped: this build has no {', '.join(missing)}")
                skipped += 1
                continue
            text = "\n".join(body)
            for old, new in replacements:
                if old not in text:
                    print(f"run-doc-blocks: {path}:{first}: the marker replaces '{old}', which the block "
                          "does not hold", file=sys.stderr)
                    return 1
                text = text.replace(old, new)
            cmds = commands(first, text.splitlines())
            t0 = time.monotonic()
            r = subprocess.run(["bash", "-c", script(os.path.join(source, path), cmds)], cwd=folder,
                               capture_output=True, text=True)
            print(f"{path}:{first}: {len(cmds)} commands, exit {r.returncode}, "
                  f"{time.monotonic() - t0:.1f} s")
            if r.returncode != 0:
                print(r.stdout[-2000:], file=sys.stderr)
                print(r.stderr[-3000:], file=sys.stderr)
                return 1
            count += 1
    if count == 0:
        print("run-doc-blocks: no block is marked runnable", file=sys.stderr)
        return 1
    print(f"run-doc-blocks: {count} runnable blocks of {len(files)} files ran as documented"
          + (f", {skipped} skipped" if skipped else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
