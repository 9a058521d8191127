#!/usr/bin/env bash
# scripts/demo.sh (`make demo`): from a bare Debian (12, 13 or testing) to ST_TDCDelaunay
# running beside PostGIS's ST_DelaunayTriangles.
#
#   1. apt-get installs the missing Debian packages (scripts/lib.sh lists them)
#   2. builds and installs the extension
#   3. starts a throw-away cluster of the release's PostgreSQL (or PG_CONFIG's)
#      on a free port, socket only
#      (or uses your server: set PGHOST/PGPORT/PGDATABASE or TDC_USE_EXISTING=1)
#   4. creates postgis and tdc_delaunay, generates random points in a
#      temporary table and triangulates them both ways
#   5. stops the throw-away server, unless KEEP=1
#
# TDC_DEMO_POINTS=N sets the number of points (default 200000).
set -euo pipefail
# shellcheck source=scripts/lib.sh
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
cd "$TDC_ROOT"

NPOINTS=${TDC_DEMO_POINTS:-200000}
[[ "$NPOINTS" =~ ^[0-9]+$ ]] && ((NPOINTS >= 3)) || tdc_die "TDC_DEMO_POINTS must be an integer >= 3"
KEEP=${KEEP:-0}

on_exit() {
	if [ "$KEEP" = 1 ] && ((TDC_CLUSTER_STARTED)); then
		echo
		tdc_say "KEEP=1: the throw-away server keeps running. Connect with:"
		echo "      psql -h $TDC_PGRUN -p $PGPORT -U $PGUSER tdc_demo"
		echo "    Stop it with:  bash scripts/cluster.sh stop"
	else
		tdc_server_down
	fi
}
trap on_exit EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

tdc_ensure_packages
tdc_build_install || tdc_die "the build failed (see above)"
tdc_server_up

if ((!TDC_EXISTING)); then
	# A fresh database in the throw-away cluster for every run.
	tdc_psql -q -d postgres -c 'SET client_min_messages = warning' \
		-c 'DROP DATABASE IF EXISTS tdc_demo' -c 'CREATE DATABASE tdc_demo'
	export PGDATABASE=tdc_demo
fi

echo
tdc_say "demo: $NPOINTS random points, ST_TDCDelaunay beside ST_DelaunayTriangles"
echo "    (random points in a 10 km square, fixed seed; the real-data benchmark on the"
echo "    world's coastlines, GSHHG from Debian's gmt-gshhg-full, is \`make bench\`)"
echo

# Everything lives in temporary tables, so that nothing is left in your database.
tdc_psql -q -v npoints="$NPOINTS" -v cpus="$(nproc)" <<'SQL'
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay;
\pset footer off

SELECT setseed(0.2014) \gset
CREATE TEMP TABLE tdc_demo_points AS
	SELECT i AS id, ST_MakePoint(random() * 10000, random() * 10000) AS geom
	FROM generate_series(1, :npoints) AS i;
ANALYZE tdc_demo_points;

-- The exact triangle count of a Delaunay triangulation is 2n - 2 - h
-- (n unique sites, h of them on the convex hull).
CREATE TEMP TABLE tdc_demo_result (method text, triangles bigint, seconds float8);
INSERT INTO tdc_demo_result
	SELECT 'exact: 2n - 2 - h', 2 * n - 2 - h, NULL
	FROM (SELECT count(DISTINCT (ST_X(geom), ST_Y(geom))) AS n,
				 ST_NPoints(ST_ConvexHull(ST_Collect(geom))) - 1 AS h
		  FROM tdc_demo_points) s;

-- Each INSERT times itself: clock_timestamp() is read after the aggregate
-- has produced its row, statement_timestamp() when the statement began.
INSERT INTO tdc_demo_result
	SELECT 'ST_TDCDelaunay(geom)', ST_NumGeometries(t),
		   extract(epoch FROM clock_timestamp() - statement_timestamp())
	FROM (SELECT ST_TDCDelaunay(geom) AS t FROM tdc_demo_points) s;
INSERT INTO tdc_demo_result
	SELECT 'ST_DelaunayTriangles(ST_Collect(geom))', ST_NumGeometries(t),
		   extract(epoch FROM clock_timestamp() - statement_timestamp())
	FROM (SELECT ST_DelaunayTriangles(ST_Collect(geom)) AS t FROM tdc_demo_points) s;

SELECT method, triangles, round(seconds::numeric, 3) AS seconds
FROM tdc_demo_result;

SELECT round((SELECT seconds FROM tdc_demo_result WHERE method LIKE 'ST_Delaunay%')::numeric
			 / nullif((SELECT seconds FROM tdc_demo_result WHERE method LIKE 'ST_TDC%'), 0)::numeric, 1)
		   AS "speed-up",
	   postgis_lib_version() AS postgis, split_part(postgis_geos_version(), '-', 1) AS geos,
	   current_setting('tdc_delaunay.threads', true) AS "tdc_delaunay.threads", :'cpus' AS "CPUs";
SQL

echo "    (PostGIS before GEOS 3.13 misses some hull triangles: its count can be below the exact one)"
echo
tdc_say "demo done"
