#!/usr/bin/env bash
# test/hardening/core_cancel.sh: the core's own share of cancel latency
# (no PostgreSQL needed): builds core_cancel.c against src/core and cancels
# jobs at evenly spread moments of a run, timing tdc_job_wait after
# tdc_job_cancel ("stop") and tdc_job_free ("free").
#
#   bash test/hardening/core_cancel.sh [POINTS [THREADS [RUNS [MAX_STOP_MS [MAX_FREE_MS]]]]]
#   default: 2000000 points, 2 threads, 30 runs, stop <= 100 ms, free <= 150 ms
#
# Prints one line per run, a summary per phase and "N passed, N failed".
# About 30 s for 2M points.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
BIN=$(mktemp "${TMPDIR:-/tmp}/tdc_core_cancel.XXXXXX")
trap 'rm -f "$BIN"' EXIT
"${CC_CORE:-cc}" -std=c11 -D_GNU_SOURCE -O2 -ffp-contract=off -pthread -I"$ROOT/src/core" \
	-o "$BIN" "$HERE/core_cancel.c" "$ROOT"/src/core/*/*.c -lm
echo "== core_cancel.sh"
"$BIN" "${1:-2000000}" "${2:-2}" "${3:-30}" "${4:-100}" "${5:-150}"
