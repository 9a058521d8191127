/* tdc_delaunay--0.1.0--1.0.0.sql */

-- complain if script is sourced in psql, rather than via ALTER EXTENSION
\echo Use "ALTER EXTENSION tdc_delaunay UPDATE TO '1.0.0'" to load this file. \quit

-- 1.0.0 adds the version report of src/sql/version.sql, as it was released;
-- every object of 0.1.0 stays as it was (test/upgrade.sh compares the
-- catalogue with a fresh 1.0.0 install).

CREATE FUNCTION tdc_delaunay_lib_version()
RETURNS text
AS 'MODULE_PATHNAME', 'tdc_delaunay_lib_version'
LANGUAGE C STABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION tdc_delaunay_lib_version() IS
'The version of the loaded tdc_delaunay library, as 1.0.0.';

CREATE FUNCTION tdc_delaunay_full_version()
RETURNS text
AS 'MODULE_PATHNAME', 'tdc_delaunay_full_version'
LANGUAGE C STABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION tdc_delaunay_full_version() IS
'For bug reports, as postgis_full_version(): the library''s version, the SQL objects'' version in this database, '
'the PostgreSQL and PostGIS the library was built against and runs with, and the thread count a triangulation '
'would use with the current settings.';
