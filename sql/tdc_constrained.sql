--
-- tdc_constrained: ST_TDCConstrainedDelaunayTriangles against SFCGAL's
-- constrained Delaunay triangulation (postgis_sfcgal, shipped with Debian's
-- postgresql-NN-postgis-3) on general-position input, where the constrained
-- Delaunay triangulation is unique; then the rules, Z, SRID, errors, cancel.
--
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis_sfcgal;
RESET client_min_messages;

-- SFCGAL's constrained triangulation under the name this PostGIS gives it:
-- CG_ConstrainedDelaunayTriangles where it exists (PostGIS 3.5 on; 3.6
-- warns that the ST_ name is deprecated), ST_ConstrainedDelaunayTriangles
-- before.  The body names one of them, so it is chosen when it is created.
DO $$
BEGIN
	EXECUTE format('CREATE FUNCTION tdc_sfcgal_cdt(g geometry) RETURNS geometry LANGUAGE sql AS %L',
		format('SELECT %s(g)',
			   CASE WHEN to_regprocedure('cg_constraineddelaunaytriangles(geometry)') IS NULL
					THEN 'ST_ConstrainedDelaunayTriangles' ELSE 'CG_ConstrainedDelaunayTriangles' END));
END $$;

-- Triangles of a result as a set of normalized polygons (TIN members are
-- TRIANGLEs: the same ring as a POLYGON).
CREATE FUNCTION tdc_cdt_tris(g geometry) RETURNS SETOF text LANGUAGE sql AS $$
	SELECT ST_AsText(ST_Normalize(ST_MakePolygon(ST_ExteriorRing(
		CASE WHEN GeometryType(d.geom) = 'TRIANGLE'
			 THEN ST_GeomFromText(replace(ST_AsText(d.geom), 'TRIANGLE', 'POLYGON'))
			 ELSE d.geom END))))
	FROM ST_Dump(g) d $$;

-- Same triangle set as SFCGAL?  Counts and both differences.
CREATE FUNCTION tdc_cdt_vs_sfcgal(g geometry) RETURNS text LANGUAGE sql AS $$
	WITH ours AS (SELECT tdc_cdt_tris(ST_TDCConstrainedDelaunayTriangles(g, 2)) t),
		 theirs AS (SELECT tdc_cdt_tris(tdc_sfcgal_cdt(g)) t)
	SELECT format('%s triangles, SFCGAL %s, only ours %s, only SFCGAL %s',
				  (SELECT count(*) FROM ours), (SELECT count(*) FROM theirs),
				  (SELECT count(*) FROM (SELECT t FROM ours EXCEPT SELECT t FROM theirs) x),
				  (SELECT count(*) FROM (SELECT t FROM theirs EXCEPT SELECT t FROM ours) x)) $$;

-- Contour-like nested noisy rings (as closed linestrings), free points between.
CREATE TABLE tdc_contours AS
SELECT r, ST_MakeLine(array_agg(ST_MakePoint(
		(r + 0.3 * (hashint4(r * 1000 + i) / 2147483648.0)) * cos(2 * pi() * (i % n) / n),
		(r + 0.3 * (hashint4(r * 1000 + i) / 2147483648.0)) * sin(2 * pi() * (i % n) / n))
		ORDER BY i)) AS g
FROM generate_series(1, 15) r, LATERAL (SELECT 40 + 5 * r AS n) k,
	 LATERAL generate_series(0, n) i
GROUP BY r;
-- close each ring exactly (the last vertex computed as the first)
UPDATE tdc_contours SET g = ST_SetPoint(g, ST_NPoints(g) - 1, ST_StartPoint(g));

SELECT tdc_cdt_vs_sfcgal(ST_Collect(g)) AS contours FROM tdc_contours;
SELECT tdc_cdt_vs_sfcgal(ST_Collect(g)) AS contours_and_points
FROM (SELECT g FROM tdc_contours
	  UNION ALL
	  SELECT ST_MakePoint(hashint4(i) / 2147483648.0 * 15, hashint4(-i) / 2147483648.0 * 15)
	  FROM generate_series(1, 300) i) s;

-- A polygon with holes, and points inside it.
SELECT tdc_cdt_vs_sfcgal(ST_Collect(ARRAY[
	ST_Difference(ST_Buffer('POINT(0 0)'::geometry, 10, 24),
				  ST_Union(ARRAY[ST_Buffer('POINT(-4 0)'::geometry, 2, 5),
								 ST_Buffer('POINT(4 1)'::geometry, 2.5, 7),
								 ST_Buffer('POINT(0.3 5)'::geometry, 1.7, 3)])),
	ST_GeomFromText('MULTIPOINT(1.1 -3.3, -2.2 -6.1, 6.3 -2.9, -0.7 1.4)')])) AS polygon_with_holes;

-- The aggregate over one row per contour segment (with free points) equals
-- the function on their collection: serially, then under a parallel plan
-- whose partial states carry the segments between processes.
CREATE FUNCTION tdc_cdt_same(a geometry, b geometry) RETURNS text LANGUAGE sql AS $$
	SELECT format('%s triangles, %s, only first %s, only second %s',
				  (SELECT count(*) FROM tdc_cdt_tris(a)), (SELECT count(*) FROM tdc_cdt_tris(b)),
				  (SELECT count(*) FROM (SELECT tdc_cdt_tris(a) EXCEPT SELECT tdc_cdt_tris(b)) x),
				  (SELECT count(*) FROM (SELECT tdc_cdt_tris(b) EXCEPT SELECT tdc_cdt_tris(a)) x)) $$;
CREATE TABLE tdc_contour_segs AS
SELECT ST_MakeLine(ST_PointN(g, i), ST_PointN(g, i + 1)) AS g
FROM tdc_contours, LATERAL generate_series(1, ST_NPoints(g) - 1) i
UNION ALL
SELECT ST_MakePoint(hashint4(i) / 2147483648.0 * 15, hashint4(-i) / 2147483648.0 * 15)
FROM generate_series(1, 300) i;
SELECT tdc_cdt_same((SELECT ST_TDCConstrainedDelaunay(g) FROM tdc_contour_segs),
					(SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(g)) FROM tdc_contour_segs))
	AS aggregate_serial;
-- (serialization costs lowered for this small table, as in tdc_parallel)
ALTER FUNCTION st_tdcconstraineddelaunay_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcconstraineddelaunay_deserialfn(bytea, internal) COST 1;
ANALYZE tdc_contour_segs;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
EXPLAIN (COSTS OFF) SELECT ST_TDCConstrainedDelaunay(g, 2) FROM tdc_contour_segs;
CREATE TABLE tdc_cdt_par AS SELECT ST_TDCConstrainedDelaunay(g, 2) AS g FROM tdc_contour_segs;
-- flags 5 crosses the processes too: the same constraint edges as serially
CREATE TABLE tdc_cdt_par5 AS SELECT ST_TDCConstrainedDelaunay(g, 5) AS g FROM tdc_contour_segs;
RESET parallel_setup_cost;
RESET parallel_tuple_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;
RESET parallel_leader_participation;
ALTER FUNCTION st_tdcconstraineddelaunay_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcconstraineddelaunay_deserialfn(bytea, internal) COST 10000000;
SELECT GeometryType(g) AS parallel_type,
	   tdc_cdt_same(g, (SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(g)) FROM tdc_contour_segs))
	AS aggregate_parallel
FROM tdc_cdt_par;
SELECT ST_NumGeometries(p.g) AS parallel_constraint_edges,
	   ST_Equals(p.g, (SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(g), 5) FROM tdc_contour_segs))
	AS same_as_function
FROM tdc_cdt_par5 p;
DROP TABLE tdc_cdt_par5;

-- ST_TDCConstrainedDelaunayDump: the same triangles as the function on the
-- query's collection, one row each, numbered from 1; the query's rules are
-- ST_TDCDelaunayDump's (read-only, one geometry column, NULL rows skipped).
SELECT tdc_cdt_same((SELECT ST_Collect(geom ORDER BY id) FROM ST_TDCConstrainedDelaunayDump(
						'SELECT g FROM tdc_contour_segs UNION ALL SELECT NULL::geometry')),
					(SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(g)) FROM tdc_contour_segs))
	AS dump_same;
SELECT min(id) AS first_id, max(id) = count(*) AS numbered
FROM ST_TDCConstrainedDelaunayDump('SELECT g FROM tdc_contour_segs');
SELECT id, ST_AsText(geom) AS dump_rhombus
FROM ST_TDCConstrainedDelaunayDump('SELECT ''GEOMETRYCOLLECTION(MULTIPOINT(5 1,5 -1,5 5,5 -5),LINESTRING(0 0,10 0))''::geometry')
ORDER BY id;
SELECT count(*) AS dump_no_rows FROM ST_TDCConstrainedDelaunayDump('SELECT g FROM tdc_contour_segs WHERE false');
SELECT count(*) AS dump_null_query FROM ST_TDCConstrainedDelaunayDump(NULL);
\set VERBOSITY terse
SELECT count(*) FROM ST_TDCConstrainedDelaunayDump('VALUES (''LINESTRING(0 0,2 2)''::geometry), (''LINESTRING(0 2,2 0)'')');
SELECT count(*) FROM ST_TDCConstrainedDelaunayDump('DELETE FROM tdc_contour_segs RETURNING g');
SELECT count(*) FROM ST_TDCConstrainedDelaunayDump('SELECT 1');
\set VERBOSITY default
SELECT count(*) AS segs_kept FROM tdc_contour_segs;
-- flags must agree on all rows; a crossing across rows is the same error
SELECT ST_TDCConstrainedDelaunay(g, i % 2) FROM (VALUES ('POINT(0 0)'::geometry, 1), ('POINT(1 0)', 2)) v(g, i);
SELECT ST_TDCConstrainedDelaunay(g) FROM (VALUES ('LINESTRING(0 0,2 2)'::geometry), ('LINESTRING(0 2,2 0)')) v(g);
SELECT ST_TDCConstrainedDelaunay(g) AS no_rows FROM tdc_contour_segs WHERE false;

-- The thin rhombus: the Delaunay triangulation lacks the segment.
SELECT ST_AsText(ST_Normalize(ST_TDCConstrainedDelaunayTriangles(
	'GEOMETRYCOLLECTION(MULTIPOINT(5 1,5 -1,5 5,5 -5),LINESTRING(0 0,10 0))'::geometry))) AS rhombus;
SELECT tdc_cdt_vs_sfcgal('GEOMETRYCOLLECTION(MULTIPOINT(5 1,5 -1,5 5,5 -5),LINESTRING(0 0,10 0))') AS rhombus;

-- A segment through other vertices is split there (flags 1: the edges).
SELECT ST_AsText(ST_Normalize(ST_TDCConstrainedDelaunayTriangles(
	'GEOMETRYCOLLECTION(LINESTRING(0 0,4 0),MULTIPOINT(1 0,2 0,3 0,2 0.01,2 -0.01))'::geometry, 1)))
	AS split_edges;
-- flags 5: the constraint edges alone, split at the vertices on them, with
-- Z and SRID; no bounding box of the whole triangulation (the envelope is the
-- edges'), EMPTY for no segments, and the aggregate.
SELECT ST_AsText(ST_Normalize(ST_TDCConstrainedDelaunayTriangles(
	'GEOMETRYCOLLECTION(LINESTRING(0 0,4 0),MULTIPOINT(1 0,2 0,3 0,2 0.01,2 -0.01))'::geometry, 5)))
	AS constraint_edges;
SELECT ST_AsEWKT(ST_Normalize(ST_TDCConstrainedDelaunayTriangles(
	'SRID=3857;GEOMETRYCOLLECTION(LINESTRING Z (0 0 1,4 0 2),MULTIPOINT Z (1 0 5,2 0.01 6,3 3 8))'::geometry, 5)))
	AS constraint_edges_z;
SELECT ST_AsText(ST_Envelope(ST_TDCConstrainedDelaunayTriangles(
	'GEOMETRYCOLLECTION(LINESTRING(0 0,1 0),MULTIPOINT(5 5,-3 7))'::geometry, 5))) AS constraint_envelope;
SELECT ST_AsEWKT(ST_TDCConstrainedDelaunayTriangles('SRID=4326;MULTIPOINT(0 0,1 1,2 0)'::geometry, 5))
	AS no_constraints;
SELECT ST_AsText(ST_Normalize(ST_TDCConstrainedDelaunay(geom, 5))) AS constraint_edges_agg
FROM (VALUES ('LINESTRING(0 0,1 0,1 1)'::geometry), ('POLYGON((3 3,4 3,4 4,3 3))'), ('POINT(9 9)')) v(geom);

-- collinear overlaps, a zero-length segment, duplicate vertices
SELECT ST_NumGeometries(ST_TDCConstrainedDelaunayTriangles(
	'GEOMETRYCOLLECTION(LINESTRING(0 0,2 0),LINESTRING(1 0,3 0),LINESTRING(3 0,3 0),POINT(1 1),POINT(1 1))'::geometry))
	AS overlap_triangles;

-- Z kept (of the first duplicate), M dropped, SRID carried; TIN and empty.
-- (The triangles through tdc_norm: ST_Normalize keeps a TIN from PostGIS
-- 3.7 on, and made it a collection of polygons before.)
SELECT GeometryType(g) AS type, ST_SRID(g) AS srid, tdc_norm(g) AS z_srid
FROM (SELECT ST_TDCConstrainedDelaunayTriangles(
	'SRID=3857;GEOMETRYCOLLECTION(LINESTRING Z (0 0 1,2 0 2),POINT Z (1 1 3),POINT Z (1 -1 4),POINT Z (1 -1 5))'::geometry, 2) AS g) s;
SELECT ST_AsEWKT(ST_TDCConstrainedDelaunayTriangles('SRID=4326;LINESTRING M (0 0 7,1 0 8)'::geometry, 1))
	AS m_dropped;
SELECT ST_AsEWKT(ST_TDCConstrainedDelaunayTriangles('SRID=4326;POLYGON EMPTY'::geometry)) AS empty;

-- Errors: crossing segments, with the hint; NaN; bad flags.
\set VERBOSITY default
SELECT ST_TDCConstrainedDelaunayTriangles('MULTILINESTRING((0 0,2 2),(0 2,2 0))'::geometry);
SELECT ST_TDCConstrainedDelaunayTriangles('POLYGON((0 0,4 0,4 4,0 4,0 0),(1 1,5 2,1 3,1 1))'::geometry);
-- noded first, the same lines work
SELECT ST_NumGeometries(ST_TDCConstrainedDelaunayTriangles(
	ST_Node('MULTILINESTRING((0 0,2 2),(0 2,2 0))'::geometry))) AS noded;
SELECT ST_TDCConstrainedDelaunayTriangles(ST_MakeLine(ST_MakePoint(0, 0), ST_MakePoint('NaN', 1)));
SELECT ST_TDCConstrainedDelaunayTriangles('LINESTRING(0 0,1 1)'::geometry, 3);
SELECT ST_TDCConstrainedDelaunayTriangles('LINESTRING(0 0,1 1)'::geometry, 4);
\set VERBOSITY terse

-- Cancel: a statement_timeout during a long constrained triangulation
-- (one thread; 4000 long lines across 300000 points) stops it, and the
-- session goes on.  Quiet, the statement would take some 380 ms: reading
-- and triangulating about 80, the insertion about 175, writing and
-- ST_NumGeometries the rest; the timeout falls in the insertion then, and
-- earlier under load, never after the end (300 ms with 1000 lines fell
-- after the insertion, and the statement could finish first).
CREATE TABLE tdc_cdt_big AS
SELECT ST_Collect(g) AS g FROM (
	SELECT ST_MakePoint((hashint4(i) & 2147483647) / 2147483648.0,
						(hashint4(-i) & 2147483647) / 2147483648.0) AS g
	FROM generate_series(1, 300000) i
	UNION ALL
	SELECT ST_MakeLine(ST_MakePoint(-1, j / 4000.0), ST_MakePoint(2, j / 4000.0 + 0.0005))
	FROM generate_series(0, 3999) j) s;
SET tdc_delaunay.threads = 1;
SET statement_timeout = '150ms';
SELECT ST_NumGeometries(ST_TDCConstrainedDelaunayTriangles(g)) FROM tdc_cdt_big;
RESET statement_timeout;
RESET tdc_delaunay.threads;
SELECT ST_NumGeometries(ST_TDCConstrainedDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)'::geometry)) AS after_cancel;
DROP TABLE tdc_cdt_big;
