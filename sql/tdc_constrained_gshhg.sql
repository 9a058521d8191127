--
-- tdc_constrained_gshhg: the constrained triangulation of real polygons, the
-- GSHHG shoreline of the Stockholm archipelago, against SFCGAL's
-- constrained Delaunay triangulation.  (A file of its own: its big values
-- would change the memory state of tdc_constrained's session, whose cancel
-- test is timed.)
--
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis_sfcgal;
RESET client_min_messages;

-- SFCGAL's triangulation is tdc_sfcgal_cdt, under the name this PostGIS
-- gives it (from tdc_constrained, which runs first).

-- Triangles of a result as a set of normalized polygons (as in tdc_constrained).
CREATE OR REPLACE FUNCTION tdc_cdt_tris(g geometry) RETURNS SETOF text LANGUAGE sql AS $$
	SELECT ST_AsText(ST_Normalize(ST_MakePolygon(ST_ExteriorRing(
		CASE WHEN GeometryType(d.geom) = 'TRIANGLE'
			 THEN ST_GeomFromText(replace(ST_AsText(d.geom), 'TRIANGLE', 'POLYGON'))
			 ELSE d.geom END))))
	FROM ST_Dump(g) d $$;

-- Real polygons: the GSHHG shoreline of the Stockholm archipelago
-- (test/fixtures/gshhg-stockholm.wkt, one WKT geometry a line: 1,304
-- polygons and the mainland line, 17,548 vertices).  psql reads the file on
-- the client side (pg_regress gives the source directory in PG_ABS_SRCDIR),
-- so the server need not be able to read the clone.  Its coordinates lie on
-- a grid, so some sites are exactly cocircular, and there the constrained
-- triangulation is not unique: the triangles must be SFCGAL's but for
-- regions of ties, which both sides cover, each with its corners on one
-- circle (to 1e-9 of its radius; our own tie-break is exact).  Our
-- unconstrained triangulation must fail the same comparison.
\getenv abs_srcdir PG_ABS_SRCDIR
\set fixture :abs_srcdir '/test/fixtures/gshhg-stockholm.wkt'
\set wkt `cat :'fixture'`
CREATE TABLE tdc_gshhg AS
SELECT ST_GeomFromText(w) AS g FROM regexp_split_to_table(rtrim(:'wkt', E'\n'), E'\n') w;
\unset wkt
SELECT GeometryType(g) AS gshhg, count(*), sum(ST_NPoints(g)) AS vertices
FROM tdc_gshhg GROUP BY 1 ORDER BY 1;
-- Are the corners of polygon r on one circle (the circle through its first three)?
CREATE FUNCTION tdc_cocircular(r geometry) RETURNS boolean LANGUAGE sql AS $$
	WITH p AS (SELECT ST_X(d.geom) - ST_X(ST_PointN(ST_ExteriorRing(r), 1)) AS x,
					  ST_Y(d.geom) - ST_Y(ST_PointN(ST_ExteriorRing(r), 1)) AS y, d.path[2] AS i
			   FROM ST_DumpPoints(r) d),
		 a AS (SELECT x, y FROM p WHERE i = 2),
		 b AS (SELECT x, y FROM p WHERE i = 3),
		 c AS (SELECT (b.y * (a.x ^ 2 + a.y ^ 2) - a.y * (b.x ^ 2 + b.y ^ 2)) / (2 * (a.x * b.y - a.y * b.x)) AS cx,
					  (a.x * (b.x ^ 2 + b.y ^ 2) - b.x * (a.x ^ 2 + a.y ^ 2)) / (2 * (a.x * b.y - a.y * b.x)) AS cy
			   FROM a, b)
	SELECT bool_and(abs(sqrt((p.x - cx) ^ 2 + (p.y - cy) ^ 2) - sqrt(cx ^ 2 + cy ^ 2)) <= 1e-9 * sqrt(cx ^ 2 + cy ^ 2))
	FROM p, c $$;
-- The triangle sets of a and b: counts, and where they differ, whether the
-- two differences cover the same regions, each cocircular.
CREATE FUNCTION tdc_cdt_same_but_ties(a geometry, b geometry) RETURNS text LANGUAGE sql AS $$
	WITH ta AS (SELECT tdc_cdt_tris(a) t),
		 tb AS (SELECT tdc_cdt_tris(b) t),
		 only_a AS (SELECT t::geometry AS t FROM (SELECT t FROM ta EXCEPT SELECT t FROM tb) x),
		 only_b AS (SELECT t::geometry AS t FROM (SELECT t FROM tb EXCEPT SELECT t FROM ta) x),
		 regions AS (SELECT (ST_Dump(ST_Union(t))).geom AS r FROM only_a)
	SELECT format('%s triangles, %s; only first %s, only second %s, in %s regions; the same regions: %s; each cocircular: %s',
				  (SELECT count(*) FROM ta), (SELECT count(*) FROM tb),
				  (SELECT count(*) FROM only_a), (SELECT count(*) FROM only_b),
				  (SELECT count(*) FROM regions),
				  coalesce(ST_Equals((SELECT ST_Union(t) FROM only_a), (SELECT ST_Union(t) FROM only_b)), true),
				  coalesce((SELECT bool_and(tdc_cocircular(r)) FROM regions), true)) $$;
SELECT tdc_cdt_same_but_ties(ST_TDCConstrainedDelaunayTriangles(ST_Collect(g), 2),
							 tdc_sfcgal_cdt(ST_Collect(g))) AS gshhg_vs_sfcgal
FROM tdc_gshhg;
SELECT tdc_cdt_same_but_ties(ST_TDCDelaunayTriangles(ST_Collect(g), 0, 2),
							 tdc_sfcgal_cdt(ST_Collect(g))) AS gshhg_unconstrained_vs_sfcgal
FROM tdc_gshhg;

-- the aggregate over its rows: the same triangles as the function
SELECT tdc_cdt_same_but_ties((SELECT ST_TDCConstrainedDelaunay(g) FROM tdc_gshhg),
							 (SELECT ST_TDCConstrainedDelaunayTriangles(ST_Collect(g)) FROM tdc_gshhg)) AS gshhg_aggregate;
