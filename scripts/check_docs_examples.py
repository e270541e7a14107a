#!/usr/bin/env python3
"""Checks that documented command output still matches what the commands print now.

  scripts/check_docs_examples.py TRANSCRIPTS_DIR [--require NAME ...] [FILE.md ...]

Every code block in README.md and docs/*.md (or the given files) preceded by the line
`<!-- docs_examples: NAME -->` (optionally `<!-- docs_examples: NAME skip="REGEX" -->`) is
compared with TRANSCRIPTS_DIR/NAME.txt, written by scripts/docs_examples.sh. Each documented
line must appear in the transcript, in order (the transcript may have more lines). Two lines
match when their text is equal apart from numbers and runs of spaces, and every number agrees:
  - within 1e-4 relative or one unit in the last digit the documentation prints;
  - timings are not compared: a number followed by " s", a cell of a table column whose
    header ends in " s" or names seconds, and every number of a documented line that matches
    the block's skip regex (e.g. a pandas table of seconds);
  - paths must be the same text, so a documented absolute path from some machine fails.
Blocks whose transcript is absent are listed as not checked (scripts/docs_examples.sh --fast
runs only the fast examples) unless named with --require. Exit 0 when every checked block
matches, 1 otherwise with the first unmatched line of each block.
"""
import argparse
import glob
import os
import re
import sys

NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
MARKER = re.compile(r'^<!--\s*docs_examples:\s*([A-Za-z0-9_]+)(?:\s+skip="([^"]*)")?\s*-->\s*$')


def blocks(path):
    """(name, skip regex or None, first line number, lines) of each marked code block."""
    lines = open(path, encoding="utf-8").read().split("\n")
    out = []
    i = 0
    while i < len(lines):
        m = MARKER.match(lines[i])
        if not m:
            i += 1
            continue
        j = i + 1
        while j < len(lines) and not lines[j].strip():
            j += 1
        if j >= len(lines) or not lines[j].startswith("```"):
            raise SystemExit(f"{path}:{i + 1}: marker '{m.group(1)}' is not followed by a code block")
        k = j + 1
        while k < len(lines) and not lines[k].startswith("```"):
            k += 1
        out.append((m.group(1), m.group(2), j + 2, lines[j + 1:k]))
        i = k + 1
    return out


def last_digit_unit(token):
    mantissa = re.split(r"[eE]", token)[0]
    exponent = int(re.split(r"[eE]", token)[1]) if re.search(r"[eE]", token) else 0
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 10.0 ** (exponent - decimals)


def timing_positions(line, header):
    """Indices (among the line's numbers) that are timings."""
    nums = list(NUMBER.finditer(line))
    skip = set()
    for n, m in enumerate(nums):
        if re.match(r"\s?s\b", line[m.end():]):
            skip.add(n)
    if header and line.startswith("|"):
        names = [c.strip() for c in header.strip().strip("|").split("|")]
        cells = line.strip().strip("|").split("|")
        offset = line.index("|") + 1
        for c, cell in enumerate(cells):
            start, end = offset, offset + len(cell)
            offset = end + 1
            if c < len(names) and (names[c].endswith(" s") or "seconds" in names[c]):
                for n, m in enumerate(nums):
                    if start <= m.start() < end:
                        skip.add(n)
    return skip


def same(doc, got, header, skip_all):
    if re.sub(r"\s+", " ", NUMBER.sub("#", doc)).strip() != \
            re.sub(r"\s+", " ", NUMBER.sub("#", got)).strip():
        return False
    dn, gn = NUMBER.findall(doc), NUMBER.findall(got)
    if len(dn) != len(gn):
        return False
    if skip_all:
        return True
    skip = timing_positions(doc, header)
    for n, (a, b) in enumerate(zip(dn, gn)):
        if n in skip:
            continue
        x, y = float(a), float(b)
        if abs(x - y) > max(1e-4 * max(abs(x), abs(y)), last_digit_unit(a) * 1.0001):
            return False
    return True


def check(name, skip, lines, transcript):
    got = open(transcript, encoding="utf-8", errors="replace").read().split("\n")
    skip_re = re.compile(skip) if skip else None
    header = None
    pos = 0
    for n, doc in enumerate(lines):
        if doc.startswith("|") and n + 1 < len(lines) and re.match(r"^\|[-:| ]+\|$", lines[n + 1]):
            header = doc
        skip_all = bool(skip_re and skip_re.search(doc))
        while pos < len(got) and not same(doc, got[pos], header, skip_all):
            pos += 1
        if pos == len(got):
            return doc
        pos += 1
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("transcripts")
    ap.add_argument("files", nargs="*")
    ap.add_argument("--require", nargs="*", default=[])
    a = ap.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    files = a.files or [os.path.join(root, "README.md")] + sorted(
        glob.glob(os.path.join(root, "docs", "*.md")))
    failed = 0
    seen = set()
    for path in files:
        for name, skip, first, lines in blocks(path):
            seen.add(name)
            where = f"{os.path.relpath(path, root)}:{first}"
            transcript = os.path.join(a.transcripts, name + ".txt")
            if not os.path.exists(transcript):
                if name in a.require:
                    print(f"FAIL {where}: {name}: no transcript {transcript}")
                    failed += 1
                else:
                    print(f"not checked {where}: {name} (no transcript; a slow example)")
                continue
            bad = check(name, skip, lines, transcript)
            if bad is None:
                print(f"ok {where}: {name} ({len(lines)} lines)")
            else:
                print(f"FAIL {where}: {name}: this documented line is not printed any more "
                      f"(or not in this order):\n  {bad}\n  see {transcript}")
                failed += 1
    for name in a.require:
        if name not in seen:
            print(f"FAIL: no documented block is marked '{name}'")
            failed += 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
