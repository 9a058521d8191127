#!/usr/bin/env bash
# test/bench_quiet.sh: the benchmark harness writes a report only when the
# machine was quiet (bench/quiet.sh, through bench/lib.sh).
#
# A tiny benchmark (written below into a temporary directory) goes through
# bench_begin, bench_end, bench_figure and bench_publish like every script of
# bench/, with BENCH_DOCS, BENCH_OUT and BENCH_LOCK in that directory, never
# docs/benchmarks/.  The cases that must find the machine quiet read a made-up
# /proc (BENCH_PROC, BENCH_LOADAVG_FILE): this test runs in CI beside other
# lanes and busy loops, where the real machine is never quiet.  The refusal
# beside a real busy loop reads the real /proc: on a busy machine the loop, or
# what keeps it from its share, is always seen, and the case only needs a
# refusal.
#
#   1. quiet (made-up /proc): the report and its figure are written, with the
#      samples and "quiet rule | held" in the header, nothing half-written
#   2. a real busy loop beside it: refused (status 3), the loop named, nothing
#      written and a report already there left as it was
#   3. a real busy loop started once the timed runs have begun: refused
#   4. (made-up /proc) a foreign process busy only during the timed runs is
#      caught by the sampler and named, while a busy process of the run's own
#      tree is not counted as foreign
#   5. BENCH_NOISY=1 beside a real busy loop: written, "(noisy machine)" in the
#      title, the noisy samples in the header
#   6. one benchmark at a time: a second one is refused while the first holds
#      the lock; a dead owner's lock is taken over
#   7. bench_publish without bench_begin refuses; a bad knob is an error
# Prints "N passed, N failed".  About 15 s.
set -uo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); printf 'FAIL: %s\n' "$*"; }
check() {	# DESCRIPTION COMMAND...
	local d=$1
	shift
	if "$@"; then ok; else bad "$d"; fi
}

T=$(mktemp -d "${TMPDIR:-/tmp}/bench_quiet.XXXXXX")
LOOPS=()
cleanup() {
	local p
	# a child forked by "&" and killed before its exec would run this too
	[ "$BASHPID" = $$ ] || return 0
	for p in "${LOOPS[@]}"; do kill "$p" 2>/dev/null; done
	wait 2>/dev/null
	rm -rf "$T"
}
trap cleanup EXIT

# busy_loop: a busy loop beside the benchmark, not in its process tree; its
# pid in BL, returns once it runs
busy_loop() {
	local i
	sh -c 'while :; do :; done' &
	BL=$!
	LOOPS+=("$BL")
	for ((i = 0; i < 50; i++)); do
		[ "$(cat "/proc/$BL/comm" 2>/dev/null)" = sh ] && break
		sleep 0.05
	done
}
stop_loop() { kill "$BL" 2>/dev/null; wait "$BL" 2>/dev/null; }

# the made-up /proc: fake PID COMM PPID UTIME writes PID/stat
FAKE=$T/proc
fake() {
	mkdir -p "$FAKE/$1"
	echo "$1 ($2) S $3 0 0 0 -1 0 0 0 0 0 $4 0 0 0 20 0 1 0 100 0 0 0" > "$FAKE/$1/stat.tmp"
	mv "$FAKE/$1/stat.tmp" "$FAKE/$1/stat"
}
fake 1 init 0 500
fake 2 kthreadd 0 10
fake 30 kworker 2 10
fake 400 sshd 1 70
echo "0.10 0.20 0.30 1/100 9999" > "$FAKE/loadavg"

# the tiny benchmark: TINY_DURING runs as its timed part
cat > "$T/tiny.sh" <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
ROOT=$TINY_ROOT
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"
TXT=$BENCH_OUT/tiny.txt
mkdir -p "$BENCH_OUT"
bench_begin
eval "${TINY_DURING:-sleep 1}"
bench_end
printf '| points | seconds |\n|---|---|\n| 1000 | 0.5 |\n' > "$TXT"
printf 'not really a PNG\n' > "$BENCH_OUT/tiny.png"
bench_figure "$BENCH_OUT/tiny.png" "a figure"
bench_publish tiny "A tiny benchmark" "$TXT"
EOF
chmod +x "$T/tiny.sh"

export TINY_ROOT=$ROOT BENCH_SAMPLE_INTERVAL=0.3 BENCH_SETTLE=1
unset BENCH_NOISY BENCH_PROC BENCH_LOADAVG_FILE TINY_DURING
# run CASE [VAR=VALUE...]: the tiny benchmark with fresh directories of its own;
# status in RC, stderr in $T/CASE.err, reports in $T/CASE/docs
run() {
	local c=$1
	shift
	mkdir -p "$T/$c/docs"
	RC=0
	env BENCH_DOCS="$T/$c/docs" BENCH_OUT="$T/$c/out" BENCH_LOCK="$T/$c/lock" "$@" \
		"$T/tiny.sh" > "$T/$c.out" 2> "$T/$c.err" || RC=$?
}
fakeproc=(BENCH_PROC="$FAKE" BENCH_LOADAVG_FILE="$FAKE/loadavg")
empty() { [ -z "$(ls -A "$1")" ]; }
show() { sed 's/^/    /' "$T/$1.err"; }

# 1. quiet
run quiet "${fakeproc[@]}"
R=$T/quiet/docs/tiny.md
check "quiet: status 0 (got $RC)" [ "$RC" = 0 ]
check "quiet: the report is written" [ -s "$R" ]
check "quiet: its figure is copied beside it" cmp -s "$T/quiet/out/tiny.png" "$T/quiet/docs/tiny.png"
check "quiet: the title is not marked noisy" grep -qx '# A tiny benchmark' "$R"
check "quiet: the header says the rule held" grep -q '^| quiet rule | held' "$R"
check "quiet: the header has the load before and after" \
	grep -q '^| load average (1, 5, 15 min) | 0.10 0.20 0.30 before, 0.10 0.20 0.30 after' "$R"
check "quiet: the header has the samples" grep -q '^| samples | [1-9][0-9]* during the run' "$R"
check "quiet: the tables follow the header" grep -qx '| 1000 | 0.5 |' "$R"
check "quiet: then the figure" grep -qxF '![a figure](tiny.png)' "$R"
check "quiet: the samples file has before, during and after" \
	awk -F, '{ p[$1]++ } END { exit !(p["before"] == 1 && p["during"] >= 1 && p["after"] == 1) }' "$T/quiet/out/tiny.load.csv"
check "quiet: nothing half-written is left" [ -z "$(find "$T/quiet/docs" -name '*.tmp')" ]
[ "$fail" = 0 ] || show quiet

# 2. a real busy loop beside it
busy_loop
sleep 0.5
mkdir -p "$T/busy/docs"
echo 'an older report' > "$T/busy/docs/tiny.md"
run busy
stop_loop
check "busy loop: refused with status 3 (got $RC)" [ "$RC" = 3 ]
check "busy loop: the report already there is left as it was" \
	[ "$(cat "$T/busy/docs/tiny.md")" = 'an older report' ]
check "busy loop: nothing else is written" [ "$(ls -A "$T/busy/docs")" = tiny.md ]
check "busy loop: the message says why" grep -q 'REFUSED: the machine is not quiet' "$T/busy.err"
# the loop is named, unless the machine is so busy that it did not get 20% of a
# CPU: then the load, or the others' CPU together, are over the limit
check "busy loop: the loop or the load is named" \
	grep -Eq "sh $BL [0-9]+%|load [0-9.]+ > |others together" "$T/busy.err"
[ "$RC" = 3 ] || show busy

# 3. a real busy loop that starts once the timed runs have begun (on a busy
#    machine the refusal comes before them: either way, a refusal)
mkdir -p "$T/late/docs"
env BENCH_DOCS="$T/late/docs" BENCH_OUT="$T/late/out" BENCH_LOCK="$T/late/lock" \
	TINY_DURING="touch '$T/late.go'; sleep 2" "$T/tiny.sh" > /dev/null 2> "$T/late.err" &
bench=$!
for ((i = 0; i < 100; i++)); do
	{ [ -e "$T/late.go" ] || ! kill -0 "$bench" 2>/dev/null; } && break
	sleep 0.1
done
busy_loop
RC=0
wait "$bench" || RC=$?
stop_loop
check "busy loop during the run: refused with status 3 (got $RC)" [ "$RC" = 3 ]
check "busy loop during the run: nothing written" empty "$T/late/docs"
if [ -e "$T/late.go" ]; then
	check "busy loop during the run: named as a noisy sample during the run" \
		grep -Eq "[0-9:]+ during: .*(sh $BL [0-9]+%|others together)" "$T/late.err"
fi
[ "$RC" = 3 ] || show late

# 4. made-up /proc: a foreign process busy only during the timed runs, and one
#    of the run's own (its parent is the benchmark's shell), gaining 50 and 100
#    s of CPU every 0.1 s (so that a starved test still sees them busy), until
#    the sampler has taken 3 samples since they appeared (or 30 s)
mkdir -p "$FAKE/500" "$FAKE/600"
run during "${fakeproc[@]}" TINY_DURING='
	n0=$(grep -c "^during," "$BENCH_SAMPLES" || true)
	for ((i = 1; i <= 300; i++)); do
		printf "500 (foreignbusy) R 1 0 0 0 -1 0 0 0 0 0 %d 0 0 0 20 0 1 0 200 0 0 0\n" $((i * 5000)) > "$BENCH_PROC/500/s"
		printf "600 (ownbusy) R %d 0 0 0 -1 0 0 0 0 0 %d 0 0 0 20 0 1 0 300 0 0 0\n" $$ $((i * 10000)) > "$BENCH_PROC/600/s"
		mv "$BENCH_PROC/500/s" "$BENCH_PROC/500/stat"
		mv "$BENCH_PROC/600/s" "$BENCH_PROC/600/stat"
		[ "$(grep -c "^during," "$BENCH_SAMPLES")" -lt $((n0 + 3)) ] || break
		sleep 0.1
	done
	rm -rf "$BENCH_PROC/500" "$BENCH_PROC/600"'
check "sampler: refused with status 3 (got $RC)" [ "$RC" = 3 ]
check "sampler: nothing written" empty "$T/during/docs"
check "sampler: the foreign process is named" grep -q 'during: .*foreignbusy 500' "$T/during.err"
check "sampler: the run's own process is not" eval "! grep -q ownbusy '$T/during.err'"
check "sampler: the run's own process counts as own" \
	awk -F, '$1 == "during" && $7 + 0 > 100 { f = 1 } END { exit !f }' "$T/during/out/tiny.load.csv"
check "sampler: before and after were quiet" \
	awk -F, '$1 ~ /^(before|after)$/ && $10 != "quiet" { f = 1 } END { exit f }' "$T/during/out/tiny.load.csv"
[ "$RC" = 3 ] || show during

# 5. BENCH_NOISY=1 beside a real busy loop
busy_loop
sleep 0.5
run noisy BENCH_NOISY=1
stop_loop
R=$T/noisy/docs/tiny.md
check "BENCH_NOISY=1: status 0 (got $RC)" [ "$RC" = 0 ]
check "BENCH_NOISY=1: the report is written" [ -s "$R" ]
check "BENCH_NOISY=1: its title says (noisy machine)" grep -qx '# A tiny benchmark (noisy machine)' "$R"
check "BENCH_NOISY=1: the header lists the noisy samples" \
	grep -Eq '^\| quiet rule \| broken at [0-9]+ samples, written with BENCH_NOISY=1: [0-9:]+ before: ' "$R"
[ "$RC" = 0 ] || show noisy

# 6. one benchmark at a time
mkdir -p "$T/lock1/docs"
env BENCH_DOCS="$T/lock1/docs" BENCH_OUT="$T/lock1/out" BENCH_LOCK="$T/shared.lock" "${fakeproc[@]}" \
	TINY_DURING="for ((i = 0; i < 300; i++)); do [ -e '$T/lock.go' ] && break; sleep 0.1; done" \
	"$T/tiny.sh" > /dev/null 2> "$T/lock1.err" &
first=$!
for ((i = 0; i < 300; i++)); do
	[ -s "$T/shared.lock/owner" ] && break
	sleep 0.1
done
mkdir -p "$T/lock2/docs"
RC=0
env BENCH_DOCS="$T/lock2/docs" BENCH_OUT="$T/lock2/out" BENCH_LOCK="$T/shared.lock" "${fakeproc[@]}" \
	"$T/tiny.sh" > /dev/null 2> "$T/lock2.err" || RC=$?
check "lock: a second benchmark is refused (status $RC)" [ "$RC" = 3 ]
check "lock: it names the first" grep -q "another benchmark runs: .*tiny.sh (pid $first)" "$T/lock2.err"
check "lock: the second writes nothing" empty "$T/lock2/docs"
touch "$T/lock.go"
RC=0
wait "$first" || RC=$?
check "lock: the first writes its report (status $RC)" [ -s "$T/lock1/docs/tiny.md" ]
check "lock: released by the first" [ ! -e "$T/shared.lock" ]
sh -c 'exit 0' &
dead=$!
wait "$dead"
mkdir -p "$T/shared.lock"
echo "$dead 12345 bench/gone.sh" > "$T/shared.lock/owner"
RC=0
env BENCH_DOCS="$T/lock2/docs" BENCH_OUT="$T/lock2/out" BENCH_LOCK="$T/shared.lock" "${fakeproc[@]}" \
	"$T/tiny.sh" > /dev/null 2> "$T/lock3.err" || RC=$?
check "lock: a dead owner's lock is taken over (status $RC)" [ -s "$T/lock2/docs/tiny.md" ]

# 7. no bench_begin; a bad knob
cat > "$T/nobegin.sh" <<'EOF'
#!/usr/bin/env bash
set -euo pipefail
ROOT=$TINY_ROOT
. "$ROOT/bench/lib.sh"
echo '| x |' > "$BENCH_OUT/t.txt"
bench_publish nobegin "No samples" "$BENCH_OUT/t.txt"
EOF
mkdir -p "$T/nobegin/docs" "$T/nobegin/out"
RC=0
env BENCH_DOCS="$T/nobegin/docs" BENCH_OUT="$T/nobegin/out" bash "$T/nobegin.sh" 2> "$T/nobegin.err" || RC=$?
check "no bench_begin: refused (status $RC)" [ "$RC" = 3 ]
check "no bench_begin: nothing written" empty "$T/nobegin/docs"
run knob "${fakeproc[@]}" BENCH_SAMPLE_INTERVAL=often
check "a bad knob: status 1 (got $RC)" [ "$RC" = 1 ]
check "a bad knob: named" grep -q "BENCH_SAMPLE_INTERVAL='often' is not a number" "$T/knob.err"

echo "$pass passed, $fail failed"
[ "$fail" = 0 ]
