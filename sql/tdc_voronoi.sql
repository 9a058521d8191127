--
-- tdc_voronoi: ST_TDCVoronoiPolygons and ST_TDCVoronoiLines against PostGIS's
-- ST_VoronoiPolygons and ST_VoronoiLines on the same server.
--
-- tdc_vor_sites(g): the distinct vertices of g (2D), numbered in input order
-- of their first occurrence: the n-th is the site of our n-th cell.
CREATE FUNCTION tdc_vor_sites(g geometry) RETURNS TABLE(n bigint, p geometry)
LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT row_number() OVER (ORDER BY k), p
	FROM (SELECT DISTINCT ON (ST_X(p), ST_Y(p)) k, p
		  FROM (SELECT d.k, ST_Force2D(d.geom) AS p
				FROM ST_DumpPoints(g) WITH ORDINALITY d(path, geom, k)) s
		  ORDER BY ST_X(p), ST_Y(p), k) f $$;

-- tdc_vor_compare(g, tolerance, extend_to): for every distinct vertex of g,
-- in input order of its first occurrence, our k-th cell against the PostGIS
-- cell containing that vertex.  Reports the number of cells of each, how
-- many of ours are valid, contain their site and match a PostGIS cell with a
-- symmetric difference of at most 1e-9 of the cell's area, and whether the
-- total area equals the clip envelope's (PostGIS's union of cells).
CREATE FUNCTION tdc_vor_compare(g geometry, tol float8 DEFAULT 0, ext geometry DEFAULT NULL)
RETURNS TABLE(ours bigint, theirs bigint, valid bigint, contain bigint, match bigint,
			  area_ok boolean, dims int, srid int)
LANGUAGE plpgsql AS $$
DECLARE
	res geometry := ST_TDCVoronoiPolygons(g, tol, ext);
BEGIN
	CREATE TEMP TABLE vt_sites AS SELECT * FROM tdc_vor_sites(g);
	CREATE TEMP TABLE vt_ours AS
		SELECT (d).path[1] AS n, (d).geom AS c FROM ST_Dump(res) d;
	CREATE TEMP TABLE vt_theirs AS
		SELECT (d).geom AS c FROM ST_Dump(ST_VoronoiPolygons(g, tol, ext)) d;
	CREATE INDEX ON vt_theirs USING gist (c);
	ANALYZE vt_theirs;
	RETURN QUERY
	SELECT (SELECT count(*) FROM vt_ours),
		   (SELECT count(*) FROM vt_theirs),
		   count(*) FILTER (WHERE ST_IsValid(o.c)),
		   count(*) FILTER (WHERE ST_Covers(o.c, s.p)),
		   count(*) FILTER (WHERE ST_Area(ST_SymDifference(o.c, t.c)) <= 1e-9 * ST_Area(t.c)),
		   abs((SELECT sum(ST_Area(c)) FROM vt_ours) - ST_Area(ST_Envelope(ST_Collect(t.c))))
			   <= 1e-12 * ST_Area(ST_Envelope(ST_Collect(t.c))),
		   ST_NDims(res)::int, ST_SRID(res)
	FROM vt_sites s
	JOIN vt_ours o USING (n)
	LEFT JOIN LATERAL (SELECT c FROM vt_theirs WHERE ST_Intersects(vt_theirs.c, s.p)
					   ORDER BY ST_Distance(ST_Centroid(vt_theirs.c), s.p) LIMIT 1) t ON true;
	DROP TABLE vt_sites, vt_ours, vt_theirs;
END $$;

-- tdc_vor_check(g): our cells of the sites of g checked on their own, for
-- where PostGIS's are wrong.  Reports the number of cells, how many are
-- valid, convex, contain their site and have no vertex nearer to another
-- site than to their own (by more than 1e-9 of the squared distances),
-- whether no two cells overlap by more than 1e-12 of the envelope's area,
-- and whether the total area equals the envelope's (PostGIS's, as in
-- tdc_vor_compare).  Convex cells that tile the envelope, each inside the
-- region of points nearest its site, are the Voronoi diagram.
CREATE FUNCTION tdc_vor_check(g geometry)
RETURNS TABLE(cells bigint, valid bigint, convex bigint, contain bigint, nearest bigint,
			  no_overlap boolean, area_ok boolean)
LANGUAGE sql AS $$
	WITH s AS MATERIALIZED (SELECT n, p, ST_X(p) AS x, ST_Y(p) AS y FROM tdc_vor_sites(g)),
		 o AS MATERIALIZED (SELECT d.path[1] AS n, d.geom AS c FROM ST_Dump(ST_TDCVoronoiPolygons(g)) d),
		 env AS (SELECT ST_Area(ST_Envelope(ST_VoronoiPolygons(g))) AS area),
		 far AS (SELECT o.n, count(*) AS pairs
				 FROM o JOIN s ON s.n = o.n, ST_DumpPoints(o.c) v, s t,
					  LATERAL (SELECT (ST_X(v.geom) - s.x) ^ 2 + (ST_Y(v.geom) - s.y) ^ 2 AS own,
									  (ST_X(v.geom) - t.x) ^ 2 + (ST_Y(v.geom) - t.y) ^ 2 AS other) d
				 WHERE t.n <> o.n AND d.own - d.other > 1e-9 * (d.own + d.other)
				 GROUP BY o.n)
	SELECT count(*),
		   count(*) FILTER (WHERE ST_IsValid(o.c)),
		   count(*) FILTER (WHERE ST_Area(ST_ConvexHull(o.c)) - ST_Area(o.c) <= 1e-12 * ST_Area(o.c)),
		   count(*) FILTER (WHERE ST_Covers(o.c, s.p)),
		   count(*) FILTER (WHERE NOT EXISTS (SELECT FROM far WHERE far.n = o.n)),
		   NOT EXISTS (SELECT FROM o a JOIN o b ON a.n < b.n AND ST_Intersects(a.c, b.c)
					   WHERE ST_Area(ST_Intersection(a.c, b.c)) > 1e-12 * (SELECT area FROM env)),
		   abs(sum(ST_Area(o.c)) - (SELECT area FROM env)) <= 1e-12 * (SELECT area FROM env)
	FROM s JOIN o USING (n) $$;

-- uniform, clustered (deterministic pseudo-random points)
CREATE TABLE vor_uniform AS
	SELECT i AS id, ST_MakePoint((hashint4(i) & 2147483647) / 2147483647.0 * 1000,
								 (hashint4(-i) & 2147483647) / 2147483647.0 * 1000) AS geom
	FROM generate_series(1, 1500) i;
CREATE TABLE vor_clustered AS
	SELECT i AS id, ST_MakePoint((i % 7) * 100 + (hashint4(i) & 65535) / 65535.0 * (hashint4(3 * i) & 255) / 255.0,
								 (i % 5) * 100 + (hashint4(-i) & 65535) / 65535.0 * (hashint4(5 * i) & 255) / 255.0) AS geom
	FROM generate_series(1, 1500) i;

SELECT 'uniform' AS set, * FROM tdc_vor_compare((SELECT ST_Collect(geom ORDER BY id) FROM vor_uniform));
SELECT 'clustered' AS set, * FROM tdc_vor_compare((SELECT ST_Collect(geom ORDER BY id) FROM vor_clustered));
-- SRID and Z: the result keeps the SRID and is 2D
SELECT 'srid+z' AS set, * FROM tdc_vor_compare(
	(SELECT ST_SetSRID(ST_Collect(ST_MakePoint(ST_X(geom), ST_Y(geom), id) ORDER BY id), 32631)
	 FROM vor_uniform WHERE id <= 500));
-- coastline subset: the vertices of test/fixtures/gshhg-stockholm.wkt (17,548
-- vertices of real, clustered shoreline, 16,244 distinct; one WKT geometry
-- per line), read by psql on the client side: the server need not be able
-- to read the source tree.  pg_regress (PG 15+) exports PG_ABS_SRCDIR, the
-- input directory, which is the project's root.
\getenv abs_srcdir PG_ABS_SRCDIR
\set coast_file :abs_srcdir '/test/fixtures/gshhg-stockholm.wkt'
\set coast `cat :coast_file`
CREATE TABLE vor_coast AS
	SELECT row_number() OVER (ORDER BY l.k, d.path) AS id, d.geom
	FROM regexp_split_to_table(:'coast', E'\n') WITH ORDINALITY l(line, k),
		 ST_DumpPoints(ST_GeomFromText(l.line, 4326)) d
	WHERE l.line <> '';
\unset coast
SELECT count(*) AS vertices, count(DISTINCT (ST_X(geom), ST_Y(geom))) AS distinct_vertices
FROM vor_coast;
SELECT 'coastline' AS set, * FROM tdc_vor_compare((SELECT ST_Collect(geom ORDER BY id) FROM vor_coast));
-- the aggregate gives the same bytes
SELECT (SELECT ST_TDCVoronoi(geom ORDER BY id) FROM vor_coast)::bytea =
	   ST_TDCVoronoiPolygons((SELECT ST_Collect(geom ORDER BY id) FROM vor_coast))::bytea AS agg_same;
DROP TABLE vor_coast;
-- extend_to, larger and smaller than the default envelope
SELECT 'extend_to' AS set, * FROM tdc_vor_compare(
	(SELECT ST_Collect(geom ORDER BY id) FROM vor_uniform WHERE id <= 300), 0,
	'LINESTRING(-5000 -200, 9000 1200)');
-- an extend_to whose box is not made of floats: PostGIS rounds it outward
-- to floats, as it stores boxes, and so do we (a point too); the exact
-- box would move the cells along three sides by some 1e-7
SELECT 'extend_to floats' AS set, * FROM tdc_vor_compare(
	(SELECT ST_Collect(geom ORDER BY id) FROM vor_uniform WHERE id <= 300), 0,
	'LINESTRING(-5000.3 -200.7, 9000.1 1200.9)');
SELECT 'extend_to point' AS set, * FROM tdc_vor_compare('MULTIPOINT(1 1, 2 2)', 0, 'POINT(-10.3 -5.7)');
SELECT ST_AsText(ST_TDCVoronoiPolygons('MULTIPOINT(1 1, 2 2)', 0, 'POINT(-10.3 -5.7)')) AS float_box;
SELECT 'extend_to inside' AS set, * FROM tdc_vor_compare(
	(SELECT ST_Collect(geom ORDER BY id) FROM vor_uniform WHERE id <= 300), 0,
	'POINT(500 500)');
-- duplicates: one cell per distinct vertex, in order of first occurrence
SELECT 'duplicates' AS set, * FROM tdc_vor_compare(
	(SELECT ST_Collect(geom ORDER BY k, id) FROM vor_uniform, generate_series(1, 3) k WHERE id <= 200));
-- the vertices of lines and polygons: the 28 sites of a stroked circle,
-- cocircular but for rounding.  GEOS 3.15 gets their diagram wrong: its
-- cells overlap, their areas adding up to some 40,000 in an envelope of
-- 3,600.  So ours are checked on their own (tdc_vor_check), and against
-- GEOS's only where those tile the envelope (GEOS 3.11 and 3.13 do).
CREATE TABLE vor_polygon AS SELECT ST_Buffer(ST_MakePoint(0, 0), 10, 7) AS g;
SELECT 'polygon' AS set, c.* FROM vor_polygon, tdc_vor_check(g) c;
SELECT 'polygon' AS set, c.ours, c.valid, c.contain, c.area_ok, c.dims, c.srid,
	   (c.theirs = c.ours AND c.match = c.ours) OR NOT t.tiles AS same_as_postgis_where_it_tiles
FROM vor_polygon, tdc_vor_compare(g) c,
	 LATERAL (SELECT abs(sum(ST_Area(d.geom)) - ST_Area(ST_Envelope(ST_Collect(d.geom))))
					 <= 1e-12 * ST_Area(ST_Envelope(ST_Collect(d.geom))) AS tiles
			  FROM ST_Dump(ST_VoronoiPolygons(g)) d) t;
DROP TABLE vor_polygon;
-- curves: their stored vertices (control points) are the sites, as GEOS
-- gets them from PostGIS; the aggregate and the Dump read them the same way
SELECT 'curves' AS set, * FROM tdc_vor_compare(
	'GEOMETRYCOLLECTION(CIRCULARSTRING(0 0, 1 1, 2 0), POINT(1 5), CURVEPOLYGON(COMPOUNDCURVE(CIRCULARSTRING(3 0, 5 2, 7 0), (7 0, 3 0))), MULTICURVE((9 9, 8 6), CIRCULARSTRING(4 7, 5 8, 6 7)))');
SELECT ST_AsText(ST_TDCVoronoiLines('CIRCULARSTRING(0 0, 1 1, 2 0)')) AS ours,
	   ST_AsText(ST_VoronoiLines('CIRCULARSTRING(0 0, 1 1, 2 0)')) AS postgis;
SELECT md5(ST_AsBinary(ST_TDCVoronoi(g))) = md5(ST_AsBinary(ST_TDCVoronoiPolygons(ST_Collect(g)))) AS aggregate,
	   (SELECT count(*) FROM ST_TDCVoronoiDump($$SELECT 1::bigint, 'CIRCULARSTRING(0 0, 1 1, 2 0)'::geometry$$)) AS dump_rows
FROM (VALUES ('CIRCULARSTRING(0 0, 1 1, 2 0)'::geometry), ('POINT(1 5)')) v(g);

-- The examples of the PostGIS documentation of ST_VoronoiPolygons / ST_VoronoiLines.
SELECT ST_AsText(ST_TDCVoronoiPolygons('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)'));
SELECT 'docs' AS set, * FROM tdc_vor_compare('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)');
SELECT ST_AsText(ST_TDCVoronoiLines('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)'));
SELECT ST_NumGeometries(ST_TDCVoronoiLines(g)) = ST_NumGeometries(ST_VoronoiLines(g)) AS same_count,
	   ST_HausdorffDistance(ST_TDCVoronoiLines(g), ST_VoronoiLines(g)) < 1e-9 AS same_lines
FROM (VALUES ('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)'::geometry),
			 ('MULTIPOINT (0 0, 2 0, 5 0)'), ('MULTIPOINT (0 0, 2 0)')) v(g);
-- Tolerance: ours merges vertices closer than it (the rule of
-- ST_TDCDelaunayTriangles): (60 30) joins (50 30) and (110 120) joins
-- (100 100).  GEOS snaps while inserting, which here gives the same 3 sites
-- (but not always: see the last two rows, where GEOS keeps 4 sites).
SELECT count(*) AS cells,
	   count(*) FILTER (WHERE EXISTS (SELECT FROM ST_Dump(ST_VoronoiPolygons(g, 30)) t
									 WHERE ST_Area(ST_SymDifference(o.geom, t.geom)) <= 1e-9 * ST_Area(t.geom))) AS match
FROM (VALUES ('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)'::geometry)) v(g),
	 ST_Dump(ST_TDCVoronoiPolygons(g, 30)) o;
SELECT ST_NumGeometries(ST_TDCVoronoiPolygons(g, t)) AS ours,
	   ST_NumGeometries(ST_VoronoiPolygons(g, t)) AS postgis
FROM (VALUES ('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)'::geometry, 30),
			 ('MULTIPOINT (0 0, 2 0, 0 1, 0.1 0)', 0.5)) v(g, t);
SELECT ST_AsText(ST_TDCVoronoiLines('MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)', 30));
-- extend_to from the PostGIS docs' use: the envelope grows to include it
SELECT 'docs extend_to' AS set, * FROM tdc_vor_compare(
	'MULTIPOINT (50 30, 60 30, 100 100,10 150, 110 120)', 0, ST_MakeEnvelope(-500, -500, 500, 500));

-- Collinear sites: slabs, as PostGIS gives them
SELECT ST_AsText(ST_TDCVoronoiPolygons('MULTIPOINT(0 0,2 0,5 0)'));
SELECT 'collinear' AS set, * FROM tdc_vor_compare('MULTIPOINT(0 0,2 0,5 0, 9 0, 9.5 0)');
SELECT 'collinear diagonal' AS set, * FROM tdc_vor_compare('MULTIPOINT(0 0,1 1,3 3,4 4)');
-- a lattice (cocircular sites): valid cells, areas add up
SELECT count(*) AS cells, bool_and(ST_IsValid(c)) AS valid, sum(ST_Area(c)) AS area
FROM ST_Dump(ST_TDCVoronoiPolygons(
	(SELECT ST_Collect(ST_MakePoint(x, y)) FROM generate_series(0, 9) x, generate_series(0, 9) y))) d(p, c);

-- Fewer than 2 sites, EMPTY, NULL: as PostGIS
SELECT ST_AsEWKT(ST_TDCVoronoiPolygons('SRID=4326;POINT(1 1)')) AS one,
	   ST_AsEWKT(ST_VoronoiPolygons('SRID=4326;POINT(1 1)')) AS postgis_one;
SELECT ST_AsEWKT(ST_TDCVoronoiPolygons('MULTIPOINT(1 1, 1 1)')) AS dup,
	   ST_AsEWKT(ST_TDCVoronoiLines('MULTIPOINT(1 1, 1 1)')) AS dup_lines,
	   ST_AsEWKT(ST_TDCVoronoiPolygons('POINT EMPTY')) AS empty;
SELECT ST_TDCVoronoiPolygons(NULL) IS NULL AS null_in,
	   ST_TDCVoronoiLines(NULL, 0, 'POINT(1 1)') IS NULL AS null_lines,
	   ST_NumGeometries(ST_TDCVoronoiPolygons('MULTIPOINT(0 0, 1 1)', 0, NULL)) AS null_extend_to;
-- extend_to's SRID is ignored, as in PostGIS
SELECT ST_SRID(ST_TDCVoronoiPolygons('SRID=4326;MULTIPOINT(0 0, 1 1)', 0, 'SRID=3857;POINT(5 5)')) AS srid;

-- Errors
SELECT ST_TDCVoronoiPolygons('MULTIPOINT(0 0, 1 1)', -1);
SELECT ST_TDCVoronoiPolygons('MULTIPOINT(0 0, 1 1)', NULL);
SELECT ST_TDCVoronoiPolygons('MULTIPOINT(0 0, 1 1)', 'NaN');
SELECT ST_TDCVoronoiLines('MULTIPOINT(0 0, 1 1)', 0, 'POINT EMPTY');
-- extend_to with arcs: PostGIS takes the box of the arcs themselves, which
-- is not the box of their vertices (sites with arcs are fine, see above)
SELECT ST_TDCVoronoiPolygons('MULTIPOINT(1 1, 2 2)', 0, 'CIRCULARSTRING(0 0, 5 5, 10 0)');

-- Cancel: a statement_timeout stops a big diagram, the session stays usable
-- and no engine thread is left behind.
SET tdc_delaunay.threads = 1;
CREATE TABLE vor_big AS
	SELECT ST_Collect(ST_MakePoint((hashint4(i) & 2147483647)::float8, (hashint4(-i) & 2147483647)::float8)) AS g
	FROM generate_series(1, 1000000) i;
-- (Terse: under load the timeout may come while the value is still read,
-- which adds a CONTEXT line.)
\set VERBOSITY terse
SET statement_timeout = '300ms';
SELECT ST_NumGeometries(ST_TDCVoronoiPolygons(g)) FROM vor_big;
RESET statement_timeout;
\set VERBOSITY default
-- no thread left behind (tdc_backend_threads: tdc_basic.sql)
SELECT tdc_backend_threads() AS threads;
RESET tdc_delaunay.threads;
SELECT ST_NumGeometries(ST_TDCVoronoiPolygons('MULTIPOINT(0 0, 1 1, 2 0)')) AS after_cancel;
DROP TABLE vor_big;
