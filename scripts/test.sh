#!/usr/bin/env bash
# scripts/test.sh (`make test`): every test of tdc_delaunay, from a bare Debian
# (12, 13 or testing), on the release's PostgreSQL major or PG_CONFIG's.
#
#   1. apt-get installs the missing Debian packages (scripts/lib.sh lists
#      them; the Citus build's and, for the matrix, debootstrap with them;
#      nodejs and npm unless node and npm are there)
#   2. starts the lanes, parts that run in the background one after the
#      other, each lane beside the others and the foreground:
#        core        make check-core, check-core-asan, check-core-tsan
#        fuzz        make fuzz-run: each libFuzzer target replays its corpus,
#                    then fuzzes for TDC_FUZZ_SECONDS (default 20)
#        citus-build Citus 13.2.2 from ../shared/citus (test/citus/build.sh,
#                    cached in ~/.cache/tdc-citus), when the major has Citus
#        matrix-S    with TDC_MATRIX=1 (.ci/run's default), for each release S
#                    of TDC_MATRIX_SUITES (default "trixie forky": PostgreSQL
#                    17 and 18): its debootstrap root made or updated
#                    (scripts/roots.sh prepare, kept in TDC_ROOTS_DIR), then
#                    the build, pg_regress and a 100k-point smoke test in it
#                    (roots.sh check).  Needs root.
#   3. in the foreground: builds and installs the extension and ./tdc,
#      starts a throw-away PostgreSQL cluster (or uses yours, see README.md),
#      runs pg_regress against it (make installcheck), every executable
#      test/*.sh with the server's PG* settings exported, the CI-sized
#      hardening scripts of test/hardening/ (settings, bad_input, memcap,
#      concurrency, leak), and test/citus/run.sh (tdc_delaunay_tiled on a
#      throw-away 3-node Citus cluster, with the lane's build)
#   4. waits for the lanes and prints their parts
#   5. with no lane left, what measures latencies: test/hardening/core_cancel.sh
#      with CI limits, and test/hardening/cancel.sh (QUICK=1)
#
# Why lanes: on 2 shared cores the suite is CPU-bound, and beside busy loops
# (a shared machine; FRESH_BUSY) the scheduler gives each runnable process
# its share, so one part at a time gets a fraction of the machine.  Several
# at once take back what the loops would have had; the matrix roots wait on
# the network and dpkg meanwhile.
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
# TDC_FUZZ_SECONDS=SECONDS per fuzz target (default 20; 0 skips fuzzing).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$TDC_ROOT"
mkdir -p "$TDC_LOGDIR"

PART_TIMEOUT=${TDC_PART_TIMEOUT:-900}
# the test build leaves out the JIT bitcode (scripts/lib.sh, tdc_build_install)
export TDC_WITH_LLVM=${TDC_WITH_LLVM:-no}
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
declare -A LANE_PID=()
on_exit() {
	local rc=$? l n
	[ -z "$CHILD" ] || kill -TERM "$CHILD" 2>/dev/null || true
	# Stop every part and lane still running, and wait for them: nothing
	# this run started may outlive it (inside a chroot, a process left
	# behind keeps the chroot's mounts busy, and whoever removes the chroot
	# then walks through them).  TERM, up to 30 s, then KILL.  A part's
	# command runs under `timeout`, in a process group of its own, whose id
	# part_exec keeps in build/logs/NAME.log.pgid while it runs.
	local groups=() g f
	for l in "${!LANE_PID[@]}"; do
		[ -z "${LANE_PID[$l]}" ] || groups+=("${LANE_PID[$l]}")
	done
	for f in "$TDC_LOGDIR"/*.pgid; do
		[ -f "$f" ] && read -r g <"$f" && [ -n "$g" ] && groups+=("$g")
	done
	for g in "${groups[@]}"; do
		kill -TERM -- "-$g" 2>/dev/null || true
	done
	for ((n = 0; n < 30; n++)); do
		l=0
		for g in "${groups[@]}"; do
			kill -0 -- "-$g" 2>/dev/null && l=1
		done
		((l)) || break
		sleep 1
	done
	for g in "${groups[@]}"; do
		kill -KILL -- "-$g" 2>/dev/null || true
	done
	wait 2>/dev/null || true
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

# A part's command under `timeout` (which runs it in a process group of its
# own and relays a TERM to all of it), its output appended to LOG; then
# "EXIT CPU WALL" into LOG.status: the exit status, the CPU seconds of all
# its processes (user + system: `times` of a shell that ran nothing else)
# and the wall seconds.
part_exec() {	# log command...
	# shellcheck disable=SC2016  # expanded by the inner bash
	bash -c '
		log=$1 limit=$2
		shift 2
		timeout -k 30 "$limit" "$@" >>"$log" 2>&1 </dev/null &
		pid=$!
		# timeout leads a process group of its own: on_exit stops it by that
		echo "$pid" >"$log.pgid"
		trap "kill -TERM $pid 2>/dev/null" TERM INT HUP
		rc=0
		wait "$pid" || rc=$?
		# a signal ends the wait, not the part: wait for the part itself
		while kill -0 "$pid" 2>/dev/null; do rc=0; wait "$pid" || rc=$?; done
		times >"$log.times"
		cpu=$(awk "NR == 2 { for (i = 1; i <= 2; i++) { split(\$i, a, /[ms]/); s += a[1] * 60 + a[2] } printf \"%.0f\", s }" "$log.times")
		rm -f "$log.times" "$log.pgid"
		echo "$rc $cpu $SECONDS" >"$log.status"
		exit "$rc"
	' part "$1" "$PART_TIMEOUT" "${@:2}"
}

# Record the part NAME from build/logs/NAME.log and its .status: its counts
# (part_counts), wall and CPU seconds.
record_part() {	# name counts [note]
	local log=$TDC_LOGDIR/$1.log rc=1 cpu="" secs=""
	[ -s "$log.status" ] && read -r rc cpu secs <"$log.status"
	part_counts "$2" "$log" "$rc"
	record "$1" "$PART_P" "$PART_F" "${secs:-?} s${cpu:+, cpu $cpu s}${3:+ $3}${PART_NOTE:+ $PART_NOTE}"
}

# Run one part in the foreground: its output goes to the terminal and to
# build/logs/NAME.log; its counts are read from the last count line it printed.
#   counts=plain    "N passed, N failed" (optionally "Word: " before it)
#   counts=regress  pg_regress's "All N tests passed." / "N of M tests failed."
run_part() {	# name counts command...
	local name=$1 counts=$2
	shift 2
	local log=$TDC_LOGDIR/$name.log
	tdc_say "[$name] $*"
	# In the background so that Ctrl-C reaches the trap at once.
	: >"$log"
	rm -f "$log.status"
	part_exec "$log" "$@" &
	CHILD=$!
	tail --pid="$CHILD" -n +1 -f "$log" &
	wait "$CHILD" || true
	CHILD=
	wait $! || true
	record_part "$name" "$counts"
	return 0
}

# Lanes: parts that run in the background, one after the other, beside the
# foreground's.  A lane is a process group of its own (on_exit stops all of
# it).  Its parts write only to their logs, which collect_lane prints, and
# records, once the lane has ended.
start_lane() {	# name command...
	local name=$1
	shift
	set -m
	"$@" </dev/null >/dev/null 2>&1 &
	LANE_PID[$name]=$!
	set +m
	tdc_say "[lane $name] in the background: $*"
}

lane_part() {	# name command...   (inside a lane)
	local log=$TDC_LOGDIR/$1.log
	printf '==> [%s] %s\n' "$1" "${*:2}" >"$log"
	rm -f "$log.status"
	part_exec "$log" "${@:2}" || true
}

lane_part_ok() {	# name: did that lane part exit 0?
	[ "$(cut -d' ' -f1 "$TDC_LOGDIR/$1.log.status" 2>/dev/null)" = 0 ]
}

wait_lane() {	# name
	[ -n "${LANE_PID[$1]:-}" ] || return 0
	wait "${LANE_PID[$1]}" || true
	LANE_PID[$1]=
}

# Wait for the lane, then print and record its parts (plain counts), in order.
collect_lane() {	# lane part...
	local lane=$1 p
	shift
	wait_lane "$lane"
	for p in "$@"; do
		tdc_say "[$p] (ran in the background, lane $lane; log build/logs/$p.log)"
		cat "$TDC_LOGDIR/$p.log" 2>/dev/null || echo "(no log: the lane stopped before this part)"
		record_part "$p" plain "(bg)"
	done
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
# Citus: its build's -dev packages come with ours (one apt-get run, before
# the lanes start); whether the major is one Citus supports is known later.
citus_src=${TDC_CITUS_SRC:-$TDC_ROOT/../shared/citus}
CITUS=${TDC_CITUS:-1}
if ((CITUS)) && [ -f "$citus_src/citus-13.2.2.tar.gz" ]; then
	TDC_EXTRA_PACKAGES="${TDC_EXTRA_PACKAGES:-} $(bash test/citus/build.sh --deps)"
fi
run_step packages tdc_ensure_packages || true
# test/cli_las.sh's loaders.gl cross-check (under CI it fails without them)
run_step node tdc_ensure_node || true
# on a fresh machine the step above learnt the major (in its subshell)
tdc_set_major
MAKE=(make --no-print-directory PG_CONFIG="$PG_CONFIG")

# --- The lanes, started at once --------------------------------------------
#
# On 2 shared cores the suite is CPU-bound.  Run one after the other, its
# parts leave one core idle most of the time, and beside busy loops (a
# shared machine, or FRESH_BUSY) the scheduler gives one runnable process
# no more than its share: running several at once takes more of the CPU.
# What runs in the lanes needs neither the server nor a quiet machine; what
# measures a latency (core_cancel, the hardening cancel script) runs at the
# end, when the lanes are done.  The core suites' own cancel checks and
# pg_regress's tdc_cancel keep margins meant for a loaded machine (250 ms,
# best of 3 tries; 400 ms past the timeout).

# The matrix: each release's root is made (or updated) and then tested
# (scripts/roots.sh check) in a lane of its own; mostly network and dpkg.
matrix_lane() {	# suite
	# a fresh root: debootstrap and the packages, up to twice a part's time
	PART_TIMEOUT=$((PART_TIMEOUT * 2)) lane_part "root-$1" bash scripts/roots.sh prepare "$1"
	lane_part_ok "root-$1" || return 0
	lane_part "matrix-$1" bash scripts/roots.sh check "$1"
}
if ((MATRIX)); then
	for s in "${MATRIX_SUITES[@]}"; do
		start_lane "matrix-$s" matrix_lane "$s"
	done
fi

# Citus 13.2.2 from ../shared/citus (test/citus/build.sh, cached in
# ~/.cache/tdc-citus): the build takes 4-12 minutes on 2 cores the first
# time, so it runs from the start; the citus part below only installs it.
citus_why=""
if ((CITUS)); then
	if [ ! -f "$citus_src/citus-13.2.2.tar.gz" ]; then
		citus_why="no Citus source (../shared/citus or TDC_CITUS_SRC)"
		tdc_warn "$citus_why: the Citus part is skipped"
	elif ! citus_why=$(PG_CONFIG=$PG_CONFIG bash test/citus/build.sh --supported 2>&1); then
		citus_why=${citus_why#citus-build: }
		tdc_say "[citus] skipped: $citus_why"
	else
		citus_why=""
		citus_lane() {
			# a first build on a loaded 2-core machine: up to 12 minutes and more
			PART_TIMEOUT=$((PART_TIMEOUT * 2)) lane_part citus-build env PG_CONFIG="$PG_CONFIG" bash test/citus/build.sh
		}
		start_lane citus-build citus_lane
	fi
fi

# The core suites (no server, no build of the extension needed), then the
# fuzzers, one after the other in one lane: the plain build, the sanitizers,
# then the libFuzzer targets (fuzz/), built with -j and each run from its
# seed corpus.  libFuzzer first replays the whole corpus (the regression
# test: every input that ever found a bug or new coverage; fuzz/run.sh fails
# a target that did not get through it) and then mutates until the time is
# up: TDC_FUZZ_SECONDS per target, counted from its start (default 20).  The
# replay is what guards against regressions; finding new bugs takes hours of
# mutation, which no CI run has: `make fuzz-run FUZZ_SECONDS=3600` by hand
# (fuzz/README.md).  A lane's parts may wait for the CPU behind the other
# lanes, so each gets twice a foreground part's time.
FUZZ_SECONDS=${TDC_FUZZ_SECONDS:-20}
core_lane() {
	local PART_TIMEOUT=$((PART_TIMEOUT * 2))
	lane_part check-core "${MAKE[@]}" check-core
	lane_part check-core-asan "${MAKE[@]}" check-core-asan
	lane_part check-core-tsan "${MAKE[@]}" check-core-tsan
	((FUZZ_SECONDS <= 0)) ||
		lane_part fuzz "${MAKE[@]}" -j"$(nproc)" fuzz-run FUZZ_SECONDS="$FUZZ_SECONDS"
}
start_lane core core_lane

# --- The foreground ---------------------------------------------------------

built=0
run_step build+install tdc_build_install && built=1
# ./tdc for the harnesses in test/*.sh (an old binary would test old code).
run_step "make tdc" "${MAKE[@]}" tdc || true

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
	# tdc_pointcloud and tdc_pointcloud_tiled run only where pgpointcloud is
	# installed (the Makefile looks for its control file): say so when they
	# are left out
	if [ ! -e "$("${PG_CONFIG:-pg_config}" --sharedir 2>/dev/null)/extension/pointcloud.control" ]; then
		echo "pg_regress: pgpointcloud (postgresql-${TDC_PG_MAJOR:-NN}-pointcloud) is not installed: tdc_pointcloud and tdc_pointcloud_tiled left out"
	fi
	rm -f build/regress/tdc_raster_arbiter.txt build/regress/tdc_tin_jacksboro.txt
	run_part pg_regress regress "${MAKE[@]}" installcheck
	if [ -s build/regress/regression.diffs ]; then
		echo "--- build/regress/regression.diffs (first 80 lines) ---"
		head -n 80 build/regress/regression.diffs
	fi
	# GDAL's 'linear' against the exact arbiter (tdc_raster_arbiter,
	# tdc_tin_jacksboro): the counts depend on GDAL's version, so the
	# expected output cannot hold them; the tests write them here
	for f in build/regress/tdc_raster_arbiter.txt build/regress/tdc_tin_jacksboro.txt; do
		if [ -s "$f" ]; then echo "--- $f ---"; cat "$f"; fi
	done
else
	record pg_regress 0 1 "(not run: no build or no server)"
fi

# cli.sh's tiled runs on clustered data (reruns of tiles at half the
# one-shot's memory) are the foreground's longest CPU; beside the lanes and
# two busy loops they took more than the part timeout of wall.
for t in test/*.sh; do
	[ -x "$t" ] || continue
	if [ "$t" = test/cli.sh ]; then
		PART_TIMEOUT=$((PART_TIMEOUT * 2)) run_part cli plain "./$t"
	else
		run_part "$(basename "$t" .sh)" plain "./$t"
	fi
done

# The CI-sized hardening scripts (test/hardening/README.md), on the throw-away
# cluster only: they need a superuser and keep tables in a schema tdc_hard.
# TDC_HARDENING=0 skips them, =1 runs them on your server too.  cancel
# measures latencies: it runs last, once the lanes are done.
hardening=${TDC_HARDENING:-$((!TDC_EXISTING))}
run_hardening_server() {	# name...
	local h
	for h in "$@"; do
		case $h in
			concurrency) run_part "hardening-$h" plain env QUICK=1 bash "test/hardening/$h.sh" ;;
			cancel) run_part "hardening-$h" plain env QUICK=1 MAX_LATENCY_MS="${TDC_CANCEL_MAX_MS:-1000}" \
				bash "test/hardening/$h.sh" ;;
			*) run_part "hardening-$h" plain bash "test/hardening/$h.sh" ;;
		esac
	done
}
HARDENING_QUIET=(cancel)
HARDENING_BUSY=()
for h in "${HARDENING_SERVER[@]}"; do
	[[ " ${HARDENING_QUIET[*]} " == *" $h "* ]] || HARDENING_BUSY+=("$h")
done
if ((hardening && built && server)); then
	run_hardening_server "${HARDENING_BUSY[@]}"
fi

# Citus (test/citus/run.sh): installs the build of the lane above (or
# builds it, if that failed), then runs tdc_delaunay_tiled on its own
# throw-away coordinator and two workers (about 40 s).  TDC_CITUS=0 skips
# it, and so does a clone without the Citus source beside it
# (../shared/citus, or TDC_CITUS_SRC): Debian has no Citus to install
# instead; and a PostgreSQL major Citus 13.2.2 does not support (18).  The
# summary says so.
if ((CITUS && built)); then
	if [ -n "$citus_why" ]; then
		record citus 0 0 "skipped: $citus_why"
	else
		wait_lane citus-build
		if ! lane_part_ok citus-build; then
			tdc_warn "the Citus build in the background failed (build/logs/citus-build.log); the citus part tries again"
			tail -n 20 "$TDC_LOGDIR/citus-build.log" || true
		fi
		PART_TIMEOUT=$((PART_TIMEOUT * 2)) run_part citus plain env PG_CONFIG="$PG_CONFIG" bash test/citus/run.sh
	fi
fi

# --- The lanes' results, then what needs a quiet machine --------------------

if ((FUZZ_SECONDS > 0)); then
	collect_lane core check-core check-core-asan check-core-tsan fuzz
else
	collect_lane core check-core check-core-asan check-core-tsan
fi
# The matrix: a root not ready (prepare failed or timed out) counts as one failure.
for s in "${MATRIX_SUITES[@]}"; do
	((MATRIX)) || break
	wait_lane "matrix-$s"
	tdc_say "[root-$s] (lane matrix-$s)"
	sed 's/^/    /' "$TDC_LOGDIR/root-$s.log" 2>/dev/null || true
	if lane_part_ok "root-$s"; then
		collect_lane "matrix-$s" "matrix-$s"
	else
		read -r rc _ secs <"$TDC_LOGDIR/root-$s.log.status" 2>/dev/null || rc="?" secs="?"
		record "matrix-$s" 0 1 "(root not ready: exit $rc after $secs s; build/logs/root-$s.log)"
	fi
done
wait_lane citus-build

# Latencies, with no lane running beside them.  The core's cancel latency
# (no server): its default limits (stop 100 ms, free 150 ms) hold on a quiet
# machine; on 2 shared cores at load 5-9 stops of 130-320 ms were seen, so
# CI allows 750 ms each: still far below the rest of a 2M-point run, which a
# job that ignored the cancel would take.
for h in "${HARDENING_CORE[@]}"; do
	case $h in
		core_cancel) run_part "hardening-$h" plain bash "test/hardening/$h.sh" 2000000 2 12 \
			"${TDC_CORE_CANCEL_MAX_MS:-750}" "${TDC_CORE_CANCEL_MAX_MS:-750}" ;;
		*) run_part "hardening-$h" plain bash "test/hardening/$h.sh" ;;
	esac
done
if ((hardening && built && server)); then
	run_hardening_server "${HARDENING_QUIET[@]}"
fi

tdc_server_down
FINISHED=1
print_summary
((TOTAL_FAILED == 0))
