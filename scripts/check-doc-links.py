#!/usr/bin/env python3
"""Checks the relative links of the project's Markdown files: every link to a file must name an
existing file, every #anchor a heading of the file it points into (GitHub's heading ids).

Usage: scripts/check-doc-links.py ROOT [FILE.md ...]
  With no FILE, checks ROOT/README.md and ROOT/docs/*.md. Exit 0 when every link resolves, 1
  with one line per broken link ("FILE:LINE: link TARGET: why").
Links to other sites (http:, https:, mailto:) are not checked: tests must not need a network.
"""

import pathlib
import re
import sys

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def prose_lines(text):
    """(line number, line) outside fenced code blocks, with inline code spans removed."""
    fenced = False
    for number, line in enumerate(text.splitlines(), start=1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            yield number, re.sub(r"`[^`]*`", "", line)


def heading_ids(path):
    """GitHub's ids of the headings of a Markdown file (duplicates get -1, -2, ...)."""
    ids, seen = set(), {}
    fenced = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        match = None if fenced else HEADING.match(line)
        if not match:
            continue
        slug = re.sub(r"[^\w\- ]", "", match.group(2).strip().lower()).replace(" ", "-")
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        ids.add(slug if count == 0 else f"{slug}-{count}")
    return ids


def check(root, path):
    problems = []
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        for target in LINK.findall(line):
            if re.match(r"^[a-z]+:", target):
                continue
            file_part, _, anchor = target.partition("#")
            linked = (path.parent / file_part).resolve() if file_part else path.resolve()
            where = f"{path.relative_to(root)}:{number}: link {target}"
            if not linked.exists():
                problems.append(f"{where}: {file_part} does not exist")
            elif anchor and linked.suffix == ".md" and anchor not in heading_ids(linked):
                problems.append(f"{where}: no heading #{anchor} in {linked.relative_to(root)}")
    return problems


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    root = pathlib.Path(argv[1]).resolve()
    files = [pathlib.Path(f).resolve() for f in argv[2:]]
    if not files:
        files = [root / "README.md"] + sorted((root / "docs").glob("*.md"))
    problems = [problem for path in files for problem in check(root, path)]
    for problem in problems:
        print(problem)
    if not problems:
        print(f"{len(files)} files, every relative link resolves")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
