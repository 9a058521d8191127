-- src/sql/tiled_internals.sql: the internal functions and aggregates that
-- tdc_delaunay_tiled (src/sql/tiled.sql) runs

-- tdc_delaunay_tiled: the triangulation of a whole table, tile by tile, into a new table
-- (src/pg/fn_tiled.c and src/core/tile_final.c explain the per-tile step)

CREATE FUNCTION _tdc_tile_transfn(internal, geometry, int8, int8, float8[], float8[], float8[], int8, int8)
RETURNS internal
AS 'MODULE_PATHNAME', '_tdc_tile_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_tile_transfn(internal, geometry, int8, int8, float8[], float8[], float8[], int8, int8) IS
'Transition function of _tdc_tile: collects the vertices of a tile and its halo with the label of their owning tile.';

CREATE FUNCTION _tdc_tile_finalfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', '_tdc_tile_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_tile_finalfn(internal) IS
'Final function of _tdc_tile: triangulates the tile with its halo and keeps its final triangles, '
'or the box it needs when they are not final yet.';

CREATE AGGREGATE _tdc_tile(geometry, int8, int8, float8[], float8[], float8[], int8, int8) (
	SFUNC = _tdc_tile_transfn,
	STYPE = internal,
	FINALFUNC = _tdc_tile_finalfn
);

COMMENT ON AGGREGATE _tdc_tile(geometry, int8, int8, float8[], float8[], float8[], int8, int8) IS
'Internal, for tdc_delaunay_tiled: _tdc_tile(point, owner label, this tile''s label, known box {xmin,ymin,xmax,ymax}, '
'hull {x,y,...}, extra known boxes {xmin,ymin,xmax,ymax,...}, source position (row, vertex)) over the points of a tile''s known box, '
'in any order; expand with _tdc_tile_triangles.';

CREATE FUNCTION _tdc_tile_triangles(bytea)
RETURNS TABLE(k bigint, geom geometry)
AS 'MODULE_PATHNAME', '_tdc_tile_triangles'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
ROWS 1000;

COMMENT ON FUNCTION _tdc_tile_triangles(bytea) IS
'Internal, for tdc_delaunay_tiled: the rows of a _tdc_tile result, triangles numbered k = 1.., '
'or one row k = 0 with the box a tile that is not final yet needs.';

CREATE FUNCTION _tdc_curve_to_line(geometry)
RETURNS geometry
AS 'MODULE_PATHNAME', '_tdc_curve_to_line'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_curve_to_line(geometry) IS
'Internal, for tdc_delaunay_tiled: the geometry as the Delaunay functions read it, stroked by ST_CurveToLine '
'(as ST_DelaunayTriangles strokes it) when it has arcs, else unchanged.';

CREATE FUNCTION _tdc_first_box(float8, float8, float8[], int4)
RETURNS boolean
AS 'MODULE_PATHNAME', '_tdc_first_box'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_first_box(float8, float8, float8[], int4) IS
'Internal, for tdc_delaunay_tiled: whether box i (from 0) of {xmin,ymin,xmax,ymax,...} is the first that holds the point x, y.';

CREATE FUNCTION _tdc_hull_transfn(internal, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', '_tdc_hull_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_hull_transfn(internal, geometry) IS
'Transition function of _tdc_hull(geometry): adds the vertices, keeping only the hull when its buffer fills.';

CREATE FUNCTION _tdc_hull_transfn(internal, float8[])
RETURNS internal
AS 'MODULE_PATHNAME', '_tdc_hull_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_hull_transfn(internal, float8[]) IS
'Transition function of _tdc_hull(float8[]): adds the x,y pairs of a partial hull.';

CREATE FUNCTION _tdc_hull_finalfn(internal)
RETURNS float8[]
AS 'MODULE_PATHNAME', '_tdc_hull_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_hull_finalfn(internal) IS
'Final function of _tdc_hull: the exact convex hull as {x,y,...}, counter-clockwise.';

CREATE AGGREGATE _tdc_hull(geometry) (
	SFUNC = _tdc_hull_transfn,
	STYPE = internal,
	FINALFUNC = _tdc_hull_finalfn
);

COMMENT ON AGGREGATE _tdc_hull(geometry) IS
'Internal, for tdc_delaunay_tiled: the exact convex hull of the vertices as {x,y,...} (bounded memory).';

CREATE AGGREGATE _tdc_hull(float8[]) (
	SFUNC = _tdc_hull_transfn,
	STYPE = internal,
	FINALFUNC = _tdc_hull_finalfn
);

COMMENT ON AGGREGATE _tdc_hull(float8[]) IS
'Internal, for tdc_delaunay_tiled: the convex hull of partial hulls given as {x,y,...}.';
