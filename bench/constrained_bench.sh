#!/usr/bin/env bash
# bench/constrained_bench.sh -- the constrained Delaunay triangulation in SQL:
# tdc_delaunay against SFCGAL's ST_ConstrainedDelaunayTriangles, and against
# our own unconstrained triangulation of the same vertices, in one run
# (issue 14).  It prints figures; it asserts nothing.
#
# Server: the usual libpq variables (PGHOST, PGPORT, PGUSER, PGDATABASE); the
# extensions postgis, postgis_sfcgal (when available) and tdc_delaunay are
# created if missing (tdc_delaunay must be installed: make install).  Tables
# live in schema "bench_cdt" and are kept between runs (BENCH_CDT_RELOAD=1
# rebuilds them).
#
# Data sets:
#   contours  about 1M vertices in 320 nested noisy rings, one closed
#             LINESTRING per ring (ring r: 16 + 196 r / 10 vertices, radius
#             r + 0.3 * noise, the noise from hashint4, so the table is a pure
#             function of its formula); BENCH_CDT_RINGS=320 changes the count
#   coast     GSHHG full-resolution shorelines of a region (BENCH_CDT_COAST_REGION,
#             default 15/30/57/66: the Baltic from Stockholm to the Gulf of
#             Finland and the Gulf of Bothnia, about 460k vertices), made as
#             test/fixtures/README.md describes for gshhg-stockholm.wkt:
#             `gmt coast -R<region> -Df -W -M` (gmt, gmt-gshhg-full), the pieces
#             joined by ST_LineMerge(ST_Collect(...)), each closed line made a
#             POLYGON by ST_BuildArea, the open ones (cut by the box) kept as
#             LINESTRINGs; one row per polygon or line
# BENCH_CDT_DATASETS="contours coast" selects them.
#
# Statements, each as pg_column_size(...) (the production of the value) and as
# ST_NumGeometries(...) (the value taken apart again by PostGIS):
#   agg      SELECT f(ST_TDCConstrainedDelaunay(geom)) FROM t
#   dropin   SELECT f(ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom))) FROM t
#   sfcgal   SELECT f(ST_ConstrainedDelaunayTriangles(ST_Collect(geom))) FROM t
#   unc      SELECT f(ST_TDCDelaunay(geom)) FROM t   (the same vertices, no constraints)
# ours with tdc_delaunay.threads = 1 and 2 under a serial plan
# (max_parallel_workers_per_gather = 0), and agg and unc once more with the
# server's defaults (threads, max_parallel_workers_per_gather: whatever plan
# the planner picks; the plan is recorded).  SFCGAL is serial and one-threaded.
#
# Timing: server side, clock_timestamp() around EXECUTE in a plpgsql function;
# the settings of a statement are made before its clock starts.  One psql
# session per data set: each statement once untimed (warm-up, BENCH_CDT_WARM),
# then BENCH_CDT_REPS rounds, each round every statement once in the same
# order (interleaved: the load on the machine affects all); medians.  A
# statement that fails (error, or statement_timeout = BENCH_CDT_TIMEOUT s) is
# recorded with its message and not run again in that session.
#
# Outputs: build/bench/constrained_runs.csv  every run (rep <= 0: warm-up)
#          build/bench/constrained.csv       medians, ratios, triangle counts
#          build/bench/constrained.txt       header + Markdown tables (for the README)
# Knobs:   BENCH_CDT_REPS=5  BENCH_CDT_WARM=1  BENCH_CDT_TIMEOUT=600
#          BENCH_CDT_DATASETS="contours coast"  BENCH_CDT_RINGS=320
#          BENCH_CDT_COAST_REGION=15/30/57/66  BENCH_CDT_RELOAD=1
#          BENCH_CDT_SETTINGS="jit=off" (session settings, name=value ..., as in
#          bench/sweep_bench.sh; "" keeps the server's)
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

REPS=${BENCH_CDT_REPS:-5}
WARM=${BENCH_CDT_WARM:-1}
TIMEOUT=${BENCH_CDT_TIMEOUT:-600}
DATASETS=${BENCH_CDT_DATASETS:-"contours coast"}
RINGS=${BENCH_CDT_RINGS:-320}
REGION=${BENCH_CDT_COAST_REGION:-15/30/57/66}
RELOAD=${BENCH_CDT_RELOAD:-0}
SETTINGS=${BENCH_CDT_SETTINGS-"jit=off"}
S=bench_cdt

mkdir -p "$BENCH_OUT" "$BENCH_DATA"
RUNS=$BENCH_OUT/constrained_runs.csv
CSV=$BENCH_OUT/constrained.csv
TXT=$BENCH_OUT/constrained.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT


command -v psql >/dev/null || die "psql not found"
sql -c 'SELECT 1' >/dev/null 2>&1 ||
	die "no PostgreSQL server reachable with PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} PGUSER=${PGUSER:-} PGDATABASE=${PGDATABASE:-}"
sql -c "CREATE EXTENSION IF NOT EXISTS postgis" >/dev/null
sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay" >/dev/null 2> "$WORK/err" ||
	die "tdc_delaunay extension not available ($(head -1 "$WORK/err")): make install first"
HAVE_SFCGAL=0
if sql -c "CREATE EXTENSION IF NOT EXISTS postgis_sfcgal" >/dev/null 2> "$WORK/err"; then
	HAVE_SFCGAL=1
else
	log "postgis_sfcgal not available ($(head -1 "$WORK/err")): SFCGAL not run"
fi


bench_sql_helpers "$S" | sql >/dev/null

# ---------------------------------------------------------------- data
# is_current TABLE SPEC: the table exists and its comment is SPEC
is_current() {
	[ "$RELOAD" = 0 ] && [ "$(sql -c "SELECT obj_description(to_regclass('$1'), 'pg_class')")" = "$2" ]
}

ensure_contours() {
	local t=$S.contours spec="cdt v1: contours, $RINGS rings, n = 16 + 196 r / 10"
	is_current $t "$spec" && return 0
	log "creating $t ($RINGS rings)"
	# the formula of the issue's contour benchmark; the last vertex of each
	# ring is then set to its first, so that the rings close exactly
	sql <<EOF >/dev/null
SET statement_timeout = 0;
DROP TABLE IF EXISTS $t;
CREATE TABLE $t AS SELECT r, ST_MakeLine(array_agg(ST_MakePoint(
	(r + 0.3 * (hashint4(r * 100000 + i) / 2147483648.0)) * cos(2 * pi() * (i % n) / n),
	(r + 0.3 * (hashint4(r * 100000 + i) / 2147483648.0)) * sin(2 * pi() * (i % n) / n)) ORDER BY i)) AS geom
FROM generate_series(1, $RINGS) r, LATERAL (SELECT 16 + (196 * r) / 10 AS n) k,
	LATERAL generate_series(0, n) i GROUP BY r;
UPDATE $t SET geom = ST_SetPoint(geom, ST_NPoints(geom) - 1, ST_StartPoint(geom));
COMMENT ON TABLE $t IS '$spec';
VACUUM (ANALYZE) $t;
EOF
}

ensure_coast() {
	local t=$S.coast spec="cdt v1: coast, GSHHG full resolution, gmt coast -R$REGION -Df -W -M" f
	is_current $t "$spec" && return 0
	f=$BENCH_DATA/coast_${REGION//\//_}.tsv
	if [ ! -s "$f" ]; then
		ensure_debs gmt gmt-gshhg-full
		log "extracting GSHHG full resolution: gmt coast -R$REGION -Df -W -M"
		# GMT writes gmt.history into the working directory: run it in $WORK;
		# each piece becomes one row "id<TAB>LINESTRING(...)"
		(cd "$WORK" && gmt coast -R"$REGION" -Df -W -M > coast.txt) || die "gmt coast failed"
		awk '/^>/ { if (n > 1) print id "\t" s ")"; id++; s = "LINESTRING("; n = 0; next }
			{ s = s (n ? "," : "") $1 " " $2; n++ }
			END { if (n > 1) print id "\t" s ")" }' "$WORK/coast.txt" > "$f.tmp" && mv "$f.tmp" "$f"
	fi
	log "creating $t from $f"
	sql <<EOF >/dev/null
SET statement_timeout = 0;
DROP TABLE IF EXISTS $t, ${t}_pieces;
CREATE TABLE ${t}_pieces (id int, geom geometry);
\copy ${t}_pieces FROM '$f'
CREATE TABLE $t AS
SELECT CASE WHEN ST_IsClosed(g) THEN ST_BuildArea(g) ELSE g END AS geom
FROM (SELECT (ST_Dump(ST_LineMerge(ST_Collect(geom)))).geom AS g FROM ${t}_pieces) s;
DROP TABLE ${t}_pieces;
COMMENT ON TABLE $t IS '$spec';
VACUUM (ANALYZE) $t;
EOF
}

describe() {
	sql -c "SELECT string_agg(format('%s %s', c, ty), ', ') || format(' (%s vertices)', sum(v))
		FROM (SELECT GeometryType(geom) ty, count(*) c, sum(ST_NPoints(geom)) v FROM $S.$1 GROUP BY 1) s"
}

for d in $DATASETS; do
	case $d in
		contours) ensure_contours ;;
		coast) ensure_coast ;;
		*) die "unknown data set '$d' (contours coast)" ;;
	esac
done

# ---------------------------------------------------------------- statements
SERIAL="max_parallel_workers_per_gather=0"
# name|settings|expression of geom (the table's column)
STMTS=(
	"agg1|tdc_delaunay.threads=1 $SERIAL|ST_TDCConstrainedDelaunay(geom)"
	"agg2|tdc_delaunay.threads=2 $SERIAL|ST_TDCConstrainedDelaunay(geom)"
	"aggdef|tdc_delaunay.threads=DEFAULT max_parallel_workers_per_gather=DEFAULT|ST_TDCConstrainedDelaunay(geom)"
	"drop1|tdc_delaunay.threads=1 $SERIAL|ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom))"
	"drop2|tdc_delaunay.threads=2 $SERIAL|ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom))"
	"unc1|tdc_delaunay.threads=1 $SERIAL|ST_TDCDelaunay(geom)"
	"unc2|tdc_delaunay.threads=2 $SERIAL|ST_TDCDelaunay(geom)"
	"uncdef|tdc_delaunay.threads=DEFAULT max_parallel_workers_per_gather=DEFAULT|ST_TDCDelaunay(geom)"
)
[ "$HAVE_SFCGAL" = 1 ] && STMTS+=("sfcgal|$SERIAL|ST_ConstrainedDelaunayTriangles(ST_Collect(geom))")
FORMS=(pcs ng)
form_sql() { [ "$1" = pcs ] && echo "pg_column_size($2)" || echo "ST_NumGeometries($2)"; }

label() {
	case $1 in
		agg1) echo "ours, aggregate \`ST_TDCConstrainedDelaunay(geom)\`, 1 thread" ;;
		agg2) echo "ours, aggregate, 2 threads" ;;
		aggdef) echo "ours, aggregate, default settings" ;;
		drop1) echo "ours, drop-in \`ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom))\`, 1 thread" ;;
		drop2) echo "ours, drop-in, 2 threads" ;;
		unc1) echo "ours, unconstrained \`ST_TDCDelaunay(geom)\`, 1 thread" ;;
		unc2) echo "ours, unconstrained, 2 threads" ;;
		uncdef) echo "ours, unconstrained, default settings" ;;
		sfcgal) echo "SFCGAL \`ST_ConstrainedDelaunayTriangles(ST_Collect(geom))\`" ;;
	esac
}
# the unconstrained statement of the same thread count and plan
unc_of() {
	case $1 in
		agg1 | drop1) echo unc1 ;;
		agg2 | drop2) echo unc2 ;;
		aggdef) echo uncdef ;;
	esac
}

# ---------------------------------------------------------------- timing
SO=$(pg_config --pkglibdir 2>/dev/null)/tdc_delaunay.so
SET_SQL=""
for kvp in $SETTINGS; do
	case $kvp in *=*) ;; *) die "BENCH_CDT_SETTINGS: '$kvp' is not name=value" ;; esac
	SET_SQL+="SET ${kvp%%=*} = '${kvp#*=}';"$'\n'
done
SO_START=$(so_id)
bench_begin server
echo "dataset,statement,form,rep,ms,result,status,message,plan" > "$RUNS"

run_dataset() {
	local d=$1 st name set expr form q rep line ms res stt msg
	{
		echo "SET statement_timeout = '${TIMEOUT}s';"
		printf '%s' "$SET_SQL"
		for st in "${STMTS[@]}"; do
			IFS='|' read -r name set expr <<< "$st"
			q="SELECT $(form_sql pcs "$expr") FROM $S.$d"
			echo "SELECT 'plan', '$name', $S.plan_of(\$bq\$$q\$bq\$, '$set');"
		done
		for rep in $(seq $((1 - WARM)) "$REPS"); do
			for form in "${FORMS[@]}"; do
				for st in "${STMTS[@]}"; do
					IFS='|' read -r name set expr <<< "$st"
					q="SELECT $(form_sql "$form" "$expr") FROM $S.$d"
					echo "SELECT 'run', '$form', * FROM $S.time_query('${name}_$form', $rep, \$bq\$$q\$bq\$, '$set');"
				done
			done
		done
	} > "$WORK/$d.sql"
	log "$d: ${#STMTS[@]} statements x ${#FORMS[@]} forms x ($WARM + $REPS)"
	psql -X -q -A -t -F '|' -f "$WORK/$d.sql" > "$WORK/$d.out" 2> "$WORK/$d.err" || true
	if grep -q . "$WORK/$d.err"; then
		log "  psql said: $(head -3 "$WORK/$d.err" | tr '\n' ' ')"
	fi
	declare -A PLAN=()
	while IFS='|' read -r tag name plan; do
		[ "$tag" = plan ] && PLAN[$name]=$plan
	done < "$WORK/$d.out"
	for rep in $(seq $((1 - WARM)) "$REPS"); do
		for form in "${FORMS[@]}"; do
			for st in "${STMTS[@]}"; do
				IFS='|' read -r name set expr <<< "$st"
				line=$(awk -F'|' -v s="${name}_$form" -v r="$rep" '$1 == "run" && $3 == s && $4 == r' "$WORK/$d.out")
				if [ -n "$line" ]; then
					IFS='|' read -r _ _ _ _ ms res stt msg <<< "$line"
					[ "$stt" = ok ] || [ "$stt" = skipped ] || log "  $name $form: $stt after $(fmt_ms "$ms"): $msg"
				else
					ms=""; res=""; stt=error
					msg=$(grep -m1 -E 'FATAL|ERROR|server closed|connection' "$WORK/$d.err" | sed 's/,/;/g' || true)
					[ -n "$msg" ] || msg="no output from psql"
				fi
				echo "$d,$name,$form,$rep,$ms,$res,$stt,$msg,${PLAN[$name]:-}" >> "$RUNS"
			done
		done
	done
}

for d in $DATASETS; do
	run_dataset "$d"
done
bench_end
SO_END=$(so_id)
[ "$SO_START" = "$SO_END" ] || log "WARNING: $SO changed during the run ($SO_START -> $SO_END)"

# ---------------------------------------------------------------- summary
# vals D NAME FORM: the ms of the timed successful runs
vals() { awk -F, -v d="$1" -v s="$2" -v f="$3" 'NR > 1 && $1 == d && $2 == s && $3 == f && $4 >= 1 && $7 == "ok" { print $5 }' "$RUNS"; }
result_of() { awk -F, -v d="$1" -v s="$2" -v f="$3" 'NR > 1 && $1 == d && $2 == s && $3 == f && $7 == "ok" { print $6; exit }' "$RUNS"; }
failure_of() { awk -F, -v d="$1" -v s="$2" 'NR > 1 && $1 == d && $2 == s && ($7 == "error" || $7 == "timeout") { print $3 " " $7 ": " $8; exit }' "$RUNS"; }
plan_of() { awk -F, -v d="$1" -v s="$2" 'NR > 1 && $1 == d && $2 == s { print $9; exit }' "$RUNS"; }
ratio() { [ -n "$1" ] && [ -n "$2" ] && awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3g", a / b }' || true; }

PG_VER=$(sql -c "SELECT split_part(version(), ' on ', 1)")
PGIS_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'")
SFCGAL_VER=$([ "$HAVE_SFCGAL" = 1 ] && sql -c "SELECT postgis_sfcgal_full_version()" 2>/dev/null || echo "not installed")
TDC_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")
THREADS_DEF=$(sql -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)') IS NOT NULL" -c "SELECT reset_val FROM pg_settings WHERE name = 'tdc_delaunay.threads'" | tail -1)
MPWG_DEF=$(sql -c "SELECT reset_val FROM pg_settings WHERE name = 'max_parallel_workers_per_gather'")

echo "dataset,statement,settings,plan,pcs_median_ms,ng_median_ms,pcs_runs,ng_runs,pcs_min_ms,pcs_max_ms,ng_min_ms,ng_max_ms,bytes,triangles,sfcgal_over_this_pcs,sfcgal_over_this_ng,this_over_unconstrained_pcs,this_over_unconstrained_ng,triangles_as_sfcgal,failure" > "$CSV"
{
	echo "- server: $PG_VER, PostGIS $PGIS_VER, $SFCGAL_VER, tdc_delaunay $TDC_VER (git $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?')$(git -C "$ROOT" diff --quiet HEAD -- src bench 2>/dev/null || echo ', with uncommitted changes in src/ or bench/'); $SO: $SO_START)"
	if [ "$SO_START" != "$SO_END" ]; then
		echo "- **WARNING: tdc_delaunay.so was replaced during the run ($SO_START -> $SO_END): the figures mix two builds; run again.**"
	fi
	echo "- settings: jit and the rest as the server's${SETTINGS:+, except (set for the runs) $SETTINGS}; serial rows: max_parallel_workers_per_gather = 0 and tdc_delaunay.threads = 1 or 2; default rows: the server's tdc_delaunay.threads ($THREADS_DEF) and max_parallel_workers_per_gather ($MPWG_DEF); statement_timeout ${TIMEOUT}s"
	echo "- timing: server side (clock_timestamp() around EXECUTE in plpgsql), one session per data set, every statement once untimed ($WARM), then $REPS rounds of all statements in turn; medians. pcs = \`pg_column_size(f)\`, the value built; ng = \`ST_NumGeometries(f)\`, the value built and taken apart again by PostGIS"
} > "$TXT"

for d in $DATASETS; do
	declare -A PCS=() NG=() TRI=()
	for st in "${STMTS[@]}"; do
		IFS='|' read -r name set expr <<< "$st"
		PCS[$name]=$(vals "$d" "$name" pcs | median)
		NG[$name]=$(vals "$d" "$name" ng | median)
		TRI[$name]=$(result_of "$d" "$name" ng)
	done
	{
		echo
		echo "#### $d: $(describe "$d")"
		echo
		echo "| statement | plan | pcs | ng | SFCGAL / this (pcs, ng) | this / unconstrained (pcs, ng) | triangles |"
		echo "|---|---|--:|--:|--:|--:|--:|"
	} >> "$TXT"
	for st in "${STMTS[@]}"; do
		IFS='|' read -r name set expr <<< "$st"
		u=$(unc_of "$name")
		rs_p=""; rs_n=""; ru_p=""; ru_n=""; same=""
		if [ -n "$u" ] && [ "$HAVE_SFCGAL" = 1 ]; then
			rs_p=$(ratio "${PCS[sfcgal]}" "${PCS[$name]}")
			rs_n=$(ratio "${NG[sfcgal]}" "${NG[$name]}")
			if [ -n "${TRI[$name]}" ] && [ -n "${TRI[sfcgal]}" ]; then
				[ "${TRI[$name]}" = "${TRI[sfcgal]}" ] && same=yes || same=no
			fi
		fi
		if [ -n "$u" ]; then
			ru_p=$(ratio "${PCS[$name]}" "${PCS[$u]}")
			ru_n=$(ratio "${NG[$name]}" "${NG[$u]}")
		fi
		fail=$(failure_of "$d" "$name")
		pcsv=$(vals "$d" "$name" pcs | sort -g)
		ngv=$(vals "$d" "$name" ng | sort -g)
		echo "$d,$name,$set,$(plan_of "$d" "$name"),${PCS[$name]},${NG[$name]},$(grep -c . <<< "$pcsv" || true),$(grep -c . <<< "$ngv" || true),$(head -1 <<< "$pcsv"),$(tail -1 <<< "$pcsv"),$(head -1 <<< "$ngv"),$(tail -1 <<< "$ngv"),$(result_of "$d" "$name" pcs),${TRI[$name]},$rs_p,$rs_n,$ru_p,$ru_n,$same,$fail" >> "$CSV"
		cell_r() { [ -n "$1$2" ] && echo "${1:--}× / ${2:--}×" || echo ""; }
		tri=${TRI[$name]:+$(thousands "${TRI[$name]}")}
		[ "$same" = no ] && tri="$tri (**SFCGAL: $(thousands "${TRI[sfcgal]}")**)"
		printf '| %s | %s | %s | %s | %s | %s | %s |\n' "$(label "$name")" "$(plan_of "$d" "$name")" \
			"$(fmt_ms "${PCS[$name]}")" "$(fmt_ms "${NG[$name]}")" "$(cell_r "$rs_p" "$rs_n")" \
			"$(cell_r "$ru_p" "$ru_n")" "${tri:-${fail:+failed: $fail}}" >> "$TXT"
	done
	if [ "$HAVE_SFCGAL" = 1 ] && [ -n "${TRI[sfcgal]}" ]; then
		n_same=0; n_tdc=0
		for name in agg1 agg2 aggdef drop1 drop2; do
			[ -n "${TRI[$name]}" ] || continue
			n_tdc=$((n_tdc + 1))
			[ "${TRI[$name]}" = "${TRI[sfcgal]}" ] && n_same=$((n_same + 1))
		done
		echo >> "$TXT"
		echo "Triangle counts: $n_same of $n_tdc constrained statements of ours give SFCGAL's $(thousands "${TRI[sfcgal]}")." >> "$TXT"
	fi
	unset PCS NG TRI
done

bench_publish constrained "Constrained Delaunay in SQL: tdc_delaunay against SFCGAL" "$TXT"
cat "$TXT"
log "wrote $RUNS, $CSV, $TXT"
