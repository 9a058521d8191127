--
-- tdc_maxedge: max_edge=L in the method of ST_TDCInterpolateRaster,
-- ST_TDCInterpolate, ST_TDCDrape and ST_TDCContours (issue 39): the
-- triangles with an edge longer than L are dropped: their pixels are empty,
-- a draped target may not cross them, contour lines stop at them.
--
-- The samples: a lake, the lattice 0..20 with no sample within 6 of
-- (10 10) but one at it, heights z = x + 2 y.  The pixels expected empty
-- come from an independent rule in SQL: a pixel centre (never a sample)
-- has a value when some triangle of ST_TDCDelaunayTriangles covering it
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

-- each pixel centre (never a sample: they lie at quarters) by the rule, at
-- max_edge 1.5 and 2
CREATE TABLE tdc_me_px AS
	SELECT c, rw,
		   EXISTS (SELECT FROM tdc_me_tri WHERE t && p AND ST_Covers(t, p) AND longest <= 1.5) AS kept_1_5,
		   EXISTS (SELECT FROM tdc_me_tri WHERE t && p AND ST_Covers(t, p) AND longest <= 2) AS kept_2
	  FROM (SELECT c, rw, ST_MakePoint((c - 0.5) * 0.5, 20 - (rw - 0.5) * 0.5) AS p
			  FROM generate_series(1, 40) c, generate_series(1, 40) rw) s;
-- each pixel: empty or not, against the rule (l: 1.5, 2, or none)
CREATE FUNCTION tdc_me_check(r raster, l float8)
	RETURNS TABLE (empty_pixels bigint, unlike_the_rule bigint) LANGUAGE sql AS $$
	SELECT count(*) FILTER (WHERE ST_Value(r, 1, c, rw) IS NULL),
		   count(*) FILTER (WHERE (ST_Value(r, 1, c, rw) IS NULL) =
								  CASE l WHEN 1.5 THEN kept_1_5 WHEN 2 THEN kept_2 ELSE true END)
	  FROM tdc_me_px $$;

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
WITH a AS MATERIALIZED (SELECT ST_TDCInterpolateRaster((SELECT ST_Collect(geom) FROM tdc_me_lake), 'natural_neighbor', tmpl) AS r0,
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
-- ST_TDCContours(geom, interval, base, method)
-- ----------------------------------------------------------------------
-- z = x: the levels 0.5 .. 19.5 are the lines x = level; with max_edge each
-- is cut where the kept triangles end, and their length is that of the
-- vertical lines within the kept triangles' union (computed by GEOS)
CREATE TABLE tdc_me_zx AS SELECT ST_MakePoint(ST_X(geom), ST_Y(geom), ST_X(geom)) AS geom FROM tdc_me_lake;
CREATE TABLE tdc_me_c AS
	SELECT ST_TDCContours(geom, 1, 0.5) AS plain,
		   ST_TDCContours(geom, 1, 0.5, 'linear') AS linear,
		   ST_TDCContours(geom, 1, 0.5, 'linear:max_edge=1.5') AS cut
	  FROM tdc_me_zx;
SELECT ST_NumGeometries(plain) AS lines_without, ST_AsBinary(plain) = ST_AsBinary(linear) AS linear_is_plain,
	   ST_NumGeometries(cut) AS lines_with_max_edge,
	   (SELECT count(*) FROM ST_Dump(cut) d WHERE ST_Z(ST_StartPoint(d.geom)) = 10.5) AS pieces_at_10_5,
	   (SELECT bool_and(NOT ST_IsClosed(d.geom)) FROM ST_Dump(cut) d) AS all_open
  FROM tdc_me_c;
SELECT abs(ST_Length(cut) - (SELECT sum(ST_Length(ST_Intersection(ST_MakeLine(ST_MakePoint(k + 0.5, 0), ST_MakePoint(k + 0.5, 20)), u)))
							   FROM generate_series(0, 19) k,
									(SELECT ST_Union(t) AS u FROM tdc_me_tri WHERE longest <= 1.5) kept)) < 1e-9
	   AS length_within_the_kept_triangles,
	   (SELECT bool_and(EXISTS (SELECT FROM tdc_me_tri WHERE longest <= 1.5 AND ST_DWithin(t, p.geom, 1e-12)))
		  FROM ST_DumpPoints(cut) p) AS every_vertex_on_a_kept_triangle
  FROM tdc_me_c;
-- in a parallel plan the method travels with the states (serial, deserial, combine)
CREATE TABLE tdc_me_par AS SELECT geom FROM tdc_me_zx, generate_series(1, 3);
ANALYZE tdc_me_par;
SET max_parallel_workers_per_gather = 0;
CREATE TABLE tdc_me_serial AS SELECT ST_AsBinary(ST_TDCContours(geom, 1, 0.5, 'linear:max_edge=1.5')) AS c FROM tdc_me_par;
ALTER FUNCTION st_tdccontours_serialfn(internal) COST 1;
ALTER FUNCTION st_tdccontours_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
CREATE FUNCTION tdc_me_par_run(query text, OUT workers_launched int) LANGUAGE plpgsql AS $$
DECLARE
	plan		jsonb;
BEGIN
	EXECUTE format('EXPLAIN (ANALYZE, VERBOSE, COSTS OFF, TIMING OFF, SUMMARY OFF, FORMAT JSON) CREATE TABLE tdc_me_parallel AS %s',
				   query) INTO plan;
	SELECT coalesce(sum((n ->> 'Workers Launched')::int), 0) INTO workers_launched
	  FROM jsonb_path_query(plan, 'strict $.** ? (exists (@."Workers Launched"))') n;
END $$;
SELECT workers_launched > 0 AS workers_ran
  FROM tdc_me_par_run($q$SELECT ST_AsBinary(ST_TDCContours(geom, 1, 0.5, 'linear:max_edge=1.5')) AS c FROM tdc_me_par$q$);
SELECT s.c = p.c AS parallel_same FROM tdc_me_serial s, tdc_me_parallel p;
RESET parallel_leader_participation;
RESET max_parallel_workers_per_gather;
RESET min_parallel_table_scan_size;
RESET parallel_tuple_cost;
RESET parallel_setup_cost;
ALTER FUNCTION st_tdccontours_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdccontours_deserialfn(bytea, internal) COST 10000000;
-- the method: linear with max_edge only, the same in every row; NULL skips the row
SELECT ST_NumGeometries(ST_TDCContours(geom, 1, 0.5, CASE WHEN ST_X(geom) = 3 THEN NULL ELSE 'linear:max_edge=1.5' END))
  FROM tdc_me_zx;
SELECT ST_TDCContours(geom, 1, 0.5, 'nearest:max_edge=1.5') FROM tdc_me_zx;
SELECT ST_TDCContours(geom, 1, 0.5, 'linear:radius=0:max_edge=1.5') FROM tdc_me_zx;
SELECT ST_TDCContours(geom, 1, 0.5, 'linear:breaklines=true') FROM tdc_me_zx;
SELECT ST_TDCContours(geom, 1, 0.5, 'linear:max_edge=-1') FROM tdc_me_zx;
SELECT ST_TDCContours(geom, 1, 0.5, CASE WHEN ST_X(geom) < 5 THEN 'linear' ELSE 'linear:max_edge=2' END) FROM tdc_me_zx;

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
DROP FUNCTION tdc_me_par_run(text);
DROP TABLE tdc_me_lake, tdc_me_tri, tdc_me_px, tdc_me_rast, tdc_me_ridge, tdc_me_zx, tdc_me_c, tdc_me_par, tdc_me_serial,
	tdc_me_parallel;
SET client_min_messages = warning;
\if :me_make_raster
DROP EXTENSION tdc_delaunay_raster;
\endif
\if :me_make_postgis_raster
DROP EXTENSION postgis_raster;
\endif
RESET client_min_messages;
