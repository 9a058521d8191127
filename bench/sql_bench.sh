#!/usr/bin/env bash
# bench/sql_bench.sh -- SQL benchmark: tdc_delaunay against PostGIS
# ST_DelaunayTriangles (GEOS) inside PostgreSQL, in the same run.
#
# Server: the usual libpq variables (PGHOST, PGPORT, PGUSER, PGDATABASE); the
# extensions postgis and tdc_delaunay are created if missing (tdc_delaunay
# must be installed: make install).  Tables live in schema "bench" and are
# kept between runs (BENCH_SQL_RELOAD=1 reloads them).
#
# Timed statements (server-side, clock_timestamp() around EXECUTE):
#   tdc      SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM t           (tdc_delaunay.threads = 0: all CPUs)
#   tdc_1t   the same with SET tdc_delaunay.threads = 1
#   postgis  SELECT ST_NumGeometries(ST_DelaunayTriangles(ST_Collect(geom))) FROM t
#   collect  SELECT ST_NumGeometries(ST_Collect(geom)) FROM t   (baseline: reading and aggregating the points only)
# on uniform and clustered points (n = 1e4, 1e5, 1e6; the same deterministic
# points as the core benchmark), on a 1M random subset of the GSHHG vertices,
# and on the GSHHG coastlines (211,907 LINESTRINGs, 10.64M vertices):
#   tdc_dump  CREATE TABLE bench.tin AS SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM bench.coastlines')
#   tdc_dump_count  SELECT count(*) FROM ST_TDCDelaunayDump(...)  (the same without writing the table)
#   tdc, postgis  the aggregate forms above (expected to fail: 1 GB value limit)
# Every statement runs under statement_timeout (BENCH_SQL_TIMEOUT, default 600 s);
# failures are recorded with their error message and elapsed time.
#
# Triangle counts are checked against the exact count 2n-2-h, taken from
# CGAL (exact predicates) on the same coordinates: its finite-face count.
#
# Outputs: build/bench/sql_runs.csv, build/bench/sql.csv, build/bench/sql.txt,
#          build/bench/sql.png (time vs n, log-log), build/bench/coast_tin.png, and
#          docs/benchmarks/sql.md (bench_publish's header, then sql.txt and the two
#          figures, copied beside it) if the machine was quiet (bench/quiet.sh).
# Knobs: BENCH_SQL_SIZES="1e4 1e5 1e6" BENCH_SQL_SETS="uniform clustered"
#        BENCH_SQL_REPS_SMALL=5 (n <= 1e5) BENCH_SQL_REPS_MID=3 (n <= 1e6)
#        BENCH_SQL_COAST=1  BENCH_SQL_PG_COAST=1 (try PostGIS on the coastlines)
#        BENCH_SQL_TDC_COAST_AGG=1 (try the ST_TDCDelaunay aggregate there)
#        BENCH_SQL_HULLCHECK=1 (count unique vertices and hull vertices in SQL)
#        BENCH_DOCS=DIR (where the report and PNGs go, default docs/benchmarks/)  BENCH_SQL_PLOT_ONLY=1 (replot into build/bench/ from the CSVs)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

SIZES=${BENCH_SQL_SIZES:-"1e4 1e5 1e6"}
SETS=${BENCH_SQL_SETS:-"uniform clustered"}
REPS_SMALL=${BENCH_SQL_REPS_SMALL:-5}
REPS_MID=${BENCH_SQL_REPS_MID:-3}
COAST=${BENCH_SQL_COAST:-1}
PG_COAST=${BENCH_SQL_PG_COAST:-1}
TDC_COAST_AGG=${BENCH_SQL_TDC_COAST_AGG:-1}
HULLCHECK=${BENCH_SQL_HULLCHECK:-1}
TIMEOUT=${BENCH_SQL_TIMEOUT:-600}
RELOAD=${BENCH_SQL_RELOAD:-0}
FIGS=$BENCH_OUT

mkdir -p "$BENCH_OUT"
RUNS=$BENCH_OUT/sql_runs.csv
CSV=$BENCH_OUT/sql.csv
TXT=$BENCH_OUT/sql.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT


command -v psql >/dev/null || die "psql not found"
"${PSQL[@]}" -c 'SELECT 1' >/dev/null 2>&1 ||
	die "no PostgreSQL server reachable with PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} PGUSER=${PGUSER:-} PGDATABASE=${PGDATABASE:-}"
command -v gnuplot >/dev/null || ensure_debs gnuplot-nox
build_helpers
build_cgal


sql -c "CREATE EXTENSION IF NOT EXISTS postgis" >/dev/null
HAVE_TDC=1
if ! sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay" >/dev/null 2> "$WORK/err"; then
	log "tdc_delaunay extension not available ($(head -1 "$WORK/err")): PostGIS half only"
	HAVE_TDC=0
fi

sql <<'EOF' >/dev/null
CREATE SCHEMA IF NOT EXISTS bench;
CREATE OR REPLACE FUNCTION bench.time_query(q text, OUT ms float8, OUT result text)
LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz;
	nrows bigint;
BEGIN
	t0 := clock_timestamp();
	IF q ~* '^\s*(create|insert)' THEN
		EXECUTE q;
		GET DIAGNOSTICS nrows = ROW_COUNT;
		result := nrows::text;
	ELSE
		EXECUTE q INTO result;
	END IF;
	ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
END $$;
EOF

# ---------------------------------------------------------------- plots
# make_plots: $FIGS/sql.png from sql.csv/sql_runs.csv, $FIGS/coast_tin.png from the server
make_plots() {
	rm -f "$FIGS/sql.png" "$FIGS/coast_tin.png"
	log "plotting $FIGS/sql.png"
	for tool in tdc tdc_1t postgis; do
		for k in $SETS; do
			awk -F, -v k="$k" -v t="$tool" 'NR > 1 && $4 == t && index($1, k "_") == 1 && $6 != "-" { print $2, $6 }' "$CSV" > "$WORK/$tool.$k.dat"
		done
		awk -F, -v t="$tool" 'NR > 1 && $4 == t && $1 == "gshhg_1m" && $6 != "-" { print $2, $6 }' "$CSV" > "$WORK/$tool.g1m.dat"
	done
	awk -F, 'NR > 1 && $1 == "coastlines" && $4 == "tdc_dump" && $6 != "-" { print $2, $6 }' "$CSV" > "$WORK/dump.dat"
	awk -F, 'NR > 1 && $1 == "coastlines" && $4 == "tdc_dump_count" && $6 != "-" { print $2, $6 }' "$CSV" > "$WORK/dumpc.dat"
	pgfail=$(awk -F, 'NR > 1 && $1 == "coastlines" && $3 == "postgis" && $7 != "ok" { printf "%s %.3f\n", $2, $5 / 1000 }' "$RUNS")
	echo "$pgfail" | awk 'NF == 2' > "$WORK/pgfail.dat"

	plotcmds=()
	addplot() { [ -s "$1" ] && plotcmds+=("'$1' using 1:2 $2") || true; }
	addplot "$WORK/tdc.uniform.dat" "with linespoints lw 2 pt 7 lc rgb '#1f77b4' title 'tdc\\_delaunay, uniform'"
	addplot "$WORK/tdc.clustered.dat" "with linespoints lw 2 pt 5 lc rgb '#17becf' title 'tdc\\_delaunay, clustered'"
	addplot "$WORK/tdc_1t.uniform.dat" "with linespoints lw 1 dt 2 pt 6 lc rgb '#1f77b4' title 'tdc\\_delaunay 1 thread, uniform'"
	addplot "$WORK/postgis.uniform.dat" "with linespoints lw 2 pt 7 lc rgb '#d62728' title 'PostGIS ST\\_DelaunayTriangles, uniform'"
	addplot "$WORK/postgis.clustered.dat" "with linespoints lw 2 pt 5 lc rgb '#ff7f0e' title 'PostGIS, clustered'"
	addplot "$WORK/tdc.g1m.dat" "with points pt 9 ps 2 lc rgb '#1f77b4' title 'tdc\\_delaunay, 1M coastline vertices'"
	addplot "$WORK/postgis.g1m.dat" "with points pt 9 ps 2 lc rgb '#d62728' title 'PostGIS, 1M coastline vertices'"
	addplot "$WORK/dump.dat" "with points pt 13 ps 2.5 lc rgb '#2ca02c' title 'tdc\\_delaunay Dump into a table, GSHHG coastlines (10.6M)'"
	addplot "$WORK/dumpc.dat" "with points pt 12 ps 2.5 lw 2 lc rgb '#2ca02c' title 'tdc\\_delaunay Dump, count(*) only'"
	addplot "$WORK/pgfail.dat" "with points pt 2 ps 3 lw 2 lc rgb '#d62728' title 'PostGIS on coastlines: failed after this time'"
	if [ ${#plotcmds[@]} -gt 0 ]; then
		{
			echo "set terminal pngcairo size 900,600 font 'DejaVu Sans,11'"
			echo "set output '$FIGS/sql.png'"
			echo "set logscale xy"
			echo "set format x '10^{%L}'"
			echo "set xlabel 'points n'"
			echo "set ylabel 'seconds (server side)'"
			echo "set title 'Delaunay triangulation in PostgreSQL 15: tdc\\_delaunay vs PostGIS $(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'") ($(nproc) CPUs)'"
			echo "set grid"
			echo "set key bottom right"
			echo "set xrange [5e3:3e7]"
			printf 'plot '
			(IFS=,; echo "${plotcmds[*]}")
		} > "$WORK/bench.gp"
		gnuplot "$WORK/bench.gp" || log "gnuplot failed"
	fi

	if [ "$COAST" = 1 ] && [ $HAVE_TDC = 1 ]; then
		# Strait of Gibraltar: triangulate the full-resolution coastline vertices
		# inside the window and draw the triangles under the coastline
		log "plotting $FIGS/coast_tin.png (Strait of Gibraltar)"
		ENV="ST_MakeEnvelope(-6.0, 35.75, -5.25, 36.2, 4326)"
		sql -F ' ' > "$WORK/tin.dat" <<-EOF
	WITH pts AS (
		SELECT (d).geom AS geom
		FROM (SELECT ST_DumpPoints(geom) AS d FROM bench.coastlines WHERE geom && $ENV) s
		WHERE ST_Intersects((d).geom, $ENV)),
	tri AS (SELECT (ST_Dump(ST_TDCDelaunay(geom))).geom AS t FROM pts)
	SELECT string_agg(ST_X((p).geom) || ' ' || ST_Y((p).geom), E'\n' ORDER BY (p).path) || E'\n'
	FROM (SELECT row_number() OVER () AS id, ST_DumpPoints(t) AS p FROM tri) q
	GROUP BY id;
	EOF
		sql -F ' ' > "$WORK/coast.dat" <<-EOF
	SELECT string_agg(ST_X((p).geom) || ' ' || ST_Y((p).geom), E'\n' ORDER BY (p).path) || E'\n'
	FROM (SELECT id, ST_DumpPoints(ST_Intersection(geom, $ENV)) AS p
		  FROM bench.coastlines WHERE geom && $ENV) q
	GROUP BY id;
	EOF
		ntri=$(sql -c "SELECT ST_NumGeometries(ST_TDCDelaunay((d).geom)) FROM (SELECT ST_DumpPoints(geom) AS d FROM bench.coastlines WHERE geom && $ENV) s WHERE ST_Intersects((d).geom, $ENV)")
		npts=$(sql -c "SELECT count(*) FROM (SELECT ST_DumpPoints(geom) AS d FROM bench.coastlines WHERE geom && $ENV) s WHERE ST_Intersects((d).geom, $ENV)")
		gnuplot <<-EOF || log "gnuplot failed"
	set terminal png size 900,700 font 'DejaVu Sans,9'
	set output '$FIGS/coast_tin.png'
	set title 'Strait of Gibraltar: ST\\_TDCDelaunay of $npts GSHHG full-resolution coastline vertices ($ntri triangles)'
	set xrange [-6.0:-5.25]
	set yrange [35.75:36.2]
	set xlabel 'longitude'
	set ylabel 'latitude'
	unset key
	# 1 degree of longitude is cos(36 deg) of a degree of latitude: stretch y
	set size ratio (0.45 / (0.75 * cos(36.0 * pi / 180)))
	plot '$WORK/tin.dat' using 1:2 with lines lw 1 lc rgb '#7f9fbf', \
		 '$WORK/coast.dat' using 1:2 with lines lw 2 lc rgb '#000000'
	EOF
	fi
}

if [ "${BENCH_SQL_PLOT_ONLY:-0}" = 1 ]; then
	make_plots
	exit 0
fi

# ---------------------------------------------------------------- loading
# table_rows TABLE: row count, or empty if the table does not exist
table_rows() {
	if [ -n "$(sql -c "SELECT to_regclass('$1')")" ]; then
		sql -c "SELECT count(*) FROM $1"
	fi
}

# load_points TABLE TSV SRID
load_points() {
	local t=$1 tsv=$2 srid=$3 n
	n=$(wc -l < "$tsv")
	if [ "$RELOAD" = 0 ] && [ "$(table_rows "$t")" = "$n" ]; then
		return 0
	fi
	log "loading $t ($n points)"
	sql <<EOF
DROP TABLE IF EXISTS $t, bench.stage;
CREATE UNLOGGED TABLE bench.stage (x float8, y float8);
\copy bench.stage FROM '$tsv'
CREATE TABLE $t AS SELECT ST_SetSRID(ST_MakePoint(x, y), $srid)::geometry(Point, $srid) AS geom FROM bench.stage;
DROP TABLE bench.stage;
VACUUM ANALYZE $t;
EOF
}

declare -a PT_SETS=()
for nl in $SIZES; do
	for k in $SETS; do
		tsv=$BENCH_DATA/${k}_${nl}.tsv
		if [ ! -s "$tsv" ]; then
			mkdir -p "$BENCH_DATA"
			"$BENCH_BIN/gen_points" "$k" "$nl" "$POINT_SEED" "${tsv%.tsv}.tmp.tsv" && mv "${tsv%.tsv}.tmp.tsv" "$tsv"
		fi
		ensure_points "$k" "$nl" >/dev/null	# .bin for the exact count
		load_points "bench.${k}_${nl}" "$tsv" 0
		PT_SETS+=("${k}_${nl}")
	done
done

if [ "$COAST" = 1 ]; then
	ensure_gshhg
	load_points bench.gshhg_1m "$BENCH_DATA/gshhg_sub.tsv" 4326
	PT_SETS+=(gshhg_1m)
	nseg=$(wc -l < "$BENCH_DATA/gshhg_lines.ewkt")
	if [ "$RELOAD" = 1 ] || [ "$(table_rows bench.coastlines)" != "$nseg" ]; then
		log "loading bench.coastlines ($nseg LINESTRINGs, EWKT via COPY)"
		t0=$(date +%s.%N)
		sql <<EOF
DROP TABLE IF EXISTS bench.coastlines;
CREATE TABLE bench.coastlines (id serial PRIMARY KEY, geom geometry(LineString, 4326));
\copy bench.coastlines (geom) FROM '$BENCH_DATA/gshhg_lines.ewkt'
VACUUM ANALYZE bench.coastlines;
EOF
		log "loaded in $(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f s", b - a }')"
	fi
	COAST_LINES=$(sql -c "SELECT count(*) FROM bench.coastlines")
	COAST_VERTS=$(sql -c "SELECT sum(ST_NPoints(geom)) FROM bench.coastlines")
fi

# ---------------------------------------------------------------- exact counts (CGAL)
declare -A EXACT_TRI=() EXACT_N=()
exact_of() {	# SET BINFILE
	"$BENCH_BIN/cgal_dt" "$2" > "$WORK/cgal" || die "cgal_dt $2 failed"
	grep '^n=' "$WORK/cgal" > "$WORK/cgal1"
	EXACT_TRI[$1]=$(kv "$WORK/cgal1" faces)
	EXACT_N[$1]=$(kv "$WORK/cgal1" vertices)
}
for s in "${PT_SETS[@]}"; do
	if [ "$s" = gshhg_1m ]; then exact_of "$s" "$BENCH_DATA/gshhg_sub.bin"; else exact_of "$s" "$BENCH_DATA/$s.bin"; fi
done
[ "$COAST" = 1 ] && exact_of coastlines "$BENCH_DATA/gshhg.bin"

# ---------------------------------------------------------------- timing
echo "set,n,tool,rep,ms,result,status,message" > "$RUNS"

# timed SET N TOOL REP SETUP QUERY
timed() {
	local set=$1 n=$2 tool=$3 rep=$4 setup=$5 q=$6 st=ok msg="" ms="" res="" t0 t1
	local args=(-F ' ' -c "SET statement_timeout = '${TIMEOUT}s'")
	[ -n "$setup" ] && args+=(-c "$setup")
	args+=(-c "SELECT ms, result FROM bench.time_query(\$bq\$$q\$bq\$)")
	t0=$(date +%s.%N)
	if sql "${args[@]}" > "$WORK/out" 2> "$WORK/err"; then
		read -r ms res < "$WORK/out"
	else
		t1=$(date +%s.%N)
		ms=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.0f", 1000 * (b - a) }')
		msg=$(grep -m1 ERROR "$WORK/err" | sed 's/^.*ERROR: *//; s/,/;/g' || true)
		[ -z "$msg" ] && msg=$(head -1 "$WORK/err" | sed 's/,/;/g')
		if grep -q 'statement timeout' "$WORK/err"; then st=timeout; else st=error; fi
		log "  $tool on $set: $st after ${ms} ms: $msg"
	fi
	echo "$set,$n,$tool,$rep,$ms,$res,$st,$msg" >> "$RUNS"
}

TDC_Q='SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM bench.%s'
PG_Q='SELECT ST_NumGeometries(ST_DelaunayTriangles(ST_Collect(geom))) FROM bench.%s'

bench_begin server
for s in "${PT_SETS[@]}"; do
	n=$(table_rows "bench.$s")
	reps=1
	if [ "$n" -le 100000 ]; then reps=$REPS_SMALL; elif [ "$n" -le 1000000 ]; then reps=$REPS_MID; fi
	log "$s (n=$n, $reps repetitions)"
	# warm the buffer cache once, untimed
	sql -c "SELECT count(*) FROM bench.$s" >/dev/null
	for rep in $(seq 1 "$reps"); do
		# alternate the order between repetitions
		if [ $((rep % 2)) = 1 ]; then tools="tdc tdc_1t postgis collect"; else tools="collect postgis tdc_1t tdc"; fi
		for tool in $tools; do
			if [ "$tool" = collect ]; then
				timed "$s" "$n" collect "$rep" "" "SELECT ST_NumGeometries(ST_Collect(geom)) FROM bench.$s"
			elif [ "$tool" = postgis ]; then
				timed "$s" "$n" postgis "$rep" "" "$(printf "$PG_Q" "$s")"
			elif [ $HAVE_TDC = 1 ]; then
				thr=0
				[ "$tool" = tdc_1t ] && thr=1
				timed "$s" "$n" "$tool" "$rep" "SET tdc_delaunay.threads = $thr" "$(printf "$TDC_Q" "$s")"
			fi
		done
	done
done

if [ "$COAST" = 1 ]; then
	n=$COAST_VERTS
	log "coastlines ($COAST_LINES LINESTRINGs, $n vertices), one run each"
	if [ $HAVE_TDC = 1 ]; then
		sql -c "DROP TABLE IF EXISTS bench.tin" >/dev/null
		timed coastlines "$n" tdc_dump 1 "SET tdc_delaunay.threads = 0" \
			"CREATE TABLE bench.tin AS SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM bench.coastlines')"
		timed coastlines "$n" tdc_dump_count 1 "SET tdc_delaunay.threads = 0" \
			"SELECT count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM bench.coastlines')"
		if [ "$TDC_COAST_AGG" = 1 ]; then
			timed coastlines "$n" tdc 1 "SET tdc_delaunay.threads = 0" "$(printf "$TDC_Q" coastlines)"
		fi
	fi
	if [ "$PG_COAST" = 1 ]; then
		timed coastlines "$n" postgis 1 "" "$(printf "$PG_Q" coastlines)"
	fi
	bench_end
	if [ "$HULLCHECK" = 1 ]; then
		log "coastlines: unique vertices and convex-hull vertices (collinear ones included) in SQL"
		sql -F ' ' > "$WORK/hull" <<'EOF' || log "hull check failed"
SET statement_timeout = 0;
CREATE TEMP TABLE u AS
	SELECT DISTINCT ST_X((d).geom) AS x, ST_Y((d).geom) AS y
	FROM (SELECT ST_DumpPoints(geom) AS d FROM bench.coastlines) s;
WITH h AS (SELECT ST_ExteriorRing(ST_ConvexHull(ST_Collect(ST_MakePoint(x, y)))) AS r FROM u)
SELECT (SELECT count(*) FROM u),
	   (SELECT count(*) FROM u, h WHERE ST_Intersects(r, ST_MakePoint(x, y)));
EOF
		read -r SQL_UNIQ SQL_HULL < "$WORK/hull" || true
	fi
fi

[ -n "${BENCH_T1:-}" ] || bench_end

# ---------------------------------------------------------------- tables
med() {	# SET TOOL FIELD(ms)
	awk -F, -v s="$1" -v t="$2" '$1 == s && $3 == t && $7 == "ok" { print $5 }' "$RUNS" | median
}
cnt() { awk -F, -v s="$1" -v t="$2" -v st="${3:-ok}" '$1 == s && $3 == t && $7 == st { k++ } END { print k + 0 }' "$RUNS"; }
resof() { awk -F, -v s="$1" -v t="$2" '$1 == s && $3 == t && $7 == "ok" { print $6; exit }' "$RUNS"; }
failof() { awk -F, -v s="$1" -v t="$2" '$1 == s && $3 == t && $7 != "ok" { printf "%s after %.1f s: %s", $7, $5 / 1000, $8; exit }' "$RUNS"; }
sec() { awk -v x="$1" 'BEGIN { if (x == "") print "-"; else printf "%.3f\n", x / 1000 }'; }

echo "set,n,exact_triangles,tool,runs,median_s,min_s,max_s,triangles,triangles_exact,status" > "$CSV"
{
	echo "# server: $(sql -c "SELECT split_part(version(), ' on ', 1)"), PostGIS $(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'") (GEOS $(sql -c "SELECT split_part(postgis_geos_version(), '-', 1)")), tdc_delaunay $(sql -c "SELECT coalesce((SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'), 'absent')")"
	echo "# shared_buffers=$(sql -c 'SHOW shared_buffers') work_mem=$(sql -c 'SHOW work_mem'); statement_timeout=${TIMEOUT}s"
	echo "# times: server-side (clock_timestamp around EXECUTE), medians; tdc = all CPUs, tdc_1t = tdc_delaunay.threads=1, postgis = ST_DelaunayTriangles(ST_Collect(geom)),"
	echo "#        collect = ST_Collect(geom) alone (cost of reading + aggregating the input, a floor for both)"
	echo "# exact = 2n-2-h from CGAL (exact predicates) on the same coordinates"
	if [ "$COAST" = 1 ]; then
		echo "# GSHHG coastlines: $COAST_LINES LINESTRINGs, $COAST_VERTS vertices (SRID 4326); $(cat "$BENCH_DATA/gshhg.meta")"
	fi
	echo
	printf '%-14s %9s %10s  %-14s %4s %9s %9s %9s %10s %6s  %s\n' set n exact tool runs median_s min_s max_s triangles =exact note
} | tee "$TXT"

tools_of() { awk -F, -v s="$1" 'NR > 1 && $1 == s && !seen[$3]++ { print $3 }' "$RUNS"; }
for s in "${PT_SETS[@]}" $([ "$COAST" = 1 ] && echo coastlines); do
	n=$(awk -F, -v s="$s" '$1 == s { print $2; exit }' "$RUNS")
	for tool in $(tools_of "$s"); do
		runs=$(( $(cnt "$s" "$tool") + $(cnt "$s" "$tool" error) + $(cnt "$s" "$tool" timeout) ))
		m=$(med "$s" "$tool")
		mn=$(awk -F, -v s="$s" -v t="$tool" '$1 == s && $3 == t && $7 == "ok" { print $5 }' "$RUNS" | sort -g | head -1)
		mx=$(awk -F, -v s="$s" -v t="$tool" '$1 == s && $3 == t && $7 == "ok" { print $5 }' "$RUNS" | sort -g | tail -1)
		tri=$(resof "$s" "$tool")
		ex=${EXACT_TRI[$s]:-}
		eq=""
		[ -n "$tri" ] && [ -n "$ex" ] && [ "$tool" != collect ] && { [ "$tri" = "$ex" ] && eq=yes || eq="NO($((tri - ex)))"; }
		note=$(failof "$s" "$tool")
		status=ok
		[ -n "$note" ] && status=$(awk -F, -v s="$s" -v t="$tool" '$1 == s && $3 == t && $7 != "ok" { print $7; exit }' "$RUNS")
		echo "$s,$n,$ex,$tool,$runs,$(sec "$m"),$(sec "$mn"),$(sec "$mx"),$tri,$eq,$status" >> "$CSV"
		printf '%-14s %9s %10s  %-14s %4s %9s %9s %9s %10s %6s  %s\n' "$s" "$n" "${ex:--}" "$tool" "$runs" \
			"$(sec "$m")" "$(sec "$mn")" "$(sec "$mx")" "${tri:--}" "${eq:--}" "$note" | tee -a "$TXT"
	done
done

if [ "$COAST" = 1 ]; then
	{
		echo
		ex=${EXACT_TRI[coastlines]:-}
		en=${EXACT_N[coastlines]:-}
		tin=$(resof coastlines tdc_dump)
		echo "Coastlines TIN (ST_TDCDelaunayDump -> bench.tin): ${tin:-not built} triangles"
		if [ -n "$ex" ]; then
			echo "  exact (CGAL on the same vertices): n = $en unique sites, h = $((2 * en - 2 - ex)) hull sites (collinear included), 2n-2-h = $ex"
		fi
		if [ -n "${SQL_UNIQ:-}" ]; then
			echo "  in SQL: $SQL_UNIQ unique vertices, $SQL_HULL of them on the convex hull boundary -> 2n-2-h = $((2 * SQL_UNIQ - 2 - SQL_HULL))"
		fi
		if [ -n "$tin" ] && [ -n "$ex" ]; then
			[ "$tin" = "$ex" ] && echo "  TIN triangle count matches 2n-2-h exactly" || echo "  TIN triangle count DIFFERS from 2n-2-h by $((tin - ex))"
		fi
	} | tee -a "$TXT"
fi

make_plots
ls -l "$FIGS"/sql.png "$FIGS"/coast_tin.png 2>/dev/null >&2 || true
bench_figure "$FIGS/sql.png" sql
bench_figure "$FIGS/coast_tin.png" coast_tin
bench_publish sql "Aggregates in SQL: tdc_delaunay against PostGIS on uniform, clustered and coastline points" "$TXT" text
log "wrote $CSV, $RUNS, $TXT"
