#!/usr/bin/env bash
# test/hardening/valgrind.sh: the extension's regression tests (a subset)
# with every backend under valgrind memcheck.
#
#   bash test/hardening/valgrind.sh [TEST...]     default: tdc_basic tdc_errors
#
# It never touches another server: it makes a throw-away cluster in a temp
# directory, listening on a Unix socket there only (no TCP), creates postgis
# in it natively, then restarts the postmaster under
#   valgrind --tool=memcheck --trace-children=yes --leak-check=no
#            --error-limit=no --num-callers=30 --log-file=DIR/vg.%p.log
# (backends are forked, so all of them run under memcheck) and runs
# pg_regress --use-existing on the given tests from sql/ (tdc_basic must come
# first: it creates the extension and the helper functions).  Results are
# compared with expected/ as usual.  Then every valgrind log is scanned:
# an error whose stack goes through tdc_delaunay.so is a failure; other
# errors (PostgreSQL itself without USE_VALGRIND has a few known ones:
# uninitialised padding written to files and sockets) are only counted.
#
# PostgreSQL here is not built with USE_VALGRIND, so palloc'd chunks are not
# tracked individually: memcheck sees overruns of malloc'd memory (the core's
# arrays), uses of uninitialised values, invalid frees and thread errors, but
# not overruns inside a memory context block.  Slow: tdc_basic + tdc_errors
# take several minutes.  Run as root (uses the postgres user) or as a user
# that may run initdb.  Prints "N passed, N failed".
#   VG_KEEP=1       keep the directory with the logs
#   VG_ARGS=...     extra valgrind options
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

PG_CONFIG=${PG_CONFIG:-pg_config}
PGBIN=$("$PG_CONFIG" --bindir)
PGXS_DIR=$(dirname "$("$PG_CONFIG" --pgxs)")
PG_REGRESS=$PGXS_DIR/../test/regress/pg_regress
TESTS=("$@")
((${#TESTS[@]})) || TESTS=(tdc_basic tdc_errors)

command -v valgrind >/dev/null || { echo "valgrind is not installed" >&2; fail "valgrind installed"; finish; }

DIR=$(mktemp -d "${TMPDIR:-/tmp}/tdc_vg.XXXXXX")
as_owner() {
	if [ "$(id -u)" = 0 ]; then
		runuser -u postgres -- "$@"
	else
		"$@"
	fi
}
[ "$(id -u)" != 0 ] || chown postgres "$DIR"
PORT=5494
VGPID=
stop_server() {
	as_owner "$PGBIN/pg_ctl" -D "$DIR/data" -m fast -w -t 300 stop >/dev/null 2>&1 || true
	if [ -n "$VGPID" ]; then
		wait "$VGPID" 2>/dev/null || true
		VGPID=
	fi
}
cleanup() {
	stop_server
	if [ -z "${VG_KEEP:-}" ]; then rm -rf "$DIR"; else echo "logs kept in $DIR"; fi
}
trap cleanup EXIT

echo "== valgrind.sh: ${TESTS[*]} (cluster in $DIR)"
as_owner "$PGBIN/initdb" -D "$DIR/data" -A trust -U postgres >"$DIR/initdb.log" 2>&1
cat >>"$DIR/data/postgresql.conf" <<EOF
listen_addresses = ''
unix_socket_directories = '$DIR'
port = $PORT
max_parallel_workers_per_gather = 0
fsync = off
shared_buffers = 32MB
max_connections = 10
autovacuum = off
EOF
export PGHOST=$DIR PGPORT=$PORT PGUSER=postgres PGDATABASE=postgres
unset PGOPTIONS

# postgis natively (its install script is big), then stop
as_owner "$PGBIN/pg_ctl" -D "$DIR/data" -l "$DIR/native.log" -w start >/dev/null
psql -X -q -c "CREATE DATABASE tdc_vg" -c "\\c tdc_vg" -c "CREATE EXTENSION postgis" >/dev/null
stop_server

# now under valgrind (the postmaster in the foreground of a background job)
as_owner valgrind --tool=memcheck --trace-children=yes --leak-check=no --error-limit=no \
	--num-callers=30 --log-file="$DIR/vg.%p.log" ${VG_ARGS:-} \
	"$PGBIN/postgres" -D "$DIR/data" >"$DIR/server.log" 2>&1 &
VGPID=$!
for _ in $(seq 1 300); do
	psql -X -q -c 'SELECT 1' >/dev/null 2>&1 && break
	sleep 1
done
psql -X -q -c 'SELECT 1' >/dev/null || { fail "server under valgrind started"; finish; }
pass "server under valgrind started"

t0=$(date +%s)
rc=0
(cd "$ROOT" && "$PG_REGRESS" --use-existing --dbname=tdc_vg --inputdir=. \
	--outputdir="$DIR/regress" --max-connections=1 "${TESTS[@]}") >"$DIR/regress.out" 2>&1 || rc=$?
t1=$(date +%s)
sed -n '/^test \|^ok \|^not ok \|tests passed\|failed/p' "$DIR/regress.out" | sed 's/^/    /'
echo "  pg_regress under valgrind took $((t1 - t0)) s"
check "pg_regress ${TESTS[*]} under valgrind (exit $rc)" test "$rc" -eq 0
[ "$rc" -eq 0 ] || [ ! -f "$DIR/regress/regression.diffs" ] || head -n 40 "$DIR/regress/regression.diffs" | sed 's/^/      /' || true
check "postmaster still running" psql -X -q -c 'SELECT 1' -o /dev/null
stop_server

# scan the logs: one "==PID== <error>" block per error, stack lines after it
total=0
ours=0
for f in "$DIR"/vg.*.log; do
	n=$(sed -n 's/.*ERROR SUMMARY: \([0-9]*\) errors.*/\1/p' "$f" | tail -n1)
	total=$((total + ${n:-0}))
done
awk '
	/^==[0-9]+== [A-Z][a-z]/ && !/ERROR SUMMARY|HEAP SUMMARY|Memcheck|Copyright|Using Valgrind|Command:|Parent PID|== For |Rerun with|Use --|Warning: / {
		if (blk != "") print blk "\n--"; blk = $0; next }
	/^==[0-9]+== +(at|by) / { if (blk != "") blk = blk "\n" $0; next }
	/^==[0-9]+== *$/ { if (blk != "") print blk "\n--"; blk = ""; next }
	END { if (blk != "") print blk "\n--" }' "$DIR"/vg.*.log >"$DIR/errors.txt"
ours=$(awk 'BEGIN { RS = "\n--\n" } /tdc_delaunay\.so|tdc_[a-z_]+ \(|src\/(core|pg)\// { n++ } END { print n + 0 }' "$DIR/errors.txt")
echo "  valgrind: $(find "$DIR" -name 'vg.*.log' | wc -l) processes, $total errors in all, $ours with tdc_delaunay in the stack"
if ((ours > 0)); then
	awk 'BEGIN { RS = "\n--\n" } /tdc_delaunay\.so|tdc_[a-z_]+ \(|src\/(core|pg)\// { print; print "--"; if (++n >= 5) exit }' "$DIR/errors.txt" | sed 's/^/      /'
fi
if ((total > ours)); then
	echo "  other (PostgreSQL/PostGIS/glibc) errors, by kind and innermost frame:"
	{ awk 'BEGIN { RS = "\n--\n" } { split($0, l, "\n"); k = l[1]; f = l[2];
			sub(/^==[0-9]+== /, "", k); sub(/^==[0-9]+== +at 0x[0-9A-F]+: /, "", f); print k " | " f }' "$DIR/errors.txt" |
		sort | uniq -c | sort -rn | head -n 8 | sed 's/^/      /'; } || true
fi
check "no valgrind error in tdc_delaunay code" test "$ours" -eq 0
finish
