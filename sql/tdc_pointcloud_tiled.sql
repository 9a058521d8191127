--
-- tdc_pointcloud_tiled: the tiled procedures over a pcpatch column
-- (tdc_interpolate_tiled, tdc_contours_tiled, tdc_delaunay_tiled with
-- tdc_delaunay_pointcloud installed).  Run only where pgpointcloud is
-- installed (Makefile).
--
-- The patches are made by pgpointcloud (PC_MakePoint and the PC_Patch
-- aggregate) under formats of int32 X, Y, Z scaled by 0.01 with offsets and
-- a uint8 Classification, compressed 'dimensional' and 'none'.  The same
-- points as pgpointcloud reads them (PC_Explode, PC_Get), in patch order,
-- are a geometry table: each procedure on the patch column must give what
-- it gives on the geometry column, in one pass and in the core's bounded
-- run (a tdc_delaunay.max_memory one pass does not fit), and with a filter
-- what it gives on the geometry rows of that class.
--
SET client_min_messages = warning;
SELECT count(*) = 0 AS raster_was_absent FROM pg_extension WHERE extname = 'postgis_raster' \gset
CREATE EXTENSION IF NOT EXISTS postgis_raster;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster;
CREATE EXTENSION pointcloud;
CREATE EXTENSION tdc_delaunay_pointcloud;
RESET client_min_messages;
-- errors with their hints, without PL/pgSQL's CONTEXT lines
\set SHOW_CONTEXT never

-- Test helpers (superuser only, LANGUAGE internal): a patch's stored bytes
-- as bytea and back (byteacat(x, '') returns x), to make a LAZ patch,
-- which pgpointcloud of Debian cannot.
CREATE FUNCTION tdc_pc_raw(pcpatch, bytea) RETURNS bytea
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';
CREATE FUNCTION tdc_pc_mk(bytea, bytea) RETURNS pcpatch
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';

-- The formats: 21 dimensional, 22 uncompressed, 23 without Z.
CREATE FUNCTION tdc_pc_format(dims text[], compression text) RETURNS text LANGUAGE sql AS $$
SELECT '<?xml version="1.0" encoding="UTF-8"?>
<pc:PointCloudSchema xmlns:pc="http://pointcloud.org/schemas/PC/1.1">' ||
	string_agg(format('
  <pc:dimension><pc:position>%s</pc:position><pc:size>%s</pc:size><pc:name>%s</pc:name>
    <pc:interpretation>%s</pc:interpretation>%s</pc:dimension>', k, CASE WHEN d[2] = 'uint8_t' THEN 1 ELSE 4 END,
		d[1], d[2], CASE WHEN d[3] IS NULL THEN '' ELSE
		format('<pc:scale>0.01</pc:scale><pc:offset>%s</pc:offset>', d[3]) END), '' ORDER BY k) ||
'
  <pc:metadata><Metadata name="compression">' || compression || '</Metadata></pc:metadata>
</pc:PointCloudSchema>'
FROM unnest(dims) WITH ORDINALITY u(t, k), LATERAL string_to_array(t, ' ') d $$;
DELETE FROM pointcloud_formats WHERE pcid BETWEEN 21 AND 23;
INSERT INTO pointcloud_formats (pcid, srid, schema) VALUES
	(21, 3006, tdc_pc_format('{"X int32_t 500000","Y int32_t 6000000","Z int32_t 100","Classification uint8_t"}',
							 'dimensional')),
	(22, 3006, tdc_pc_format('{"X int32_t 500000","Y int32_t 6000000","Z int32_t 100","Classification uint8_t"}',
							 'none')),
	(23, 3006, tdc_pc_format('{"X int32_t 500000","Y int32_t 6000000","Intensity int32_t 0"}', 'none'));

-- The points: 9 clusters of 29,200 (262,800: the bounded run needs 2^18),
-- on a jittered lattice (no two alike), in patches of 400; every seventh
-- point is of class 1, the others of class 2.  Set 0 is the first 2,000
-- points of the first cluster, set 1 all of them.
CREATE TABLE pct_src AS
SELECT c * 29200 + i AS n, CASE WHEN c * 29200 + i < 2000 THEN 0 ELSE 1 END AS small,
	500000 + (c % 3) * 100 + (i % 180) * 0.17 + ((i::bigint * 7919) % 13) * 0.01 AS x,
	6000000 + (c / 3) * 100 + (i / 180) * 0.19 + ((i::bigint * 104729) % 11) * 0.01 AS y,
	CASE WHEN i % 7 = 0 THEN 1 ELSE 2 END AS cls
FROM generate_series(0, 8) c, generate_series(0, 29199) i;
CREATE TABLE pct_pat AS
SELECT pcid, n / 400 AS p, min(small) AS small,
	PC_Patch(PC_MakePoint(pcid, ARRAY[x, y, round((sin((x - 500000) / 7) * 10 + cos((y - 6000000) / 5) * 5)::numeric, 2),
									  cls]) ORDER BY n) AS pa
FROM pct_src, (VALUES (21), (22)) f(pcid)
WHERE pcid = 21 OR n < 2000
GROUP BY pcid, n / 400 ORDER BY pcid, p;
-- the same points as pgpointcloud reads them, in patch order
CREATE TABLE pct_pts AS
SELECT pcid, small, ST_SetSRID(ST_MakePoint(v[1], v[2], v[3]), 3006) AS geom, v[4] AS cls
FROM (SELECT pcid, small, p, k, PC_Get(pt) AS v
		FROM pct_pat, PC_Explode(pa) WITH ORDINALITY e(pt, k) ORDER BY pcid, p, k) s;
SELECT pcid, PC_Compression(pa) AS compression, count(*) AS patches, sum(PC_NumPoints(pa)) AS points
FROM pct_pat GROUP BY 1, 2 ORDER BY 1;
-- the sources, each a view of one set
CREATE VIEW pct_pa_small AS SELECT pa FROM pct_pat WHERE pcid = 21 AND small = 0;
CREATE VIEW pct_pa_small_none AS SELECT pa FROM pct_pat WHERE pcid = 22;
CREATE VIEW pct_pa_big AS SELECT pa FROM pct_pat WHERE pcid = 21;
CREATE VIEW pct_g_small AS SELECT geom FROM pct_pts WHERE pcid = 21 AND small = 0;
CREATE VIEW pct_g_small2 AS SELECT geom FROM pct_pts WHERE pcid = 21 AND small = 0 AND cls = 2;
CREATE VIEW pct_g_big AS SELECT geom FROM pct_pts WHERE pcid = 21;
CREATE VIEW pct_g_big2 AS SELECT geom FROM pct_pts WHERE pcid = 21 AND cls = 2;

-- Two coverages: tiles, and tiles equal to the other's, pixel for pixel.
CREATE FUNCTION pct_same_tiles(a text, b text, OUT tiles bigint, OUT equal bigint) LANGUAGE plpgsql AS $$
BEGIN
	EXECUTE format('SELECT (SELECT count(*) FROM %1$I), count(*) FROM %1$I x JOIN %2$I y USING (rid)
					 WHERE ST_AsBinary(x.rast) = ST_AsBinary(y.rast) AND (SELECT count(*) FROM %1$I) = (SELECT count(*) FROM %2$I)',
				   a, b) INTO tiles, equal;
END $$;
-- Two tables of lines: rows, and rows of one equal (id, level and
-- geometry) to a row of the other.
CREATE FUNCTION pct_same_lines(a text, b text, OUT lines bigint, OUT equal bigint) LANGUAGE plpgsql AS $$
BEGIN
	EXECUTE format('SELECT (SELECT count(*) FROM %1$I), count(*) FROM %1$I x JOIN %2$I y USING (id, level)
					 WHERE ST_AsEWKB(x.geom) = ST_AsEWKB(y.geom) AND (SELECT count(*) FROM %1$I) = (SELECT count(*) FROM %2$I)',
				   a, b) INTO lines, equal;
END $$;
-- Two tables of triangles: rows, and the triangles (normalised: the
-- bounded run writes them in any order, from any corner) of each that the
-- other lacks.
CREATE FUNCTION pct_same_triangles(a text, b text, OUT triangles bigint, OUT only_a bigint, OUT only_b bigint)
LANGUAGE plpgsql AS $$
BEGIN
	EXECUTE format('SELECT (SELECT count(*) FROM %1$I),
						   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)) FROM %1$I
												  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)) FROM %2$I) s),
						   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)) FROM %2$I
												  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)) FROM %1$I) s)',
				   a, b) INTO triangles, only_a, only_b;
END $$;

-- tdc_interpolate_tiled, one pass: 2,000 points, tiles of 16 x 13 on a
-- 47 x 41 grid (the last column and row cut), both compressions, linear
-- and natural neighbour, and the filter.
SET client_min_messages = warning;
CALL tdc_interpolate_tiled('pct_pa_small', 'pct_cov_pa', 'pa',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'linear', '64BF', -9999, 16, 13);
CALL tdc_interpolate_tiled('pct_pa_small_none', 'pct_cov_none', 'pa',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'linear', '64BF', -9999, 16, 13);
CALL tdc_interpolate_tiled('pct_g_small', 'pct_cov_g', 'geom',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'linear', '64BF', -9999, 16, 13);
CALL tdc_interpolate_tiled('pct_pa_small', 'pct_cov_pa_nn', 'pa',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'natural_neighbor', '32BF',
						   -9999, 16, 13);
CALL tdc_interpolate_tiled('pct_g_small', 'pct_cov_g_nn', 'geom',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'natural_neighbor', '32BF',
						   -9999, 16, 13);
CALL tdc_interpolate_tiled('pct_pa_small', 'pct_cov_pa2', 'pa',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'linear', '64BF', -9999, 16, 13,
						   filter => 'Classification=2');
CALL tdc_interpolate_tiled('pct_g_small2', 'pct_cov_g2', 'geom',
						   ST_MakeEmptyRaster(47, 41, 499999, 6000031, 0.75, -0.8, 0, 0, 3006), 'linear', '64BF', -9999, 16, 13);
SELECT 'dimensional' AS cov, * FROM pct_same_tiles('pct_cov_pa', 'pct_cov_g')
UNION ALL SELECT 'none', * FROM pct_same_tiles('pct_cov_none', 'pct_cov_g')
UNION ALL SELECT 'natural_neighbor', * FROM pct_same_tiles('pct_cov_pa_nn', 'pct_cov_g_nn')
UNION ALL SELECT 'class 2', * FROM pct_same_tiles('pct_cov_pa2', 'pct_cov_g2')
-- the filter keeps fewer points: other tiles
UNION ALL SELECT 'class 2 vs all', * FROM pct_same_tiles('pct_cov_pa2', 'pct_cov_g');
SELECT DISTINCT ST_SRID(rast) AS srid FROM pct_cov_pa;

-- In the core's bounded run: one pass of 262,800 points does not fit 16
-- MB; tiles of 64 x 50 on 331 x 290 pixels, with and without the filter;
-- the NOTICE gives the run's tiles.
SET tdc_delaunay.max_memory = 16;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('pct_pa_big', 'pct_big_pa', 'pa',
						   ST_MakeEmptyRaster(331, 290, 499980, 6000250, 1.0, -1.0, 0, 0, 3006), 'linear', '32BF', -9999, 64, 50);
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_interpolate_tiled('pct_g_big', 'pct_big_g', 'geom',
						   ST_MakeEmptyRaster(331, 290, 499980, 6000250, 1.0, -1.0, 0, 0, 3006), 'linear', '32BF', -9999, 64, 50);
CALL tdc_interpolate_tiled('pct_pa_big', 'pct_big_pa2', 'pa',
						   ST_MakeEmptyRaster(331, 290, 499980, 6000250, 1.0, -1.0, 0, 0, 3006), 'linear', '64BF', -9999, 64, 50,
						   'Classification=2');
CALL tdc_interpolate_tiled('pct_g_big2', 'pct_big_g2', 'geom',
						   ST_MakeEmptyRaster(331, 290, 499980, 6000250, 1.0, -1.0, 0, 0, 3006), 'linear', '64BF', -9999, 64, 50);
SELECT 'bounded' AS cov, * FROM pct_same_tiles('pct_big_pa', 'pct_big_g')
UNION ALL SELECT 'bounded class 2', * FROM pct_same_tiles('pct_big_pa2', 'pct_big_g2');

-- tdc_contours_tiled: one pass and bounded (the NOTICE), with and without
-- the filter.
CALL tdc_contours_tiled('pct_g_big', 'pct_lines_big_g', 'geom', 2.5, 0.25);
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_contours_tiled('pct_pa_big', 'pct_lines_big_pa', 'pa', 2.5, 0.25);
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_contours_tiled('pct_g_big2', 'pct_lines_big_g2', 'geom', 2.5, 0.25);
CALL tdc_contours_tiled('pct_pa_big', 'pct_lines_big_pa2', 'pa', 2.5, 0.25, 'Classification=2');
RESET tdc_delaunay.max_memory;
CALL tdc_contours_tiled('pct_g_small', 'pct_lines_g', 'geom', 1.5);
CALL tdc_contours_tiled('pct_pa_small_none', 'pct_lines_none', 'pa', 1.5);
CALL tdc_contours_tiled('pct_g_small2', 'pct_lines_g2', 'geom', 1.5);
CALL tdc_contours_tiled('pct_pa_small', 'pct_lines_pa2', 'pa', 1.5, filter => 'Classification=2');
SELECT 'one pass, none' AS source, * FROM pct_same_lines('pct_lines_none', 'pct_lines_g')
UNION ALL SELECT 'one pass, class 2', * FROM pct_same_lines('pct_lines_pa2', 'pct_lines_g2')
UNION ALL SELECT 'bounded', * FROM pct_same_lines('pct_lines_big_pa', 'pct_lines_big_g')
UNION ALL SELECT 'bounded, class 2', * FROM pct_same_lines('pct_lines_big_pa2', 'pct_lines_big_g2')
-- the filter keeps fewer points: other lines
UNION ALL SELECT 'class 2 vs all', * FROM pct_same_lines('pct_lines_big_pa2', 'pct_lines_big_g');
SELECT format_type(atttypid, atttypmod) AS lines_geom FROM pg_attribute
WHERE attrelid = 'pct_lines_big_pa'::regclass AND attname = 'geom';

-- tdc_delaunay_tiled: one pass and bounded (the NOTICE), with and without
-- the filter.
SET tdc_delaunay.max_memory = 16;
CALL tdc_delaunay_tiled('pct_g_big', 'pct_tri_big_g', 'geom');
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('pct_pa_big', 'pct_tri_big_pa', 'pa');
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_delaunay_tiled('pct_g_big2', 'pct_tri_big_g2', 'geom');
CALL tdc_delaunay_tiled('pct_pa_big', 'pct_tri_big_pa2', 'pa', filter => 'Classification=2');
RESET tdc_delaunay.max_memory;
CALL tdc_delaunay_tiled('pct_g_small', 'pct_tri_g', 'geom');
CALL tdc_delaunay_tiled('pct_pa_small_none', 'pct_tri_none', 'pa');
SELECT 'one pass, none' AS source, * FROM pct_same_triangles('pct_tri_none', 'pct_tri_g')
UNION ALL SELECT 'bounded', * FROM pct_same_triangles('pct_tri_big_pa', 'pct_tri_big_g')
UNION ALL SELECT 'bounded, class 2', * FROM pct_same_triangles('pct_tri_big_pa2', 'pct_tri_big_g2');
SELECT format_type(atttypid, atttypmod) AS triangles_geom FROM pg_attribute
WHERE attrelid = 'pct_tri_big_pa'::regclass AND attname = 'geom';
RESET client_min_messages;

-- Refusals, each leaving no target behind.
-- a filter on a geometry column
CALL tdc_interpolate_tiled('pct_g_small', 'pct_bad', 'geom', ST_MakeEmptyRaster(10, 10, 500000, 6000010, 1, -1, 0, 0, 3006),
						   filter => 'Classification=2');
-- a filter on a dimension the schema lacks
CALL tdc_contours_tiled('pct_pa_small', 'pct_bad', 'pa', 1, filter => 'Intensity=3');
-- patches of two pcids
CREATE VIEW pct_pa_mixed AS SELECT pa FROM pct_pat WHERE small = 0;
CALL tdc_delaunay_tiled('pct_pa_mixed', 'pct_bad', 'pa');
-- a LAZ patch (compression word 2)
CREATE TABLE pct_laz AS
SELECT tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x02000000'::bytea FROM 5), '') AS pa
FROM pct_pat WHERE pcid = 22 AND p = 0;
CALL tdc_interpolate_tiled('pct_laz', 'pct_bad', 'pa', ST_MakeEmptyRaster(10, 10, 500000, 6000010, 1, -1, 0, 0, 3006));
-- a schema without Z
CREATE TABLE pct_noz AS SELECT PC_Patch(PC_MakePoint(23, ARRAY[500000 + i, 6000000 + i * i, i])) AS pa
FROM generate_series(1, 5) i;
CALL tdc_contours_tiled('pct_noz', 'pct_bad', 'pa', 1);
SELECT to_regclass('pct_bad') IS NULL AS no_target;
-- without tdc_delaunay_pointcloud, a pcpatch column is refused with a hint
DROP EXTENSION tdc_delaunay_pointcloud;
CALL tdc_delaunay_tiled('pct_pa_small', 'pct_bad', 'pa');
SELECT to_regclass('pct_bad') IS NULL AS no_target;

DROP VIEW pct_pa_small, pct_pa_small_none, pct_pa_big, pct_g_small, pct_g_small2, pct_g_big, pct_g_big2, pct_pa_mixed;
DROP TABLE pct_cov_pa, pct_cov_none, pct_cov_g, pct_cov_pa_nn, pct_cov_g_nn, pct_cov_pa2, pct_cov_g2,
	pct_big_pa, pct_big_g, pct_big_pa2, pct_big_g2,
	pct_lines_big_g, pct_lines_big_pa, pct_lines_big_g2, pct_lines_big_pa2, pct_lines_g, pct_lines_none,
	pct_lines_g2, pct_lines_pa2,
	pct_tri_big_g, pct_tri_big_pa, pct_tri_big_g2, pct_tri_big_pa2, pct_tri_g, pct_tri_none,
	pct_laz, pct_noz, pct_pat, pct_pts, pct_src;
DROP FUNCTION tdc_pc_raw(pcpatch, bytea), tdc_pc_mk(bytea, bytea), tdc_pc_format(text[], text),
	pct_same_tiles(text, text), pct_same_lines(text, text), pct_same_triangles(text, text);
DELETE FROM pointcloud_formats WHERE pcid BETWEEN 21 AND 23;
DROP EXTENSION pointcloud;
\if :raster_was_absent
DROP EXTENSION tdc_delaunay_raster;
DROP EXTENSION postgis_raster;
\endif
-- the raster extensions count only when this file made them (another test may have)
SELECT count(*) AS left_behind FROM pg_extension
WHERE extname IN ('pointcloud', 'tdc_delaunay_pointcloud') OR
	(:'raster_was_absent'::bool AND extname IN ('tdc_delaunay_raster', 'postgis_raster'));
