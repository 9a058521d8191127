--
-- tdc_raster_gdal: ST_TDCInterpolateRaster against PostGIS's
-- ST_InterpolateRaster (GDAL's gridding) on 64BF bands; the
-- ST_TDCInterpolate aggregates, serial and parallel; a cancel.  Needs
-- tdc_raster (the extension) and tdc_basic (tdc_random_points,
-- tdc_backend_threads).
--
-- The terrain: 3000 points in general position (hashed coordinates) in
-- [0, 100]^2, z a smooth hill and valley; the template's 60 x 50 pixels
-- reach a few pixels beyond the samples' hull on every side.
CREATE TABLE tdc_ip_pts AS
SELECT id, ST_MakePoint(x, y, 100 + 30 * sin(x / 7) * cos(y / 5) + 0.5 * x - 0.2 * y) AS geom
FROM (SELECT id, ST_X(geom) * 100 AS x, ST_Y(geom) * 100 AS y FROM tdc_random_points(3000, 5)) s;
CREATE TABLE tdc_ip_tmpl AS
SELECT ST_AddBand(ST_MakeEmptyRaster(60, 50, -5, 106, 1.85, -2.22, 0, 0, 0), '64BF'::text, -9999::float8, -9999::float8) AS r;

-- Both ways, with GDAL's defaults (radius -1: outside the hull the nearest
-- sample, at any distance) and with radius=0 (outside the hull nodata;
-- GDAL writes its nodata option there, made the band's so that it reads as
-- nodata too).  GDAL's grid is the template's extent cut into columns and
-- rows, its pixel centres min + (i + 0.5) * (max - min) / n.
CREATE TABLE tdc_ip AS
SELECT m, ST_TDCInterpolateRaster(p, m, r) AS ours,
	   ST_InterpolateRaster(p, CASE WHEN m = 'linear' THEN m ELSE m || ':nodata=-9999' END, r) AS theirs,
	   ST_ConvexHull(p) AS hull
FROM (SELECT ST_Collect(geom) AS p FROM tdc_ip_pts) s, tdc_ip_tmpl, (VALUES ('linear'), ('linear:radius=0')) v(m);

-- Every pixel: where both have a value inside the hull (or on it), within
-- 1e-9 relative; where one is nodata and the other not, the pixel centre
-- must lie on the hull itself (within 1e-9: the two compute the centres in
-- different ways).
CREATE TABLE tdc_ip_px AS
SELECT m, x, y, c, ST_Value(ours, 1, x, y) AS a, ST_Value(theirs, 1, x, y) AS b,
	   ST_Intersects(hull, c) AS inside, ST_Distance(c, ST_Boundary(hull)) AS to_hull
FROM tdc_ip, generate_series(1, 60) x, generate_series(1, 50) y, ST_PixelAsCentroid(ours, x, y) c;
SELECT m, count(*) AS pixels,
	   count(*) FILTER (WHERE a IS NOT NULL AND b IS NOT NULL) AS both_values,
	   count(*) FILTER (WHERE a IS NULL AND b IS NULL) AS both_nodata,
	   count(*) FILTER (WHERE inside AND abs(a - b) > 1e-9 * greatest(abs(a), abs(b))) AS inside_beyond_1e9,
	   count(*) FILTER (WHERE (a IS NULL) <> (b IS NULL) AND to_hull > 1e-9) AS nodata_differs_off_hull,
	   max(abs(a - b) / greatest(abs(a), abs(b))) FILTER (WHERE inside) < 1e-12 AS inside_max_rel_below_1e12
FROM tdc_ip_px GROUP BY m ORDER BY m;
-- Outside the hull under the default radius (-1) both take "the nearest"
-- sample's value.  GDAL finds it in a square search box, doubled until it
-- holds a sample, and takes the nearest in that box: a sample up to 2 sqrt 2
-- times as far as the nearest one.  Ours is the nearest, decided exactly.
-- So where the two differ: ours is the nearest sample's Z (strictly nearer
-- than the second), GDAL's that of a sample within 2 sqrt 2 times as far.
-- (How many differ depends on GDAL's version: 16 of the 574 pixels outside
-- the hull with GDAL 3.6.)
SELECT count(*) FILTER (WHERE n.z = a AND n.d < n.d2) = count(*) AS ours_the_nearest,
	   count(*) FILTER (WHERE g.d > n.d AND g.d <= 2 * sqrt(2) * n.d) = count(*) AS gdal_a_farther_one_in_its_box
FROM tdc_ip_px,
	 LATERAL (SELECT ST_Z(q.geom) AS z, ST_Distance(q.geom, c) AS d,
					 (SELECT ST_Distance(q2.geom, c) FROM tdc_ip_pts q2 ORDER BY q2.geom <-> c OFFSET 1 LIMIT 1) AS d2
			  FROM tdc_ip_pts q ORDER BY q.geom <-> c LIMIT 1) n,
	 LATERAL (SELECT min(ST_Distance(q.geom, c)) AS d FROM tdc_ip_pts q WHERE ST_Z(q.geom) = b) g
WHERE m = 'linear' AND NOT inside AND abs(a - b) > 1e-9 * greatest(abs(a), abs(b));
-- The result's geometry is the template's.
SELECT m, ST_MetaData(ours) = ST_MetaData(theirs) AS same_metadata, ST_BandPixelType(ours) AS pixtype,
	   ST_BandNoDataValue(ours) AS nodata
FROM tdc_ip ORDER BY m;

-- Natural neighbour and linear reproduce a plane (to rounding), inside the
-- hull; exact at the samples.
WITH plane AS (SELECT ST_Collect(ST_MakePoint(ST_X(geom), ST_Y(geom), 2 * ST_X(geom) - 3 * ST_Y(geom) + 7)) AS p
			   FROM tdc_ip_pts WHERE id <= 500)
SELECT m, count(*) AS pixels, max(abs(ST_Value(o, 1, x, y) - (2 * ST_X(c) - 3 * ST_Y(c) + 7))) < 1e-9 AS plane
FROM plane, tdc_ip_tmpl, (VALUES ('linear:radius=0'), ('natural_neighbor:radius=0')) v(m),
	 ST_TDCInterpolateRaster(p, m, r) o, generate_series(1, 60) x, generate_series(1, 50) y,
	 ST_PixelAsCentroid(o, x, y) c
WHERE ST_Value(o, 1, x, y) IS NOT NULL
GROUP BY m ORDER BY m;

-- ----------------------------------------------------------------------
-- The aggregates
-- ----------------------------------------------------------------------
-- The same raster as the function over the collection, byte for byte; the
-- two-argument form is 'linear' on band 1.
SELECT ST_AsBinary(ST_TDCInterpolate(geom, r)) = (SELECT ST_AsBinary(ours) FROM tdc_ip WHERE m = 'linear') AS same_default,
	   ST_AsBinary(ST_TDCInterpolate(geom, r, 'linear:radius=0')) =
		   (SELECT ST_AsBinary(ours) FROM tdc_ip WHERE m = 'linear:radius=0') AS same_radius0,
	   ST_AsBinary(ST_TDCInterpolate(geom, r, 'natural_neighbor', 1)) =
		   (SELECT ST_AsBinary(ST_TDCInterpolateRaster(ST_Collect(q.geom), 'natural_neighbor', t.r))
			FROM tdc_ip_pts q, tdc_ip_tmpl t GROUP BY t.r) AS same_natural
FROM tdc_ip_pts, tdc_ip_tmpl;
-- No row, or NULL rows only: NULL.
SELECT ST_TDCInterpolate(geom, r) IS NULL AS no_rows FROM tdc_ip_pts, tdc_ip_tmpl WHERE id < 0;
SELECT ST_TDCInterpolate(NULL::geometry, r) IS NULL AS null_rows FROM tdc_ip_tmpl;
-- A row without Z is named; the template and method must not change.
\set VERBOSITY terse
SELECT ST_TDCInterpolate(g, r) FROM tdc_ip_tmpl,
	(VALUES ('POINT Z (1 1 1)'::geometry), ('POINT Z (5 1 1)'), ('POINT (3 3)')) v(g);
SELECT ST_TDCInterpolate(geom, CASE WHEN id = 7 THEN ST_SetSRID(r, 4326) ELSE r END) FROM tdc_ip_pts, tdc_ip_tmpl;
SELECT ST_TDCInterpolate(geom, r, CASE WHEN id = 7 THEN 'nearest' ELSE 'linear' END) FROM tdc_ip_pts, tdc_ip_tmpl;
SELECT ST_TDCInterpolate(geom, r2, 'linear', CASE WHEN id = 7 THEN 2 ELSE 1 END)
FROM tdc_ip_pts, (SELECT ST_AddBand(r, '64BF'::text, 0::float8, 0::float8) AS r2 FROM tdc_ip_tmpl) t;
SELECT ST_TDCInterpolate(geom, r, 'linear', 2) FROM tdc_ip_pts, tdc_ip_tmpl;
SELECT ST_TDCInterpolate(geom, r, 'cubic') FROM tdc_ip_pts, tdc_ip_tmpl;
\set VERBOSITY default

-- Under a parallel plan, every row read by a worker (see tdc_parallel for
-- why the plan's figures are taken from the run that makes the result).
-- The template is a scalar subquery: an InitPlan the leader runs and passes
-- to the workers (the plan's text differs between majors, so it is not
-- shown).
CREATE FUNCTION tdc_ip_par_run(dest text, query text, OUT workers_launched int, OUT rows_by_workers numeric)
	LANGUAGE plpgsql AS $$
DECLARE
	plan		jsonb;
BEGIN
	EXECUTE format('EXPLAIN (ANALYZE, VERBOSE, COSTS OFF, TIMING OFF, SUMMARY OFF, FORMAT JSON) CREATE TABLE %I AS %s',
				   dest, query) INTO plan;
	SELECT coalesce(sum((n ->> 'Workers Launched')::int), 0) INTO workers_launched
	FROM jsonb_path_query(plan, 'strict $.** ? (exists (@."Workers Launched"))') n;
	SELECT coalesce(sum((w ->> 'Actual Rows')::numeric * (w ->> 'Actual Loops')::int), 0) INTO rows_by_workers
	FROM jsonb_path_query(plan, 'strict $.** ? (@."Node Type" == "Seq Scan" && @."Relation Name" == "tdc_ip_pts")."Workers"[*]') w;
END $$;
ANALYZE tdc_ip_pts;
ALTER FUNCTION st_tdcinterpolate_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcinterpolate_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
SELECT workers_launched > 0 AS workers_launched, rows_by_workers = 3000 AS every_row_read_by_a_worker
FROM tdc_ip_par_run('tdc_ip_par', 'SELECT ST_TDCInterpolate(geom, (SELECT r FROM tdc_ip_tmpl), ''linear:radius=0'') AS o FROM tdc_ip_pts');
SELECT ST_AsBinary(o) = (SELECT ST_AsBinary(ours) FROM tdc_ip WHERE m = 'linear:radius=0') AS same_as_serial
FROM tdc_ip_par;
RESET parallel_setup_cost;
RESET parallel_tuple_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;
RESET parallel_leader_participation;
ALTER FUNCTION st_tdcinterpolate_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcinterpolate_deserialfn(bytea, internal) COST 10000000;

-- Breaklines under a parallel plan: eight horizontal polylines (heights
-- from the same surface) among the samples; their segments travel with
-- the vertices in the state (version 2).  The aggregate gives the function's
-- raster serially and in parallel, and not the raster without breaklines.
CREATE TABLE tdc_ip_brk AS SELECT id, geom FROM tdc_ip_pts
	UNION ALL SELECT 4000 + k, ST_MakeLine(ARRAY(
		SELECT ST_MakePoint(x, 11 * k + 0.5, 100 + 30 * sin(x / 7) * cos((11 * k + 0.5) / 5) + 0.5 * x - 0.2 * (11 * k + 0.5))
		FROM generate_series(2, 98, 6) x))
	FROM generate_series(1, 8) k;
ANALYZE tdc_ip_brk;
CREATE TABLE tdc_ip_brk_fn AS
SELECT ST_AsBinary(ST_TDCInterpolateRaster(ST_Collect(geom), 'linear:radius=0:breaklines=true', r)) AS brk,
	   ST_AsBinary(ST_TDCInterpolateRaster(ST_Collect(geom), 'linear:radius=0', r)) AS plain
FROM tdc_ip_brk, tdc_ip_tmpl GROUP BY r;
SELECT ST_AsBinary(ST_TDCInterpolate(geom, r, 'linear:radius=0:breaklines=true')) = (SELECT brk FROM tdc_ip_brk_fn) AS same_serial,
	   (SELECT brk <> plain FROM tdc_ip_brk_fn) AS breaklines_differ
FROM tdc_ip_brk, tdc_ip_tmpl;
ALTER FUNCTION st_tdcinterpolate_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcinterpolate_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
SELECT workers_launched > 0 AS workers_launched
FROM tdc_ip_par_run('tdc_ip_brk_par', 'SELECT ST_TDCInterpolate(geom, (SELECT r FROM tdc_ip_tmpl), ''linear:radius=0:breaklines=true'') AS o FROM tdc_ip_brk');
SELECT ST_AsBinary(o) = (SELECT brk FROM tdc_ip_brk_fn) AS same_as_serial FROM tdc_ip_brk_par;
RESET parallel_setup_cost;
RESET parallel_tuple_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;
RESET parallel_leader_participation;
ALTER FUNCTION st_tdcinterpolate_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcinterpolate_deserialfn(bytea, internal) COST 10000000;
DROP TABLE tdc_ip_brk, tdc_ip_brk_fn, tdc_ip_brk_par;

-- A statement_timeout inside the grid operation: 3000 x 3000 natural
-- neighbour values from the 3000 samples, seconds of work on the engine's
-- threads.  The template is stored beforehand (a value read by its first
-- bytes), and the samples take milliseconds to triangulate, so the timeout
-- lands in the grid; the threads are gone afterwards and the session goes on.
CREATE TABLE tdc_ip_bigtmpl AS
SELECT ST_AddBand(ST_MakeEmptyRaster(3000, 3000, -5, 106, 0.037, -0.037, 0, 0, 0), '64BF'::text,
				  0::float8, -1::float8) AS r;
CREATE FUNCTION tdc_ip_cancel_probe() RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
BEGIN
	PERFORM ST_Width(ST_TDCInterpolateRaster(p, 'natural_neighbor', r))
	FROM (SELECT ST_Collect(geom) AS p FROM tdc_ip_pts) s, tdc_ip_bigtmpl;
	RETURN 'not canceled';
EXCEPTION WHEN query_canceled THEN
	RETURN 'canceled' || CASE WHEN clock_timestamp() - t0 < interval '2 s' THEN ', promptly'
						 ELSE ', too late: ' || (clock_timestamp() - t0)::text END;
END $$;
SET statement_timeout = '500ms';
SELECT tdc_ip_cancel_probe();
RESET statement_timeout;
SELECT tdc_backend_threads() AS threads_after_cancel;

DROP TABLE tdc_ip_pts, tdc_ip_tmpl, tdc_ip, tdc_ip_px, tdc_ip_par, tdc_ip_bigtmpl;
DROP FUNCTION tdc_ip_par_run(text, text);
DROP FUNCTION tdc_ip_cancel_probe();
-- The tests after this one run without the raster extensions, as before.
DROP EXTENSION tdc_delaunay_raster;
DROP EXTENSION postgis_raster;
