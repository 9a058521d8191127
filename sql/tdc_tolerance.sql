--
-- tdc_tolerance: the tolerance rule holds exactly, wherever the points lie.
-- Rule: take the points in (x, y) order; keep a point unless a kept one is
-- closer than the tolerance (exact distance); a dropped point joins the
-- nearest such kept point.
--
-- Runs alone too (make installcheck REGRESS=tdc_tolerance).
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay;
RESET client_min_messages;

-- Issue 16: with a point 3e6 away, the two points 4.07e-11 apart were both
-- kept under tolerance 1e-10.  The later one in (x, y) order is dropped:
-- 3 vertices, one triangle.
SELECT ST_GeometryType(e) AS type, ST_NumGeometries(e) AS edges
FROM (SELECT ST_TDCDelaunayTriangles('MULTIPOINT((-3000000 0),(0 0.001),(2.2154003234078255e-10 0),(2.6228008245794195e-10 0))', 1e-10, 1) AS e) r;
SELECT DISTINCT ST_X(p) AS x, ST_Y(p) AS y
FROM (SELECT (ST_DumpPoints(ST_TDCDelaunayTriangles('MULTIPOINT((-3000000 0),(0 0.001),(2.2154003234078255e-10 0),(2.6228008245794195e-10 0))', 1e-10, 1))).geom AS p) d
ORDER BY x, y;
-- The same with the far point at -1, and as triangles and through the aggregate.
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT((-1 0),(0 0.001),(2.2154003234078255e-10 0),(2.6228008245794195e-10 0))', 1e-10, 1)) AS edges_near,
	   ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT((-3000000 0),(0 0.001),(2.2154003234078255e-10 0),(2.6228008245794195e-10 0))', 1e-10)) AS triangles;
SELECT ST_NumGeometries(ST_TDCDelaunay(g, 1e-10, 1)) AS edges_aggregate
FROM (VALUES ('POINT(-3000000 0)'::geometry), ('POINT(0 0.001)'), ('POINT(2.2154003234078255e-10 0)'),
			 ('POINT(2.6228008245794195e-10 0)')) v(g);

-- Exactly at the tolerance is not closer: (3 4) is 5 from (0 0) and stays;
-- one ulp more tolerance drops it, leaving two sites and no triangle.
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 3 4, 6 0)', 5)) AS at_tolerance,
	   ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 3 4, 6 0)', 5.000000000000001)) AS above_tolerance;
