#!/usr/bin/env bash
# bench/tin_bench.sh -- the TIN in SQL (issue 29): interpolation into rasters
# against PostGIS ST_InterpolateRaster (GDAL's gdal_grid "linear"), draping,
# contours, and our Delaunay aggregate on the same rows, in the same run; then
# a size sweep of the interpolation against ST_InterpolateRaster, per row, per
# group and over a whole table.  It prints figures, and checks that the
# answers it timed are right (see Checks below): a benchmark must not time a
# wrong answer.  A failed check is reported in the tables and makes the script
# exit 1 after writing them.
#
# Server: the usual libpq variables (PGHOST, PGPORT, PGUSER, PGDATABASE); the
# extensions tdc_delaunay_raster (with tdc_delaunay, postgis, postgis_raster)
# are created if missing (make install first).  Tables live in schema
# "bench_tin" and are kept between runs (BENCH_TIN_RELOAD=1 rebuilds them).
#
# Data: held-out samples of one known terrain.  Sample i lies at
#   x = 1000 * (hashint8extended(i, 1) & (2^52 - 1)) / 2^52,  y = the same with seed 2
# (uniform in [0, 1000)^2, general position), its Z the terrain's height there,
#   z = 100 + 50 sin(x / 80) cos(y / 120) + 30 sin(y / 33) + 0.05 x,
# so every table is a pure function of its sizes, and every interpolated value
# can be compared with the surface the samples came from.  Each data set takes
# its indices from its own range (samples from 0, per-row sets from 2^40, group
# sets from 2^41, draped points from 2^42): the draped points are held out from
# the samples.  Templates: W x W pixels over [0, 1000]^2, one 64BF band, nodata
# -9999 (pixel centres at (i + 0.5) * 1000 / W, as gdal_grid places them).
#
# Workloads (t: the template, a parameter of the statement; n samples, one
# POINT Z per row):
#   main   n = BENCH_TIN_N (1e6) samples, t = BENCH_TIN_PIXELS^2 (1000 x 1000):
#            gdal      SELECT ST_InterpolateRaster(ST_Collect(geom), 'linear', t) FROM s
#            lin       SELECT ST_TDCInterpolate(geom, t, 'linear') FROM s
#            nn        SELECT ST_TDCInterpolate(geom, t, 'natural_neighbor') FROM s
#            dropin    SELECT ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', t) FROM s
#            drape     SELECT ST_TDCDrape(geom, target) IS NOT NULL FROM s
#                      (target: one MULTIPOINT of BENCH_TIN_DRAPE_N (= n) held-out
#                      points inside the samples' hull, a parameter of the statement)
#            contours  SELECT ST_TDCContours(geom, interval, base) IS NOT NULL FROM s
#                      (BENCH_TIN_LEVELS = 20 levels: interval = (zmax - zmin) / 20,
#                      base = zmin + interval / 2)
#            delaunay  SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM s
#   agg    the same three interpolations (gdal, lin, nn, dropin) for each n in
#          BENCH_TIN_SIZES (3, 100, 1e4, 1e5, 1e6) into BENCH_TIN_SWEEP_PIXELS^2
#          (200 x 200); the size equal to BENCH_TIN_N is not run again: its
#          row in the sweep is the main one (at its template).
#   row    per row, BENCH_TIN_ROWS = "k:R ..." (3:1000 100:1000): R rows of one
#          MULTIPOINT Z of k samples each, t = BENCH_TIN_ROW_PIXELS^2 (32 x 32):
#            gdal      SELECT count(ST_InterpolateRaster(g, 'linear', t)) FROM r
#            dropin    SELECT count(ST_TDCInterpolateRaster(g, 'linear', t)) FROM r
#   group  per group, BENCH_TIN_GROUPS = "k:G ..." (3:1000 100:1000 1e4:10): G
#          groups of k POINT Z rows, the same template:
#            gdal      SELECT count(r) FROM (SELECT ST_InterpolateRaster(ST_Collect(geom), 'linear', t) r FROM g GROUP BY grp) s
#            lin       the same with ST_TDCInterpolate(geom, t, 'linear')
#            dropin    the same with ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', t)
#
# Timing: server side, clock_timestamp() around EXECUTE ... USING t, target in
# a plpgsql function (time_run below), so that the template and the target are
# parameters, that is constants of the statement, as a literal would be.  A
# raster result is kept (copied into a plpgsql variable, then stored for the
# checks after the clock stopped) for the raster statements, ours and GDAL's
# alike; the geometry statements are timed as "IS NOT NULL" (the value built,
# then dropped) and run once more, untimed, for the checks.  Each cell
# (workload, size) runs in one psql session: the session settings, one tiny
# untimed call of ST_InterpolateRaster and of ours (to load the libraries),
# then each statement once untimed (BENCH_TIN_WARM), then BENCH_TIN_REPS
# rounds, each running every statement once in the order above, so that the
# load on the machine affects all of them alike; medians reported.
# ST_InterpolateRaster with n >= BENCH_TIN_SLOW_N (1e6) samples runs
# BENCH_TIN_SLOW_REPS (1) time(s), in the first round, with no warm-up.  A
# statement that fails (error, or statement_timeout: BENCH_TIN_TIMEOUT s,
# BENCH_TIN_GDAL_TIMEOUT s for ST_InterpolateRaster) is recorded with its
# message and the time until it failed, and not run again in that cell.
# Note: ST_InterpolateRaster gives GDALGridCreate no progress callback, so
# GDAL's gridding cannot be interrupted: a statement_timeout that falls inside
# it takes effect only when it has finished (one inside ST_Collect, at once),
# and the report gives "> N s" with the time until the statement stopped.
#
# Checks (after the timed runs, untimed):
#   - ours 'linear' against GDAL's, pixel by pixel, in main, in every agg size
#     and in every row and group: every pixel both give a value within 1e-9
#     relative, except outside the samples' hull (where GDAL's default radius
#     gives "a near" sample's value from a box search, ours the nearest) or on
#     it; the drop-in's raster byte for byte the aggregate's (and, per group,
#     the drop-in's over ST_Collect);
#   - main: linear and natural neighbour against the terrain at the pixel
#     centres inside the hull: RMS error under 1% of the height range;
#   - main drape: every target point gets a Z, RMS error against the terrain
#     under 1% of the height range; and the centres of about 10,000 pixels
#     inside the hull draped: their Z within 1e-9 relative of GDAL's pixels;
#   - main contours: exactly BENCH_TIN_LEVELS levels, each line flat at its
#     level, the levels base + k * interval;
#   - main Delaunay: 2n - 2 - h triangles (h: vertices of the convex hull).
#
# Outputs: build/bench/tin_runs.csv    every run (rep <= 0: warm-up)
#          build/bench/tin.csv         medians, min, max, ratios
#          build/bench/tin_checks.csv  the checks
#          build/bench/tin.txt         the tables (Markdown)
#          docs/benchmarks/tin.md      the report: bench_publish's header + tin.txt
#                                      (BENCH_DOCS=DIR writes it elsewhere)
# Knobs:   BENCH_TIN_N=1e6  BENCH_TIN_PIXELS=1000  BENCH_TIN_DRAPE_N (= N)
#          BENCH_TIN_LEVELS=20  BENCH_TIN_SIZES="3 100 1e4 1e5 1e6" (commas or spaces)
#          BENCH_TIN_SWEEP_PIXELS=200  BENCH_TIN_ROWS="3:1000 100:1000"
#          BENCH_TIN_GROUPS="3:1000 100:1000 1e4:10"  BENCH_TIN_ROW_PIXELS=32
#          BENCH_TIN_WORKLOADS="main agg row group"
#          BENCH_TIN_REPS=3  BENCH_TIN_WARM=1  BENCH_TIN_SLOW_N=1e6  BENCH_TIN_SLOW_REPS=1
#          BENCH_TIN_TIMEOUT=600  BENCH_TIN_GDAL_TIMEOUT=300 (s per statement)
#          BENCH_TIN_SETTINGS="jit=off max_parallel_workers_per_gather=0"
#          (session settings, name=value ...; "" keeps the server's)  BENCH_TIN_RELOAD=1
# A try-out in a couple of minutes:
#   BENCH_TIN_N=1e4 BENCH_TIN_PIXELS=100 BENCH_TIN_SIZES=3,100,1e4 BENCH_TIN_SWEEP_PIXELS=100 \
#   BENCH_TIN_ROWS=3:100,100:100 BENCH_TIN_GROUPS=3:100,100:100 BENCH_DOCS=/tmp/tin bash bench/tin_bench.sh
#
# jit=off and serial plans by default, as in the other SQL benchmarks: JIT
# would be paid by whichever statement's planner cost passes jit_above_cost,
# and a parallel plan gives our aggregates workers that ST_Collect cannot use.
# Ours computes on tdc_delaunay.threads threads (the header gives it); GDAL's
# gridding is single-threaded.  The plan of every statement is recorded.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
# shellcheck source=bench/lib.sh
. "$ROOT/bench/lib.sh"

N=$(n_of "${BENCH_TIN_N:-1e6}")
PIX=${BENCH_TIN_PIXELS:-1000}
DRAPE_N=$(n_of "${BENCH_TIN_DRAPE_N:-$N}")
LEVELS=${BENCH_TIN_LEVELS:-20}
SIZES=$(tr ',' ' ' <<< "${BENCH_TIN_SIZES:-3 100 1e4 1e5 1e6}")
SWEEP_PIX=${BENCH_TIN_SWEEP_PIXELS:-200}
ROW_SIZES=$(tr ',' ' ' <<< "${BENCH_TIN_ROWS:-3:1000 100:1000}")
GRP_SIZES=$(tr ',' ' ' <<< "${BENCH_TIN_GROUPS:-3:1000 100:1000 1e4:10}")
ROW_PIX=${BENCH_TIN_ROW_PIXELS:-32}
WORKLOADS=${BENCH_TIN_WORKLOADS:-"main agg row group"}
REPS=${BENCH_TIN_REPS:-3}
WARM=${BENCH_TIN_WARM:-1}
SLOW_N=$(n_of "${BENCH_TIN_SLOW_N:-1e6}")
SLOW_REPS=${BENCH_TIN_SLOW_REPS:-1}
TIMEOUT=${BENCH_TIN_TIMEOUT:-600}
GDAL_TIMEOUT=${BENCH_TIN_GDAL_TIMEOUT:-300}
RELOAD=${BENCH_TIN_RELOAD:-0}
SETTINGS=${BENCH_TIN_SETTINGS-"jit=off max_parallel_workers_per_gather=0"}
S=bench_tin
# the data's definition: change it when the formulas above change
DATA_VERSION="tin v1"
SEED_ROWS=1099511627776		# 2^40
SEED_GROUPS=2199023255552	# 2^41
SEED_DRAPE=4398046511104	# 2^42

for v in N PIX DRAPE_N LEVELS SWEEP_PIX ROW_PIX REPS WARM SLOW_N SLOW_REPS; do
	[[ ${!v} =~ ^[0-9]+$ ]] || die "BENCH_TIN_$v: '${!v}' is not a whole number"
done
for v in TIMEOUT GDAL_TIMEOUT; do
	[[ ${!v} =~ ^[0-9]*\.?[0-9]+$ ]] && [ "${!v}" != 0 ] || die "BENCH_TIN_$v: '${!v}' is not a number of seconds above 0"
done
[ "$N" -ge 3 ] && [ "$PIX" -ge 1 ] && [ "$LEVELS" -ge 1 ] || die "BENCH_TIN_N must be >= 3, the pixels and levels >= 1"

mkdir -p "$BENCH_OUT"
RUNS=$BENCH_OUT/tin_runs.csv
CSV=$BENCH_OUT/tin.csv
CHECKS=$BENCH_OUT/tin_checks.csv
TXT=$BENCH_OUT/tin.txt
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

command -v psql >/dev/null || die "psql not found"
sql -c 'SELECT 1' >/dev/null 2>&1 ||
	die "no PostgreSQL server reachable with PGHOST=${PGHOST:-} PGPORT=${PGPORT:-} PGUSER=${PGUSER:-} PGDATABASE=${PGDATABASE:-}"
sql -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE" >/dev/null 2> "$WORK/err" ||
	die "tdc_delaunay_raster not available ($(head -1 "$WORK/err")): make install first"
PG_VER=$(sql -c "SELECT split_part(version(), ' on ', 1)")
PGIS_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'postgis'")
GDAL_VER=$(sql -c "SELECT postgis_gdal_version()")
TDC_VER=$(sql -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")

SET_SQL=""
for kvp in $SETTINGS; do
	case $kvp in *=*) ;; *) die "BENCH_TIN_SETTINGS: '$kvp' is not name=value" ;; esac
	SET_SQL+="SET ${kvp%%=*} = '${kvp#*=}';"$'\n'
done

# ---------------------------------------------------------------- SQL helpers
bench_sql_helpers "$S" | sql >/dev/null
sql <<EOF >/dev/null
-- the terrain the samples come from
CREATE OR REPLACE FUNCTION $S.terrain(x float8, y float8) RETURNS float8
LANGUAGE sql IMMUTABLE PARALLEL SAFE AS
\$\$ SELECT 100 + 50 * sin(x / 80) * cos(y / 120) + 30 * sin(y / 33) + 0.05 * x \$\$;

-- sample i: pt(i) scaled to [0, 1000)^2, Z the terrain's height there
CREATE OR REPLACE FUNCTION $S.sample(i bigint) RETURNS geometry
LANGUAGE sql IMMUTABLE PARALLEL SAFE AS
\$\$ SELECT ST_MakePoint(x, y, $S.terrain(x, y))
	FROM (SELECT 1000 * ST_X(p) AS x, 1000 * ST_Y(p) AS y FROM (SELECT $S.pt(i) AS p) q) s \$\$;

-- a W x W template over [0, 1000]^2, one 64BF band, nodata -9999
CREATE OR REPLACE FUNCTION $S.template(w int) RETURNS raster
LANGUAGE sql IMMUTABLE AS
\$\$ SELECT ST_AddBand(ST_MakeEmptyRaster(w, w, 0, 1000, 1000.0 / w, -1000.0 / w, 0, 0, 0),
					  '64BF'::text, -9999::float8, -9999::float8) \$\$;

-- per samples table: its size, hull, number of hull vertices and heights
CREATE TABLE IF NOT EXISTS $S.info(name text PRIMARY KEY, n bigint, hull geometry, h int, zmin float8, zmax float8);
-- the results kept for the checks (unlogged: scratch)
CREATE UNLOGGED TABLE IF NOT EXISTS $S.kept(key text PRIMARY KEY, r raster, g geometry);
TRUNCATE $S.kept;

-- time_run(key, rep, q, kind, t, target): runs q once, EXECUTE q USING t,
-- target, and times the EXECUTE alone.  kind 'raster': q returns a raster,
-- kept in $S.kept (the first one of the key) after the clock stopped;
-- 'geometry': the same for a geometry (replacing the kept one); 'value': the
-- result (text) is returned.  Never raises: a failure (error or
-- statement_timeout) becomes status/message, with the time until it
-- happened, and marks the key as failed for the rest of the session, after
-- which every call for it returns 'skipped' at once.  t and target are
-- copied into memory first (ST_SetSRID makes a new value), so that no
-- statement pays for reading them from TOAST.
CREATE OR REPLACE FUNCTION $S.time_run(p_key text, p_rep int, q text, p_kind text, p_tmpl raster, p_target geometry,
	OUT o_key text, OUT o_rep int, OUT ms float8, OUT result text, OUT status text, OUT message text)
LANGUAGE plpgsql AS \$\$
DECLARE
	t0 timestamptz;
	tm raster := ST_SetSRID(p_tmpl, ST_SRID(p_tmpl));
	tg geometry := ST_SetSRID(p_target, ST_SRID(p_target));
	vr raster;
	vg geometry;
	vt text;
BEGIN
	o_key := p_key;
	o_rep := p_rep;
	status := 'ok';
	message := '';
	IF current_setting('$S.failed_' || p_key, true) = '1' THEN
		status := 'skipped';
		message := 'not run: an earlier run of this statement failed';
		RETURN;
	END IF;
	BEGIN
		IF p_kind = 'raster' THEN
			t0 := clock_timestamp();
			EXECUTE q INTO vr USING tm, tg;
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
		ELSIF p_kind = 'geometry' THEN
			t0 := clock_timestamp();
			EXECUTE q INTO vg USING tm, tg;
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
		ELSE
			t0 := clock_timestamp();
			EXECUTE q INTO vt USING tm, tg;
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
		END IF;
	EXCEPTION
		WHEN query_canceled THEN
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
			status := 'timeout';
			message := SQLERRM;
		WHEN OTHERS THEN
			ms := 1000 * extract(epoch FROM clock_timestamp() - t0);
			status := 'error';
			message := SQLERRM;
	END;
	IF status <> 'ok' THEN
		PERFORM set_config('$S.failed_' || p_key, '1', false);
	ELSIF p_kind = 'raster' THEN
		result := CASE WHEN vr IS NULL THEN 'NULL' ELSE ST_Width(vr) || 'x' || ST_Height(vr) || ' md5 ' || md5(ST_AsBinary(vr)) END;
		INSERT INTO $S.kept(key, r) VALUES (p_key, vr) ON CONFLICT (key) DO NOTHING;
	ELSIF p_kind = 'geometry' THEN
		result := CASE WHEN vg IS NULL THEN 'NULL' ELSE ST_GeometryType(vg) || ' ' || ST_NPoints(vg) END;
		INSERT INTO $S.kept(key, g) VALUES (p_key, vg) ON CONFLICT (key) DO UPDATE SET g = EXCLUDED.g;
	ELSE
		result := vt;
	END IF;
	-- one CSV field, one line
	message := regexp_replace(message, '[,|\t\r\n]+', ' ', 'g');
	result := regexp_replace(result, '[,|\t\r\n]+', ' ', 'g');
END \$\$;

-- plan_with(q, t, target): the plan's shape (parallel workers, JIT) with the parameters bound
CREATE OR REPLACE FUNCTION $S.plan_with(q text, p_tmpl raster, p_target geometry) RETURNS text
LANGUAGE plpgsql AS \$\$
DECLARE
	l text;
	w text := '';
	jit bool := false;
BEGIN
	FOR l IN EXECUTE 'EXPLAIN ' || q USING p_tmpl, p_target LOOP
		IF l ~ 'Workers Planned' THEN
			w := substring(l FROM '[0-9]+');
		END IF;
		IF l ~ '^JIT:' THEN
			jit := true;
		END IF;
	END LOOP;
	RETURN CASE WHEN w = '' THEN 'serial' ELSE w || ' workers' END || CASE WHEN jit THEN ' jit' ELSE '' END;
END \$\$;

-- pixels(r): pixel i (1-based, row by row), its centre and its value (NULL: nodata)
CREATE OR REPLACE FUNCTION $S.pixels(r raster) RETURNS TABLE(i bigint, x float8, y float8, v float8)
LANGUAGE sql STABLE AS
\$\$ SELECT u.i, m.upperleftx + ((u.i - 1) % m.width + 0.5) * m.scalex,
		   m.upperlefty + ((u.i - 1) / m.width + 0.5) * m.scaley, u.v
	FROM ST_MetaData(r) m, unnest(ST_DumpValues(r, 1)) WITH ORDINALITY u(v, i) \$\$;

-- cmp(a, b, hull): a against b pixel by pixel.  A pixel differs when one has
-- a value and the other not, or both differ by more than 1e-9 relative;
-- differ_inside counts those whose centre lies in the hull, farther than
-- 1e-9 of the extent from its boundary; max_rel the largest relative
-- difference among the others.
CREATE OR REPLACE FUNCTION $S.cmp(a raster, b raster, hull geometry,
	OUT pixels bigint, OUT both_values bigint, OUT differ bigint, OUT differ_inside bigint, OUT max_rel float8)
LANGUAGE sql STABLE AS
\$\$ WITH j AS (SELECT pa.i, pa.x, pa.y, pa.v AS va, pb.v AS vb,
					  (pa.v IS NULL) <> (pb.v IS NULL) OR
					  abs(pa.v - pb.v) > 1e-9 * greatest(abs(pa.v), abs(pb.v)) AS bad
			   FROM $S.pixels(a) pa JOIN $S.pixels(b) pb USING (i))
	SELECT count(*), count(*) FILTER (WHERE va IS NOT NULL AND vb IS NOT NULL),
		   count(*) FILTER (WHERE bad),
		   count(*) FILTER (WHERE bad AND ST_Intersects(hull, ST_MakePoint(x, y)) AND
							ST_Distance(ST_MakePoint(x, y), ST_Boundary(hull)) > 1e-9 * 1000),
		   coalesce(max(abs(va - vb) / nullif(greatest(abs(va), abs(vb)), 0)) FILTER (WHERE NOT bad), 0)
	FROM j \$\$;

-- truth(r, hull): r against the terrain at the pixel centres in the hull
CREATE OR REPLACE FUNCTION $S.truth(r raster, hull geometry, OUT pixels bigint, OUT nodata bigint, OUT rms float8, OUT maxerr float8)
LANGUAGE sql STABLE AS
\$\$ SELECT count(*), count(*) FILTER (WHERE v IS NULL),
		   sqrt(avg((v - $S.terrain(x, y))^2)), max(abs(v - $S.terrain(x, y)))
	FROM $S.pixels(r) WHERE ST_Intersects(hull, ST_MakePoint(x, y)) \$\$;
EOF

# ensure TABLE SPEC SQL: run SQL (which creates $S.TABLE) unless $S.TABLE
# exists with the comment SPEC (how it was made)
ensure() {
	local t=$1 spec="$DATA_VERSION: $2" body=$3
	if [ "$RELOAD" = 0 ] && [ "$(sql -c "SELECT obj_description(to_regclass('$S.$t'), 'pg_class')")" = "$spec" ]; then
		return 0
	fi
	log "creating $S.$t ($2)"
	sql <<EOF >/dev/null
SET statement_timeout = 0;
DROP TABLE IF EXISTS $S.$t;
$body
COMMENT ON TABLE $S.$t IS '$spec';
VACUUM (ANALYZE) $S.$t;
EOF
}

# ensure_samples N: $S.s_N, n samples, one POINT Z per row, and its info row
ensure_samples() {
	local n=$1
	ensure "s_$n" "samples 0 .. $((n - 1))" "
CREATE TABLE $S.s_$n AS SELECT i AS id, $S.sample(i) AS geom FROM generate_series(0::bigint, $((n - 1))) i;
DELETE FROM $S.info WHERE name = 's_$n';
INSERT INTO $S.info
SELECT 's_$n', n, hull, ST_NPoints(ST_ExteriorRing(hull)) - 1, zmin, zmax
FROM (SELECT count(*) AS n, ST_ConvexHull(ST_Collect(geom)) AS hull, min(ST_Z(geom)) AS zmin, max(ST_Z(geom)) AS zmax
	  FROM $S.s_$n) s;"
}

# ensure_target D N: $S.target_D_N, one MULTIPOINT of the held-out points
# D of them, those inside the hull of s_N (all of them but a few at the edges)
ensure_target() {
	local d=$1 n=$2
	ensure "target_${d}_$n" "draped points $SEED_DRAPE + 0 .. $((d - 1)) inside the hull of s_$n" "
CREATE TABLE $S.target_${d}_$n AS
SELECT ST_Collect(p ORDER BY i) AS g
FROM (SELECT i, ST_Force2D($S.sample($SEED_DRAPE + i)) AS p FROM generate_series(0::bigint, $((d - 1))) i) s,
	 $S.info h
WHERE h.name = 's_$n' AND ST_Intersects(h.hull, p);"
}

# ensure_rows K R: $S.rows_K_R, R rows of one MULTIPOINT Z of K samples each
ensure_rows() {
	local k=$1 r=$2
	ensure "rows_${k}_$r" "$r rows of $k samples from $SEED_ROWS" "
CREATE TABLE $S.rows_${k}_$r AS
SELECT r AS id, ST_Collect($S.sample($SEED_ROWS + r * $k + j) ORDER BY j) AS g
FROM generate_series(0::bigint, $((r - 1))) r, generate_series(0::bigint, $((k - 1))) j GROUP BY r ORDER BY r;"
}

# ensure_groups K G: $S.grp_K_G, G groups of K POINT Z rows
ensure_groups() {
	local k=$1 g=$2
	ensure "grp_${k}_$g" "$g groups of $k samples from $SEED_GROUPS" "
CREATE TABLE $S.grp_${k}_$g AS
SELECT g AS grp, $S.sample($SEED_GROUPS + g * $k + j) AS geom
FROM generate_series(0::bigint, $((g - 1))) g, generate_series(0::bigint, $((k - 1))) j ORDER BY g, j;"
}

sql <<EOF >/dev/null
CREATE TABLE IF NOT EXISTS $S.tmpl(name text PRIMARY KEY, w int, r raster);
TRUNCATE $S.tmpl;
INSERT INTO $S.tmpl VALUES ('main', $PIX, $S.template($PIX)), ('agg', $SWEEP_PIX, $S.template($SWEEP_PIX)),
	('row', $ROW_PIX, $S.template($ROW_PIX)), ('tiny', 4, $S.template(4));
EOF

# ---------------------------------------------------------------- the cells
# A cell is one psql session: its statements, added with stmt, then run_cell.
has() { case " $WORKLOADS " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }
ST_KEY=() ST_KIND=() ST_Q=() ST_TMPL=() ST_TARGET=() ST_SLOW=()
stmt() {	# KEY KIND QUERY TEMPLATE TARGET SLOW
	ST_KEY+=("$1") ST_KIND+=("$2") ST_Q+=("$3") ST_TMPL+=("$4") ST_TARGET+=("$5") ST_SLOW+=("$6")
}
# the argument expressions of time_run for a template name and a target table
tmpl_arg() { if [ -n "$1" ]; then echo "(SELECT r FROM $S.tmpl WHERE name = '$1')"; else echo "NULL::raster"; fi; }
target_arg() { if [ -n "$1" ]; then echo "(SELECT g FROM $S.$1)"; else echo "NULL::geometry"; fi; }

echo "cell,key,rep,ms,result,status,message,plan" > "$RUNS"
SO=$(pg_config --pkglibdir 2>/dev/null)/tdc_delaunay.so
SO_START=$(so_id)
bench_begin server

# run_cell CELL: the statements added since the last cell, in one session
run_cell() {
	local cell=$1 i rep first last to line ms res st msg key
	local nst=${#ST_KEY[@]}
	{
		echo "SET statement_timeout = '${TIMEOUT}s';"
		printf '%s' "$SET_SQL"
		# load GDAL and ours into the session
		echo "SELECT 'load', ST_InterpolateRaster('MULTIPOINT Z (0 0 1, 1000 0 2, 0 1000 3)', 'linear', r) IS NOT NULL,"
		echo "       ST_TDCInterpolateRaster('MULTIPOINT Z (0 0 1, 1000 0 2, 0 1000 3)', 'linear', r) IS NOT NULL"
		echo "FROM $S.tmpl WHERE name = 'tiny';"
		for ((i = 0; i < nst; i++)); do
			echo "SELECT 'plan', '${ST_KEY[i]}', $S.plan_with(\$bq\$${ST_Q[i]}\$bq\$, $(tmpl_arg "${ST_TMPL[i]}"), $(target_arg "${ST_TARGET[i]}"));"
		done
		for rep in $(seq $((1 - WARM)) "$REPS"); do
			for ((i = 0; i < nst; i++)); do
				if [ "${ST_SLOW[i]}" = 1 ]; then
					[ "$rep" -ge 1 ] && [ "$rep" -le "$SLOW_REPS" ] || continue
				fi
				to=$TIMEOUT
				case ${ST_KEY[i]} in *.gdal) to=$GDAL_TIMEOUT ;; esac
				echo "SET statement_timeout = '${to}s';"
				echo "SELECT 'run', * FROM $S.time_run('${ST_KEY[i]}', $rep, \$bq\$${ST_Q[i]}\$bq\$, '${ST_KIND[i]}', $(tmpl_arg "${ST_TMPL[i]}"), $(target_arg "${ST_TARGET[i]}"));"
			done
		done
	} > "$WORK/cell.sql"
	log "$cell: ${ST_KEY[*]} x ($WARM + $REPS)"
	psql -X -q -A -t -F '|' -f "$WORK/cell.sql" > "$WORK/cell.out" 2> "$WORK/cell.err" || true
	if grep -q . "$WORK/cell.err"; then
		log "  psql said: $(head -3 "$WORK/cell.err" | tr '\n' ' ')"
	fi
	declare -A PLAN=()
	while IFS='|' read -r tag key plan; do
		[ "$tag" = plan ] && PLAN[$key]=$plan
	done < "$WORK/cell.out"
	for ((i = 0; i < nst; i++)); do
		key=${ST_KEY[i]}
		first=$((1 - WARM)) last=$REPS
		[ "${ST_SLOW[i]}" = 1 ] && first=1 last=$SLOW_REPS
		for rep in $(seq "$first" "$last"); do
			line=$(awk -F'|' -v s="$key" -v r="$rep" '$1 == "run" && $2 == s && $3 == r' "$WORK/cell.out")
			if [ -n "$line" ]; then
				IFS='|' read -r _ _ _ ms res st msg <<< "$line"
				[ "$st" = ok ] || [ "$st" = skipped ] || log "  $key: $st after $(fmt_ms "$ms"): $msg"
			else
				ms="" res="" st=error
				msg=$(grep -m1 -E 'FATAL|ERROR|server closed|connection' "$WORK/cell.err" | sed 's/,/;/g' || true)
				[ -n "$msg" ] || msg="no output from psql"
			fi
			echo "$cell,$key,$rep,$ms,$res,$st,$msg,${PLAN[$key]:-}" >> "$RUNS"
		done
	done
	ST_KEY=() ST_KIND=() ST_Q=() ST_TMPL=() ST_TARGET=() ST_SLOW=()
}

# the interpolation statements over the samples table s_N into template TMPL
interp_stmts() {	# CELL N TMPL
	local c=$1 n=$2 tm=$3 t=$S.s_$2 slow=0
	[ "$n" -ge "$SLOW_N" ] && slow=1
	stmt "$c.gdal" raster "SELECT ST_InterpolateRaster(ST_Collect(geom), 'linear', \$1) FROM $t" "$tm" "" "$slow"
	stmt "$c.lin" raster "SELECT ST_TDCInterpolate(geom, \$1, 'linear') FROM $t" "$tm" "" 0
	stmt "$c.nn" raster "SELECT ST_TDCInterpolate(geom, \$1, 'natural_neighbor') FROM $t" "$tm" "" 0
	stmt "$c.dropin" raster "SELECT ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', \$1) FROM $t" "$tm" "" 0
}

# main
INTERVAL="" BASE=""
if has main; then
	ensure_samples "$N"
	ensure_target "$DRAPE_N" "$N"
	DRAPE_COUNT=$(sql -c "SELECT ST_NumGeometries(g) FROM $S.target_${DRAPE_N}_$N")
	read -r INTERVAL BASE < <(sql -F ' ' -c "SELECT (zmax - zmin) / $LEVELS, zmin + (zmax - zmin) / $LEVELS / 2 FROM $S.info WHERE name = 's_$N'")
	interp_stmts main "$N" main
	stmt main.drape value "SELECT ST_TDCDrape(geom, \$2) IS NOT NULL FROM $S.s_$N" "" "target_${DRAPE_N}_$N" 0
	stmt main.contours value "SELECT ST_TDCContours(geom, $INTERVAL, $BASE) IS NOT NULL FROM $S.s_$N" "" "" 0
	stmt main.delaunay value "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM $S.s_$N" "" "" 0
	run_cell main
fi

# the sweep: one aggregate over a whole table
AGG_NS=()
if has agg; then
	for nl in $SIZES; do
		n=$(n_of "$nl")
		[ "$n" -ge 3 ] || die "BENCH_TIN_SIZES: $nl is below 3"
		AGG_NS+=("$n")
		if [ "$n" = "$N" ] && has main; then
			continue
		fi
		ensure_samples "$n"
		interp_stmts "agg$n" "$n" agg
		run_cell "agg$n"
	done
fi

# per row and per group
ROW_KS=() GRP_KS=()
declare -A ROW_R=() GRP_G=()
if has row; then
	for kr in $ROW_SIZES; do
		k=$(n_of "${kr%%:*}") r=$(n_of "${kr#*:}")
		ROW_KS+=("$k") ROW_R[$k]=$r
		ensure_rows "$k" "$r"
		stmt "row$k.gdal" value "SELECT count(ST_InterpolateRaster(g, 'linear', \$1)) FROM $S.rows_${k}_$r" row "" 0
		stmt "row$k.dropin" value "SELECT count(ST_TDCInterpolateRaster(g, 'linear', \$1)) FROM $S.rows_${k}_$r" row "" 0
		run_cell "row$k"
	done
fi
if has group; then
	for kg in $GRP_SIZES; do
		k=$(n_of "${kg%%:*}") g=$(n_of "${kg#*:}")
		GRP_KS+=("$k") GRP_G[$k]=$g
		ensure_groups "$k" "$g"
		t=$S.grp_${k}_$g
		stmt "grp$k.gdal" value "SELECT count(r) FROM (SELECT ST_InterpolateRaster(ST_Collect(geom), 'linear', \$1) r FROM $t GROUP BY grp) s" row "" 0
		stmt "grp$k.lin" value "SELECT count(r) FROM (SELECT ST_TDCInterpolate(geom, \$1, 'linear') r FROM $t GROUP BY grp) s" row "" 0
		stmt "grp$k.dropin" value "SELECT count(r) FROM (SELECT ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', \$1) r FROM $t GROUP BY grp) s" row "" 0
		run_cell "grp$k"
	done
fi
bench_end
SO_END=$(so_id)
[ "$SO_START" = "$SO_END" ] || log "WARNING: $SO changed during the run ($SO_START -> $SO_END)"

# ---------------------------------------------------------------- checks
# status KEY: ok when at least one run of KEY succeeded
ok_runs() { awk -F, -v k="$1" 'NR > 1 && $2 == k && $6 == "ok"' "$RUNS" | grep -c . || true; }
is_ok() { [ "$(ok_runs "$1")" -gt 0 ]; }
kept() { echo "(SELECT r FROM $S.kept WHERE key = '$1')"; }

echo "name,status,detail" > "$CHECKS"
NFAIL=0
# check NAME SQL: SQL returns one row: status (ok or FAIL), detail
check() {
	local name=$1 q=$2 out st detail t0=$SECONDS
	if ! out=$({ echo "SET statement_timeout = '${TIMEOUT}s';"; printf '%s' "$SET_SQL"; echo "$q"; } |
		psql -X -q -A -t -F '|' -v ON_ERROR_STOP=1 2>&1); then
		st=FAIL detail="the check failed: $(tr '\n' ' ' <<< "$out" | cut -c1-300)"
	else
		out=$(tail -1 <<< "$out")
		st=${out%%|*} detail=${out#*|}
		[ -n "$out" ] || { st=FAIL; detail="no answer"; }
	fi
	[ "$st" = ok ] || { NFAIL=$((NFAIL + 1)); log "CHECK FAILED: $name: $detail"; }
	log "  $st ($((SECONDS - t0)) s): $name"
	echo "${name//,/;},$st,${detail//,/;}" >> "$CHECKS"
}
skip_check() { echo "${1//,/;},skipped,${2//,/;}" >> "$CHECKS"; }

# ours against GDAL, pixel by pixel (CELL NAME INFO)
check_vs_gdal() {
	local c=$1 what=$2 info=$3
	if is_ok "$c.lin" && is_ok "$c.gdal"; then
		check "$what: ST_TDCInterpolate linear = ST_InterpolateRaster linear" "
SELECT CASE WHEN c.differ_inside = 0 THEN 'ok' ELSE 'FAIL' END,
	   format('%s pixels; %s differ by more than 1e-9 relative, %s of them inside the hull; elsewhere at most %s relative',
			  c.pixels, c.differ, c.differ_inside, btrim(to_char(c.max_rel, '9.9EEEE')))
FROM $S.cmp($(kept "$c.lin"), $(kept "$c.gdal"), (SELECT hull FROM $S.info WHERE name = '$info')) c;"
	else
		skip_check "$what: ST_TDCInterpolate linear = ST_InterpolateRaster linear" "a statement failed"
	fi
	if is_ok "$c.lin" && is_ok "$c.dropin"; then
		check "$what: ST_TDCInterpolateRaster = ST_TDCInterpolate byte for byte" "
SELECT CASE WHEN ST_AsBinary(a) = ST_AsBinary(b) THEN 'ok' ELSE 'FAIL' END, md5(ST_AsBinary(a)) || ' and ' || md5(ST_AsBinary(b))
FROM (SELECT $(kept "$c.dropin") a, $(kept "$c.lin") b) s;"
	fi
}

log "checks"
# every run of a statement gave the same answer: the same raster (md5 of its
# WKB), true for the IS NOT NULL forms, a raster per row or group
same_answers() {
	local k c bad=0 nk=0 nr=0 detail="" want res
	for k in $(awk -F, 'NR > 1 && $6 == "ok" { print $2 }' "$RUNS" | sort -u); do
		nk=$((nk + 1))
		nr=$((nr + $(ok_runs "$k")))
		case $k in
			main.drape | main.contours | main.delaunay) want=true ;;
			row*) c=${k#row} want=${ROW_R[${c%%.*}]:-} ;;
			grp*) c=${k#grp} want=${GRP_G[${c%%.*}]:-} ;;
			*) want="" ;;
		esac
		while read -r res; do
			if [ -n "$want" ] && [ "$res" != "$want" ]; then
				bad=$((bad + 1)) detail+=" $k gave '$res' (expected $want);"
			fi
		done < <(awk -F, -v k="$k" 'NR > 1 && $2 == k && $6 == "ok" { print $5 }' "$RUNS" | sort -u)
		if [ "$(awk -F, -v k="$k" 'NR > 1 && $2 == k && $6 == "ok" { print $5 }' "$RUNS" | sort -u | grep -c .)" -gt 1 ]; then
			bad=$((bad + 1)) detail+=" $k gave different answers in different runs;"
		fi
	done
	local st=ok
	[ "$bad" = 0 ] || { st=FAIL; NFAIL=$((NFAIL + 1)); log "CHECK FAILED: the same answer in every run:$detail"; }
	echo "every run of a statement gives the same answer,$st,$nr runs of $nk statements: every raster the same (md5 of its WKB) in every run; the IS NOT NULL forms true; a raster for every row or group${detail//,/;}" >> "$CHECKS"
}
same_answers
if has main; then
	check_vs_gdal main "main" "s_$N"
	for m in lin nn; do
		is_ok "main.$m" || continue
		check "main: $([ $m = lin ] && echo linear || echo 'natural neighbour') against the terrain" "
SELECT CASE WHEN t.nodata = 0 AND t.rms < 0.01 * (i.zmax - i.zmin) THEN 'ok' ELSE 'FAIL' END,
	   format('%s pixel centres in the hull, %s nodata; RMS error %s, largest %s (heights span %s)',
			  t.pixels, t.nodata, btrim(to_char(t.rms, '9.99EEEE')), btrim(to_char(t.maxerr, '9.99EEEE')), round((i.zmax - i.zmin)::numeric, 1))
FROM $S.info i, $S.truth($(kept "main.$m"), i.hull) t WHERE i.name = 's_$N';"
	done
	if is_ok main.drape; then
		log "  drape: the target, and pixel centres against $(is_ok main.gdal && echo GDAL || echo 'our linear raster')"
		TG=target_${DRAPE_N}_$N
		check "main: the drape against the terrain" "
SELECT 'check', (r).status, (r).ms FROM (SELECT $S.time_run('check.drape', 0, 'SELECT ST_TDCDrape(geom, \$2) FROM $S.s_$N', 'geometry', NULL, (SELECT g FROM $S.$TG)) r) s \\g /dev/null
WITH d AS (SELECT (ST_DumpPoints(g)).geom AS p FROM $S.kept WHERE key = 'check.drape')
SELECT CASE WHEN nd = $DRAPE_COUNT AND nz = nd AND rms < 0.01 * (i.zmax - i.zmin) THEN 'ok' ELSE 'FAIL' END,
	   format('%s of %s points draped, %s with Z; RMS error %s, largest %s', nd, $DRAPE_COUNT, nz,
			  btrim(to_char(rms, '9.99EEEE')), btrim(to_char(maxerr, '9.99EEEE')))
FROM (SELECT count(*) nd, count(ST_Z(p)) nz, sqrt(avg((ST_Z(p) - $S.terrain(ST_X(p), ST_Y(p)))^2)) rms,
			 max(abs(ST_Z(p) - $S.terrain(ST_X(p), ST_Y(p)))) maxerr FROM d) s, $S.info i WHERE i.name = 's_$N';"
		ref=main.gdal
		is_ok main.gdal || ref=main.lin
		if is_ok "$ref"; then
			stride=$(( PIX * PIX / 10000 + 7 ))
			check "main: the drape at pixel centres = $([ $ref = main.gdal ] && echo "ST_InterpolateRaster's" || echo "ST_TDCInterpolate's") pixels" "
CREATE TEMP TABLE px AS
SELECT row_number() OVER (ORDER BY p.i) AS k, p.x, p.y, p.v
FROM $S.pixels($(kept $ref)) p, $S.info h
WHERE h.name = 's_$N' AND p.i % $stride = 0 AND ST_Intersects(h.hull, ST_MakePoint(p.x, p.y))
	  AND ST_Distance(ST_MakePoint(p.x, p.y), ST_Boundary(h.hull)) > 1e-6;
SELECT (r).status FROM (SELECT $S.time_run('check.drape_px', 0, 'SELECT ST_TDCDrape(geom, \$2) FROM $S.s_$N', 'geometry', NULL,
										 (SELECT ST_Collect(ST_MakePoint(x, y) ORDER BY k) FROM px)) r) s \\g /dev/null
WITH d AS (SELECT (dp).path[1] AS k, (dp).geom AS p FROM (SELECT ST_DumpPoints(g) dp FROM $S.kept WHERE key = 'check.drape_px') s)
SELECT CASE WHEN count(*) = (SELECT count(*) FROM px) AND count(*) FILTER (WHERE bad) = 0 THEN 'ok' ELSE 'FAIL' END,
	   format('%s pixel centres (every %s-th pixel in the hull), %s beyond 1e-9 relative, at most %s relative',
			  count(*), $stride, count(*) FILTER (WHERE bad), btrim(to_char(max(rel), '9.9EEEE')))
FROM (SELECT NOT coalesce(ST_X(d.p) = px.x AND ST_Y(d.p) = px.y AND abs(ST_Z(d.p) - px.v) <= 1e-9 * abs(px.v), false) AS bad,
			 abs(ST_Z(d.p) - px.v) / nullif(abs(px.v), 0) AS rel
	  FROM d JOIN px USING (k)) s;"
		fi
	fi
	if is_ok main.contours; then
		check "main: $LEVELS contour levels" "
SELECT (r).status FROM (SELECT $S.time_run('check.contours', 0, 'SELECT ST_TDCContours(geom, $INTERVAL, $BASE) FROM $S.s_$N', 'geometry', NULL, NULL) r) s \\g /dev/null
WITH l AS (SELECT (ST_Dump(g)).geom AS l FROM $S.kept WHERE key = 'check.contours'),
	 z AS (SELECT l, ST_ZMin(l) AS z, ST_ZMax(l) AS z1 FROM l)
SELECT CASE WHEN count(DISTINCT z) = $LEVELS AND count(*) FILTER (WHERE z <> z1) = 0
				 AND count(*) FILTER (WHERE z <> $BASE + round((z - $BASE) / $INTERVAL) * $INTERVAL) = 0 THEN 'ok' ELSE 'FAIL' END,
	   format('%s lines (%s closed), %s levels from %s to %s, %s lines not flat, %s off base + k * interval; length %s',
			  count(*), count(*) FILTER (WHERE ST_IsClosed(l)), count(DISTINCT z), round(min(z)::numeric, 3), round(max(z)::numeric, 3),
			  count(*) FILTER (WHERE z <> z1), count(*) FILTER (WHERE z <> $BASE + round((z - $BASE) / $INTERVAL) * $INTERVAL),
			  round(sum(ST_Length(l))::numeric))
FROM z;"
	fi
	if is_ok main.delaunay; then
		check "main: ST_TDCDelaunay gives 2n - 2 - h triangles" "
SELECT CASE WHEN t = 2 * i.n - 2 - i.h THEN 'ok' ELSE 'FAIL' END, format('%s triangles, 2n - 2 - h = %s (n = %s, h = %s)', t, 2 * i.n - 2 - i.h, i.n, i.h)
FROM (SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) t FROM $S.s_$N) s, $S.info i WHERE i.name = 's_$N';"
	fi
fi
for n in "${AGG_NS[@]}"; do
	[ "$n" = "$N" ] && has main && continue
	check_vs_gdal "agg$n" "sweep n = $n" "s_$n"
done
for k in "${ROW_KS[@]}"; do
	t=$S.rows_${k}_${ROW_R[$k]}
	check "per row of $k samples: ST_TDCInterpolateRaster = ST_InterpolateRaster (linear)" "
SELECT CASE WHEN sum(c.differ_inside) = 0 AND count(*) = ${ROW_R[$k]} THEN 'ok' ELSE 'FAIL' END,
	   format('%s rows, %s pixels; %s differ by more than 1e-9 relative, %s of them inside the hull; elsewhere at most %s relative',
			  count(*), sum(c.pixels), sum(c.differ), sum(c.differ_inside), btrim(to_char(max(c.max_rel), '9.9EEEE')))
FROM $t, (SELECT r FROM $S.tmpl WHERE name = 'row') tm,
	 LATERAL $S.cmp(ST_TDCInterpolateRaster(g, 'linear', tm.r), ST_InterpolateRaster(g, 'linear', tm.r), ST_ConvexHull(g)) c;"
done
for k in "${GRP_KS[@]}"; do
	t=$S.grp_${k}_${GRP_G[$k]}
	check "per group of $k samples: ST_TDCInterpolate = ST_InterpolateRaster (linear) and = ST_TDCInterpolateRaster" "
SELECT CASE WHEN sum(c.differ_inside) = 0 AND count(*) = ${GRP_G[$k]} AND count(*) FILTER (WHERE ST_AsBinary(a) <> ST_AsBinary(d)) = 0
			THEN 'ok' ELSE 'FAIL' END,
	   format('%s groups, %s pixels; %s differ by more than 1e-9 relative, %s of them inside the hull; elsewhere at most %s relative; %s aggregate rasters differ from the drop-in''s',
			  count(*), sum(c.pixels), sum(c.differ), sum(c.differ_inside), btrim(to_char(max(c.max_rel), '9.9EEEE')),
			  count(*) FILTER (WHERE ST_AsBinary(a) <> ST_AsBinary(d)))
FROM (SELECT grp, ST_TDCInterpolate(geom, (SELECT r FROM $S.tmpl WHERE name = 'row'), 'linear') a,
			 ST_InterpolateRaster(ST_Collect(geom), 'linear', (SELECT r FROM $S.tmpl WHERE name = 'row')) b,
			 ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', (SELECT r FROM $S.tmpl WHERE name = 'row')) d,
			 ST_ConvexHull(ST_Collect(geom)) h
	  FROM $t GROUP BY grp) s, LATERAL $S.cmp(a, b, h) c;"
done

# ---------------------------------------------------------------- summary
vals() { awk -F, -v k="$1" 'NR > 1 && $2 == k && $3 >= 1 && $6 == "ok" { print $4 }' "$RUNS"; }
failure_of() { awk -F, -v k="$1" 'NR > 1 && $2 == k && ($6 == "error" || $6 == "timeout") { print $6 "|" $4 "|" $7; exit }' "$RUNS"; }
plan_of() { awk -F, -v k="$1" 'NR > 1 && $2 == k { print $8; exit }' "$RUNS"; }
ratio() { [ -n "$1" ] && [ -n "$2" ] && awk -v a="$1" -v b="$2" 'BEGIN { printf "%.3g", a / b }'; }
declare -A MED=() LOW=()
NOTES=()
echo "key,median_ms,min_ms,max_ms,runs,status,plan" > "$CSV"
# stat KEY: MED[KEY] (median, or empty), LOW[KEY] (a failed run's elapsed
# time: a lower bound when it timed out), and the CSV line
stat() {
	local k=$1 med mn mx nr f st=ok plan
	med=$(vals "$k" | median)
	mn=$(vals "$k" | sort -g | head -1)
	mx=$(vals "$k" | sort -g | tail -1)
	nr=$(vals "$k" | grep -c . || true)
	f=$(failure_of "$k")
	plan=$(plan_of "$k")
	MED[$k]=$med
	LOW[$k]=""
	if [ -n "$f" ]; then
		st=${f%%|*}
		[ "$st" = timeout ] && LOW[$k]=$(cut -d'|' -f2 <<< "$f")
		NOTES+=("\`$k\`: $st after $(fmt_ms "$(cut -d'|' -f2 <<< "$f")"): $(cut -d'|' -f3 <<< "$f")")
	fi
	[ -n "$plan" ] && [ "$plan" != serial ] && NOTES+=("\`$k\`: plan $plan")
	echo "$k,$med,$mn,$mx,$nr,$st,$plan" >> "$CSV"
	STAT_CELL_RANGE=$([ -n "$mn" ] && echo "$(fmt_ms "$mn") - $(fmt_ms "$mx")" || echo -) STAT_CELL_N=$nr
}
# shown KEY: the median, or what happened instead
shown() {
	if [ -n "${MED[$1]}" ]; then
		fmt_ms "${MED[$1]}"
	elif [ -n "${LOW[$1]}" ]; then
		echo "> $(fmt_ms "${LOW[$1]}") (timed out)"
	elif [ -n "$(failure_of "$1")" ]; then
		echo "error"
	else
		echo "-"
	fi
}
# speedup GDAL OURS: GDAL's median / ours, "> x" when GDAL timed out
speedup() {
	if [ -n "${MED[$1]}" ] && [ -n "${MED[$2]}" ]; then
		echo "$(ratio "${MED[$1]}" "${MED[$2]}")x"
	elif [ -n "${LOW[$1]}" ] && [ -n "${MED[$2]}" ]; then
		echo "> $(ratio "${LOW[$1]}" "${MED[$2]}")x"
	else
		echo "-"
	fi
}

THREADS=$(sql -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)') IS NOT NULL" -c "SELECT current_setting('tdc_delaunay.threads', true)" | tail -1)
setting() { sql -c "$SET_SQL" -c "SELECT current_setting('$1', true)" | tail -1; }
{
	echo "- server: $PG_VER, PostGIS $PGIS_VER ($GDAL_VER), tdc_delaunay $TDC_VER (git $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo '?'); $SO: $SO_START)"
	if [ "$SO_START" != "$SO_END" ]; then
		echo "- **WARNING: tdc_delaunay.so was replaced during the run ($SO_START -> $SO_END): the figures mix two builds; run again.**"
	fi
	echo "- settings: jit=$(setting jit) max_parallel_workers_per_gather=$(setting max_parallel_workers_per_gather) tdc_delaunay.threads=${THREADS:-?} (0: all cores; GDAL's gridding is single-threaded) shared_buffers=$(setting shared_buffers) work_mem=$(setting work_mem) statement_timeout=${TIMEOUT}s, ${GDAL_TIMEOUT}s for ST_InterpolateRaster${SETTINGS:+ (set for the runs: $SETTINGS)}"
	echo "- timing: server side (clock_timestamp() around EXECUTE in plpgsql, the template and target as parameters), one session per workload and size, each statement run $WARM time(s) untimed first, then $REPS rounds of all statements interleaved; ST_InterpolateRaster at $(thousands "$SLOW_N") samples or more $SLOW_REPS time(s), no warm-up; medians (min - max). Samples: a known terrain at uniform random points of [0, 1000)^2, one POINT Z per row; templates 64BF over [0, 1000]^2."
	echo "- ST_InterpolateRaster gives GDAL no progress callback, so GDAL's gridding cannot be interrupted: a statement_timeout that falls inside it takes effect only once it has finished. A run that timed out shows \"> the time until it stopped\"."
	echo "- checked: every answer timed here (see Checks): ours linear against GDAL's pixel by pixel, the terrain, the contour levels, the triangle count."
} > "$TXT"

if has main; then
	{
		echo
		echo "### $(thousands "$N") samples into $PIX x $PIX pixels, $(thousands "${DRAPE_COUNT:-0}") draped points, $LEVELS contour levels"
		echo
		echo "| statement | median | min - max | runs | ST_InterpolateRaster / this |"
		echo "|---|--:|--:|--:|--:|"
	} >> "$TXT"
	main_row() {	# KEY NAME [ratio]
		local k=$1
		stat "$k"
		printf '| %s | %s | %s | %s | %s |\n' "$2" "$(shown "$k")" "$STAT_CELL_RANGE" "$STAT_CELL_N" \
			"$([ "${3:-}" = ratio ] && speedup main.gdal "$k" || echo -)" >> "$TXT"
	}
	main_row main.gdal "PostGIS \`ST_InterpolateRaster(ST_Collect(geom), 'linear', t)\`" ratio
	main_row main.lin "\`ST_TDCInterpolate(geom, t, 'linear')\` (aggregate)" ratio
	main_row main.nn "\`ST_TDCInterpolate(geom, t, 'natural_neighbor')\` (aggregate)" ratio
	main_row main.dropin "\`ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', t)\` (drop-in)" ratio
	main_row main.drape "\`ST_TDCDrape(geom, target)\`, target: $(thousands "${DRAPE_COUNT:-0}") held-out points"
	main_row main.contours "\`ST_TDCContours(geom, interval, base)\`, $LEVELS levels"
	main_row main.delaunay "\`ST_TDCDelaunay(geom)\` (our Delaunay aggregate)"
	at_size=""
	[ "$N" = 1000000 ] && [ "$PIX" = 1000 ] || at_size=" (this run: $(thousands "$N") samples, $PIX x $PIX pixels; the acceptance is stated at 1,000,000 and 1000 x 1000)"
	sp=$(speedup main.gdal main.lin)
	acc1="-"
	if [ -n "${MED[main.lin]}" ]; then
		if [ -n "${MED[main.gdal]}" ]; then
			acc1=$(awk -v a="${MED[main.gdal]}" -v b="${MED[main.lin]}" 'BEGIN { print (a / b >= 20 ? "met" : "**not met**") }')
		elif [ -n "${LOW[main.gdal]}" ]; then
			acc1=$(awk -v a="${LOW[main.gdal]}" -v b="${MED[main.lin]}" 'BEGIN { print (a / b >= 20 ? "met (GDAL timed out: a lower bound)" : "not known: GDAL timed out before 20x") }')
		fi
	fi
	acc2="-"
	cr=""
	if [ -n "${MED[main.contours]}" ] && [ -n "${MED[main.delaunay]}" ]; then
		cr=$(ratio "${MED[main.contours]}" "${MED[main.delaunay]}")
		acc2=$(awk -v r="$cr" 'BEGIN { print (r <= 2 ? "met" : "**not met**") }')
	fi
	{
		echo
		echo "Acceptance (issue 29)$at_size:"
		echo "- \`ST_TDCInterpolate(..., 'linear')\` against \`ST_InterpolateRaster(..., 'linear', ...)\`: ${sp} (at least 20x): $acc1"
		echo "- \`ST_TDCContours\` at $LEVELS levels against the Delaunay aggregate on the same rows: $([ -n "$cr" ] && echo "${cr}x" || echo -) (at most 2x): $acc2"
	} >> "$TXT"
fi

if has agg || has row || has group; then
	{
		echo
		echo "### Size sweep: the interpolation against ST_InterpolateRaster, 'linear'"
		echo
		echo "| workload | samples per call | calls | pixels per call | PostGIS \`ST_InterpolateRaster\` | ours | statement | PostGIS / ours |"
		echo "|---|--:|--:|--:|--:|--:|---|--:|"
	} >> "$TXT"
	sweep_row() {	# WORKLOAD K CALLS W GDALKEY OURKEY NAME
		printf '| %s | %s | %s | %s x %s | %s | %s | %s | %s |\n' "$1" "$(thousands "$2")" "$(thousands "$3")" "$4" "$4" \
			"$(shown "$5")" "$(shown "$6")" "$7" "$(speedup "$5" "$6")" >> "$TXT"
	}
	for n in "${AGG_NS[@]}"; do
		c=agg$n w=$SWEEP_PIX
		if [ "$n" = "$N" ] && has main; then c=main w=$PIX; fi
		for s in gdal lin nn dropin; do [ "$c" = main ] || stat "$c.$s"; done
		sweep_row "one aggregate" "$n" 1 "$w" "$c.gdal" "$c.lin" "\`ST_TDCInterpolate(geom, t, 'linear')\`"
		sweep_row "one aggregate" "$n" 1 "$w" "$c.gdal" "$c.nn" "\`ST_TDCInterpolate(geom, t, 'natural_neighbor')\`"
		sweep_row "one aggregate" "$n" 1 "$w" "$c.gdal" "$c.dropin" "\`ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', t)\`"
	done
	for k in "${ROW_KS[@]}"; do
		for s in gdal dropin; do stat "row$k.$s"; done
		sweep_row "per row (MULTIPOINT Z)" "$k" "${ROW_R[$k]}" "$ROW_PIX" "row$k.gdal" "row$k.dropin" "\`ST_TDCInterpolateRaster(g, 'linear', t)\`"
	done
	for k in "${GRP_KS[@]}"; do
		for s in gdal lin dropin; do stat "grp$k.$s"; done
		sweep_row "per group (GROUP BY)" "$k" "${GRP_G[$k]}" "$ROW_PIX" "grp$k.gdal" "grp$k.lin" "\`ST_TDCInterpolate(geom, t, 'linear')\`"
		sweep_row "per group (GROUP BY)" "$k" "${GRP_G[$k]}" "$ROW_PIX" "grp$k.gdal" "grp$k.dropin" "\`ST_TDCInterpolateRaster(ST_Collect(geom), 'linear', t)\`"
	done
	echo >> "$TXT"
	echo "Times per statement (all calls). PostGIS per row: \`ST_InterpolateRaster(g, 'linear', t)\`; per group and over the table: \`ST_InterpolateRaster(ST_Collect(geom), 'linear', t)\`." >> "$TXT"
fi

{
	echo
	echo "### Checks"
	echo
	echo "| check | result | figures |"
	echo "|---|---|---|"
	tail -n +2 "$CHECKS" | while IFS=, read -r name st detail; do
		[ "$st" = ok ] || st="**$st**"
		printf '| %s | %s | %s |\n' "$name" "$st" "$detail"
	done
	if [ ${#NOTES[@]} -gt 0 ]; then
		echo
		for note in "${NOTES[@]}"; do echo "- $note"; done
	fi
} >> "$TXT"

bench_publish tin "The TIN in SQL: interpolation, draping and contours against PostGIS ST_InterpolateRaster" "$TXT"
cat "$TXT"
log "wrote $RUNS, $CSV, $CHECKS, $TXT"
if [ "$NFAIL" -gt 0 ]; then
	die "$NFAIL check(s) failed: the figures above time a wrong answer somewhere"
fi
