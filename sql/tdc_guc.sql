--
-- tdc_guc: the tdc_delaunay.* settings.
--
-- The settings exist once the library is loaded (by any function call).
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)')) AS loaded;
SELECT name, setting, unit, context, vartype, min_val, max_val
FROM pg_settings WHERE name LIKE 'tdc_delaunay.%' ORDER BY name COLLATE "C";

-- The prefix is reserved: typos are errors, not silent placeholders.
SET tdc_delaunay.thread = 2;

-- Out of range.
SET tdc_delaunay.threads = -1;
SET tdc_delaunay.levels = -2;
-- the engine's limit (TDC_MAX_LEVELS): a SET error, not a failure of every
-- later triangulation
SET tdc_delaunay.levels = 25;
SHOW tdc_delaunay.levels;
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)')) AS after_levels_25;
RESET tdc_delaunay.levels;
SET tdc_delaunay.max_result_bytes = 10;

-- threads, levels and grid size change how, not what.
CREATE TABLE tdc_guc_pts AS SELECT id, geom FROM tdc_random_points(5000, 3);
CREATE TABLE tdc_guc_ref AS SELECT tdc_norm(ST_TDCDelaunay(geom)) AS t FROM tdc_guc_pts;
SET tdc_delaunay.threads = 1;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS threads_1 FROM tdc_guc_pts;
SET tdc_delaunay.threads = 3;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS threads_3 FROM tdc_guc_pts;
SET tdc_delaunay.levels = -1;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS no_subdivision FROM tdc_guc_pts;
SET tdc_delaunay.levels = 4;
SET tdc_delaunay.grid_size = 16;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS levels_4_grid_16 FROM tdc_guc_pts;
-- the largest depth is accepted (the engine then stops at 2^d <= points)
SET tdc_delaunay.levels = 24;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS levels_24 FROM tdc_guc_pts;
RESET tdc_delaunay.levels;
RESET tdc_delaunay.grid_size;
-- the superuser ceiling applies.  The triangle set is the same for any
-- thread count, so what is asserted is the thread count the engine was
-- given, from the stats DETAIL ("threads N, levels L, grid G; <timings>").
-- The timings differ from run to run and psql cannot filter a notice, so a
-- second session (the same server and database) runs the statement and only
-- the thread figure is printed.  A superuser's max_threads is not bound by
-- the CPU count, so the figures do not depend on the machine.  (30000
-- points: below TDC_INLINE_MAX, 20000, a job runs on one thread whatever
-- the settings.)
\setenv PGDATABASE :DBNAME
\! psql -X -q -c "SET tdc_delaunay.stats = on; SET tdc_delaunay.max_threads = 1; SET tdc_delaunay.threads = 0; SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: *\(threads [0-9]*\),.*/max_threads 1, threads 0: \1/p'
\! psql -X -q -c "SET tdc_delaunay.stats = on; SET tdc_delaunay.max_threads = 1; SET tdc_delaunay.threads = 3; SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: *\(threads [0-9]*\),.*/max_threads 1, threads 3: \1/p'
\! psql -X -q -c "SET tdc_delaunay.stats = on; SET tdc_delaunay.max_threads = 2; SET tdc_delaunay.threads = 3; SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: *\(threads [0-9]*\),.*/max_threads 2, threads 3: \1/p'
\! psql -X -q -c "SET tdc_delaunay.stats = on; SET tdc_delaunay.max_threads = 3; SET tdc_delaunay.threads = 2; SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: *\(threads [0-9]*\),.*/max_threads 3, threads 2: \1/p'
-- and the result under the ceiling is still the same
SET tdc_delaunay.max_threads = 1;
SET tdc_delaunay.threads = 0;
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_guc_ref) AS max_threads_1 FROM tdc_guc_pts;
RESET tdc_delaunay.max_threads;
RESET tdc_delaunay.threads;

-- keep_memory: a session keeps the engine's freed arrays for its next run
-- (the stats DETAIL of a value ends with "kept N kB": what is kept after
-- the run), up to tdc_delaunay.keep_memory, and gives them back
-- keep_memory_time after its last run, when a transaction aborts, and when
-- a run's max_memory needs the room.  Each line is one session (one -c per
-- transaction); the figure depends on the thread count, so only its size
-- class is printed.
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "after a run:", ($1 > 1024 ? "more than 1 MB kept" : $1 " kB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SET tdc_delaunay.keep_memory = 0" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "keep_memory 0:", ($1 > 1024 ? "more than 1 MB kept" : $1 " kB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" -c "SELECT pg_sleep(0.3)" -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)') IS NOT NULL" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "0.3 s later, default keep_memory_time:", ($1 > 1024 ? "more than 1 MB kept" : $1 " kB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SET tdc_delaunay.keep_memory_time = '20ms'" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" -c "SELECT pg_sleep(0.3)" -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)') IS NOT NULL" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "0.3 s later, keep_memory_time 20ms:", ($1 > 1024 ? "more than 1 MB kept" : $1 " kB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(30000, 3)" -c "SELECT 1 / 0" -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)') IS NOT NULL" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "after an aborted transaction:", ($1 > 1024 ? "more than 1 MB kept" : $1 " kB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(100000, 3)" -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)') IS NOT NULL" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "100000 points, then a run without a limit:", ($1 >= 6144 ? "6 MB or more kept" : "less than 6 MB kept") }'
\! psql -X -q -c "SET tdc_delaunay.stats = on" -c "SELECT ST_TDCDelaunay(geom) IS NOT NULL FROM tdc_random_points(100000, 3)" -c "SET tdc_delaunay.max_memory = '6MB'" -c "SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)') IS NOT NULL" 2>&1 | sed -n 's/^DETAIL: .* kept \([0-9]*\) kB$/\1/p' | tail -1 | awk '{ print "100000 points, then a run under max_memory 6MB:", ($1 >= 6144 ? "6 MB or more kept" : "less than 6 MB kept") }'
-- and the triangles do not depend on what was kept
SET tdc_delaunay.keep_memory = 0;
CREATE TEMP TABLE tdc_keep_ref AS SELECT tdc_norm(ST_TDCDelaunay(geom)) AS t FROM tdc_random_points(30000, 5);
RESET tdc_delaunay.keep_memory;
SELECT ST_TDCDelaunay(geom) IS NOT NULL AS filled FROM tdc_random_points(30000, 6);
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_keep_ref) AS same_from_kept_arrays FROM tdc_random_points(30000, 5);
SELECT tdc_norm(ST_TDCDelaunay(geom)) = (SELECT t FROM tdc_keep_ref) AS same_again FROM tdc_random_points(30000, 5);
DROP TABLE tdc_keep_ref;
-- (its range error, and those of the other settings with a unit: tdc_guc_units)

-- stats: a NOTICE with the counts (timings and threads go to the DETAIL).
\set VERBOSITY terse
SET tdc_delaunay.stats = on;
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1, 1 1, 0.5 0.4)')) AS triangles;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_guc_pts WHERE id <= 100');
RESET tdc_delaunay.stats;
\set VERBOSITY default

-- max_memory: a clear error before allocating past it, both while
-- collecting rows and before starting the engine.
SET tdc_delaunay.max_memory = '1MB';
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts WHERE id <= 100;
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts;
SELECT ST_NumGeometries(ST_TDCDelaunay(g)) FROM (SELECT ST_MakePoint(i, i % 7) g FROM generate_series(1, 100000) i) s;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT ST_MakePoint(i, i % 7) FROM generate_series(1, 100000) i');
-- The same vertices get the same estimate from every function; the result
-- value of the aggregate and of ST_TDCDelaunayTriangles is named apart.
CREATE FUNCTION pg_temp.tdc_mem_estimate(q text) RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	m text;
BEGIN
	EXECUTE q;
	RETURN 'no error';
EXCEPTION WHEN program_limit_exceeded THEN
	GET STACKED DIAGNOSTICS m = MESSAGE_TEXT;
	RETURN substring(m FROM 'triangulating [0-9]+ vertices needs about [0-9]+ MB');
END $$;
SELECT agg = dump AND agg = triangles AS same_estimate FROM (SELECT
	pg_temp.tdc_mem_estimate('SELECT ST_TDCDelaunay(geom) FROM tdc_guc_pts') AS agg,
	pg_temp.tdc_mem_estimate('SELECT count(*) FROM ST_TDCDelaunayDump(''SELECT geom FROM tdc_guc_pts'')') AS dump,
	pg_temp.tdc_mem_estimate('SELECT ST_TDCDelaunayTriangles(ST_Collect(geom)) FROM tdc_guc_pts') AS triangles) s;
SET tdc_delaunay.max_memory = '64MB';
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) = tdc_expected_triangles(ST_Collect(geom)) AS fits FROM tdc_guc_pts;
RESET tdc_delaunay.max_memory;
-- Arrays kept beside the vertices count with them, checked as they grow:
-- the row ids of ST_TDCVoronoiDump (8 bytes a vertex), the segments of a
-- constrained triangulation (8 bytes each) and the owners and source
-- positions of a tile of tdc_delaunay_tiled (24 bytes a vertex).  At vertex
-- 131073 the coordinates double to 4 MB; the ids then double to 2 MB (6 MB
-- in all, over 5); a line of 140,000 vertices holds 4 MB of coordinates and
-- 1.1 MB of segments (over 5); a tile's arrays double to 6 MB (10 MB, over 8).
SET tdc_delaunay.max_memory = '5MB';
SELECT count(*) FROM ST_TDCVoronoiDump('SELECT i, ST_MakePoint(i, i % 7) FROM generate_series(1, 140000) i');
SELECT ST_TDCConstrainedDelaunayTriangles(ST_MakeLine(array_agg(ST_MakePoint(i, i % 7) ORDER BY i))) IS NULL
FROM generate_series(1, 140000) i;
SET tdc_delaunay.max_memory = '8MB';
SELECT _tdc_tile(ST_MakePoint(i, i % 7), 1, 1, '{0,0,140001,7}', '{0,0,140001,0,0,7}', '{}', i, 1) IS NULL
FROM generate_series(1, 140000) i;
RESET tdc_delaunay.max_memory;

-- memory_ceiling (superuser) bounds max_memory: a user's own limit only
-- lowers it, and the error names the setting that applied.
SET tdc_delaunay.memory_ceiling = '1MB';
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts;
SET tdc_delaunay.max_memory = '64MB';
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_guc_pts');
SET tdc_delaunay.memory_ceiling = '64MB';
SET tdc_delaunay.max_memory = '1MB';
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts;
RESET tdc_delaunay.max_memory;
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) = tdc_expected_triangles(ST_Collect(geom)) AS fits_ceiling FROM tdc_guc_pts;
-- -1: no ceiling at all
SET tdc_delaunay.memory_ceiling = -1;
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) = tdc_expected_triangles(ST_Collect(geom)) AS no_ceiling FROM tdc_guc_pts;
RESET tdc_delaunay.memory_ceiling;

-- max_result_bytes (test only): results over the limit of one value point
-- to ST_TDCDelaunayDump.  A 2D triangle takes 80 bytes.
SET tdc_delaunay.max_result_bytes = 1000;
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1)')) AS small_fits;
SELECT ST_TDCDelaunay(geom) FROM tdc_guc_pts WHERE id <= 100;
SELECT ST_TDCDelaunayTriangles(ST_Collect(geom), 0, 1) FROM tdc_guc_pts WHERE id <= 100;
SELECT count(*) = tdc_expected_triangles((SELECT ST_Collect(geom) FROM tdc_guc_pts WHERE id <= 100)) AS dump_unaffected
FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_guc_pts WHERE id <= 100');
RESET tdc_delaunay.max_result_bytes;

-- superuser-only settings
CREATE ROLE tdc_guc_user;
GRANT SELECT ON tdc_guc_pts TO tdc_guc_user;
SET ROLE tdc_guc_user;
SET tdc_delaunay.max_threads = 64;
SET tdc_delaunay.max_result_bytes = 100;
SET tdc_delaunay.memory_ceiling = -1;
SET tdc_delaunay.memory_ceiling = '100GB';
SET tdc_delaunay.threads = 2;
SHOW tdc_delaunay.threads;
-- a user may ask for more than the ceiling; the ceiling still applies
SET tdc_delaunay.max_memory = '100GB';
SHOW tdc_delaunay.max_memory;
RESET ROLE;
SET tdc_delaunay.memory_ceiling = '1MB';
SET ROLE tdc_guc_user;
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM tdc_guc_pts;
RESET ROLE;
RESET tdc_delaunay.memory_ceiling;
RESET tdc_delaunay.max_memory;
REVOKE SELECT ON tdc_guc_pts FROM tdc_guc_user;
DROP ROLE tdc_guc_user;
RESET tdc_delaunay.threads;

DROP TABLE tdc_guc_pts, tdc_guc_ref;
