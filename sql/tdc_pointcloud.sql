--
-- tdc_pointcloud: the tdc_delaunay_pointcloud extension, the pcpatch
-- overloads of ST_TDCDelaunay, ST_TDCContours, ST_TDCDrape and
-- ST_TDCInterpolate.  Run only where pgpointcloud is installed (Makefile).
--
-- The patches are made by pgpointcloud itself (PC_MakePoint and the
-- PC_Patch aggregate) under its formats; each aggregate over them must give
-- the bytes the geometry aggregate gives over the same points, read back by
-- pgpointcloud (PC_Explode, and PC_Get(pt), whose float8[] holds the exact
-- scaled values: PC_Get(pt, name) goes through numeric and keeps only 15
-- digits), in the same order.
--
SET client_min_messages = warning;
-- tdc_delaunay was created (tdc_basic) without pgpointcloud...
SELECT count(*) AS pointcloud_installed FROM pg_extension WHERE extname = 'pointcloud';
-- (the raster extensions are dropped at the end if this test made them:
-- tdc_raster, later, checks that tdc_delaunay needed no postgis_raster)
SELECT count(*) = 0 AS raster_was_absent FROM pg_extension WHERE extname = 'postgis_raster' \gset
CREATE EXTENSION IF NOT EXISTS postgis_raster;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster;
-- ...which tdc_delaunay_pointcloud needs.
\set VERBOSITY terse
CREATE EXTENSION tdc_delaunay_pointcloud;
\set VERBOSITY default
CREATE EXTENSION pointcloud;
CREATE EXTENSION tdc_delaunay_pointcloud;
RESET client_min_messages;

-- Every object of the extension has a comment; what it holds.
SELECT count(*) AS objects_without_comment
FROM pg_depend d
JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay_pointcloud'
WHERE d.deptype = 'e' AND d.classid = 'pg_proc'::regclass
  AND obj_description(d.objid, 'pg_proc') IS NULL;
SELECT p.oid::regprocedure AS function, p.prokind, p.proparallel
FROM pg_proc p
JOIN pg_depend d ON d.objid = p.oid AND d.classid = 'pg_proc'::regclass AND d.deptype = 'e'
JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay_pointcloud'
WHERE p.prokind = 'a'
ORDER BY p.oid::regprocedure::text COLLATE "C";

-- Test helpers (superuser only, LANGUAGE internal): a patch's stored bytes
-- as bytea and back (byteacat(x, '') returns x), to make the patches
-- pgpointcloud cannot: LAZ, unknown compressions, truncated values.
CREATE FUNCTION tdc_pc_raw(pcpatch, bytea) RETURNS bytea
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';
CREATE FUNCTION tdc_pc_mk(bytea, bytea) RETURNS pcpatch
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';

-- The formats: int32 X, Y, Z scaled by 0.01 with offsets and a uint8
-- Classification, dimensional (1) and uncompressed (2); double X, Y, Z,
-- dimensional (3); and one without Z (4).
CREATE FUNCTION tdc_pc_schema(dims text, compression text) RETURNS text LANGUAGE sql AS $$
SELECT '<?xml version="1.0" encoding="UTF-8"?>
<pc:PointCloudSchema xmlns:pc="http://pointcloud.org/schemas/PC/1.1"
    xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">' || dims ||
'  <pc:metadata>
    <Metadata name="compression">' || compression || '</Metadata>
  </pc:metadata>
</pc:PointCloudSchema>' $$;
CREATE FUNCTION tdc_pc_dim(pos int, name text, interp text, scale float8, off float8) RETURNS text
LANGUAGE sql AS $$
SELECT format('
  <pc:dimension>
    <pc:position>%s</pc:position>
    <pc:size>%s</pc:size>
    <pc:description>%s &amp; more</pc:description>
    <pc:name>%s</pc:name>
    <pc:interpretation>%s</pc:interpretation>%s%s
  </pc:dimension>', pos, CASE interp WHEN 'uint8_t' THEN 1 WHEN 'double' THEN 8 ELSE 4 END, name, name, interp,
	CASE WHEN scale IS NULL THEN '' ELSE format('
    <pc:scale>%s</pc:scale>', scale) END,
	CASE WHEN off IS NULL THEN '' ELSE format('
    <pc:offset>%s</pc:offset>', off) END) $$;
CREATE TEMP TABLE dims_int AS SELECT
	tdc_pc_dim(1, 'X', 'int32_t', 0.01, 500000) || tdc_pc_dim(2, 'Y', 'int32_t', 0.01, 6000000) ||
	tdc_pc_dim(3, 'Z', 'int32_t', 0.01, 100) || tdc_pc_dim(4, 'Classification', 'uint8_t', NULL, NULL) AS d;
DELETE FROM pointcloud_formats WHERE pcid BETWEEN 1 AND 6;
INSERT INTO pointcloud_formats (pcid, srid, schema)
SELECT 1, 2154, tdc_pc_schema(d, 'dimensional') FROM dims_int UNION ALL
SELECT 2, 2154, tdc_pc_schema(d, 'none') FROM dims_int UNION ALL
SELECT 3, 2154, tdc_pc_schema(tdc_pc_dim(1, 'X', 'double', NULL, NULL) || tdc_pc_dim(2, 'Y', 'double', NULL, NULL) ||
	tdc_pc_dim(3, 'Z', 'double', NULL, NULL), 'dimensional') UNION ALL
SELECT 4, 2154, tdc_pc_schema(tdc_pc_dim(1, 'X', 'double', NULL, NULL) || tdc_pc_dim(2, 'Y', 'double', NULL, NULL) ||
	tdc_pc_dim(3, 'Intensity', 'double', NULL, NULL), 'none');

-- The points: 12 patches of 3 rows of 20 (720 points).  Within a patch, X
-- spans 20 m in 0.01 steps (a few significant bits), Y is the same along a
-- row (long runs), Z goes from -300 to +300 around the offset 100 (raw
-- values of both signs: no common bits, no runs, so zlib), and the
-- Classification is 2 for the first two rows and 1 for the third (runs).
-- So pgpointcloud compresses X with significant bits, Y and Classification
-- run-length and Z with zlib; the doubles of format 3 all with zlib.
CREATE TEMP TABLE src AS
SELECT p, r, c,
	500000 + (p % 4) * 20 + c + ((p * 7919 + r * 104729 + c * 1299709) % 97) * 0.01 AS x,
	6000000 + (p / 4) * 20 + r * 6.5 + 0.25 * (p % 3) AS y,
	100 + ((p * 31 + r * 17 + c * 53) % 601 - 300) + ((c * 37 + r) % 100) * 0.01 AS z,
	CASE WHEN r < 2 THEN 2 ELSE 1 END AS cls
FROM generate_series(0, 11) p, generate_series(0, 2) r, generate_series(0, 19) c;
CREATE TEMP TABLE pat AS
SELECT pcid, p, PC_Patch(PC_MakePoint(pcid, CASE WHEN pcid = 3 THEN ARRAY[x, y, z] ELSE ARRAY[x, y, z, cls] END)
	ORDER BY r, c) AS pa
FROM src, (VALUES (1), (2), (3)) f(pcid)
GROUP BY pcid, p;
-- The same points as pgpointcloud reads them, in patch order.
CREATE TEMP TABLE pts AS
SELECT pcid, p, k, ST_SetSRID(ST_MakePoint(v[1], v[2], v[3]), 2154) AS g, v[4] AS cls
FROM pat, LATERAL (SELECT PC_Get(pt) AS v, k FROM PC_Explode(pa) WITH ORDINALITY e(pt, k)) e;

-- One call site over groups of three formats: the format kept per call
-- site (fn_extra) serves the groups of its pcid, and a group of another
-- pcid reads its own (1 and 2 differ in compression only, 3 in types).
SELECT a.pcid, count(*) AS groups, bool_and(ST_AsEWKB(a.d) = ST_AsEWKB(b.d)) AS same
FROM (SELECT pcid, p, ST_TDCDelaunay(pa) d FROM pat GROUP BY pcid, p) a
JOIN (SELECT pcid, p, ST_TDCDelaunay(g ORDER BY k) d FROM pts GROUP BY pcid, p) b USING (pcid, p)
GROUP BY a.pcid ORDER BY a.pcid;

-- The compressions pgpointcloud chose (PC_Summary), one line per format.
SELECT pcid, PC_Compression(pa) AS patch,
	string_agg(DISTINCT d->>'name' || ':' || coalesce(d->>'compr', 'none'), ' ') AS dims
FROM pat, json_array_elements(PC_Summary(pa)::json->'dims') d
GROUP BY pcid, PC_Compression(pa) ORDER BY pcid;

-- Every aggregate, every format: the same bytes as the geometry path.
SELECT f.pcid,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g ORDER BY p, k)) FROM pts WHERE pcid = f.pcid) AS delaunay,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa, 0.5, 1 ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g, 0.5, 1 ORDER BY p, k)) FROM pts WHERE pcid = f.pcid) AS delaunay_edges,
	(SELECT ST_AsEWKB(ST_TDCContours(pa, 50 ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCContours(g, 50 ORDER BY p, k)) FROM pts WHERE pcid = f.pcid) AS contours,
	(SELECT ST_AsEWKB(ST_TDCContours(pa, 40, 5, 'linear:max_edge=9' ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCContours(g, 40, 5, 'linear:max_edge=9' ORDER BY p, k)) FROM pts WHERE pcid = f.pcid)
		AS contours_max_edge,
	(SELECT ST_AsEWKB(ST_TDCDrape(pa, 'SRID=2154;LINESTRING(500003 6000002, 500077 6000046)'::geometry ORDER BY p))
		FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDrape(g, 'SRID=2154;LINESTRING(500003 6000002, 500077 6000046)'::geometry ORDER BY p, k))
		FROM pts WHERE pcid = f.pcid) AS drape,
	(SELECT ST_AsEWKB(ST_TDCDrape(pa, 'SRID=2154;POINT(500040 6000030)'::geometry, 'natural_neighbor' ORDER BY p))
		FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDrape(g, 'SRID=2154;POINT(500040 6000030)'::geometry, 'natural_neighbor' ORDER BY p, k))
		FROM pts WHERE pcid = f.pcid) AS drape_nn,
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(pa, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '64BF'::text), 'linear' ORDER BY p))) FROM pat WHERE pcid = f.pcid) =
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(g, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '64BF'::text), 'linear' ORDER BY p, k))) FROM pts WHERE pcid = f.pcid) AS interpolate,
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(pa, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '32BF'::text, 0::float8, -9999::float8), 'nearest', 1 ORDER BY p))) FROM pat WHERE pcid = f.pcid) =
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(g, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '32BF'::text, 0::float8, -9999::float8), 'nearest', 1 ORDER BY p, k))) FROM pts WHERE pcid = f.pcid) AS interpolate_nearest
FROM (VALUES (1), (2), (3)) f(pcid) ORDER BY 1;

-- What the results hold, so that equal bytes are not two equal failures.
SELECT ST_NumGeometries(ST_TDCDelaunay(pa)) AS triangles, ST_SRID(ST_TDCDelaunay(pa)) AS srid
FROM pat WHERE pcid = 1;
SELECT ST_NumGeometries(ST_TDCContours(pa, 50)) AS contour_lines FROM pat WHERE pcid = 1;
SELECT ST_AsText(ST_TDCDrape(pa, 'SRID=2154;POINT(500040 6000030)'::geometry), 6) AS draped FROM pat WHERE pcid = 2;

-- The filter: the last argument of the longest form, on the Classification
-- (the same bytes as the geometry path over the points of class 2, and two
-- values: every point); NULL is no filter.
SELECT f.pcid,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa, 0, 0, 'Classification=2' ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g, 0, 0 ORDER BY p, k)) FROM pts WHERE pcid = f.pcid AND cls = 2) AS delaunay_class2,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa, 0, 0, 'classification = 1, 2' ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g, 0, 0 ORDER BY p, k)) FROM pts WHERE pcid = f.pcid) AS delaunay_both,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa, 0, 0, NULL ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g, 0, 0 ORDER BY p, k)) FROM pts WHERE pcid = f.pcid) AS delaunay_null,
	(SELECT ST_AsEWKB(ST_TDCContours(pa, 50, 0, 'linear', 'Classification=1' ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCContours(g, 50, 0, 'linear' ORDER BY p, k)) FROM pts WHERE pcid = f.pcid AND cls = 1) AS contours_class1,
	(SELECT ST_AsEWKB(ST_TDCDrape(pa, 'SRID=2154;LINESTRING(500003 6000002, 500077 6000046)'::geometry, 'linear', 'Classification=2' ORDER BY p))
		FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDrape(g, 'SRID=2154;LINESTRING(500003 6000002, 500077 6000046)'::geometry, 'linear' ORDER BY p, k))
		FROM pts WHERE pcid = f.pcid AND cls = 2) AS drape_class2,
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(pa, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '64BF'::text), 'linear', 1, 'Classification=2' ORDER BY p))) FROM pat WHERE pcid = f.pcid) =
	(SELECT md5(ST_AsBinary(ST_TDCInterpolate(g, ST_AddBand(ST_MakeEmptyRaster(37, 29, 500000, 6000060, 2.2, -2.1, 0, 0, 2154), '64BF'::text), 'linear', 1 ORDER BY p, k))) FROM pts WHERE pcid = f.pcid AND cls = 2) AS interpolate_class2
FROM (VALUES (1), (2)) f(pcid) ORDER BY 1;
-- a filter on a coordinate itself (Y, run-length in format 1)
SELECT f.pcid,
	(SELECT ST_AsEWKB(ST_TDCDelaunay(pa, 0, 0, 'Y=6000000,6000006.5,6000026.75' ORDER BY p)) FROM pat WHERE pcid = f.pcid) =
	(SELECT ST_AsEWKB(ST_TDCDelaunay(g, 0, 0 ORDER BY p, k)) FROM pts
	 WHERE pcid = f.pcid AND ST_Y(g) IN (6000000, 6000006.5, 6000026.75)) AS delaunay_y,
	(SELECT count(*) FROM pts WHERE pcid = f.pcid AND ST_Y(g) IN (6000000, 6000006.5, 6000026.75)) AS points_kept
FROM (VALUES (1), (2), (3)) f(pcid) ORDER BY 1;
SELECT ST_NumGeometries(ST_TDCDelaunay(pa, 0, 0, 'Classification=2')) AS class2_triangles FROM pat WHERE pcid = 1;
-- a filter that keeps nothing: no vertex, as for no row
SELECT ST_AsText(ST_TDCDelaunay(pa, 0, 0, 'Classification=7')) AS no_point FROM pat WHERE pcid = 1;

-- Refusals, each with its hint.
-- a schema without Z
SELECT ST_TDCDelaunay(pa) FROM (SELECT PC_Patch(PC_MakePoint(4, ARRAY[x, y, z])) pa FROM src WHERE p = 0) s;
-- patches of two pcids in one aggregate
SELECT ST_TDCDelaunay(pa ORDER BY pcid) FROM pat WHERE pcid IN (1, 2);
-- a filter on a dimension the schema lacks, and one without "="
SELECT ST_TDCDelaunay(pa, 0, 0, 'Intensity=3') FROM pat WHERE pcid = 1;
SELECT ST_TDCDelaunay(pa, 0, 0, 'Classification') FROM pat WHERE pcid = 1;
-- the filter must be the same in every row
SELECT ST_TDCDelaunay(pa, 0, 0, CASE WHEN p = 0 THEN 'Classification=1' ELSE 'Classification=2' END ORDER BY p)
FROM pat WHERE pcid = 1;
-- breaklines need linework
SELECT ST_TDCDrape(pa, 'SRID=2154;POINT(500040 6000030)'::geometry, 'linear:breaklines=true') FROM pat WHERE pcid = 1;
-- a LAZ patch (compression word 2; Debian's pgpointcloud cannot make one)
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x02000000'::bytea FROM 5), ''))
FROM pat WHERE pcid = 2 AND p = 0;
-- an unknown patch compression, and an unknown compression of a dimension
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x07000000'::bytea FROM 5), ''))
FROM pat WHERE pcid = 2 AND p = 0;
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x09'::bytea FROM 45 + 3 * 13), ''))
FROM pat WHERE pcid = 1 AND p = 0;
-- truncated: inside the statistics, inside the points, inside a dimension
SELECT ST_TDCDelaunay(tdc_pc_mk(substr(tdc_pc_raw(pa, ''), 1, 60), '')) FROM pat WHERE pcid = 2 AND p = 0;
SELECT ST_TDCDelaunay(tdc_pc_mk(substr(tdc_pc_raw(pa, ''), 1, 44 + 3 * 13 + 59 * 13), ''))
FROM pat WHERE pcid = 2 AND p = 0;
SELECT ST_TDCDelaunay(tdc_pc_mk(substr(tdc_pc_raw(pa, ''), 1, 44 + 3 * 13 + 20), '')) FROM pat WHERE pcid = 1 AND p = 0;
-- a point count the bytes cannot hold (10^9): refused before room is made for it
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x00ca9a3b'::bytea FROM 9), ''))
FROM pat WHERE pcid = 1 AND p = 0;
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x00ca9a3b'::bytea FROM 9), ''))
FROM pat WHERE pcid = 2 AND p = 0;
-- a run-length block whose runs do not add up (Y: the second dimension)
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(b PLACING '\x50'::bytea FROM 45 + 39 + 5 + get_byte(b, 44 + 39 + 1) + 5), ''))
FROM (SELECT tdc_pc_raw(pa, '') b FROM pat WHERE pcid = 1 AND p = 0) s;
-- a pcid that is not in pointcloud_formats
SELECT ST_TDCDelaunay(tdc_pc_mk(overlay(tdc_pc_raw(pa, '') PLACING '\x63000000'::bytea FROM 1), ''))
FROM pat WHERE pcid = 2 AND p = 0;
-- a schema this reader does not understand (a CDATA section), though
-- pgpointcloud reads it
UPDATE pointcloud_formats SET schema = replace(schema, '<pc:description>X &amp; more</pc:description>',
	'<pc:description><![CDATA[X]]></pc:description>') WHERE pcid = 2;
SELECT ST_TDCDelaunay(pa) FROM pat WHERE pcid = 2;

DROP FUNCTION tdc_pc_raw(pcpatch, bytea), tdc_pc_mk(bytea, bytea), tdc_pc_schema(text, text),
	tdc_pc_dim(int, text, text, float8, float8);
DELETE FROM pointcloud_formats WHERE pcid BETWEEN 1 AND 6;
DROP TABLE pat, pts, src, dims_int;
DROP EXTENSION tdc_delaunay_pointcloud;
DROP EXTENSION pointcloud;
\if :raster_was_absent
DROP EXTENSION tdc_delaunay_raster;
DROP EXTENSION postgis_raster;
\endif
-- the raster extensions count only when this file made them (another test may have)
SELECT count(*) AS left_behind FROM pg_extension
WHERE extname IN ('pointcloud', 'tdc_delaunay_pointcloud') OR
	(:'raster_was_absent'::bool AND extname IN ('tdc_delaunay_raster', 'postgis_raster'));
