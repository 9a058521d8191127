/* tdc_delaunay--0.1.0.sql */

-- complain if script is sourced in psql, rather than via CREATE EXTENSION
\echo Use "CREATE EXTENSION tdc_delaunay" to load this file. \quit

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

-- Diagnostics

CREATE FUNCTION _st_tdcdelaunay_state_check(bytea)
RETURNS bigint
AS 'MODULE_PATHNAME', '_st_tdcdelaunay_state_check'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _st_tdcdelaunay_state_check(bytea) IS
'Diagnostic: validates a serialized ST_TDCDelaunay aggregate state as the parallel deserialization function does '
'(raising an error when it is corrupt) and returns its vertex count.';

-- Voronoi diagrams, from the same exact triangulation

CREATE FUNCTION ST_TDCVoronoiPolygons(g1 geometry, tolerance float8 DEFAULT 0.0,
									  extend_to geometry DEFAULT NULL)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcvoronoipolygons'
LANGUAGE C IMMUTABLE PARALLEL SAFE
COST 10000;

COMMENT ON FUNCTION ST_TDCVoronoiPolygons(geometry, float8, geometry) IS
'Voronoi cells of the vertices of g1 as a GEOMETRYCOLLECTION of 2D POLYGONs, one per distinct vertex in input order, '
'clipped to the vertices'' bounding box grown by its larger side (and grown to extend_to''s box); '
'drop-in for ST_VoronoiPolygons, built from the exact triangulation.';

CREATE FUNCTION ST_TDCVoronoiLines(g1 geometry, tolerance float8 DEFAULT 0.0,
								   extend_to geometry DEFAULT NULL)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcvoronoilines'
LANGUAGE C IMMUTABLE PARALLEL SAFE
COST 10000;

COMMENT ON FUNCTION ST_TDCVoronoiLines(geometry, float8, geometry) IS
'Edges of the Voronoi diagram of the vertices of g1 inside the clip envelope of ST_TDCVoronoiPolygons, '
'as a MULTILINESTRING (a LINESTRING for one edge); drop-in for ST_VoronoiLines.';

-- ST_TDCVoronoi: aggregate, parallel safe like ST_TDCDelaunay

CREATE FUNCTION st_tdcvoronoi_transfn(internal, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcvoronoi_transfn(internal, geometry) IS
'Internal: transition function of ST_TDCVoronoi(geometry).';

CREATE FUNCTION st_tdcvoronoi_transfn(internal, geometry, float8, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcvoronoi_transfn(internal, geometry, float8, geometry) IS
'Internal: transition function of ST_TDCVoronoi(geometry, float8, geometry).';

CREATE FUNCTION st_tdcvoronoi_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcvoronoi_combinefn(internal, internal) IS
'Internal: combines two partial ST_TDCVoronoi states (parallel aggregation).';

CREATE FUNCTION st_tdcvoronoi_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcvoronoi_serialfn(internal) IS
'Internal: serializes a partial ST_TDCVoronoi state (parallel aggregation).';

CREATE FUNCTION st_tdcvoronoi_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcvoronoi_deserialfn(bytea, internal) IS
'Internal: deserializes a partial ST_TDCVoronoi state, checking it (parallel aggregation).';

CREATE FUNCTION st_tdcvoronoi_finalfn(internal)
RETURNS geometry
AS 'MODULE_PATHNAME', 'st_tdcvoronoi_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcvoronoi_finalfn(internal) IS
'Internal: final function of ST_TDCVoronoi: builds the Voronoi cells.';

CREATE AGGREGATE ST_TDCVoronoi(geometry) (
	SFUNC = st_tdcvoronoi_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcvoronoi_finalfn,
	COMBINEFUNC = st_tdcvoronoi_combinefn,
	SERIALFUNC = st_tdcvoronoi_serialfn,
	DESERIALFUNC = st_tdcvoronoi_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCVoronoi(geometry) IS
'Voronoi cells of the vertices of all input geometries; same as ST_TDCVoronoiPolygons(ST_Collect(geom)) '
'without the collection.';

CREATE AGGREGATE ST_TDCVoronoi(geometry, float8, geometry) (
	SFUNC = st_tdcvoronoi_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcvoronoi_finalfn,
	COMBINEFUNC = st_tdcvoronoi_combinefn,
	SERIALFUNC = st_tdcvoronoi_serialfn,
	DESERIALFUNC = st_tdcvoronoi_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCVoronoi(geometry, float8, geometry) IS
'Voronoi cells of the vertices of all input geometries with tolerance and extend_to (the same in every row); '
'same as ST_TDCVoronoiPolygons(ST_Collect(geom), tolerance, extend_to).';

-- ST_TDCVoronoiDump: the cell of every input vertex, keyed by its row's id

CREATE FUNCTION ST_TDCVoronoiDump(query text, extend_to geometry DEFAULT NULL)
RETURNS TABLE(id bigint, geom geometry)
AS 'MODULE_PATHNAME', 'st_tdcvoronoidump'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000 ROWS 100000;

COMMENT ON FUNCTION ST_TDCVoronoiDump(text, geometry) IS
'Runs a query returning (id bigint, geom geometry) with the caller''s rights and returns one row per vertex '
'with its row''s id and its Voronoi cell (duplicates share the cell), clipped as by ST_TDCVoronoiPolygons; '
'not bound by the 1 GB limit of a single value.';
