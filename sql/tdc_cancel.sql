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

-- The backend's threads once the one that unmaps a cancelled job's memory
-- (started while the error goes out) is done; a worker left running would
-- still be counted after the 5 s.
CREATE FUNCTION tdc_backend_threads() RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
	n int;
BEGIN
	LOOP
		n := substring(pg_read_file('/proc/' || pg_backend_pid() || '/status') FROM 'Threads:\s*(\d+)')::int;
		EXIT WHEN n = 1 OR clock_timestamp() > t0 + interval '5 s';
		PERFORM pg_sleep(0.005);
	END LOOP;
	RETURN n;
END $$;

-- One worker thread: the engine then needs over a second for this input,
-- far more than the timeouts below.
SET tdc_delaunay.threads = 1;

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
SET statement_timeout = '300ms';
SELECT tdc_cancel_probe(300);
RESET statement_timeout;
SELECT tdc_backend_threads() AS threads_after;

-- The plain error, as a client sees it.  (Terse: under load the timeout may
-- hit the Dump while it still reads its query, which adds a CONTEXT line.)
\set VERBOSITY terse
SET statement_timeout = '200ms';
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_big;
SELECT count(*) FROM ST_TDCDelaunayDump('SELECT g FROM tdc_big');
RESET statement_timeout;
\set VERBOSITY default
SELECT tdc_backend_threads() AS threads_after_errors;

-- Canceled inside a subtransaction; the outer transaction goes on.
BEGIN;
SAVEPOINT s;
SET LOCAL statement_timeout = '200ms';
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_big;
ROLLBACK TO SAVEPOINT s;
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1)')) AS in_same_transaction;
COMMIT;

-- The session is still usable, and the big triangulation does finish when
-- given time: 2n - 2 - h triangles.
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) = 2 * ST_NPoints(g) - 2 - (ST_NPoints(ST_ConvexHull(g)) - 1) AS finishes
FROM tdc_big;
SELECT tdc_backend_threads() AS threads_at_end;

RESET tdc_delaunay.threads;
DROP FUNCTION tdc_cancel_probe(int);
DROP FUNCTION tdc_backend_threads();
DROP TABLE tdc_big;
