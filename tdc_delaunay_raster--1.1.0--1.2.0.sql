/* tdc_delaunay_raster--1.1.0--1.2.0.sql */

-- complain if script is sourced in psql, rather than via ALTER EXTENSION
\echo Use "ALTER EXTENSION tdc_delaunay_raster UPDATE TO '1.2.0'" to load this file. \quit

-- 1.2.0 adds the procedure tdc_interpolate_tiled and its internal function,
-- as src/sql/raster_tiled.sql has them; every object of 1.1.0 stays as it was.

CREATE FUNCTION _tdc_interpolate_tiled_write(query text, target regclass, gt float8[], width int4,
											 height int4, srid int4, method text, pixel_type text,
											 nodata float8, tile_width int4, tile_height int4,
											 geom_type regtype)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_interpolate_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_interpolate_tiled_write(text, regclass, float8[], int4, int4, int4, text, text, float8, int4, int4, regtype) IS
'Internal, for tdc_interpolate_tiled: the Z of the query''s vertices (its geometry column, of type geom_type) '
'interpolated at the pixel centres of the grid (GDAL geotransform gt, width x height, srid) and written into '
'target (rid bigint, rast raster) as tiles of tile_width x tile_height, the last column and row cut to fit: in one '
'pass when it fits tdc_delaunay.max_memory, else tile by tile through the core''s bounded run. Returns the tiles written.';

-- The procedure: the arguments checked, the target made from the
-- template's geometry, and the work done by _tdc_interpolate_tiled_write
-- in one call, in the caller's transaction: an error or a cancel leaves no
-- target behind.
CREATE PROCEDURE tdc_interpolate_tiled(source text, target text, geom_column text, template raster,
									   method text DEFAULT 'linear', pixel_type text DEFAULT '32BF',
									   nodata float8 DEFAULT -9999, tile_width int DEFAULT 256,
									   tile_height int DEFAULT 256, filter text DEFAULT NULL)
LANGUAGE plpgsql
-- the source is read in its order, as ST_TDCInterpolate reads it (the
-- first copy of a duplicate gives its Z)
SET synchronize_seqscans = off
AS $proc$
DECLARE
	fn constant text := 'tdc_interpolate_tiled';
	src regclass;
	gtyp regtype;
	md record;
	tparts text[];
	qtarget text;
BEGIN
	IF source IS NULL OR target IS NULL OR geom_column IS NULL OR method IS NULL THEN
		RAISE EXCEPTION '%: source, target, geom_column and method must not be NULL', fn
			USING ERRCODE = 'null_value_not_allowed';
	END IF;
	src := to_regclass(source);
	IF src IS NULL THEN
		RAISE EXCEPTION '%: source "%" does not exist', fn, source
			USING ERRCODE = 'undefined_table';
	END IF;
	gtyp := _tdc_tiled_geometry(fn, src, geom_column, filter);
	-- the template: the grid's geometry, without bands
	IF template IS NULL THEN
		RAISE EXCEPTION '%: template must not be NULL', fn
			USING ERRCODE = 'null_value_not_allowed';
	END IF;
	md := ST_MetaData(template);
	IF md.numbands <> 0 THEN
		RAISE EXCEPTION '%: template has % band(s); it must have none', fn, md.numbands
			USING ERRCODE = 'invalid_parameter_value',
				  HINT = 'The pixel type and nodata value are arguments; ST_MakeEmptyRaster(template) keeps the geometry alone.';
	END IF;
	IF md.width = 0 OR md.height = 0 THEN
		RAISE EXCEPTION '%: template is empty (% x % pixels)', fn, md.width, md.height
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	IF NOT (md.scalex * md.scaley - md.skewx * md.skewy <> 0) THEN
		RAISE EXCEPTION '%: template''s pixels have no area (scale % x %, skew % x %)', fn,
			md.scalex, md.scaley, md.skewx, md.skewy
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	IF pixel_type IS NULL OR upper(pixel_type) NOT IN ('1BB', '2BUI', '4BUI', '8BSI', '8BUI', '16BSI', '16BUI',
														'32BSI', '32BUI', '32BF', '64BF') THEN
		RAISE EXCEPTION '%: pixel_type % is not a PostGIS pixel type', fn, coalesce(quote_literal(pixel_type), 'NULL')
			USING ERRCODE = 'invalid_parameter_value',
				  HINT = 'Use one of 1BB, 2BUI, 4BUI, 8BSI, 8BUI, 16BSI, 16BUI, 32BSI, 32BUI, 32BF, 64BF.';
	END IF;
	IF tile_width IS NULL OR tile_height IS NULL OR tile_width NOT BETWEEN 1 AND 65535
	   OR tile_height NOT BETWEEN 1 AND 65535 THEN
		RAISE EXCEPTION '%: tile_width and tile_height must be 1 to 65535, not % and %', fn,
			coalesce(tile_width::text, 'NULL'), coalesce(tile_height::text, 'NULL')
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	-- the target: never overwritten
	tparts := _tdc_tiled_target(fn, target);
	qtarget := format('%I.%I', tparts[1], tparts[2]);
	EXECUTE format('CREATE TABLE %s (rid bigint, rast %s)', qtarget, pg_typeof(template));
	IF (SELECT t.typname = 'pcpatch' FROM pg_type t WHERE t.oid = gtyp) THEN
		-- the pcpatch form of the internal function (tdc_delaunay_pointcloud)
		PERFORM _tdc_interpolate_tiled_write(format('SELECT %I FROM %s', geom_column, src), qtarget::regclass,
											 ARRAY[md.upperleftx, md.scalex, md.skewx, md.upperlefty, md.skewy,
												   md.scaley],
											 md.width, md.height, md.srid, method, upper(pixel_type), nodata,
											 tile_width, tile_height, gtyp, filter);
	ELSE
		PERFORM _tdc_interpolate_tiled_write(format('SELECT %I FROM %s', geom_column, src), qtarget::regclass,
											 ARRAY[md.upperleftx, md.scalex, md.skewx, md.upperlefty, md.skewy,
												   md.scaley],
											 md.width, md.height, md.srid, method, upper(pixel_type), nodata,
											 tile_width, tile_height, gtyp);
	END IF;
END
$proc$;

COMMENT ON PROCEDURE tdc_interpolate_tiled(text, text, text, raster, text, text, float8, int, int, text) IS
'Interpolates the Z of the vertices of source.geom_column (a pcpatch column with tdc_delaunay_pointcloud: its '
'points'' X, Y, Z, those the filter ''dimension=value[,...]'' keeps) at the pixel centres of the band-less template''s grid '
'with a method (''linear'', ''nearest'', ''natural_neighbor'', GDAL''s options) into a new table target(rid bigint, '
'rast raster), a coverage of tiles of tile_width x tile_height pixels as raster2pgsql -t writes (rid 1.. row by row, '
'the last column and row cut to fit), one band of pixel_type with nodata: each tile equals the same window of '
'ST_TDCInterpolate over all the samples, pixel for pixel, and all-nodata tiles are written too. In one pass when it '
'fits tdc_delaunay.max_memory (any method), else through the core''s bounded run (any grid whose pixels have an '
'area; natural neighbour where each tile proves its pixels'' natural neighbours within the limit, else an error '
'says so).';
