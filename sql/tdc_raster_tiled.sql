--
-- tdc_raster_tiled: tdc_interpolate_tiled, a raster coverage (a table of
-- tiles as raster2pgsql -t writes) equal pixel for pixel to the one raster
-- ST_TDCInterpolate makes over all the samples: in one pass, and through
-- the core's bounded run under a tdc_delaunay.max_memory that one pass
-- does not fit.  Then its refusals, none of which leaves a target.
--
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE;
RESET client_min_messages;
-- (the plan depends on the engine's memory estimate, which depends on the
-- thread count: one thread, the same plan on every machine)
SET tdc_delaunay.threads = 1;

-- A coverage against ST_TDCInterpolate over the same samples, with the
-- template given a band of pixel_type and nodata: its tiles counted, those
-- whose pixels (raw values, nodata included) differ from the same window
-- of the one raster, those whose upper left corner is not the grid's pixel
-- corner as PostGIS computes it, or whose pixel type, nodata value, scale,
-- skew or SRID differ; the pixels covered, and the tiles all nodata
-- (flagged so, as ST_AddBand flags a band of nodata, which ST_DumpValues
-- then reads as NULLs: their window must be the nodata value throughout).
CREATE FUNCTION cov_check(cov regclass, src text, tmpl raster, method text, pixtype text, nodata float8,
						  tw int, th int)
RETURNS TABLE (tiles bigint, bad_pixels bigint, bad_corner bigint, bad_band bigint, pixels bigint,
			   nodata_tiles bigint)
LANGUAGE plpgsql AS $$
DECLARE
	one raster;
	v float8[];
	ncols int := (ST_Width(tmpl) + tw - 1) / tw;
BEGIN
	EXECUTE format('SELECT ST_TDCInterpolate(geom, ST_AddBand($1, $2::text, $3::float8, $3::float8), $4) FROM %s', src)
	   INTO one USING tmpl, pixtype, nodata, method;
	v := ST_DumpValues(one, 1, false);
	RETURN QUERY EXECUTE format($q$
		SELECT count(*),
			   count(*) FILTER (WHERE CASE WHEN ST_BandIsNoData(c.rast)
										   THEN EXISTS (SELECT FROM unnest($1[r0 + 1 : r0 + ST_Height(c.rast)][c0 + 1 : c0 + ST_Width(c.rast)]) x
														 WHERE x IS DISTINCT FROM ST_BandNoDataValue(c.rast))
										   ELSE ST_DumpValues(c.rast, 1, false) IS DISTINCT FROM
												$1[r0 + 1 : r0 + ST_Height(c.rast)][c0 + 1 : c0 + ST_Width(c.rast)] END),
			   count(*) FILTER (WHERE ST_UpperLeftX(c.rast) <> ST_RasterToWorldCoordX($2, (c0 + 1)::int, (r0 + 1)::int)
									  OR ST_UpperLeftY(c.rast) <> ST_RasterToWorldCoordY($2, (c0 + 1)::int, (r0 + 1)::int)),
			   count(*) FILTER (WHERE ST_BandPixelType(c.rast) <> ST_BandPixelType($2)
									  OR ST_BandNoDataValue(c.rast) IS DISTINCT FROM ST_BandNoDataValue($2)
									  OR ST_ScaleX(c.rast) <> ST_ScaleX($2) OR ST_ScaleY(c.rast) <> ST_ScaleY($2)
									  OR ST_SkewX(c.rast) <> ST_SkewX($2) OR ST_SkewY(c.rast) <> ST_SkewY($2)
									  OR ST_SRID(c.rast) <> ST_SRID($2) OR ST_NumBands(c.rast) <> 1),
			   sum(ST_Width(c.rast) * ST_Height(c.rast))::bigint,
			   count(*) FILTER (WHERE ST_BandIsNoData(c.rast))
		  FROM (SELECT rast, ((rid - 1) / $3) * $4 AS r0, ((rid - 1) %% $3) * $5 AS c0 FROM %s) c$q$, cov)
	  USING v, one, ncols, th, tw;
END $$;

-- Whether AddRasterConstraints takes a coverage, and what it recorded.
CREATE FUNCTION cov_constraints(cov name)
RETURNS TABLE (added boolean, same_alignment boolean, blocksize_x int, blocksize_y int, srid int)
LANGUAGE plpgsql AS $$
BEGIN
	added := AddRasterConstraints(cov, 'rast'::name);
	SELECT c.same_alignment, c.blocksize_x, c.blocksize_y, c.srid INTO same_alignment, blocksize_x, blocksize_y, srid
	  FROM raster_columns c WHERE c.r_table_name = cov;
	RETURN NEXT;
END $$;

-- Clustered samples with heights: 2,000 of them, then 9 clusters of
-- 29,200 (2^18 and a few: below 2^18 points the bounded run's grid is
-- uniform, and it holds some 9 MB of its own, so one pass of a small set
-- always fits a limit the run fits).
SELECT setseed(0.25);
CREATE TABLE rt_small AS
	SELECT ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
	  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
			  FROM (SELECT (i % 2) * 60 AS cx, (i / 2) * 50 AS cy FROM generate_series(0, 3) i) c,
				   generate_series(1, 500)) q;
CREATE TABLE rt_c9 AS
	SELECT ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
	  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
			  FROM (SELECT (i % 3) * 100 AS cx, ((i / 3) % 3) * 100 AS cy FROM generate_series(0, 8) i) c,
				   generate_series(1, 29200)) q;

-- One pass (it fits the default limit): any method, tiles of 30 x 17 on
-- 137 x 101 pixels (the last column and row cut to fit); the summary is a
-- NOTICE.
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_small', 'rt_small_lin', 'geom',
						   ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326), 'linear', '64BF', -9999, 30, 17);
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_interpolate_tiled('rt_small', 'rt_small_nn', 'geom',
						   ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326), 'natural_neighbor', '32BF', -9999, 30, 17);
CALL tdc_interpolate_tiled('rt_small', 'rt_small_near', 'geom',
						   ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326), 'nearest:radius=3', '32BF', NULL, 30, 17);
-- a tile larger than the grid: one tile, the grid's size
CALL tdc_interpolate_tiled('rt_small', 'rt_small_one', 'geom',
						   ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326), 'linear', '32BF', 0, 500, 500);
-- a skewed grid, in one pass
CALL tdc_interpolate_tiled('rt_small', 'rt_small_skew', 'geom',
						   ST_MakeEmptyRaster(90, 70, -30, 60, 1.1, -0.9, 0.35, -0.2, 0), 'linear', '64BF', -9999, 32, 32);
SELECT 'lin' AS cov, * FROM cov_check('rt_small_lin', 'rt_small', ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326),
									  'linear', '64BF', -9999, 30, 17)
UNION ALL
SELECT 'nn', * FROM cov_check('rt_small_nn', 'rt_small', ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326),
							  'natural_neighbor', '32BF', -9999, 30, 17)
UNION ALL
SELECT 'near', * FROM cov_check('rt_small_near', 'rt_small', ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326),
								'nearest:radius=3', '32BF', NULL, 30, 17)
UNION ALL
SELECT 'one', * FROM cov_check('rt_small_one', 'rt_small', ST_MakeEmptyRaster(137, 101, -20, 80, 0.75, -1.05, 0, 0, 4326),
							   'linear', '32BF', 0, 500, 500)
UNION ALL
SELECT 'skew', * FROM cov_check('rt_small_skew', 'rt_small', ST_MakeEmptyRaster(90, 70, -30, 60, 1.1, -0.9, 0.35, -0.2, 0),
								'linear', '64BF', -9999, 32, 32);
SELECT 'lin' AS cov, * FROM cov_constraints('rt_small_lin')
UNION ALL SELECT 'skew', * FROM cov_constraints('rt_small_skew')
UNION ALL SELECT 'one', * FROM cov_constraints('rt_small_one');
-- the nodata value of a pixel with none: nodata NULL takes the method's
SELECT DISTINCT ST_BandNoDataValue(rast) AS near_nodata FROM rt_small_near;

-- The core's bounded run: one pass of rt_c9 does not fit 16 MB.  Tiles of
-- 64 x 50 on 331 x 290 pixels, 32BF and 64BF, linear and nearest; the
-- NOTICE gives the run's tiles.  The samples end at x = 215: with radius 0
-- the last two columns of tiles have no value, and are written all nodata.
SET tdc_delaunay.max_memory = 16;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_32', 'geom',
						   ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006), 'linear', '32BF', -9999, 64, 50);
-- Skewed, rotated and flipped templates in tiles too (the same 30 run
-- tiles): each tile's upper left corner is the template's geotransform at
-- its first pixel's corner, its scale and skew the template's.  Skewed
-- (linear, 64BF) here; below, rotated by 30 degrees (nearest with a
-- radius, 32BF) and flipped (scale x < 0, scale y > 0: linear with
-- max_edge, 32BF); each reaches past the samples on every side.
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_skew', 'geom',
						   ST_MakeEmptyRaster(290, 290, -102, 208, 1.1, -1.0, 0.3, 0.25, 3006), 'linear', '64BF', -9999, 64, 50);
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_64', 'geom',
						   ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006), 'linear:radius=0', '64BF', -1e30, 64, 50);
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_near', 'geom',
						   ST_MakeEmptyRaster(200, 190, -20, 230, 1.6, -1.55, 0, 0, 3006), 'nearest', '32BF', -9999, 256, 37);
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_rot', 'geom',
						   ST_MakeEmptyRaster(290, 290, -140, 160, 1.2 * cos(pi() / 6), -1.2 * cos(pi() / 6),
											  1.2 * sin(pi() / 6), 1.2 * sin(pi() / 6), 3006),
						   'nearest:radius=4', '32BF', -9999, 60, 45);
CALL tdc_interpolate_tiled('rt_c9', 'rt_c9_flip', 'geom',
						   ST_MakeEmptyRaster(170, 160, 230, -20, -1.5, 1.6, 0, 0, 3006), 'linear:max_edge=6', '32BF', -9999, 50, 50);
RESET tdc_delaunay.max_memory;
SELECT '32' AS cov, * FROM cov_check('rt_c9_32', 'rt_c9', ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006),
									 'linear', '32BF', -9999, 64, 50)
UNION ALL
SELECT '64', * FROM cov_check('rt_c9_64', 'rt_c9', ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006),
							  'linear:radius=0', '64BF', -1e30, 64, 50)
UNION ALL
SELECT 'near', * FROM cov_check('rt_c9_near', 'rt_c9', ST_MakeEmptyRaster(200, 190, -20, 230, 1.6, -1.55, 0, 0, 3006),
								'nearest', '32BF', -9999, 256, 37)
UNION ALL
SELECT 'skew', * FROM cov_check('rt_c9_skew', 'rt_c9', ST_MakeEmptyRaster(290, 290, -102, 208, 1.1, -1.0, 0.3, 0.25, 3006),
								'linear', '64BF', -9999, 64, 50)
UNION ALL
SELECT 'rot', * FROM cov_check('rt_c9_rot', 'rt_c9', ST_MakeEmptyRaster(290, 290, -140, 160, 1.2 * cos(pi() / 6), -1.2 * cos(pi() / 6),
																		 1.2 * sin(pi() / 6), 1.2 * sin(pi() / 6), 3006),
							   'nearest:radius=4', '32BF', -9999, 60, 45)
UNION ALL
SELECT 'flip', * FROM cov_check('rt_c9_flip', 'rt_c9', ST_MakeEmptyRaster(170, 160, 230, -20, -1.5, 1.6, 0, 0, 3006),
								'linear:max_edge=6', '32BF', -9999, 50, 50);
SELECT '32' AS cov, * FROM cov_constraints('rt_c9_32')
UNION ALL SELECT 'near', * FROM cov_constraints('rt_c9_near')
UNION ALL SELECT 'skew', * FROM cov_constraints('rt_c9_skew')
UNION ALL SELECT 'rot', * FROM cov_constraints('rt_c9_rot')
UNION ALL SELECT 'flip', * FROM cov_constraints('rt_c9_flip');

-- Natural neighbour in tiles: each tile proves every pixel's cavity (the
-- triangles whose circumcircle holds the pixel's centre) global in its own
-- triangulation, or runs again knowing more (terrain/raster_natural.c).
-- 270,000 samples spread over 300 x 300 (one pass does not fit 16 MB),
-- 64BF, and with max_edge and radius=0 beyond a grid wider than the data.
CREATE TABLE rt_u AS
	SELECT ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
	  FROM (SELECT 300 * random() AS x, 300 * random() AS y FROM generate_series(1, 270000)) q;
SET tdc_delaunay.max_memory = 16;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_u', 'rt_u_nn', 'geom',
						   ST_MakeEmptyRaster(331, 290, -20, 295, 1.0, -1.0, 0, 0, 3006), 'natural_neighbor', '64BF', -9999, 64, 50);
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_interpolate_tiled('rt_u', 'rt_u_nn_me', 'geom',
						   ST_MakeEmptyRaster(331, 290, -20, 295, 1.0, -1.0, 0, 0, 3006),
						   'natural_neighbor:max_edge=1.5:radius=0', '32BF', -9999, 64, 50);
RESET tdc_delaunay.max_memory;
SELECT 'nn' AS cov, * FROM cov_check('rt_u_nn', 'rt_u', ST_MakeEmptyRaster(331, 290, -20, 295, 1.0, -1.0, 0, 0, 3006),
									 'natural_neighbor', '64BF', -9999, 64, 50)
UNION ALL
SELECT 'nn_me', * FROM cov_check('rt_u_nn_me', 'rt_u', ST_MakeEmptyRaster(331, 290, -20, 295, 1.0, -1.0, 0, 0, 3006),
								 'natural_neighbor:max_edge=1.5:radius=0', '32BF', -9999, 64, 50);

-- The GSHHG shoreline of the Stockholm archipelago (test/fixtures/
-- gshhg-stockholm.wkt, as tdc_constrained_gshhg reads it): its 17,548
-- vertices with a made-up Z, in one pass, 4 x 3 tiles of 64 x 64.
\getenv abs_srcdir PG_ABS_SRCDIR
\set fixture :abs_srcdir '/test/fixtures/gshhg-stockholm.wkt'
\set wkt `cat :'fixture'`
CREATE TABLE rt_gshhg AS
SELECT ST_Force3DZ(ST_SetSRID(p.geom, 4326), 10 * sin(ST_X(p.geom) * 40) + 5 * cos(ST_Y(p.geom) * 70)) AS geom
  FROM regexp_split_to_table(rtrim(:'wkt', E'\n'), E'\n') w, ST_DumpPoints(ST_GeomFromText(w)) p;
\unset wkt
-- (ST_Force3DZ(g, z) sets every vertex's Z to z; each row is one point)
SELECT count(*) AS gshhg_points FROM rt_gshhg;
CALL tdc_interpolate_tiled('rt_gshhg', 'rt_gshhg_cov', 'geom',
						   ST_MakeEmptyRaster(230, 150, 18.1, 59.6, 0.004, -0.0025, 0, 0, 4326), 'linear', '32BF', -9999, 64, 64);
SELECT * FROM cov_check('rt_gshhg_cov', 'rt_gshhg', ST_MakeEmptyRaster(230, 150, 18.1, 59.6, 0.004, -0.0025, 0, 0, 4326),
						'linear', '32BF', -9999, 64, 64);
SELECT * FROM cov_constraints('rt_gshhg_cov');
-- and through the core's bounded run: a 2000 x 1500 grid of 9 bytes a
-- pixel does not fit 20 MB with them in one pass (one run tile: the set
-- is small)
SET tdc_delaunay.max_memory = 20;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_gshhg', 'rt_gshhg_big', 'geom',
						   ST_MakeEmptyRaster(2000, 1500, 18.1, 59.6, 0.00045, -0.00025, 0, 0, 4326), 'linear', '32BF', -9999, 256, 64);
\set VERBOSITY default
SET client_min_messages = warning;
RESET tdc_delaunay.max_memory;
-- nearest too, on a window narrower than the shoreline (its rows cross the
-- hull beside the grid)
SET tdc_delaunay.max_memory = 20;
CALL tdc_interpolate_tiled('rt_gshhg', 'rt_gshhg_near', 'geom',
						   ST_MakeEmptyRaster(1800, 1700, 18.3, 59.6, 0.0004, -0.00022, 0, 0, 4326), 'nearest', '32BF', -9999, 256, 64);
RESET tdc_delaunay.max_memory;
SELECT 'linear' AS method, * FROM cov_check('rt_gshhg_big', 'rt_gshhg', ST_MakeEmptyRaster(2000, 1500, 18.1, 59.6, 0.00045, -0.00025, 0, 0, 4326),
											'linear', '32BF', -9999, 256, 64)
UNION ALL
SELECT 'nearest', * FROM cov_check('rt_gshhg_near', 'rt_gshhg', ST_MakeEmptyRaster(1800, 1700, 18.3, 59.6, 0.0004, -0.00022, 0, 0, 4326),
								   'nearest', '32BF', -9999, 256, 64);

-- Refusals: each a clear error, and none leaves its target.
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', NULL);
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_AddBand(ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), '8BUI'));
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(0, 10, 0, 10, 1, -1, 0, 0, 0));
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, 0, 0, 0, 0));
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), 'linear', '48BF');
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), 'linear', '32BF', 0, 0, 10);
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), 'linear', '32BF', 0, 10, 70000);
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), 'cubic');
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0), 'linear:breaklines=true');
CALL tdc_interpolate_tiled('rt_small', 'rt_small_lin', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0));
CALL tdc_interpolate_tiled('rt_nosuch', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0));
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'nosuch', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0));
-- a skewed template whose pixels have no area (scale x scale y = skew x skew y)
CALL tdc_interpolate_tiled('rt_small', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 2, 2, 1, 4, 0));
-- in tiles: natural neighbour where the cavities of a tile's pixels reach
-- further than the limit lets it read (the clusters' gaps hold triangles
-- as wide as them) is refused with the reason
SET tdc_delaunay.max_memory = 16;
CALL tdc_interpolate_tiled('rt_c9', 'rt_bad', 'geom', ST_MakeEmptyRaster(100, 100, -20, 230, 3, -3, 0, 0, 0), 'natural_neighbor');
-- and a template whose pixels are nearly flat (their area 1e-14 of a square's: the core cannot map
-- a point back to its pixel with a bounded error), naming its geotransform
CALL tdc_interpolate_tiled('rt_c9', 'rt_bad', 'geom', ST_MakeEmptyRaster(100, 100, -20, 230, 1, -1, 1, -0.99999999999999, 0));
-- a cancel (here a statement timeout) stops it, in the read or the run
SET statement_timeout = '300ms';
CALL tdc_interpolate_tiled('rt_c9', 'rt_bad', 'geom', ST_MakeEmptyRaster(331, 290, -20, 230, 1.0, -1.0, 0, 0, 3006));
RESET statement_timeout;
RESET tdc_delaunay.max_memory;
\set VERBOSITY default
SELECT to_regclass('rt_bad') IS NULL AS no_target_left;
-- samples without Z
CREATE TABLE rt_flat AS SELECT ST_MakePoint(i, i * i % 7) AS geom FROM generate_series(1, 10) i;
\set VERBOSITY terse
CALL tdc_interpolate_tiled('rt_flat', 'rt_bad', 'geom', ST_MakeEmptyRaster(10, 10, 0, 10, 1, -1, 0, 0, 0));
\set VERBOSITY default
SELECT to_regclass('rt_bad') IS NULL AS no_target_left;
-- nor any file: the runs' directories under pgsql_tmp are gone
SELECT count(*) AS tmp_left FROM pg_ls_dir('base/pgsql_tmp', true, false) f WHERE f LIKE 'pgsql_tmp%.tdc.%';

DROP TABLE rt_small, rt_c9, rt_gshhg, rt_flat, rt_small_lin, rt_small_nn, rt_small_near, rt_small_one, rt_small_skew,
	rt_c9_32, rt_c9_64, rt_c9_near, rt_c9_skew, rt_c9_rot, rt_c9_flip, rt_u, rt_u_nn, rt_u_nn_me, rt_gshhg_cov,
	rt_gshhg_big, rt_gshhg_near;
DROP FUNCTION cov_check(regclass, text, raster, text, text, float8, int, int);
DROP FUNCTION cov_constraints(name);
RESET tdc_delaunay.threads;
RESET client_min_messages;
