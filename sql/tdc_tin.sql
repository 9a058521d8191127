--
-- tdc_tin: TIN analysis, the ST_TDCContours and ST_TDCDrape aggregates.
--
-- Contours: lines at base + k * interval, each vertex's Z its level, merged
-- (closed rings around hills, open lines ending on the hull), a level at a
-- sample's height counted once; per level the total length equals an
-- independent per-triangle computation (tdc_level_length below, in SQL over
-- the TIN's triangles).  Drape: the target with Z at every vertex, lines
-- split at every triangle edge they cross, on a plane exactly the plane.
-- Then errors, NULLs, EMPTY, SRID, and the parallel aggregates.

-- The length of the level set of "lev" in each triangle of a TIN, summed:
-- a height equal to the level counts as above it, as ST_TDCContours has it.
CREATE FUNCTION tdc_level_length(tin geometry, lev float8) RETURNS float8
	LANGUAGE plpgsql IMMUTABLE STRICT AS $$
DECLARE
	t		geometry;
	x		float8[];
	y		float8[];
	z		float8[];
	px		float8[];
	py		float8[];
	a		int;
	b		int;
	u		float8;
	total	float8 := 0;
BEGIN
	FOR t IN SELECT (ST_Dump(tin)).geom LOOP
		x := ARRAY[]::float8[]; y := x; z := x; px := x; py := x;
		FOR i IN 1..3 LOOP
			x := x || ST_X(ST_PointN(ST_ExteriorRing(t), i));
			y := y || ST_Y(ST_PointN(ST_ExteriorRing(t), i));
			z := z || ST_Z(ST_PointN(ST_ExteriorRing(t), i));
		END LOOP;
		FOR i IN 1..3 LOOP
			a := i;
			b := i % 3 + 1;
			IF (z[a] >= lev) <> (z[b] >= lev) THEN
				IF z[a] >= lev THEN a := b; b := i; END IF;	-- a below, b above
				u := (lev - z[a]) / (z[b] - z[a]);
				px := px || (x[a] + u * (x[b] - x[a]));
				py := py || (y[a] + u * (y[b] - y[a]));
			END IF;
		END LOOP;
		IF cardinality(px) = 2 THEN
			total := total + sqrt((px[2] - px[1]) ^ 2 + (py[2] - py[1]) ^ 2);
		END IF;
	END LOOP;
	RETURN total;
END $$;

-- Each level of a contour result against the per-triangle sum: the worst
-- relative difference, and the number of levels.
CREATE FUNCTION tdc_contour_check(contours geometry, tin geometry,
								  OUT levels bigint, OUT worst float8) LANGUAGE sql AS $$
	SELECT count(*), max(abs(len - tdc_level_length(tin, lev)) / greatest(len, 1e-300))
	FROM (SELECT ST_Z(ST_StartPoint(d.geom)) AS lev, sum(ST_Length(d.geom)) AS len
		  FROM ST_Dump(contours) d GROUP BY 1) l $$;

-- Terrain: 2,000 random samples with heights.
CREATE TABLE tdc_tin_terrain AS
	SELECT id, ST_SetSRID(ST_MakePoint(ST_X(geom) * 1000, ST_Y(geom) * 1000,
						  50 * sin(ST_X(geom) * 12) * cos(ST_Y(geom) * 8) + 30 * ST_Y(geom)), 2056) AS geom
	FROM tdc_random_points(2000, 3);

-- SRID, Z at every vertex equal to its line's level, levels base + k * interval.
CREATE TABLE tdc_tin_contours AS SELECT ST_TDCContours(geom, 10) AS c, ST_TDCContours(geom, 7, 2.5) AS c2,
	ST_TDCDelaunay(geom, 0, 2) AS tin FROM tdc_tin_terrain;
SELECT GeometryType(c), ST_SRID(c), ST_NDims(c), ST_NumGeometries(c) > 10 AS many_lines FROM tdc_tin_contours;
SELECT count(*) FILTER (WHERE ST_Z(p.geom) <> ST_Z(ST_StartPoint(d.geom))) AS z_not_level,
	   count(DISTINCT ST_Z(p.geom)) FILTER (WHERE ST_Z(p.geom) / 10 <> round(ST_Z(p.geom) / 10)) AS off_level
FROM tdc_tin_contours, ST_Dump(c) d, ST_DumpPoints(d.geom) p;
SELECT array_agg(DISTINCT ST_Z(ST_StartPoint(d.geom)) ORDER BY ST_Z(ST_StartPoint(d.geom))) AS levels
FROM tdc_tin_contours, ST_Dump(c2) d;
-- merged: closed lines are rings; open lines end on the hull
SELECT count(*) FILTER (WHERE ST_IsClosed(d.geom)) > 0 AS some_rings,
	   count(*) FILTER (WHERE NOT ST_IsClosed(d.geom) AND
						(ST_Distance(ST_StartPoint(d.geom), ST_Boundary(ST_ConvexHull(tin))) > 1e-6 OR
						 ST_Distance(ST_EndPoint(d.geom), ST_Boundary(ST_ConvexHull(tin))) > 1e-6)) AS open_inside,
	   count(*) FILTER (WHERE ST_IsClosed(d.geom) AND ST_NPoints(d.geom) < 4) AS short_rings
FROM tdc_tin_contours, ST_Dump(c) d;
-- the length of every level equals the per-triangle sum
SELECT levels > 10 AS many_levels, worst < 1e-9 AS lengths_match
FROM tdc_tin_contours, tdc_contour_check(c, tin);
SELECT levels > 10 AS many_levels, worst < 1e-9 AS lengths_match
FROM tdc_tin_contours, tdc_contour_check(c2, tin);

-- A hill: one closed, counter-clockwise ring per level.
CREATE TABLE tdc_tin_hill AS
	SELECT ST_MakePoint(x, y, 100 * exp(-(x * x + y * y) / 500.0)) AS geom
	FROM generate_series(-50, 50, 5) x, generate_series(-50, 50, 5) y;
SELECT ST_NumGeometries(c) AS lines,
	   count(*) FILTER (WHERE ST_IsClosed(d.geom)) AS closed,
	   count(*) FILTER (WHERE ST_IsPolygonCCW(ST_MakePolygon(ST_Force2D(d.geom)))) AS counter_clockwise,
	   count(DISTINCT ST_Z(ST_StartPoint(d.geom))) AS levels
FROM (SELECT ST_TDCContours(geom, 10) AS c FROM tdc_tin_hill) h, ST_Dump(c) d GROUP BY c;

-- Levels through the samples' heights: integer heights on a lattice, levels
-- at the integers; every level once (no piece twice, none missing).
CREATE TABLE tdc_tin_steps AS
	SELECT ST_MakePoint(x, y, (hashint4(x * 100 + y) & 3)::float8) AS geom
	FROM generate_series(0, 20) x, generate_series(0, 20) y;
SELECT levels, worst < 1e-12 AS lengths_match
FROM (SELECT ST_TDCContours(geom, 1) AS c, ST_TDCDelaunay(geom, 0, 2) AS tin FROM tdc_tin_steps) s,
	 tdc_contour_check(c, tin);
-- z = x on a lattice: each level at a column of samples is the column, once
SELECT ST_AsText(ST_TDCContours(ST_MakePoint(x, y, x), 1))
FROM generate_series(0, 3) x, generate_series(0, 2) y;

-- Drape.  On a plane every vertex of the draped line is on the plane, and
-- a line crossing the TIN gets a vertex at every edge it crosses.
CREATE TABLE tdc_tin_plane AS
	SELECT ST_SetSRID(ST_MakePoint(x * 1000, y * 1000, 2 * x * 1000 - 3 * y * 1000 + 7), 2056) AS geom
	FROM (SELECT ST_X(geom) AS x, ST_Y(geom) AS y FROM tdc_random_points(500, 5)) p
	UNION ALL SELECT ST_SetSRID(ST_MakePoint(x, y, 2 * x - 3 * y + 7), 2056)
	FROM (VALUES (0, 0), (1000, 0), (0, 1000), (1000, 1000)) c(x, y);
CREATE TABLE tdc_tin_draped AS
	SELECT ST_TDCDrape(geom, 'SRID=2056;LINESTRING(10 10, 990 980, 500 20)') AS line,
		   ST_TDCDrape(geom, 'SRID=2056;LINESTRING(10 10, 990 980, 500 20)', 'natural_neighbor') AS nn,
		   ST_TDCDrape(geom, 'SRID=2056;POLYGON((100 100, 900 100, 900 900, 100 100))') AS poly,
		   ST_TDCDrape(geom, 'SRID=2056;MULTIPOINT(5 5, 500 500)', 'nearest') AS mp
	FROM tdc_tin_plane;
SELECT GeometryType(line), ST_SRID(line), ST_NDims(line), ST_NPoints(line) > 100 AS split,
	   ST_HausdorffDistance(line, 'SRID=2056;LINESTRING(10 10, 990 980, 500 20)') < 1e-9 AS same_line,
	   ST_NPoints(nn) AS nn_points
FROM tdc_tin_draped;
SELECT max(abs(ST_Z(p.geom) - (2 * ST_X(p.geom) - 3 * ST_Y(p.geom) + 7))) < 1e-9 AS on_plane
FROM tdc_tin_draped, ST_DumpPoints(line) p;
SELECT max(abs(ST_Z(p.geom) - (2 * ST_X(p.geom) - 3 * ST_Y(p.geom) + 7))) < 1e-9 AS nn_on_plane
FROM tdc_tin_draped, ST_DumpPoints(nn) p;
SELECT GeometryType(poly), ST_IsValid(poly), ST_IsClosed(ST_ExteriorRing(poly)),
	   ST_HausdorffDistance(poly, 'SRID=2056;POLYGON((100 100, 900 100, 900 900, 100 100))') < 1e-9 AS same_area,
	   ST_NPoints(poly) > 4 AS split
FROM tdc_tin_draped;
SELECT ST_AsText(mp) AS points, ST_NDims(mp) FROM tdc_tin_draped;
-- nearest drape (issue 36): every vertex had Z = 0, which the line above
-- let through while it checked only the shape; each vertex takes its nearest
-- sample's height
SELECT ST_AsText(ST_TDCDrape(geom, 'MULTIPOINT(0.2 0.2, 0.6 0.1)', 'nearest')) AS nearest_drape
FROM (VALUES ('POINT Z (0 0 1)'::geometry), ('POINT Z (1 0 2)'), ('POINT Z (0 1 3)')) v(geom);
SELECT ST_AsText(ST_TDCDrape(geom, 'LINESTRING M (0.1 0.8 5, 0.9 0.05 6)', 'nearest')) AS nearest_line
FROM (VALUES ('POINT Z (0 0 1)'::geometry), ('POINT Z (1 0 2)'), ('POINT Z (0 1 3)')) v(geom);
-- the edge crossings: as many as the TIN's edges the segment crosses
SELECT (SELECT ST_NPoints(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(10 10, 990 980)')) - 2 FROM tdc_tin_plane) =
	   (SELECT count(*) FROM (SELECT ST_TDCDelaunay(geom, 0, 1) AS e FROM tdc_tin_plane) t, ST_Dump(e) d
		WHERE ST_Crosses(d.geom, 'SRID=2056;LINESTRING(10 10, 990 980)')) AS one_vertex_per_crossing;
-- a point, a target with M (M interpolated on the new vertices), a TIN
-- target (heights at its corners only), a collection, EMPTY
SELECT ST_AsText(ST_TDCDrape(geom, 'SRID=2056;POINT(500 500)')) FROM tdc_tin_plane;
SELECT ST_NDims(d), ST_M(ST_StartPoint(d)), ST_M(ST_EndPoint(d)),
	   bool_and(ST_M(p.geom) BETWEEN 0 AND 10) AS m_between, ST_NPoints(d) > 10 AS split
FROM (SELECT ST_TDCDrape(geom, 'SRID=2056;LINESTRING M (10 10 0, 990 990 10)') AS d FROM tdc_tin_plane) s,
	 ST_DumpPoints(d) p GROUP BY d;
SELECT ST_NPoints(d) = 8 AS corners_only, GeometryType(d), ST_NDims(d)
FROM (SELECT ST_TDCDrape(geom, 'SRID=2056;TIN(((10 10, 900 10, 10 900, 10 10)), ((900 10, 900 900, 10 900, 900 10)))') AS d
	  FROM tdc_tin_plane) s;
SELECT ST_AsText(ST_TDCDrape(geom, 'SRID=2056;GEOMETRYCOLLECTION(POINT(1 1), LINESTRING EMPTY, POINT(2 2))')),
	   ST_AsText(ST_TDCDrape(geom, 'SRID=2056;LINESTRING EMPTY'))
FROM tdc_tin_plane;
-- Their heights as well (these checks once looked at the shape alone): the
-- polygon's, the M line's and the TIN's vertices lie on the plane, and the
-- nearest drape's vertices have the nearest samples' heights (ordered by
-- distance, then x, then y: the documented tie rule).
SELECT k, count(*) AS vertices, max(abs(ST_Z(p.geom) - (2 * ST_X(p.geom) - 3 * ST_Y(p.geom) + 7))) < 1e-9 AS on_plane
FROM (SELECT 'polygon' AS k, poly AS d FROM tdc_tin_draped
	  UNION ALL SELECT 'line M', ST_TDCDrape(geom, 'SRID=2056;LINESTRING M (10 10 0, 990 990 10)') FROM tdc_tin_plane
	  UNION ALL SELECT 'TIN', ST_TDCDrape(geom, 'SRID=2056;TIN(((10 10, 900 10, 10 900, 10 10)), ((900 10, 900 900, 10 900, 900 10)))')
	  FROM tdc_tin_plane) s, ST_DumpPoints(d) p
GROUP BY k ORDER BY k;
SELECT count(*) AS vertices,
	   bool_and(ST_Z(p.geom) = (SELECT ST_Z(s.geom) FROM tdc_tin_plane s
								ORDER BY ST_Distance(s.geom, p.geom), ST_X(s.geom), ST_Y(s.geom) LIMIT 1)) AS nearest_heights
FROM tdc_tin_draped, ST_DumpPoints(mp) p;

-- NULLs and EMPTY: skipped rows; no row gives NULL
SELECT ST_TDCContours(geom, 10) IS NULL AS no_rows FROM tdc_tin_terrain WHERE false;
SELECT ST_TDCContours(NULL::geometry, 10) IS NULL AS null_rows;
SELECT ST_TDCContours(geom, NULL) IS NULL AS null_interval FROM tdc_tin_terrain;
SELECT ST_AsText(ST_TDCContours(g, 1)) AS empty_samples FROM (VALUES ('POINT EMPTY'::geometry), ('POINT Z EMPTY')) v(g);
SELECT ST_AsText(ST_TDCContours(g, 1)) AS collinear FROM (VALUES ('POINT Z (0 0 0)'::geometry), ('POINT Z (1 1 5)'), ('POINT Z (2 2 9)')) v(g);
SELECT ST_TDCDrape(geom, NULL::geometry) IS NULL AS null_target FROM tdc_tin_plane;
-- a target that is not a constant (a column) is compared row by row: the same result
CREATE TABLE tdc_tin_target AS SELECT 'SRID=2056;LINESTRING(10 10, 990 980)'::geometry AS g;
SELECT ST_AsBinary(ST_TDCDrape(p.geom, t.g)) = (SELECT ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(10 10, 990 980)'))
												FROM tdc_tin_plane) AS column_target_same
FROM tdc_tin_plane p, tdc_tin_target t;
-- a target from a subquery is an executor parameter, read once per
-- aggregation; a correlated one changes with the outer row, and each outer
-- row's aggregate must drape its own target
SELECT ST_AsBinary(ST_TDCDrape(geom, (SELECT g FROM tdc_tin_target))) =
	   (SELECT ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(10 10, 990 980)')) FROM tdc_tin_plane)
	   AS subquery_target_same
FROM tdc_tin_plane;
SELECT v.k, ST_X(s.d), ST_Y(s.d), abs(ST_Z(s.d) - (2 * ST_X(s.d) - 3 * ST_Y(s.d) + 7)) < 1e-9 AS on_plane
FROM (VALUES (1, 'SRID=2056;POINT(100 200)'::geometry), (2, 'SRID=2056;POINT(300 100)')) v(k, g),
	 LATERAL (SELECT ST_TDCDrape(p.geom, v.g) AS d FROM tdc_tin_plane p) s
ORDER BY v.k;
SELECT v.k, ST_AsText(ST_Force2D((SELECT ST_TDCDrape(p.geom, v.g) FROM tdc_tin_plane p))) AS correlated
FROM (VALUES (1, 'SRID=2056;POINT(100 200)'::geometry), (2, 'SRID=2056;POINT(300 100)')) v(k, g)
ORDER BY v.k;

-- Errors
\set VERBOSITY default
SELECT ST_TDCContours(g, 1) FROM (VALUES ('POINT Z (0 0 1)'::geometry), ('POINT(1 2)')) v(g);
SELECT ST_TDCContours(geom, 0) FROM tdc_tin_terrain;
SELECT ST_TDCContours(geom, 'NaN') FROM tdc_tin_terrain;
SELECT ST_TDCContours(geom, 1, 'Infinity') FROM tdc_tin_terrain;
SELECT ST_TDCContours(geom, 1e-12) FROM tdc_tin_terrain;
SELECT ST_TDCContours(geom, id) FROM tdc_tin_terrain;
SELECT ST_TDCContours(g, 1) FROM (VALUES ('SRID=4326;POINT Z (0 0 1)'::geometry), ('SRID=2056;POINT Z (1 2 3)')) v(g);
SELECT ST_TDCDrape(geom, 'SRID=2056;LINESTRING(500 500, 2000 500)') FROM tdc_tin_plane;
SELECT ST_TDCDrape(geom, 'LINESTRING(500 500, 600 500)') FROM tdc_tin_plane;
SELECT ST_TDCDrape(geom, 'SRID=2056;POINT(500 500)', 'cubic') FROM tdc_tin_plane;
SELECT ST_TDCDrape(geom, 'SRID=2056;POINT(500 500)', 'linear:radius=10') FROM tdc_tin_plane;
SELECT ST_TDCDrape(geom, 'SRID=2056;CIRCULARSTRING(100 100, 200 200, 300 100)') FROM tdc_tin_plane;
SELECT ST_TDCDrape(geom, ST_SetSRID(ST_MakePoint(100 + (ST_X(geom) > 500)::int, 100), 2056)) FROM tdc_tin_plane;
SELECT ST_TDCDrape(g, 'POINT(0 0)') FROM (VALUES ('POINT(1 2)'::geometry)) v(g);

-- Parallel aggregation gives the serial result: every partial state goes
-- through the serial, deserial and combine functions (tdc_parallel's set-up,
-- and its check that workers ran and sent states: a plan that only says
-- "Workers Planned" proves nothing).
CREATE FUNCTION tdc_tin_par_run(dest text, query text,
								OUT workers_launched int, OUT worker_states bigint)
	LANGUAGE plpgsql AS $$
DECLARE
	plan		jsonb;
BEGIN
	EXECUTE format('EXPLAIN (ANALYZE, VERBOSE, COSTS OFF, TIMING OFF, SUMMARY OFF, FORMAT JSON) CREATE TABLE %I AS %s',
				   dest, query) INTO plan;
	SELECT coalesce(sum((n ->> 'Workers Launched')::int), 0) INTO workers_launched
	FROM jsonb_path_query(plan, 'strict $.** ? (exists (@."Workers Launched"))') n;
	SELECT count(*) FILTER (WHERE (w ->> 'Actual Rows')::numeric > 0) INTO worker_states
	FROM jsonb_path_query(plan, 'strict $.** ? (@."Node Type" == "Seq Scan")."Workers"[*]') w;
END $$;
CREATE TABLE tdc_tin_par AS SELECT id, geom FROM tdc_tin_terrain;
INSERT INTO tdc_tin_par SELECT id + 2000, ST_Translate(geom, 0.5, 0.25) FROM tdc_tin_terrain;
ANALYZE tdc_tin_par;
SET max_parallel_workers_per_gather = 0;
CREATE TABLE tdc_tin_serial AS SELECT ST_AsBinary(ST_TDCContours(geom, 10)) AS c,
	ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(100 100, 900 800)', 'natural_neighbor')) AS d
	FROM tdc_tin_par;
ALTER FUNCTION st_tdccontours_serialfn(internal) COST 1;
ALTER FUNCTION st_tdccontours_deserialfn(bytea, internal) COST 1;
ALTER FUNCTION st_tdcdrape_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcdrape_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
EXPLAIN (COSTS OFF) SELECT ST_TDCContours(geom, 10) FROM tdc_tin_par;
SELECT workers_launched > 0 AS workers_ran, worker_states > 0 AS states_crossed
FROM tdc_tin_par_run('tdc_tin_parallel', $q$SELECT ST_AsBinary(ST_TDCContours(geom, 10)) AS c,
	ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(100 100, 900 800)', 'natural_neighbor')) AS d
	FROM tdc_tin_par$q$);
SELECT s.c = p.c AS contours_same, s.d = p.d AS drape_same FROM tdc_tin_serial s, tdc_tin_parallel p;
RESET parallel_leader_participation;
RESET max_parallel_workers_per_gather;
RESET min_parallel_table_scan_size;
RESET parallel_tuple_cost;
RESET parallel_setup_cost;
ALTER FUNCTION st_tdccontours_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdccontours_deserialfn(bytea, internal) COST 10000000;
ALTER FUNCTION st_tdcdrape_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcdrape_deserialfn(bytea, internal) COST 10000000;

-- The same contours for any thread count.
SET tdc_delaunay.threads = 1;
CREATE TABLE tdc_tin_t1 AS SELECT ST_AsBinary(ST_TDCContours(geom, 10)) AS c FROM tdc_tin_par;
RESET tdc_delaunay.threads;
SELECT t.c = s.c AS one_thread_same FROM tdc_tin_t1 t, tdc_tin_serial s;

-- Breaklines ('linear:breaklines=true'): the samples' linestrings and
-- polygon rings as hard breaklines.  A ridge L(0 1)-R(4 1) at 10 between
-- P(2 0) at 0 and Q(2 2) at 4: Q lies in the circle through L, P and R, so
-- the Delaunay TIN takes the diagonal P-Q across the ridge and the ridge
-- sags (8 at x = 0.5, 2 where it crosses P-Q); with the breakline it stays
-- at 10, and beside it the constrained triangle L, P, R (z = 10y) gives 5
-- at (2 0.5), where P-Q gives 1.
CREATE TABLE tdc_tin_ridge (id int, geom geometry);
INSERT INTO tdc_tin_ridge VALUES (1, 'LINESTRING Z (0 1 10, 4 1 10)'), (2, 'POINT Z (2 0 0)'), (3, 'POINT Z (2 2 4)');
SELECT ST_AsText(ST_TDCDrape(geom, 'LINESTRING(0.5 1, 3.5 1)')) AS plain,
	   ST_AsText(ST_TDCDrape(geom, 'LINESTRING(0.5 1, 3.5 1)', 'linear:breaklines=true')) AS breaklines,
	   ST_AsText(ST_TDCDrape(geom, 'LINESTRING(0.5 1, 3.5 1)', 'Linear:BreakLines=FALSE')) AS off
FROM tdc_tin_ridge;
SELECT ST_AsText(ST_TDCDrape(geom, 'POINT(2 0.5)')) AS plain,
	   ST_AsText(ST_TDCDrape(geom, 'POINT(2 0.5)', 'linear:breaklines=true')) AS breaklines
FROM tdc_tin_ridge;
-- a polygon ring is a breakline too; nearest and natural neighbour refuse
-- the option (natural neighbour coordinates need the Delaunay TIN; the
-- nearest sample does not depend on lines), as do GDAL's options here
SELECT ST_AsText(ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true'))
FROM (VALUES ('POLYGON Z ((0 1 10, 2 0 0, 4 1 10, 0 1 10))'::geometry), ('POINT Z (2 2 4)')) v(geom);
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'natural_neighbor:breaklines=true') FROM tdc_tin_ridge;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'nearest:breaklines=true') FROM tdc_tin_ridge;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=maybe') FROM tdc_tin_ridge;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true:radius=0') FROM tdc_tin_ridge;
-- crossing breaklines are an error naming both (node them first), as in
-- ST_TDCConstrainedDelaunay; curves are refused, as there
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true')
FROM (SELECT geom FROM tdc_tin_ridge UNION ALL SELECT 'LINESTRING Z (1 0.5 0, 1 1.5 0)') s;
SELECT ST_TDCDrape(geom, 'POINT(2 1)', 'linear:breaklines=true')
FROM (SELECT geom FROM tdc_tin_ridge UNION ALL SELECT 'CIRCULARSTRING Z (0 0 1, 1 -1 1, 2 0 1)') s;

-- Breaklines in a parallel plan: the segments travel with the vertices in
-- the state (version 2); the same draped line as serially, and not the
-- same as without the breaklines.
CREATE TABLE tdc_tin_brk AS SELECT id, geom FROM tdc_tin_terrain
	UNION ALL SELECT 5000 + k, ST_SetSRID(ST_MakeLine(ARRAY(
		SELECT ST_MakePoint(x, 100 * k + 37.5, 100 + k) FROM generate_series(20, 980, 40) x)), 2056)
	FROM generate_series(1, 9) k;
ANALYZE tdc_tin_brk;
SET max_parallel_workers_per_gather = 0;
CREATE TABLE tdc_tin_brk_serial AS
	SELECT ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(100 100, 900 800)', 'linear:breaklines=true')) AS d,
		   ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(100 100, 900 800)')) AS plain
	FROM tdc_tin_brk;
ALTER FUNCTION st_tdcdrape_serialfn(internal) COST 1;
ALTER FUNCTION st_tdcdrape_deserialfn(bytea, internal) COST 1;
SET parallel_setup_cost = 0;
SET parallel_tuple_cost = 0;
SET min_parallel_table_scan_size = 0;
SET max_parallel_workers_per_gather = 2;
SET parallel_leader_participation = off;
SELECT workers_launched > 0 AS workers_ran, worker_states > 0 AS states_crossed
FROM tdc_tin_par_run('tdc_tin_brk_parallel', $q$SELECT
	ST_AsBinary(ST_TDCDrape(geom, 'SRID=2056;LINESTRING(100 100, 900 800)', 'linear:breaklines=true')) AS d
	FROM tdc_tin_brk$q$);
SELECT s.d = p.d AS breaklines_same, s.d <> s.plain AS breaklines_differ
FROM tdc_tin_brk_serial s, tdc_tin_brk_parallel p;
RESET parallel_leader_participation;
RESET max_parallel_workers_per_gather;
RESET min_parallel_table_scan_size;
RESET parallel_tuple_cost;
RESET parallel_setup_cost;
ALTER FUNCTION st_tdcdrape_serialfn(internal) COST 10000000;
ALTER FUNCTION st_tdcdrape_deserialfn(bytea, internal) COST 10000000;
-- the draped line on a breakline's own vertical: at every crossing of the
-- line y = 137.5 the height is the breakline's, 101
SELECT bool_and(abs(ST_Z(p.geom) - 101) < 1e-9) AS on_breakline, count(*) > 0 AS crossings
FROM (SELECT ST_TDCDrape(geom, 'SRID=2056;LINESTRING(520 50, 520 950)', 'linear:breaklines=true') AS d
	  FROM tdc_tin_brk) s, ST_DumpPoints(d) p
WHERE ST_Y(p.geom) = 137.5;
DROP TABLE tdc_tin_ridge, tdc_tin_brk, tdc_tin_brk_serial, tdc_tin_brk_parallel;

DROP TABLE tdc_tin_t1, tdc_tin_parallel, tdc_tin_serial, tdc_tin_par, tdc_tin_target, tdc_tin_draped, tdc_tin_plane,
	tdc_tin_steps, tdc_tin_hill, tdc_tin_contours, tdc_tin_terrain;
DROP FUNCTION tdc_tin_par_run(text, text);
DROP FUNCTION tdc_contour_check(geometry, geometry);
DROP FUNCTION tdc_level_length(geometry, float8);
