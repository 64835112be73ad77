#!/usr/bin/env python3
"""Checks that the paper's prose states no measured number (issue 58, item 5).

Every measured number in the paper comes from a table that `make paper` generates. This script
finds every decimal, exponent or percentage in paper/paper.md's prose (code spans, include lines
and HTML comments left out: commands and generated tables) and requires each to be listed in
paper/stated-numbers.txt with why it is not a measurement (a setting, a test's bound, theory).
A new number in the prose therefore needs a line there, which a reviewer reads; a measured one
needs a generated table instead.

Usage: check-paper-numbers.py PAPER_MD STATED_NUMBERS   (exit 1 naming each unlisted number)
"""
import re
import sys

NUMBER = re.compile(r"(?<![\w.^/])(\d+\.\d+|\d+(?:\.\d+)?e[-+]?\d+|\d+(?:\.\d+)?\s?%)(?!\w)")


def prose(text):
    text = re.sub(r"<!--.*?-->", "", text, flags=re.S)  # comments and include lines
    text = re.sub(r"\A---\n.*?\n---\n", "", text, flags=re.S)  # the front matter
    return re.sub(r"`[^`]*`", "", text)  # code spans: commands, keys, names


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    listed = set()
    for line in open(sys.argv[2], encoding="utf-8"):
        if line.strip() and not line.startswith("#"):
            listed.add(line.split()[0])
    unlisted = []
    for n, line in enumerate(prose(open(sys.argv[1], encoding="utf-8").read()).splitlines(), 1):
        for m in NUMBER.finditer(line):
            token = m.group(1).replace(" ", "")
            if token not in listed:
                unlisted.append(f"{sys.argv[1]}: '{token}' in: {line.strip()[:100]}")
    for u in unlisted:
        print(u, file=sys.stderr)
    if unlisted:
        print(f"check-paper-numbers: {len(unlisted)} numbers of the prose are neither generated nor "
              f"listed in {sys.argv[2]} as settings, bounds or theory", file=sys.stderr)
        return 1
    print(f"check-paper-numbers: every number of the prose is listed ({len(listed)} listed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
