#!/usr/bin/env bash
# bench/tiled_sql.sh [NPOINTS]: tdc_delaunay_tiled against ST_TDCDelaunayDump
# on NPOINTS uniform points (default 10000000), each in a fresh session, with
# the wall time and the backend's peak RSS (VmHWM from /proc/self/status, so
# the server must run on this machine and the user must be a superuser).
# Uses the server of the PG* variables (e.g. eval "$(bash scripts/cluster.sh
# env)").  With CITUS=1 it also runs the same count on the throw-away 3-node
# Citus cluster of test/citus/run.sh (tiles of a 4 x 4 grid, 2 workers) and
# prints the coordinator backend's peak RSS.
set -euo pipefail
N=${1:-10000000}
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
psql() { command psql -X -q -A -t -v ON_ERROR_STOP=1 "$@"; }
hwm="SELECT regexp_replace(pg_read_file('/proc/self/status'), '.*VmHWM:\s*([0-9]+ kB).*', '\1')"
now() { date +%s.%N; }

echo "tiled_sql: $N uniform points, $(nproc) CPUs, $(date -u '+%Y-%m-%d %H:%M UTC'), load $(cut -d' ' -f1-3 /proc/loadavg)"
psql -c "CREATE EXTENSION IF NOT EXISTS postgis; CREATE EXTENSION IF NOT EXISTS tdc_delaunay;
	DROP TABLE IF EXISTS tb_pts, tb_tiled, tb_dump;
	SELECT setseed(0.5);
	CREATE TABLE tb_pts AS SELECT ST_MakePoint(random() * 1000, random() * 1000) AS geom FROM generate_series(1, $N);
	ANALYZE tb_pts;" >/dev/null

t1=$(now)
out=$(psql -c "SET client_min_messages = notice; CALL tdc_delaunay_tiled('tb_pts', 'tb_tiled')" -c "$hwm" 2>&1)
t2=$(now)
echo "tiled_sql: tdc_delaunay_tiled (automatic tiles)  $(echo "$t2 - $t1" | bc) s, backend peak RSS $(echo "$out" | tail -1)"
echo "$out" | grep -o '[0-9]* triangles from .*' | sed 's/^/tiled_sql:   /'

t1=$(now)
out=$(psql -c "CREATE TABLE tb_dump AS SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM tb_pts')" -c "$hwm" 2>&1)
t2=$(now)
echo "tiled_sql: CREATE TABLE AS ST_TDCDelaunayDump   $(echo "$t2 - $t1" | bc) s, backend peak RSS $(echo "$out" | tail -1)"
echo "tiled_sql:   $(psql -c "SELECT (SELECT count(*) FROM tb_tiled) || ' tiled, ' || (SELECT count(*) FROM tb_dump) || ' one-shot triangles'")"
psql -c "DROP TABLE tb_pts, tb_tiled, tb_dump"

if [ "${CITUS:-0}" = 1 ]; then
	TDC_CITUS_BENCH=$N bash "$HERE/../test/citus/run.sh" | grep 'citus bench'
fi
