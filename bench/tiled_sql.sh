#!/usr/bin/env bash
# bench/tiled_sql.sh -- CALL tdc_delaunay_tiled against CREATE TABLE AS of
# ST_TDCDelaunayDump (and, where PostGIS can take it in one value, of
# ST_DelaunayTriangles): a program that prints figures and asserts nothing.
#
# Cases (each a table of points, loaded once):
#   uniform 1e6 and 1e7: random points in a 1000 square (SQL random(),
#     setseed 0.5), the procedure under tdc_delaunay.max_memory low enough
#     that it runs in tiles (BENCH_TSQL_LIMITS: 40 MB for 1e6, 400 MB for 1e7)
#     and with the default settings (one pass), beside the Dump, and at 1e6
#     PostGIS's ST_DelaunayTriangles (at 1e7 its one GEOMETRYCOLLECTION would
#     pass the 1 GB limit of a value); and with a tile column of 16 tiles
#     (t, a 4 x 4 grid of squares of 250) under the same limit, its peak
#     against the limit plus shared_buffers, and once its triangles against
#     the Dump's (each as its vertices from the smallest, with
#     multiplicity);
#   clusters64 2e6: gen_points clusters64 2000000 42 (64 Gaussian clusters of
#     widths 0.1 to 20), the procedure under 60 MB beside the Dump, and once
#     the two targets' triangle sets compared (ST_Normalize, EXCEPT ALL).
# Every run is a statement of its own in a new session, timed by the client
# (wall, connection included), with the backend's peak RSS (VmHWM, which
# counts the shared buffers it touched); the kinds alternate, BENCH_TSQL_REPS
# rounds, and the medians are printed with the ratio procedure / Dump, and,
# for a load that changes during the run, the median of each round's ratio.
# The procedure's NOTICE (tiles, runs, halo, phases) is kept from its last run.
#
# Uses the server of the PG* variables (eval "$(bash scripts/cluster.sh env)"),
# which must run on this machine with a superuser (VmHWM is read with
# pg_read_file), and the tdc_delaunay installed there; it makes and drops the
# database tdc_tiled_bench.
#
# Environment knobs:
#   BENCH_TSQL_REPS=3
#   BENCH_TSQL_SIZES="1e6 1e7"     uniform sizes
#   BENCH_TSQL_LIMITS="40 400"     max_memory (MB) of the procedure, per size
#   BENCH_TSQL_CLUSTERED=2e6       clusters64 points ("" skips the case)
#   BENCH_TSQL_CLUSTERED_LIMIT=60
#   CITUS=1                        also the largest uniform size on the
#                                  throw-away Citus cluster of test/citus/run.sh
# Output: stdout, build/bench/tiled_sql.txt, build/bench/tiled_sql_runs.csv,
# and docs/benchmarks/tiled_sql.md.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

REPS=${BENCH_TSQL_REPS:-3}
read -r -a SIZES <<< "${BENCH_TSQL_SIZES:-1e6 1e7}"
read -r -a LIMITS <<< "${BENCH_TSQL_LIMITS:-40 400}"
CLU=${BENCH_TSQL_CLUSTERED-2e6}
CLIMIT=${BENCH_TSQL_CLUSTERED_LIMIT:-60}
DB=tdc_tiled_bench
[ ${#SIZES[@]} -eq ${#LIMITS[@]} ] || die "BENCH_TSQL_SIZES and BENCH_TSQL_LIMITS differ in length"

mkdir -p "$BENCH_OUT"
TXT=$BENCH_OUT/tiled_sql.txt
RUNS=$BENCH_OUT/tiled_sql_runs.csv
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tiled_sql.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
build_helpers

q() { command psql -X -q -A -t -v ON_ERROR_STOP=1 -d "$DB" "$@"; }
hwm="SELECT regexp_replace(pg_read_file('/proc/self/status'), '.*VmHWM:\s*([0-9]+) kB.*', '\1')"
now() { date +%s.%N; }

command psql -X -q -d postgres -c "DROP DATABASE IF EXISTS $DB" -c "CREATE DATABASE $DB" >/dev/null
trap 'rm -rf "$WORK"; command psql -X -q -d postgres -c "DROP DATABASE IF EXISTS $DB" >/dev/null 2>&1 || true' EXIT
q -c "CREATE EXTENSION postgis; CREATE EXTENSION tdc_delaunay" >/dev/null

# the tables
for i in "${!SIZES[@]}"; do
	n=$(n_of "${SIZES[$i]}")
	log "loading $n uniform points"
	q -c "SELECT setseed(0.5);
		CREATE TABLE u_$i AS SELECT geom, (floor(ST_X(geom) / 250) * 4 + floor(ST_Y(geom) / 250))::int AS t
		  FROM (SELECT ST_MakePoint(random() * 1000, random() * 1000) AS geom FROM generate_series(1, $n)) s;" \
		-c "VACUUM ANALYZE u_$i" >/dev/null
done
if [ -n "$CLU" ]; then
	cn=$(n_of "$CLU")
	log "loading $cn clusters64 points (seed $POINT_SEED)"
	"$BENCH_BIN/gen_points" clusters64 "$cn" "$POINT_SEED" "$WORK/c.bin" >/dev/null
	q -c "CREATE TABLE c (geom geometry)"
	# od prints each double in its shortest form that reads back exactly
	od -A n -t f8 -v -w16 "$WORK/c.bin" | awk '{ print "POINT(" $1 " " $2 ")" }' |
		q -c "COPY c (geom) FROM STDIN"
	q -c "VACUUM ANALYZE c" >/dev/null
	rm -f "$WORK/c.bin"
fi

# one timed statement in a session of its own: "wall_s hwm_kb", the NOTICEs to $WORK/notice
run() {
	local pre=$1 stmt=$2 t0 t1 out
	t0=$(now)
	out=$(q -c "SET client_min_messages = notice" ${pre:+-c "$pre"} -c "$stmt" -c "$hwm" 2>"$WORK/notice")
	t1=$(now)
	echo "$(echo "$t1 - $t0" | bc) $(echo "$out" | tail -1)"
}

echo "case,kind,round,wall_s,hwm_kb" > "$RUNS"
bench_begin server
exec > >(tee "$TXT")
TEE_PID=$!

echo "runs: each statement in a new session, timed by the client (wall); peak = the backend's VmHWM (shared buffers included)"
echo "kinds alternate, $REPS rounds; medians; ratio = procedure / CREATE TABLE AS of the Dump"

# case NAME TABLE LIMIT [postgis]: the rounds of one table
bench_case() {
	local name=$1 tab=$2 limit=$3 pg=${4:-} tilecol=${5:-} r kind stmt pre res
	local kinds="dump tiled onepass"
	[ -n "$pg" ] && kinds="$kinds postgis"
	[ -n "$tilecol" ] && kinds="$kinds tilecol"
	echo
	echo "== $name ($(q -c "SELECT to_char(count(*), 'FM999,999,999') FROM $tab") points), procedure under tdc_delaunay.max_memory = $limit MB"
	for r in $(seq 1 "$REPS"); do
		for kind in $kinds; do
			q -c "DROP TABLE IF EXISTS out_$kind" 2>/dev/null
			pre=
			case $kind in
				dump) stmt="CREATE TABLE out_dump AS SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM $tab')" ;;
				tiled) pre="SET tdc_delaunay.max_memory = $limit"
					stmt="CALL tdc_delaunay_tiled('$tab', 'out_tiled')" ;;
				onepass) stmt="CALL tdc_delaunay_tiled('$tab', 'out_onepass')" ;;
				tilecol) pre="SET tdc_delaunay.max_memory = $limit"
					stmt="CALL tdc_delaunay_tiled('$tab', 'out_tilecol', tile_column => 't')" ;;
				postgis) stmt="CREATE TABLE out_postgis AS SELECT (ST_Dump(ST_DelaunayTriangles(ST_Collect(geom)))).geom FROM $tab" ;;
			esac
			res=$(run "$pre" "$stmt")
			echo "$name,$kind,$r,${res% *},${res#* }" >> "$RUNS"
			[ "$kind" = tiled ] && cp "$WORK/notice" "$WORK/notice_tiled"
			[ "$kind" = tilecol ] && cp "$WORK/notice" "$WORK/notice_tilecol"
		done
	done
	printf '%-26s %10s %10s %12s %10s\n' run wall_s peak_mb triangles ratio
	local dmed
	dmed=$(awk -F, -v c="$name" '$1 == c && $2 == "dump" { print $4 }' "$RUNS" | median)
	for kind in $kinds; do
		local med peak ntri label
		med=$(awk -F, -v c="$name" -v k="$kind" '$1 == c && $2 == k { print $4 }' "$RUNS" | median)
		peak=$(awk -F, -v c="$name" -v k="$kind" '$1 == c && $2 == k { print $5 / 1024 }' "$RUNS" | median)
		ntri=$(q -c "SELECT count(*) FROM out_$kind")
		case $kind in
			dump) label="CREATE TABLE AS Dump" ;;
			tiled) label="tdc_delaunay_tiled, tiles" ;;
			onepass) label="tdc_delaunay_tiled, 1 pass" ;;
			postgis) label="PostGIS (CTAS, ST_Dump)" ;;
			tilecol) label="tdc_delaunay_tiled, column" ;;
		esac
		printf '%-26s %10.2f %10.1f %12s %9.2fx\n' "$label" "$med" "$peak" "$(thousands "$ntri")" \
			"$(echo "$med / $dmed" | bc -l)"
	done
	echo "  median of the per-round ratios, procedure / Dump: $(awk -F, -v c="$name" '
		$1 == c && $2 == "dump" { d[$3] = $4 } $1 == c && $2 == "tiled" { t[$3] = $4 }
		END { for (r in t) if (d[r] > 0) print t[r] / d[r] }' "$RUNS" | median | awk '{ printf "%.2fx", $1 }')"
	echo "  the procedure's NOTICE (last run):"
	sed 's/^/    /' "$WORK/notice_tiled"
	[ -n "$tilecol" ] && tile_column_report "$name" "$tab" "$limit"
	return 0
}

# The run with the tile column: its ratio, its peak against the limit plus
# shared_buffers (VmHWM counts the shared buffers the backend touched), its
# NOTICE, and its triangles against the Dump's: each triangle as its
# vertices from the smallest on (both write them counter-clockwise), an
# order-free fingerprint of the set (count, sum of hashes) on each side.
tile_column_report() {
	local name=$1 tab=$2 limit=$3 sb peak
	echo "  median of the per-round ratios, tile column / Dump: $(awk -F, -v c="$name" '
		$1 == c && $2 == "dump" { d[$3] = $4 } $1 == c && $2 == "tilecol" { t[$3] = $4 }
		END { for (r in t) if (d[r] > 0) print t[r] / d[r] }' "$RUNS" | median | awk '{ printf "%.2fx", $1 }')"
	sb=$(q -c "SELECT pg_size_bytes(current_setting('shared_buffers')) / 1048576")
	peak=$(awk -F, -v c="$name" '$1 == c && $2 == "tilecol" { printf "%.1f\n", $5 / 1024 }' "$RUNS" | sort -n | tail -1)
	echo "  tile column: highest peak of the rounds $peak MB; max_memory + shared_buffers = $limit + $sb MB:" \
		"$(awk -v p="$peak" -v l="$((limit + sb))" 'BEGIN { print (p <= l ? "within" : "OVER") }')"
	echo "  tile column: $(q -c "SELECT count(DISTINCT tile) FROM out_tilecol") tiles; the NOTICE (last run):"
	sed 's/^/    /' "$WORK/notice_tilecol"
	local key="CASE WHEN (x1, y1) <= (x2, y2) AND (x1, y1) <= (x3, y3) THEN ARRAY[x1, y1, x2, y2, x3, y3]
					WHEN (x2, y2) <= (x3, y3) THEN ARRAY[x2, y2, x3, y3, x1, y1] ELSE ARRAY[x3, y3, x1, y1, x2, y2] END"
	local corners="SELECT ST_X(ST_PointN(r, 1)) AS x1, ST_Y(ST_PointN(r, 1)) AS y1, ST_X(ST_PointN(r, 2)) AS x2,
					ST_Y(ST_PointN(r, 2)) AS y2, ST_X(ST_PointN(r, 3)) AS x3, ST_Y(ST_PointN(r, 3)) AS y3
				   FROM TABLE, ST_ExteriorRing(geom) r"
	local fp="SELECT count(*) || ' ' || sum(hashtextextended(($key)::text, 0)::numeric) FROM ($corners) c"
	local a b
	a=$(q -c "${fp//TABLE/out_tilecol}")
	b=$(q -c "${fp//TABLE/out_dump}")
	echo "  tile column against the Dump (count, fingerprint): $a / $b: $([ "$a" = "$b" ] && echo same || echo DIFFER)"
}

for i in "${!SIZES[@]}"; do
	pg=
	[ "$(n_of "${SIZES[$i]}")" -le 1000000 ] && pg=postgis
	bench_case "uniform ${SIZES[$i]}" "u_$i" "${LIMITS[$i]}" "$pg" tilecol
done
if [ -n "$CLU" ]; then
	bench_case "clusters64 $CLU" c "$CLIMIT"
	echo "  the procedure's triangles against the Dump's (normalized, with multiplicity):"
	q -c "SELECT '    only in the procedure: ' || (SELECT count(*) FROM (SELECT ST_AsBinary(ST_Normalize(geom)) FROM out_tiled
				EXCEPT ALL SELECT ST_AsBinary(ST_Normalize(geom)) FROM out_dump) x)
		|| ', only in the Dump: ' || (SELECT count(*) FROM (SELECT ST_AsBinary(ST_Normalize(geom)) FROM out_dump
				EXCEPT ALL SELECT ST_AsBinary(ST_Normalize(geom)) FROM out_tiled) x)"
fi

if [ "${CITUS:-0}" = 1 ]; then
	echo
	echo "== Citus: the same count on the throw-away 3-node cluster of test/citus/run.sh (tiles of a 4 x 4 grid, 2 workers)"
	TDC_CITUS_BENCH=$(n_of "${SIZES[-1]}") bash "$ROOT/test/citus/run.sh" | grep 'citus bench'
fi
exec >&-
wait "$TEE_PID" 2>/dev/null || true
bench_end
bench_publish tiled_sql "tdc_delaunay_tiled against CREATE TABLE AS of ST_TDCDelaunayDump" "$TXT" text
