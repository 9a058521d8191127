--
-- tdc_basic: install, helpers used by every later test, basic semantics.
--
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION tdc_delaunay;
RESET client_min_messages;

-- Every object of the extension has a comment.
SELECT count(*) AS objects_without_comment
FROM pg_depend d
JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay'
WHERE d.deptype = 'e' AND d.classid = 'pg_proc'::regclass
  AND obj_description(d.objid, 'pg_proc') IS NULL;

-- Volatility, strictness and parallel safety as declared.
SELECT p.oid::regprocedure AS function, p.provolatile, p.proisstrict, p.proparallel, p.prokind
FROM pg_proc p
JOIN pg_depend d ON d.objid = p.oid AND d.classid = 'pg_proc'::regclass AND d.deptype = 'e'
JOIN pg_extension e ON e.oid = d.refobjid AND e.extname = 'tdc_delaunay'
ORDER BY p.oid::regprocedure::text COLLATE "C";

-- Test helpers (superuser only, LANGUAGE internal): byteacat(x, '') returns x
-- unchanged, so these reinterpret a geometry's serialized bytes as bytea and
-- back, without going through WKB.
CREATE FUNCTION tdc_raw(geometry, bytea) RETURNS bytea
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';
CREATE FUNCTION tdc_mkgeom(bytea, bytea) RETURNS geometry
	LANGUAGE internal IMMUTABLE STRICT AS 'byteacat';

-- Triangles as a canonical text: the same set gives the same text.  A TIN
-- is first made a GEOMETRYCOLLECTION of its triangles as polygons, which is
-- what ST_Normalize does with one up to PostGIS 3.5 (3.7 keeps the TIN), so
-- the text is the same on every PostGIS.
CREATE FUNCTION tdc_norm(g geometry) RETURNS text
	LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT ST_AsText(ST_Normalize(CASE WHEN GeometryType(g) = 'TIN' THEN
		(SELECT coalesce(ST_ForceCollection(ST_Collect(ST_MakePolygon(ST_ExteriorRing(d.geom)))),
						 'GEOMETRYCOLLECTION EMPTY'::geometry)
		 FROM ST_Dump(g) d)
		ELSE g END)) $$;

-- Triangles of a result that are not counter-clockwise, not closed 4-point
-- rings, or not valid polygons.
CREATE FUNCTION tdc_bad_triangles(g geometry) RETURNS bigint
	LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT count(*) FROM (
		SELECT d.geom,
			ST_X(ST_PointN(r, 1)) ax, ST_Y(ST_PointN(r, 1)) ay,
			ST_X(ST_PointN(r, 2)) bx, ST_Y(ST_PointN(r, 2)) by,
			ST_X(ST_PointN(r, 3)) cx, ST_Y(ST_PointN(r, 3)) cy,
			ST_NPoints(r) np, ST_IsClosed(r) closed
		FROM ST_Dump(g) d, LATERAL ST_ExteriorRing(d.geom) r) t
	WHERE np <> 4 OR NOT closed OR NOT ST_IsValid(geom)
	   OR (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) <= 0 $$;

-- Exact triangle count of a Delaunay triangulation: 2n - 2 - h, n unique XY
-- sites, h sites on the convex hull boundary (collinear ones included).
CREATE FUNCTION tdc_expected_triangles(pts geometry) RETURNS bigint
	LANGUAGE sql IMMUTABLE STRICT AS $$
	WITH s AS (SELECT DISTINCT ST_X(geom) x, ST_Y(geom) y FROM ST_DumpPoints(pts)),
	     h AS MATERIALIZED (SELECT ST_Boundary(ST_ConvexHull(pts)) b)
	SELECT 2 * count(*) - 2 - count(*) FILTER (WHERE ST_Intersects(ST_SetSRID(ST_MakePoint(x, y), ST_SRID(pts)), b))
	FROM s, h $$;

-- Pairs (triangle, site) with the site strictly inside the circumcircle.
-- Exact in float8 for small integer coordinates.
CREATE FUNCTION tdc_delaunay_violations(tri geometry, pts geometry) RETURNS bigint
	LANGUAGE sql IMMUTABLE STRICT AS $$
	WITH t AS (
		SELECT ST_X(ST_PointN(r, 1)) ax, ST_Y(ST_PointN(r, 1)) ay,
			   ST_X(ST_PointN(r, 2)) bx, ST_Y(ST_PointN(r, 2)) by,
			   ST_X(ST_PointN(r, 3)) cx, ST_Y(ST_PointN(r, 3)) cy
		FROM ST_Dump(tri) d, LATERAL ST_ExteriorRing(d.geom) r),
	s AS (SELECT DISTINCT ST_X(geom) x, ST_Y(geom) y FROM ST_DumpPoints(pts))
	SELECT count(*) FROM t, s,
	LATERAL (SELECT ax - x adx, ay - y ady, bx - x bdx, by - y bdy, cx - x cdx, cy - y cdy) q
	WHERE (adx * adx + ady * ady) * (bdx * cdy - cdx * bdy)
		+ (bdx * bdx + bdy * bdy) * (cdx * ady - adx * cdy)
		+ (cdx * cdx + cdy * cdy) * (adx * bdy - bdx * ady) > 0 $$;

-- Deterministic pseudo-random points in [0, 1)^2: i -> (hash, hash).
CREATE FUNCTION tdc_random_points(n int, seed int DEFAULT 0) RETURNS TABLE(id int, geom geometry)
	LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT i, ST_MakePoint((hashint4(i + seed * 7919) & 2147483647)::float8 / 2147483648.0,
						   (hashint4(i + 1000000007 + seed) & 2147483647)::float8 / 2147483648.0)
	FROM generate_series(1, n) i $$;

-- The backend's threads once the one that unmaps a cancelled job's memory
-- (started while the error goes out) is done; a worker left running would
-- still be counted after 5 s (tdc_cancel, tdc_voronoi).
CREATE FUNCTION tdc_backend_threads() RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
	n int;
BEGIN
	LOOP
		n := substring(pg_read_file('/proc/' || pg_backend_pid() || '/status') FROM 'Threads:\s*(\d+)')::int;
		EXIT WHEN n = 1 OR clock_timestamp() > t0 + interval '5 s';
		PERFORM pg_sleep(0.005);
	END LOOP;
	RETURN n;
END $$;

--
-- Basic outputs for the three flags (normalized: start vertex and member
-- order are not part of the contract).
--
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)'));
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 0, 1));
-- (members through ST_Dump: PostGIS 3.7's ST_NumGeometries counts a TIN as one)
SELECT ST_AsText(t) LIKE 'TIN(((%' AS is_tin,
	   (SELECT count(*) FROM ST_Dump(t)) AS triangles,
	   (SELECT min(ST_GeometryType(geom)) FROM ST_Dump(t)) AS member
FROM (SELECT ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 0, 2) AS t) s;
SELECT tdc_bad_triangles(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)')) AS bad;

-- Triangles are counter-clockwise with a closed 4-point ring; TIN members too.
SELECT ST_IsPolygonCCW(d.geom) AS ccw, ST_NPoints(d.geom) AS npoints
FROM ST_Dump(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)')) d;
SELECT bool_and(ST_IsPolygonCCW(ST_MakePolygon(ST_ExteriorRing(d.geom)))) AS tin_ccw
FROM ST_Dump(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 0, 2)) d;

-- Defaults equal explicit 0, 0.
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)')) =
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 0.0, 0)) AS same;

--
-- The serialized result is read correctly by PostGIS: round trips.
--
WITH r AS (SELECT ST_TDCDelaunayTriangles('SRID=3857;MULTIPOINT Z(5 5 3, 6 0 2, 7 9 1, 8 9 4)') AS g)
SELECT ST_IsValid(g) AS valid, ST_SRID(g) AS srid, ST_NDims(g) AS ndims, ST_Zmflag(g) AS zm,
	   ST_GeometryType(g) AS type, ST_NumGeometries(g) AS n,
	   ST_AsEWKB(g) = ST_AsEWKB(ST_GeomFromEWKB(ST_AsEWKB(g))) AS ewkb_roundtrip,
	   ST_OrderingEquals(g, ST_GeomFromEWKT(ST_AsEWKT(g))) AS ewkt_roundtrip,
	   ST_Equals(g, ST_GeomFromWKB(ST_AsBinary(g), 3857)) AS wkb_equals,
	   g = ST_GeomFromEWKB(ST_AsEWKB(g)) AS eq_operator
FROM r;
-- Exact bytes of a result: header (SRID 4326, flags 0x44 = version 2 with a
-- box), the float box xmin, xmax, ymin, ymax (0, 1, 0, 1), GEOMETRYCOLLECTION
-- (7) of 1 POLYGON (3) of 1 ring of 4 points, padded.
SELECT substr(tdc_raw(ST_TDCDelaunayTriangles('SRID=4326;MULTIPOINT(0 0, 1 0, 0 1)'), ''), 1, 40) AS header;
-- The box is the one PostGIS writes for its own result: float bounds rounded
-- outward (1.1 and 1.3 are not floats), Z included; without it every
-- PostGIS function reading the result would first compute it from all
-- vertices.  Empty results have none, like PostGIS's.
SELECT postgis_hasbbox(t) AS has_box, postgis_getbbox(t)::text AS box,
	   postgis_getbbox(t) = postgis_getbbox(p) AS box_as_postgis,
	   ST_XMax(t) AS exact_xmax
FROM (SELECT ST_TDCDelaunayTriangles(g) AS t, ST_DelaunayTriangles(g) AS p
	  FROM (SELECT 'MULTIPOINT(-2.7 0, 1.1 0, 0 1.3, 0.5 -0.1)'::geometry AS g) s) r;
SELECT postgis_hasbbox(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1.1 0, 0 1.3)', 0, 1)) AS edges_box,
	   postgis_hasbbox(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1.1 0, 0 1.3)', 0, 2)) AS tin_box,
	   postgis_hasbbox(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1.1 0)')) AS empty_box;
-- Z range: over the Z that the result keeps (the first of each XY), so the
-- later duplicate's 100 is outside it; 3D box text is BOX3D.
SELECT substr(tdc_raw(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 -5, 1 0 7, 0 1 9, 0 0 100)'), ''), 5, 24) AS box_3d,
	   ST_ZMax(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 -5, 1 0 7, 0 1 9, 0 0 100)')) AS zmax;
-- With a tolerance the box is that of the kept sites: (10.01 10.01) is
-- absorbed by (10 10), so the box ends at 10.
SELECT postgis_getbbox(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 10 0, 0 10, 10 10, 10.01 10.01)', 0.1))::text AS tolerance_box,
	   postgis_getbbox(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 10 0, 0 10, 10 10, 10.01 10.01)'))::text AS no_tolerance_box;
SELECT length(tdc_raw(ST_TDCDelaunayTriangles('SRID=4326;MULTIPOINT(0 0, 1 0, 0 1)'), '')) AS bytes_2d,
	   length(tdc_raw(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 0, 1 0 0, 0 1 0)'), '')) AS bytes_3d;
SELECT tdc_raw(ST_TDCDelaunayTriangles('SRID=999999;POINT(1 1)'), '') AS empty_collection,
	   tdc_raw(ST_TDCDelaunayTriangles('POINT(1 1)', 0, 1), '') AS empty_multilinestring,
	   tdc_raw(ST_TDCDelaunayTriangles('POINT(1 1)', 0, 2), '') AS empty_tin;
-- Results serve as PostGIS input again, also to ourselves.
SELECT tdc_norm(ST_TDCDelaunayTriangles(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)'))) =
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)')) AS idempotent;

--
-- Input types: vertices of everything (rings incl. holes, nested collections,
-- TIN, polyhedral surfaces, triangles, bounding boxes in the input value).
--
-- (compared with PostGIS on the collected vertices: ST_DelaunayTriangles
-- itself rejects POLYHEDRALSURFACE)
SELECT t, tdc_norm(ST_TDCDelaunayTriangles(g::geometry)) =
		  tdc_norm(ST_DelaunayTriangles((SELECT ST_Collect(geom) FROM ST_DumpPoints(g::geometry)))) AS same_as_postgis,
	   ST_NumGeometries(ST_TDCDelaunayTriangles(g::geometry)) AS triangles
FROM (VALUES
	('point', 'POINT(1 2)'),
	('linestring', 'LINESTRING(0 0, 10 0, 10 10, 0 11)'),
	('polygon with hole', 'POLYGON((0 0, 10 0, 10 10, 0 10, 0 0), (2 2, 3 2, 3 4, 2 2))'),
	('multipolygon', 'MULTIPOLYGON(((0 0, 10 0, 10 10, 0 0)), ((20 0, 30 0, 30 5, 20 0)), EMPTY)'),
	('multilinestring', 'MULTILINESTRING((0 0, 1 5), (3 1, 7 2, 9 9))'),
	('nested collection', 'GEOMETRYCOLLECTION(POINT(0 0), GEOMETRYCOLLECTION(LINESTRING(4 0, 5 5), MULTIPOINT(1 7, 9 3)), POLYGON EMPTY)'),
	('triangle', 'TRIANGLE((0 0, 4 0, 1 3, 0 0))'),
	('tin', 'TIN(((0 0, 4 0, 1 3, 0 0)), ((4 0, 5 4, 1 3, 4 0)))'),
	('polyhedral surface', 'POLYHEDRALSURFACE Z(((0 0 0, 0 2 0, 3 2 1, 1 0 0, 0 0 0)), ((0 0 0, 1 0 0, 2 -3 2, 0 0 0)), ((3 3 3, 4 3 3, 4 5 3, 3 3 3)))')
) v(t, g);
-- The same inputs with a bounding box stored in the value (ST_Force3D adds
-- one; ST_Force2D keeps it): same triangles.
SELECT tdc_norm(ST_TDCDelaunayTriangles(ST_Force2D(ST_Force3D('POLYGON((0 0, 10 0, 10 10, 0 10, 0 0), (2 2, 3 2, 3 4, 2 2))')))) =
	   tdc_norm(ST_DelaunayTriangles('POLYGON((0 0, 10 0, 10 10, 0 10, 0 0), (2 2, 3 2, 3 4, 2 2))')) AS with_bbox;
SELECT get_byte(tdc_raw(ST_Force3D('POLYGON((0 0, 1 0, 0 1, 0 0))'), ''), 3) & 4 = 4 AS input_had_bbox;

--
-- Degenerate inputs.
--
SELECT g, tdc_norm(ST_TDCDelaunayTriangles(g::geometry)) AS polygons,
	   tdc_norm(ST_TDCDelaunayTriangles(g::geometry, 0, 1)) AS edges,
	   tdc_norm(ST_TDCDelaunayTriangles(g::geometry, 0, 2)) AS tin
FROM (VALUES
	('POINT EMPTY'), ('GEOMETRYCOLLECTION EMPTY'), ('POINT(1 2)'), ('MULTIPOINT(0 0, 1 1)'),
	('MULTIPOINT(0 0, 5 0, 10 0)'), ('MULTIPOINT(0 0, 0 0, 0 0)'), ('LINESTRING(0 0, 1 1, 2 2, 3 3, 1 1)')
) v(g);
-- Exact XY duplicates are removed.
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 0 0, 1 0, 0 1, 1 0)')) AS dups;
SELECT tdc_norm(ST_TDCDelaunayTriangles('SRID=4326;POINT EMPTY')) AS srid_on_empty, ST_SRID(ST_TDCDelaunayTriangles('SRID=4326;POINT EMPTY')) AS srid;
-- NULL in, NULL out.
SELECT ST_TDCDelaunayTriangles(NULL) IS NULL AS null_geom,
	   ST_TDCDelaunayTriangles('POINT(0 0)', NULL, 0) IS NULL AS null_tolerance,
	   ST_TDCDelaunayTriangles('POINT(0 0)', 0, NULL) IS NULL AS null_flags;

--
-- Z and M.
--
SELECT ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT Z(5 5 3, 6 0 2, 7 9 1)')) ~ '^GEOMETRYCOLLECTION Z \(POLYGON Z' AS z_kept,
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT Z(5 5 3, 6 0 2, 7 9 1)')) AS z_triangle;
-- The Z of the first input vertex with that XY survives.
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 1, 0 0 9, 1 0 0, 0 1 0)')) AS first_z;
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 9, 0 0 1, 1 0 0, 0 1 0)')) AS first_z_other_order;
-- M is dropped: XYM -> XY, XYZM -> XYZ.
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT M(0 0 5, 1 0 5, 0 1 5)')) AS m_dropped,
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT ZM(0 0 1 5, 1 0 2 5, 0 1 3 5)')) AS zm_to_z;
-- The same through the aggregate, one point per row (its own read path):
-- the results must equal the one-value ones above.
SELECT tdc_norm(ST_TDCDelaunay(g ORDER BY i)) AS agg_first_z
FROM (VALUES (1, 'POINT Z(0 0 1)'::geometry), (2, 'POINT Z(0 0 9)'), (3, 'POINT Z(1 0 0)'), (4, 'POINT Z(0 1 0)')) v(i, g);
SELECT tdc_norm(ST_TDCDelaunay(g)) AS agg_m_dropped
FROM (VALUES ('POINT M(0 0 5)'::geometry), ('POINT M(1 0 5)'), ('POINT M(0 1 5)')) v(g);
SELECT tdc_norm(ST_TDCDelaunay(g ORDER BY i)) AS agg_zm_to_z
FROM (VALUES (1, 'POINT ZM(0 0 1 5)'::geometry), (2, 'POINT ZM(1 0 2 5)'), (3, 'POINT ZM(0 1 3 5)')) v(i, g);
SELECT ST_SRID(ST_TDCDelaunay(g)) AS agg_srid, ST_NumGeometries(ST_TDCDelaunay(g)) AS agg_point_empty_skipped
FROM (VALUES ('SRID=3857;POINT(0 0)'::geometry), ('SRID=3857;POINT EMPTY'), ('SRID=3857;POINT(1 0)'), ('SRID=3857;POINT(0 1)')) v(g);
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 1, 1 0 2, 0 1 3)', 0, 1)) AS z_edges,
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 1, 1 0 2, 0 1 3)', 0, 2)) AS z_tin,
	   ST_AsText(ST_TDCDelaunayTriangles('MULTIPOINT Z(0 0 1, 1 1 2)')) AS z_empty;

--
-- SRID.
--
SELECT ST_SRID(ST_TDCDelaunayTriangles('SRID=4326;MULTIPOINT(0 0, 1 0, 0 1)')) AS f0,
	   ST_SRID(ST_TDCDelaunayTriangles('SRID=4326;MULTIPOINT(0 0, 1 0, 0 1)', 0, 1)) AS f1,
	   ST_SRID(ST_TDCDelaunayTriangles('SRID=4326;MULTIPOINT(0 0, 1 0, 0 1)', 0, 2)) AS f2,
	   ST_SRID(ST_TDCDelaunayTriangles('SRID=999999;MULTIPOINT(0 0, 1 0, 0 1)')) AS max_srid,
	   ST_SRID(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)')) AS no_srid;

--
-- Tolerance.
--
SELECT tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 2)) AS tol2,
	   tdc_norm(ST_TDCDelaunayTriangles('MULTIPOINT(5 5, 6 0, 7 9, 8 9)', 0.5)) AS tol_half;

--
-- Aggregates: same as ST_DelaunayTriangles(ST_Collect(...)).
--
CREATE TABLE tdc_pts AS SELECT id, geom FROM tdc_random_points(2000);
SELECT tdc_norm(ST_TDCDelaunay(geom)) = tdc_norm(ST_TDCDelaunayTriangles(ST_Collect(geom))) AS agg_eq_func,
	   tdc_norm(ST_TDCDelaunay(geom, 0, 1)) = tdc_norm(ST_TDCDelaunayTriangles(ST_Collect(geom), 0, 1)) AS agg_eq_func_edges,
	   tdc_norm(ST_TDCDelaunay(geom, 0, 2)) = tdc_norm(ST_TDCDelaunayTriangles(ST_Collect(geom), 0, 2)) AS agg_eq_func_tin,
	   ST_NumGeometries(ST_TDCDelaunay(geom)) = tdc_expected_triangles(ST_Collect(geom)) AS count_2n_2_h,
	   tdc_bad_triangles(ST_TDCDelaunay(geom)) AS bad,
	   ST_NumGeometries(ST_TDCDelaunay(geom, 0, 1)) = 3 * 2000 - 3 - (2 * 2000 - 2 - ST_NumGeometries(ST_TDCDelaunay(geom))) AS edges_3n_3_h
FROM tdc_pts;
-- Compared with PostGIS (no cocircular points here): every PostGIS triangle
-- is ours; GEOS 3.11 may miss a few along the convex hull (see
-- tdc_postgis_cases), never the other way round.
WITH a AS (SELECT ST_AsText((ST_Dump(ST_Normalize(ST_TDCDelaunay(geom)))).geom) t FROM tdc_pts),
	 b AS (SELECT ST_AsText((ST_Dump(ST_Normalize(ST_DelaunayTriangles(ST_Collect(geom))))).geom) t FROM tdc_pts)
SELECT (SELECT count(*) FROM b WHERE t NOT IN (SELECT t FROM a)) AS only_in_postgis,
	   (SELECT count(*) FROM a) >= (SELECT count(*) FROM b) AS ours_not_fewer;
-- Input order does not matter.
SELECT tdc_norm(ST_TDCDelaunay(geom ORDER BY id)) = tdc_norm(ST_TDCDelaunay(geom ORDER BY id DESC)) AS order_independent
FROM tdc_pts;
-- Mixed input types, NULLs and empties.
SELECT tdc_norm(ST_TDCDelaunay(g)) = tdc_norm(ST_DelaunayTriangles(ST_Collect(g))) AS mixed
FROM (VALUES ('POINT(0 0)'::geometry), (NULL), ('POINT EMPTY'), ('LINESTRING(5 0, 5 5, 9 9)'),
			 ('POLYGON((1 1, 2 1, 2 3, 1 1))'), ('MULTIPOINT(7 1, 0 9)'), (NULL)) v(g);
-- No rows or only NULLs: NULL.  Rows with NULL tolerance or flags are skipped.
SELECT ST_TDCDelaunay(geom) IS NULL AS no_rows FROM tdc_pts WHERE false;
SELECT ST_TDCDelaunay(NULL::geometry) IS NULL AS only_nulls FROM generate_series(1, 3);
SELECT ST_TDCDelaunay(geom, 0, 0) IS NULL AS no_rows3 FROM tdc_pts WHERE false;
SELECT ST_AsText(ST_TDCDelaunay(g, t, 0)) AS skipped_null_tolerance
FROM (VALUES ('MULTIPOINT(0 0, 1 0, 0 1)'::geometry, 0::float8), ('POINT(5 5)', NULL)) v(g, t);
-- Few or collinear points.
SELECT ST_AsText(ST_TDCDelaunay(g)) AS two_points, ST_AsText(ST_TDCDelaunay(g, 0, 1)) AS two_points_edges,
	   ST_AsText(ST_TDCDelaunay(g, 0, 2)) AS two_points_tin
FROM (VALUES ('POINT(0 0)'::geometry), ('POINT(1 1)')) v(g);
SELECT tdc_norm(ST_TDCDelaunay(g, 0, 1)) AS collinear_edges
FROM (VALUES ('POINT(0 0)'::geometry), ('POINT(2 0)'), ('POINT(1 0)'), ('POINT(3 0)')) v(g);
-- Z of the first row with that XY, in aggregation order; SRID kept.
SELECT tdc_norm(ST_TDCDelaunay(g ORDER BY k)) AS first_z_wins
FROM (VALUES (1, 'SRID=2056;POINT Z(0 0 1)'::geometry), (2, 'SRID=2056;POINT Z(0 0 9)'),
			 (3, 'SRID=2056;POINT Z(1 0 2)'), (4, 'SRID=2056;POINT Z(0 1 3)')) v(k, g);
SELECT tdc_norm(ST_TDCDelaunay(g ORDER BY k DESC)) AS first_z_wins_reversed
FROM (VALUES (1, 'SRID=2056;POINT Z(0 0 1)'::geometry), (2, 'SRID=2056;POINT Z(0 0 9)'),
			 (3, 'SRID=2056;POINT Z(1 0 2)'), (4, 'SRID=2056;POINT Z(0 1 3)')) v(k, g);
-- Aggregate as a window function (final function called repeatedly).
SELECT k, ST_NumGeometries(ST_TDCDelaunay(g) OVER (ORDER BY k)) AS triangles
FROM (VALUES (1, 'POINT(0 0)'::geometry), (2, 'POINT(4 0)'), (3, 'POINT(0 4)'), (4, 'POINT(4 4)'), (5, 'POINT(2 1)')) v(k, g)
ORDER BY k;
-- GROUP BY: one triangulation per group.
SELECT id % 3 AS grp, ST_NumGeometries(ST_TDCDelaunay(geom)) = tdc_expected_triangles(ST_Collect(geom)) AS ok
FROM tdc_pts GROUP BY 1 ORDER BY 1;

--
-- Larger inputs: a grid (many cocircular quadruples, collinear hull) and
-- random points; exact counts and the empty-circumcircle property.
--
WITH g AS (SELECT ST_Collect(ST_MakePoint(x, y)) AS pts FROM generate_series(0, 19) x, generate_series(0, 14) y)
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(pts)) AS grid_triangles,  -- 2*300 - 2 - 66
	   tdc_expected_triangles(pts) AS expected,
	   tdc_bad_triangles(ST_TDCDelaunayTriangles(pts)) AS bad,
	   tdc_delaunay_violations(ST_TDCDelaunayTriangles(pts), pts) AS violations,
	   ST_Area(ST_TDCDelaunayTriangles(pts)) AS area   -- 19 * 14
FROM g;
WITH g AS (SELECT ST_Collect(ST_MakePoint(round(ST_X(geom) * 1000), round(ST_Y(geom) * 1000))) AS pts FROM tdc_random_points(400, 7))
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(pts)) = tdc_expected_triangles(pts) AS count_ok,
	   tdc_bad_triangles(ST_TDCDelaunayTriangles(pts)) AS bad,
	   tdc_delaunay_violations(ST_TDCDelaunayTriangles(pts), pts) AS violations,
	   abs(ST_Area(ST_TDCDelaunayTriangles(pts)) - ST_Area(ST_ConvexHull(pts))) < 1e-6 AS covers_hull
FROM g;
