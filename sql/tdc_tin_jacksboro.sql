--
-- tdc_tin_jacksboro: real terrain (issue 36).  A 120 x 120 window of the
-- USGS elevation model of the Jacksboro fault, Tennessee
-- (test/fixtures/jacksboro-dem.txt: 3 arc-second cells, heights 354 to
-- 1,076 m; source and licence in test/fixtures/README.md), projected to
-- metres by an equirectangular projection about its centre latitude,
-- 36.52 N: a cell (row r from the north, column c) is the point
--		x = 500000 + 74.5 c,	y = 4040000 + 92.625 (119 - r)
-- (3 arc-seconds are 74.47 m east-west and 92.66 m north-south there; the
-- spacings are rounded to 1/8 m so that every coordinate is exact).
--
-- 20% of the cells, chosen by a hash, and the window's border (so that the
-- hull is the whole window) are the samples; 600 other cells are held out.
-- At those: the RMSE against the true heights must order natural neighbour
-- <= linear < nearest; the nearest drape must equal the nearest raster
-- (ST_TDCInterpolateRaster on the window's grid) and the brute-force
-- nearest sample, ties included (a lattice has many); and the linear drape
-- must be a Delaunay value at every cell, by the exact arbiter
-- (sql/include/tin_arbiter.sql).  The lattice is full of cocircular
-- rectangles, where either diagonal is Delaunay and GDAL may take the other
-- one: how many held-out cells GDAL's linear gives another value (with
-- GDAL 3.6: see README) goes to build/regress/tdc_tin_jacksboro.txt, as it
-- depends on GDAL's version.
--
\getenv abs_srcdir PG_ABS_SRCDIR
\getenv abs_builddir PG_ABS_BUILDDIR
\set arbiter :abs_srcdir '/sql/include/tin_arbiter.sql'
\set ECHO none
\i :arbiter
\set ECHO all
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE;
RESET client_min_messages;

\set fixture :abs_srcdir '/test/fixtures/jacksboro-dem.txt'
\set txt `cat :'fixture'`
CREATE TABLE jb_cell AS
	SELECT r::int AS r, c::int - 1 AS c, h::int AS h, 500000 + 74.5 * (c - 1) AS x, 4040000 + 92.625 * (119 - r) AS y
	FROM (SELECT row_number() OVER (ORDER BY n) - 2 AS r, l
		  FROM regexp_split_to_table(rtrim(:'txt', E'\n'), E'\n') WITH ORDINALITY t(l, n) WHERE l !~ '^#') t,
		 unnest(string_to_array(l, ' ')) WITH ORDINALITY u(h, c)
	WHERE r >= 0;
\unset txt
SELECT count(*) AS cells, min(h) AS lowest, max(h) AS highest FROM jb_cell;
CREATE TABLE jb_sample AS
	SELECT row_number() OVER (ORDER BY r, c) AS ord, r, c, ST_MakePoint(x, y, h) AS geom
	FROM jb_cell
	WHERE hashint4(r * 1000 + c) % 5 = 0 OR r IN (0, 119) OR c IN (0, 119);
CREATE TABLE jb_held AS
	SELECT row_number() OVER (ORDER BY r, c) AS k, r, c, x, y, h
	FROM jb_cell
	WHERE NOT (hashint4(r * 1000 + c) % 5 = 0 OR r IN (0, 119) OR c IN (0, 119)) AND hashint4(r * 7919 + c) % 19 = 0;
SELECT (SELECT count(*) FROM jb_sample) AS samples, (SELECT count(*) FROM jb_held) AS held_out;

-- The three drapes of the held-out cells (one MULTIPOINT, in k order), and
-- the nearest raster on the window's grid, read at the held-out cells.
CREATE TABLE jb_drape AS
	SELECT m, ST_TDCDrape(geom, t.g, m ORDER BY ord) AS d
	FROM jb_sample, (SELECT ST_Collect(ST_MakePoint(x, y) ORDER BY k) AS g FROM jb_held) t,
		 (VALUES ('natural_neighbor'), ('linear'), ('nearest')) v(m)
	GROUP BY m, t.g;
CREATE TABLE jb_tmpl AS
	SELECT ST_AddBand(ST_MakeEmptyRaster(120, 120, 500000 - 37.25, 4040000 + 92.625 * 119 + 46.3125, 74.5, -92.625,
										 0, 0, 0), '64BF'::text, -9999::float8, -9999::float8) AS rast;
CREATE TABLE jb_val AS
	SELECT h.k, h.h, max(p.z) FILTER (WHERE p.m = 'natural_neighbor') AS nn, max(p.z) FILTER (WHERE p.m = 'linear') AS lin,
		   max(p.z) FILTER (WHERE p.m = 'nearest') AS near, max(r.v) AS near_raster
	FROM jb_held h
		 JOIN (SELECT m, d.path[1] AS k, ST_Z(d.geom) AS z FROM jb_drape, ST_DumpPoints(jb_drape.d) d) p USING (k)
		 JOIN (SELECT u.v, u.i
			   FROM jb_tmpl, unnest(ST_DumpValues((SELECT ST_TDCInterpolateRaster(ST_Collect(geom ORDER BY ord), 'nearest', rast)
												  FROM jb_sample), 1)) WITH ORDINALITY u(v, i)) r
		   ON r.i = h.r * 120 + h.c + 1
	GROUP BY h.k, h.h;
SELECT round(sqrt(avg((nn - h) ^ 2))::numeric, 2) AS rmse_natural_neighbor,
	   round(sqrt(avg((lin - h) ^ 2))::numeric, 2) AS rmse_linear,
	   round(sqrt(avg((near - h) ^ 2))::numeric, 2) AS rmse_nearest,
	   sqrt(avg((nn - h) ^ 2)) <= sqrt(avg((lin - h) ^ 2)) AND sqrt(avg((lin - h) ^ 2)) < sqrt(avg((near - h) ^ 2))
		   AS nn_le_linear_lt_nearest,
	   count(*) FILTER (WHERE near IS DISTINCT FROM near_raster) AS nearest_drape_not_raster
FROM jb_val;

-- The arbiter at the held-out cells: the brute-force nearest sample (how
-- many cells have two or four equally near) and the linear value of a
-- triangle whose circumcircle it checked (circle 0: other samples on it,
-- the lattice's cocircular rectangles; -1 would be a sample inside).
SELECT tdc_arb_samples(ST_Collect(geom ORDER BY ord)) AS arbiter_samples,
	   tdc_arb_triangles(ST_TDCDelaunayTriangles(ST_Collect(geom ORDER BY ord))) AS candidate_triangles
FROM jb_sample;
SELECT tdc_arb_queries(ST_Collect(ST_MakePoint(x, y) ORDER BY k)) AS queries FROM jb_held;
CREATE TABLE jb_ref AS
	SELECT n.qid AS k, n.z AS near, n.ties AS equally_near, l.circle, l.z AS lin
	FROM tdc_arb_nearest() n JOIN tdc_arb_linear() l USING (qid);
SELECT count(*) AS held_out, count(*) FILTER (WHERE equally_near > 1) AS nearest_ties,
	   count(*) FILTER (WHERE v.near IS DISTINCT FROM ref.near) AS nearest_wrong,
	   count(*) FILTER (WHERE circle = 0) AS on_cocircular_triangles,
	   count(*) FILTER (WHERE NOT coalesce(circle >= 0 AND abs(tdc_arb_num(v.lin) - ref.lin) <= 1e-9, false))
		   AS linear_not_delaunay
FROM jb_val v JOIN jb_ref ref USING (k);

-- GDAL's linear at the held-out cells, into the file: how many differ from
-- ours beyond 1e-9 m (ours being a Delaunay value at each).
\set counts :abs_builddir '/tdc_tin_jacksboro.txt'
\o :counts
SELECT count(*) AS held_out, count(*) FILTER (WHERE abs(g.v - v.lin) > 1e-9) AS gdal_linear_differs,
	   round(max(abs(g.v - v.lin))::numeric, 3) AS largest_difference_m
FROM jb_val v JOIN jb_held h USING (k)
	 JOIN (SELECT u.v, u.i
		   FROM jb_tmpl, unnest(ST_DumpValues((SELECT ST_InterpolateRaster(ST_Collect(geom ORDER BY ord), 'linear', rast)
											  FROM jb_sample), 1)) WITH ORDINALITY u(v, i)) g
	   ON g.i = h.r * 120 + h.c + 1;
\o

DROP TABLE jb_cell, jb_sample, jb_held, jb_drape, jb_tmpl, jb_val, jb_ref;
\set arbiter :abs_srcdir '/sql/include/tin_arbiter_drop.sql'
\set ECHO none
\i :arbiter
\set ECHO all
-- The tests after this one run without the raster extensions, as before.
DROP EXTENSION tdc_delaunay_raster;
DROP EXTENSION postgis_raster;
