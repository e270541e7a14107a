#!/usr/bin/env bash
# Unpacks the embedded default corpus (CGAL's demo meshes, Debian package libcgal-demo)
# into data/meshes/ (git-ignored). Idempotent.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$root/data/meshes"
if [ -f "$dest/.complete" ]; then
  echo "[setup_data] meshes present in $dest"
  exit 0
fi
archive=""
for candidate in /usr/share/doc/libcgal-dev/data.tar.gz /usr/share/doc/libcgal-demo/data.tar.gz; do
  if [ -f "$candidate" ]; then archive="$candidate"; break; fi
done
if [ -z "$archive" ]; then
  echo "[setup_data] error: CGAL demo data not found (install libcgal-demo)" >&2
  exit 1
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
tar xzf "$archive" -C "$tmp" data/meshes
rm -rf "$dest"
mkdir -p "$(dirname "$dest")"
mv "$tmp/data/meshes" "$dest"
touch "$dest/.complete"
echo "[setup_data] unpacked $(ls "$dest" | wc -l) files from $archive into $dest"
