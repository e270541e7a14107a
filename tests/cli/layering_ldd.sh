#!/usr/bin/env bash
# Layering check: the given binaries (the tests of core/, gmm/ and protocols/) must not link
# the heavy registration libraries, so those layers keep building and running without them.
# Usage: layering_ldd.sh BINARY... Prints one line per forbidden library found, naming the
# binary and the library, and exits 1 if there is any. CGAL is matched as libCGAL: since
# CGAL 5 it is header-only and leaves no shared library that ldd could show.
set -uo pipefail
[ "$#" -gt 0 ] || { echo "usage: layering_ldd.sh BINARY..." >&2; exit 2; }
status=0
for bin in "$@"; do
  if ! libs="$(ldd "$bin" 2>&1)"; then
    echo "FAIL: ldd $bin: $libs" >&2
    status=1
    continue
  fi
  while read -r lib _; do
    case "$lib" in
      libCGAL*) family=CGAL ;;
      libOpen3D*) family=Open3D ;;
      libpcl_*) family=PCL ;;
      libtorch*|libc10*) family=Torch ;;
      *) continue ;;
    esac
    echo "FAIL: $bin links $family ($lib)" >&2
    status=1
  done <<< "$libs"
done
[ "$status" -eq 0 ] && echo "ok: $# binaries link none of CGAL, Open3D, PCL, Torch"
exit "$status"
