--
-- tdc_parallel: the aggregate under a parallel plan gives the serial result.
--
CREATE TABLE tdc_par AS SELECT id, geom FROM tdc_random_points(60000, 11);
ANALYZE tdc_par;
CREATE TABLE tdc_par_serial AS
	SELECT tdc_norm(ST_TDCDelaunay(geom)) AS t, ST_NumGeometries(ST_TDCDelaunay(geom)) AS n,
		   tdc_norm(ST_TDCDelaunay(geom, 0, 1)) AS e
	FROM tdc_par;

SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;

EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM tdc_par;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom, 0, 1) FROM tdc_par;

SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) = (SELECT n FROM tdc_par_serial) AS same_count,
	   tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_par_serial) AS same_triangles,
	   tdc_norm(ST_TDCDelaunay(geom, 0, 1)) = (SELECT e FROM tdc_par_serial) AS same_edges
FROM tdc_par;

-- With Z and an SRID.
CREATE TABLE tdc_par_z AS SELECT id, ST_SetSRID(ST_MakePoint(ST_X(geom), ST_Y(geom), id), 4326) AS geom FROM tdc_par;
ANALYZE tdc_par_z;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM tdc_par_z;
CREATE TABLE tdc_par_zres AS SELECT ST_TDCDelaunay(geom) AS g FROM tdc_par_z;
SELECT ST_SRID(g) AS srid, ST_NDims(g) AS ndims, ST_NumGeometries(g) = (SELECT n FROM tdc_par_serial) AS same_count,
	   tdc_norm(ST_Force2D(g)) = (SELECT t FROM tdc_par_serial) AS same_triangles
FROM tdc_par_zres;
-- Z values are carried through the partial states (no duplicate XY here).
SELECT count(*) AS vertices_with_wrong_z
FROM tdc_par_zres t, ST_DumpPoints(t.g) p
JOIN tdc_par_z z ON ST_X(z.geom) = ST_X(p.geom) AND ST_Y(z.geom) = ST_Y(p.geom)
WHERE ST_Z(p.geom) <> z.id;

-- Groups.
-- (random points: no collinear hull vertices, h = hull vertices)
SELECT id % 4 AS grp,
	   ST_NumGeometries(ST_TDCDelaunay(geom)) = 2 * count(*) - 2 - (ST_NPoints(ST_ConvexHull(ST_Collect(geom))) - 1) AS count_ok
FROM tdc_par GROUP BY 1 ORDER BY 1;

-- Mixed SRIDs are detected wherever the rows meet (a worker's state or the
-- combine step).
INSERT INTO tdc_par_z VALUES (0, 'SRID=3857;POINT(0.5 0.5 0)');
\set VERBOSITY terse
SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_par_z;
\set VERBOSITY default

RESET parallel_setup_cost;
RESET parallel_tuple_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;
DROP TABLE tdc_par, tdc_par_serial, tdc_par_z, tdc_par_zres;
