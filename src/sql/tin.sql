-- src/sql/tin.sql: TIN analysis, new in 1.1.0 (the ST_TDCContours and ST_TDCDrape
-- aggregates; C side: src/pg/fn/fn_contours_agg.c, fn_drape_agg.c,
-- src/pg/runtime/tin_run.c, and src/core/tin/tin*.c).
-- tdc_delaunay--1.0.0--1.1.0.sql holds the same objects but
-- ST_TDCContours(geometry, float8, float8, text), new in 1.2.0
-- (tdc_delaunay--1.1.0--1.2.0.sql).

-- ST_TDCContours: contour lines of the TIN of all rows' vertices (heights from Z)

CREATE FUNCTION st_tdccontours_transfn(internal, geometry, float8)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_transfn(internal, geometry, float8) IS
'Internal: transition function of ST_TDCContours(geometry, float8): collects the samples'' vertices with Z.';

CREATE FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8) IS
'Internal: transition function of ST_TDCContours(geometry, float8, float8): collects the samples'' vertices with Z.';

CREATE FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_transfn(internal, geometry, float8, float8, text) IS
'Internal: transition function of ST_TDCContours(geometry, float8, float8, text): collects the samples'' vertices with Z.';

CREATE FUNCTION st_tdccontours_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_combinefn(internal, internal) IS
'Internal: combines two partial ST_TDCContours states (parallel aggregation).';

-- The costs of ST_TDCDelaunay's (src/sql/delaunay.sql): a parallel plan only
-- for very large tables, since the triangulation runs once in the leader.
CREATE FUNCTION st_tdccontours_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdccontours_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdccontours_serialfn(internal) IS
'Internal: serializes a partial ST_TDCContours state (parallel aggregation).';

CREATE FUNCTION st_tdccontours_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdccontours_deserialfn(bytea, internal) IS
'Internal: deserializes a partial ST_TDCContours state, checking it (parallel aggregation).';

CREATE FUNCTION st_tdccontours_finalfn(internal)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdccontours_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE
COST 10000;

COMMENT ON FUNCTION st_tdccontours_finalfn(internal) IS
'Internal: final function of ST_TDCContours: triangulates the samples and draws the contour lines.';

CREATE AGGREGATE ST_TDCContours(geometry, float8) (
	SFUNC = st_tdccontours_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	COMBINEFUNC = st_tdccontours_combinefn,
	SERIALFUNC = st_tdccontours_serialfn,
	DESERIALFUNC = st_tdccontours_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(geometry, float8) IS
'Contour lines at the levels k * interval of the TIN (linear surface) of the vertices of all input geometries, '
'whose Z are the heights, as one MULTILINESTRING Z: lines merged, closed where they do not end on the hull, '
'each vertex''s Z its level; a sample exactly at a level counts as above it.';

CREATE AGGREGATE ST_TDCContours(geometry, float8, float8) (
	SFUNC = st_tdccontours_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	COMBINEFUNC = st_tdccontours_combinefn,
	SERIALFUNC = st_tdccontours_serialfn,
	DESERIALFUNC = st_tdccontours_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(geometry, float8, float8) IS
'Contour lines at the levels base + k * interval of the TIN of the vertices of all input geometries (heights from Z), '
'as one MULTILINESTRING Z; interval and base must be the same in every row.';

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

-- ST_TDCDrape: a target geometry with Z from the TIN of all rows' vertices

CREATE FUNCTION st_tdcdrape_transfn(internal, geometry, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_transfn(internal, geometry, geometry) IS
'Internal: transition function of ST_TDCDrape(geometry, geometry): collects the samples'' vertices with Z.';

CREATE FUNCTION st_tdcdrape_transfn(internal, geometry, geometry, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_transfn(internal, geometry, geometry, text) IS
'Internal: transition function of ST_TDCDrape(geometry, geometry, text): collects the samples'' vertices with Z.';

CREATE FUNCTION st_tdcdrape_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_combinefn(internal, internal) IS
'Internal: combines two partial ST_TDCDrape states (parallel aggregation).';

CREATE FUNCTION st_tdcdrape_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdcdrape_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcdrape_serialfn(internal) IS
'Internal: serializes a partial ST_TDCDrape state (parallel aggregation).';

CREATE FUNCTION st_tdcdrape_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcdrape_deserialfn(bytea, internal) IS
'Internal: deserializes a partial ST_TDCDrape state, checking it (parallel aggregation).';

CREATE FUNCTION st_tdcdrape_finalfn(internal)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcdrape_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE
COST 10000;

COMMENT ON FUNCTION st_tdcdrape_finalfn(internal) IS
'Internal: final function of ST_TDCDrape: triangulates the samples and drapes the target on them.';

CREATE AGGREGATE ST_TDCDrape(geometry, geometry) (
	SFUNC = st_tdcdrape_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdrape_finalfn,
	COMBINEFUNC = st_tdcdrape_combinefn,
	SERIALFUNC = st_tdcdrape_serialfn,
	DESERIALFUNC = st_tdcdrape_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDrape(geometry, geometry) IS
'The target (second argument, the same in every row) with Z at every vertex, linear on the TIN of the vertices '
'of all input geometries (heights from Z); lines and rings get a vertex at every triangle edge they cross. '
'A target vertex outside the samples'' convex hull is an error.';

CREATE AGGREGATE ST_TDCDrape(geometry, geometry, text) (
	SFUNC = st_tdcdrape_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdrape_finalfn,
	COMBINEFUNC = st_tdcdrape_combinefn,
	SERIALFUNC = st_tdcdrape_serialfn,
	DESERIALFUNC = st_tdcdrape_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDrape(geometry, geometry, text) IS
'The target with Z at every vertex from the samples by method ''linear'' (lines split at the triangle edges; '
'''linear:breaklines=true'' takes the samples'' linestrings and polygon rings as hard breaklines), '
'''nearest'' or ''natural_neighbor'' (Sibson); a target vertex outside the samples'' convex hull is an error.';
