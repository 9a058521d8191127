# test/hardening/lib.sh: shared helpers of the hardening scripts (sourced).
#
# The scripts talk to the server named by the libpq environment (PGHOST,
# PGPORT, PGUSER, PGDATABASE); the role must be a superuser (they read
# /proc/<backend>/status with pg_read_file and signal other backends).  They
# need postgis and tdc_delaunay installed (CREATE EXTENSION IF NOT EXISTS is
# run) and keep their tables in the schema tdc_hard, which they create.
# shellcheck shell=bash

HARD_PASSED=0
export PGOPTIONS="${PGOPTIONS:-} -c client_min_messages=warning"
HARD_FAILED=0

# psql, quiet, unaligned, tuples only, stop on error.
hpsql() {
	psql -X -q -A -t -v ON_ERROR_STOP=1 "$@"
}

pass() {
	HARD_PASSED=$((HARD_PASSED + 1))
	echo "  ok    $*"
}

fail() {
	HARD_FAILED=$((HARD_FAILED + 1))
	echo "  FAIL  $*"
}

# check NAME CONDITION-EXIT-STATUS...: pass/fail on a command's status.
check() {
	local name=$1
	shift
	if "$@"; then
		pass "$name"
	else
		fail "$name"
	fi
}

finish() {
	echo "$HARD_PASSED passed, $HARD_FAILED failed"
	((HARD_FAILED == 0))
}

# Abort early when the server is not there: one failure, summary, exit 1.
require_server() {
	if ! hpsql -c 'SELECT 1' >/dev/null 2>&1; then
		echo "no server answers (PGHOST=${PGHOST:-} PGPORT=${PGPORT:-}); set the libpq environment" >&2
		fail "server reachable"
		finish || exit 1
	fi
	hpsql -c 'CREATE EXTENSION IF NOT EXISTS postgis; CREATE EXTENSION IF NOT EXISTS tdc_delaunay; CREATE SCHEMA IF NOT EXISTS tdc_hard;' >/dev/null
	if [ "$(hpsql -c 'SELECT rolsuper FROM pg_roles WHERE rolname = current_user')" != t ]; then
		echo "the hardening scripts need a superuser role" >&2
		fail "superuser"
		finish || exit 1
	fi
}

postmaster_start() {
	hpsql -c 'SELECT pg_postmaster_start_time()'
}

# server_begin: require_server, then note the postmaster's start time in
# START0.  A backend crash makes the postmaster reinitialise, which resets
# that time, so check_postmaster at the end catches crashes that no client
# saw (a session killed between two checks).
server_begin() {
	require_server
	START0=$(postmaster_start)
}

check_postmaster() {
	check "postmaster not restarted" test "$(postmaster_start)" = "$START0"
}

# work_dir NAME: a scratch directory $WORK, removed on exit together with
# the background sessions in HARD_BG, so that an aborted script (set -e, ^C)
# leaves no psql running against the server.
HARD_BG=()
work_dir() {
	WORK=$(mktemp -d "${TMPDIR:-/tmp}/tdc_$1.XXXXXX")
	trap cleanup_work EXIT
}

cleanup_work() {
	local p
	for p in "${HARD_BG[@]+"${HARD_BG[@]}"}"; do
		kill "$p" 2>/dev/null || true
	done
	rm -rf "$WORK"
}

# bg_psql FILE OUT ERR [PSQL-OPTION...]: run the statements of FILE in a
# background session, stdout to OUT and stderr to ERR (ERR "-": both to OUT,
# in order); its pid is appended to HARD_BG.  The session carries on after
# an ERROR: a statement's error is an outcome the scripts check, not a
# reason to skip the rest.
bg_psql() {
	local file=$1 out=$2 err=$3
	shift 3
	if [ "$err" = - ]; then
		psql -X -A -t -v ON_ERROR_STOP=0 "$@" -f "$file" >"$out" 2>&1 &
	else
		psql -X -A -t -v ON_ERROR_STOP=0 "$@" -f "$file" >"$out" 2>"$err" &
	fi
	HARD_BG+=($!)
}

# A table tdc_hard.NAME(id, geom) of N pseudo-random points in a 1e6 square
# (hashint4, so the same on every run); reused when it already has N rows.
make_points() {
	local name=$1 n=$2
	local have
	have=-1
	if [ -n "$(hpsql -c "SELECT to_regclass('tdc_hard.$name')")" ]; then
		have=$(hpsql -c "SELECT count(*) FROM tdc_hard.$name")
	fi
	if [ "$have" != "$n" ]; then
		hpsql -c "DROP TABLE IF EXISTS tdc_hard.$name;
			CREATE UNLOGGED TABLE tdc_hard.$name AS
			SELECT i AS id, ST_MakePoint((hashint4(i) & 2147483647)::float8 / 2147.483647,
										 (hashint4(-i) & 2147483647)::float8 / 2147.483647) AS geom
			FROM generate_series(1, $n) i;
			ANALYZE tdc_hard.$name;" >/dev/null
	fi
}

# median and max of numbers on stdin (one per line)
stats_line() {
	sort -g | awk '{ a[NR] = $1 } END {
		if (NR == 0) { print "n 0"; exit }
		m = (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2
		printf "n %d  min %.1f  median %.1f  max %.1f\n", NR, a[1], m, a[NR] }'
}
