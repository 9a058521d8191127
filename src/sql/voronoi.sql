-- src/sql/voronoi.sql: Voronoi diagrams (ST_TDCVoronoiPolygons, ST_TDCVoronoiLines,
-- the ST_TDCVoronoi aggregates, ST_TDCVoronoiDump; C side: src/pg/fn/fn_voronoi*.c)

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
