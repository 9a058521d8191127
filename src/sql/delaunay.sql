-- src/sql/delaunay.sql: Delaunay triangulation (ST_TDCDelaunayTriangles, the
-- ST_TDCDelaunay aggregates, ST_TDCDelaunayDump; C side: src/pg/fn/fn_delaunay.c,
-- fn_delaunay_agg.c, agg_state.c, dump_query.c)

-- ST_TDCDelaunayTriangles: drop-in for ST_DelaunayTriangles

CREATE FUNCTION ST_TDCDelaunayTriangles(g1 geometry,
										tolerance float8 DEFAULT 0.0,
										flags int4 DEFAULT 0)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcdelaunaytriangles'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
-- A call costs microseconds to seconds, far above an operator: as for
-- ST_DelaunayTriangles, the planner should prefer plans that call it less
-- often and spread its calls over parallel workers.
COST 1000;

COMMENT ON FUNCTION ST_TDCDelaunayTriangles(geometry, float8, int4) IS
'Exact Delaunay triangulation of the vertices of a geometry, drop-in for ST_DelaunayTriangles. '
'flags 0: GEOMETRYCOLLECTION of POLYGON triangles, 1: MULTILINESTRING of the edges, 2: TIN. '
'tolerance > 0 drops vertices closer than tolerance to a kept one.';

-- Aggregates: ST_TDCDelaunay(geometry [, tolerance, flags])
--   = ST_DelaunayTriangles(ST_Collect(geometry), tolerance, flags)

CREATE FUNCTION st_tdcdelaunay_transfn(internal, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_transfn(internal, geometry) IS
'Transition function of ST_TDCDelaunay(geometry): collects the vertices of each input.';

CREATE FUNCTION st_tdcdelaunay_transfn(internal, geometry, float8, int4)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_transfn(internal, geometry, float8, int4) IS
'Transition function of ST_TDCDelaunay(geometry, float8, int4): collects the vertices of each input.';

CREATE FUNCTION st_tdcdelaunay_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_combinefn(internal, internal) IS
'Combine function of ST_TDCDelaunay: appends the vertices of one partial state to another.';

-- Parallel aggregation pays, per partial state, a worker's start (loading
-- PostGIS and this library), a copy of its points into a bytea, the trip
-- through the tuple queue and two copies in the leader, while it saves only
-- part of the reading: the triangulation runs once, in the leader, either
-- way.  Measured on 2 cores, the parallel plan was slower up to millions of
-- rows.  These costs (counted per partial state, or per group and worker)
-- let the planner choose a parallel plan only for tables of about ten
-- million rows and more, and not for GROUP BY over many groups.
CREATE FUNCTION st_tdcdelaunay_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcdelaunay_serialfn(internal) IS
'Serialization function of ST_TDCDelaunay for parallel aggregation.';

CREATE FUNCTION st_tdcdelaunay_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcdelaunay_deserialfn(bytea, internal) IS
'Deserialization function of ST_TDCDelaunay for parallel aggregation; checks the header and length.';

CREATE FUNCTION st_tdcdelaunay_finalfn(internal)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_finalfn(internal) IS
'Final function of ST_TDCDelaunay: triangulates the collected vertices.';

CREATE AGGREGATE ST_TDCDelaunay(geometry) (
	SFUNC = st_tdcdelaunay_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdelaunay_finalfn,
	COMBINEFUNC = st_tdcdelaunay_combinefn,
	SERIALFUNC = st_tdcdelaunay_serialfn,
	DESERIALFUNC = st_tdcdelaunay_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDelaunay(geometry) IS
'Exact Delaunay triangulation of the vertices of all input geometries, as a GEOMETRYCOLLECTION of POLYGON triangles; '
'same as ST_DelaunayTriangles(ST_Collect(geom)).';

CREATE AGGREGATE ST_TDCDelaunay(geometry, float8, int4) (
	SFUNC = st_tdcdelaunay_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdelaunay_finalfn,
	COMBINEFUNC = st_tdcdelaunay_combinefn,
	SERIALFUNC = st_tdcdelaunay_serialfn,
	DESERIALFUNC = st_tdcdelaunay_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDelaunay(geometry, float8, int4) IS
'Exact Delaunay triangulation of the vertices of all input geometries with tolerance and flags '
'(0: GEOMETRYCOLLECTION of POLYGON, 1: MULTILINESTRING of edges, 2: TIN); '
'same as ST_DelaunayTriangles(ST_Collect(geom), tolerance, flags).';

-- ST_TDCDelaunayDump: one row per triangle, for results past 1 GB

CREATE FUNCTION ST_TDCDelaunayDump(query text, tolerance float8 DEFAULT 0.0)
RETURNS TABLE(id bigint, geom geometry)
AS 'MODULE_PATHNAME', 'st_tdcdelaunaydump'
LANGUAGE C VOLATILE STRICT PARALLEL UNSAFE
COST 10000 ROWS 100000;

COMMENT ON FUNCTION ST_TDCDelaunayDump(text, float8) IS
'Runs a query returning one geometry column (with the caller''s rights), triangulates the vertices of all rows '
'and returns one POLYGON row per triangle, numbered from 1; not bound by the 1 GB limit of a single value.';
