#!/usr/bin/env bash
# scripts/test.sh (`make test`): every test of tdc_delaunay, from a bare Debian
# (12, 13 or testing), on the release's PostgreSQL major or PG_CONFIG's.
#
#   1. apt-get installs the missing Debian packages (scripts/lib.sh lists them)
#   2. builds and installs the extension, and builds ./tdc
#   3. the core suite: make check-core, check-core-asan, check-core-tsan,
#      test/hardening/core_cancel.sh with CI limits, and a short run of the
#      libFuzzer targets (make fuzz-run)
#   4. starts a throw-away PostgreSQL cluster (or uses yours, see README.md)
#      and runs pg_regress against it (make installcheck)
#   5. every executable test/*.sh, with the server's PG* settings exported
#   6. the CI-sized hardening scripts in test/hardening/ (settings,
#      bad_input, memcap, concurrency and cancel with QUICK=1), on the
#      throw-away cluster
#   7. test/citus/run.sh: tdc_delaunay_tiled on a throw-away 3-node Citus
#      cluster (Citus built from ../shared/citus, cached between runs)
#   8. with TDC_MATRIX=1 (as .ci/run sets it): on the PostgreSQL of other Debian
#      releases (TDC_MATRIX_SUITES, default "trixie forky": PostgreSQL 17 and
#      18), in debootstrap roots (scripts/roots.sh, kept between runs in
#      TDC_ROOTS_DIR), the build, pg_regress and a 100k-point smoke test.
#      The roots are prepared in the background from the start (network and
#      dpkg, mostly); each release is one part.  Needs root.
#
# Each part prints "N passed, N failed" (pg_regress: "All N tests passed." or
# "N of M tests failed."); they are added up into the last line of output,
# "N passed, N failed".  A part that prints no such line counts as a failure,
# even if it exits 0.  Exits non-zero if anything failed.  The throw-away
# server is always stopped on exit.  `bash scripts/test.sh --self-test` tests
# this counting alone (it is also the first part of every run).
#
# TDC_PART_TIMEOUT=SECONDS bounds each part (default 900).
# TDC_CORE_CANCEL_MAX_MS=MS stop and free limits of core_cancel.sh (default 750).
# TDC_FUZZ_SECONDS=SECONDS per fuzz target (default 60; 0 skips fuzzing).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$TDC_ROOT"
mkdir -p "$TDC_LOGDIR"

PART_TIMEOUT=${TDC_PART_TIMEOUT:-900}
# test/hardening/ scripts run here: without a server, and on the throw-away
# cluster (their README's CI column must say the same; --self-test checks).
HARDENING_CORE=(core_cancel)
HARDENING_SERVER=(settings bad_input memcap concurrency cancel leak)
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

# The counts of a part from its log and exit status, into PART_P, PART_F and
# PART_NOTE.  A part that printed no count line has not shown that it tested
# anything: it counts as one failure whatever its exit status, and so does
# a non-zero exit after a count line without failures, or a timeout.
part_counts() {	# counts log rc
	local counts=$1 log=$2 rc=$3 line
	PART_P=0 PART_F=0 PART_NOTE=""
	if [ "$counts" = regress ]; then
		line=$(grep -Eo '(All [0-9]+ tests passed|[0-9]+ of [0-9]+ tests (failed|passed))' "$log" | tail -n 1 || true)
		case "$line" in
			All*) PART_P=$(echo "$line" | awk '{print $2}') ;;
			*failed) PART_F=$(echo "$line" | awk '{print $1}'); PART_P=$(($(echo "$line" | awk '{print $3}') - PART_F)) ;;
			*passed) PART_P=$(echo "$line" | awk '{print $1}'); PART_F=$(($(echo "$line" | awk '{print $3}') - PART_P)) ;;
		esac
	else
		line=$(grep -Eo '(^|[[:space:]])[0-9]+ passed, [0-9]+ failed' "$log" | tail -n 1 || true)
		if [ -n "$line" ]; then
			PART_P=$(echo "$line" | awk '{print $1}')
			PART_F=$(echo "$line" | awk '{print $3}')
		fi
	fi
	if ((rc == 124 || rc == 137)); then
		PART_NOTE="timed out after ${PART_TIMEOUT}s"
		((PART_F > 0)) || PART_F=1
	elif [ -z "$line" ]; then
		PART_F=1
		PART_NOTE="(no count line; exit $rc)"
	elif ((rc != 0 && PART_F == 0)); then
		PART_F=1
		PART_NOTE="(exit $rc after reporting no failure)"
	fi
}

# scripts/test.sh --self-test: part_counts on made-up logs (the first part
# of every run, so that a change to the counting is tested too).
if [ "${1:-}" = --self-test ]; then
	st_pass=0 st_fail=0
	st_log=$(mktemp)
	st_case() {	# counts rc "log text" want_p want_f
		printf '%b' "$3" >"$st_log"
		part_counts "$1" "$st_log" "$2"
		if [ "$PART_P/$PART_F" = "$4/$5" ]; then
			st_pass=$((st_pass + 1))
		else
			st_fail=$((st_fail + 1))
			echo "FAIL: counts=$1 exit $2 log '$3': got $PART_P/$PART_F (passed/failed), want $4/$5"
		fi
	}
	st_case plain 0 'x: 3 passed, 0 failed\n' 3 0
	st_case plain 0 'engine: 9 passed, 0 failed so far\n12 passed, 0 failed\n' 12 0
	st_case plain 0 '' 0 1
	st_case plain 0 'all good\n' 0 1
	st_case plain 2 '' 0 1
	st_case plain 1 '2 passed, 0 failed\n' 2 1
	st_case plain 1 '5 passed, 2 failed\n' 5 2
	st_case plain 124 '4 passed, 0 failed\n' 4 1
	st_case regress 0 ' All 7 tests passed. \n' 7 0
	st_case regress 2 ' 1 of 7 tests failed. \n' 6 1
	st_case regress 0 '' 0 1
	rm -f "$st_log"
	# every hardening script the README says runs in CI is run here
	while read -r h; do
		if [[ " ${HARDENING_CORE[*]} ${HARDENING_SERVER[*]} " == *" $h "* ]]; then
			st_pass=$((st_pass + 1))
		else
			st_fail=$((st_fail + 1))
			echo "FAIL: test/hardening/README.md says $h.sh runs in CI; scripts/test.sh does not run it"
		fi
	done < <(awk -F'|' '$2 ~ /^ `[a-z_]+[.]sh` $/ && $5 !~ /^ *no/ { gsub(/[` ]|[.]sh/, "", $2); print $2 }' \
			 test/hardening/README.md)
	for h in "${HARDENING_CORE[@]}" "${HARDENING_SERVER[@]}"; do
		if [ -f "test/hardening/$h.sh" ]; then
			st_pass=$((st_pass + 1))
		else
			st_fail=$((st_fail + 1))
			echo "FAIL: test/hardening/$h.sh is missing"
		fi
	done
	echo "$st_pass passed, $st_fail failed"
	((st_fail == 0))
	exit
fi

CHILD=
on_exit() {
	local rc=$?
	[ -z "$CHILD" ] || kill -TERM "$CHILD" 2>/dev/null || true
	# A root still being made is stopped, and waited for: nothing this run
	# started may outlive it (a process left in a chroot keeps its mounts busy).
	local s n
	for s in "${!MATRIX_PID[@]}"; do
		[ -n "${MATRIX_PID[$s]}" ] || continue
		kill -TERM -- "-${MATRIX_PID[$s]}" 2>/dev/null || true
		for ((n = 0; n < 30; n++)); do
			kill -0 -- "-${MATRIX_PID[$s]}" 2>/dev/null || break
			sleep 1
		done
		kill -KILL -- "-${MATRIX_PID[$s]}" 2>/dev/null || true
		wait "${MATRIX_PID[$s]}" 2>/dev/null || true
	done
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
	local log=$TDC_LOGDIR/$name.log rc t0=$SECONDS
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
	part_counts "$counts" "$log" "$rc"
	record "$name" "$PART_P" "$PART_F" "$((SECONDS - t0)) s $PART_NOTE"
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

run_part test.sh-counting plain bash scripts/test.sh --self-test
MATRIX=${TDC_MATRIX:-0}
# shellcheck disable=SC2206  # a list of suite names
MATRIX_SUITES=(${TDC_MATRIX_SUITES:-trixie forky})
((MATRIX)) && TDC_EXTRA_PACKAGES="${TDC_EXTRA_PACKAGES:-} debootstrap"
run_step packages tdc_ensure_packages || true
# on a fresh machine the step above learnt the major (in its subshell)
tdc_set_major

# The matrix's roots, made (or updated) in the background while the rest runs.
declare -A MATRIX_PID=()
if ((MATRIX)); then
	for s in "${MATRIX_SUITES[@]}"; do
		# a process group of its own, so that on_exit can stop debootstrap and apt-get too
		setsid bash scripts/roots.sh prepare "$s" >"$TDC_LOGDIR/root-$s.log" 2>&1 </dev/null &
		MATRIX_PID[$s]=$!
		tdc_say "[matrix] preparing the $s root in the background (log: build/logs/root-$s.log)"
	done
fi
built=0
run_step build+install tdc_build_install && built=1

MAKE=(make --no-print-directory PG_CONFIG="$PG_CONFIG")
# ./tdc for the harnesses in test/*.sh (an old binary would test old code).
run_step "make tdc" "${MAKE[@]}" tdc || true
run_part check-core plain "${MAKE[@]}" check-core
run_part check-core-asan plain "${MAKE[@]}" check-core-asan
run_part check-core-tsan plain "${MAKE[@]}" check-core-tsan
# The core's cancel latency (no server).  Its default limits (stop 100 ms,
# free 150 ms) hold on a quiet machine; on 2 shared cores at load 5-9 stops
# of 130-210 ms were seen, so CI allows 750 ms each: still far below the
# rest of a 2M-point run, which a job that ignored the cancel would take.
for h in "${HARDENING_CORE[@]}"; do
	case $h in
		core_cancel) run_part "hardening-$h" plain bash "test/hardening/$h.sh" 2000000 2 12 \
			"${TDC_CORE_CANCEL_MAX_MS:-750}" "${TDC_CORE_CANCEL_MAX_MS:-750}" ;;
		*) run_part "hardening-$h" plain bash "test/hardening/$h.sh" ;;
	esac
done

# libFuzzer targets (fuzz/), a short run from their seed corpora.
FUZZ_SECONDS=${TDC_FUZZ_SECONDS:-60}
if ((FUZZ_SECONDS > 0)); then
	run_part fuzz plain "${MAKE[@]}" fuzz-run FUZZ_SECONDS="$FUZZ_SECONDS"
fi

server=0
if tdc_use_existing || (tdc_cluster_paths && [ -x "$TDC_PGBIN/initdb" ]) >/dev/null 2>&1; then
	# Not in a subshell: the server's PG* settings must reach the parts below.
	# If it cannot start, on_exit reports the run as aborted.
	tdc_server_up
	server=1
else
	record server 0 1 "($(tdc_pg_name) is not installed)"
fi

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

for t in test/*.sh; do
	[ -x "$t" ] || continue
	run_part "$(basename "$t" .sh)" plain "./$t"
done

# The CI-sized hardening scripts (test/hardening/README.md), on the throw-away
# cluster only: they need a superuser and keep tables in a schema tdc_hard.
# TDC_HARDENING=0 skips them, =1 runs them on your server too.
hardening=${TDC_HARDENING:-$((!TDC_EXISTING))}
if ((hardening && built && server)); then
	for h in "${HARDENING_SERVER[@]}"; do
		case $h in
			concurrency) run_part "hardening-$h" plain env QUICK=1 bash "test/hardening/$h.sh" ;;
			cancel) run_part "hardening-$h" plain env QUICK=1 MAX_LATENCY_MS="${TDC_CANCEL_MAX_MS:-1000}" \
				bash "test/hardening/$h.sh" ;;
			*) run_part "hardening-$h" plain bash "test/hardening/$h.sh" ;;
		esac
	done
fi

# Citus (test/citus/run.sh): builds Citus 13.2.2 from ../shared/citus once
# (cached in ~/.cache/tdc-citus, about 4-12 minutes on 2 cores), then runs
# tdc_delaunay_tiled on its own throw-away coordinator and two workers
# (about 40 s).  TDC_CITUS=0 skips it, and so does a clone without the
# Citus source beside it (../shared/citus, or TDC_CITUS_SRC): Debian has no
# Citus to install instead; and a PostgreSQL major Citus 13.2.2 does not
# support (18).  The summary says so.
citus_src=${TDC_CITUS_SRC:-$TDC_ROOT/../shared/citus}
if ((${TDC_CITUS:-1} && built)); then
	if [ ! -f "$citus_src/citus-13.2.2.tar.gz" ]; then
		tdc_warn "no Citus source ($citus_src/citus-13.2.2.tar.gz): the Citus part is skipped"
		record citus 0 0 "skipped: no Citus source (../shared/citus or TDC_CITUS_SRC)"
	elif ! why=$(PG_CONFIG=$PG_CONFIG bash test/citus/build.sh --supported 2>&1); then
		tdc_say "[citus] skipped: ${why#citus-build: }"
		record citus 0 0 "skipped: ${why#citus-build: }"
	else
		# its first run builds Citus: up to 12 minutes on a loaded 2-core machine
		PART_TIMEOUT=$((PART_TIMEOUT * 2)) run_part citus plain env PG_CONFIG="$PG_CONFIG" bash test/citus/run.sh
	fi
fi

# The matrix: each release's root, once ready, builds and tests a copy of
# this tree (scripts/roots.sh check).  A root not ready within the part's
# timeout, or that failed, counts as one failure.
for s in "${MATRIX_SUITES[@]}"; do
	[ -n "${MATRIX_PID[$s]:-}" ] || continue
	t0=$SECONDS
	while kill -0 "${MATRIX_PID[$s]}" 2>/dev/null && ((SECONDS - t0 < PART_TIMEOUT)); do
		sleep 2
	done
	if kill -0 "${MATRIX_PID[$s]}" 2>/dev/null; then
		kill -TERM -- "-${MATRIX_PID[$s]}" 2>/dev/null || true
	fi
	rc=0
	wait "${MATRIX_PID[$s]}" || rc=$?
	MATRIX_PID[$s]=
	sed 's/^/    /' "$TDC_LOGDIR/root-$s.log"
	if ((rc == 0)); then
		run_part "matrix-$s" plain bash scripts/roots.sh check "$s"
	else
		record "matrix-$s" 0 1 "(root not ready: exit $rc after $((SECONDS - t0)) s of waiting; build/logs/root-$s.log)"
	fi
done

tdc_server_down
FINISHED=1
print_summary
((TOTAL_FAILED == 0))
