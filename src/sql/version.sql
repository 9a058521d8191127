-- src/sql/version.sql: what a bug report needs (C side: src/pg/fn/version.c)

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
