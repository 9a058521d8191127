#!/usr/bin/env bash
# scripts/test.sh (`make test`): every test of tdc_delaunay, from a bare Debian 12.
#
#   1. apt-get installs the missing Debian packages (scripts/lib.sh lists them)
#   2. builds and installs the extension, and builds ./tdc
#   3. the core suite: make check-core, check-core-asan, check-core-tsan, and
#      a short run of the libFuzzer targets (make fuzz-run)
#   4. starts a throw-away PostgreSQL 15 cluster (or uses yours, see README.md)
#      and runs pg_regress against it (make installcheck)
#   5. every executable test/*.sh, with the server's PG* settings exported
#   6. the CI-sized hardening scripts in test/hardening/ (bad_input, memcap,
#      concurrency and cancel with QUICK=1), on the throw-away cluster
#
# Each part prints "N passed, N failed" (pg_regress: "All N tests passed." or
# "N of M tests failed."); they are added up into the last line of output,
# "N passed, N failed".  Exits non-zero if anything failed.  The throw-away
# server is always stopped on exit.
#
# TDC_PART_TIMEOUT=SECONDS bounds each part (default 900).
# TDC_FUZZ_SECONDS=SECONDS per fuzz target (default 60; 0 skips fuzzing).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$TDC_ROOT"
mkdir -p "$TDC_LOGDIR"

PART_TIMEOUT=${TDC_PART_TIMEOUT:-900}
TOTAL_PASSED=0
TOTAL_FAILED=0
SUMMARY=()
FINISHED=0

record() {	# name passed failed [note]
	TOTAL_PASSED=$((TOTAL_PASSED + $2))
	TOTAL_FAILED=$((TOTAL_FAILED + $3))
	SUMMARY+=("$(printf '  %-28s %7d passed, %5d failed  %s' "$1" "$2" "$3" "${4:-}")")
}

print_summary() {
	echo
	echo "==================== tdc_delaunay test summary ===================="
	printf '%s\n' "${SUMMARY[@]}"
	echo "=================================================== $SECONDS s in all ==="
	echo "$TOTAL_PASSED passed, $TOTAL_FAILED failed"
}

CHILD=
on_exit() {
	local rc=$?
	[ -z "$CHILD" ] || kill -TERM "$CHILD" 2>/dev/null || true
	tdc_server_down
	if ((!FINISHED)); then
		record "(aborted)" 0 1 "scripts/test.sh stopped early with status $rc"
		print_summary
		exit 1
	fi
}
trap on_exit EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# Run one part: its output goes to the terminal and to build/logs/NAME.log;
# its counts are read from the last count line it printed.
#   counts=plain    "N passed, N failed" (optionally "Word: " before it)
#   counts=regress  pg_regress's "All N tests passed." / "N of M tests failed."
run_part() {	# name counts command...
	local name=$1 counts=$2
	shift 2
	local log=$TDC_LOGDIR/$name.log rc p=0 f=0 line note="" t0=$SECONDS
	tdc_say "[$name] $*"
	# In the background so that Ctrl-C reaches the trap at once (timeout runs
	# the part in a process group of its own and relays the TERM we send it).
	: >"$log"
	timeout -k 30 "$PART_TIMEOUT" "$@" >>"$log" 2>&1 </dev/null &
	CHILD=$!
	tail --pid="$CHILD" -n +1 -f "$log" &
	rc=0
	wait "$CHILD" || rc=$?
	CHILD=
	wait $! || true
	if [ "$counts" = regress ]; then
		line=$(grep -Eo '(All [0-9]+ tests passed|[0-9]+ of [0-9]+ tests (failed|passed))' "$log" | tail -n 1 || true)
		case "$line" in
			All*) p=$(echo "$line" | awk '{print $2}') ;;
			*failed) f=$(echo "$line" | awk '{print $1}'); p=$(($(echo "$line" | awk '{print $3}') - f)) ;;
			*passed) p=$(echo "$line" | awk '{print $1}'); f=$(($(echo "$line" | awk '{print $3}') - p)) ;;
		esac
	else
		line=$(grep -Eo '(^|[[:space:]])[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1 || true)
		if [ -n "$line" ]; then
			p=$(echo "$line" | awk '{print $1}')
			f=$(echo "$line" | awk '{print $3}')
		fi
	fi
	if ((rc == 124 || rc == 137)); then
		note="timed out after ${PART_TIMEOUT}s"
		((f > 0)) || f=1
	elif [ -z "$line" ]; then
		if ((rc == 0)); then
			p=1
			note="(no count line; exit 0)"
		else
			f=1
			note="(no count line; exit $rc)"
		fi
	elif ((rc != 0 && f == 0)); then
		f=1
		note="(exit $rc after reporting no failure)"
	fi
	record "$name" "$p" "$f" "$((SECONDS - t0)) s $note"
	return 0
}

# Steps that count only when they fail (the set-up).
run_step() {	# name command...
	local name=$1 rc
	shift
	set +e
	(
		set -e
		"$@"
	)
	rc=$?
	set -e
	((rc == 0)) && return 0
	record "$name" 0 1 "(failed, exit $rc)"
	return 1
}

echo "tdc_delaunay: make test ($(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) CPUs)"

run_step packages tdc_ensure_packages || true
built=0
run_step build+install tdc_build_install && built=1

MAKE=(make --no-print-directory PG_CONFIG="$PG_CONFIG")
# ./tdc for the harnesses in test/*.sh (an old binary would test old code).
run_step "make tdc" "${MAKE[@]}" tdc || true
run_part check-core plain "${MAKE[@]}" check-core
run_part check-core-asan plain "${MAKE[@]}" check-core-asan
run_part check-core-tsan plain "${MAKE[@]}" check-core-tsan

# libFuzzer targets (fuzz/), a short run from their seed corpora.
FUZZ_SECONDS=${TDC_FUZZ_SECONDS:-60}
if grep -q '^fuzz-run:' Makefile && ((FUZZ_SECONDS > 0)); then
	run_part fuzz plain "${MAKE[@]}" fuzz-run FUZZ_SECONDS="$FUZZ_SECONDS"
fi

server=0
if tdc_use_existing || (tdc_cluster_paths && [ -x "$TDC_PGBIN/initdb" ]) >/dev/null 2>&1; then
	# Not in a subshell: the server's PG* settings must reach the parts below.
	# If it cannot start, on_exit reports the run as aborted.
	tdc_server_up
	server=1
else
	record server 0 1 "(PostgreSQL $TDC_PG_MAJOR is not installed)"
fi

if compgen -G 'sql/*.sql' >/dev/null; then
	if ((built && server)); then
		mkdir -p build/regress
		run_part pg_regress regress "${MAKE[@]}" installcheck
		if [ -s build/regress/regression.diffs ]; then
			echo "--- build/regress/regression.diffs (first 80 lines) ---"
			head -n 80 build/regress/regression.diffs
		fi
	else
		record pg_regress 0 1 "(not run: no build or no server)"
	fi
else
	record pg_regress 0 0 "(no sql/*.sql yet)"
fi

for t in test/*.sh; do
	[ -f "$t" ] && [ -x "$t" ] || continue
	run_part "$(basename "$t" .sh)" plain "./$t"
done

# The CI-sized hardening scripts (test/hardening/README.md), on the throw-away
# cluster only: they need a superuser and keep tables in a schema tdc_hard.
# TDC_HARDENING=0 skips them, =1 runs them on your server too.
hardening=${TDC_HARDENING:-$((!TDC_EXISTING))}
if ((hardening && built && server)) && [ -d test/hardening ]; then
	for h in settings bad_input memcap concurrency cancel; do
		[ -f "test/hardening/$h.sh" ] || continue
		case $h in
			concurrency) run_part "hardening-$h" plain env QUICK=1 bash "test/hardening/$h.sh" ;;
			cancel) run_part "hardening-$h" plain env QUICK=1 MAX_LATENCY_MS="${TDC_CANCEL_MAX_MS:-1000}" \
				bash "test/hardening/$h.sh" ;;
			*) run_part "hardening-$h" plain bash "test/hardening/$h.sh" ;;
		esac
	done
fi

tdc_server_down
FINISHED=1
print_summary
((TOTAL_FAILED == 0))
