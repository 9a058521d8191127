# test/db_lib.sh: helpers of test/upgrade.sh and test/dump_restore.sh (sourced).
#
# They talk to the server the libpq environment names (PGHOST, PGPORT,
# PGUSER), as a superuser (tdc_delaunay is not a trusted extension;
# scripts/test.sh runs them on its throw-away cluster), and make and drop
# databases of their own, named tdc_<script>_*.
# shellcheck shell=bash

# pass, fail, check and finish ("N passed, N failed") are the hardening
# scripts' (test/hardening/lib.sh; its other helpers are not used here).
# shellcheck source=test/hardening/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/hardening/lib.sh"
DB_WORK=$(mktemp -d)
DB_MADE=()
DB_FINISHED=0

db_finish() {
	DB_FINISHED=1
	finish
}

# same NAME WANT GOT: pass when equal, else fail with both.
same() {
	if [ "$2" = "$3" ]; then
		pass "$1"
	else
		fail "$1"
		echo "        want: $2"
		echo "        got:  $3"
	fi
}

# The client programs of the server's major (pg_dump refuses a newer
# server, and an older pg_restore may not read a newer dump): PG_CONFIG's,
# else Debian's directory of that major, else the PATH's.
db_bindir() {
	local major
	if [ -n "${PG_CONFIG:-}" ] && [ -x "$("$PG_CONFIG" --bindir 2>/dev/null)/pg_dump" ]; then
		"$PG_CONFIG" --bindir
		return
	fi
	major=$(psql -X -A -t -d postgres -c 'SHOW server_version_num' 2>/dev/null || true)
	major=$((${major:-0} / 10000))
	if [ -x "/usr/lib/postgresql/$major/bin/pg_dump" ]; then
		echo "/usr/lib/postgresql/$major/bin"
	else
		dirname "$(command -v pg_dump)"
	fi
}
PGBIN=$(db_bindir)

# q DB SQL...: psql, quiet, unaligned, tuples only, stop on error.
q() {
	local db=$1
	shift
	"$PGBIN/psql" -X -q -A -t -v ON_ERROR_STOP=1 -d "$db" "$@"
}

# fresh_db NAME: drop and create it; dropped again on exit.
fresh_db() {
	q postgres -c "DROP DATABASE IF EXISTS $1" -c "CREATE DATABASE $1 TEMPLATE template0" >/dev/null
	DB_MADE+=("$1")
}

# On exit: the databases go; a script that a failing command stopped
# (they run under set -e) still ends with its count line, one failure more.
db_cleanup() {
	local rc=$? d
	if ((!DB_FINISHED)); then
		fail "stopped early by a failing command (exit $rc)"
		finish || true
	fi
	for d in "${DB_MADE[@]}"; do
		q postgres -c "DROP DATABASE IF EXISTS $d" >/dev/null 2>&1 || true
	done
	rm -rf "$DB_WORK"
}
trap db_cleanup EXIT

# Abort with one failure when no server answers or the role is not a
# superuser.
db_require_server() {
	if ! q postgres -c 'SELECT 1' >/dev/null 2>&1; then
		echo "no server answers (PGHOST=${PGHOST:-} PGPORT=${PGPORT:-}); set the libpq environment" >&2
		fail "server reachable"
		db_finish || exit 1
	fi
	if [ "$(q postgres -c 'SELECT rolsuper FROM pg_roles WHERE rolname = current_user')" != t ]; then
		fail "the role is a superuser"
		db_finish || exit 1
	fi
	echo "  (server $(q postgres -c 'SHOW server_version'), client programs from $PGBIN)"
}

# digest DB QUERY: "rows md5" of the query's rows as text, sorted, so that
# two results compare equal exactly when they hold the same rows (geometry
# as hex EWKB: every bit of every coordinate).
digest() {
	q "$1" -c "SELECT count(*) || ' ' || md5(coalesce(string_agg(r::text, E'\\n' ORDER BY r::text), ''))
				 FROM ($2) r"
}

# take_digests DB OBJECT...: BEFORE[object] := the digest of its rows, each
# checked to have some; same_digests DB WHEN OBJECT...: compare with them.
declare -A BEFORE=()
take_digests() {
	local db=$1 o n
	shift
	for o in "$@"; do
		BEFORE[$o]=$(digest "$db" "SELECT * FROM $o")
		n=${BEFORE[$o]%% *}
		check "$o has rows ($n)" test "$n" -gt 0
	done
}

same_digests() {
	local db=$1 when=$2 o
	shift 2
	for o in "$@"; do
		same "$when $o gives the same rows" "${BEFORE[$o]}" "$(digest "$db" "SELECT * FROM $o")"
	done
}

# The test data, in the current database: 600 points (id, geom) on a
# scrambled grid with duplicates, and line strings (closed rings and
# open polylines, none crossing) for the constrained functions.
TEST_DATA="
CREATE TABLE pts AS
	SELECT i AS id, g AS grp,
		   ST_SetSRID(ST_MakePoint((i * 7919) % 1009 / 10.0, (i * 104729) % 997 / 10.0 + g * 0.5), 4326) AS geom
	  FROM generate_series(1, 600) i, LATERAL (SELECT i % 3 AS g) s;
INSERT INTO pts SELECT id + 1000, grp, geom FROM pts WHERE id % 50 = 0;
CREATE TABLE lines AS
	SELECT k AS id,
		   ST_SetSRID(CASE WHEN k % 2 = 0
					  THEN ST_ExteriorRing(ST_Buffer(ST_MakePoint(k * 20, 5), 4, 3))
					  ELSE ST_MakeLine(ARRAY[ST_MakePoint(k * 20 - 8, 12), ST_MakePoint(k * 20, 15),
											 ST_MakePoint(k * 20 + 8, 12)]) END, 4326) AS geom
	  FROM generate_series(1, 5) k;
INSERT INTO lines SELECT 100 + id, ST_Translate(geom, 0, 30) FROM lines;
"
