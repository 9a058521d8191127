#!/usr/bin/env bash
# test/upgrade.sh: a database made with an older tdc_delaunay (0.1.0, 1.0.0
# and 1.1.0) goes on working with the new library, and ALTER EXTENSION
# tdc_delaunay UPDATE brings it to exactly what a fresh install of the
# default version makes.  For each older version:
#
#   1. CREATE EXTENSION tdc_delaunay VERSION 'FROM' CASCADE in a new
#      database, and on it a view, a table (CREATE TABLE AS) and a
#      materialized view that use every function family; their results,
#      with the new library and the old SQL objects, are kept as digests;
#   2. ALTER EXTENSION tdc_delaunay UPDATE;
#   3. the catalogue equals a fresh install's in another database: every
#      function, aggregate and procedure of the extension with its argument
#      and result types, defaults, volatility, parallel safety, strictness,
#      cost, rows, security, settings, symbol or body, access and comment;
#      every aggregate's support functions, state type and initial values;
#      every other member object (compared as sorted text, diff on failure);
#   4. the view, the table and the materialized view give the same rows as
#      before the update, and so does the materialized view refreshed;
#   5. what the updates added (1.1.0: ST_TDCContours and ST_TDCDrape; 1.2.0:
#      ST_TDCContours with a method, max_edge) gives in the updated database
#      what it gives in the fresh one;
#   6. tdc_delaunay_raster installs on the updated database, and
#      tdc_delaunay never created postgis_raster; its 1.1.0 updated to its
#      default version has a fresh install's routines;
#   7. what 1.2.0 changed (tdc_delaunay_tiled with a tile column, in one C
#      function) gives in the updated database what it gives in the fresh
#      one.
#
#   PGHOST=... PGPORT=... PGUSER=... bash test/upgrade.sh
# Needs a superuser (scripts/test.sh: its throw-away cluster); makes and
# drops the databases tdc_upgrade_old_* and tdc_upgrade_new.
# Prints "N passed, N failed".  About 20 s.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/db_lib.sh
source "$HERE/db_lib.sh"

NEW=tdc_upgrade_new
# Every older version a database may be at: each is installed, used, updated.
FROMS=(0.1.0 1.0.0 1.1.0)

db_require_server
TO=$(q postgres -c "SELECT default_version FROM pg_available_extensions WHERE name = 'tdc_delaunay'")
fresh_db "$NEW"
q "$NEW" -c "CREATE EXTENSION tdc_delaunay CASCADE" >/dev/null

# What 1.1.0 and 1.2.0 added, as text: the same in an updated and in a fresh
# database.
TIN_PROBE="
SELECT ST_AsText(ST_TDCContours(ST_MakePoint(x, y, x * y), 1.5, 0.25))
  FROM generate_series(0, 4) x, generate_series(0, 3) y
UNION ALL
SELECT ST_AsText(ST_TDCDrape(ST_MakePoint(x, y, x * y), 'LINESTRING(0.5 0.5, 3.5 2.5)'))
  FROM generate_series(0, 4) x, generate_series(0, 3) y
UNION ALL
SELECT ST_AsText(ST_TDCDrape(ST_MakePoint(x, y, x * y), 'POINT(1.5 1.25)', 'natural_neighbor'))
  FROM generate_series(0, 4) x, generate_series(0, 3) y
UNION ALL
SELECT ST_AsText(ST_TDCContours(ST_MakePoint(x, y, x * y), 1.5, 0.25, 'linear:max_edge=1.5'))
  FROM generate_series(0, 4) x, generate_series(0, 3) y WHERE (x, y) <> (2, 1)"

upgrade_from() {
local FROM=$1
local OLD=tdc_upgrade_old_${1//./_}

echo "== upgrade.sh: tdc_delaunay $FROM, then ALTER EXTENSION UPDATE"
fresh_db "$OLD"

q "$OLD" -c "CREATE EXTENSION tdc_delaunay VERSION '$FROM' CASCADE" -c "$TEST_DATA" >/dev/null
same "the old database is at $FROM" "$FROM" \
	"$(q "$OLD" -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")"

# What depends on the extension: every function family, in a view, a table
# and a materialized view (the Dumps' queries schema-qualified).
q "$OLD" >/dev/null <<'SQL'
CREATE VIEW v_families AS
	SELECT 'triangles' AS f, grp, (ST_Dump(ST_TDCDelaunayTriangles(ST_Collect(geom)))).geom FROM pts GROUP BY grp
	UNION ALL SELECT 'edges', 0, ST_TDCDelaunayTriangles(ST_Collect(geom), 0.0, 1) FROM pts
	UNION ALL SELECT 'aggregate', grp, (ST_Dump(ST_TDCDelaunay(geom))).geom FROM pts GROUP BY grp
	UNION ALL SELECT 'aggregate tin', 0, ST_TDCDelaunay(geom, 0.5, 2) FROM pts
	UNION ALL SELECT 'voronoi', 0, (ST_Dump(ST_TDCVoronoiPolygons(ST_Collect(geom)))).geom FROM pts
	UNION ALL SELECT 'voronoi lines', 0, ST_TDCVoronoiLines(ST_Collect(geom), 0.0, ST_MakeEnvelope(-50, -50, 150, 150, 4326)) FROM pts
	UNION ALL SELECT 'voronoi aggregate', 0, (ST_Dump(ST_TDCVoronoi(geom))).geom FROM pts
	UNION ALL SELECT 'constrained', 0, (ST_Dump(ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom)))).geom FROM lines
	UNION ALL SELECT 'constrained aggregate', 0, ST_TDCConstrainedDelaunay(geom, 5) FROM lines;
CREATE TABLE t_dump AS
	SELECT 'delaunay' AS f, id, geom FROM ST_TDCDelaunayDump('SELECT geom FROM public.pts')
	UNION ALL SELECT 'constrained', id, geom FROM ST_TDCConstrainedDelaunayDump('SELECT geom FROM public.lines');
CREATE MATERIALIZED VIEW mv_voronoi AS
	SELECT id, geom FROM ST_TDCVoronoiDump('SELECT id::bigint, geom FROM public.pts')
	UNION ALL SELECT -1, ST_TDCVoronoi(geom, 0.0, ST_MakeEnvelope(-50, -50, 150, 150, 4326)) FROM pts;
CALL tdc_delaunay_tiled('pts', 'tiled', tile_size => 30);
SQL

OBJECTS=(v_families t_dump mv_voronoi tiled)
take_digests "$OLD" "${OBJECTS[@]}"
# The tiled triangulation and the Dump have the same triangles.
same "tdc_delaunay_tiled's triangles are ST_TDCDelaunayDump's" \
	"$(digest "$OLD" "SELECT ST_Normalize(geom) FROM t_dump WHERE f = 'delaunay'")" \
	"$(digest "$OLD" "SELECT ST_Normalize(geom) FROM tiled")"

# The new library behind the old SQL objects reports the difference.
out=$(q "$OLD" -c "SET client_min_messages = warning" \
	-c "CREATE FUNCTION pg_temp.full_version() RETURNS text AS '\$libdir/tdc_delaunay', 'tdc_delaunay_full_version' LANGUAGE C" \
	-c "SELECT pg_temp.full_version()" 2>&1)
check "with the $FROM SQL objects the library's report says EXTENSION=\"$FROM\" [needs ALTER EXTENSION ...]" \
	grep -q "EXTENSION=\"$FROM\" \[needs ALTER EXTENSION tdc_delaunay UPDATE\]" <<<"$out"
check "... with a WARNING and its HINT" grep -q "HINT:  Run ALTER EXTENSION tdc_delaunay UPDATE" <<<"$out"

check "ALTER EXTENSION tdc_delaunay UPDATE" q "$OLD" -c "ALTER EXTENSION tdc_delaunay UPDATE"
same "after ALTER EXTENSION UPDATE the old database is at $TO" "$TO" \
	"$(q "$OLD" -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")"

# The extension's catalogue as sorted text, one line per object.
CATALOGUE="
WITH members AS (
	SELECT d.classid, d.objid, d.objsubid
	  FROM pg_depend d JOIN pg_extension e ON e.oid = d.refobjid AND d.refclassid = 'pg_extension'::regclass
	 WHERE e.extname = 'tdc_delaunay' AND d.deptype = 'e')
SELECT format('%s %s(%s) RETURNS %s | kind %s volatile %s parallel %s strict %s cost %s rows %s secdef %s '
			  'leakproof %s lang %s bin %s config %s acl %s | %s | %s',
			  n.nspname, p.proname, pg_get_function_arguments(p.oid), coalesce(pg_get_function_result(p.oid), '-'),
			  p.prokind, p.provolatile, p.proparallel, p.proisstrict, p.procost, p.prorows, p.prosecdef,
			  p.proleakproof, l.lanname, p.probin, p.proconfig, p.proacl,
			  coalesce(obj_description(p.oid, 'pg_proc'), 'NO COMMENT'), md5(p.prosrc))
  FROM members m JOIN pg_proc p ON m.classid = 'pg_proc'::regclass AND p.oid = m.objid
  JOIN pg_namespace n ON n.oid = p.pronamespace JOIN pg_language l ON l.oid = p.prolang
UNION ALL
SELECT format('aggregate %s | kind %s transfn %s finalfn %s extra %s modify %s combinefn %s serialfn %s '
			  'deserialfn %s stype %s sspace %s initval %s msfunc %s minvfunc %s mfinalfn %s mstype %s '
			  'minitval %s sortop %s',
			  a.aggfnoid::regprocedure, a.aggkind, a.aggtransfn::oid::regprocedure,
			  a.aggfinalfn::oid::regprocedure, a.aggfinalextra, a.aggfinalmodify,
			  a.aggcombinefn::oid::regprocedure, a.aggserialfn::oid::regprocedure,
			  a.aggdeserialfn::oid::regprocedure, a.aggtranstype::regtype, a.aggtransspace, a.agginitval,
			  a.aggmtransfn::oid::regprocedure, a.aggminvtransfn::oid::regprocedure,
			  a.aggmfinalfn::oid::regprocedure, a.aggmtranstype::regtype, a.aggminitval, a.aggsortop)
  FROM members m JOIN pg_aggregate a ON m.classid = 'pg_proc'::regclass AND a.aggfnoid = m.objid
UNION ALL
SELECT 'member ' || pg_describe_object(m.classid, m.objid, m.objsubid) FROM members m
UNION ALL
SELECT format('extension %s schema %s relocatable %s config %s', e.extversion, e.extnamespace::regnamespace,
			  e.extrelocatable, e.extconfig)
  FROM pg_extension e WHERE e.extname = 'tdc_delaunay'
ORDER BY 1"
q "$OLD" -c "$CATALOGUE" >"$DB_WORK/updated.txt"
q "$NEW" -c "$CATALOGUE" >"$DB_WORK/fresh.txt"
nfun=$(grep -c ' RETURNS ' "$DB_WORK/fresh.txt" || true)
nagg=$(grep -c '^aggregate ' "$DB_WORK/fresh.txt" || true)
check "a fresh install has functions, aggregates and two procedures ($nfun routines, $nagg aggregates)" \
	test "$nfun" -gt 40 -a "$nagg" -ge 8 -a "$(grep -c ' kind p ' "$DB_WORK/fresh.txt")" = 2
if diff -u "$DB_WORK/fresh.txt" "$DB_WORK/updated.txt" >"$DB_WORK/catalogue.diff"; then
	pass "the updated catalogue equals a fresh $TO install ($(wc -l <"$DB_WORK/fresh.txt") lines)"
else
	fail "the updated catalogue differs from a fresh $TO install (- fresh, + updated):"
	sed 's/^/        /' "$DB_WORK/catalogue.diff"
fi
missing=$(grep -c 'NO COMMENT' "$DB_WORK/fresh.txt" || true)
same "every function, aggregate and procedure has a COMMENT" 0 "$missing"
((missing == 0)) || grep 'NO COMMENT' "$DB_WORK/fresh.txt" | sed 's/^/        /'

same_digests "$OLD" "after the update:" "${OBJECTS[@]}"
q "$OLD" -c "REFRESH MATERIALIZED VIEW mv_voronoi" >/dev/null
same_digests "$OLD" "after the update and a refresh:" mv_voronoi
out=$(q "$OLD" -c "SELECT tdc_delaunay_full_version()" 2>&1)
echo "  (tdc_delaunay_full_version(): $out)"
check "after the update the report says EXTENSION=\"$TO\"" grep -qF "EXTENSION=\"$TO\" PGSQL=" <<<"$out"
check "... with no warning" test -z "$(grep -e WARNING -e 'needs ALTER' <<<"$out")"
tin_old=$(q "$OLD" -c "$TIN_PROBE" 2>&1)
tin_new=$(q "$NEW" -c "$TIN_PROBE" 2>&1)
same "ST_TDCContours (with a method too) and ST_TDCDrape after the update from $FROM: as in a fresh install" \
	"$tin_new" "$tin_old"
check "... and they drew something" grep -q "MULTILINESTRING Z ((" <<<"$tin_new"

# The raster functions come as a second extension, which the update leaves
# alone: tdc_delaunay never needed postgis_raster, and tdc_delaunay_raster
# goes on top of the updated tdc_delaunay (CASCADE creates postgis_raster),
# every object commented, and runs.
same "tdc_delaunay did not create postgis_raster" 0 \
	"$(q "$OLD" -c "SELECT count(*) FROM pg_extension WHERE extname = 'postgis_raster'")"
check "CREATE EXTENSION tdc_delaunay_raster CASCADE on the database updated from $FROM" \
	q "$OLD" -c "SET client_min_messages = warning" -c "CREATE EXTENSION tdc_delaunay_raster CASCADE"
same "tdc_delaunay_raster's routines all have a COMMENT" 0 "$(q "$OLD" -c "
	SELECT count(*) FROM pg_depend d JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay_raster'
	 WHERE d.deptype = 'e' AND d.classid = 'pg_proc'::regclass AND obj_description(d.objid, 'pg_proc') IS NULL")"
same "ST_TDCInterpolateRaster on the database updated from $FROM" "32BF 2" "$(q "$OLD" -F ' ' -c "
	SELECT ST_BandPixelType(r), ST_Value(r, 1, 1, 1) FROM ST_TDCInterpolateRaster(
		'MULTIPOINT Z (0 0 2, 10 0 2, 0 10 2)', 'linear',
		ST_AddBand(ST_MakeEmptyRaster(5, 5, 0, 10, 2, -2, 0, 0, 0), '32BF'::text, 0::float8, -1::float8)) r")"
# tdc_delaunay_raster 1.1.0 updated to its default version (1.2.0 adds
# tdc_interpolate_tiled) equals a fresh install of it, routine by routine.
local raster_cat="SELECT format('%s kind %s vol %s par %s strict %s cost %s config %s src %s comment %s',
		p.oid::regprocedure, p.prokind, p.provolatile, p.proparallel, p.proisstrict, p.procost, p.proconfig,
		md5(p.prosrc), md5(coalesce(obj_description(p.oid, 'pg_proc'), '')))
	  FROM pg_depend d JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay_raster'
	  JOIN pg_proc p ON p.oid = d.objid
	 WHERE d.deptype = 'e' AND d.classid = 'pg_proc'::regclass ORDER BY 1"
check "tdc_delaunay_raster 1.1.0 updated on the database updated from $FROM" \
	q "$OLD" -c "SET client_min_messages = warning" -c "DROP EXTENSION tdc_delaunay_raster" \
	-c "CREATE EXTENSION tdc_delaunay_raster VERSION '1.1.0'" -c "ALTER EXTENSION tdc_delaunay_raster UPDATE"
q "$NEW" -c "SET client_min_messages = warning" -c "CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE" >/dev/null
same "... its routines equal a fresh install's" "$(q "$NEW" -c "$raster_cat")" "$(q "$OLD" -c "$raster_cat")"
check "... with tdc_interpolate_tiled" grep -q "^tdc_interpolate_tiled(" <<<"$(q "$OLD" -c "$raster_cat")"

# 1.2.0: a tile column labels the triangles of the one C function
local tiled_probe="DROP TABLE IF EXISTS tcol, tcol_tri;
	CREATE TABLE tcol AS
		SELECT ST_MakePoint((i % 550) * 7919 % 1009 / 10.0, (i % 550) * 104729 % 997 / 10.0) AS geom,
			   'tile ' || (i % 5) AS t
		  FROM generate_series(1, 600) i;
	CALL tdc_delaunay_tiled('tcol', 'tcol_tri', tile_column => 't');"
local tiled_rows="SELECT tile, id >> 32, ST_AsText(ST_Normalize(geom)) FROM tcol_tri ORDER BY 1, 2, 3"
q "$OLD" -c "SET client_min_messages = warning" -c "$tiled_probe" >/dev/null
q "$NEW" -c "SET client_min_messages = warning" -c "$tiled_probe" >/dev/null
same "tdc_delaunay_tiled with a tile column after the update from $FROM: as in a fresh install" \
	"$(digest "$NEW" "$tiled_rows")" "$(digest "$OLD" "$tiled_rows")"
same "... with its triangles" 1 "$(q "$NEW" -c "SELECT (count(*) > 1000)::int FROM tcol_tri")"
}

for from in "${FROMS[@]}"; do
	upgrade_from "$from"
done
db_finish
