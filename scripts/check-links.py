#!/usr/bin/env python3
"""Checks every relative link (and #anchor) in README.md, HACKING.md, tools/eval/README.md and docs/*.md.

    python3 scripts/check-links.py [ROOT]    (ROOT: the source tree, default: this script's parent)
"""
import os, re, sys, glob
root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
files = ["README.md", "HACKING.md", "tools/eval/README.md"] + sorted(os.path.relpath(p, root) for p in glob.glob(os.path.join(root, "docs", "*.md")))
def anchors(path):
    out = set()
    in_code = False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            in_code = not in_code
        if in_code:
            continue
        m = re.match(r"#+\s+(.*)", line)
        if m:
            t = m.group(1).strip().lower()
            t = re.sub(r"[^\w\- ]", "", t).replace(" ", "-")
            out.add(t)
    return out
bad = 0
n = 0
for f in files:
    text = open(os.path.join(root, f), encoding="utf-8").read()
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target):
            continue
        n += 1
        path, _, frag = target.partition("#")
        full = os.path.normpath(os.path.join(root, os.path.dirname(f), path)) if path else os.path.join(root, f)
        if not os.path.exists(full):
            print(f"{f}: {target}: no such file"); bad += 1; continue
        if frag and full.endswith(".md") and frag not in anchors(full):
            print(f"{f}: {target}: no such anchor"); bad += 1
print(f"{n} links checked in {len(files)} files, {bad} broken")
sys.exit(1 if bad else 0)
