-- src/sql/tiled_internals.sql: the internal functions and aggregates that
-- tdc_delaunay_tiled (src/sql/tiled.sql) runs

-- tdc_delaunay_tiled: the triangulation of a whole table, tile by tile, into a new table
-- (src/pg/fn/fn_tiled.c and src/core/tiles/tile_final.c explain the per-tile step)

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

-- The tiling policy of src/core/tiles/tile_plan.c, the one ./tdc --max-memory
-- follows (src/pg/fn/fn_tiled_region.c): labels of squares, and a tile's first
-- known region {h, K, extra boxes...} and its growth; and the automatic
-- tiles, through the core's bounded run (src/pg/fn/fn_tiled_bounded.c).

CREATE FUNCTION _tdc_square_label(float8, float8, float8, float8, float8)
RETURNS int8
AS 'MODULE_PATHNAME', '_tdc_square_label'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_square_label(float8, float8, float8, float8, float8) IS
'Internal, for tdc_delaunay_tiled: _tdc_square_label(x, y, origin_x, origin_y, size), the label column * 2^32 + row '
'of the square of side size holding the point, counted from the origin (an error past 2^31 columns or rows).';

CREATE FUNCTION _tdc_tile_region(float8[], int8, float8[], int8, float8[])
RETURNS float8[]
AS 'MODULE_PATHNAME', '_tdc_tile_region'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_tile_region(float8[], int8, float8[], int8, float8[]) IS
'Internal, for tdc_delaunay_tiled: _tdc_tile_region(tile box, tile points, extent, points, hull), the first known region '
'{h, xmin, ymin, xmax, ymax, extra boxes...} of a tile: its box with a halo h of 8 of its mean spacings and the hull bands near it.';

CREATE FUNCTION _tdc_tile_regrow(float8[], geometry, float8[], int8, float8[])
RETURNS float8[]
AS 'MODULE_PATHNAME', '_tdc_tile_regrow'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _tdc_tile_regrow(float8[], geometry, float8[], int8, float8[]) IS
'Internal, for tdc_delaunay_tiled: _tdc_tile_regrow(region, need, extent, points, hull), the region of a tile''s next run '
'from the row of a run that was not final (the box it needs): the hull bands meeting the box that it lacks, '
'else its known box grown to the box and half its halo beyond.';

CREATE FUNCTION _tdc_tiled_write(query text, target regclass, tile_size float8)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_tiled_write(text, regclass, float8) IS
'Internal, for tdc_delaunay_tiled: the Delaunay triangles of the query''s vertices (its geometry column, as '
'ST_TDCDelaunayDump takes it) written into target, a table (id bigint, tile, geom geometry) created in this '
'transaction: in one pass when it fits tdc_delaunay.max_memory, else tile by tile through the core''s bounded run, '
'as ./tdc --max-memory runs it. Each triangle''s tile: with a second column in the query (a tile column, of the '
'type of target''s tile), the value owning its smallest vertex (the least among the vertex''s copies); with '
'tile_size, the square holding that vertex; else bigint from the run. Returns the rows written.';

-- The checks every tiled procedure makes (tdc_delaunay_tiled, tdc_contours_tiled,
-- and tdc_interpolate_tiled of tdc_delaunay_raster), their errors in the
-- caller's name fn.
CREATE FUNCTION _tdc_tiled_geometry(fn text, source regclass, geom_column text, filter text)
RETURNS regtype
LANGUAGE plpgsql STABLE
AS $fn$
DECLARE
	gtyp oid;
	gtypname name;
	typext name;
BEGIN
	SELECT a.atttypid, t.typname INTO gtyp, gtypname
	  FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
	 WHERE a.attrelid = source AND a.attname = geom_column AND a.attnum > 0 AND NOT a.attisdropped;
	IF NOT FOUND THEN
		RAISE EXCEPTION '%: column "%" of relation % does not exist', fn, geom_column, source
			USING ERRCODE = 'undefined_column';
	END IF;
	-- a pcpatch column: pgpointcloud's type, read through tdc_delaunay_pointcloud
	SELECT e.extname INTO typext
	  FROM pg_depend d JOIN pg_extension e ON e.oid = d.refobjid
	 WHERE d.classid = 'pg_type'::regclass AND d.objid = gtyp AND d.refclassid = 'pg_extension'::regclass
	   AND d.deptype = 'e';
	IF gtypname = 'pcpatch' AND typext = 'pointcloud' THEN
		IF NOT EXISTS (SELECT 1 FROM pg_extension WHERE extname = 'tdc_delaunay_pointcloud') THEN
			RAISE EXCEPTION '%: column "%" of relation % is a pcpatch column, and extension tdc_delaunay_pointcloud is not installed',
				fn, geom_column, source
				USING ERRCODE = 'feature_not_supported',
					  HINT = 'CREATE EXTENSION tdc_delaunay_pointcloud reads pgpointcloud patches.';
		END IF;
		RETURN gtyp;
	END IF;
	IF gtypname <> 'geometry' THEN
		RAISE EXCEPTION '%: column "%" of relation % is of type %, not geometry or pcpatch', fn, geom_column, source,
			gtypname
			USING ERRCODE = 'datatype_mismatch';
	END IF;
	IF filter IS NOT NULL THEN
		RAISE EXCEPTION '%: a filter is for a pcpatch column; column "%" of relation % is a geometry', fn, geom_column,
			source
			USING ERRCODE = 'invalid_parameter_value',
				  HINT = 'Select the rows with a WHERE clause in a view, and give the view as the source.';
	END IF;
	RETURN gtyp;
END
$fn$;

COMMENT ON FUNCTION _tdc_tiled_geometry(text, regclass, text, text) IS
'Internal, for the tiled procedures: the type of source.geom_column, which must exist and be a geometry, or a '
'pgpointcloud pcpatch when tdc_delaunay_pointcloud is installed; a filter (not NULL) only with a pcpatch column '
'(errors in the name fn).';

CREATE FUNCTION _tdc_tiled_target(fn text, target text)
RETURNS text[]
LANGUAGE plpgsql STABLE
AS $fn$
DECLARE
	tparts text[] := parse_ident(target);
	tschema text;
	tname text;
BEGIN
	IF cardinality(tparts) = 1 THEN
		tschema := current_schema();
		tname := tparts[1];
	ELSIF cardinality(tparts) = 2 THEN
		tschema := tparts[1];
		tname := tparts[2];
	ELSE
		RAISE EXCEPTION '%: target "%" is not a table name', fn, target
			USING ERRCODE = 'invalid_name';
	END IF;
	-- never overwritten
	IF to_regclass(format('%I.%I', tschema, tname)) IS NOT NULL THEN
		RAISE EXCEPTION '%: target %.% already exists', fn, quote_ident(tschema), quote_ident(tname)
			USING ERRCODE = 'duplicate_table', HINT = 'Drop it or choose another name; it is never overwritten.';
	END IF;
	RETURN ARRAY[tschema, tname];
END
$fn$;

COMMENT ON FUNCTION _tdc_tiled_target(text, text) IS
'Internal, for the tiled procedures: {schema, name} of the new table target (a name, or schema.name), which must not '
'exist yet (errors in the name fn).';
