#!/usr/bin/env bash
# test/cli_fmt_g17.sh: ./tdc's "%.17g" without printf (src/cli/fmt_g17.c),
# which writes its triangles, contour lines and .asc grids, against the C
# library's snprintf on 20 million and more doubles (test/fmt_g17.c says
# which); every text must be the same, byte for byte.
#   bash test/cli_fmt_g17.sh        (prints "N passed, N failed")
set -u
cd "$(dirname "$0")/.."
make -s build/fmt_g17 >/dev/null || { echo "cannot build build/fmt_g17"; echo "0 passed, 1 failed"; exit 1; }
build/fmt_g17
