#!/usr/bin/env bash
# test/dump_restore.sh: a database whose tables, views, materialized views
# and indexes use every function family of tdc_delaunay survives
# pg_dump -Fc and pg_restore into a fresh database: pg_restore exits 0 and
# every object gives the same rows (digests of the sorted rows, geometry as
# hex EWKB).
#
# pg_restore runs with an empty search_path (and PostgreSQL 17+ refreshes
# every materialized view with "pg_catalog, pg_temp"): the materialized views
# over the Dump functions restore because their queries are
# schema-qualified (public.pts).  The last part shows where an unqualified
# query fails (on restore before 17, at CREATE from 17 on), and that its
# error carries the HINT that says what to do.  And GDAL reads a raster
# coverage of tdc_interpolate_tiled as one raster.
#
#   PGHOST=... PGPORT=... PGUSER=... bash test/dump_restore.sh
# Needs a superuser (scripts/test.sh: its throw-away cluster); makes and
# drops the databases tdc_dump_src, tdc_dump_dst, tdc_dump_bad and
# tdc_dump_bad_dst.  Uses pg_dump and pg_restore of the server's major.
# Prints "N passed, N failed".  About 15 s.
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/db_lib.sh
source "$HERE/db_lib.sh"

SRC=tdc_dump_src
DST=tdc_dump_dst

echo "== dump_restore.sh: pg_dump -Fc, pg_restore into a fresh database"
db_require_server
fresh_db "$SRC"
fresh_db "$DST"
q "$SRC" -c "CREATE EXTENSION tdc_delaunay CASCADE" -c "$TEST_DATA" >/dev/null

q "$SRC" >/dev/null <<'SQL'
-- Delaunay: the function, the aggregates, the Dump
CREATE VIEW v_triangles AS
	SELECT grp, ST_TDCDelaunayTriangles(ST_Collect(geom)) AS g FROM pts GROUP BY grp
	UNION ALL SELECT -1, ST_TDCDelaunayTriangles(ST_Collect(geom), 0.5, 2) FROM pts;
CREATE MATERIALIZED VIEW mv_aggregate AS
	SELECT grp, ST_TDCDelaunay(geom) AS g, ST_TDCDelaunay(geom, 0.0, 1) AS edges FROM pts GROUP BY grp;
CREATE MATERIALIZED VIEW mv_dump AS
	SELECT id, geom FROM ST_TDCDelaunayDump('SELECT geom FROM public.pts', 0.25);
-- constrained: the function, the aggregate, the Dump
CREATE TABLE t_constrained AS
	SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom)) AS g FROM lines;
CREATE VIEW v_constrained AS
	SELECT ST_TDCConstrainedDelaunay(geom) AS g, ST_TDCConstrainedDelaunay(geom, 5) AS c FROM lines;
CREATE MATERIALIZED VIEW mv_constrained_dump AS
	SELECT id, geom FROM ST_TDCConstrainedDelaunayDump('SELECT geom FROM public.lines');
-- Voronoi: polygons, lines, the aggregate, the Dump
CREATE VIEW v_voronoi AS
	SELECT ST_TDCVoronoiPolygons(ST_Collect(geom)) AS cells,
		   ST_TDCVoronoiLines(ST_Collect(geom), 0.0, ST_MakeEnvelope(-50, -50, 150, 150, 4326)) AS edges
	  FROM pts;
CREATE MATERIALIZED VIEW mv_voronoi_aggregate AS
	SELECT grp, ST_TDCVoronoi(geom) AS cells FROM pts GROUP BY grp;
CREATE MATERIALIZED VIEW mv_voronoi_dump AS
	SELECT id, geom FROM ST_TDCVoronoiDump('SELECT id::bigint, geom FROM public.pts',
										   ST_MakeEnvelope(-50, -50, 150, 150, 4326));
-- an index whose expression calls the library as pg_restore rebuilds it
CREATE TABLE t_groups AS SELECT grp, ST_Collect(geom) AS g FROM pts GROUP BY grp;
CREATE INDEX t_groups_ntri ON t_groups ((ST_NumGeometries(ST_TDCDelaunayTriangles(g))));
-- tdc_delaunay_tiled's output table
CALL tdc_delaunay_tiled('pts', 'tiled', tile_size => 25);
SQL

OBJECTS=(v_triangles mv_aggregate mv_dump t_constrained v_constrained mv_constrained_dump
	v_voronoi mv_voronoi_aggregate mv_voronoi_dump tiled)
take_digests "$SRC" "${OBJECTS[@]}"
IDX="SET enable_seqscan = off; SELECT grp FROM t_groups WHERE ST_NumGeometries(ST_TDCDelaunayTriangles(g)) > 0 ORDER BY grp"
before_idx=$(q "$SRC" -c "$IDX" | tr '\n' ' ')

"$PGBIN/pg_dump" -Fc -d "$SRC" -f "$DB_WORK/src.dump"
rc=0
"$PGBIN/pg_restore" -d "$DST" "$DB_WORK/src.dump" >"$DB_WORK/restore.log" 2>&1 || rc=$?
same "pg_restore exits 0" 0 "$rc"
((rc == 0)) || sed 's/^/        /' "$DB_WORK/restore.log"
same "the restored database has tdc_delaunay $(q "$SRC" -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")" \
	"$(q "$SRC" -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")" \
	"$(q "$DST" -c "SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay'")"
same_digests "$DST" restored "${OBJECTS[@]}"
same "the restored expression index answers as before" "$before_idx" "$(q "$DST" -c "$IDX" | tr '\n' ' ')"
q "$DST" -c "REFRESH MATERIALIZED VIEW mv_dump" -c "REFRESH MATERIALIZED VIEW mv_voronoi_dump" \
	-c "REFRESH MATERIALIZED VIEW mv_constrained_dump" >/dev/null
same_digests "$DST" "restored and refreshed" mv_dump mv_voronoi_dump mv_constrained_dump

# The unqualified query.  PostgreSQL 17 and later run CREATE and REFRESH
# MATERIALIZED VIEW with the search_path "pg_catalog, pg_temp", so there the
# view cannot be made: the error, with the HINT, comes at once.  Before 17
# it is made and works, and pg_restore (empty search_path) fails on it.
BAD=tdc_dump_bad
fresh_db "$BAD"
fresh_db "${BAD}_dst"
q "$BAD" -c "CREATE EXTENSION tdc_delaunay CASCADE" -c "$TEST_DATA" >/dev/null
UNQUALIFIED="CREATE MATERIALIZED VIEW mv AS SELECT * FROM ST_TDCDelaunayDump('select geom from pts')"
if (($(q "$BAD" -c 'SHOW server_version_num') >= 170000)); then
	rc=0
	q "$BAD" -c "$UNQUALIFIED" >"$DB_WORK/bad.log" 2>&1 || rc=$?
	check "PostgreSQL 17+: the materialized view over an unqualified Dump query is refused (exit $rc)" test "$rc" -ne 0
	what="CREATE MATERIALIZED VIEW"
else
	q "$BAD" -c "$UNQUALIFIED" >/dev/null
	n=$(q "$BAD" -c "SELECT count(*) FROM mv")
	check "an unqualified Dump query works in its database ($n rows)" test "$n" -gt 0
	"$PGBIN/pg_dump" -Fc -d "$BAD" -f "$DB_WORK/bad.dump"
	rc=0
	"$PGBIN/pg_restore" -d "${BAD}_dst" "$DB_WORK/bad.dump" >"$DB_WORK/bad.log" 2>&1 || rc=$?
	check "... but pg_restore of it fails (exit $rc)" test "$rc" -ne 0
	what="pg_restore"
fi
check "... as relation \"pts\" does not exist" grep -q 'relation "pts" does not exist' "$DB_WORK/bad.log"
check "... with the HINT to schema-qualify the query" grep -q 'HINT: .*Schema-qualify every table' "$DB_WORK/bad.log"
check "... and the CONTEXT naming the query" grep -q 'query of ST_TDCDelaunayDump: select geom from pts' "$DB_WORK/bad.log"
echo "  ($what said:)"
grep -E 'ERROR|HINT|CONTEXT|errors ignored' "$DB_WORK/bad.log" | sed 's/^/        /'
# A raster coverage of tdc_interpolate_tiled (tdc_delaunay_raster) is what
# GDAL's PostGISRaster driver, as QGIS uses it, reads as one raster: with
# the raster constraints added, mode=2 gives the template's size and
# geotransform (tiles of 64 x 50 that do not divide 331 x 290).
echo "== a coverage of tdc_interpolate_tiled read by GDAL (mode=2)"
q "$SRC" >/dev/null <<'SQL'
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE;
CREATE TABLE cov_pts AS
	SELECT ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
	  FROM (SELECT (i * 7919 % 2311) / 10.0 AS x, (i * 104729 % 2003) / 10.0 AS y FROM generate_series(1, 3000) i) s;
CALL tdc_interpolate_tiled('cov_pts', 'cov', 'geom', ST_MakeEmptyRaster(331, 290, -20.5, 230.25, 0.75, -0.5, 0, 0, 3006),
						   'linear', '32BF', -9999, 64, 50);
SELECT AddRasterConstraints('cov', 'rast');
SQL
if command -v gdalinfo >/dev/null; then
	gdalinfo -json "PG:host=${PGHOST:-} port=${PGPORT:-5432} user=${PGUSER:-$USER} dbname=$SRC table=cov mode=2" \
		>"$DB_WORK/cov.json" 2>"$DB_WORK/cov.err" || true
	same "gdalinfo reads the coverage as one raster: size and geotransform" \
		"331 290 -20.5 0.75 0 230.25 0 -0.5" \
		"$(python3 -c 'import json, sys; d = json.load(open(sys.argv[1])); print(*d["size"], *("%.17g" % v for v in d["geoTransform"]))' \
			"$DB_WORK/cov.json" 2>&1 || cat "$DB_WORK/cov.err")"
	check "... with one band of Float32 and the tiles' nodata" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
b = d["bands"]
sys.exit(not (len(b) == 1 and b[0]["type"] == "Float32" and b[0]["noDataValue"] == -9999))' "$DB_WORK/cov.json"
else
	fail "gdalinfo is installed (gdal-bin)"
fi
db_finish
