#!/usr/bin/env bash
# bench/coverage_bench.sh -- DEMs as raster coverages in the database (issue
# 40): CALL tdc_interpolate_tiled from a geometry table and from a
# pgpointcloud patch table against ./tdc --grid on the same LiDAR ground, and
# the pcpatch aggregates against PC_Explode into the geometry aggregates.  A
# program that prints figures; its checks of the answers are part of its
# report.
#
# The data: synthetic airborne LiDAR (bench/gen_las.c, seed 1, UTM 32N), its
# ground (class 2, about 8.1 points a square metre) in a square whose side
# gives about the asked count, loaded (untimed for the comparisons, but the
# load is timed and reported) with COPY from bench/las_pg.c: a geometry(PointZ,
# 32632) table of hex EWKB, and a pcpatch table of uncompressed patch WKB, the
# ground of each square of BENCH_COV_PATCH_SIDE metres (8: some 500 points) a
# patch, under a pgpointcloud schema of int32 X, Y, Z with the LAS file's
# scales (0.01) and offsets, compression BENCH_COV_PC_COMPRESSION (none;
# PC_Compression of the stored patches is reported).  Before anything else a
# small patch table is checked against its geometry table: the same points
# (PC_NumPoints, and every PC_Get(pt) against the geometries' x, y, z).
#
#   A. BENCH_COV_N (1e8) ground points into a 1 m DEM: CALL
#      tdc_interpolate_tiled(..., ST_MakeEmptyRaster(W, H, ...), 'linear',
#      '32BF') into 256 x 256 tiles under SET tdc_delaunay.max_memory =
#      BENCH_COV_LIMIT (1000), from the geometry table and from the patch
#      table, against ./tdc --class 2 --grid 1 --max-memory 1000 --type
#      Float32 on the LAS file itself (the same doubles: X * scale + offset)
#      into the same grid (--extent).  Each run is a whole process timed by
#      GNU time (for SQL: the psql session that runs the CALL); the backend's
#      memory is sampled every 0.2 s from /proc/PID/status while the CALL
#      runs (PID: pg_backend_pid() of that session): RssAnon, its anonymous
#      resident memory (palloc, malloc, the core's buffers and its threads'),
#      which leaves out the shared buffers (RssShmem) and mapped files
#      (RssFile); smaps_rollup's Private_* would count a shared-buffer page
#      only this backend touched.  Its peak is judged against max_memory +
#      100 MB.  BENCH_COV_ROUNDS (1) rounds, the three runs interleaved.
#      Checks: AddRasterConstraints on each coverage, its tile count, and its
#      pixels read back by GDAL's PostGISRaster driver ('PG:... mode=2') as
#      raw Float32 against ./tdc's GeoTIFF, byte for byte (cmp), with the
#      size and georeferencing gdalinfo gives for both.  The patch table
#      needs tdc_interpolate_tiled to take a pcpatch column: a CALL on a tiny
#      patch table finds out; without it the report says "not supported by
#      this build" instead of a figure.
#   B. BENCH_COV_AGG_N (1e7) ground points of another survey: the pcpatch
#      aggregate against PC_Explode + PC_Get + ST_MakePoint into the geometry
#      aggregate (and the geometry table's aggregate beside them):
#      ST_TDCInterpolate(..., 'linear') into a 1 m 32BF raster, and
#      ST_TDCDelaunay on the first patches holding BENCH_COV_DT_N (2e6)
#      points (its one GEOMETRYCOLLECTION of 2 triangles a point must stay
#      under PostgreSQL's 1 GB limit of a value); results as md5 of
#      ST_AsBinary (and the triangle count), which must be equal.  Timed
#      server side (time_query of bench/lib.sh) in one session,
#      BENCH_COV_AGG_ROUNDS (3) rounds interleaved, medians.  PostGIS's
#      ST_InterpolateRaster(ST_Collect(geom), 'linear', template) over the
#      same geometry table, once, under statement_timeout
#      BENCH_COV_GDAL_TIMEOUT (900 s; GDAL's gridding is not interruptible,
#      so a timeout shows when it returns: "over N s"), its pixels against
#      ours.  PC_Get(pt) (the float8[]) and not PC_Get(pt, 'X'), which goes
#      through numeric and keeps 15 digits, so the points are the same doubles.
#
# Uses the server of the PG* variables (eval "$(bash scripts/cluster.sh env)")
# on this machine (the backend's /proc), with the extensions postgis,
# postgis_raster, pointcloud and tdc_delaunay's three installed; it makes and
# drops the database tdc_coverage_bench.  Disk at 1e8: the LAS file (~3.9 GB),
# the tables (some 10 GB), ./tdc's tiles.
#
# Knobs: BENCH_COV_N, BENCH_COV_AGG_N, BENCH_COV_DT_N, BENCH_COV_LIMIT,
# BENCH_COV_ROUNDS, BENCH_COV_AGG_ROUNDS, BENCH_COV_PATCH_SIDE,
# BENCH_COV_PC_COMPRESSION (none or dimensional), BENCH_COV_GDAL_TIMEOUT,
# BENCH_COV_TMP (build/bench/coverage), BENCH_COV_KEEP=1 (keep the database).
# BENCH_COV_TINY=1: a trial at 2e5 / 1e5 / 5e4 points that takes no lock,
# waits for nothing and writes no report (build/bench/coverage.txt only).
# Output: stdout, build/bench/coverage.txt, build/bench/coverage_runs.csv and
# docs/benchmarks/coverage.md.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

TINY=${BENCH_COV_TINY:-0}
if [ "$TINY" = 1 ]; then
	DEF_N=2e5 DEF_AGG=1e5 DEF_DT=5e4
else
	DEF_N=1e8 DEF_AGG=1e7 DEF_DT=2e6
fi
NA=${BENCH_COV_N:-$DEF_N}
NB=${BENCH_COV_AGG_N:-$DEF_AGG}
NDT=$(n_of "${BENCH_COV_DT_N:-$DEF_DT}")
LIMIT=${BENCH_COV_LIMIT:-1000}
ROUNDS=${BENCH_COV_ROUNDS:-1}
AGG_ROUNDS=${BENCH_COV_AGG_ROUNDS:-3}
PSIDE=${BENCH_COV_PATCH_SIDE:-8}
PCOMP=${BENCH_COV_PC_COMPRESSION:-none}
GDAL_TIMEOUT=${BENCH_COV_GDAL_TIMEOUT:-900}
WORK=${BENCH_COV_TMP:-$BENCH_OUT/coverage}
DB=tdc_coverage_bench
SRID=32632
TXT=$BENCH_OUT/coverage.txt
RUNS=$BENCH_OUT/coverage_runs.csv
case $PCOMP in none | dimensional) ;; *) die "BENCH_COV_PC_COMPRESSION must be none or dimensional" ;; esac
mkdir -p "$WORK" "$BENCH_OUT"

for t in gdal_translate gdalinfo; do
	command -v $t >/dev/null || ensure_debs gdal-bin
done
bench_tdc_copy
LAS_PG=$BENCH_BIN/las_pg

q() { command psql -X -q -A -t -v ON_ERROR_STOP=1 -d "$DB" "$@"; }
command psql -X -q -d postgres -c "DROP DATABASE IF EXISTS $DB" -c "CREATE DATABASE $DB" >/dev/null
[ "${BENCH_COV_KEEP:-0}" = 1 ] ||
	trap 'command psql -X -q -d postgres -c "DROP DATABASE IF EXISTS $DB" >/dev/null 2>&1 || true' EXIT
q -c "CREATE EXTENSION postgis; CREATE EXTENSION postgis_raster; CREATE EXTENSION pointcloud;
	CREATE EXTENSION tdc_delaunay; CREATE EXTENSION tdc_delaunay_raster; CREATE EXTENSION tdc_delaunay_pointcloud" >/dev/null
bench_sql_helpers bench | q >/dev/null
PGCONN="host=${PGHOST:-} port=${PGPORT:-5432} user=${PGUSER:-$(id -un)} dbname=$DB"

# the survey's side for about N ground points (gen_las: ~8.1 a square metre)
side_of() { awk -v n="$(n_of "$1")" 'BEGIN { printf "%.0f\n", sqrt(n / 8.1) }'; }

# survey NAME SIDE: $WORK/NAME.las (kept between runs) and its info line in $WORK/NAME.info
survey() {
	local las=$WORK/$1.las
	if [ ! -s "$las" ] || [ ! -s "$WORK/$1.info" ] || [ "$(cat "$WORK/$1.side")" != "$2" ]; then
		log "generating $las (side $2 m)"
		rm -f "$WORK/$1.info"
		"$BENCH_BIN/gen_las" -s 1 "$2" "$las.tmp" >&2 && mv "$las.tmp" "$las" || die "gen_las failed"
		echo "$2" > "$WORK/$1.side"
		"$LAS_PG" info "$las" 2 > "$WORK/$1.info" || die "las_pg info failed"
	fi
}

# pc_format PCID INFO: the pgpointcloud schema of int32 X, Y, Z with the LAS file's scales and offsets
pc_format() {
	local pcid=$1 info=$2 c dims=''
	for c in x y z; do
		dims+="<pc:dimension><pc:position>$(( $(printf '%d' "'$c") - 119 ))</pc:position><pc:size>4</pc:size>"
		dims+="<pc:description>${c^^} coordinate</pc:description><pc:name>${c^^}</pc:name>"
		dims+="<pc:interpretation>int32_t</pc:interpretation><pc:scale>$(kv "$info" "scale$c")</pc:scale>"
		dims+="<pc:offset>$(kv "$info" "offset$c")</pc:offset><pc:active>true</pc:active></pc:dimension>"
	done
	q -c "DELETE FROM pointcloud_formats WHERE pcid = $pcid;
		INSERT INTO pointcloud_formats (pcid, srid, schema) VALUES ($pcid, $SRID,
		'<?xml version=\"1.0\" encoding=\"UTF-8\"?><pc:PointCloudSchema xmlns:pc=\"http://pointcloud.org/schemas/PC/1.1\" xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\">$dims<pc:metadata><Metadata name=\"compression\">$PCOMP</Metadata></pc:metadata></pc:PointCloudSchema>')"
}

# load NAME PCID: tables g_NAME (id, geom) and p_NAME (id, pa) from $WORK/NAME.las;
# the COPYs timed (GNU time of las_pg | psql), into $WORK/load_NAME
load() {
	local name=$1 pcid=$2 las=$WORK/$1.las
	pc_format "$pcid" "$WORK/$name.info"
	q -c "CREATE TABLE g_$name (geom geometry(PointZ, $SRID)); CREATE TABLE p_$name (id int, pa pcpatch($pcid))"
	log "loading $las: geometries"
	/usr/bin/time -f %e -o "$WORK/t.out" bash -c "set -o pipefail; '$LAS_PG' geom '$las' 2 $SRID |
		psql -X -q -v ON_ERROR_STOP=1 -d $DB -c 'COPY g_$name (geom) FROM STDIN'" || die "loading g_$name failed"
	echo "geom $(cat "$WORK/t.out")" > "$WORK/load_$name"
	log "loading $las: patches"
	/usr/bin/time -f %e -o "$WORK/t.out" bash -c "set -o pipefail; '$LAS_PG' patch '$las' 2 $pcid $PSIDE |
		psql -X -q -v ON_ERROR_STOP=1 -d $DB -c 'COPY p_$name (id, pa) FROM STDIN'" || die "loading p_$name failed"
	echo "patch $(cat "$WORK/t.out")" >> "$WORK/load_$name"
	/usr/bin/time -f %e -o "$WORK/t.out" psql -X -q -v ON_ERROR_STOP=1 -d "$DB" -c "VACUUM ANALYZE g_$name" \
		-c "VACUUM ANALYZE p_$name" || die "VACUUM ANALYZE failed"
	echo "vacuum $(cat "$WORK/t.out")" >> "$WORK/load_$name"
}

# grid INFO: "X0 Y0 W H", 1 m pixels from the whole metre below the box, covering it
grid() {
	awk -v a="$(kv "$1" x0)" -v b="$(kv "$1" y0)" -v c="$(kv "$1" x1)" -v d="$(kv "$1" y1)" \
		'BEGIN { x = int(a); y = int(b); printf "%d %d %d %d\n", x, y, int(c - x) + 1, int(d - y) + 1 }'
}
# tmpl X0 Y0 W H: the band-less template of that grid
tmpl() { echo "ST_MakeEmptyRaster($3, $4, $1, $(($2 + $4)), 1, -1, 0, 0, $SRID)"; }

# ---------------------------------------------------------------- the patch format, checked
survey check 40
load check 9
chk=$(q -c "SELECT (SELECT count(*) FROM g_check) || ' ' || (SELECT sum(PC_NumPoints(pa)) FROM p_check) || ' ' ||
	(SELECT count(*) FROM (SELECT ST_X(geom), ST_Y(geom), ST_Z(geom) FROM g_check
		EXCEPT ALL SELECT v[1], v[2], v[3] FROM (SELECT PC_Get(pt) v FROM p_check, PC_Explode(pa) pt) e) a) || ' ' ||
	(SELECT count(*) FROM (SELECT v[1], v[2], v[3] FROM (SELECT PC_Get(pt) v FROM p_check, PC_Explode(pa) pt) e
		EXCEPT ALL SELECT ST_X(geom), ST_Y(geom), ST_Z(geom) FROM g_check) b)")
read -r chk_g chk_p chk_a chk_b <<< "$chk"
[ "$chk_g" = "$chk_p" ] && [ "$chk_a" = 0 ] && [ "$chk_b" = 0 ] ||
	die "the patches do not hold the geometries' points: $chk_g points, $chk_p in patches, $chk_a only in the geometries, $chk_b only in the patches"
log "the patch format checked: $chk_g points, the same in both tables"

# does tdc_interpolate_tiled take a pcpatch column?
CK=$(grid "$WORK/check.info")
read -r cx cy cw ch <<< "$CK"
if probe=$(q -c "CALL tdc_interpolate_tiled('p_check', 'cov_probe', 'pa', $(tmpl "$cx" "$cy" "$cw" "$ch"))" 2>&1); then
	PATCH_OK=1
	q -c "CALL tdc_interpolate_tiled('g_check', 'cov_probe_g', 'geom', $(tmpl "$cx" "$cy" "$cw" "$ch"))"
	pr=$(q -c "SELECT (SELECT md5(string_agg(md5(ST_AsBinary(rast)), '' ORDER BY rid)) FROM cov_probe) =
		(SELECT md5(string_agg(md5(ST_AsBinary(rast)), '' ORDER BY rid)) FROM cov_probe_g)")
	log "tdc_interpolate_tiled takes a pcpatch column (its tiles on the check table equal the geometry table's: $pr)"
else
	PATCH_OK=0
	PATCH_WHY=$(echo "$probe" | head -1)
	log "patch table: not supported by this build ($PATCH_WHY)"
fi

# ---------------------------------------------------------------- the data
survey a "$(side_of "$NA")"
survey b "$(side_of "$NB")"
load a 1
load b 2
GA=$(grid "$WORK/a.info")
GB=$(grid "$WORK/b.info")
read -r ax ay aw ah <<< "$GA"
read -r bx by bw bh <<< "$GB"
TA=$(tmpl "$ax" "$ay" "$aw" "$ah")
TB="ST_AddBand($(tmpl "$bx" "$by" "$bw" "$bh"), '32BF'::text, -9999, -9999)"
# the first patches holding NDT points, for the Delaunay aggregates
DT_ID=$(q -c "SELECT coalesce(min(id) FILTER (WHERE s >= $NDT), max(id)) FROM
	(SELECT id, sum(PC_NumPoints(pa)) OVER (ORDER BY id) s FROM p_b) c")
q -c "CREATE TABLE p_dt AS SELECT * FROM p_b WHERE id <= $DT_ID ORDER BY id" -c "VACUUM ANALYZE p_dt"

# ---------------------------------------------------------------- A: the runs
# mem_sampler PIDFILE OUT STOP: RssAnon and VmRSS (kB) of the backend every 0.2 s
mem_sampler() {
	local pid
	while [ ! -s "$1" ]; do
		[ -e "$3" ] && return 0
		sleep 0.05
	done
	pid=$(tr -dc 0-9 < "$1")
	while [ ! -e "$3" ] && [ -r "/proc/$pid/status" ]; do
		awk '/^RssAnon:/ { a = $2 } /^VmRSS:/ { r = $2 } END { if (a != "") print a, r }' "/proc/$pid/status" >> "$2" 2>/dev/null || true
		sleep 0.2
	done
}

# call_run LABEL ROUND SOURCE COLUMN: CALL tdc_interpolate_tiled into cov_LABEL, timed, its backend sampled
call_run() {
	local label=$1 r=$2 src=$3 col=$4 smp
	q -c "DROP TABLE IF EXISTS cov_$label"
	rm -f "$WORK/pid" "$WORK/stop" "$WORK/mem_$label"
	mem_sampler "$WORK/pid" "$WORK/mem_$label" "$WORK/stop" &
	smp=$!
	/usr/bin/time -f %e -o "$WORK/t.out" psql -X -q -A -t -v ON_ERROR_STOP=1 -d "$DB" \
		-c "SET client_min_messages = notice" \
		-c "\\o $WORK/pid" -c "SELECT pg_backend_pid()" -c "\\o" \
		-c "SET tdc_delaunay.max_memory = $LIMIT" \
		-c "CALL tdc_interpolate_tiled('$src', 'cov_$label', '$col', $TA, 'linear', '32BF')" \
		> "$WORK/call.out" 2> "$WORK/notice_$label" || { touch "$WORK/stop"; wait "$smp"; cat "$WORK/notice_$label" >&2; die "CALL from $src failed"; }
	touch "$WORK/stop"
	wait "$smp" || true
	echo "A,$label,$r,$(cat "$WORK/t.out"),$(awk 'BEGIN { m = 0; v = 0 } { if ($1 > m) m = $1; if ($2 > v) v = $2 } END { print m "," v "," NR }' "$WORK/mem_$label")" >> "$RUNS"
}

echo "part,label,round,wall_s,peak_anon_kb,peak_rss_kb,samples,status|message|result" > "$RUNS"
if [ "$TINY" = 1 ]; then
	BENCH_T0=$(date -u '+%Y-%m-%d %H:%M UTC')
else
	bench_begin server
fi
for ((r = 1; r <= ROUNDS; r++)); do
	log "A round $r: ./tdc"
	/usr/bin/time -f "%e %M" -o "$WORK/t.out" "$TDC_BIN" --stats --class 2 --grid 1 \
		--extent "$ax,$ay,$((ax + aw)),$((ay + ah))" --method linear:nodata=-9999 --type Float32 \
		--max-memory "$LIMIT" --tmpdir "$WORK" -o "$WORK/cli.tif" "$WORK/a.las" > /dev/null 2> "$WORK/cli_stats.txt" ||
		{ cat "$WORK/cli_stats.txt" >&2; die "./tdc failed"; }
	echo "A,cli,$r,$(awk '{ print $1 "," $2 ",," }' "$WORK/t.out")" >> "$RUNS"
	log "A round $r: CALL from the geometry table"
	call_run geom "$r" g_a geom
	if [ "$PATCH_OK" = 1 ]; then
		log "A round $r: CALL from the patch table"
		call_run patch "$r" p_a pa
	fi
done

# ---------------------------------------------------------------- B: the aggregates
EXPL="(SELECT ST_SetSRID(ST_MakePoint(v[1], v[2], v[3]), $SRID) g FROM (SELECT PC_Get(pt) v FROM TAB, PC_Explode(pa) pt) e) s"
declare -A BQ=(
	[interp_patch]="SELECT md5(ST_AsBinary(ST_TDCInterpolate(pa, $TB, 'linear'))) FROM p_b"
	[interp_explode]="SELECT md5(ST_AsBinary(ST_TDCInterpolate(g, $TB, 'linear'))) FROM ${EXPL//TAB/p_b}"
	[interp_geom]="SELECT md5(ST_AsBinary(ST_TDCInterpolate(geom, $TB, 'linear'))) FROM g_b"
	[dt_patch]="SELECT ST_NumGeometries(d) || ' ' || md5(ST_AsBinary(d)) FROM (SELECT ST_TDCDelaunay(pa) d FROM p_dt) t"
	[dt_explode]="SELECT ST_NumGeometries(d) || ' ' || md5(ST_AsBinary(d)) FROM (SELECT ST_TDCDelaunay(g) d FROM ${EXPL//TAB/p_dt}) t"
)
BKEYS="interp_patch interp_explode interp_geom dt_patch dt_explode"
{
	echo "SET statement_timeout = 0;"
	for k in $BKEYS; do
		echo "SELECT 'plan', '$k', bench.plan_of(\$bq\$${BQ[$k]}\$bq\$);"
	done
	for ((r = 1; r <= AGG_ROUNDS; r++)); do
		for k in $BKEYS; do
			echo "SELECT 'run', * FROM bench.time_query('$k', $r, \$bq\$${BQ[$k]}\$bq\$);"
		done
	done
	echo "CREATE TABLE gdal_b (r raster);"
	echo "SET statement_timeout = '${GDAL_TIMEOUT}s';"
	echo "SELECT 'run', * FROM bench.time_query('gdal', 1, \$bq\$WITH i AS (INSERT INTO gdal_b SELECT ST_InterpolateRaster(ST_Collect(geom), 'linear', $TB) FROM g_b RETURNING r) SELECT md5(ST_AsBinary(r)) FROM i\$bq\$);"
} > "$WORK/agg.sql"
log "B: the aggregates on $(thousands "$(kv "$WORK/b.info" n)") points, $AGG_ROUNDS rounds, then ST_InterpolateRaster once"
q -F '|' -f "$WORK/agg.sql" > "$WORK/agg.out" 2> "$WORK/agg.err" || { cat "$WORK/agg.err" >&2; die "part B failed"; }
awk -F'|' '$1 == "run" { print "B," $2 "," $3 "," $4 / 1000 ",,,," $6 "|" $7 "|" $5 }' "$WORK/agg.out" >> "$RUNS"

if [ "$TINY" != 1 ]; then
	bench_end
else
	BENCH_T1=$(date -u '+%Y-%m-%d %H:%M UTC')
fi

# ---------------------------------------------------------------- the checks (untimed) and the report
col() { awk -F, -v p="$1" -v l="$2" -v c="$3" '$1 == p && $2 == l { print $c }' "$RUNS"; }
med() { col "$1" "$2" "$3" | median; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { if (a == "" || b == "" || b == 0) print "-"; else printf "%.2fx\n", a / b }'; }
gdal_geo() { gdalinfo "$1" 2>/dev/null | grep -E '^(Size is|Origin =|Pixel Size =)' | tr '\n' ' '; }
raw_of() { gdal_translate -q -of ENVI -ot Float32 "$1" "$2" > /dev/null 2>&1; }

exec > >(tee "$TXT")
TEE_PID=$!
na=$(kv "$WORK/a.info" n)
nb=$(kv "$WORK/b.info" n)
ndt=$(q -c "SELECT sum(PC_NumPoints(pa)) FROM p_dt")
tiles_x=$(( (aw + 255) / 256 )) tiles_y=$(( (ah + 255) / 256 ))
pstats=$(q -c "SELECT count(*) || ' ' || min(n) || ' ' || percentile_disc(0.5) WITHIN GROUP (ORDER BY n) || ' ' || max(n)
	FROM (SELECT PC_NumPoints(pa) n FROM p_a) s")
read -r np pmin pmed pmax <<< "$pstats"
[ "$TINY" = 1 ] && echo "A TRIAL AT TINY SIZES (BENCH_COV_TINY=1): no report; the figures below time nothing of interest."
echo "Synthetic LiDAR ground (bench/gen_las.c -s 1, class 2), loaded with COPY from bench/las_pg.c; patches: the ground of each $PSIDE m square, int32 X, Y, Z scaled by $(kv "$WORK/a.info" scalex) with the LAS file's offsets, schema compression $PCOMP (stored as: $(q -c "SELECT string_agg(DISTINCT PC_Compression(pa)::text, ',') FROM (SELECT pa FROM p_a LIMIT 100) s"), pgpointcloud's PC_Compression: 0 none, 1 dimensional)."
echo "The patch format checked on a 40 m survey: $(thousands "$chk_g") points, every one the same x, y, z in the patches (PC_NumPoints, PC_Get(pt)) as in the geometry table."
echo
echo "## A. A 1 m DEM coverage from $(thousands "$na") ground points"
echo
echo "Survey $(cat "$WORK/a.side") m square; grid $aw x $ah pixels ($(thousands $((aw * ah)))), $tiles_x x $tiles_y = $(thousands $((tiles_x * tiles_y))) tiles of 256 x 256; 'linear', 32BF, nodata -9999; \`SET tdc_delaunay.max_memory = $LIMIT\` / \`--max-memory $LIMIT\`."
echo "Loads (untimed for the comparison; las_pg | psql COPY, whole pipelines): geometries $(kv <(tr ' ' = < "$WORK/load_a") geom) s, patches $(kv <(tr ' ' = < "$WORK/load_a") patch) s ($(thousands "$np") patches of $pmin to $pmax points, median $pmed), VACUUM ANALYZE of both $(kv <(tr ' ' = < "$WORK/load_a") vacuum) s."
echo "./tdc reads the LAS file itself (--class 2; the same doubles, X * scale + offset, as the tables hold), --type Float32, the grid given by --extent."
echo "Wall: whole processes under GNU time (the CALL: its psql session); $ROUNDS round(s), median. Peak: the backend's RssAnon (anonymous resident memory; the shared buffers and mapped files left out) sampled every 0.2 s during the session, highest sample; ./tdc: GNU time's maximum RSS."
echo
cli=$(med A cli 4)
echo "| run | wall | / ./tdc | peak | max_memory + 100 MB |"
echo "|---|--:|--:|--:|---|"
printf '| `./tdc --grid 1 --max-memory %s` | %s s | 1.00x | %s MB (max RSS) | |\n' "$LIMIT" "$cli" "$(awk -v k="$(med A cli 5)" 'BEGIN { printf "%.0f", k / 1024 }')"
for label in geom patch; do
	name="CALL tdc_interpolate_tiled from the geometry table"
	[ $label = patch ] && name="CALL tdc_interpolate_tiled from the patch table"
	if [ $label = patch ] && [ "$PATCH_OK" != 1 ]; then
		printf '| %s | patch table: not supported by this build | | | |\n' "$name"
		continue
	fi
	w=$(med A $label 4)
	pk=$(col A $label 5 | sort -n | tail -1)
	ns=$(col A $label 7 | sort -n | head -1)
	printf '| %s | %s s | %s | %s MB (RssAnon, %s samples) | %s |\n' "$name" "$w" "$(ratio "$w" "$cli")" \
		"$(awk -v k="$pk" 'BEGIN { printf "%.0f", k / 1024 }')" "$ns" \
		"$(awk -v k="$pk" -v l="$LIMIT" 'BEGIN { print (k / 1024 <= l + 100 ? "within" : "OVER") }')"
done
echo
echo "./tdc --stats (last run):"
echo '```text'
grep -v '^$' "$WORK/cli_stats.txt" | sed 's/ srs=.*/ srs=(the LAS file'"'"'s WKT)/' | tail -20
echo '```'
raw_of "$WORK/cli.tif" "$WORK/cli.raw"
echo
echo "Checks of each coverage:"
echo
for label in geom patch; do
	[ $label = patch ] && [ "$PATCH_OK" != 1 ] && { echo "- patch table: not supported by this build ($PATCH_WHY)"; continue; }
	echo "- from the $label table: the procedure's NOTICE: $(grep -v '^$' "$WORK/notice_$label" | tr '\n' ' ' | cut -c1-400)"
	arc=$(q -c "SELECT AddRasterConstraints('cov_$label'::name, 'rast'::name)" 2>&1 | tail -1)
	nt=$(q -c "SELECT count(*) FROM cov_$label")
	echo "  AddRasterConstraints: $arc; tiles $(thousands "$nt") (expected $(thousands $((tiles_x * tiles_y)))): $([ "$nt" = $((tiles_x * tiles_y)) ] && echo as expected || echo DIFFERENT)"
	pg="PG:$PGCONN schema=public table=cov_$label column=rast mode=2"
	echo "  GDAL reads it as: $(gdal_geo "$pg"); ./tdc's GeoTIFF: $(gdal_geo "$WORK/cli.tif")"
	if raw_of "$pg" "$WORK/cov_$label.raw"; then
		if cmp -s "$WORK/cov_$label.raw" "$WORK/cli.raw"; then
			echo "  its pixels against ./tdc's, raw Float32 (cmp): the same, byte for byte ($(thousands $((aw * ah))) pixels)"
		else
			echo "  its pixels against ./tdc's, raw Float32 (cmp): DIFFER ($(cmp -l "$WORK/cov_$label.raw" "$WORK/cli.raw" 2>/dev/null | wc -l) bytes; sizes $(stat -c %s "$WORK/cov_$label.raw") and $(stat -c %s "$WORK/cli.raw"))"
		fi
	else
		echo "  GDAL could not read the coverage (gdal_translate '$pg' failed)"
	fi
	rm -f "$WORK/cov_$label.raw"*
done
rm -f "$WORK/cli.raw"*

echo
echo "## B. The pcpatch aggregates against PC_Explode into the geometry aggregates"
echo
echo "Survey $(cat "$WORK/b.side") m square: $(thousands "$nb") ground points, $(thousands "$(q -c "SELECT count(*) FROM p_b")") patches; ST_TDCInterpolate into a 1 m 32BF raster of $bw x $bh pixels ('linear'); ST_TDCDelaunay on the first $(thousands "$(q -c "SELECT count(*) FROM p_dt")") patches ($(thousands "$ndt") points: its one value of 2 triangles a point stays under 1 GB)."
echo "Server-side times (clock_timestamp around EXECUTE, bench.time_query), one session, $AGG_ROUNDS rounds interleaved, medians; result: md5 of ST_AsBinary (ST_TDCDelaunay: the triangle count and the md5). PC_Explode path: ST_SetSRID(ST_MakePoint(v[1], v[2], v[3]), $SRID) of v = PC_Get(pt), the exact doubles."
echo
echo "| statement | plan | median | / the patch aggregate | result |"
echo "|---|---|--:|--:|---|"
bline() {
	local k=$1 desc=$2 base=$3 m st res
	m=$(med B "$k" 4)
	st=$(col B "$k" 8 | awk -F'|' '$1 != "ok" { print $1 ": " $2; exit }')
	res=$(col B "$k" 8 | awk -F'|' '{ print $3 }' | sort -u | tr '\n' ' ')
	printf '| %s | %s | %s | %s | %s |\n' "$desc" "$(awk -F'|' -v k="$k" '$1 == "plan" && $2 == k { print $3 }' "$WORK/agg.out")" \
		"$( [ -n "$st" ] && echo "$st" || fmt_ms "$(awk -v s="$m" 'BEGIN { print s * 1000 }')")" \
		"$(ratio "$m" "$(med B "$base" 4)")" "$res"
}
bline interp_patch 'ST_TDCInterpolate(pa, ...) FROM patches' interp_patch
bline interp_explode 'ST_TDCInterpolate(ST_MakePoint(PC_Get(PC_Explode(pa))), ...)' interp_patch
bline interp_geom 'ST_TDCInterpolate(geom, ...) FROM the geometry table' interp_patch
bline dt_patch 'ST_TDCDelaunay(pa) FROM patches' dt_patch
bline dt_explode 'ST_TDCDelaunay(ST_MakePoint(PC_Get(PC_Explode(pa))))' dt_patch
gst=$(col B gdal 8 | awk -F'|' '{ print $1 }')
gms=$(col B gdal 4)
if [ "$gst" = ok ]; then
	printf '| ST_InterpolateRaster(ST_Collect(geom), '"'"'linear'"'"', ...) FROM the geometry table (PostGIS, GDAL), once | | %s | %s | %s |\n' \
		"$(fmt_ms "$(awk -v s="$gms" 'BEGIN { print s * 1000 }')")" "$(ratio "$gms" "$(med B interp_patch 4)")" "$(col B gdal 8 | awk -F'|' '{ print $3 }')"
else
	printf '| ST_InterpolateRaster(ST_Collect(geom), '"'"'linear'"'"', ...) (PostGIS, GDAL), once | | over %s s (%s after %s s: %s) | | |\n' \
		"$GDAL_TIMEOUT" "$gst" "$gms" "$(col B gdal 8 | awk -F'|' '{ print $2 }')"
fi
echo
same() { [ "$(col B "$1" 8 | awk -F'|' '{ print $3 }' | sort -u)" = "$(col B "$2" 8 | awk -F'|' '{ print $3 }' | sort -u)" ] && echo same || echo DIFFERENT; }
echo "Checks: the interpolated rasters, patch aggregate against PC_Explode: $(same interp_patch interp_explode); against the geometry table: $(same interp_patch interp_geom); the triangulations, patch against PC_Explode: $(same dt_patch dt_explode)."
if [ "$gst" = ok ]; then
	cmpg=$(q -c "WITH o AS (SELECT ST_TDCInterpolate(geom, $TB, 'linear') r FROM g_b)
		SELECT count(*) || ' ' || count(*) FILTER (WHERE a = b) || ' ' || count(*) FILTER (WHERE abs(a - b) <= 0.001)
			|| ' ' || count(*) FILTER (WHERE (a IS NULL) <> (b IS NULL))
			|| ' ' || coalesce(max(abs(a - b)), 0)
		FROM o, gdal_b, unnest(ST_DumpValues(o.r, 1), ST_DumpValues(gdal_b.r, 1)) u(a, b)")
	read -r ctot csame cmm cnd cmax <<< "$cmpg"
	echo "ST_InterpolateRaster against ours (32BF, pixel by pixel): $(thousands "$csame") of $(thousands "$ctot") pixels equal, $(thousands "$cmm") within 1 mm, $cnd nodata in one only, largest difference $cmax m (which of the two is exact: bench/dem_bench.sh judges ./tdc's grid on the same synthetic ground with the exact arbiter, test/tin_arbiter.c)."
fi
exec >&-
wait "$TEE_PID" 2>/dev/null || true

if [ "$TINY" = 1 ]; then
	log "tiny trial done: $TXT (no report written)"
else
	bench_publish coverage "DEM coverages in the database: tdc_interpolate_tiled and the pcpatch aggregates" "$TXT"
fi
