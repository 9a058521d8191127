--
-- tdc_raster_arbiter: ST_TDCInterpolateRaster 'linear' against GDAL's
-- (ST_InterpolateRaster) at projected offsets, with the exact arbiter
-- deciding where they differ (issue 38).  Needs tdc_raster (the
-- extensions).
--
-- The same 20,000 random samples in a 400 m square (coordinates offset +
-- k/256, heights multiples of 1/1024 with a few metres of noise on a
-- smooth surface, so every value is exact in float8 and numeric) at
-- offsets 0, 500,000 and 5,000,000 in x and y, into 200 x 200 pixels of
-- 2 m.  Where the two rasters differ by more than 1e-12 relative, and at
-- every 97th pixel whatever GDAL says, the arbiter
-- (sql/include/tin_arbiter.sql) computes the exact value: the Delaunay
-- triangle holding the pixel centre, its circumcircle checked against every
-- sample that could lie inside, the plane's value in rational arithmetic.
-- Ours must be within 1e-9 m of it at every such pixel, on a triangle no
-- other sample's circle position could change (random samples: the
-- Delaunay triangle, and so the value, is unique).
--
-- How many pixels GDAL gets wrong depends on GDAL's version (its
-- triangulation comes from qhull, in floating point), so the counts are
-- not part of the expected output: they go to
-- build/regress/tdc_raster_arbiter.txt (the directory pg_regress gives in
-- PG_ABS_BUILDDIR), which `make test` prints after pg_regress.  With GDAL
-- 3.6 (Debian 12) they were 0, 6 and 328 pixels at the three offsets,
-- off by up to 0.17 m (README, "Differences from PostGIS").
--
\getenv abs_srcdir PG_ABS_SRCDIR
\getenv abs_builddir PG_ABS_BUILDDIR
\set arbiter :abs_srcdir '/sql/include/tin_arbiter.sql'
\set ECHO none
\i :arbiter
\set ECHO all

CREATE TABLE ra_k AS
	SELECT i, kx, ky, round(1024 * (100 + 30 * sin(kx / 256.0 / 70) * cos(ky / 256.0 / 50) + 0.05 * kx / 256.0
									+ (hashint4(i + 99) % 1000) / 250.0)) / 1024 AS z
	FROM (SELECT i, (hashint4(i) & 262143) % 102400 AS kx, (hashint4(i + 7777777) & 262143) % 102400 AS ky
		  FROM generate_series(1, 20000) i) s;
CREATE TABLE ra_o AS SELECT o FROM (VALUES (0), (500000), (5000000)) v(o);
-- Both rasters, pixel by pixel (row by row from the top: qid 1 is the top
-- left pixel); outside the hull both are nodata (radius=0).
CREATE TABLE ra_px AS
	SELECT o, u.qid, u.a, u.b
	FROM ra_o,
		 LATERAL (SELECT ST_Collect(ST_MakePoint(o + kx / 256.0, o + ky / 256.0, z) ORDER BY i) AS p FROM ra_k) s,
		 LATERAL (SELECT ST_AddBand(ST_MakeEmptyRaster(200, 200, o, o + 400, 2, -2, 0, 0, 0), '64BF'::text,
									-9999::float8, -9999::float8) AS r) t,
		 unnest(ST_DumpValues(ST_TDCInterpolateRaster(p, 'linear:radius=0', r), 1),
				ST_DumpValues(ST_InterpolateRaster(p, 'linear:radius=0:nodata=-9999', r), 1)) WITH ORDINALITY u(a, b, qid);
-- The pixels the arbiter judges: where GDAL differs, and every 97th.
CREATE TABLE ra_sel AS
	SELECT o, qid, a, b, qid % 97 = 0 AS sampled,
		   coalesce(abs(a - b) > 1e-12 * greatest(abs(a), abs(b)), false) AS differs,
		   o + ((qid - 1) % 200 + 0.5) * 2.0::float8 AS x, o + 400 - ((qid - 1) / 200 + 0.5) * 2.0::float8 AS y
	FROM ra_px
	WHERE a IS NOT NULL AND (qid % 97 = 0 OR abs(a - b) > 1e-12 * greatest(abs(a), abs(b)));
-- The arbiter, offset by offset: the samples, the selected pixel centres,
-- the triangles of our TIN around them as candidates.
CREATE TABLE ra_chk (o int, qid bigint, tri bigint, circle int, z numeric);
CREATE FUNCTION ra_judge(off int) RETURNS bool LANGUAGE plpgsql AS $$
BEGIN
	PERFORM tdc_arb_samples(ST_Collect(ST_MakePoint(off + kx / 256.0, off + ky / 256.0, z) ORDER BY i)) FROM ra_k;
	PERFORM tdc_arb_queries(ST_Collect(ST_MakePoint(x, y) ORDER BY qid)) FROM ra_sel WHERE o = off;
	PERFORM tdc_arb_triangles(ST_TDCDelaunayTriangles(ST_Collect(ST_MakePoint(off + kx / 256.0, off + ky / 256.0) ORDER BY i)),
							  true)
	FROM ra_k;
	INSERT INTO ra_chk
	SELECT off, s.qid, l.tri, l.circle, l.z
	FROM tdc_arb_linear() l JOIN tdc_arb_q q ON q.qid = l.qid
		 JOIN ra_sel s ON s.o = off AND s.x = q.fx AND s.y = q.fy;
	RETURN true;
END $$;
SELECT o AS offset, ra_judge(o) AS judged FROM ra_o ORDER BY o;

-- Ours at every judged pixel: the exact value, on the only Delaunay
-- triangle there (circle 1).
SELECT s.o AS offset, (SELECT count(*) FROM ra_px p WHERE p.o = s.o AND p.a IS NOT NULL) AS ours_values,
	   count(*) FILTER (WHERE sampled) AS sampled,
	   count(*) FILTER (WHERE sampled AND abs(tdc_arb_num(a) - c.z) <= 1e-9 AND c.circle = 1) AS sampled_exact,
	   coalesce(bool_and(abs(tdc_arb_num(a) - c.z) <= 1e-9 AND c.circle = 1) FILTER (WHERE differs), true)
		   AS exact_wherever_gdal_differs,
	   count(*) = count(c.tri) AS every_pixel_located
FROM ra_sel s LEFT JOIN ra_chk c ON c.o = s.o AND c.qid = s.qid
GROUP BY s.o ORDER BY s.o;

-- GDAL's errors, per offset, into the file: the pixels where it differs
-- from ours beyond 1e-12 relative, those where it is more than 1e-9 m from
-- the exact value, and the largest errors of both.
\set counts :abs_builddir '/tdc_raster_arbiter.txt'
\o :counts
SELECT s.o AS offset, count(*) FILTER (WHERE differs) AS gdal_differs,
	   count(*) FILTER (WHERE differs AND abs(tdc_arb_num(b) - c.z) > 1e-9) AS gdal_wrong,
	   round(max(abs(tdc_arb_num(b) - c.z)) FILTER (WHERE differs), 6) AS gdal_max_error_m,
	   max(abs(tdc_arb_num(a) - c.z))::float8 AS ours_max_error_m
FROM ra_sel s JOIN ra_chk c ON c.o = s.o AND c.qid = s.qid
GROUP BY s.o ORDER BY s.o;
\o

DROP FUNCTION ra_judge(int);
DROP TABLE ra_k, ra_o, ra_px, ra_sel, ra_chk;
\set arbiter :abs_srcdir '/sql/include/tin_arbiter_drop.sql'
\set ECHO none
\i :arbiter
\set ECHO all
