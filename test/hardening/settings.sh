#!/usr/bin/env bash
# test/hardening/settings.sh: the settings that protect the whole server
# have the documented defaults and ceilings.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/settings.sh
#
# pg_regress cannot check the thread defaults, because they depend on the
# machine's CPU count; this script compares the thread count each
# triangulation reports (tdc_delaunay.stats) with getconf _NPROCESSORS_ONLN
# of the machine the server runs on (so run it there):
#   - threads = 0 (default) uses one thread per online CPU;
#   - a user's threads = 1024 is capped at the CPU count (max_threads = 0);
#   - a superuser's max_threads caps every session's threads;
#   - only a superuser may change max_threads or memory_ceiling, and a
#     user's max_memory above memory_ceiling does not lift it.
# Needs a superuser.  A few seconds.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

echo "== settings.sh: thread and memory defaults and ceilings"
require_server
CPUS=$(getconf _NPROCESSORS_ONLN)
ROLE=tdc_hard_user

hpsql -c "CREATE TABLE IF NOT EXISTS tdc_hard.pts20k AS
	SELECT ST_MakePoint(random(), random()) AS geom FROM generate_series(1, 20000)" >/dev/null
hpsql -c "DROP ROLE IF EXISTS $ROLE; CREATE ROLE $ROLE;
	GRANT USAGE ON SCHEMA tdc_hard TO $ROLE; GRANT SELECT ON tdc_hard.pts20k TO $ROLE" >/dev/null
trap 'hpsql -c "DROP OWNED BY $ROLE; DROP ROLE IF EXISTS $ROLE" >/dev/null 2>&1 || true' EXIT

# threads_used "SET ...;" : the thread count the stats DETAIL reports.
threads_used() {
	psql -X -q -A -t -v ON_ERROR_STOP=1 \
		-c "SET client_min_messages = notice; SET tdc_delaunay.stats = on; $1" \
		-c "SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_hard.pts20k" 2>&1 |
		sed -n 's/^DETAIL: *threads \([0-9]*\),.*/\1/p'
}

t=$(threads_used "")
check "default threads = online CPUs ($t = $CPUS)" test "$t" = "$CPUS"
t=$(threads_used "SET ROLE $ROLE; SET tdc_delaunay.threads = 1024;")
check "a user's threads = 1024 capped at the CPU count ($t = $CPUS)" test "$t" = "$CPUS"
t=$(threads_used "SET tdc_delaunay.max_threads = 1; SET ROLE $ROLE; SET tdc_delaunay.threads = 8;")
check "max_threads = 1 caps a user's threads = 8 ($t = 1)" test "$t" = 1
t=$(threads_used "SET tdc_delaunay.max_threads = 3; SET tdc_delaunay.threads = 3;")
check "a superuser may raise max_threads past the CPU count ($t = 3)" test "$t" = 3

LOADED="SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)'))"
for g in max_threads memory_ceiling max_result_bytes; do
	out=$(psql -X -q -A -t -c "$LOADED" -c "SET ROLE $ROLE" -c "SET tdc_delaunay.$g = 100" 2>&1 || true)
	check "a user cannot set tdc_delaunay.$g" grep -q 'permission denied' <<<"$out"
done
# Before the library is loaded the names are mere placeholders that anyone
# may set; PostgreSQL drops a user's value of a superuser setting on load.
t=$(threads_used "SET ROLE $ROLE; SET tdc_delaunay.max_threads = 64; SET tdc_delaunay.threads = 64;")
check "a user's max_threads set before the library loaded is ignored ($t = $CPUS)" test "$t" = "$CPUS"

out=$(psql -X -q -A -t -c "SET tdc_delaunay.memory_ceiling = '2MB'" -c "SET ROLE $ROLE" \
	-c "SET tdc_delaunay.max_memory = '100GB'" \
	-c "SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_hard.pts20k" 2>&1 || true)
check "a user's max_memory = 100GB stays under memory_ceiling = 2MB" \
	grep -q 'more than tdc_delaunay.memory_ceiling (2 MB)' <<<"$out"

finish
