/* tdc_delaunay--1.1.0--1.2.0.sql */

-- complain if script is sourced in psql, rather than via ALTER EXTENSION
\echo Use "ALTER EXTENSION tdc_delaunay UPDATE TO '1.2.0'" to load this file. \quit

-- 1.2.0 adds ST_TDCContours(geometry, float8, float8, text), whose method
-- ('linear' or 'linear:max_edge=L') leaves out the triangles with an edge
-- longer than L, and its transition function, as src/sql/tin.sql has them.
-- Every other object of 1.1.0 stays as it was (test/upgrade.sh compares the
-- catalogue with a fresh 1.2.0 install).

CREATE FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8, text) IS
'Internal: transition function of ST_TDCContours(geometry, float8, float8, text): collects the samples'' vertices with Z.';

CREATE AGGREGATE ST_TDCContours(geometry, float8, float8, text) (
	SFUNC = st_tdccontours_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	COMBINEFUNC = st_tdccontours_combinefn,
	SERIALFUNC = st_tdccontours_serialfn,
	DESERIALFUNC = st_tdccontours_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(geometry, float8, float8, text) IS
'Contour lines at the levels base + k * interval of the TIN of the vertices of all input geometries (heights from Z), '
'as one MULTILINESTRING Z, on the triangles the method keeps: ''linear'' (all), or ''linear:max_edge=L'', which leaves '
'out the triangles with an edge longer than L (lines stop where they begin); interval, base and method must be the '
'same in every row.';
