#!/usr/bin/env python3
"""Checks two rules of hooke's layout (CONTRIBUTING.md, "Layers" and "Function length"):

1. Layers. solver/ is layered bottom-up as CONTRIBUTING.md lists it between the markers
   `<!-- layers -->` and `<!-- /layers -->` (that list is the only copy: this script reads it). A
   file includes hooke headers of its own layer or lower ones only; solver/ includes nothing of
   problems/, experiments/ or python/, and problems/ nothing of experiments/ or python/.
2. Function length. No function in solver/, problems/, experiments/ or python/ is longer than
   100 lines (as Universal Ctags measures it: from its first line to its closing brace).
3. Command files. A subcommand `hooke NAME` is defined (`Command add_NAME_command(CLI::App&)`)
   in a file named for one of the commands it defines, `NAME_command.cpp`, and only there:
   experiments/run/ for running a scene, experiments/studies/ for the studies, experiments/ for
   the rest (CONTRIBUTING.md, "A CLI subcommand").

Usage: check-layout.py [ROOT]   (ROOT: the source tree, default the parent of this script's
folder). Prints every violation and exits 1 if there is one, 2 if it cannot check.
"""
import os
import re
import shutil
import subprocess
import sys

MAX_FUNCTION_LINES = 100
SOURCE_EXT = (".hpp", ".cpp", ".inc", ".in", ".h")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
TOP_FOLDERS = ["solver", "problems", "experiments", "python"]  # bottom-up


def read_layers(root):
    """The layers from CONTRIBUTING.md: a list of sets of units, bottom-up. Each item of the list
    is "N. `unit`, `unit`: what it holds"; a unit is a folder of solver/ (`forces/`) or a file
    name at solver/'s root (`core.hpp`, `registry.*`)."""
    text = open(os.path.join(root, "CONTRIBUTING.md"), encoding="utf-8").read()
    m = re.search(r"<!-- layers -->(.*?)<!-- /layers -->", text, re.S)
    if not m:
        sys.exit("check-layout: CONTRIBUTING.md has no <!-- layers --> list")
    layers = []
    for line in m.group(1).splitlines():
        item = re.match(r"\s*\d+\.\s+([^:]*):", line)
        if not item:
            continue  # a continuation line of the item above
        units = set(re.findall(r"`([^`]+)`", item.group(1)))
        if not units:
            sys.exit(f"check-layout: a layer without `units` before its colon: {line.strip()}")
        layers.append({u.rstrip("/") for u in units})
    if not layers:
        sys.exit("check-layout: the <!-- layers --> list is empty")
    return layers


def layer_of(path_in_solver, layers):
    """The layer index of a file given by its path inside solver/, or None if no layer names it.
    A folder's sub-folders (linear/cholmod/) belong to the folder's layer."""
    parts = path_in_solver.split("/")
    for i, units in enumerate(layers):
        if len(parts) > 1:
            if parts[0] in units:
                return i
        else:
            name = parts[0]
            stem = name.split(".")[0]
            if name in units or stem + ".*" in units:
                return i
            if name.endswith(".in") and name[:-3] in units:  # config.hpp.in -> config.hpp
                return i
    return None


def source_files(root, top):
    for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
        dirnames[:] = sorted(d for d in dirnames if d not in ("__pycache__", "scenes"))
        for f in sorted(filenames):
            if f.endswith(SOURCE_EXT):
                yield os.path.join(dirpath, f)


def check_layers(root, layers):
    problems = []
    for path in source_files(root, "solver"):
        rel = os.path.relpath(path, os.path.join(root, "solver")).replace(os.sep, "/")
        if rel == "CMakeLists.txt":
            continue
        mine = layer_of(rel, layers)
        if mine is None:
            problems.append(f"solver/{rel}: in no layer of CONTRIBUTING.md's list")
            continue
        text = open(path, encoding="utf-8").read()
        for inc in INCLUDE.findall(text):
            if not inc.startswith("hooke/"):
                if inc.split("/")[0] in TOP_FOLDERS[1:]:
                    problems.append(f"solver/{rel}: includes {inc} from outside solver/")
                continue
            target = inc[len("hooke/"):]
            theirs = layer_of(target, layers)
            if theirs is None:
                problems.append(f"solver/{rel}: includes {inc}, in no layer")
            elif theirs > mine:
                problems.append(f"solver/{rel} (layer {mine + 1}) includes {inc} "
                                f"(layer {theirs + 1}, higher)")
    for level, top in enumerate(TOP_FOLDERS[:3]):
        for path in source_files(root, top):
            for inc in INCLUDE.findall(open(path, encoding="utf-8").read()):
                head = inc.split("/")[0]
                if head in TOP_FOLDERS and TOP_FOLDERS.index(head) > level:
                    rel = os.path.relpath(path, root).replace(os.sep, "/")
                    problems.append(f"{rel} includes {inc}, from a higher folder")
    return problems


def check_function_length(root):
    ctags = shutil.which("ctags")
    if ctags is None:
        print("check-layout: ctags not found (Debian package universal-ctags; "
              "scripts/install-deps.sh installs it)", file=sys.stderr)
        sys.exit(2)
    files = [p for top in TOP_FOLDERS for p in source_files(root, top)
             if p.endswith((".cpp", ".hpp", ".inc", ".h"))]
    out = subprocess.run(
        [ctags, "-x", "--_xformat=%n %e %F %N", "--fields=+ne", "--kinds-c++=f",
         "--language-force=c++", "-f", "-"] + files,
        check=True, capture_output=True, text=True).stdout
    problems = []
    for line in out.splitlines():
        fields = line.split(" ", 3)
        if len(fields) < 4 or not fields[1].isdigit():
            continue
        begin, end = int(fields[0]), int(fields[1])
        if end - begin + 1 > MAX_FUNCTION_LINES:
            rel = os.path.relpath(fields[2], root).replace(os.sep, "/")
            problems.append(f"{rel}:{begin}: {fields[3]} is {end - begin + 1} lines "
                            f"(at most {MAX_FUNCTION_LINES})")
    return problems


COMMAND = re.compile(r"^Command add_(\w+)_command\(CLI::App& \w+\) \{", re.M)


def check_command_files(root):
    problems = []
    for path in source_files(root, "experiments"):
        if not path.endswith(".cpp"):
            continue
        with open(path, encoding="utf-8") as f:
            names = COMMAND.findall(f.read())
        rel = os.path.relpath(path, root).replace(os.sep, "/")
        base = os.path.basename(path)
        if names and base not in {n + "_command.cpp" for n in names}:
            problems.append(f"{rel} defines add_{names[0]}_command: name it {names[0]}_command.cpp")
        if not names and base.endswith("_command.cpp"):
            problems.append(f"{rel} is named as a command file but defines no add_*_command")
    return problems


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))
    layers = read_layers(root)
    problems = (check_layers(root, layers) + check_function_length(root) +
                check_command_files(root))
    for p in problems:
        print(p)
    if problems:
        print(f"check-layout: {len(problems)} violation(s) of CONTRIBUTING.md's layout rules")
        return 1
    print(f"check-layout: {len(layers)} layers of solver/ respected; "
          f"no function over {MAX_FUNCTION_LINES} lines; every command in its NAME_command.cpp")
    return 0


if __name__ == "__main__":
    sys.exit(main())
