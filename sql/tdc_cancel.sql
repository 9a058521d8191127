--
-- tdc_cancel: a statement_timeout during a long triangulation cancels it
-- promptly, frees the engine (its threads are gone) and leaves the session
-- usable.
--
-- One big value, so that the time goes into the engine, not into reading rows.
CREATE TABLE tdc_big AS
	SELECT ST_Collect(ST_MakePoint(x, y)) AS g
	FROM (SELECT (hashint4(i) & 2147483647)::float8, (hashint4(-i) & 2147483647)::float8
		  FROM generate_series(1, 1500000) i) p(x, y);

-- One worker thread: the engine then needs over a second for this input,
-- far more than the timeouts below.
SET tdc_delaunay.threads = 1;

-- Where did the timeout land?  A cancel that comes while the value is still
-- being read, before the engine starts, passes every check below but tests
-- nothing of the engine; under load the read takes long enough for that.  The
-- engine's threads are the backend's only other threads, and the CPU time of
-- the whole process (/proc/PID/stat) counts threads that have exited, that of
-- the main thread (/proc/PID/task/PID/stat) only its own: the difference, in
-- clock ticks, is what the engine's threads used.  It is CPU time, so it does
-- not depend on the load.
CREATE FUNCTION tdc_proc_ticks(path text) RETURNS bigint LANGUAGE sql AS $$
	SELECT f[12]::bigint + f[13]::bigint	-- utime + stime (proc(5): fields 14, 15)
	FROM (SELECT string_to_array(substring(pg_read_file(path) FROM '[)] (.*)$'), ' ') AS f) s $$;
CREATE FUNCTION tdc_engine_ticks() RETURNS bigint LANGUAGE sql AS $$
	SELECT tdc_proc_ticks('/proc/' || pg_backend_pid() || '/stat')
		 - tdc_proc_ticks('/proc/' || pg_backend_pid() || '/task/' || pg_backend_pid() || '/stat') $$;

-- How long reading the value takes here and now (it is the same work as
-- the engine's input phase: detoasting 24 MB); the timeout is put well past
-- it, and the engine with one thread needs several times longer than that.
CREATE FUNCTION tdc_read_ms() RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
BEGIN
	PERFORM ST_MemSize(g) FROM tdc_big;		-- detoasts the whole value
	RETURN ceil(extract(epoch FROM clock_timestamp() - t0) * 1000);
END $$;

-- Time the cancel from inside: statement_timeout is armed when the top-level
-- statement starts; the exception handler sees how long it took.
CREATE FUNCTION tdc_cancel_probe(timeout_ms int) RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := statement_timestamp();
BEGIN
	PERFORM ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_big;
	RETURN 'not canceled';
EXCEPTION WHEN query_canceled THEN
	RETURN 'canceled: ' || SQLERRM || CASE
		WHEN clock_timestamp() - t0 < make_interval(secs => (timeout_ms + 400) / 1000.0)
		THEN ', promptly' ELSE ', too late: ' || (clock_timestamp() - t0)::text END;
END $$;

SELECT tdc_backend_threads() AS threads_before;
SELECT 300 + 2 * tdc_read_ms() AS cancel_ms, tdc_engine_ticks() AS ticks0 \gset
SET statement_timeout = :cancel_ms;
SELECT tdc_cancel_probe(:cancel_ms);
RESET statement_timeout;
SELECT tdc_engine_ticks() - :ticks0 AS canceled_ticks \gset
SELECT tdc_backend_threads() AS threads_after;

-- The plain error, as a client sees it.  (Terse: under load the timeout may
-- hit the Dump while it still reads its query, which adds a CONTEXT line.)
\set VERBOSITY terse
SET statement_timeout = '200ms';
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_big;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT g FROM tdc_big');
RESET statement_timeout;
SELECT tdc_backend_threads() AS threads_after_errors;

-- Canceled inside a subtransaction; the outer transaction goes on.  (Still
-- terse: under load this timeout too may come while the value is read.)
BEGIN;
SAVEPOINT s;
SET LOCAL statement_timeout = '200ms';
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_big;
ROLLBACK TO SAVEPOINT s;
\set VERBOSITY default
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1)')) AS in_same_transaction;
COMMIT;

-- The session is still usable, and the big triangulation does finish when
-- given time: 2n - 2 - h triangles.
SELECT tdc_engine_ticks() AS ticks0 \gset
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) = 2 * ST_NPoints(g) - 2 - (ST_NPoints(ST_ConvexHull(g)) - 1) AS finishes
FROM tdc_big;
SELECT tdc_engine_ticks() - :ticks0 AS full_ticks \gset
SELECT tdc_backend_threads() AS threads_at_end;

-- The timed cancel above landed in the engine: its threads had run when it
-- came (a cancel while reading leaves them at 0), and had not done the
-- whole job.
SELECT :canceled_ticks > 0 AS engine_was_running, :canceled_ticks < :full_ticks AS engine_had_not_finished;

RESET tdc_delaunay.threads;
DROP FUNCTION tdc_cancel_probe(int);
DROP FUNCTION tdc_read_ms();
DROP FUNCTION tdc_engine_ticks();
DROP FUNCTION tdc_proc_ticks(text);
DROP TABLE tdc_big;
