--
-- tdc_dump: ST_TDCDelaunayDump, one row per triangle.
--
CREATE TABLE tdc_dump_pts AS SELECT id, ST_SetSRID(geom, 3857) AS geom FROM tdc_random_points(20000, 5);

CREATE TABLE tdc_dump_out AS SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_dump_pts');
SELECT count(*) = tdc_expected_triangles((SELECT ST_Collect(geom) FROM tdc_dump_pts)) AS count_2n_2_h,
	   count(*) = 2 * 20000 - 2 - (SELECT ST_NPoints(ST_ConvexHull(ST_Collect(geom))) - 1 FROM tdc_dump_pts) AS count_check2,
	   min(id) = 1 AS ids_from_1, max(id) = count(*) AS ids_dense, count(DISTINCT id) = count(*) AS ids_unique,
	   bool_and(ST_GeometryType(geom) = 'ST_Polygon') AS polygons,
	   bool_and(ST_SRID(geom) = 3857) AS srid,
	   bool_and(ST_IsPolygonCCW(geom)) AS ccw,
	   bool_and(ST_NPoints(geom) = 4) AS closed_rings,
	   bool_and(ST_IsValid(geom)) AS valid
FROM tdc_dump_out;
-- Same triangles as the aggregate.
SELECT (SELECT tdc_norm(ST_ForceCollection(ST_Collect(geom ORDER BY id))) FROM tdc_dump_out) =
	   (SELECT tdc_norm(ST_TDCDelaunay(geom)) FROM tdc_dump_pts) AS same_as_aggregate;
-- The triangles tile the convex hull.
SELECT abs((SELECT sum(ST_Area(geom)) FROM tdc_dump_out) -
		   (SELECT ST_Area(ST_ConvexHull(ST_Collect(geom))) FROM tdc_dump_pts)) < 1e-9 AS tiles_hull;

-- Tolerance, Z, NULL rows, any geometry types.
SELECT count(*) AS triangles FROM ST_TDCDelaunayDump($$SELECT * FROM (VALUES ('MULTIPOINT(5 5, 6 0, 7 9, 8 9)'::geometry)) v$$, 2);
SELECT id, ST_AsText(geom) FROM ST_TDCDelaunayDump($$SELECT * FROM (VALUES ('POINT Z(0 0 1)'::geometry), (NULL), ('POINT Z(0 0 9)'), ('LINESTRING Z(1 0 2, 0 1 3)')) v$$);
-- Degenerate: no rows, only NULLs, collinear, NULL arguments.
SELECT count(*) AS no_rows FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_dump_pts WHERE false');
SELECT count(*) AS only_nulls FROM ST_TDCDelaunayDump('SELECT NULL::geometry');
SELECT count(*) AS collinear FROM ST_TDCDelaunayDump($$SELECT 'MULTIPOINT(0 0, 1 1, 2 2)'::geometry$$);
SELECT count(*) AS null_query FROM ST_TDCDelaunayDump(NULL);
-- A domain over geometry is fine.
CREATE DOMAIN tdc_geom_domain AS geometry;
SELECT count(*) AS via_domain FROM ST_TDCDelaunayDump($$SELECT 'MULTIPOINT(0 0, 1 0, 0 1, 1 1)'::geometry::tdc_geom_domain$$);
DROP DOMAIN tdc_geom_domain;
-- In a lateral join, with a parameter-built query.
SELECT k, (SELECT count(*) FROM ST_TDCDelaunayDump(format('SELECT geom FROM tdc_dump_pts WHERE id <= %s', k))) AS triangles,
	   tdc_expected_triangles((SELECT ST_Collect(geom) FROM tdc_dump_pts WHERE id <= k)) AS expected
FROM (VALUES (3), (10), (1000)) v(k);

-- The query runs with the caller's rights.
CREATE ROLE tdc_dump_user;
GRANT USAGE ON SCHEMA public TO tdc_dump_user;
SET ROLE tdc_dump_user;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_dump_pts');
SELECT count(*) AS allowed FROM ST_TDCDelaunayDump($$SELECT 'MULTIPOINT(0 0, 1 0, 0 1)'::geometry$$);
RESET ROLE;
REVOKE USAGE ON SCHEMA public FROM tdc_dump_user;
DROP ROLE tdc_dump_user;

-- The query only reads: statements that write are refused before they run
-- (issue 16: DELETE ... RETURNING used to delete the rows), and the table
-- is untouched.  A NULL query gives no rows (STRICT).
SELECT count(*) AS before FROM tdc_dump_pts;
SELECT count(*) FROM ST_TDCDelaunayDump('DELETE FROM tdc_dump_pts WHERE id > 45 RETURNING geom');
SELECT count(*) FROM ST_TDCDelaunayDump('WITH d AS (DELETE FROM tdc_dump_pts WHERE id > 45 RETURNING geom) SELECT geom FROM d');
SELECT count(*) FROM ST_TDCDelaunayDump($$INSERT INTO tdc_dump_pts VALUES (100000, 'POINT(0 0)') RETURNING geom$$);
SELECT count(*) FROM ST_TDCDelaunayDump($$UPDATE tdc_dump_pts SET geom = 'POINT(0 0)' WHERE id > 45 RETURNING geom$$);
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_dump_pts FOR UPDATE');
SELECT count(*) AS after, count(*) FILTER (WHERE ST_X(geom) = 0 AND ST_Y(geom) = 0) AS changed FROM tdc_dump_pts;
SELECT count(*) AS null_query FROM ST_TDCDelaunayDump(NULL);

-- Volatile and parallel unsafe: a parallel plan never runs it in a worker.
SELECT provolatile, proparallel, prosecdef FROM pg_proc WHERE proname = 'st_tdcdelaunaydump';

DROP TABLE tdc_dump_pts, tdc_dump_out;
