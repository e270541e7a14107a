#!/usr/bin/env python3
"""Compares the tables and result rows of two `regbench reproduce` folders, timing aside.

  compare_reports.py ONE OTHER

The tables (tables.md, tables_full.md, tables.tex, tables.csv, tables.json) must be byte for
byte equal apart from timing: the cells of timing columns (a header naming ms, seconds, s/pair
or "x floor"; not the paper's columns) and the GEMM rate a caption measured ("16.2 GMAC/s",
or the range of several processes' rates, "15.9-16.3 GMAC/s") are blanked on both sides first. Every results/*.jsonl must hold the same rows in the same
order apart from their timing fields (any key naming seconds, the GEMM rate, `machine`).
Exit 0 when equal, 1 naming the first difference of each file.
"""
import difflib
import glob
import json
import os
import re
import sys

TIMING_HEADER = re.compile(r"(^|\s)(ms|s)$|\bms\b|s/pair|seconds|x floor")
TIMING_KEY = re.compile(r"seconds|gmac_per_s|^machine$|^cpu_ms|^network_ms|^floor_ms|^x_floor")
RATE = re.compile(r"[0-9.]+(-[0-9.]+)? GMAC/s")


def timing_header(header):
    header = header.replace("*", "").strip()
    return not header.startswith("paper") and bool(TIMING_HEADER.search(header))


def markdown_masked(text):
    lines = text.split("\n")
    headers = {i for i in range(len(lines) - 1)
               if lines[i].startswith("|") and lines[i + 1].startswith("|---")}
    out, timing = [], None
    for i, line in enumerate(lines):
        line = RATE.sub("# GMAC/s", line)
        if i in headers:
            timing = [k for k, h in enumerate(line.split("|")) if timing_header(h)]
        elif not line.startswith("|"):
            timing = None
        elif timing and not line.startswith("|---"):
            cells = line.split("|")
            line = "|".join("#" if k in timing else c for k, c in enumerate(cells))
        out.append(line)
    return "\n".join(out)


def latex_masked(text):
    out, timing, header_next = [], None, False
    for line in text.split("\n"):
        line = RATE.sub("# GMAC/s", line)
        if line.startswith("\\toprule"):
            header_next = True
        elif header_next:
            header_next = False
            timing = [k for k, h in enumerate(line.rstrip(" \\").split(" & ")) if timing_header(h)]
        elif line.startswith("\\bottomrule"):
            timing = None
        elif timing and " & " in line:
            cells = line.rstrip(" \\").split(" & ")
            line = " & ".join("#" if k in timing else c for k, c in enumerate(cells)) + " \\\\"
        out.append(line)
    return "\n".join(out)


def csv_masked(text):
    # One record per (table, row, column); the column key is the third field (no commas in
    # keys), the header the fourth.
    out = []
    for line in text.split("\n"):
        fields = line.split(",")
        if len(fields) > 3 and TIMING_KEY.search(fields[2].split(".")[-1]):
            line = ",".join(fields[:4]) + ",#"
        out.append(line)
    return "\n".join(out)


def json_masked(text):
    records = json.loads(text)
    for r in records:
        if TIMING_KEY.search(r.get("column", "").split(".")[-1]):
            for k in ("value", "ci95_half_width", "ci95_lo", "ci95_hi", "text"):
                r[k] = "#"
    return json.dumps(records, indent=1, sort_keys=True)


def strip_row(value):
    if isinstance(value, dict):
        return {k: strip_row(v) for k, v in value.items() if not TIMING_KEY.search(k)}
    if isinstance(value, list):
        return [strip_row(v) for v in value]
    return value


def rows(path):
    with open(path, encoding="utf-8") as f:
        return "\n".join(json.dumps(strip_row(json.loads(l)), sort_keys=True)
                         for l in f if l.strip())


def main():
    one, other = sys.argv[1], sys.argv[2]
    checks = [("tables.md", markdown_masked), ("tables_full.md", markdown_masked),
              ("tables.tex", latex_masked), ("tables.csv", csv_masked),
              ("tables.json", json_masked)]
    problems = []
    compared = 0

    def compare(name, a, b):
        nonlocal compared
        compared += 1
        if a != b:
            diff = difflib.unified_diff(a.split("\n"), b.split("\n"), os.path.join(one, name),
                                        os.path.join(other, name), n=0, lineterm="")
            problems.append("\n".join(list(diff)[:12]))

    for name, mask in checks:
        texts = []
        for folder in (one, other):
            with open(os.path.join(folder, name), encoding="utf-8") as f:
                texts.append(mask(f.read()))
        compare(name, *texts)
    names = sorted(os.path.basename(p) for p in glob.glob(os.path.join(one, "results", "*.jsonl")))
    others = sorted(os.path.basename(p) for p in glob.glob(os.path.join(other, "results", "*.jsonl")))
    if names != others:
        problems.append(f"result files differ: {names} vs {others}")
    for name in names:
        if name in others:
            compare("results/" + name, rows(os.path.join(one, "results", name)),
                    rows(os.path.join(other, "results", name)))
    if problems:
        print("\n".join(problems), file=sys.stderr)
        return 1
    print(f"equal, timing aside: {compared} files ({len(names)} result files)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
