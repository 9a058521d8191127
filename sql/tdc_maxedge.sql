--
-- tdc_maxedge: max_edge=L in the method of ST_TDCInterpolateRaster,
-- ST_TDCInterpolate and ST_TDCDrape (issue 39): the triangles with an edge
-- longer than L are dropped: their pixels are empty, a draped target may
-- not cross them.
--
-- The samples: a lake, the lattice 0..20 with no sample within 6 of
-- (10 10) but one at it, heights z = x + 2 y.  The pixels expected empty
-- come from an independent rule in SQL: a pixel centre has a value when it
-- is a sample or some triangle of ST_TDCDelaunayTriangles covering it
-- (ST_Covers, closed) has no edge longer than L.
--
-- Independent of the other tests: the raster extension is created here if
-- tdc_raster has not run yet, and dropped again at the end.
--
SET client_min_messages = warning;
SELECT NOT EXISTS (SELECT FROM pg_extension WHERE extname = 'tdc_delaunay_raster') AS me_make_raster,
	   NOT EXISTS (SELECT FROM pg_extension WHERE extname = 'postgis_raster') AS me_make_postgis_raster \gset
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE;
RESET client_min_messages;

CREATE TABLE tdc_me_lake AS
	SELECT ST_MakePoint(x, y, x + 2 * y) AS geom
	  FROM generate_series(0, 20) x, generate_series(0, 20) y
	 WHERE (x - 10) ^ 2 + (y - 10) ^ 2 > 36 OR (x = 10 AND y = 10);

-- the TIN's triangles and each one's longest edge
CREATE TABLE tdc_me_tri AS
	SELECT t, (SELECT max(ST_Distance(ST_PointN(ST_ExteriorRing(t), i), ST_PointN(ST_ExteriorRing(t), i + 1)))
				 FROM generate_series(1, 3) i) AS longest
	  FROM (SELECT (ST_Dump(ST_TDCDelaunayTriangles(ST_Collect(geom)))).geom AS t FROM tdc_me_lake) s;

-- 40 x 40 pixels of 0.5 over the box, 32BF, nodata -9999
CREATE TABLE tdc_me_rast AS
	SELECT ST_AddBand(ST_MakeEmptyRaster(40, 40, 0, 20, 0.5, -0.5, 0, 0, 0), '32BF'::text, 0::float8, -9999::float8) AS tmpl;

-- each pixel: empty or not, against the rule
CREATE FUNCTION tdc_me_check(r raster, l float8)
	RETURNS TABLE (empty_pixels bigint, unlike_the_rule bigint) LANGUAGE sql AS $$
	WITH px AS (
		SELECT c, rw, ST_Value(r, 1, c, rw) IS NULL AS empty,
			   ST_MakePoint((c - 0.5) * 0.5, 20 - (rw - 0.5) * 0.5) AS p
		  FROM generate_series(1, 40) c, generate_series(1, 40) rw)
	SELECT count(*) FILTER (WHERE empty),
		   count(*) FILTER (WHERE empty = (EXISTS (SELECT FROM tdc_me_lake s WHERE ST_Equals(ST_Force2D(s.geom), p))
										OR EXISTS (SELECT FROM tdc_me_tri WHERE ST_Covers(t, p) AND longest <= l)))
	  FROM px $$;

-- ----------------------------------------------------------------------
-- ST_TDCInterpolateRaster and ST_TDCInterpolate: the lake is empty
-- ----------------------------------------------------------------------
SELECT m, (tdc_me_check(ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), m, tmpl), 1.5)).*
  FROM tdc_me_rast, unnest(ARRAY['linear:max_edge=1.5', 'nearest:max_edge=1.5', 'natural_neighbor:max_edge=1.5',
								 'linear:radius=0:max_edge=1.5:nodata=-9999']) m;
-- without the option no pixel is empty; at max_edge 2 the lake's shore is kept
SELECT (tdc_me_check(ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'linear', tmpl), 1e9)).*
  FROM tdc_me_rast;
SELECT (tdc_me_check(ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'linear:max_edge=2', tmpl), 2)).*
  FROM tdc_me_rast;
-- kept pixels hold the values without the option; (2.25 2.25) is on the plane
WITH a AS (SELECT ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'natural_neighbor', tmpl) AS r0,
				  ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'natural_neighbor:max_edge=1.5', tmpl) AS r1
			 FROM tdc_me_rast)
SELECT count(*) FILTER (WHERE ST_Value(r1, 1, c, rw) IS NOT NULL AND ST_Value(r1, 1, c, rw) <> ST_Value(r0, 1, c, rw))
		   AS kept_pixels_changed,
	   min(ST_Value(r1, 1, 5, 36)) AS at_2_25_2_25
  FROM a, generate_series(1, 40) c, generate_series(1, 40) rw;
-- the aggregate gives the same raster as the function
SELECT md5(ST_AsHexWKB(ST_TDCInterpolate(geom, (SELECT tmpl FROM tdc_me_rast), 'linear:max_edge=1.5')))
	   = md5(ST_AsHexWKB(ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'linear:max_edge=1.5',
												 (SELECT tmpl FROM tdc_me_rast)))) AS aggregate_equals_function,
	   md5(ST_AsHexWKB(ST_TDCInterpolate(geom, (SELECT tmpl FROM tdc_me_rast), 'linear:max_edge=1.5')))
	   <> md5(ST_AsHexWKB(ST_TDCInterpolate(geom, (SELECT tmpl FROM tdc_me_rast), 'linear'))) AS differs_without_it
  FROM tdc_me_lake;

-- The exact boundary: a 3-4-5 triangle is kept at max_edge 5, not at the
-- double below.
SELECT m, ST_Value(ST_TDCInterpolateRaster('MULTIPOINT Z (0 0 1, 4 0 1, 0 3 1)', m,
		   ST_AddBand(ST_MakeEmptyRaster(1, 1, 0.5, 1.5, 1, -1, 0, 0, 0), '32BF'::text, 0::float8, -9999::float8)),
		   1, 1, 1) AS v
  FROM unnest(ARRAY['linear:max_edge=5', 'linear:max_edge=4.9999999999999991']) m;

-- ----------------------------------------------------------------------
-- ST_TDCDrape
-- ----------------------------------------------------------------------
-- beside the lake: as without the option
SELECT ST_AsText(ST_TDCDrape(geom, 'LINESTRING(0.5 0.75, 19.5 2.25)', 'linear:max_edge=1.5'))
	   = ST_AsText(ST_TDCDrape(geom, 'LINESTRING(0.5 0.75, 19.5 2.25)')) AS beside_the_lake_unchanged
  FROM tdc_me_lake;
-- along a shore (edges between kept and dropped triangles): draped
SELECT ST_AsText(ST_TDCDrape(geom, 'LINESTRING(2 4, 8 4)', 'linear:max_edge=1.5')) FROM tdc_me_lake;
-- the sample in the lake keeps its height, for every method
SELECT m, ST_AsText(ST_TDCDrape(geom, 'POINT(10 10)', m))
  FROM tdc_me_lake, unnest(ARRAY['linear:max_edge=1.5', 'nearest:max_edge=1.5', 'natural_neighbor:max_edge=1.5']) m
 GROUP BY m ORDER BY m;
-- nearest and natural neighbour value the vertices only: a line across the
-- lake whose vertices lie on kept triangles is draped
SELECT ST_AsText(ST_TDCDrape(geom, 'LINESTRING(2.25 10.125, 17.75 9.875)', 'nearest:max_edge=1.5')) FROM tdc_me_lake;
-- errors: a vertex in the lake; linear across the lake, or along the long
-- edge (9 4)-(11 4) whose triangles are both dropped
SELECT ST_TDCDrape(geom, 'POINT(10.5 10.25)', 'natural_neighbor:max_edge=1.5') FROM tdc_me_lake;
SELECT ST_TDCDrape(geom, 'LINESTRING(2.25 10.125, 17.75 9.875)', 'linear:max_edge=1.5') FROM tdc_me_lake;
SELECT ST_TDCDrape(geom, 'LINESTRING(2 4, 18 4)', 'linear:max_edge=1.5') FROM tdc_me_lake;
-- at max_edge 2 that edge is kept
SELECT ST_NPoints(ST_TDCDrape(geom, 'LINESTRING(2 4, 18 4)', 'linear:max_edge=2')) FROM tdc_me_lake;
-- with breaklines: the ridge (0 1)-(4 1), 4 long, an edge of both triangles
CREATE TABLE tdc_me_ridge AS
	SELECT 'LINESTRING Z (0 1 10, 4 1 10)'::geometry AS geom
	UNION ALL SELECT 'POINT Z (2 0 0)' UNION ALL SELECT 'POINT Z (2 2 4)';
SELECT ST_AsText(ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true:max_edge=4')) FROM tdc_me_ridge;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true:max_edge=3.9') FROM tdc_me_ridge;
-- GDAL's options stay refused
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:radius=1:max_edge=4') FROM tdc_me_ridge;

-- ----------------------------------------------------------------------
-- The parser's errors, the same for every function that takes a method
-- ----------------------------------------------------------------------
CREATE FUNCTION tdc_me_try(m text) RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	msg		text;
	detail	text;
BEGIN
	PERFORM ST_TDCInterpolateRaster('MULTIPOINT Z (0 0 1, 4 0 1, 0 3 1)', m, tmpl) FROM tdc_me_rast;
	RETURN 'ok';
EXCEPTION WHEN invalid_parameter_value THEN
	GET STACKED DIAGNOSTICS msg = MESSAGE_TEXT, detail = PG_EXCEPTION_DETAIL;
	RETURN msg || ' / ' || detail;
END $$;
SELECT m, tdc_me_try(m) FROM unnest(ARRAY['linear:max_edge=-1', 'linear:max_edge=0', 'linear:max_edge=abc',
	'linear:max_edge', 'natural_neighbor:MAX_EDGE=2', 'linear:max_edge=inf',
	'cubic:max_edge=2']) m;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'nearest:max_edge=-1') FROM tdc_me_ridge;
SELECT ST_TDCInterpolate(geom, (SELECT tmpl FROM tdc_me_rast), 'natural_neighbor:max_edge=x') FROM tdc_me_lake;

DROP FUNCTION tdc_me_try(text);
DROP FUNCTION tdc_me_check(raster, float8);
DROP TABLE tdc_me_lake, tdc_me_tri, tdc_me_rast, tdc_me_ridge;
SET client_min_messages = warning;
\if :me_make_raster
DROP EXTENSION tdc_delaunay_raster;
\endif
\if :me_make_postgis_raster
DROP EXTENSION postgis_raster;
\endif
RESET client_min_messages;
