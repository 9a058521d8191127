-- The install script of tdc_delaunay_pointcloud, made by the Makefile from
-- src/sql/pointcloud.sql: edit that, not this.
-- A third extension in the tdc_delaunay package, so that CREATE EXTENSION
-- tdc_delaunay never needs pgpointcloud: the pcpatch overloads of the
-- aggregates ST_TDCDelaunay, ST_TDCContours, ST_TDCDrape and
-- ST_TDCInterpolate.  Their transition functions read the patches' X, Y
-- and Z natively (uncompressed and dimensional patches) into the state of
-- the geometry aggregates, whose final functions they share, so the results
-- are those of the geometry path on the same points, byte for byte.  And the
-- pcpatch forms of the internal functions of the tiled procedures
-- (tdc_delaunay_tiled, tdc_contours_tiled, tdc_interpolate_tiled), at the
-- end.
-- ST_TDCInterpolate returns a raster: this extension requires
-- tdc_delaunay_raster (and so postgis_raster) for it.
--
-- The filter: the longest form of each aggregate takes one more text
-- argument, 'dimension=value[,value...]' (e.g. 'Classification=2'), which
-- keeps the points whose scaled value is one of the values; NULL: no filter.
--
-- No combine function: the pcpatch aggregates are not split into parallel
-- partial states, so that the one-pcid-per-aggregate check covers every row.
--
-- Each signature is spelled out, its transition function, aggregate and
-- comments: SQL has no statement that declares an aggregate for several
-- signatures, and a DO block that generated them would hide each object
-- and its C symbol from this script (test/release.sh checks every
-- C symbol named after MODULE_PATHNAME in the scripts against the library, and
-- the catalogue a reader greps is the script).

-- complain if script is sourced in psql, rather than via CREATE EXTENSION
\echo Use "CREATE EXTENSION tdc_delaunay_pointcloud" to load this file. \quit
-- ST_TDCDelaunay(pcpatch, ...)
CREATE FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch) IS
'Internal: transition function of ST_TDCDelaunay(pcpatch): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDelaunay(pcpatch) (
	SFUNC = st_tdcdelaunay_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdelaunay_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDelaunay(pcpatch) IS
'the Delaunay triangulation of the X, Y, Z of all patches points, as ST_TDCDelaunay(geometry) gives on the same points.';

CREATE FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch, float8, int4)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch, float8, int4) IS
'Internal: transition function of ST_TDCDelaunay(pcpatch, float8, int4): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDelaunay(pcpatch, float8, int4) (
	SFUNC = st_tdcdelaunay_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdelaunay_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDelaunay(pcpatch, float8, int4) IS
'the Delaunay triangulation of the X, Y, Z of all patches points, as ST_TDCDelaunay(geometry, float8, int4) gives on the same points.';

CREATE FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch, float8, int4, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdelaunay_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdelaunay_pc_transfn(internal, pcpatch, float8, int4, text) IS
'Internal: transition function of ST_TDCDelaunay(pcpatch, float8, int4, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDelaunay(pcpatch, float8, int4, text) (
	SFUNC = st_tdcdelaunay_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdelaunay_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDelaunay(pcpatch, float8, int4, text) IS
'the Delaunay triangulation of the X, Y, Z of all patches points, as ST_TDCDelaunay(geometry, float8, int4) gives on the same points; the last argument filters the points: ''dimension=value[,value...]''.';

-- ST_TDCContours(pcpatch, ...)
CREATE FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8) IS
'Internal: transition function of ST_TDCContours(pcpatch, float8): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCContours(pcpatch, float8) (
	SFUNC = st_tdccontours_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(pcpatch, float8) IS
'contour lines of the TIN of all patches points, as ST_TDCContours(geometry, float8) draws them on the same points.';

CREATE FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8) IS
'Internal: transition function of ST_TDCContours(pcpatch, float8, float8): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCContours(pcpatch, float8, float8) (
	SFUNC = st_tdccontours_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(pcpatch, float8, float8) IS
'contour lines of the TIN of all patches points, as ST_TDCContours(geometry, float8, float8) draws them on the same points.';

CREATE FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8, text) IS
'Internal: transition function of ST_TDCContours(pcpatch, float8, float8, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCContours(pcpatch, float8, float8, text) (
	SFUNC = st_tdccontours_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(pcpatch, float8, float8, text) IS
'contour lines of the TIN of all patches points, as ST_TDCContours(geometry, float8, float8, text) draws them on the same points.';

CREATE FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8, text, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdccontours_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdccontours_pc_transfn(internal, pcpatch, float8, float8, text, text) IS
'Internal: transition function of ST_TDCContours(pcpatch, float8, float8, text, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCContours(pcpatch, float8, float8, text, text) (
	SFUNC = st_tdccontours_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdccontours_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCContours(pcpatch, float8, float8, text, text) IS
'contour lines of the TIN of all patches points, as ST_TDCContours(geometry, float8, float8, text, text) draws them on the same points.';

-- ST_TDCDrape(pcpatch, ...)
CREATE FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry) IS
'Internal: transition function of ST_TDCDrape(pcpatch, geometry): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDrape(pcpatch, geometry) (
	SFUNC = st_tdcdrape_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdrape_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDrape(pcpatch, geometry) IS
'the target geometry with Z from the TIN of all patches points, as ST_TDCDrape(geometry, geometry) gives on the same points.';

CREATE FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry, text) IS
'Internal: transition function of ST_TDCDrape(pcpatch, geometry, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDrape(pcpatch, geometry, text) (
	SFUNC = st_tdcdrape_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdrape_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDrape(pcpatch, geometry, text) IS
'the target geometry with Z from the TIN of all patches points, as ST_TDCDrape(geometry, geometry, text) gives on the same points.';

CREATE FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry, text, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcdrape_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcdrape_pc_transfn(internal, pcpatch, geometry, text, text) IS
'Internal: transition function of ST_TDCDrape(pcpatch, geometry, text, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCDrape(pcpatch, geometry, text, text) (
	SFUNC = st_tdcdrape_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcdrape_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCDrape(pcpatch, geometry, text, text) IS
'the target geometry with Z from the TIN of all patches points, as ST_TDCDrape(geometry, geometry, text) gives on the same points; the last argument filters the points: ''dimension=value[,value...]''.';

-- ST_TDCInterpolate(pcpatch, ...)
CREATE FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster) IS
'Internal: transition function of ST_TDCInterpolate(pcpatch, raster): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCInterpolate(pcpatch, raster) (
	SFUNC = st_tdcinterpolate_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(pcpatch, raster) IS
'interpolation of the patches points at the pixel centres of the template raster, as ST_TDCInterpolate(geometry, raster) gives on the same points.';

CREATE FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text) IS
'Internal: transition function of ST_TDCInterpolate(pcpatch, raster, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCInterpolate(pcpatch, raster, text) (
	SFUNC = st_tdcinterpolate_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(pcpatch, raster, text) IS
'interpolation of the patches points at the pixel centres of the template raster, as ST_TDCInterpolate(geometry, raster, text) gives on the same points.';

CREATE FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text, int4)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text, int4) IS
'Internal: transition function of ST_TDCInterpolate(pcpatch, raster, text, int4): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCInterpolate(pcpatch, raster, text, int4) (
	SFUNC = st_tdcinterpolate_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(pcpatch, raster, text, int4) IS
'interpolation of the patches points at the pixel centres of the template raster, as ST_TDCInterpolate(geometry, raster, text, int4) gives on the same points.';

CREATE FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text, int4, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_pc_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_pc_transfn(internal, pcpatch, raster, text, int4, text) IS
'Internal: transition function of ST_TDCInterpolate(pcpatch, raster, text, int4, text): decodes each patch''s X, Y, Z into the state.';

CREATE AGGREGATE ST_TDCInterpolate(pcpatch, raster, text, int4, text) (
	SFUNC = st_tdcinterpolate_pc_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(pcpatch, raster, text, int4, text) IS
'interpolation of the patches points at the pixel centres of the template raster, as ST_TDCInterpolate(geometry, raster, text, int4) gives on the same points; the last argument filters the points: ''dimension=value[,value...]''.';

-- The tiled procedures over a pcpatch column.  tdc_delaunay_tiled,
-- tdc_contours_tiled (tdc_delaunay) and tdc_interpolate_tiled
-- (tdc_delaunay_raster) take a pcpatch column as their geom_column when this
-- extension is installed, and a last argument filter
-- ('dimension=value[,value...]', NULL: none).  They call these forms of
-- their internal functions, which exist only here: the C functions read the
-- patches (the same reader as the aggregates) only when called with the
-- extra filter argument, so tdc_delaunay alone never reads a patch.

CREATE FUNCTION _tdc_pc_column_srid(source regclass, geom_column text)
RETURNS int4
LANGUAGE plpgsql STABLE
AS $fn$
DECLARE
	nsp name;
	srid int4;
BEGIN
	SELECT n.nspname INTO nsp
	  FROM pg_extension e JOIN pg_namespace n ON n.oid = e.extnamespace
	 WHERE e.extname = 'pointcloud';
	EXECUTE format('SELECT f.srid FROM %1$I.pointcloud_formats f
					 WHERE f.pcid = (SELECT %1$I.PC_PCId(s.%3$I) FROM %2$s s WHERE s.%3$I IS NOT NULL LIMIT 1)',
				   nsp, source, geom_column)
	   INTO srid;
	RETURN srid;
END
$fn$;

COMMENT ON FUNCTION _tdc_pc_column_srid(regclass, text) IS
'Internal, for the tiled procedures: the SRID in pointcloud_formats of the first patch of source.geom_column '
'(NULL when it has none); the reader refuses patches of another pcid later.';

CREATE FUNCTION _tdc_interpolate_tiled_write(query text, target regclass, gt float8[], width int4,
											 height int4, srid int4, method text, pixel_type text,
											 nodata float8, tile_width int4, tile_height int4,
											 geom_type regtype, filter text)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_interpolate_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_interpolate_tiled_write(text, regclass, float8[], int4, int4, int4, text, text, float8, int4, int4, regtype, text) IS
'Internal, for tdc_interpolate_tiled over a pcpatch column: as the form without filter, the samples the X, Y, Z of '
'the patches'' points that filter (''dimension=value[,...]'', NULL: all) keeps.';

CREATE FUNCTION _tdc_contours_tiled_write(query text, target regclass, "interval" float8, base float8,
										  geom_type regtype, filter text)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_contours_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_contours_tiled_write(text, regclass, float8, float8, regtype, text) IS
'Internal, for tdc_contours_tiled over a pcpatch column: as the form without filter, the samples the X, Y, Z of '
'the patches'' points that filter (''dimension=value[,...]'', NULL: all) keeps.';

CREATE FUNCTION _tdc_tiled_write(query text, target regclass, tile_size float8, geom_type regtype, filter text)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_tiled_write(text, regclass, float8, regtype, text) IS
'Internal, for tdc_delaunay_tiled over a pcpatch column: as the form without filter, the vertices the X, Y, Z of '
'the patches'' points that filter (''dimension=value[,...]'', NULL: all) keeps.';
