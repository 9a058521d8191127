--
-- tdc_raster: the tdc_delaunay_raster extension; the raster reader and
-- writer (src/pg/formats/raster_read.c, raster_write.c) checked through PostGIS's
-- own raster functions; ST_TDCInterpolateRaster and the ST_TDCInterpolate
-- aggregates against PostGIS's ST_InterpolateRaster (GDAL's gridding).
--
-- A value goes through the writer unchanged by the interpolation when a
-- sample lies at every pixel centre and the method is 'nearest': each pixel
-- then gets exactly its sample's Z.  So the round trips below put a list of
-- values at the limits of every pixel type into a raster both ways, ours
-- and PostGIS's ST_SetValues on the same template, and compare the two
-- rasters byte for byte (their WKB: header, band flags, nodata, pixels).
--
SET client_min_messages = warning;
-- tdc_delaunay was created (tdc_basic) without postgis_raster...
SELECT count(*) AS postgis_raster_installed FROM pg_extension WHERE extname = 'postgis_raster';
-- ...which tdc_delaunay_raster needs.
\set VERBOSITY terse
CREATE EXTENSION tdc_delaunay_raster;
\set VERBOSITY default
CREATE EXTENSION tdc_delaunay_raster CASCADE;
RESET client_min_messages;
SELECT e.extname, e.extversion, array_to_string(array_agg(r.extname ORDER BY r.extname), ', ') AS requires
FROM pg_extension e, pg_extension r
WHERE e.extname = 'tdc_delaunay_raster' AND r.oid IN (
	SELECT refobjid FROM pg_depend WHERE objid = e.oid AND classid = 'pg_extension'::regclass
	AND refclassid = 'pg_extension'::regclass)
GROUP BY 1, 2;

-- Every object has a comment; volatility, strictness, parallel safety, cost.
SELECT p.oid::regprocedure AS function, p.provolatile, p.proisstrict, p.proparallel, p.prokind,
	   p.procost, obj_description(p.oid, 'pg_proc') IS NOT NULL AS commented
FROM pg_proc p
JOIN pg_depend d ON d.objid = p.oid AND d.classid = 'pg_proc'::regclass AND d.deptype = 'e'
JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay_raster'
ORDER BY 1::text;

-- ----------------------------------------------------------------------
-- Round trips, every pixel type
-- ----------------------------------------------------------------------

-- The values: 48 pixels of an 8 x 6 raster, row by row; NULL: no sample.
CREATE TABLE tdc_rt_vals (i int, v float8);
INSERT INTO tdc_rt_vals SELECT i, v FROM unnest(ARRAY[
	0, 0.5, -0.5, 1, 1.5, 2.9, -2.9, 3,
	3.5, 15, 15.5, 16, 127, 127.5, 128, -128,
	-128.5, -129, 255, 255.5, 256, -255, 32767.5, 32768,
	-32768.5, -32769, 65535.5, 65536, 2147483647.5, 2147483648, -2147483648.5, -2147483649,
	4294967295.5, 4294967296, 3.5e38, -3.5e38, 1e50, -1e50, 0.1, -9999,
	-9999.00001, 1e-8, 100.7, -100.7, NULL, NULL, 7, 1 + 1.5e-7]::float8[]) WITH ORDINALITY AS u(v, i);

-- ours: a sample at every pixel centre with a value, 'nearest' within a
-- quarter pixel; theirs: the same values through ST_SetValues (a NULL is
-- nodata there).
CREATE FUNCTION tdc_rt_pair(tmpl raster, method text DEFAULT 'nearest:radius1=0.25:radius2=0.25',
							OUT ours raster, OUT theirs raster)
	LANGUAGE sql AS $$
	WITH px AS (
		SELECT x, y, v FROM tdc_rt_vals, LATERAL (SELECT (i - 1) % 8 + 1 AS x, (i - 1) / 8 + 1 AS y) c)
	SELECT (SELECT ST_TDCInterpolateRaster(ST_Collect(ST_MakePoint(ST_X(c), ST_Y(c), v)), method, tmpl)
			FROM px, ST_PixelAsCentroid(tmpl, x, y) c WHERE v IS NOT NULL),
		   ST_SetValues(tmpl, 1, 1, 1, (SELECT array_agg(r ORDER BY y)
										FROM (SELECT y, array_agg(v ORDER BY x) AS r FROM px GROUP BY y) rows))
	$$;

-- Templates: every pixel type with a nodata value, one band of nodata.
CREATE TABLE tdc_rt_types (pt text, nd float8);
INSERT INTO tdc_rt_types VALUES ('1BB', 0), ('2BUI', 3), ('4BUI', 15), ('8BSI', -128), ('8BUI', 255),
	('16BSI', -32768), ('16BUI', 0), ('32BSI', -9999), ('32BUI', 4294967295), ('32BF', -9999), ('64BF', -9999);
CREATE TABLE tdc_rt AS
SELECT pt, nd, skew, (tdc_rt_pair(ST_AddBand(
		CASE WHEN skew THEN ST_MakeEmptyRaster(8, 6, 500000, 6200000, 2, -1.5, 0.3, -0.2, 32633)
			 ELSE ST_MakeEmptyRaster(8, 6, -10, 20, 1, -1, 0, 0, 4326) END, pt, nd, nd))).*
FROM tdc_rt_types, (VALUES (false), (true)) s(skew);

-- The same bytes (WKB: header, band flags, nodata value, every pixel) as
-- PostGIS's ST_SetValues, and the same metadata, band type and nodata.
SELECT pt, nd, skew, ST_AsBinary(ours) = ST_AsBinary(theirs) AS same_bytes,
	   ST_MetaData(ours) = ST_MetaData(theirs) AS same_metadata,
	   ST_BandPixelType(ours) AS pixtype, ST_BandNoDataValue(ours) AS nodata,
	   ST_SRID(ours) AS srid, ST_BandIsNoData(ours) AS all_nodata, ST_NumBands(ours) AS bands
FROM tdc_rt ORDER BY skew, ST_BandPixelType(ours);
-- Pixel by pixel, as ST_Value reads them (with nodata as a value, and as
-- NULL): no difference.
SELECT pt, skew, x, y, ST_Value(ours, 1, x, y, false) AS ours, ST_Value(theirs, 1, x, y, false) AS theirs
FROM tdc_rt, generate_series(1, 8) x, generate_series(1, 6) y
WHERE ST_Value(ours, 1, x, y, false) IS DISTINCT FROM ST_Value(theirs, 1, x, y, false)
   OR ST_Value(ours, 1, x, y) IS DISTINCT FROM ST_Value(theirs, 1, x, y);
-- What PostGIS's rule gives at the limits (8BUI, nodata 255; 32BF, nodata
-- -9999; 16BSI): truncation toward zero, clamping, and the nodata
-- correction, which moves a value off the nodata value by one (255.5 ->
-- 254) or by FLT_EPSILON (too little for -9999.00001, which stays nodata).
SELECT pt, v, ST_Value(ours, 1, (i - 1) % 8 + 1, (i - 1) / 8 + 1, false) AS stored,
	   ST_Value(ours, 1, (i - 1) % 8 + 1, (i - 1) / 8 + 1) AS value
FROM tdc_rt, tdc_rt_vals
WHERE NOT skew AND pt IN ('8BUI', '32BF', '16BSI')
  AND v IN (-0.5, 2.9, -2.9, 255, 255.5, 256, -9999, -9999.00001, 32767.5, -32769, 3.5e38)
ORDER BY pt, i;

-- A band of nothing but nodata (no sample within the radius) is flagged
-- so, as ST_AddBand flags one; a band with one value is not.
SELECT ST_BandIsNoData(ST_TDCInterpolateRaster('POINT Z (100 100 5)', 'nearest:radius1=1:radius2=1',
											   ST_AddBand(ST_MakeEmptyRaster(3, 3, 0, 3, 1, -1, 0, 0, 0), '16BUI'::text, 9::float8, 9::float8))) AS all_nodata,
	   ST_BandIsNoData(ST_TDCInterpolateRaster('POINT Z (0.5 2.5 5)', 'nearest:radius1=1:radius2=1',
											   ST_AddBand(ST_MakeEmptyRaster(3, 3, 0, 3, 1, -1, 0, 0, 0), '16BUI'::text, 9::float8, 9::float8))) AS one_value;

-- ----------------------------------------------------------------------
-- The nodata value of the result band
-- ----------------------------------------------------------------------
-- the method's nodata option; else the template band's; else GDAL's 0.
-- It is converted to the pixel type as ST_SetBandNoDataValue converts it.
WITH t(pt, tmpl) AS (
	SELECT pt, ST_AddBand(ST_MakeEmptyRaster(2, 1, 0, 1, 1, -1, 0, 0, 0), pt, 0, nd)
	FROM (VALUES ('8BUI', 7::float8), ('8BUI', NULL), ('32BF', -1.5), ('32BF', NULL), ('64BF', NULL)) v(pt, nd)),
m(m) AS (VALUES ('nearest:radius1=0.5:radius2=0.5'), ('nearest:radius1=0.5:radius2=0.5:nodata=-5'),
				('nearest:radius1=0.5:radius2=0.5:NODATA=1000.75'))
SELECT pt, ST_BandNoDataValue(tmpl) AS template_nodata, substr(m, 32) AS options,
	   ST_BandNoDataValue(r) AS nodata, ST_Value(r, 1, 1, 1, false) AS sample, ST_Value(r, 1, 2, 1, false) AS empty,
	   ST_Value(r, 1, 2, 1) AS empty_value
FROM t, m, ST_TDCInterpolateRaster('POINT Z (0.5 0.5 42)', m, tmpl) r
ORDER BY 1, 2, 3;

-- ----------------------------------------------------------------------
-- The template: read from its first bytes, TOASTed or not; errors
-- ----------------------------------------------------------------------
-- A two-band template stored in a table (TOASTed and compressed: its first
-- band is 720 kB of zeros), band 2 behind band 1's pixels.
CREATE TABLE tdc_rt_big AS
SELECT ST_AddBand(ST_AddBand(ST_MakeEmptyRaster(300, 300, 0, 300, 1, -1, 0, 0, 2154), '64BF'::text, 0::float8, -1::float8),
				  '16BSI'::text, 0::float8, -7::float8) AS r;
SELECT pg_column_size(r) < 720000 AS compressed, octet_length(r::bytea) > 720000 AS big FROM tdc_rt_big;
SELECT ST_SameAlignment(o, r) AND ST_Width(o) = 300 AND ST_Height(o) = 300 AS same_grid,
	   ST_NumBands(o) AS bands, ST_BandPixelType(o) AS pixtype,
	   ST_BandNoDataValue(o) AS nodata, ST_SRID(o) AS srid,
	   ST_Value(o, 1, 1, 1) AS top_left, ST_Value(o, 1, 300, 300) AS bottom_right
FROM tdc_rt_big, ST_TDCInterpolateRaster('MULTIPOINT Z (0 0 10, 300 0 20, 0 300 30, 300 300 40)', 'linear', r, 2) o;

-- A raster whose band 2 is stored out of the database (hand-made WKB: an
-- 8BUI band, then a 32BF band in /nonexistent/dem.tif).
CREATE TABLE tdc_rt_outdb AS SELECT ST_RastFromHexWKB(
	'0100000200000000000000f03f000000000000f0bf000000000000000000000000000008400000000000000000'
	'0000000000000000e6100000030003004400010203040506070809ca003c1cc6002f6e6f6e6578697374656e74'
	'2f64656d2e74696600') AS r;
SELECT ST_BandIsNoData(r, 1), ST_BandPath(r, 2), ST_BandPixelType(r, 2) FROM tdc_rt_outdb;
SELECT ST_BandPixelType(ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', r, 1)) FROM tdc_rt_outdb;
SELECT ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', r, 2) FROM tdc_rt_outdb;
-- Bad band numbers.
SELECT ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', r, 3) FROM tdc_rt_outdb;
SELECT ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', r, 0) FROM tdc_rt_outdb;
SELECT ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', ST_MakeEmptyRaster(2, 2, 0, 0, 1, -1, 0, 0, 0));
-- Methods and options: GDAL's names and syntax, nothing else (the
-- error's message and detail, or the values they give: one sample at (1 1)
-- of height 1, and the template's 3 x 3 pixel centres at 0.5, 1.5 and 2.5,
-- so outside the hull everywhere; nodata shows as NULL).
CREATE FUNCTION tdc_rt_try(method text) RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	msg text;
	detail text;
	vals text;
BEGIN
	SELECT (ST_DumpValues(o, 1))::text || ', nodata ' || ST_BandNoDataValue(o) INTO vals
	FROM tdc_rt_outdb, ST_TDCInterpolateRaster('POINT Z (1 1 1)', method, r, 1) o;
	RETURN 'ok: ' || vals;
EXCEPTION WHEN invalid_parameter_value THEN
	GET STACKED DIAGNOSTICS msg = MESSAGE_TEXT, detail = PG_EXCEPTION_DETAIL;
	RETURN msg || ' / ' || detail;
END $$;
SELECT m, tdc_rt_try(m) FROM unnest(ARRAY['linear', 'nearest', 'natural_neighbor', 'Linear:Radius=0:NoData=-1',
	'nearest:radius1=1:radius2=1:angle=30:nodata=2', 'invdist', 'invdist:power=2', 'linear:power=2',
	'linear:radius', 'linear:radius=abc', 'nearest:radius1=1:radius2=2', 'natural_neighbour', '']) m;
-- Samples: no Z is an error; NULL and EMPTY give NULL, as ST_InterpolateRaster.
SELECT ST_TDCInterpolateRaster('MULTIPOINT (1 1, 2 2)', 'linear', r) FROM tdc_rt_outdb;
SELECT ST_TDCInterpolateRaster('POINT EMPTY', 'linear', r) IS NULL AS empty_is_null,
	   ST_TDCInterpolateRaster(NULL, 'linear', r) IS NULL AS null_is_null,
	   ST_TDCInterpolateRaster('POINT Z (1 1 1)', 'linear', NULL) IS NULL AS null_template
FROM tdc_rt_outdb;

-- Breaklines ('linear:breaklines=true', not GDAL's): the samples'
-- linestrings and polygon rings as hard breaklines.  A ridge L(0 1)-R(4 1)
-- at 10 between P(2 0) at 0 and Q(2 2) at 4: the Delaunay TIN crosses the
-- ridge with P-Q, so the pixel centres along it (y = 1) sag to 8 4 4 8;
-- with the breakline they stay at 10.  The second row (y = 0.5) is inside
-- the hull only at x = 1.5 and 2.5: 5 on the constrained triangle L, P, R
-- (z = 10y), 3 on the Delaunay ones (z = 8 - 4x + 2y, z = -8 + 4x + 2y).
CREATE TABLE tdc_rt_ridge AS SELECT 'GEOMETRYCOLLECTION Z (LINESTRING Z (0 1 10, 4 1 10), POINT Z (2 0 0), POINT Z (2 2 4))'::geometry AS g,
	ST_AddBand(ST_MakeEmptyRaster(4, 2, 0, 1.25, 1, -0.5, 0, 0, 0), '64BF'::text, -1::float8, -1::float8) AS r;
SELECT m, (ST_DumpValues(ST_TDCInterpolateRaster(g, m, r), 1)) AS vals
FROM tdc_rt_ridge, unnest(ARRAY['linear:radius=0', 'linear:radius=0:breaklines=true']) m;
-- the aggregate: the same, from rows
SELECT (ST_DumpValues(ST_TDCInterpolate(d.geom, r, 'linear:radius=0:breaklines=yes'), 1)) AS vals
FROM tdc_rt_ridge, ST_Dump(g) d GROUP BY r;
-- The option's values and methods (an error names the option).
SELECT m, tdc_rt_try(m) FROM unnest(ARRAY['linear:breaklines=true', 'linear:breaklines=0', 'linear:breaklines=maybe',
	'linear:breaklines', 'nearest:breaklines=true', 'natural_neighbor:breaklines=false']) m;
-- crossing breaklines are an error naming both; curves are refused
\set VERBOSITY terse
SELECT ST_TDCInterpolateRaster(ST_Collect(g, 'LINESTRING Z (1 0.5 0, 1 1.5 0)'), 'linear:breaklines=true', r) FROM tdc_rt_ridge;
SELECT ST_TDCInterpolateRaster(ST_Collect(g, 'CIRCULARSTRING Z (0 0 1, 1 -1 1, 2 0 1)'), 'linear:breaklines=true', r)
FROM tdc_rt_ridge;
-- without breaklines a curve's stored vertices are samples, as
-- ST_InterpolateRaster reads them (this once checked only for a result)
SELECT ST_AsBinary(ST_TDCInterpolateRaster(ST_Collect(g, 'CIRCULARSTRING Z (0 0 1, 1 -1 1, 2 0 1)'), 'linear', r)) =
	   ST_AsBinary(ST_TDCInterpolateRaster(ST_Collect(g, 'MULTIPOINT Z (0 0 1, 1 -1 1, 2 0 1)'), 'linear', r))
	   AS curves_without
FROM tdc_rt_ridge;
\set VERBOSITY default
DROP TABLE tdc_rt_ridge;

DROP TABLE tdc_rt, tdc_rt_types, tdc_rt_vals, tdc_rt_big, tdc_rt_outdb;
DROP FUNCTION tdc_rt_pair(raster, text);
DROP FUNCTION tdc_rt_try(text);
