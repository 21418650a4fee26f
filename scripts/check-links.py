#!/usr/bin/env python3
"""Checks that every relative link in the project's Markdown files points at a file (and, with
an anchor, a heading) inside the checkout, so that a clone without ../shared follows every
doc link (issue 22).

    python3 scripts/check-links.py          # prints each broken link; exit 1 if any

Checked: Markdown links `[text](target)` and `<a href>`-free reference links `[x]: target` in
every tracked *.md file (README.md, docs/, fixtures/, ...). Web links (http, https, mailto)
are not fetched. A link leaving the checkout (`../shared/...`) is broken by definition: a
clone does not have it. Anchors are compared with GitHub's heading slugs.
"""
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)|^\s*\[[^\]]+\]:\s*(\S+)", re.M)
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def markdown_files():
    try:
        out = subprocess.run(["git", "ls-files", "*.md"], cwd=ROOT, capture_output=True,
                             text=True, check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        out = []
        for d, dirs, files in os.walk(ROOT):
            dirs[:] = [x for x in dirs if x not in ("target", ".git")]
            out += [os.path.relpath(os.path.join(d, f), ROOT) for f in files if f.endswith(".md")]
    return sorted(out)


def slug(heading):
    s = heading.strip().lower()
    s = re.sub(r"[`*_]", "", s)
    s = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", s)
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        found = set()
        counts = {}
        in_code = False
        with open(path, encoding="utf-8") as f:
            for line in f:
                if line.startswith("```"):
                    in_code = not in_code
                    continue
                m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
                if m and not in_code:
                    base = slug(m.group(1))
                    n = counts.get(base, 0)
                    counts[base] = n + 1
                    found.add(base if n == 0 else f"{base}-{n}")
        cache[path] = found
    return cache[path]


def main():
    broken = []
    checked = 0
    for md in markdown_files():
        full = os.path.join(ROOT, md)
        with open(full, encoding="utf-8") as f:
            text = f.read()
        # Links inside code blocks and code spans are examples, not links.
        text = re.sub(r"```.*?```", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
        text = re.sub(r"`[^`\n]*`", "``", text)
        for m in list(LINK.finditer(text)) + list(IMAGE.finditer(text)):
            target = next(g for g in m.groups() if g)
            if re.match(r"^[a-z]+:", target):
                continue
            checked += 1
            line = text.count("\n", 0, m.start()) + 1
            file_part, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(full), file_part)) if file_part else full
            if not dest.startswith(ROOT + os.sep) and dest != ROOT:
                broken.append(f"{md}:{line}: {target}: outside the checkout")
            elif not os.path.exists(dest):
                broken.append(f"{md}:{line}: {target}: no such file")
            elif anchor and dest.endswith(".md") and anchor not in anchors(dest):
                broken.append(f"{md}:{line}: {target}: no heading #{anchor}")
    for b in broken:
        print(b)
    print(f"check-links: {checked} links checked, {len(broken)} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
