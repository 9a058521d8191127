-- The install script of tdc_delaunay_raster, made by the Makefile from
-- src/sql/raster_header.sql and src/sql/raster.sql: edit those, not this.
-- A second extension in the tdc_delaunay package, so that CREATE EXTENSION
-- tdc_delaunay never needs postgis_raster; its functions are in the same
-- library (module_pathname of tdc_delaunay_raster.control).

-- complain if script is sourced in psql, rather than via CREATE EXTENSION
\echo Use "CREATE EXTENSION tdc_delaunay_raster" to load this file. \quit

-- src/sql/raster.sql: interpolation of the TIN of the samples' vertices
-- into a PostGIS raster (ST_TDCInterpolateRaster, the ST_TDCInterpolate
-- aggregates; C side: src/pg/fn/fn_raster.c, fn_raster_agg.c, raster_read.c,
-- raster_write.c)

-- ST_TDCInterpolateRaster: drop-in for ST_InterpolateRaster

CREATE FUNCTION ST_TDCInterpolateRaster(input_points geometry,
										method text,
										template raster,
										template_band_num int4 DEFAULT 1)
RETURNS raster
AS 'MODULE_PATHNAME', 'st_tdcinterpolateraster'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
-- A triangulation and a value per pixel: milliseconds to seconds, as
-- ST_InterpolateRaster (COST 10000).
COST 10000;

COMMENT ON FUNCTION ST_TDCInterpolateRaster(geometry, text, raster, int4) IS
'Interpolates the Z of the vertices of input_points at the pixel centres of the template raster, drop-in for '
'ST_InterpolateRaster: method ''linear'', ''nearest'' or ''natural_neighbor'' with GDAL''s options '
'(''linear:radius=0:nodata=-9999''), and ''linear:breaklines=true'' to take the linestrings and polygon rings as '
'hard breaklines. Returns a one-band raster with the template''s extent, resolution, SRID '
'and the pixel type of band template_band_num; pixels without a value are nodata.';

-- Aggregates: ST_TDCInterpolate(geom, template [, method [, template_band_num]])
--   = ST_TDCInterpolateRaster(ST_Collect(geom), method, template, template_band_num)

CREATE FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster) IS
'Transition function of ST_TDCInterpolate(geometry, raster): collects the vertices of each input.';

CREATE FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster, text)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster, text) IS
'Transition function of ST_TDCInterpolate(geometry, raster, text): collects the vertices of each input.';

CREATE FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster, text, int4)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_transfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_transfn(internal, geometry, raster, text, int4) IS
'Transition function of ST_TDCInterpolate(geometry, raster, text, int4): collects the vertices of each input.';

CREATE FUNCTION st_tdcinterpolate_combinefn(internal, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_combinefn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_combinefn(internal, internal) IS
'Combine function of ST_TDCInterpolate: appends the vertices of one partial state to another.';

-- As for ST_TDCDelaunay: a partial state is all its vertices, copied
-- through the tuple queue, and the triangulation runs once, in the leader;
-- these costs let the planner choose a parallel plan only for big tables.
CREATE FUNCTION st_tdcinterpolate_serialfn(internal)
RETURNS bytea
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_serialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcinterpolate_serialfn(internal) IS
'Serialization function of ST_TDCInterpolate for parallel aggregation.';

CREATE FUNCTION st_tdcinterpolate_deserialfn(bytea, internal)
RETURNS internal
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_deserialfn'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE
COST 10000000;

COMMENT ON FUNCTION st_tdcinterpolate_deserialfn(bytea, internal) IS
'Deserialization function of ST_TDCInterpolate for parallel aggregation; checks the header and length.';

CREATE FUNCTION st_tdcinterpolate_finalfn(internal)
RETURNS raster
AS 'MODULE_PATHNAME', 'st_tdcinterpolate_finalfn'
LANGUAGE C IMMUTABLE PARALLEL SAFE;

COMMENT ON FUNCTION st_tdcinterpolate_finalfn(internal) IS
'Final function of ST_TDCInterpolate: triangulates the collected vertices and interpolates the raster.';

CREATE AGGREGATE ST_TDCInterpolate(geometry, raster) (
	SFUNC = st_tdcinterpolate_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	COMBINEFUNC = st_tdcinterpolate_combinefn,
	SERIALFUNC = st_tdcinterpolate_serialfn,
	DESERIALFUNC = st_tdcinterpolate_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(geometry, raster) IS
'Linear interpolation of the Z of the vertices of all input geometries at the pixel centres of the template '
'raster (band 1); same as ST_TDCInterpolateRaster(ST_Collect(geom), ''linear'', template).';

CREATE AGGREGATE ST_TDCInterpolate(geometry, raster, text) (
	SFUNC = st_tdcinterpolate_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	COMBINEFUNC = st_tdcinterpolate_combinefn,
	SERIALFUNC = st_tdcinterpolate_serialfn,
	DESERIALFUNC = st_tdcinterpolate_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(geometry, raster, text) IS
'Interpolation of the Z of the vertices of all input geometries at the pixel centres of the template raster '
'(band 1) with a method (''linear'', ''nearest'', ''natural_neighbor'', GDAL''s options, ''linear:breaklines=true''); '
'same as ST_TDCInterpolateRaster(ST_Collect(geom), method, template).';

CREATE AGGREGATE ST_TDCInterpolate(geometry, raster, text, int4) (
	SFUNC = st_tdcinterpolate_transfn,
	STYPE = internal,
	FINALFUNC = st_tdcinterpolate_finalfn,
	COMBINEFUNC = st_tdcinterpolate_combinefn,
	SERIALFUNC = st_tdcinterpolate_serialfn,
	DESERIALFUNC = st_tdcinterpolate_deserialfn,
	PARALLEL = SAFE
);

COMMENT ON AGGREGATE ST_TDCInterpolate(geometry, raster, text, int4) IS
'Interpolation of the Z of the vertices of all input geometries at the pixel centres of band template_band_num '
'of the template raster with a method (''linear'', ''nearest'', ''natural_neighbor'', GDAL''s options, ''linear:breaklines=true''); '
'same as ST_TDCInterpolateRaster(ST_Collect(geom), method, template, template_band_num).';
