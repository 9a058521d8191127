#!/usr/bin/env bash
# fuzz/run.sh: run libFuzzer targets for a while each (`make fuzz-run`).
#
#   bash fuzz/run.sh [TARGET...]      default: fuzz_core fuzz_gserialized fuzz_state
#                                     fuzz_voronoi fuzz_cdt fuzz_raster fuzz_pcpatch
#
#   FUZZ_SECONDS=60     -max_total_time per target
#   FUZZ_ARGS=...       extra libFuzzer flags (e.g. -seed=1 -jobs=2)
#
# Each target starts from its seed corpus fuzz/corpus/TARGET (read-only) and
# a working corpus build/fuzz/work/TARGET (grows between runs).  Crashes go
# to build/fuzz/artifacts/TARGET-*.  libFuzzer first runs every input of
# both corpora, whatever FUZZ_SECONDS (which counts from its start), and
# says "INITED"; then it mutates them until the time is up.  A target passes
# when its corpus ran through (INITED) and libFuzzer ended without a
# finding.  Prints executions per target and "N passed, N failed"; exits
# non-zero if any target failed.  Build first with `make fuzz`.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

SECONDS_PER=${FUZZ_SECONDS:-60}
read -r -a EXTRA <<<"${FUZZ_ARGS:-}"
if (($# == 0)); then
	set -- fuzz_core fuzz_gserialized fuzz_state fuzz_voronoi fuzz_cdt fuzz_raster fuzz_pcpatch
fi

passed=0
failed=0
lines=()
for t in "$@"; do
	bin=build/fuzz/$t
	if [ ! -x "$bin" ]; then
		echo "$t: $bin not built (make fuzz)" >&2
		failed=$((failed + 1))
		lines+=("$(printf '  %-18s NOT BUILT' "$t")")
		continue
	fi
	case $t in
		fuzz_core) maxlen=16384 ;;
		*) maxlen=8192 ;;
	esac
	mkdir -p "build/fuzz/work/$t" build/fuzz/artifacts
	log=build/fuzz/$t.log
	echo "== $t: ${SECONDS_PER}s (log $log)"
	rc=0
	"$bin" -max_total_time="$SECONDS_PER" -max_len="$maxlen" -timeout=30 \
		-rss_limit_mb=2560 -print_final_stats=1 \
		-artifact_prefix="build/fuzz/artifacts/$t-" ${EXTRA[@]+"${EXTRA[@]}"} \
		"build/fuzz/work/$t" "fuzz/corpus/$t" >"$log" 2>&1 || rc=$?
	execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
	cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | cut -d' ' -f2)
	if ((rc == 0)) && grep -q 'INITED' "$log" &&
		! grep -q '^==[0-9]*==ERROR\|^SUMMARY: \(libFuzzer\|AddressSanitizer\|UndefinedBehaviorSanitizer\)' "$log"; then
		passed=$((passed + 1))
		status=ok
	else
		failed=$((failed + 1))
		status="FAILED (exit $rc; see $log and build/fuzz/artifacts/)"
		grep -q 'INITED' "$log" || status="FAILED (the corpus was not run through: no INITED; see $log)"
		grep -m3 'ERROR\|SUMMARY\|fuzz_[a-z]*: ' "$log" | sed 's/^/    /' || true
	fi
	lines+=("$(printf '  %-18s %10s executions  cov %5s  %s' "$t" "${execs:-?}" "${cov:-?}" "$status")")
done
echo
printf '%s\n' "${lines[@]}"
echo "$passed passed, $failed failed"
((failed == 0))
