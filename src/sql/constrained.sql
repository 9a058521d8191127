-- src/sql/constrained.sql: constrained Delaunay triangulation
-- (ST_TDCConstrainedDelaunayTriangles, ST_TDCConstrainedDelaunayDump, the
-- ST_TDCConstrainedDelaunay aggregates; C side: src/pg/fn/fn_constrained.c)

-- ST_TDCConstrainedDelaunayTriangles: constrained Delaunay triangulation,
-- comparable to SFCGAL's ST_ConstrainedDelaunayTriangles

CREATE FUNCTION ST_TDCConstrainedDelaunayTriangles(g1 geometry,
												   flags int4 DEFAULT 0)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunaytriangles'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 1000;

COMMENT ON FUNCTION ST_TDCConstrainedDelaunayTriangles(geometry, int4) IS
'Exact constrained Delaunay triangulation of the vertices of a geometry, every segment of its '
'linestrings and polygon rings an edge (split at vertices on it). Crossing segments are an error. '
'flags 0: GEOMETRYCOLLECTION of POLYGON triangles, 1: MULTILINESTRING of the edges, 2: TIN, '
'5: MULTILINESTRING of the constraint edges alone.';

CREATE FUNCTION ST_TDCConstrainedDelaunayDump(query text)
RETURNS TABLE(id bigint, geom geometry)
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunaydump'
LANGUAGE C VOLATILE STRICT PARALLEL UNSAFE
COST 10000 ROWS 100000;

COMMENT ON FUNCTION ST_TDCConstrainedDelaunayDump(text) IS
'Runs a query returning one geometry column (with the caller''s rights, read-only) and returns the constrained '
'Delaunay triangulation of all its vertices, linestring and ring segments as constraints, one POLYGON row per '
'triangle numbered from 1; not bound by the 1 GB limit of a single value.';

-- Aggregates: ST_TDCConstrainedDelaunay(geometry [, flags])
--   = ST_TDCConstrainedDelaunayTriangles(ST_Collect(geometry), flags),
-- parallel-safe like ST_TDCDelaunay (the partial states carry the segments).

CREATE FUNCTION st_tdcconstraineddelaunay_transfn(internal, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_transfn(internal, geometry) IS
'Transition function of ST_TDCConstrainedDelaunay(geometry): collects the vertices and segments of each input.';

CREATE FUNCTION st_tdcconstraineddelaunay_transfn(internal, geometry, int4)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_transfn(internal, geometry, int4) IS
'Transition function of ST_TDCConstrainedDelaunay(geometry, int4): collects the vertices and segments of each input.';

CREATE FUNCTION st_tdcconstraineddelaunay_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_combinefn(internal, internal) IS
'Combine function of ST_TDCConstrainedDelaunay: appends the vertices and segments of one partial state to another.';

-- costs as for st_tdcdelaunay_serialfn: parallel plans only for big tables
CREATE FUNCTION st_tdcconstraineddelaunay_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_serialfn(internal) IS
'Serialization function of ST_TDCConstrainedDelaunay for parallel aggregation.';

CREATE FUNCTION st_tdcconstraineddelaunay_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_deserialfn(bytea, internal) IS
'Deserialization function of ST_TDCConstrainedDelaunay for parallel aggregation; checks the header, length and segment ends.';

CREATE FUNCTION st_tdcconstraineddelaunay_finalfn(internal)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcconstraineddelaunay_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcconstraineddelaunay_finalfn(internal) IS
'Final function of ST_TDCConstrainedDelaunay: the constrained triangulation of the collected vertices and segments.';

CREATE AGGREGATE ST_TDCConstrainedDelaunay(geometry) (
	SFUNC = st_tdcconstraineddelaunay_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcconstraineddelaunay_finalfn,
	COMBINEFUNC = st_tdcconstraineddelaunay_combinefn,
	SERIALFUNC = st_tdcconstraineddelaunay_serialfn,
	DESERIALFUNC = st_tdcconstraineddelaunay_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCConstrainedDelaunay(geometry) IS
'Exact constrained Delaunay triangulation of all input geometries (linestring and ring segments as constraints), '
'as a GEOMETRYCOLLECTION of POLYGON triangles; same as ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom)).';

CREATE AGGREGATE ST_TDCConstrainedDelaunay(geometry, int4) (
	SFUNC = st_tdcconstraineddelaunay_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcconstraineddelaunay_finalfn,
	COMBINEFUNC = st_tdcconstraineddelaunay_combinefn,
	SERIALFUNC = st_tdcconstraineddelaunay_serialfn,
	DESERIALFUNC = st_tdcconstraineddelaunay_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCConstrainedDelaunay(geometry, int4) IS
'Exact constrained Delaunay triangulation of all input geometries with flags '
'(0: GEOMETRYCOLLECTION of POLYGON, 1: MULTILINESTRING of edges, 2: TIN, 5: the constraint edges alone); '
'same as ST_TDCConstrainedDelaunayTriangles(ST_Collect(geom), flags).';
