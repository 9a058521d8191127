--
-- tdc_parallel: the aggregate under a parallel plan gives the serial result.
--
-- A plan that only says "Workers Planned" proves nothing: when no worker
-- starts, the leader runs the partial plan alone and no state ever crosses
-- a process boundary.  So each parallel result below is made by
-- tdc_par_run(), which runs CREATE TABLE ... AS under EXPLAIN ANALYZE (the
-- same execution makes the result and the plan figures) and reports from the
-- plan how many workers were launched, how many rows the workers read, and
-- how many non-empty partial states they sent.  With
-- parallel_leader_participation off the leader reads no row once a worker
-- runs, so every row reaches the result through the workers' serial
-- function, the leader's deserial function and the combine function.
--
-- The query given to it must be parallel safe as a whole: one parallel
-- unsafe function anywhere (tdc_norm, say, which is plain SQL) and the
-- planner makes no parallel plan at all, which the comparison used to do.
--
-- Figures of a plan: workers launched; rows the workers' scans returned;
-- (scan, worker) pairs that returned rows, i.e. non-empty partial states
-- when each scan has a Partial Aggregate of its own.
CREATE FUNCTION tdc_par_run(dest text, query text,
							OUT workers_launched int, OUT rows_by_workers numeric,
							OUT worker_states bigint)
	LANGUAGE plpgsql AS $$
DECLARE
	plan		jsonb;
BEGIN
	EXECUTE format('EXPLAIN (ANALYZE, VERBOSE, COSTS OFF, TIMING OFF, SUMMARY OFF, FORMAT JSON) CREATE TABLE %I AS %s',
				   dest, query) INTO plan;
	SELECT coalesce(sum((n ->> 'Workers Launched')::int), 0) INTO workers_launched
	FROM jsonb_path_query(plan, 'strict $.** ? (exists (@."Workers Launched"))') n;
	SELECT coalesce(sum((w ->> 'Actual Rows')::numeric * (w ->> 'Actual Loops')::int), 0),
		   count(*) FILTER (WHERE (w ->> 'Actual Rows')::numeric > 0)
	INTO rows_by_workers, worker_states
	FROM jsonb_path_query(plan, 'strict $.** ? (@."Node Type" == "Seq Scan")."Workers"[*]') w;
END $$;

CREATE TABLE tdc_par AS SELECT id, geom FROM tdc_random_points(60000, 11);
ANALYZE tdc_par;
SET max_parallel_workers_per_gather = 0;
CREATE TABLE tdc_par_serial AS
	SELECT tdc_norm(ST_TDCDelaunay(geom)) AS t, ST_NumGeometries(ST_TDCDelaunay(geom)) AS n,
		   tdc_norm(ST_TDCDelaunay(geom, 0, 1)) AS e
	FROM tdc_par;

-- (force_parallel_mode is not needed: with these costs the planner picks
-- the parallel plan itself, as the EXPLAINs show.)  The serialization
-- functions' high costs keep the planner from partial aggregation below
-- millions of rows (tdc_small shows it); lowered here for the test's table.
ALTER FUNCTION st_tdcdelaunay_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcdelaunay_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;

EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM tdc_par;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom, 0, 1) FROM tdc_par;

SELECT workers_launched > 0 AS workers_launched,
	   rows_by_workers = (SELECT count(*) FROM tdc_par) AS every_row_read_by_a_worker,
	   worker_states > 0 AS combined_worker_states
FROM tdc_par_run('tdc_par_res', 'SELECT ST_TDCDelaunay(geom) AS g, ST_TDCDelaunay(geom, 0, 1) AS e FROM tdc_par');
SELECT ST_NumGeometries(g) = (SELECT n FROM tdc_par_serial) AS same_count,
	   tdc_norm(g) = (SELECT t FROM tdc_par_serial) AS same_triangles,
	   tdc_norm(e) = (SELECT e FROM tdc_par_serial) AS same_edges
FROM tdc_par_res;

-- Two non-empty states combined, whatever the workers' timing: with
-- partitionwise aggregation each partition has a Partial Aggregate of its
-- own, so the finalize step gets at least one non-empty state per partition.
CREATE TABLE tdc_par_parts (id int, geom geometry) PARTITION BY RANGE (id);
CREATE TABLE tdc_par_parts_1 PARTITION OF tdc_par_parts FOR VALUES FROM (MINVALUE) TO (30001);
CREATE TABLE tdc_par_parts_2 PARTITION OF tdc_par_parts FOR VALUES FROM (30001) TO (MAXVALUE);
INSERT INTO tdc_par_parts SELECT id, geom FROM tdc_par;
ANALYZE tdc_par_parts;
SET enable_partitionwise_aggregate = on;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM tdc_par_parts;
SELECT workers_launched > 0 AS workers_launched,
	   rows_by_workers = (SELECT count(*) FROM tdc_par) AS every_row_read_by_a_worker,
	   worker_states >= 2 AS combined_two_or_more_states
FROM tdc_par_run('tdc_par_parts_res',
				 'SELECT ST_TDCDelaunay(geom) AS g, ST_TDCDelaunay(geom, 0, 1) AS e FROM tdc_par_parts');
SELECT tdc_norm(g) = (SELECT t FROM tdc_par_serial) AS same_triangles,
	   tdc_norm(e) = (SELECT e FROM tdc_par_serial) AS same_edges
FROM tdc_par_parts_res;
RESET enable_partitionwise_aggregate;

-- With Z and an SRID.
CREATE TABLE tdc_par_z AS SELECT id, ST_SetSRID(ST_MakePoint(ST_X(geom), ST_Y(geom), id), 4326) AS geom FROM tdc_par;
ANALYZE tdc_par_z;
EXPLAIN (COSTS OFF) SELECT ST_TDCDelaunay(geom) FROM tdc_par_z;
SELECT workers_launched > 0 AS workers_launched,
	   rows_by_workers = (SELECT count(*) FROM tdc_par_z) AS every_row_read_by_a_worker
FROM tdc_par_run('tdc_par_zres', 'SELECT ST_TDCDelaunay(geom) AS g FROM tdc_par_z');
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
RESET parallel_leader_participation;
ALTER FUNCTION st_tdcdelaunay_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcdelaunay_deserialfn(bytea, internal) COST 10000000;
DROP TABLE tdc_par, tdc_par_serial, tdc_par_res, tdc_par_parts, tdc_par_parts_res, tdc_par_z, tdc_par_zres;
DROP FUNCTION tdc_par_run(text, text);
