--
-- tdc_voronoi_agg: the ST_TDCVoronoi aggregates (serial and parallel) and
-- ST_TDCVoronoiDump.
--
-- A cell set, independent of the cells' order and of where rings start.
CREATE FUNCTION tdc_vnorm(g geometry) RETURNS text[] LANGUAGE sql IMMUTABLE PARALLEL SAFE AS $$
	SELECT array_agg(ST_AsText(ST_Normalize((d).geom)) ORDER BY ST_AsText(ST_Normalize((d).geom)))
	FROM ST_Dump(g) d $$;

CREATE TABLE vagg AS
	SELECT i AS id, ST_MakePoint((hashint4(i) & 2147483647) / 2147483647.0 * 1000,
								 (hashint4(-i) & 2147483647) / 2147483647.0 * 1000) AS geom
	FROM generate_series(1, 30000) i;
ANALYZE vagg;

-- Serial: the same as ST_TDCVoronoiPolygons(ST_Collect(geom)), byte for byte
-- when the rows come in the same order.
SET max_parallel_workers_per_gather = 0;
SELECT ST_TDCVoronoi(geom ORDER BY id) = ST_TDCVoronoiPolygons(ST_Collect(geom ORDER BY id)) AS same_value,
	   ST_AsBinary(ST_TDCVoronoi(geom ORDER BY id)) = ST_AsBinary(ST_TDCVoronoiPolygons(ST_Collect(geom ORDER BY id))) AS same_bytes
FROM vagg;
SELECT ST_AsBinary(ST_TDCVoronoi(geom, 0, 'POINT(5000 5000)' ORDER BY id)) =
	   ST_AsBinary(ST_TDCVoronoiPolygons(ST_Collect(geom ORDER BY id), 0, 'POINT(5000 5000)')) AS same_extend_to,
	   ST_AsBinary(ST_TDCVoronoi(geom, 1, NULL ORDER BY id)) =
	   ST_AsBinary(ST_TDCVoronoiPolygons(ST_Collect(geom ORDER BY id), 1)) AS same_tolerance
FROM vagg;
CREATE TABLE vagg_serial AS SELECT tdc_vnorm(ST_TDCVoronoi(geom)) AS n FROM vagg;

-- NULL rows are skipped; no row gives NULL; parameters must agree.
SELECT ST_TDCVoronoi(g) IS NULL AS no_rows FROM vagg, LATERAL (SELECT NULL::geometry) s(g) WHERE false;
SELECT ST_NumGeometries(ST_TDCVoronoi(g)) AS with_nulls
FROM (VALUES ('POINT(0 0)'::geometry), (NULL), ('POINT(1 1)'), ('POINT(2 0)')) v(g);
SELECT ST_TDCVoronoi(g, t, NULL) FROM (VALUES ('POINT(0 0)'::geometry, 0), ('POINT(1 1)', 1)) v(g, t);
SELECT ST_TDCVoronoi(g, 0, e) FROM (VALUES ('POINT(0 0)'::geometry, 'POINT(5 5)'::geometry), ('POINT(1 1)', NULL)) v(g, e);
SELECT ST_TDCVoronoi(g, -1, NULL) FROM (VALUES ('POINT(0 0)'::geometry)) v(g);

-- Parallel: workers collect, the leader builds; same cells as the serial run.
ALTER FUNCTION st_tdcvoronoi_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcvoronoi_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
EXPLAIN (COSTS OFF) SELECT ST_TDCVoronoi(geom) FROM vagg;
CREATE FUNCTION tdc_vpar_workers(query text) RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	plan jsonb;
BEGIN
	EXECUTE 'EXPLAIN (ANALYZE, COSTS OFF, TIMING OFF, SUMMARY OFF, FORMAT JSON) ' || query INTO plan;
	RETURN (SELECT coalesce(sum((n ->> 'Workers Launched')::int), 0)
			FROM jsonb_path_query(plan, 'strict $.** ? (exists (@."Workers Launched"))') n);
END $$;
SELECT tdc_vpar_workers('CREATE TABLE vagg_par AS SELECT ST_TDCVoronoi(geom) AS g, ST_TDCVoronoi(geom, 0, ''POINT(-3000 0)'') AS e FROM vagg') > 0
	AS workers_launched;
SELECT tdc_vnorm(g) = (SELECT n FROM vagg_serial) AS same_cells,
	   tdc_vnorm(e) = (SELECT tdc_vnorm(ST_TDCVoronoiPolygons(ST_Collect(geom), 0, 'POINT(-3000 0)')) FROM vagg) AS same_cells_extend_to
FROM vagg_par;
-- the extend_to box travels through the workers' states: a different one in a row is caught
\set VERBOSITY terse
SELECT ST_TDCVoronoi(geom, 0, CASE WHEN id = 29999 THEN 'POINT(9 9)'::geometry ELSE 'POINT(-3000 0)' END) IS NOT NULL FROM vagg;
\set VERBOSITY default
RESET parallel_setup_cost;
RESET parallel_tuple_cost;
RESET min_parallel_table_scan_size;
RESET max_parallel_workers_per_gather;
RESET parallel_leader_participation;
ALTER FUNCTION st_tdcvoronoi_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcvoronoi_deserialfn(bytea, internal) COST 10000000;

-- ST_TDCVoronoiDump: one row per input point with its id; duplicates share the cell.
CREATE TABLE vdump AS
	SELECT id, geom FROM vagg WHERE id <= 2000
	UNION ALL
	SELECT id + 100000, geom FROM vagg WHERE id <= 50;
SELECT count(*) AS rows, count(DISTINCT d.id) AS ids,
	   count(*) FILTER (WHERE ST_Covers(d.geom, v.geom)) AS cell_covers_its_point,
	   bool_and(ST_IsValid(d.geom)) AS valid
FROM ST_TDCVoronoiDump('SELECT id, geom FROM vdump') d JOIN vdump v USING (id);
SELECT count(*) AS duplicate_pairs_with_the_same_cell
FROM ST_TDCVoronoiDump('SELECT id, geom FROM vdump') a
JOIN ST_TDCVoronoiDump('SELECT id, geom FROM vdump') b ON b.id = a.id + 100000
WHERE ST_Equals(a.geom, b.geom);
-- the same cells as ST_TDCVoronoiPolygons
SELECT (SELECT tdc_vnorm(ST_Collect(geom)) FROM ST_TDCVoronoiDump('SELECT id, geom FROM vdump WHERE id <= 2000')) =
	   tdc_vnorm(ST_TDCVoronoiPolygons((SELECT ST_Collect(geom) FROM vdump WHERE id <= 2000))) AS same_cells;
SELECT count(*) AS rows_extend_to, abs(sum(ST_Area(geom)) - 40000.0 * 40000) <= 1e-12 * 40000 * 40000 AS area
FROM ST_TDCVoronoiDump('SELECT id, geom FROM vdump WHERE id <= 2000', ST_MakeEnvelope(-20000, -20000, 20000, 20000));
-- int4 ids, NULL geometries, NULL query, fewer than 2 sites
SELECT count(*) FROM ST_TDCVoronoiDump('SELECT 1, ''POINT(0 0)''::geometry UNION ALL SELECT 2, NULL UNION ALL SELECT 3, ''POINT(1 1)''');
SELECT count(*) FROM ST_TDCVoronoiDump(NULL);
SELECT count(*) FROM ST_TDCVoronoiDump('SELECT 1::bigint, ''POINT(0 0)''::geometry');
-- errors
SELECT * FROM ST_TDCVoronoiDump('SELECT geom FROM vdump');
SELECT * FROM ST_TDCVoronoiDump('SELECT ''a''::text, geom FROM vdump');
SELECT * FROM ST_TDCVoronoiDump('SELECT NULL::bigint, geom FROM vdump');
SELECT * FROM ST_TDCVoronoiDump('DELETE FROM vdump RETURNING id, geom');
SELECT count(*) FROM vdump;
