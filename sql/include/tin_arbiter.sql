--
-- sql/include/tin_arbiter.sql: the exact arbiter of the TIN value tests,
-- included (\i) by tdc_tin_values, tdc_tin_jacksboro and
-- tdc_raster_arbiter.  Not a test itself: the Makefile's REGRESS list takes
-- sql/*.sql only.
--
-- What a height computed from samples must be, decided in rational
-- arithmetic (numeric: + - * are exact, and rationals are compared by
-- cross-multiplying, never by dividing), independently of the code it
-- judges:
--
--   nearest   the sample at the least squared distance, found by brute
--             force over every sample; ties go to the sample first in
--             (x, y) order, and of samples with equal x and y the first
--             one (in the order given) counts, as README documents;
--   linear    the value of the plane of a triangle that holds the point
--             exactly (orientation signs, boundary included) and whose
--             circumcircle holds no sample strictly inside it (exact
--             in-circle signs against every sample that could lie in it).
--             Such a triangle belongs to a Delaunay triangulation, so its
--             value is a Delaunay value, however the triangulation split
--             cocircular samples; when no other sample lies on the circle
--             either, every Delaunay triangulation has that triangle and
--             the value is the only one.  The candidate triangles may come
--             from anywhere (the tests load ours): a candidate is only
--             used once the arbiter has checked it.
--
-- Inputs are float8; tdc_arb_num converts one to the numeric of exactly its
-- binary value (a float8::numeric cast keeps 15 significant digits).  A
-- linear value is returned as the rational's quotient truncated at 40
-- decimals, for comparison with a float8 within a stated tolerance.
--
-- The samples live in tdc_arb_s, the candidate triangles in tdc_arb_t and
-- the query points in tdc_arb_q, filled by tdc_arb_samples,
-- tdc_arb_triangles and tdc_arb_queries (each call replaces what was
-- there); tdc_arb_nearest() and tdc_arb_linear() give the references at
-- every query (both VOLATILE: a stable SQL function returning a set would
-- be inlined into the caller's query, and a nested loop there would
-- compute it again for every outer row).  A test drops the tables and the
-- functions at its end with sql/include/tin_arbiter_drop.sql.

-- The exact value of a float8 as numeric: its 64 bits read as sign,
-- exponent and 53-bit mantissa m, the value m * 2^e written as
-- m * 5^-e * 10^e when e < 0 (a finite decimal).
CREATE FUNCTION tdc_arb_num_bits(f float8) RETURNS numeric LANGUAGE plpgsql IMMUTABLE STRICT AS $$
DECLARE
	bits	bigint := ('x' || encode(float8send(f), 'hex'))::bit(64)::bigint;
	e		int := ((bits >> 52) & 2047)::int;
	m		numeric := bits & 4503599627370495;
BEGIN
	IF e = 2047 THEN
		RAISE EXCEPTION 'tdc_arb_num: % is not finite', f;
	END IF;
	IF e = 0 THEN
		e := 1;						-- subnormal
	ELSE
		m := m + 4503599627370496;	-- the implicit bit
	END IF;
	e := e - 1075;
	IF e >= 0 THEN
		m := m * 2::numeric ^ e;
	ELSE
		m := m * 5::numeric ^ (-e) * ('1e' || e)::numeric;
	END IF;
	RETURN trim_scale(CASE WHEN bits < 0 THEN -m ELSE m END);
END $$;

-- The same, quicker for the tests' data: a multiple of 2^-10 below 2^40 in
-- magnitude is f * 1024 (an integer, exact in float8 and bigint) times
-- 2^-10 = 0.0009765625, exactly.  (Not STRICT, so that it is inlined: a
-- NULL reaches tdc_arb_num_bits, which is.)
CREATE FUNCTION tdc_arb_num(f float8) RETURNS numeric LANGUAGE sql IMMUTABLE AS $$
	SELECT CASE WHEN abs(f) < 1099511627776 AND f * 1024 = trunc(f * 1024)
				THEN (f * 1024)::bigint * 0.0009765625 ELSE tdc_arb_num_bits(f) END $$;

-- Twice the signed area of (a, b, c): > 0 counter-clockwise.
CREATE FUNCTION tdc_arb_orient(ax numeric, ay numeric, bx numeric, b_y numeric, cx numeric, cy numeric)
	RETURNS numeric LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT (bx - ax) * (cy - ay) - (b_y - ay) * (cx - ax) $$;

-- > 0 when d lies strictly inside the circle through the counter-clockwise
-- a, b, c; 0 on it.
CREATE FUNCTION tdc_arb_incircle(ax numeric, ay numeric, bx numeric, b_y numeric, cx numeric, cy numeric,
								 dx numeric, dy numeric)
	RETURNS int LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT sign(((ax - dx) * (ax - dx) + (ay - dy) * (ay - dy)) * ((bx - dx) * (cy - dy) - (cx - dx) * (b_y - dy))
			  - ((bx - dx) * (bx - dx) + (b_y - dy) * (b_y - dy)) * ((ax - dx) * (cy - dy) - (cx - dx) * (ay - dy))
			  + ((cx - dx) * (cx - dx) + (cy - dy) * (cy - dy)) * ((ax - dx) * (b_y - dy) - (bx - dx) * (ay - dy)))::int $$;

-- n / d truncated at 40 decimals (integer division is exact): a quotient
-- used only against a tolerance, or to widen a search box.
CREATE FUNCTION tdc_arb_div(n numeric, d numeric) RETURNS numeric LANGUAGE sql IMMUTABLE STRICT AS $$
	SELECT div(n * 1e40, d) * 1e-40 $$;

CREATE TABLE tdc_arb_s (ord bigint PRIMARY KEY, x numeric, y numeric, z numeric, fx float8, fy float8, fz float8,
						g geometry);
CREATE TABLE tdc_arb_t (id bigint PRIMARY KEY, a bigint, b bigint, c bigint, g geometry);
CREATE TABLE tdc_arb_q (qid bigint PRIMARY KEY, x numeric, y numeric, fx float8, fy float8, g geometry);
CREATE INDEX tdc_arb_s_g ON tdc_arb_s USING gist (g);
CREATE INDEX tdc_arb_s_xy ON tdc_arb_s (fx, fy);
CREATE INDEX tdc_arb_t_g ON tdc_arb_t USING gist (g);
CREATE INDEX tdc_arb_q_g ON tdc_arb_q USING gist (g);

-- The samples: every vertex of coll (points, lines' and rings' vertices),
-- in the order ST_DumpPoints gives, Z required; of equal x and y the first
-- is kept.  Returns the number of distinct samples.
CREATE FUNCTION tdc_arb_samples(coll geometry) RETURNS bigint LANGUAGE plpgsql AS $$
DECLARE
	n		bigint;
BEGIN
	TRUNCATE tdc_arb_s, tdc_arb_t;
	DROP INDEX tdc_arb_s_g, tdc_arb_s_xy;		-- built again once the rows are in: quicker
	INSERT INTO tdc_arb_s
	SELECT DISTINCT ON (fx, fy) ord, tdc_arb_num(fx), tdc_arb_num(fy), tdc_arb_num(fz), fx, fy, fz,
		   ST_MakePoint(fx, fy)
	FROM (SELECT p.ord, ST_X(p.geom) AS fx, ST_Y(p.geom) AS fy, ST_Z(p.geom) AS fz
		  FROM ST_DumpPoints(coll) WITH ORDINALITY p(path, geom, ord)) d
	ORDER BY fx, fy, ord;
	GET DIAGNOSTICS n = ROW_COUNT;
	IF EXISTS (SELECT 1 FROM tdc_arb_s WHERE fz IS NULL) THEN
		RAISE EXCEPTION 'tdc_arb_samples: a sample without Z';
	END IF;
	CREATE INDEX tdc_arb_s_g ON tdc_arb_s USING gist (g);
	CREATE INDEX tdc_arb_s_xy ON tdc_arb_s (fx, fy);
	ANALYZE tdc_arb_s;
	RETURN n;
END $$;

-- The queries: every vertex of g, numbered from 1 in ST_DumpPoints's order
-- (a vertex may come twice).  Returns their number.
CREATE FUNCTION tdc_arb_queries(g geometry) RETURNS bigint LANGUAGE plpgsql AS $$
DECLARE
	n		bigint;
BEGIN
	TRUNCATE tdc_arb_q;
	DROP INDEX tdc_arb_q_g;
	INSERT INTO tdc_arb_q
	SELECT p.ord, tdc_arb_num(ST_X(p.geom)), tdc_arb_num(ST_Y(p.geom)), ST_X(p.geom), ST_Y(p.geom),
		   ST_MakePoint(ST_X(p.geom), ST_Y(p.geom))
	FROM ST_DumpPoints(g) WITH ORDINALITY p(path, geom, ord);
	GET DIAGNOSTICS n = ROW_COUNT;
	CREATE INDEX tdc_arb_q_g ON tdc_arb_q USING gist (g);
	ANALYZE tdc_arb_q;
	RETURN n;
END $$;

-- Candidate triangles: the polygons (or triangles) of tin, each of whose
-- corners must be a sample, stored counter-clockwise; a degenerate one is
-- an error.  With near_queries, only those whose bounding box holds a
-- query (load the queries first): a big TIN queried at a few points.
-- Returns the number of triangles.
CREATE FUNCTION tdc_arb_triangles(tin geometry, near_queries bool DEFAULT false) RETURNS bigint
	LANGUAGE plpgsql AS $$
DECLARE
	n		bigint;
BEGIN
	TRUNCATE tdc_arb_t;
	DROP INDEX tdc_arb_t_g;
	INSERT INTO tdc_arb_t
	SELECT t.id, sa.ord, CASE WHEN o > 0 THEN sb.ord ELSE sc.ord END, CASE WHEN o > 0 THEN sc.ord ELSE sb.ord END,
		   t.g
	FROM (SELECT d.path[1] AS id, d.geom AS g, ST_PointN(ST_ExteriorRing(d.geom), 1) AS pa,
				 ST_PointN(ST_ExteriorRing(d.geom), 2) AS pb, ST_PointN(ST_ExteriorRing(d.geom), 3) AS pc
		  FROM ST_Dump(tin) d
		  WHERE NOT near_queries OR EXISTS (SELECT 1 FROM tdc_arb_q q WHERE q.g && d.geom)) t
		 LEFT JOIN tdc_arb_s sa ON sa.fx = ST_X(t.pa) AND sa.fy = ST_Y(t.pa)
		 LEFT JOIN tdc_arb_s sb ON sb.fx = ST_X(t.pb) AND sb.fy = ST_Y(t.pb)
		 LEFT JOIN tdc_arb_s sc ON sc.fx = ST_X(t.pc) AND sc.fy = ST_Y(t.pc),
		 LATERAL tdc_arb_orient(sa.x, sa.y, sb.x, sb.y, sc.x, sc.y) o;
	GET DIAGNOSTICS n = ROW_COUNT;
	IF EXISTS (SELECT 1 FROM tdc_arb_t WHERE a IS NULL OR b IS NULL OR c IS NULL) THEN
		RAISE EXCEPTION 'tdc_arb_triangles: a corner that is no sample';
	END IF;
	IF EXISTS (SELECT 1 FROM tdc_arb_t t, tdc_arb_s sa, tdc_arb_s sb, tdc_arb_s sc
			   WHERE sa.ord = t.a AND sb.ord = t.b AND sc.ord = t.c
				 AND tdc_arb_orient(sa.x, sa.y, sb.x, sb.y, sc.x, sc.y) = 0) THEN
		RAISE EXCEPTION 'tdc_arb_triangles: a degenerate triangle';
	END IF;
	CREATE INDEX tdc_arb_t_g ON tdc_arb_t USING gist (g);
	ANALYZE tdc_arb_t;
	RETURN n;
END $$;

-- A candidate triangle holding (qx, qy) exactly, boundary included (the one
-- with the least id); NULL when none does.  The bounding boxes only narrow
-- the candidates (PostGIS rounds them outwards; the margin is for the
-- point's own conversion to float8).
CREATE FUNCTION tdc_arb_locate(qx numeric, qy numeric) RETURNS bigint LANGUAGE sql STABLE AS $$
	SELECT t.id
	FROM tdc_arb_t t, tdc_arb_s sa, tdc_arb_s sb, tdc_arb_s sc
	WHERE t.g && ST_Expand(ST_MakePoint(qx::float8, qy::float8), 1e-9 * (1 + abs(qx::float8) + abs(qy::float8)))
	  AND sa.ord = t.a AND sb.ord = t.b AND sc.ord = t.c
	  AND tdc_arb_orient(sa.x, sa.y, sb.x, sb.y, qx, qy) >= 0
	  AND tdc_arb_orient(sb.x, sb.y, sc.x, sc.y, qx, qy) >= 0
	  AND tdc_arb_orient(sc.x, sc.y, sa.x, sa.y, qx, qy) >= 0
	ORDER BY t.id LIMIT 1 $$;

-- The circumcircle of triangle tri against every sample that could lie in
-- it: 1 no other sample inside or on it, 0 some on it but none inside
-- (cocircular samples: a Delaunay triangle, not the only choice), -1 a
-- sample strictly inside (not Delaunay).  The samples are first narrowed to
-- the circle's bounding box, from the centre and radius truncated at 40
-- decimals and widened by a margin far beyond that rounding; the decision
-- itself is the exact in-circle sign.
CREATE FUNCTION tdc_arb_circle(tri bigint) RETURNS int LANGUAGE sql STABLE AS $$
	WITH t AS (SELECT sa.x AS ax, sa.y AS ay, sb.x AS bx, sb.y AS b_y, sc.x AS cx, sc.y AS cy, t.a, t.b, t.c
			   FROM tdc_arb_t t, tdc_arb_s sa, tdc_arb_s sb, tdc_arb_s sc
			   WHERE t.id = tri AND sa.ord = t.a AND sb.ord = t.b AND sc.ord = t.c),
		 -- the centre relative to a: (ux, uy) / d, as in any textbook
		 l AS (SELECT t.*, (bx - ax) * (bx - ax) + (b_y - ay) * (b_y - ay) AS lb,
					  (cx - ax) * (cx - ax) + (cy - ay) * (cy - ay) AS lc
			   FROM t),
		 m AS (SELECT l.*, 2 * tdc_arb_orient(ax, ay, bx, b_y, cx, cy) AS d,
					  (cy - ay) * lb - (b_y - ay) * lc AS ux, (bx - ax) * lc - (cx - ax) * lb AS uy
			   FROM l),
		 c AS (SELECT m.*, ax + tdc_arb_div(ux, d) AS ox, ay + tdc_arb_div(uy, d) AS oy,
					  sqrt(tdc_arb_div(ux * ux + uy * uy, d * d)) AS r
			   FROM m),
		 box AS (SELECT c.*, ST_Expand(ST_MakePoint(ox::float8, oy::float8),
									   (r * (1 + 1e-9) + 1e-9 * (1 + abs(ox) + abs(oy)))::float8) AS bb
				 FROM c)
	SELECT coalesce(min(CASE WHEN s.ord IN (box.a, box.b, box.c) THEN 1
							 ELSE -tdc_arb_incircle(ax, ay, bx, b_y, cx, cy, s.x, s.y) END), 1)
	FROM box LEFT JOIN tdc_arb_s s ON s.g && box.bb $$;

-- The linear value at (qx, qy) on triangle tri: exact barycentric weights,
-- the quotient truncated at 40 decimals.
CREATE FUNCTION tdc_arb_value(tri bigint, qx numeric, qy numeric) RETURNS numeric LANGUAGE sql STABLE AS $$
	SELECT tdc_arb_div(sa.z * tdc_arb_orient(sb.x, sb.y, sc.x, sc.y, qx, qy)
					   + sb.z * tdc_arb_orient(sc.x, sc.y, sa.x, sa.y, qx, qy)
					   + sc.z * tdc_arb_orient(sa.x, sa.y, sb.x, sb.y, qx, qy),
					   tdc_arb_orient(sa.x, sa.y, sb.x, sb.y, sc.x, sc.y))
	FROM tdc_arb_t t, tdc_arb_s sa, tdc_arb_s sb, tdc_arb_s sc
	WHERE t.id = tri AND sa.ord = t.a AND sb.ord = t.b AND sc.ord = t.c $$;

-- The nearest sample's height at every query, by brute force over every
-- sample: least squared distance, then least x, then least y (equal x and y
-- were merged into the first sample); and how many samples are that near
-- (ties > 1: the rule decided).  The squared distances are first computed
-- in float8 for every (query, sample) pair, within a relative 1e-15 of the
-- exact ones, and only the samples within a relative 1e-12 of a query's
-- least one are then compared exactly.
CREATE FUNCTION tdc_arb_nearest() RETURNS TABLE (qid bigint, z float8, ties bigint) LANGUAGE sql VOLATILE AS $$
	SELECT q.qid, n.z, n.ties
	FROM tdc_arb_q q,
		 LATERAL (SELECT min((s.fx - q.fx) * (s.fx - q.fx) + (s.fy - q.fy) * (s.fy - q.fy)) AS d2
				  FROM tdc_arb_s s) m,
		 LATERAL (SELECT (array_agg(c.fz ORDER BY c.d2, c.x, c.y))[1] AS z, count(*) FILTER (WHERE c.d2 = c.least) AS ties
				  FROM (SELECT s.fz, s.x, s.y, e.d2, min(e.d2) OVER () AS least
						FROM tdc_arb_s s,
							 LATERAL (SELECT (s.x - q.x) * (s.x - q.x) + (s.y - q.y) * (s.y - q.y) AS d2) e
						WHERE (s.fx - q.fx) * (s.fx - q.fx) + (s.fy - q.fy) * (s.fy - q.fy) <= m.d2 * (1 + 1e-12::float8)) c) n $$;

-- The linear value at every query: the candidate triangle holding it (NULL
-- when none does), that triangle's circumcircle (tdc_arb_circle) and the
-- exact value there.
CREATE FUNCTION tdc_arb_linear() RETURNS TABLE (qid bigint, tri bigint, circle int, z numeric)
	LANGUAGE sql VOLATILE AS $$
	WITH l AS (SELECT q.qid, q.x, q.y, tdc_arb_locate(q.x, q.y) AS tri FROM tdc_arb_q q),
		 c AS (SELECT u.tri, tdc_arb_circle(u.tri) AS circle FROM (SELECT DISTINCT l.tri FROM l) u)
	SELECT l.qid, l.tri, c.circle, tdc_arb_value(l.tri, l.x, l.y)
	FROM l LEFT JOIN c ON c.tri = l.tri $$;
