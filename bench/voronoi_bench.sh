#!/usr/bin/env bash
# bench/voronoi_bench.sh -- Voronoi diagrams in SQL: tdc_delaunay against
# PostGIS ST_VoronoiPolygons (GEOS) on the same server, in the same run, with
# our Delaunay aggregate beside them (issue 15).  It prints figures; it
# asserts nothing.
#
# Server: the usual libpq variables (PGHOST, PGPORT, PGUSER, PGDATABASE); the
# extensions postgis and tdc_delaunay are created if missing (tdc_delaunay
# must be installed: make install).  Tables live in schema "bench_vor" and are
# kept between runs (BENCH_VOR_RELOAD=1 rebuilds them).
#
# Data: n uniform points in [0,1)^2, one POINT per row, point i being
#   x = (hashint8extended(i, 1) & (2^52 - 1)) / 2^52,  y = the same with seed 2
# (the formula of bench/sweep_bench.sh), so every table is a pure function of n.
#
# Statements, over the table t of n points:
#   geos       ST_VoronoiPolygons(ST_Collect(geom))      PostGIS (GEOS)
#   tdc_poly   ST_TDCVoronoiPolygons(ST_Collect(geom))   ours, the drop-in
#   tdc_agg    ST_TDCVoronoi(geom)                       ours, the aggregate
#   tdc_del    ST_TDCDelaunay(geom)                      our Delaunay aggregate
# each in two forms: "SELECT <expr> IS NOT NULL FROM t" (isnn: the value is
# built and written, as for a row that is stored or sent on) and
# "SELECT ST_NumGeometries(<expr>) FROM t" (ng: PostGIS also reads it back);
# the ng results are the cell (triangle) counts, checked below: every Voronoi
# statement must give n cells (the points are distinct), the Delaunay one
# 2n - 2 - h triangles (h: vertices of the convex hull).
#
# Timing: server side, clock_timestamp() around EXECUTE in a plpgsql
# function.  Each size runs in one psql session: the session settings, then
# each statement once untimed (warm-up; BENCH_VOR_WARM), then BENCH_VOR_REPS
# rounds, each round running every statement once in the order above (so the
# load on the machine affects all of them alike); medians reported, with the
# ratio GEOS median / our median of the same form.  A statement that fails
# (error, or statement_timeout = BENCH_VOR_TIMEOUT s) is recorded with its
# message and not run again in that session.
#
# Outputs: build/bench/voronoi_runs.csv  every run (rep <= 0: warm-up)
#          build/bench/voronoi.csv       medians, min, max, ratios, counts
#          build/bench/voronoi.txt       header + Markdown table (for the README)
# Knobs:   BENCH_VOR_SIZES="1e5 1e6"  BENCH_VOR_REPS=5  BENCH_VOR_WARM=1
#          BENCH_VOR_FORMS="isnn ng"  BENCH_VOR_TIMEOUT=600 (s per statement)
#          BENCH_VOR_SETTINGS="jit=off max_parallel_workers_per_gather=0"
#          (session settings, name=value ...; "" keeps the server's)
#          BENCH_VOR_RELOAD=1
#
# jit=off and a serial plan by default: with jit on, only the statements whose
# planner cost passes jit_above_cost pay for compilation (that would measure
# the cost constants), and a parallel plan would give ours parallel workers
# that ST_Collect cannot use.  The plan of every statement is recorded.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

SIZES=${BENCH_VOR_SIZES:-"1e5 1e6"}
REPS=${BENCH_VOR_REPS:-5}
WARM=${BENCH_VOR_WARM:-1}
FORMS=${BENCH_VOR_FORMS:-"isnn ng"}
TIMEOUT=${BENCH_VOR_TIMEOUT:-600}
RELOAD=${BENCH_VOR_RELOAD:-0}
SETTINGS=${BENCH_VOR_SETTINGS-"jit=off max_parallel_workers_per_gather=0"}
SYSTEMS=(geos tdc_poly tdc_agg tdc_del)
S=bench_vor

mkdir -p "$BENCH_OUT"
RUNS=$BENCH_OUT/voronoi_runs.csv
CSV=$BENCH_OUT/voronoi.csv
TXT=$BENCH_OUT/voronoi.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT


command -v psql >/dev/null || die "psql not found"


sql -c 'SELECT 1' >/dev/null 2>&1 ||
	die "no PostgreSQL server reachable with PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} PGUSER=${PGUSER:-} PGDATABASE=${PGDATABASE:-}"
sql -c "CREATE EXTENSION IF NOT EXISTS postgis" >/dev/null
sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay" >/dev/null 2> "$WORK/err" ||
	die "tdc_delaunay extension not available ($(head -1 "$WORK/err")): make install first"
PG_VER=$(sql -c "SELECT split_part(version(), ' on ', 1)")
PGIS_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'")
GEOS_VER=$(sql -c "SELECT split_part(postgis_geos_version(), '-', 1)")
TDC_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")

SET_SQL=""
for kvp in $SETTINGS; do
	case $kvp in *=*) ;; *) die "BENCH_VOR_SETTINGS: '$kvp' is not name=value" ;; esac
	SET_SQL+="SET ${kvp%%=*} = '${kvp#*=}';"$'\n'
done

bench_sql_helpers "$S" | sql >/dev/null

# ensure_table N: $S.pts_N unless an identical one exists (its comment says how it was made)
ensure_table() {
	local n=$1 t=$S.pts_$1 spec
	spec="voronoi v1: n=$n, points $S.pt(0 .. $((n - 1)))"
	if [ "$RELOAD" = 0 ] && [ "$(sql -c "SELECT obj_description(to_regclass('$t'), 'pg_class')")" = "$spec" ]; then
		return 0
	fi
	log "creating $t ($n points)"
	sql <<EOF >/dev/null
SET statement_timeout = 0;
DROP TABLE IF EXISTS $t;
CREATE TABLE $t AS SELECT $S.pt(i) AS geom FROM generate_series(0::bigint, $((n - 1))) i ORDER BY i;
COMMENT ON TABLE $t IS '$spec';
VACUUM (ANALYZE) $t;
EOF
}

expr_of() {
	case $1 in
		geos) echo "ST_VoronoiPolygons(ST_Collect(geom))" ;;
		tdc_poly) echo "ST_TDCVoronoiPolygons(ST_Collect(geom))" ;;
		tdc_agg) echo "ST_TDCVoronoi(geom)" ;;
		tdc_del) echo "ST_TDCDelaunay(geom)" ;;
	esac
}
query_of() {	# SYSTEM FORM TABLE
	case $2 in
		isnn) echo "SELECT $(expr_of "$1") IS NOT NULL FROM $3" ;;
		ng) echo "SELECT ST_NumGeometries($(expr_of "$1")) FROM $3" ;;
		*) die "unknown form '$2' (isnn ng)" ;;
	esac
}

SIZE_NS=()
for nl in $SIZES; do
	n=$(n_of "$nl")
	SIZE_NS+=("$n")
	ensure_table "$n"
done

SO=$(pg_config --pkglibdir 2>/dev/null)/tdc_delaunay.so
SO_START=$(so_id)
bench_begin server
echo "n,form,system,rep,ms,result,status,message,plan" > "$RUNS"

# run_size N: one session; warm-up, then REPS rounds of every statement
run_size() {
	local n=$1 t=$S.pts_$1 sys form rep line ms res st msg key
	declare -A Q=()
	for form in $FORMS; do
		for sys in "${SYSTEMS[@]}"; do
			Q[$sys.$form]=$(query_of "$sys" "$form" "$t")
		done
	done
	{
		echo "SET statement_timeout = '${TIMEOUT}s';"
		printf '%s' "$SET_SQL"
		for key in "${!Q[@]}"; do
			echo "SELECT 'plan', '$key', $S.plan_of(\$bq\$${Q[$key]}\$bq\$);"
		done
		for rep in $(seq $((1 - WARM)) "$REPS"); do
			for form in $FORMS; do
				for sys in "${SYSTEMS[@]}"; do
					echo "SELECT 'run', * FROM $S.time_query('$sys.$form', $rep, \$bq\$${Q[$sys.$form]}\$bq\$);"
				done
			done
		done
	} > "$WORK/size.sql"
	log "n=$n: ${SYSTEMS[*]} x {$FORMS} x ($WARM + $REPS)"
	psql -X -q -A -t -F '|' -f "$WORK/size.sql" > "$WORK/size.out" 2> "$WORK/size.err" || true
	if grep -q . "$WORK/size.err"; then
		log "  psql said: $(head -3 "$WORK/size.err" | tr '\n' ' ')"
	fi
	declare -A PLAN=()
	while IFS='|' read -r tag key plan; do
		[ "$tag" = plan ] && PLAN[$key]=$plan
	done < "$WORK/size.out"
	for rep in $(seq $((1 - WARM)) "$REPS"); do
		for form in $FORMS; do
			for sys in "${SYSTEMS[@]}"; do
				line=$(awk -F'|' -v s="$sys.$form" -v r="$rep" '$1 == "run" && $2 == s && $3 == r' "$WORK/size.out")
				if [ -n "$line" ]; then
					IFS='|' read -r _ _ _ ms res st msg <<< "$line"
					[ "$st" = ok ] || [ "$st" = skipped ] || log "  $sys $form: $st after $(fmt_ms "$ms"): $msg"
				else
					ms=""; res=""; st=error
					msg=$(grep -m1 -E 'FATAL|ERROR|server closed|connection' "$WORK/size.err" | sed 's/,/;/g' || true)
					[ -n "$msg" ] || msg="no output from psql"
				fi
				echo "$n,$form,$sys,$rep,$ms,$res,$st,$msg,${PLAN[$sys.$form]:-}" >> "$RUNS"
			done
		done
	done
}

for n in "${SIZE_NS[@]}"; do
	run_size "$n"
done
bench_end
SO_END=$(so_id)
[ "$SO_START" = "$SO_END" ] || log "WARNING: $SO changed during the run ($SO_START -> $SO_END)"

# ---------------------------------------------------------------- summary
vals() { awk -F, -v n="$1" -v f="$2" -v s="$3" 'NR > 1 && $1 == n && $2 == f && $3 == s && $4 >= 1 && $7 == "ok" { print $5 }' "$RUNS"; }
result_of() { awk -F, -v n="$1" -v f="$2" -v s="$3" 'NR > 1 && $1 == n && $2 == f && $3 == s && $7 == "ok" { print $6; exit }' "$RUNS"; }
failure_of() { awk -F, -v n="$1" -v f="$2" -v s="$3" 'NR > 1 && $1 == n && $2 == f && $3 == s && ($7 == "error" || $7 == "timeout") { print $7 " after " $5 " ms: " $8; exit }' "$RUNS"; }
name_of() {
	case $1 in
		geos) echo "PostGIS \`ST_VoronoiPolygons(ST_Collect(geom))\`" ;;
		tdc_poly) echo "\`ST_TDCVoronoiPolygons(ST_Collect(geom))\`" ;;
		tdc_agg) echo "aggregate \`ST_TDCVoronoi(geom)\`" ;;
		tdc_del) echo "Delaunay aggregate \`ST_TDCDelaunay(geom)\`" ;;
	esac
}
form_name() { case $1 in isnn) echo "IS NOT NULL" ;; ng) echo "ST_NumGeometries" ;; esac; }

THREADS=$(sql -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)') IS NOT NULL" -c "SELECT current_setting('tdc_delaunay.threads', true)" | tail -1)
setting() { sql -c "$SET_SQL" -c "SELECT current_setting('$1', true)" | tail -1; }

echo "n,form,system,median_ms,min_ms,max_ms,runs,geos_over_this,result,expected_result,status,plan" > "$CSV"
{
	echo "- server: $PG_VER, PostGIS $PGIS_VER, GEOS $GEOS_VER, tdc_delaunay $TDC_VER (git $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?'); $SO: $SO_START)"
	if [ "$SO_START" != "$SO_END" ]; then
		echo "- **WARNING: tdc_delaunay.so was replaced during the run ($SO_START -> $SO_END): the figures mix two builds; run again.**"
	fi
	echo "- settings: jit=$(setting jit) max_parallel_workers_per_gather=$(setting max_parallel_workers_per_gather) tdc_delaunay.threads=${THREADS:-?} shared_buffers=$(setting shared_buffers) work_mem=$(setting work_mem) statement_timeout=${TIMEOUT}s${SETTINGS:+ (set for the runs: $SETTINGS)}"
	echo "- timing: server side (clock_timestamp() around EXECUTE in plpgsql), one session per size, each statement run $WARM time(s) untimed first, then $REPS rounds of all statements interleaved; medians (min-max). Points uniform in [0,1)^2, one POINT per row. Ratio: the GEOS median over this median, same form."
	echo
	echo "| n | form | statement | median | min - max | GEOS / this | cells |"
	echo "|--:|---|---|--:|--:|--:|--:|"
} > "$TXT"

NOTES=()
for n in "${SIZE_NS[@]}"; do
	hull=""
	for form in $FORMS; do
		geos_med=$(vals "$n" "$form" geos | median)
		for sys in "${SYSTEMS[@]}"; do
			med=$(vals "$n" "$form" "$sys" | median)
			mn=$(vals "$n" "$form" "$sys" | sort -g | head -1)
			mx=$(vals "$n" "$form" "$sys" | sort -g | tail -1)
			nr=$(vals "$n" "$form" "$sys" | grep -c . || true)
			res=$(result_of "$n" "$form" "$sys")
			fail=$(failure_of "$n" "$form" "$sys")
			plan=$(awk -F, -v n="$n" -v f="$form" -v s="$sys" 'NR > 1 && $1 == n && $2 == f && $3 == s { print $9; exit }' "$RUNS")
			ratio=""
			[ -n "$geos_med" ] && [ -n "$med" ] && ratio=$(awk -v a="$geos_med" -v b="$med" 'BEGIN { printf "%.3g", a / b }')
			expect=""
			if [ "$form" = ng ]; then
				if [ "$sys" = tdc_del ]; then
					[ -n "$hull" ] || hull=$(sql -c "SELECT ST_NPoints(ST_ExteriorRing(ST_ConvexHull(ST_Collect(geom)))) - 1 FROM $S.pts_$n")
					expect=$((2 * n - 2 - hull))
				else
					expect=$n
				fi
				if [ -n "$res" ] && [ "$res" != "$expect" ]; then
					NOTES+=("n=$(thousands "$n"), $(name_of "$sys"): $res cells, expected $expect")
				fi
			fi
			[ -n "$fail" ] && NOTES+=("n=$(thousands "$n"), $(form_name "$form"), $(name_of "$sys"): $fail")
			[ -n "$plan" ] && [ "$plan" != serial ] && NOTES+=("n=$(thousands "$n"), $(form_name "$form"), $(name_of "$sys"): plan $plan")
			echo "$n,$form,$sys,$med,$mn,$mx,$nr,$ratio,$res,$expect,$([ -n "$fail" ] && echo "${fail%% *}" || echo ok),$plan" >> "$CSV"
			printf '| %s | %s | %s | %s | %s | %s | %s |\n' "$(thousands "$n")" "$(form_name "$form")" "$(name_of "$sys")" \
				"$([ -n "$med" ] && fmt_ms "$med" || echo "${fail:+${fail%% *}}")" \
				"$([ -n "$mn" ] && echo "$(fmt_ms "$mn") - $(fmt_ms "$mx")" || echo -)" \
				"$([ -n "$ratio" ] && echo "${ratio}x" || echo -)" \
				"$([ -n "$res" ] && [ "$form" = ng ] && thousands "$res" || echo -)" >> "$TXT"
		done
	done
done
{
	echo
	echo "Cells: ST_NumGeometries of the result (the ng form); n for every Voronoi statement (distinct points), 2n - 2 - h triangles for the Delaunay aggregate (h = vertices of the convex hull)."
	for note in "${NOTES[@]}"; do echo "- $note"; done
} >> "$TXT"

bench_publish voronoi "Voronoi diagrams in SQL: tdc_delaunay against PostGIS (GEOS)" "$TXT"
cat "$TXT"
log "wrote $RUNS, $CSV, $TXT"
