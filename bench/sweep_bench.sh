#!/usr/bin/env bash
# bench/sweep_bench.sh -- size sweep in SQL: tdc_delaunay against PostGIS
# ST_DelaunayTriangles (GEOS), from 3 points per call to 10 million, in the
# same run (issue 12).  It prints figures; it asserts nothing.
#
# Server: the usual libpq variables (PGHOST, PGPORT, PGUSER, PGDATABASE); the
# extensions postgis and tdc_delaunay are created if missing (tdc_delaunay
# must be installed: make install).  Tables live in schema "bench_sweep" and
# are kept between runs (BENCH_SWEEP_RELOAD=1 rebuilds them).
#
# Data: uniform points in [0,1)^2 from a fixed formula, point i being
#   x = (hashint8extended(i, 1) & (2^52 - 1)) / 2^52,  y = the same with seed 2
# (PostgreSQL's hash functions are stable: hash partitioning depends on it),
# so every table is a pure function of its sizes.
#
# Workloads (PostGIS statement first, then ours):
#   row    a table of R rows, each one MULTIPOINT of k points:
#            SELECT count(ST_DelaunayTriangles(g)) FROM t
#            SELECT count(ST_TDCDelaunayTriangles(g)) FROM t
#          k:R = 3:10000 5:10000 10:10000 20:10000 100:2000 1000:200 1e4:20
#                1e5:3 1e6:1 (and 5e6:1 with BENCH_SWEEP_BIG=1)
#   group  a table of G*k points with a group key, G groups of k points:
#            SELECT count(d) FROM (SELECT ST_DelaunayTriangles(ST_Collect(geom)) d FROM t GROUP BY grp) s
#            SELECT count(d) FROM (SELECT ST_TDCDelaunay(geom) d FROM t GROUP BY grp) s
#          k:G = 3:1000 10:1000 30:1000 100:1000 1000:100 1e4:10
#   agg    one aggregate over a whole table of n points:
#            SELECT ST_DelaunayTriangles(ST_Collect(geom)) IS NOT NULL FROM t
#            SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM t
#          n = 3 10 100 1e3 1e4 1e5 1e6 1e7 (PostGIS at 1e7 only with
#          BENCH_SWEEP_PG_10M=1), plus "agg_ng": the ST_NumGeometries(...)
#          form of both at 1e6 (or at the largest n run, if smaller)
#
# BENCH_SWEEP_SOURCE=patch sweeps the pcpatch aggregates instead (issue 40):
# the same points, z = 0, as pgpointcloud patches (PC_Patch of PC_MakePoint,
# schema of double X, Y, Z, uncompressed; patches of at most 400 points, a
# row's one patch of k), against what a user of pgpointcloud has without
# them: PC_Explode each patch, PC_Get its point, ST_MakePoint, into the
# geometry aggregate (PostGIS's ST_DelaunayTriangles is slower than it on
# the same points, the geometry sweep shows).  Workloads ("explode" first):
#   row    SELECT count(d) FROM (SELECT ST_TDCDelaunay(ST_MakePoint(v[1], v[2], v[3])) d
#            FROM (SELECT id, PC_Get(pt) v FROM t, PC_Explode(t.pa) pt) e GROUP BY id) s
#          SELECT count(d) FROM (SELECT ST_TDCDelaunay(pa) d FROM t GROUP BY id) s
#   group  the same grouped by grp, k points a group in patches of at most 400
#   agg    SELECT ST_TDCDelaunay(ST_MakePoint(...)) IS NOT NULL FROM (SELECT PC_Get(pt) v ...) e
#          SELECT ST_TDCDelaunay(pa) IS NOT NULL FROM t
#          (and agg_ng: ST_NumGeometries of both)
# The outputs are named sweep_patch* instead of sweep*; the extensions
# pointcloud and tdc_delaunay_pointcloud are created if missing.
#
# Timing: server side, clock_timestamp() around EXECUTE in a plpgsql function.
# Each cell (workload, size) runs in one psql session: the session settings,
# then each statement once untimed (warm-up: shared libraries, caches;
# BENCH_SWEEP_WARM), then
# BENCH_SWEEP_REPS repetitions interleaved PostGIS, ours, PostGIS, ours, ...
# so that the load on the machine affects both; medians reported.  A
# statement that fails (error, or statement_timeout = BENCH_SWEEP_TIMEOUT s)
# is recorded with its message and elapsed time and not run again in that cell.
#
# Outputs: build/bench/sweep_runs.csv  every run (rep <= 0: warm-up)
#          build/bench/sweep.csv       medians, PostGIS/ours ratio, time per call
#          build/bench/sweep.txt       header + Markdown table (for the README)
#          build/bench/sweep.png       log-log time per call vs points per call, and the ratio
#          docs/benchmarks/sweep.md    the report: bench_publish's header + that table and
#                                      the figure, copied beside it, if the machine was
#                                      quiet (bench/quiet.sh); quick mode writes no report
# Knobs:   BENCH_SWEEP_REPS=5  BENCH_SWEEP_WORKLOADS="row group agg"
#          BENCH_SWEEP_MAX_N (skip cells with more points per call; e.g. 1e5)
#          BENCH_SWEEP_QUICK=1 (3 reps, at most 1e3 points per call: to try it out)
#          BENCH_SWEEP_BIG=1 (row 5e6)  BENCH_SWEEP_PG_10M=1 (PostGIS agg 1e7)
#          BENCH_SWEEP_TIMEOUT=600 (s per statement)  BENCH_SWEEP_RELOAD=1
#          BENCH_SWEEP_WARM=1 (untimed runs of each statement per cell, before the timed ones)
#          BENCH_SWEEP_SETTINGS="jit=off" (session settings, name=value ...; see below)
#          BENCH_SWEEP_ROW_SIZES, BENCH_SWEEP_GROUP_SIZES ("k:count ..."),
#          BENCH_SWEEP_AGG_SIZES ("n ...") replace the lists above
#          BENCH_SWEEP_PNG=FILE (where the figure is drawn)  BENCH_SWEEP_PLOT_ONLY=1 (redraw it from the CSVs)
#
# jit=off by default: ST_DelaunayTriangles is declared COST 10000, ours less
# (the header prints both), so with the server's jit=on the PostGIS statements
# over 10,000 rows (and not ours) pass jit_above_cost and pay for JIT
# compilation in every run; that would measure the planner's cost constants,
# not the triangulations.  BENCH_SWEEP_SETTINGS="" keeps the server's settings.
# The plan of every statement (parallel workers, JIT) is recorded.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

QUICK=${BENCH_SWEEP_QUICK:-0}
if [ "$QUICK" = 1 ]; then
	REPS=${BENCH_SWEEP_REPS:-3}
	MAX_N=$(n_of "${BENCH_SWEEP_MAX_N:-1e3}")
else
	REPS=${BENCH_SWEEP_REPS:-5}
	MAX_N=$(n_of "${BENCH_SWEEP_MAX_N:-1e12}")
fi
WORKLOADS=${BENCH_SWEEP_WORKLOADS:-"row group agg"}
WARM=${BENCH_SWEEP_WARM:-1}
BIG=${BENCH_SWEEP_BIG:-0}
PG_10M=${BENCH_SWEEP_PG_10M:-0}
TIMEOUT=${BENCH_SWEEP_TIMEOUT:-600}
RELOAD=${BENCH_SWEEP_RELOAD:-0}
SETTINGS=${BENCH_SWEEP_SETTINGS-"jit=off"}
ROW_SIZES=${BENCH_SWEEP_ROW_SIZES:-"3:10000 5:10000 10:10000 20:10000 100:2000 1000:200 1e4:20 1e5:3 1e6:1"}
[ "$BIG" = 1 ] && [ -z "${BENCH_SWEEP_ROW_SIZES:-}" ] && ROW_SIZES="$ROW_SIZES 5e6:1"
GROUP_SIZES=${BENCH_SWEEP_GROUP_SIZES:-"3:1000 10:1000 30:1000 100:1000 1000:100 1e4:10"}
AGG_SIZES=${BENCH_SWEEP_AGG_SIZES:-"3 10 100 1e3 1e4 1e5 1e6 1e7"}
PNG=${BENCH_SWEEP_PNG:-$BENCH_OUT/sweep.png}
S=bench_sweep
SRC=${BENCH_SWEEP_SOURCE:-geom}
# what the report calls the two systems (pg: the statement a user has without
# the feature; tdc: ours), the outputs' name, and the patches' format
case $SRC in
	geom) NAME=sweep; A_NAME=PostGIS; B_NAME=tdc_delaunay ;;
	patch) NAME=sweep_patch; A_NAME=PC_Explode; B_NAME="pcpatch aggregate"; PCID=4711
		[ -n "${BENCH_SWEEP_PNG:-}" ] || PNG=$BENCH_OUT/sweep_patch.png
		# one value of 2 triangles a point: past some 5e6 points over 1 GB
		[ -n "${BENCH_SWEEP_AGG_SIZES:-}" ] || AGG_SIZES="3 10 100 1e3 1e4 1e5 1e6" ;;
	*) die "BENCH_SWEEP_SOURCE: '$SRC' is not geom or patch" ;;
esac
# the most points in one patch of a group's or an aggregate's table
PATCH=400
# the names in gnuplot's enhanced text
GA=${A_NAME//_/\\_}
GB=${B_NAME//_/\\_}

mkdir -p "$BENCH_OUT" "$(dirname "$PNG")"
RUNS=$BENCH_OUT/${NAME}_runs.csv
CSV=$BENCH_OUT/$NAME.csv
TXT=$BENCH_OUT/$NAME.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT


command -v psql >/dev/null || die "psql not found"
command -v gnuplot >/dev/null || ensure_debs gnuplot-nox

# ---------------------------------------------------------------- formatting

# ---------------------------------------------------------------- plot
# make_plot: $PNG from sweep.csv (+ the failures in sweep_runs.csv)
make_plot() {
	rm -f "$PNG"
	log "plotting $PNG"
	local w sys col
	for w in row group agg; do
		for sys in pg tdc; do
			[ $sys = pg ] && col=5 || col=6
			# points per call, seconds per call
			awk -F, -v w="$w" -v c="$col" 'NR > 1 && $1 == w && $c != "" { print $4, $c / $3 / 1000 }' "$CSV" > "$WORK/$w.$sys.dat"
			# failures: elapsed time of the failed run (per call)
			awk -F, -v w="$w" -v s="$sys" 'NR > 1 && $1 == w && $5 == s && ($9 == "error" || $9 == "timeout") { print $4, $7 / $3 / 1000 }' "$RUNS" > "$WORK/$w.$sys.fail"
		done
		awk -F, -v w="$w" 'NR > 1 && $1 == w && $7 != "" { print $4, $7 }' "$CSV" > "$WORK/$w.ratio.dat"
	done
	local t=() r=() pt dt wl
	# add FILE ARRAY STYLE: append a plot clause for FILE when it has data
	add() {
		local -n arr=$2
		if [ -s "$1" ]; then arr+=("'$1' using 1:2 $3"); fi
	}
	for w in row group agg; do
		case $w in
			row) pt=7; dt=1; wl="per row (MULTIPOINT)"; [ "$SRC" = patch ] && wl="per row (one patch)" ;;
			group) pt=5; dt=2; wl="per group (GROUP BY)" ;;
			agg) pt=9; dt=3; wl="one aggregate" ;;
		esac
		add "$WORK/$w.pg.dat" t "with linespoints lw 2 dt $dt pt $pt lc rgb '#d62728' title '$GA, $wl'"
		add "$WORK/$w.tdc.dat" t "with linespoints lw 2 dt $dt pt $pt lc rgb '#1f77b4' title '$GB, $wl'"
		add "$WORK/$w.pg.fail" t "with points pt 2 ps 2.5 lw 2 lc rgb '#d62728' title '$GA $wl: failed after'"
		add "$WORK/$w.tdc.fail" t "with points pt 2 ps 2.5 lw 2 lc rgb '#1f77b4' title '$GB $wl: failed after'"
		add "$WORK/$w.ratio.dat" r "with linespoints lw 2 dt $dt pt $pt lc rgb '#2ca02c' title '$wl'"
	done
	if [ ${#t[@]} -eq 0 ]; then
		log "nothing to plot"
		return 0
	fi
	local title
	title="Delaunay in PostgreSQL: tdc\\_delaunay vs PostGIS ${PGIS_VER:-} (GEOS ${GEOS_VER:-}), $(nproc) CPUs"
	[ "$SRC" = patch ] && title="Delaunay of pgpointcloud patches: the pcpatch aggregate vs PC\\_Explode into the geometry one, $(nproc) CPUs"
	{
		echo "set terminal pngcairo size 1400,620 font 'DejaVu Sans,11'"
		echo "set output '$PNG'"
		echo "set multiplot layout 1,2 title '$title'"
		echo "set logscale xy"
		echo "set format x '10^{%L}'"
		echo "set format y '10^{%L}'"
		echo "set xlabel 'points per call (k or n)'"
		echo "set ylabel 'seconds per call (per row, group or aggregate; server side, median)'"
		echo "set grid"
		echo "set key top left font ',9'"
		echo "set title 'time per call'"
		printf 'plot '
		(IFS=,; echo "${t[*]}")
		echo "unset logscale y"
		echo "set logscale y 2"
		echo "set format y '%g'"
		echo "set ylabel '$GA time / $GB time'"
		echo "set title 'speed-up ($GA / $GB); 1 = same'"
		echo "set key top left font ',9'"
		if [ ${#r[@]} -gt 0 ]; then
			printf 'plot 1 with lines lc rgb "#888888" dt 4 notitle, '
			(IFS=,; echo "${r[*]}")
		fi
		echo "unset multiplot"
	} > "$WORK/sweep.gp"
	gnuplot "$WORK/sweep.gp" || log "gnuplot failed"
}

server_versions() {
	PG_VER=$(sql -c "SELECT split_part(version(), ' on ', 1)")
	PGIS_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'")
	GEOS_VER=$(sql -c "SELECT split_part(postgis_geos_version(), '-', 1)")
	TDC_VER=$(sql -c "SELECT coalesce((SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'), 'absent')")
}

if [ "${BENCH_SWEEP_PLOT_ONLY:-0}" = 1 ]; then
	{ [ -s "$CSV" ] && [ -s "$RUNS" ]; } || die "no $CSV / $RUNS to plot"
	server_versions 2>/dev/null || true
	make_plot
	exit 0
fi

sql -c 'SELECT 1' >/dev/null 2>&1 ||
	die "no PostgreSQL server reachable with PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} PGUSER=${PGUSER:-} PGDATABASE=${PGDATABASE:-}"
sql -c "CREATE EXTENSION IF NOT EXISTS postgis" >/dev/null
sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay" >/dev/null 2> "$WORK/err" ||
	die "tdc_delaunay extension not available ($(head -1 "$WORK/err")): make install first"
if [ "$SRC" = patch ]; then
	sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay_pointcloud CASCADE" >/dev/null 2> "$WORK/err" ||
		die "tdc_delaunay_pointcloud not available ($(head -1 "$WORK/err")): pgpointcloud and make install first"
	# the patches' format: double X, Y, Z, uncompressed
	dims=""
	for c in X Y Z; do
		dims+="<pc:dimension><pc:position>$(( $(printf '%d' "'$c") - 87 ))</pc:position><pc:size>8</pc:size>"
		dims+="<pc:description>$c</pc:description><pc:name>$c</pc:name><pc:interpretation>double</pc:interpretation>"
		dims+="<pc:active>true</pc:active></pc:dimension>"
	done
	sql -c "DELETE FROM pointcloud_formats WHERE pcid = $PCID" \
		-c "INSERT INTO pointcloud_formats (pcid, srid, schema) VALUES ($PCID, 0, '<?xml version=\"1.0\" encoding=\"UTF-8\"?><pc:PointCloudSchema xmlns:pc=\"http://pointcloud.org/schemas/PC/1.1\" xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\">$dims<pc:metadata><Metadata name=\"compression\">none</Metadata></pc:metadata></pc:PointCloudSchema>')" >/dev/null
fi
server_versions

# SET lines for the session settings (BENCH_SWEEP_SETTINGS)
SET_SQL=""
for kvp in $SETTINGS; do
	case $kvp in *=*) ;; *) die "BENCH_SWEEP_SETTINGS: '$kvp' is not name=value" ;; esac
	SET_SQL+="SET ${kvp%%=*} = '${kvp#*=}';"$'\n'
done

bench_sql_helpers "$S" | sql >/dev/null

# ---------------------------------------------------------------- cells
# CELLS: "workload k calls" in run order, k = points per call
CELLS=()
for w in $WORKLOADS; do
	case $w in
		row)
			for kc in $ROW_SIZES; do
				k=$(n_of "${kc%%:*}")
				[ "$k" -le "$MAX_N" ] && CELLS+=("row $k $(n_of "${kc#*:}")")
			done
			;;
		group)
			for kc in $GROUP_SIZES; do
				k=$(n_of "${kc%%:*}")
				[ "$k" -le "$MAX_N" ] && CELLS+=("group $k $(n_of "${kc#*:}")")
			done
			;;
		agg)
			ng=""
			for nl in $AGG_SIZES; do
				n=$(n_of "$nl")
				[ "$n" -le "$MAX_N" ] || continue
				CELLS+=("agg $n 1")
				[ "$n" -le 1000000 ] && ng=$n
			done
			[ -n "$ng" ] && CELLS+=("agg_ng $ng 1")
			;;
		*) die "unknown workload '$w' (row group agg)" ;;
	esac
done
[ ${#CELLS[@]} -gt 0 ] || die "no cells to run (BENCH_SWEEP_WORKLOADS=$WORKLOADS, BENCH_SWEEP_MAX_N=$MAX_N)"

# table_of WORKLOAD K CALLS: the cell's table (agg_ng shares agg's)
table_of() {
	local p=""
	[ "$SRC" = patch ] && p=pc_
	case $1 in
		row) echo "$S.${p}row_k$2_r$3" ;;
		group) echo "$S.${p}grp_k$2_g$3" ;;
		agg | agg_ng) echo "$S.${p}agg_n$2" ;;
	esac
}

# ensure_table WORKLOAD K CALLS: create the table unless an identical one exists.
# The table's comment records how it was made; any difference rebuilds it.
ensure_table() {
	local w=$1 k=$2 c=$3 t spec body
	[ "$w" = agg_ng ] && w=agg
	t=$(table_of "$w" "$k" "$c")
	spec="sweep v1: $w k=$k calls=$c, points $S.pt(0 .. $((k * c - 1)))"
	[ "$SRC" = patch ] && spec="$spec as pcpatch($PCID) of at most $PATCH (a row: k) points"
	if [ "$RELOAD" = 0 ] && [ "$(sql -c "SELECT obj_description(to_regclass('$t'), 'pg_class')")" = "$spec" ]; then
		return 0
	fi
	case $w in
		row)
			# row r: points r*k .. r*k+k-1, one MULTIPOINT
			body="SELECT (i / $k)::int AS id, ST_Collect($S.pt(i) ORDER BY i) AS g
				FROM generate_series(0::bigint, $((k * c - 1))) i GROUP BY 1 ORDER BY 1" ;;
		group)
			body="SELECT (i / $k)::int AS grp, $S.pt(i) AS geom
				FROM generate_series(0::bigint, $((k * c - 1))) i ORDER BY i" ;;
		agg)
			body="SELECT $S.pt(i) AS geom FROM generate_series(0::bigint, $((k - 1))) i ORDER BY i" ;;
	esac
	if [ "$SRC" = patch ]; then
		# the same points, z = 0, in patches: a row's k, else at most PATCH
		local per=$k key="(i / $k)::int"
		[ "$w" = row ] || per=$((k < PATCH ? k : PATCH))
		[ "$w" = agg ] && key="0"
		body="SELECT ($([ "$w" = row ] && echo "i / $k" || echo "i / $per"))::int AS id, $key AS grp,
				PC_Patch(PC_MakePoint($PCID, ARRAY[ST_X(p), ST_Y(p), 0]) ORDER BY i) AS pa
			FROM generate_series(0::bigint, $((k * c - 1))) i, $S.pt(i) p GROUP BY 1, 2 ORDER BY 1"
	fi
	log "creating $t ($c x $k points)"
	sql <<EOF >/dev/null
SET statement_timeout = 0;
DROP TABLE IF EXISTS $t;
CREATE TABLE $t AS $body;
COMMENT ON TABLE $t IS '$spec';
VACUUM (ANALYZE) $t;
EOF
}

# queries WORKLOAD TABLE: sets QPG and QTDC
queries() {
	local ex="(SELECT t.id, t.grp, PC_Get(pt) v FROM $2 t, PC_Explode(t.pa) pt) e" mk="ST_MakePoint(v[1], v[2], v[3])"
	if [ "$SRC" = patch ]; then
		case $1 in
			row)
				QPG="SELECT count(d) FROM (SELECT ST_TDCDelaunay($mk) d FROM $ex GROUP BY id) s"
				QTDC="SELECT count(d) FROM (SELECT ST_TDCDelaunay(pa) d FROM $2 GROUP BY id) s" ;;
			group)
				QPG="SELECT count(d) FROM (SELECT ST_TDCDelaunay($mk) d FROM $ex GROUP BY grp) s"
				QTDC="SELECT count(d) FROM (SELECT ST_TDCDelaunay(pa) d FROM $2 GROUP BY grp) s" ;;
			agg)
				QPG="SELECT ST_TDCDelaunay($mk) IS NOT NULL FROM $ex"
				QTDC="SELECT ST_TDCDelaunay(pa) IS NOT NULL FROM $2" ;;
			agg_ng)
				QPG="SELECT ST_NumGeometries(ST_TDCDelaunay($mk)) FROM $ex"
				QTDC="SELECT ST_NumGeometries(ST_TDCDelaunay(pa)) FROM $2" ;;
		esac
		return 0
	fi
	case $1 in
		row)
			QPG="SELECT count(ST_DelaunayTriangles(g)) FROM $2"
			QTDC="SELECT count(ST_TDCDelaunayTriangles(g)) FROM $2" ;;
		group)
			QPG="SELECT count(d) FROM (SELECT ST_DelaunayTriangles(ST_Collect(geom)) d FROM $2 GROUP BY grp) s"
			QTDC="SELECT count(d) FROM (SELECT ST_TDCDelaunay(geom) d FROM $2 GROUP BY grp) s" ;;
		agg)
			QPG="SELECT ST_DelaunayTriangles(ST_Collect(geom)) IS NOT NULL FROM $2"
			QTDC="SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM $2" ;;
		agg_ng)
			QPG="SELECT ST_NumGeometries(ST_DelaunayTriangles(ST_Collect(geom))) FROM $2"
			QTDC="SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM $2" ;;
	esac
}

for cell in "${CELLS[@]}"; do
	# shellcheck disable=SC2086
	ensure_table $cell
done

# ---------------------------------------------------------------- timing
# so_id: md5 and mtime of the installed tdc_delaunay.so (if this server uses
# pg_config's pkglibdir).  Every cell is a new session that loads the file
# afresh, so a make install during the run would mix two builds in the table.
SO=$(pg_config --pkglibdir 2>/dev/null)/tdc_delaunay.so
SO_START=$(so_id)
if [ "$QUICK" = 1 ]; then bench_begin server noreport; else bench_begin server; fi
echo "workload,k,calls,points,system,rep,ms,result,status,message,plan" > "$RUNS"

# run_cell WORKLOAD K CALLS: one psql session, warm-up then REPS interleaved runs
run_cell() {
	local w=$1 k=$2 c=$3 t systems=() sys rep line ms res st msg
	t=$(table_of "$w" "$k" "$c")
	queries "$w" "$t"
	systems=(pg tdc)
	if [ "$SRC" = geom ] && [ "$w" = agg ] && [ "$k" -gt 1000000 ] && [ "$PG_10M" != 1 ]; then
		systems=(tdc)	# PostGIS past 1e6 points in one aggregate only on request
	fi
	declare -A Q=([pg]=$QPG [tdc]=$QTDC)
	{
		echo "SET statement_timeout = '${TIMEOUT}s';"
		printf '%s' "$SET_SQL"
		for sys in "${systems[@]}"; do
			echo "SELECT 'plan', '$sys', $S.plan_of(\$bq\$${Q[$sys]}\$bq\$);"
		done
		for rep in $(seq $((1 - WARM)) "$REPS"); do
			for sys in "${systems[@]}"; do
				echo "SELECT 'run', * FROM $S.time_query('$sys', $rep, \$bq\$${Q[$sys]}\$bq\$);"
			done
		done
	} > "$WORK/cell.sql"
	log "$w k=$k calls=$c: ${systems[*]} x ($WARM + $REPS)"
	# no ON_ERROR_STOP: time_query never raises; a crash ends the session,
	# and the runs it did not report are recorded as errors below
	psql -X -q -A -t -F '|' -f "$WORK/cell.sql" > "$WORK/cell.out" 2> "$WORK/cell.err" || true
	if grep -q . "$WORK/cell.err"; then
		log "  psql said: $(head -3 "$WORK/cell.err" | tr '\n' ' ')"
	fi
	declare -A PLAN=()
	while IFS='|' read -r tag sys plan; do
		[ "$tag" = plan ] && PLAN[$sys]=$plan
	done < "$WORK/cell.out"
	for rep in $(seq $((1 - WARM)) "$REPS"); do
		for sys in "${systems[@]}"; do
			line=$(awk -F'|' -v s="$sys" -v r="$rep" '$1 == "run" && $2 == s && $3 == r' "$WORK/cell.out")
			if [ -n "$line" ]; then
				IFS='|' read -r _ _ _ ms res st msg <<< "$line"
				[ "$st" = ok ] || [ "$st" = skipped ] || log "  $sys: $st after $(fmt_ms "$ms"): $msg"
			else
				ms=""; res=""; st=error
				msg=$(grep -m1 -E 'FATAL|ERROR|server closed|connection' "$WORK/cell.err" | sed 's/,/;/g' || true)
				[ -n "$msg" ] || msg="no output from psql"
			fi
			echo "$w,$k,$c,$k,$sys,$rep,$ms,$res,$st,$msg,${PLAN[$sys]:-}" >> "$RUNS"
		done
	done
}

for cell in "${CELLS[@]}"; do
	# shellcheck disable=SC2086
	run_cell $cell
done
bench_end
SO_END=$(so_id)
[ "$SO_START" = "$SO_END" ] || log "WARNING: $SO changed during the run ($SO_START -> $SO_END)"

# ---------------------------------------------------------------- summary
# vals W K SYS: the ms of the timed (rep >= 1) successful runs
vals() { awk -F, -v w="$1" -v k="$2" -v s="$3" 'NR > 1 && $1 == w && $2 == k && $5 == s && $6 >= 1 && $9 == "ok" { print $7 }' "$RUNS"; }
# first W K SYS FIELD: FIELD of the first row matching (any rep)
first() { awk -F, -v w="$1" -v k="$2" -v s="$3" -v f="$4" 'NR > 1 && $1 == w && $2 == k && $5 == s { print $f; exit }' "$RUNS"; }
# failure W K SYS: "status|ms|message" of the first failed run
failure() {
	awk -F, -v w="$1" -v k="$2" -v s="$3" 'NR > 1 && $1 == w && $2 == k && $5 == s && ($9 == "error" || $9 == "timeout") { print $9 "|" $7 "|" $10; exit }' "$RUNS"
}
# status W K SYS: ok | timeout | error | not run
status() {
	local f
	f=$(failure "$@")
	if [ -n "$f" ]; then echo "${f%%|*}"
	elif [ -n "$(first "$@" 9)" ]; then echo ok
	else echo "not run"; fi
}

echo "workload,k,calls,points,pg_median_ms,tdc_median_ms,ratio_pg_over_tdc,pg_per_call_ms,tdc_per_call_ms,pg_runs,tdc_runs,pg_min_ms,pg_max_ms,tdc_min_ms,tdc_max_ms,pg_status,tdc_status,pg_result,tdc_result,results_agree,pg_plan,tdc_plan,expected_result" > "$CSV"

wl_name() {
	case $1 in
		row) echo "per row" ;;
		group) echo "per group" ;;
		agg) echo "aggregate" ;;
		agg_ng) echo "aggregate, ST_NumGeometries" ;;
	esac
}

FIRST_TOUCH=$(first_touch_note)
THREADS=$(sql -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)') IS NOT NULL" -c "SELECT current_setting('tdc_delaunay.threads', true)" | tail -1)
setting() { sql -c "$SET_SQL" -c "SELECT current_setting('$1', true)" | tail -1; }
{
	echo "- $FIRST_TOUCH"
	echo "- server: $PG_VER, PostGIS $PGIS_VER, GEOS $GEOS_VER, tdc_delaunay $TDC_VER (git $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?'); $SO: $SO_START)"
	if [ "$SO_START" != "$SO_END" ]; then
		echo "- **WARNING: tdc_delaunay.so was replaced during the run ($SO_START -> $SO_END): the figures mix two builds; run again.**"
	fi
	echo "- function costs (pg_proc.procost): $(sql -c "SELECT string_agg(proname || ' ' || procost, ', ' ORDER BY proname) FROM pg_proc WHERE proname IN ('st_delaunaytriangles', 'st_tdcdelaunaytriangles', 'st_tdcdelaunay_finalfn')")"
	echo "- settings: shared_buffers=$(setting shared_buffers) work_mem=$(setting work_mem) jit=$(setting jit) max_parallel_workers_per_gather=$(setting max_parallel_workers_per_gather) tdc_delaunay.threads=${THREADS:-?} statement_timeout=${TIMEOUT}s${SETTINGS:+ (set for the runs: $SETTINGS)}"
	echo "- timing: server side (clock_timestamp() around EXECUTE in plpgsql), one session per cell, each statement run $WARM time(s) untimed first, then $REPS runs interleaved $A_NAME, $B_NAME, $A_NAME, ...; medians. Points uniform in [0,1)^2."
	if [ "$SRC" = patch ]; then
		echo "- patches: the points with z = 0 as pcpatch($PCID) values (PC_Patch of PC_MakePoint; double X, Y, Z, compression none), at most $PATCH points a patch (per row: one patch of k points a row); $A_NAME: \`e = (SELECT t.id, t.grp, PC_Get(pt) v FROM t, PC_Explode(t.pa) pt)\` into \`ST_TDCDelaunay(ST_MakePoint(v[1], v[2], v[3]))\`"
		echo "- per row: \`SELECT count(d) FROM (SELECT ST_TDCDelaunay(ST_MakePoint(...)) d FROM e GROUP BY id) s\` vs \`SELECT count(d) FROM (SELECT ST_TDCDelaunay(pa) d FROM t GROUP BY id) s\`"
		echo "- per group: the same with \`GROUP BY grp\`, groups of k points"
		echo "- aggregate: \`SELECT ST_TDCDelaunay(ST_MakePoint(...)) IS NOT NULL FROM e\` vs \`SELECT ST_TDCDelaunay(pa) IS NOT NULL FROM t\` over n points; \"ST_NumGeometries\": \`ST_NumGeometries(...)\` of both"
	else
		echo "- per row: \`SELECT count(ST_DelaunayTriangles(g)) FROM t\` vs \`SELECT count(ST_TDCDelaunayTriangles(g)) FROM t\`, t = rows of one MULTIPOINT of k points"
		echo "- per group: \`SELECT count(d) FROM (SELECT ST_DelaunayTriangles(ST_Collect(geom)) d FROM t GROUP BY grp) s\` vs the same with \`ST_TDCDelaunay(geom)\`, groups of k points"
		echo "- aggregate: \`SELECT ST_DelaunayTriangles(ST_Collect(geom)) IS NOT NULL FROM t\` vs \`SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM t\` over n points; \"ST_NumGeometries\": \`ST_NumGeometries(...)\` of both"
	fi
	echo
	echo "| workload | k or n | rows / groups | $A_NAME median | $B_NAME median | $A_NAME / $B_NAME | $A_NAME per call | $B_NAME per call |"
	echo "|---|--:|--:|--:|--:|--:|--:|--:|"
} > "$TXT"

NOTES=()
for cell in "${CELLS[@]}"; do
	read -r w k c <<< "$cell"
	declare -A MED=() PER=() ST=() RES=() NR=() MN=() MX=() PL=() CELLTXT=()
	for sys in pg tdc; do
		MED[$sys]=$(vals "$w" "$k" $sys | median)
		NR[$sys]=$(vals "$w" "$k" $sys | grep -c . || true)
		MN[$sys]=$(vals "$w" "$k" $sys | sort -g | head -1)
		MX[$sys]=$(vals "$w" "$k" $sys | sort -g | tail -1)
		PER[$sys]=""
		[ -n "${MED[$sys]}" ] && PER[$sys]=$(awk -v m="${MED[$sys]}" -v c="$c" 'BEGIN { printf "%.6g", m / c }')
		ST[$sys]=$(status "$w" "$k" $sys)
		RES[$sys]=$(awk -F, -v w="$w" -v k="$k" -v s="$sys" 'NR > 1 && $1 == w && $2 == k && $5 == s && $9 == "ok" { print $8; exit }' "$RUNS")
		PL[$sys]=$(first "$w" "$k" $sys 11)
		if [ -n "${MED[$sys]}" ]; then
			CELLTXT[$sys]=$(fmt_ms "${MED[$sys]}")
		elif [ "${ST[$sys]}" = "not run" ]; then
			CELLTXT[$sys]="not run"
		else
			f=$(failure "$w" "$k" $sys)
			IFS='|' read -r fst fms fmsg <<< "$f"
			CELLTXT[$sys]="$fst after $(fmt_ms "$fms")"
			NOTES+=("$(wl_name "$w") $(thousands "$k"), $([ $sys = pg ] && echo "$A_NAME" || echo "$B_NAME"): $fst after $(fmt_ms "$fms"): $fmsg")
		fi
	done
	ratio=""
	[ -n "${MED[pg]}" ] && [ -n "${MED[tdc]}" ] && ratio=$(awk -v a="${MED[pg]}" -v b="${MED[tdc]}" 'BEGIN { printf "%.3g", a / b }')
	agree=""
	[ -n "${RES[pg]}" ] && [ -n "${RES[tdc]}" ] && { [ "${RES[pg]}" = "${RES[tdc]}" ] && agree=yes || agree=no; }
	# the triangle count of n points in general position is 2n-2-h
	expect=""
	if [ "$w" = agg_ng ]; then
		expect=$(sql -c "SELECT 2 * count(*) - 2 - (ST_NPoints(ST_ExteriorRing(ST_ConvexHull(ST_Collect(geom)))) - 1) FROM (SELECT $S.pt(i) AS geom FROM generate_series(0::bigint, $((k - 1))) i) s")
		NOTES+=("$(wl_name "$w") $(thousands "$k"): triangles: $A_NAME ${RES[pg]:--}, $B_NAME ${RES[tdc]:--}; 2n-2-h = $expect (h = vertices of ST_ConvexHull)")
	elif [ "$agree" = no ]; then
		NOTES+=("$(wl_name "$w") $(thousands "$k"): results differ: $A_NAME ${RES[pg]}, $B_NAME ${RES[tdc]}")
	fi
	echo "$w,$k,$c,$k,${MED[pg]},${MED[tdc]},$ratio,${PER[pg]},${PER[tdc]},${NR[pg]},${NR[tdc]},${MN[pg]},${MX[pg]},${MN[tdc]},${MX[tdc]},${ST[pg]},${ST[tdc]},${RES[pg]},${RES[tdc]},$agree,${PL[pg]},${PL[tdc]},$expect" >> "$CSV"
	printf '| %s | %s | %s | %s | %s | %s | %s | %s |\n' "$(wl_name "$w")" "$(thousands "$k")" "$(thousands "$c")" \
		"${CELLTXT[pg]}" "${CELLTXT[tdc]}" "$([ -n "$ratio" ] && echo "${ratio}x" || echo -)" \
		"$([ -n "${PER[pg]}" ] && fmt_ms "${PER[pg]}" || echo -)" "$([ -n "${PER[tdc]}" ] && fmt_ms "${PER[tdc]}" || echo -)" >> "$TXT"
	unset MED PER ST RES NR MN MX PL CELLTXT
done

{
	echo
	echo "Per call = median / rows (per row), / groups (per group), or the median itself (aggregate)."
	plans=$(awk -F, 'function p(x) { return x == "" ? "-" : x }
		NR > 1 && ($21 != "serial" && $21 != "" || $22 != "serial" && $22 != "") { printf "%s%s %s: " a " %s, " b " %s", sep, $1, $2, p($21), p($22); sep = "; " }' a="$A_NAME" b="$B_NAME" "$CSV")
	if [ -n "$plans" ]; then echo "Plans with parallel workers or JIT (all others serial, no JIT): $plans."; fi
	if awk -F, 'NR > 1 && $16 == "not run" { f = 1 } END { exit !f }' "$CSV"; then
		echo "PostGIS \"not run\": one aggregate over more than 10^6 points, only with BENCH_SWEEP_PG_10M=1."
	fi
	for n in "${NOTES[@]}"; do echo "- $n"; done
} >> "$TXT"

make_plot
if [ "$QUICK" != 1 ]; then
	bench_figure "$PNG" "time per call and ratio against points per call"
	if [ "$SRC" = patch ]; then
		bench_publish sweep_patch "Size sweep of the pcpatch aggregates against PC_Explode, 3 to 10^6 points per call" "$TXT"
	else
		bench_publish sweep "Size sweep in SQL: tdc_delaunay against PostGIS, 3 to 10^7 points per call" "$TXT"
	fi
fi
cat "$TXT"
log "wrote $RUNS, $CSV, $TXT, $PNG"
