#!/usr/bin/env bash
# Screenshots of a `regbench reproduce` HTML report with Debian's headless Chromium, as in
# docs/reproducing.md: the top of the page (the paper's tables) and one experiment's plots. The second shot
# loads the report in an iframe shifted up by OFFSET pixels, so the picture is the real render
# of that part of the page.
# Usage: scripts/screenshot_report.sh REPORT.html OUT_DIR [OFFSET]   (OFFSET default 5640: the
# tab1_same section of a `reproduce --quick` report at 1200 px width)
set -euo pipefail
report="$(realpath "$1")"
out="$2"
offset="${3:-5640}"
mkdir -p "$out"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
chrome=(timeout 300 chromium --headless --no-sandbox --disable-gpu --disable-background-networking
        --disable-component-update --disable-sync --no-first-run --allow-file-access-from-files
        --user-data-dir="$tmp/profile")
"${chrome[@]}" --screenshot="$out/report-tables.png" --window-size=1200,820 "file://$report" \
  >"$tmp/log" 2>&1
cat >"$tmp/crop.html" <<HTML
<html><body style="margin:0;overflow:hidden"><iframe src="file://$report" scrolling="no"
style="border:0;position:absolute;top:-${offset}px;left:0;width:1200px;height:40000px"></iframe>
</body></html>
HTML
"${chrome[@]}" --screenshot="$out/report-plots.png" --window-size=1200,1000 "file://$tmp/crop.html" \
  >>"$tmp/log" 2>&1
ls -l "$out/report-tables.png" "$out/report-plots.png"
