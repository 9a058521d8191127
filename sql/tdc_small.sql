--
-- tdc_small: the small-input path.  Below 20,000 points a triangulation runs
-- on the backend's own thread (no worker thread, no mapping); from 20,000 on
-- it runs on the thread pool.  Both must give the same triangles, and the
-- small path must keep every rule of the big one.  Uses tdc_basic's helpers.
--

-- The planner knows the functions are expensive, as ST_DelaunayTriangles is.
SELECT p.oid::regprocedure AS function, p.procost, p.prorows
FROM pg_proc p
WHERE p.proname IN ('st_tdcdelaunaytriangles', 'st_tdcdelaunaydump')
ORDER BY p.oid::regprocedure::text COLLATE "C";

-- 0 to 10 points, each against the exact count 2n - 2 - h and checked for
-- orientation and validity.
SELECT k,
	   ST_NumGeometries(t) AS triangles,
	   greatest(tdc_expected_triangles(pts), 0) AS expected,
	   tdc_bad_triangles(t) AS bad
FROM generate_series(0, 10) k,
	 LATERAL (SELECT coalesce(ST_Collect(ST_MakePoint(i * 7 % 11, i * i % 13)), 'MULTIPOINT EMPTY') AS pts
			  FROM generate_series(1, k) i) p,
	 LATERAL (SELECT ST_TDCDelaunayTriangles(pts) AS t) r
ORDER BY k;

-- Degenerate small inputs: collinear (no triangle; edges with flags 1),
-- all duplicates, duplicates of a triangle.
SELECT ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 1, 2 2, 3 3)'));
SELECT ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 1, 2 2, 3 3)', 0, 1));
SELECT ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 5 5, 5 5)'));
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 0 0, 1 0, 0 1)'));

-- Z kept from the first vertex with the XY; flags 1 and 2; a tolerance.
SELECT ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 1, 1 0 2, 0 1 3, 0 0 9)'));
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 2 0, 0 2, 2 2, 1 1)', 0, 1));
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 2 0, 0 2, 2 2, 1 1)', 0, 2));
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 2 0, 0 2, 2 2, 1 1, 1.05 1)', 0.1));

-- The same sites on both sides of the switch: n points (small path) and the
-- same n points plus duplicates up to 20,000 or more (thread pool) give the
-- same triangles, at n = 5, 1,000 and 19,999.
CREATE TABLE sw AS
SELECT i, ST_MakePoint((hashint4(i) & 65535)::float8 / 65.536,
					   (hashint4(-i) & 65535)::float8 / 65.536) AS geom
FROM generate_series(1, 19999) i;
SET tdc_delaunay.threads = 2;
SELECT n,
	   md5(tdc_norm(small)) = md5(tdc_norm(threaded)) AS same,
	   ST_NumGeometries(small) AS triangles
FROM (VALUES (5), (1000), (19999)) v(n),
	 LATERAL (SELECT ST_TDCDelaunay(geom) AS small FROM sw WHERE i <= n) a,
	 LATERAL (SELECT ST_TDCDelaunay(s.geom) AS threaded
			  FROM (SELECT geom FROM sw WHERE i <= n
					UNION ALL
					SELECT sw.geom FROM sw, generate_series(1, 20001 / n + 1) r WHERE sw.i <= n) s) b
ORDER BY n;
RESET tdc_delaunay.threads;

-- Parallel aggregation pays a worker's start and copies of every point for a
-- share of the reading; the serialization functions' costs keep the planner
-- from it for tables of millions of rows or fewer, even when starting
-- workers is free.  (With the default cost of 1 it picked a partial
-- aggregate here, which measured slower.)
ANALYZE sw;
SET parallel_setup_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM sw;
CREATE FUNCTION pg_temp.plan_has_gather(q text) RETURNS boolean
	LANGUAGE plpgsql AS $$
DECLARE
	l text;
BEGIN
	FOR l IN EXECUTE 'EXPLAIN (COSTS OFF) ' || q LOOP
		IF l LIKE '%Gather%' THEN
			RETURN true;
		END IF;
	END LOOP;
	RETURN false;
END $$;
SELECT pg_temp.plan_has_gather('SELECT ST_TDCDelaunay(geom) FROM sw GROUP BY i % 100') AS group_by_parallel;
-- the same with the default cost: a partial aggregate
BEGIN;
ALTER FUNCTION st_tdcdelaunay_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcdelaunay_deserialfn(bytea, internal) COST 1;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM sw;
ROLLBACK;
RESET parallel_setup_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;

-- One call per row, many rows: every row's result is its own.
SELECT count(*) AS rows, sum(ST_NumGeometries(t)) AS triangles,
	   sum(tdc_bad_triangles(t)) AS bad
FROM (SELECT ST_TDCDelaunayTriangles(ST_Collect(geom)) AS t
	  FROM sw WHERE i <= 5000 GROUP BY i % 1000) s;
SELECT count(*) AS groups, sum(ST_NumGeometries(t)) AS triangles
FROM (SELECT ST_TDCDelaunay(geom) AS t FROM sw WHERE i <= 5000 GROUP BY i % 1000) s;

DROP TABLE sw;
