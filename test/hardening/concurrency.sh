#!/usr/bin/env bash
# test/hardening/concurrency.sh: concurrent sessions triangulating at once,
# each with worker threads on.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/concurrency.sh
#
# SESSIONS (8) psql sessions run RUNS (50) triangulations each of the same
# POINTS (100000) point table tdc_hard.pts100k, all at the same time, with
# tdc_delaunay.threads = THREADS (4: more threads than cores on purpose):
#   sessions 1..3   SELECT ST_TDCDelaunay(geom) FROM ...             (serial plan)
#   sessions 4..6   the same with a parallel aggregate plan allowed (partial
#                   states serialized between processes, when the server has
#                   background workers to spare)
#   sessions 7..8   ST_TDCDelaunayDump('SELECT geom FROM ...')
# Every run prints a digest: triangle count and md5 of the result's WKB (for
# Dump, of the rows' WKB in id order).  Checked:
#   - no errors, every run completed;
#   - every aggregate run has the same digest and so has every Dump run; runs
#     whose md5 differs only in triangle order are compared normalized
#     (sorted ST_Normalize text of the triangles), which must then agree;
#   - the result is valid: 2n - 2 - h triangles (h: hull vertices including
#     collinear ones), area equal to the convex hull's, all triangles CCW;
#   - cancel storm: 6 sessions run the same statements while two random
#     active ones are cancelled every 0-80 ms; each statement ends with the
#     right count or the cancel error, nothing else; some were cancelled and
#     some completed (only every other statement of a session is a target,
#     so that completions do not depend on the machine's load);
#   - pg_postmaster_start_time() unchanged (no backend crashed).
# QUICK=1: 5 runs per session (CI).  Prints figures and "N passed, N failed".
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

QUICK=${QUICK:-0}
SESSIONS=${SESSIONS:-8}
if ((QUICK)); then RUNS=${RUNS:-5}; else RUNS=${RUNS:-50}; fi
POINTS=${POINTS:-100000}
THREADS=${THREADS:-4}
TABLE=tdc_hard.conc$POINTS
work_dir conc

echo "== concurrency.sh: $SESSIONS sessions x $RUNS runs, $POINTS points, tdc_delaunay.threads = $THREADS"
server_begin
make_points "${TABLE#tdc_hard.}" "$POINTS"

# expected triangle count and hull area, independently of tdc_delaunay
read -r EXPECT HULL_AREA <<<"$(hpsql -F ' ' -c "
	WITH hull AS MATERIALIZED (
		SELECT ST_Boundary(ST_ConvexHull(ST_Collect(geom))) AS b, ST_Area(ST_ConvexHull(ST_Collect(geom))) AS a
		FROM $TABLE),
	sites AS MATERIALIZED (SELECT DISTINCT ST_X(geom) AS x, ST_Y(geom) AS y FROM $TABLE)
	SELECT 2 * (SELECT count(*) FROM sites) - 2
		   - (SELECT count(*) FROM sites, hull WHERE ST_Intersects(ST_MakePoint(x, y), hull.b)),
		   (SELECT a FROM hull)")"
echo "expected triangles $EXPECT, hull area $HULL_AREA"

AGG_DIGEST="SELECT 'agg ' || ST_NumGeometries(t) || ' ' || md5(ST_AsBinary(t)) FROM (SELECT ST_TDCDelaunay(geom) AS t FROM $TABLE) s;"
DUMP_DIGEST="SELECT 'dump ' || count(*) || ' ' || md5(string_agg(ST_AsBinary(geom), ''::bytea ORDER BY id)) FROM ST_TDCDelaunayDump('SELECT geom FROM $TABLE');"
PARALLEL="SET max_parallel_workers_per_gather = 2; SET parallel_setup_cost = 0; SET parallel_tuple_cost = 0; SET min_parallel_table_scan_size = 0;"

t0=$(date +%s%N)
for ((s = 1; s <= SESSIONS; s++)); do
	{
		echo "SET tdc_delaunay.threads = $THREADS;"
		if ((s >= 4 && s <= 6)); then echo "$PARALLEL"; fi
		for ((r = 1; r <= RUNS; r++)); do
			if ((s >= 7)); then echo "$DUMP_DIGEST"; else echo "$AGG_DIGEST"; fi
		done
	} >"$WORK/s$s.sql"
	bg_psql "$WORK/s$s.sql" "$WORK/s$s.out" "$WORK/s$s.err" -q
done
rcs=0
for p in "${HARD_BG[@]}"; do
	wait "$p" || rcs=$((rcs + 1))
done
HARD_BG=()
t1=$(date +%s%N)
wall_ms=$(((t1 - t0) / 1000000))

cat "$WORK"/s*.out >"$WORK/all.out"
cat "$WORK"/s*.err >"$WORK/all.err"
total=$((SESSIONS * RUNS))
done_runs=$(grep -c '^\(agg\|dump\) ' "$WORK/all.out" || true)
echo "completed $done_runs of $total triangulations in $wall_ms ms ($(awk -v n="$done_runs" -v ms="$wall_ms" 'BEGIN { printf "%.1f", (ms > 0 ? n * 1000 / ms : 0) }') per second)"
echo "distinct digests:"
sort "$WORK/all.out" | uniq -c | sed 's/^/    /'

check "all sessions exited cleanly" test "$rcs" -eq 0
check "no errors" test ! -s "$WORK/all.err"
[ ! -s "$WORK/all.err" ] || { sort "$WORK/all.err" | uniq -c | sort -rn | head -5 | sed 's/^/        /' || true; }
check "all $total triangulations completed" test "$done_runs" -eq "$total"

nagg=$(grep '^agg ' "$WORK/all.out" | sort -u | wc -l)
ndump=$(grep '^dump ' "$WORK/all.out" | sort -u | wc -l)
counts=$(awk '{ print $2 }' "$WORK/all.out" | sort -u | tr '\n' ' ')
check "every run has the expected $EXPECT triangles (saw: $counts)" test "$counts" = "$EXPECT "
check "all Dump runs identical ($ndump distinct)" test "$ndump" -le 1
if ((nagg <= 1)); then
	pass "all aggregate runs identical (1 distinct)"
else
	# same triangles in another order?  Compare the sets normalized.
	norms=$(hpsql -c "SET tdc_delaunay.threads = $THREADS;
		SELECT md5(string_agg(x, ',' ORDER BY x)) FROM (
			SELECT ST_AsText(ST_Normalize((ST_Dump(ST_TDCDelaunay(geom))).geom)) AS x FROM $TABLE) s;
		SET max_parallel_workers_per_gather = 2; SET parallel_setup_cost = 0; SET parallel_tuple_cost = 0;
		SET min_parallel_table_scan_size = 0;
		SELECT md5(string_agg(x, ',' ORDER BY x)) FROM (
			SELECT ST_AsText(ST_Normalize((ST_Dump(t)).geom)) AS x FROM (SELECT ST_TDCDelaunay(geom) AS t FROM $TABLE) a) s;" | sort -u | wc -l)
	check "aggregate runs differ only in triangle order ($nagg distinct md5s, $norms distinct normalized sets)" test "$norms" -eq 1
fi

# validity of the result itself
read -r ntri area ccw <<<"$(hpsql -F ' ' -c "SET tdc_delaunay.threads = $THREADS;
	SELECT count(*), sum(ST_Area(d.geom)), bool_and(ST_IsPolygonCCW(d.geom))
	FROM (SELECT ST_TDCDelaunay(geom) AS t FROM $TABLE) s, ST_Dump(s.t) d")"
check "result has $EXPECT triangles ($ntri)" test "$ntri" = "$EXPECT"
check "triangles tile the convex hull (area $area vs $HULL_AREA)" \
	awk -v a="$area" -v b="$HULL_AREA" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 1e-9 * b) }'
check "all triangles counter-clockwise" test "$ccw" = t
# --- cancel storm: the same load while random statements get cancelled ------
# 6 sessions (3 serial, 2 parallel-plan aggregates, 1 Dump) x STORM_RUNS,
# two random active targets cancelled every 0-80 ms.  Every statement must
# end with the right triangle count or with the cancel error, nothing else.
# Odd statements of each session are targets, even ones are not: on a
# loaded machine the statements take longer while the cancels keep coming,
# so a target may well be cancelled every time; the others complete unless
# a cancel sent just as a target finished lands on them.
STORM_RUNS=${STORM_RUNS:-$((QUICK ? 5 : 20))}
HARD_BG=()
for ((s = 1; s <= 6; s++)); do
	{
		echo "SET tdc_delaunay.threads = $THREADS;"
		if ((s == 4 || s == 5)); then echo "$PARALLEL"; fi
		for ((r = 1; r <= STORM_RUNS; r++)); do
			if ((r % 2)); then role=target; else role=free; fi
			if ((s == 6)); then
				echo "SELECT 'storm $role ' || count(*) AS storm_$role FROM ST_TDCDelaunayDump('SELECT geom FROM $TABLE');"
			else
				echo "SELECT 'storm $role ' || ST_NumGeometries(ST_TDCDelaunay(geom)) AS storm_$role FROM $TABLE;"
			fi
		done
	} >"$WORK/storm$s.sql"
	bg_psql "$WORK/storm$s.sql" "$WORK/storm$s.out" - -q
done
ncancel_sent=0
rounds=0
storm_t0=$(date +%s%N)
while :; do
	running=0
	for p in "${HARD_BG[@]}"; do
		if kill -0 "$p" 2>/dev/null; then running=1; fi
	done
	((running)) || break
	sent=$(hpsql -c "SELECT count(*) FILTER (WHERE pg_cancel_backend(pid)) FROM (
		SELECT pid FROM pg_stat_activity WHERE state = 'active' AND pid <> pg_backend_pid()
		AND query LIKE '%storm_target%' AND query NOT LIKE '%pg_stat_activity%' ORDER BY random() LIMIT 2) s" 2>/dev/null) || sent=0
	ncancel_sent=$((ncancel_sent + ${sent:-0}))
	rounds=$((rounds + 1))
	sleep "0.0$((RANDOM % 9))"
done
for p in "${HARD_BG[@]}"; do wait "$p" || true; done
HARD_BG=()
storm_ms=$((($(date +%s%N) - storm_t0) / 1000000))
cat "$WORK"/storm*.out >"$WORK/storm.all"
storm_ok=$(grep -c "^storm \(target\|free\) $EXPECT\$" "$WORK/storm.all" || true)
storm_free_ok=$(grep -c "^storm free $EXPECT\$" "$WORK/storm.all" || true)
storm_cancel=$(grep -c 'ERROR:  canceling statement due to user request' "$WORK/storm.all" || true)
storm_other=$(grep -v "^storm \(target\|free\) $EXPECT\$" "$WORK/storm.all" | grep -v 'canceling statement due to user request\|^CONTEXT:  query of ST_TDCDelaunayDump\|^CONTEXT:  parallel worker$' || true)
echo "cancel storm: $ncancel_sent cancels sent in $rounds rounds over $storm_ms ms; $storm_ok statements completed" \
	"($((storm_ok - storm_free_ok)) targets, $storm_free_ok others), $storm_cancel cancelled, of $((6 * STORM_RUNS))"
check "cancel storm: every statement completed correctly or was cancelled" \
	test $((storm_ok + storm_cancel)) -eq $((6 * STORM_RUNS)) -a -z "$storm_other"
[ -z "$storm_other" ] || { printf '%s\n' "$storm_other" | head -n 5 | sed 's/^/        /' || true; }
check "cancel storm: some statements were cancelled and some completed" test "$storm_cancel" -gt 0 -a "$storm_ok" -gt 0
check_postmaster
finish
