--
-- tdc_tin_values: the heights every TIN function computes, against
-- independent references (issue 36), on held-out points at a projected
-- offset (around (500000, 4000000)).
--
-- Every method of every function that computes heights (ST_TDCDrape,
-- ST_TDCInterpolate, ST_TDCInterpolateRaster, ST_TDCContours) is compared
-- with:
--   nearest            a brute-force search over every sample, exact, with
--                      the documented tie rule (sql/include/tin_arbiter.sql);
--   linear             the exact arbiter: the value, in rational arithmetic,
--                      of a triangle holding the point whose circumcircle
--                      holds no sample (the triangle, and so the value, is
--                      Delaunay);
--   natural_neighbor   CGAL's natural neighbour value, and
--   breaklines         the linear value on CGAL's constrained Delaunay
--                      triangulation, both precomputed with exact
--                      constructions into test/fixtures/tin-reference.txt
--                      (the core suite checks that CGAL still prints them);
--   contours           every crossing of the exact Delaunay triangulation's
--                      edges with a level, at its exact position, once.
-- The drape takes every target type (points, lines, polygons, the multi
-- kinds, a collection) in each of XY, XYZ, XYM and XYZM.  A lattice adds
-- what random samples lack: nearest ties (two and four samples equally
-- near), duplicates whose first height counts, and cocircular squares,
-- where the linear value of either diagonal is a Delaunay value.
--
-- Coordinates are 500000 + k/256 and 4000000 + k/256 (exact in float8 and
-- in the arbiter's numeric); heights are compared within 1e-9 m (ours are
-- computed in double: about 1e-13 m from the exact value here), the new
-- vertices of a linear drape, which are rounded onto their edge, within
-- 1e-6 m.  Before the fix of issue 36 every nearest drape here had Z = 0.
--
-- The arbiter's functions and tables, not echoed (pg_regress gives the
-- source directory in PG_ABS_SRCDIR; psql reads the test from standard
-- input, so \ir would look in the current directory).
\getenv abs_srcdir PG_ABS_SRCDIR
\set arbiter :abs_srcdir '/sql/include/tin_arbiter.sql'
\set ECHO none
\i :arbiter
\set ECHO all
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay_raster CASCADE;
RESET client_min_messages;

-- The fixture, read on the client side: samples, breakline segments,
-- queries.
\set fixture :abs_srcdir '/test/fixtures/tin-reference.txt'
\set txt `cat :'fixture'`
CREATE TABLE tv_txt AS
	SELECT n, l FROM regexp_split_to_table(rtrim(:'txt', E'\n'), E'\n') WITH ORDINALITY t(l, n) WHERE l !~ '^#';
\unset txt
CREATE FUNCTION tv_section(word text) RETURNS TABLE (k bigint, f text[]) LANGUAGE sql AS $$
	SELECT row_number() OVER (ORDER BY n), string_to_array(l, ' ')
	FROM tv_txt
	WHERE n > (SELECT n FROM tv_txt WHERE l LIKE word || ' %')
	  AND n < coalesce((SELECT min(t.n) FROM tv_txt t WHERE t.l ~ '^[a-z]'
						AND t.n > (SELECT n FROM tv_txt WHERE l LIKE word || ' %')), 1e9) $$;
CREATE TABLE tv_s AS SELECT k AS ord, f[1]::float8 AS x, f[2]::float8 AS y, f[3]::float8 AS z FROM tv_section('samples');
CREATE TABLE tv_q AS SELECT k AS qid, f[1]::float8 AS x, f[2]::float8 AS y, f[3]::float8 AS nn, f[4]::float8 AS brk
FROM tv_section('queries');
-- the rows: points, and for the breaklines also each segment as a line
CREATE TABLE tv_pts AS SELECT ord, ST_MakePoint(x, y, z) AS geom FROM tv_s;
CREATE TABLE tv_brk AS SELECT ord, geom FROM tv_pts
	UNION ALL SELECT 2000 + k, ST_MakeLine(a.geom, b.geom)
	FROM tv_section('segments') s, tv_pts a, tv_pts b WHERE a.ord = f[1]::int + 1 AND b.ord = f[2]::int + 1;
SELECT (SELECT count(*) FROM tv_s) AS samples, (SELECT count(*) FROM tv_brk) - (SELECT count(*) FROM tv_s) AS segments,
	   (SELECT count(*) FROM tv_q) AS queries;

-- The references at the 1,024 pixel centres: the nearest sample's height,
-- and the linear value on a triangle of our TIN that the arbiter checked
-- (circle 1: no other sample on its circumcircle either, so the Delaunay
-- triangle holding the point is unique and so is the value).
SELECT tdc_arb_samples(ST_Collect(geom ORDER BY ord)) AS arbiter_samples,
	   tdc_arb_triangles(ST_TDCDelaunayTriangles(ST_Collect(geom ORDER BY ord))) AS candidate_triangles
FROM tv_pts;
SELECT tdc_arb_queries(ST_Collect(ST_MakePoint(x, y) ORDER BY qid)) AS arbiter_queries FROM tv_q;
CREATE TABLE tv_ref AS
	SELECT q.*, n.z AS near, l.tri, l.circle, l.z AS lin
	FROM tv_q q JOIN tdc_arb_nearest() n USING (qid) JOIN tdc_arb_linear() l USING (qid);
SELECT count(*) AS queries, count(tri) AS located, min(circle) AS least_circle FROM tv_ref;

-- ----------------------------------------------------------------------
-- Rasters: ST_TDCInterpolateRaster and the ST_TDCInterpolate aggregate,
-- every pixel of a 32 x 32 template whose pixel centres are the queries.
-- ----------------------------------------------------------------------
CREATE TABLE tv_tmpl AS
	SELECT ST_AddBand(ST_MakeEmptyRaster(32, 32, 500000, 4001000, 31.25, -31.25, 0, 0, 0), '64BF'::text,
					  -9999::float8, -9999::float8) AS r;
CREATE TABLE tv_rast AS
	SELECT 'function' AS fn, m, ST_TDCInterpolateRaster(s.c, m, r) AS o
	FROM tv_tmpl, (VALUES ('nearest'), ('linear'), ('natural_neighbor')) v(m),
		 (SELECT ST_Collect(geom ORDER BY ord) AS c FROM tv_pts) s
	UNION ALL
	SELECT 'function', 'linear:breaklines=true',
		   ST_TDCInterpolateRaster((SELECT ST_Collect(geom ORDER BY ord) FROM tv_brk), 'linear:breaklines=true', r)
	FROM tv_tmpl
	UNION ALL
	SELECT 'aggregate', m, (SELECT ST_TDCInterpolate(geom, r, m ORDER BY ord) FROM tv_pts)
	FROM tv_tmpl, (VALUES ('nearest'), ('linear'), ('natural_neighbor')) v(m)
	UNION ALL
	SELECT 'aggregate', 'linear:breaklines=true',
		   (SELECT ST_TDCInterpolate(geom, r, 'linear:breaklines=true' ORDER BY ord) FROM tv_brk)
	FROM tv_tmpl;
-- Within tol of the method's reference (nearest: the same sample, exactly).
CREATE FUNCTION tv_wrong(m text, v float8, ref tv_ref, tol float8 DEFAULT 1e-9) RETURNS bool LANGUAGE sql AS $$
	SELECT NOT coalesce(CASE split_part(m, ':', 1)
						WHEN 'nearest' THEN v = ref.near
						WHEN 'natural_neighbor' THEN abs(v - ref.nn) <= tol
						ELSE CASE WHEN m LIKE '%breaklines%' THEN abs(v - ref.brk) <= tol
								  ELSE ref.circle >= 0 AND abs(tdc_arb_num(v) - ref.lin) <= tol END END, false) $$;
SELECT fn, m AS method, count(*) AS pixels, count(*) FILTER (WHERE tv_wrong(m, v, ref)) AS wrong
FROM tv_rast, unnest(ST_DumpValues(o, 1)) WITH ORDINALITY u(v, qid) JOIN tv_ref ref USING (qid)
GROUP BY fn, m ORDER BY fn, m;

-- ----------------------------------------------------------------------
-- ST_TDCDrape: every target type in XY, XYZ (its Z replaced), XYM and XYZM
-- (M kept), its vertices at pixel centres, written in pixel units and
-- moved onto them (ST_Affine: exact, the scale and offsets being dyadic).
-- ----------------------------------------------------------------------
CREATE TABLE tv_targets AS
	SELECT kind, dims,
		   CASE dims WHEN 'XY' THEN g WHEN 'XYZ' THEN ST_Force3DZ(g, 999) WHEN 'XYM' THEN ST_Force3DM(g, 7)
					 ELSE ST_Force4D(g, 999, 7) END AS target
	FROM (SELECT kind, ST_Affine(ST_GeomFromText(w), 31.25, 0, 0, -31.25, 500015.625, 4000984.375) AS g
		  FROM (VALUES ('POINT', 'POINT(17 9)'),
					   ('MULTIPOINT', 'MULTIPOINT(0 0, 31 0, 0 31, 31 31, 5 6, 12 3, 22 17, 9 28, 16 16, 27 11)'),
					   ('LINESTRING', 'LINESTRING(1 1, 30 5, 3 12, 28 20, 10 30)'),
					   ('MULTILINESTRING', 'MULTILINESTRING((2 2, 2 29), (5 25, 25 5, 29 29))'),
					   ('POLYGON', 'POLYGON((3 3, 28 3, 28 28, 3 28, 3 3), (10 10, 10 20, 20 20, 20 10, 10 10))'),
					   ('MULTIPOLYGON', 'MULTIPOLYGON(((0 0, 8 0, 0 8, 0 0)), ((31 31, 20 31, 31 20, 31 31)))'),
					   ('GEOMETRYCOLLECTION', 'GEOMETRYCOLLECTION(POINT(15 15), LINESTRING(0 16, 31 16), '
											  'POLYGON((12 2, 18 2, 15 7, 12 2)))')) v(kind, w)) t,
		 (VALUES ('XY'), ('XYZ'), ('XYM'), ('XYZM')) d(dims);
CREATE TABLE tv_draped AS
	SELECT kind, dims, m, target,
		   CASE WHEN m LIKE '%breaklines%' THEN (SELECT ST_TDCDrape(geom, target, m ORDER BY ord) FROM tv_brk)
				ELSE (SELECT ST_TDCDrape(geom, target, m ORDER BY ord) FROM tv_pts) END AS d
	FROM tv_targets, (VALUES ('nearest'), ('linear'), ('natural_neighbor'), ('linear:breaklines=true')) v(m);
-- The same type and structure, Z added, M kept; nearest and natural
-- neighbour keep the vertices as they are.
SELECT m AS method, count(*) AS targets,
	   count(*) FILTER (WHERE ST_GeometryType(d) <> ST_GeometryType(target) OR ST_Zmflag(d) <> (ST_Zmflag(target) | 2)
							  OR ST_NumGeometries(d) <> ST_NumGeometries(target)) AS wrong_shape,
	   count(*) FILTER (WHERE m IN ('nearest', 'natural_neighbor')
							  AND ST_AsText(ST_Force2D(d)) <> ST_AsText(ST_Force2D(target))) AS moved
FROM tv_draped GROUP BY m ORDER BY m;
-- Every vertex's height: a vertex at a pixel centre against the reference
-- there; a vertex a linear drape added (a crossing of a triangle edge)
-- against the arbiter at that point, within 1e-6 m (the breakline drape's
-- crossings have no reference: CGAL's values are at the pixel centres).
CREATE TABLE tv_dv AS
	SELECT kind, dims, m, p.path, ST_X(p.geom) AS x, ST_Y(p.geom) AS y, ST_Z(p.geom) AS z, ST_M(p.geom) AS pm
	FROM tv_draped, ST_DumpPoints(d) p;
SELECT tdc_arb_queries(ST_Collect(ST_MakePoint(x, y) ORDER BY x, y)) > 0 AS crossings_queried
FROM (SELECT DISTINCT x, y FROM tv_dv v WHERE m = 'linear' AND NOT EXISTS (SELECT 1 FROM tv_q q WHERE q.x = v.x AND q.y = v.y)) c;
CREATE TABLE tv_cross AS
	SELECT q.fx AS x, q.fy AS y, l.circle, l.z AS lin FROM tdc_arb_q q JOIN tdc_arb_linear() l USING (qid);
SELECT v.m AS method, count(*) AS vertices, count(ref.qid) AS at_pixel_centres,
	   count(c.x) AS crossings_checked,
	   count(*) FILTER (WHERE CASE WHEN ref.qid IS NOT NULL THEN tv_wrong(v.m, v.z, ref)
								   WHEN c.x IS NOT NULL THEN NOT coalesce(c.circle >= 0 AND abs(tdc_arb_num(v.z) - c.lin) <= 1e-6, false)
								   ELSE v.m <> 'linear:breaklines=true' END) AS wrong_z,
	   count(*) FILTER (WHERE v.dims LIKE '%M' AND v.pm IS DISTINCT FROM 7) AS wrong_m
FROM tv_dv v LEFT JOIN tv_ref ref ON ref.x = v.x AND ref.y = v.y
	 LEFT JOIN tv_cross c ON v.m = 'linear' AND c.x = v.x AND c.y = v.y
GROUP BY v.m ORDER BY v.m;

-- ----------------------------------------------------------------------
-- Contours, levels 2.5 + 7k: the arbiter checks every triangle of our TIN
-- (its circumcircle, with no other sample on it, so it is in every
-- Delaunay triangulation); there are 2n - 2 - h of them, h = 4 (the
-- fixture's hull is its corners, every other sample strictly inside), so
-- they are the Delaunay triangulation.  Then every edge whose ends lie on
-- both sides of a level (a height equal to the level counts as above)
-- must have its crossing, at its exact position within 1e-6 m, among the
-- contour vertices, and every contour vertex must be such a crossing.
-- ----------------------------------------------------------------------
SELECT count(*) AS triangles, count(DISTINCT (a, b, c)) AS distinct_triangles,
	   count(*) FILTER (WHERE tdc_arb_circle(id) = 1) AS unique_delaunay,
	   2 * (SELECT count(*) FROM tdc_arb_s) - 2 - 4 AS two_n_minus_2_minus_h,
	   (SELECT count(*) FROM tdc_arb_s WHERE fx > 500000 AND fx < 501000 AND fy > 4000000 AND fy < 4001000) AS strictly_inside
FROM tdc_arb_t;
CREATE TABLE tv_cv AS
	SELECT DISTINCT ST_X(p.geom) AS x, ST_Y(p.geom) AS y, ST_Z(p.geom) AS lev, ST_MakePoint(ST_X(p.geom), ST_Y(p.geom)) AS g
	FROM (SELECT ST_TDCContours(geom, 7, 2.5 ORDER BY ord) AS c FROM tv_pts) s, ST_DumpPoints(c) p;
CREATE INDEX ON tv_cv USING gist (g);
CREATE TABLE tv_crossing AS
	WITH e AS (SELECT DISTINCT least(u, v) AS u, greatest(u, v) AS v
			   FROM tdc_arb_t, LATERAL (VALUES (a, b), (b, c), (c, a)) p(u, v)),
		 lo AS (SELECT CASE WHEN su.z < sv.z THEN su ELSE sv END AS l, CASE WHEN su.z < sv.z THEN sv ELSE su END AS h
				FROM e JOIN tdc_arb_s su ON su.ord = e.u JOIN tdc_arb_s sv ON sv.ord = e.v)
	SELECT DISTINCT lev, (l).x + tdc_arb_div((lev::numeric - (l).z) * ((h).x - (l).x), (h).z - (l).z) AS px,
		   (l).y + tdc_arb_div((lev::numeric - (l).z) * ((h).y - (l).y), (h).z - (l).z) AS py
	FROM lo, generate_series(floor(((l).z - 2.5) / 7)::int, ceil(((h).z - 2.5) / 7)::int) k, LATERAL (SELECT 2.5 + k * 7.0::float8 AS lev) v
	WHERE (l).z < lev::numeric AND (h).z >= lev::numeric;
SELECT (SELECT count(*) FROM tv_crossing) AS crossings, (SELECT count(*) FROM tv_cv) AS contour_vertices,
	   (SELECT count(*) FROM tv_crossing x
		WHERE (SELECT count(*) FROM tv_cv v WHERE v.g && ST_Expand(ST_MakePoint(x.px::float8, x.py::float8), 1e-6)
				 AND v.lev = x.lev AND abs(tdc_arb_num(v.x) - x.px) <= 1e-6 AND abs(tdc_arb_num(v.y) - x.py) <= 1e-6) = 1)
	   AS crossings_found_once;

-- ----------------------------------------------------------------------
-- A plane at the offset: linear and natural neighbour give it (to 1e-9 m)
-- at every pixel centre, as rasters and as a drape.
-- ----------------------------------------------------------------------
CREATE TABLE tv_plane AS SELECT ord, ST_MakePoint(x, y, 0.5 * (x - 500000) - 0.25 * (y - 4000000) + 100) AS geom FROM tv_s;
SELECT m AS method, count(*) AS pixels,
	   count(*) FILTER (WHERE NOT abs(v - (0.5 * (q.x - 500000) - 0.25 * (q.y - 4000000) + 100)) <= 1e-9) AS off_plane
FROM (VALUES ('linear'), ('natural_neighbor')) t(m), tv_tmpl,
	 (SELECT ST_Collect(geom ORDER BY ord) AS c FROM tv_plane) s,
	 unnest(ST_DumpValues(ST_TDCInterpolateRaster(s.c, m, r), 1)) WITH ORDINALITY u(v, qid) JOIN tv_q q USING (qid)
GROUP BY m ORDER BY m;
SELECT m AS method, count(*) AS vertices,
	   count(*) FILTER (WHERE NOT abs(ST_Z(p.geom) - (0.5 * (ST_X(p.geom) - 500000) - 0.25 * (ST_Y(p.geom) - 4000000) + 100)) <= 1e-9) AS off_plane
FROM (VALUES ('linear'), ('natural_neighbor')) t(m),
	 LATERAL (SELECT ST_TDCDrape(geom, (SELECT ST_Collect(ST_MakePoint(x, y)) FROM tv_q), m) AS d FROM tv_plane) s,
	 ST_DumpPoints(d) p
GROUP BY m ORDER BY m;

-- ----------------------------------------------------------------------
-- A lattice: 12 x 12 samples 10 m apart, then 20 of them again with other
-- heights (the first height counts); pixel centres every 5 m, so at the
-- samples, halfway between two (a tie of two) and at the squares' centres
-- (a tie of four; the rule: the sample first in (x, y) order).  Every
-- square is cocircular: either diagonal gives a Delaunay value.
-- ----------------------------------------------------------------------
CREATE TABLE tv_lat AS
	SELECT row_number() OVER (ORDER BY o, i, j) AS ord, ST_MakePoint(500000 + 10 * i, 4000000 + 10 * j, z) AS geom
	FROM (SELECT 0 AS o, i, j, (hashint4(i * 31 + j) % 1000) / 8.0 AS z
		  FROM generate_series(0, 11) i, generate_series(0, 11) j
		  UNION ALL SELECT 1, i, j, -1000 - i - j FROM generate_series(0, 11, 3) i, generate_series(0, 11, 2) j) s;
CREATE TABLE tv_lat_tmpl AS
	SELECT ST_AddBand(ST_MakeEmptyRaster(23, 23, 499997.5, 4000112.5, 5, -5, 0, 0, 0), '64BF'::text,
					  -9999::float8, -9999::float8) AS r;
SELECT tdc_arb_samples(ST_Collect(geom ORDER BY ord)) AS lattice_samples,
	   tdc_arb_triangles(ST_TDCDelaunayTriangles(ST_Collect(geom ORDER BY ord))) AS candidate_triangles
FROM tv_lat;
SELECT tdc_arb_queries(ST_Collect(ST_MakePoint(499997.5 + 5 * c + 2.5, 4000112.5 - 5 * r - 2.5) ORDER BY r, c)) AS pixel_centres
FROM generate_series(0, 22) r, generate_series(0, 22) c;
CREATE TABLE tv_lat_ref AS
	SELECT q.qid, q.fx AS x, q.fy AS y, n.z AS near, n.ties AS equally_near, l.tri, l.circle, l.z AS lin
	FROM tdc_arb_q q JOIN tdc_arb_nearest() n USING (qid) JOIN tdc_arb_linear() l USING (qid);
SELECT equally_near, count(*) AS pixel_centres, min(circle) AS least_circle FROM tv_lat_ref GROUP BY 1 ORDER BY 1;
CREATE TABLE tv_lat_out AS
	SELECT 'function' AS fn, m, v, qid
	FROM (VALUES ('nearest'), ('linear')) t(m), tv_lat_tmpl,
		 (SELECT ST_Collect(geom ORDER BY ord) AS c FROM tv_lat) s,
		 unnest(ST_DumpValues(ST_TDCInterpolateRaster(s.c, m, r), 1)) WITH ORDINALITY u(v, qid)
	UNION ALL
	SELECT 'aggregate', m, v, qid
	FROM (VALUES ('nearest'), ('linear')) t(m), tv_lat_tmpl,
		 unnest(ST_DumpValues((SELECT ST_TDCInterpolate(geom, r, m ORDER BY ord) FROM tv_lat), 1)) WITH ORDINALITY u(v, qid)
	UNION ALL
	SELECT 'drape', m, ST_Z(p.geom), p.path[1]
	FROM (VALUES ('nearest'), ('linear')) t(m),
		 LATERAL (SELECT ST_TDCDrape(geom, (SELECT ST_Collect(ST_MakePoint(fx, fy) ORDER BY qid) FROM tdc_arb_q), m ORDER BY ord) AS d
				  FROM tv_lat) s,
		 ST_DumpPoints(d) p;
SELECT fn, m AS method, count(*) AS values,
	   count(*) FILTER (WHERE NOT coalesce(CASE m WHEN 'nearest' THEN v = near
										   ELSE circle >= 0 AND abs(tdc_arb_num(v) - lin) <= 1e-9 END, false)) AS wrong,
	   count(*) FILTER (WHERE m = 'nearest' AND equally_near > 1 AND v = near) AS ties_right
FROM tv_lat_out JOIN tv_lat_ref USING (qid)
GROUP BY fn, m ORDER BY fn, m;

DROP FUNCTION tv_section(text), tv_wrong(text, float8, tv_ref, float8);
DROP TABLE tv_txt, tv_s, tv_q, tv_pts, tv_brk, tv_ref, tv_tmpl, tv_rast, tv_targets, tv_draped, tv_dv, tv_cross,
	tv_cv, tv_crossing, tv_plane, tv_lat, tv_lat_tmpl, tv_lat_ref, tv_lat_out;
\set arbiter :abs_srcdir '/sql/include/tin_arbiter_drop.sql'
\set ECHO none
\i :arbiter
\set ECHO all
-- The tests after this one run without the raster extensions, as before.
DROP EXTENSION tdc_delaunay_raster;
DROP EXTENSION postgis_raster;
