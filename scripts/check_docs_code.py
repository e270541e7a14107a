#!/usr/bin/env python3
"""Checks that the code a document shows is the code a test compiles.

  scripts/check_docs_code.py [FILE.md ...]

Every code block in docs/*.md (or the given files) preceded by the line
`<!-- code: PATH -->` must equal the text between the lines `// EXAMPLE BEGIN` and
`// EXAMPLE END` of PATH (relative to the repository root), apart from whitespace (the
documents may wrap lines differently from clang-format). Exit 0 when every block matches, 1
otherwise naming the document, the line and the first differing token.
"""
import glob
import os
import re
import sys

MARKER = re.compile(r"^<!--\s*code:\s*(\S+)\s*-->\s*$")


def example(path):
    text = open(path, encoding="utf-8").read()
    begin, end = text.find("// EXAMPLE BEGIN\n"), text.find("// EXAMPLE END")
    if begin < 0 or end < begin:
        raise SystemExit(f"{path}: no // EXAMPLE BEGIN ... // EXAMPLE END block")
    return text[begin + len("// EXAMPLE BEGIN\n"):end]


def check(doc, root):
    lines = open(doc, encoding="utf-8").read().split("\n")
    problems, count = [], 0
    for i, line in enumerate(lines):
        m = MARKER.match(line)
        if not m:
            continue
        j = i + 1
        if j >= len(lines) or not lines[j].startswith("```"):
            problems.append(f"{doc}:{i + 1}: marker not followed by a code block")
            continue
        k = j + 1
        while k < len(lines) and not lines[k].startswith("```"):
            k += 1
        shown = "\n".join(lines[j + 1:k]).split()
        tested = example(os.path.join(root, m.group(1))).split()
        count += 1
        if shown != tested:
            at = next((n for n, (a, b) in enumerate(zip(shown, tested)) if a != b),
                      min(len(shown), len(tested)))
            got = shown[at] if at < len(shown) else "<end>"
            want = tested[at] if at < len(tested) else "<end>"
            problems.append(f"{doc}:{j + 1}: block differs from {m.group(1)}'s EXAMPLE at "
                            f"token {at}: '{got}' vs '{want}'")
    return problems, count


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    docs = sys.argv[1:] or sorted(glob.glob(os.path.join(root, "docs", "*.md")))
    problems, count = [], 0
    for doc in docs:
        p, c = check(doc, root)
        problems += p
        count += c
    for p in problems:
        print(p)
    print(f"check_docs_code: {count} block(s), {len(problems)} problem(s)")
    return 1 if problems or count == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
