--
-- tdc_release: the version report for bug reports, and the HINT a Dump
-- function's error carries when a name in its query is not found.
--

-- The library's version is the extension's.
SELECT tdc_delaunay_lib_version() = extversion AS lib_is_extension_version,
	   tdc_delaunay_lib_version() ~ '^[0-9]+\.[0-9]+\.[0-9]+$' AS three_numbers
FROM pg_extension WHERE extname = 'tdc_delaunay';

-- The full report: its keys in order, each value quoted (values elided).
SELECT regexp_replace(tdc_delaunay_full_version(), '"[^"]*"', '"x"', 'g') AS shape;

-- Its values: the library, the SQL objects, the server (and the major it was
-- built for), PostGIS, the threads.
CREATE FUNCTION tdc_release_report(k text) RETURNS text LANGUAGE sql AS
$$ SELECT (regexp_match(tdc_delaunay_full_version(), k || '="([^"]*)"'))[1] $$;
SELECT tdc_release_report('TDC_DELAUNAY') = tdc_delaunay_lib_version() AS library,
	   tdc_release_report('EXTENSION') = (SELECT extversion FROM pg_extension WHERE extname = 'tdc_delaunay') AS sql_objects,
	   tdc_release_report('PGSQL') = current_setting('server_version') AS server,
	   split_part(tdc_release_report('BUILT_PGSQL'), '.', 1) = split_part(current_setting('server_version'), '.', 1) AS built_same_major,
	   tdc_release_report('POSTGIS') = (SELECT extversion FROM pg_extension WHERE extname = 'postgis') AS postgis,
	   tdc_release_report('BUILT_POSTGIS') ~ '^([0-9]+\.[0-9]+\.[0-9]+|unknown)' AS built_postgis,
	   tdc_release_report('THREADS')::int >= 1 AS threads;
-- The threads follow the settings as a triangulation does.
SET tdc_delaunay.threads = 1;
SELECT tdc_release_report('THREADS') AS threads_1;
SET tdc_delaunay.threads = 64;
SET tdc_delaunay.max_threads = 1;
SELECT tdc_release_report('THREADS') AS threads_64_max_1;
RESET tdc_delaunay.threads;
RESET tdc_delaunay.max_threads;

-- A Dump query that names a missing table: the error carries the HINT, as
-- pg_restore shows it for a materialized view whose query is not
-- schema-qualified (pg_restore empties the search_path).
\set VERBOSITY default
SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM tdc_release_missing');
SELECT * FROM ST_TDCVoronoiDump('SELECT 1::bigint, geom FROM tdc_release_missing');
SELECT * FROM ST_TDCConstrainedDelaunayDump('SELECT geom FROM tdc_release_missing');
CREATE TABLE tdc_release_pts AS
	SELECT ST_MakePoint(i % 7, i / 7 + (i % 3) * 0.25) AS geom FROM generate_series(0, 48) i;
SET search_path = '';
SELECT count(*) FROM public.ST_TDCDelaunayDump('SELECT geom FROM tdc_release_pts');
SELECT count(*) FROM public.ST_TDCDelaunayDump('SELECT geom FROM public.tdc_release_pts');
RESET search_path;
\set VERBOSITY terse

-- A missing function, operator or type gets the HINT too, after the hint
-- it had; other errors keep theirs and get none.
CREATE FUNCTION tdc_release_error(query text,
								  OUT code text, OUT has_own_hint boolean, OUT schema_hint boolean)
LANGUAGE plpgsql AS $$
DECLARE
	hint text;
BEGIN
	EXECUTE query;
EXCEPTION WHEN OTHERS THEN
	GET STACKED DIAGNOSTICS code = RETURNED_SQLSTATE, hint = PG_EXCEPTION_HINT;
	schema_hint := hint LIKE '%Schema-qualify every table, function and type in the query %';
	has_own_hint := hint LIKE '_%' || E'\n' || '%';
END $$;
SET search_path = '';
SELECT 'function' AS missing, * FROM public.tdc_release_error(
	'SELECT count(*) FROM public.ST_TDCDelaunayDump(''SELECT ST_Centroid(geom) FROM public.tdc_release_pts'')');
SELECT 'operator' AS missing, * FROM public.tdc_release_error(
	'SELECT count(*) FROM public.ST_TDCVoronoiDump(''SELECT 1::bigint, geom FROM public.tdc_release_pts WHERE geom && geom'')');
SELECT 'type' AS missing, * FROM public.tdc_release_error(
	'SELECT count(*) FROM public.ST_TDCConstrainedDelaunayDump(''SELECT ''''POINT(0 0)''''::geometry'')');
RESET search_path;
SELECT 'none: division by zero' AS missing, * FROM tdc_release_error(
	'SELECT count(*) FROM ST_TDCDelaunayDump(''SELECT geom FROM tdc_release_pts WHERE 1 / 0 = 1'')');
SELECT 'none: not a SELECT' AS missing, * FROM tdc_release_error(
	'SELECT count(*) FROM ST_TDCDelaunayDump(''DELETE FROM tdc_release_pts RETURNING geom'')');
\set VERBOSITY default

DROP FUNCTION tdc_release_error(text);
DROP FUNCTION tdc_release_report(text);
DROP TABLE tdc_release_pts;
