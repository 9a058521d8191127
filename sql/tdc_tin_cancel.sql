--
-- tdc_tin_cancel: a statement_timeout while a TIN operation runs (a natural
-- neighbour drape of a long line, on one thread) cancels it promptly, stops
-- the engine's threads and leaves the session usable; the same statement
-- then finishes when given time.
--
-- One value of samples and one long target, so that the time goes into the
-- operation, not into reading rows: 40,000 samples (a triangulation of tens
-- of ms) and 600,000 target vertices, each a natural neighbour value.
CREATE TABLE tdc_tin_big AS
	SELECT ST_Collect(ST_MakePoint(x, y, sin(x / 50) * 20 + y / 30)) AS samples
	FROM (SELECT (hashint4(i) & 1048575)::float8 / 1048.576, (hashint4(-i) & 1048575)::float8 / 1048.576
		  FROM generate_series(1, 40000) i) p(x, y);
CREATE TABLE tdc_tin_line AS
	SELECT ST_MakeLine(array_agg(ST_MakePoint(100 + (i % 700) + ((i / 700) % 1000) * 1e-3, 100 + (i / 700) % 700) ORDER BY i)) AS target
	FROM generate_series(1, 600000) i;
SET tdc_delaunay.threads = 1;

-- Where did the timeout land?  As in tdc_cancel: the CPU time of the
-- engine's threads (the process's, which counts exited threads, less the
-- main thread's), in clock ticks.  The set-up (reading, triangulating,
-- building the TIN) uses some; a cancel in the drape itself has used more,
-- and less than the whole drape.
CREATE FUNCTION tdc_tin_proc_ticks(path text) RETURNS bigint LANGUAGE sql AS $$
	SELECT f[12]::bigint + f[13]::bigint
	FROM (SELECT string_to_array(substring(pg_read_file(path) FROM '[)] (.*)$'), ' ') AS f) s $$;
CREATE FUNCTION tdc_tin_engine_ticks() RETURNS bigint LANGUAGE sql AS $$
	SELECT tdc_tin_proc_ticks('/proc/' || pg_backend_pid() || '/stat')
		 - tdc_tin_proc_ticks('/proc/' || pg_backend_pid() || '/task/' || pg_backend_pid() || '/stat') $$;

CREATE FUNCTION tdc_tin_cancel_probe(timeout_ms int) RETURNS text LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := statement_timestamp();
BEGIN
	PERFORM ST_NPoints(ST_TDCDrape(samples, target, 'natural_neighbor')) FROM tdc_tin_big, tdc_tin_line;
	RETURN 'not canceled';
EXCEPTION WHEN query_canceled THEN
	RETURN 'canceled' || CASE
		WHEN clock_timestamp() - t0 < make_interval(secs => (timeout_ms + 400) / 1000.0)
		THEN ', promptly' ELSE ', too late: ' || (clock_timestamp() - t0)::text END;
END $$;

-- How long the part before the drape takes here and now: reading the
-- target (tdc_tin_read_ms), and reading the samples, triangulating them and
-- building their TIN (a drape of one point, tdc_tin_setup_ms).  The timeout
-- is put well past both, and the natural neighbour drape of 600,000
-- vertices on one thread needs several times longer.  The set-up's engine
-- time is what a cancel inside the drape must have passed.
CREATE FUNCTION tdc_tin_read_ms() RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
BEGIN
	PERFORM ST_MemSize(target) FROM tdc_tin_line;		-- detoasts the whole value
	RETURN ceil(extract(epoch FROM clock_timestamp() - t0) * 1000);
END $$;
CREATE FUNCTION tdc_tin_setup_ms() RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
BEGIN
	PERFORM ST_NPoints(ST_TDCDrape(samples, 'POINT(500 500)')) FROM tdc_tin_big;
	RETURN ceil(extract(epoch FROM clock_timestamp() - t0) * 1000);
END $$;

SELECT tdc_backend_threads() AS threads_before;
SELECT tdc_tin_engine_ticks() AS ticks0 \gset
SELECT 300 + 2 * (tdc_tin_read_ms() + tdc_tin_setup_ms()) AS cancel_ms \gset
SELECT tdc_tin_engine_ticks() - :ticks0 AS setup_ticks, tdc_tin_engine_ticks() AS ticks0 \gset
SET statement_timeout = :cancel_ms;
SELECT tdc_tin_cancel_probe(:cancel_ms);
RESET statement_timeout;
SELECT tdc_tin_engine_ticks() - :ticks0 AS canceled_ticks \gset
SELECT tdc_backend_threads() AS threads_after;

-- The error as a client sees it.
\set VERBOSITY terse
SET statement_timeout = :cancel_ms;
SELECT ST_NPoints(ST_TDCDrape(samples, target, 'natural_neighbor')) FROM tdc_tin_big, tdc_tin_line;
RESET statement_timeout;
\set VERBOSITY default
SELECT tdc_backend_threads() AS threads_after_error;

-- The session is usable, and the drape finishes when given time: every
-- vertex draped, none added (natural neighbour splits nothing).
SELECT tdc_tin_engine_ticks() AS ticks0 \gset
SELECT ST_NPoints(d) = (SELECT ST_NPoints(target) FROM tdc_tin_line) AS finishes
FROM (SELECT ST_TDCDrape(samples, target, 'natural_neighbor') AS d FROM tdc_tin_big, tdc_tin_line) s;
SELECT tdc_tin_engine_ticks() - :ticks0 AS full_ticks \gset
SELECT tdc_backend_threads() AS threads_at_end;

-- The timed cancel landed in the drape: past the set-up's engine time, short
-- of the whole run's.
SELECT :canceled_ticks > :setup_ticks AS in_the_drape, :canceled_ticks < :full_ticks AS before_its_end;

RESET tdc_delaunay.threads;
DROP FUNCTION tdc_tin_setup_ms();
DROP FUNCTION tdc_tin_read_ms();
DROP FUNCTION tdc_tin_cancel_probe(int);
DROP FUNCTION tdc_tin_engine_ticks();
DROP FUNCTION tdc_tin_proc_ticks(text);
DROP TABLE tdc_tin_line, tdc_tin_big;
