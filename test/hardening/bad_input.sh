#!/usr/bin/env bash
# test/hardening/bad_input.sh: edge-case and hostile inputs that the
# pg_regress suite (sql/*.sql) does not already cover.
#
#   PGHOST=... PGPORT=... PGUSER=... PGDATABASE=... bash test/hardening/bad_input.sh
#
# Every case runs in its own psql session and either must return true or
# must fail with an ERROR matching a pattern; after each failing case the
# next session must still work, and at the end pg_postmaster_start_time()
# must be unchanged (no backend crashed).  Expected triangle counts are
# 2n - 2 - h (n distinct sites, h of them on the convex hull boundary,
# collinear ones included, found with GEOS' exact point-on-line test), not
# ST_DelaunayTriangles' count: GEOS drops sliver triangles next to the hull
# on integer-lattice inputs (e.g. 11 points, 14 triangles, GEOS gives 13).
# Takes about a minute.  Prints "N passed, N failed".
set -euo pipefail
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# shellcheck source=test/hardening/lib.sh
source "$HERE/lib.sh"

echo "== bad_input.sh"
require_server
START0=$(postmaster_start)

# expect_true NAME SQL: the last row printed must be "t"
# (cases slower than 2 s say how long they took)
took() {
	local ms=$((($(date +%s%N) - $1) / 1000000))
	((ms < 2000)) || echo " (${ms} ms)"
}

expect_true() {
	local name=$1 sql=$2 out t0
	t0=$(date +%s%N)
	if out=$(hpsql -c "$sql" 2>&1) && [ "$(printf '%s\n' "$out" | tail -n1)" = t ]; then
		pass "$name$(took "$t0")"
	else
		fail "$name: $(printf '%s' "$out" | tail -n3 | tr '\n' ' ' | cut -c1-300)"
	fi
}

# expect_error NAME SQL REGEX: must fail with an ERROR whose text matches
expect_error() {
	local name=$1 sql=$2 re=$3 out t0
	t0=$(date +%s%N)
	if out=$(hpsql -c "$sql" 2>&1); then
		fail "$name: no error (got: $(printf '%s' "$out" | tail -n1 | cut -c1-200))"
	elif grep -q '^ERROR: ' <<<"$out" && grep -Eq "$re" <<<"$out"; then
		pass "$name$(took "$t0")"
	else
		fail "$name: $(printf '%s' "$out" | head -n3 | tr '\n' ' ' | cut -c1-300)"
	fi
}

hpsql >/dev/null <<'EOF'
-- triangles of PostGIS for the same vertices (via ST_DelaunayTriangles)
CREATE OR REPLACE FUNCTION tdc_hard.postgis_count(g geometry, flags int DEFAULT 0) RETURNS int
LANGUAGE sql AS $$ SELECT ST_NumGeometries(ST_DelaunayTriangles(ST_Collect(ARRAY(SELECT geom FROM ST_DumpPoints(g))), 0, flags)) $$;
-- 2n - 2 - h for the vertices of g (0 when they span no area)
CREATE OR REPLACE FUNCTION tdc_hard.expected(g geometry) RETURNS bigint
LANGUAGE sql AS $$
	WITH s AS MATERIALIZED (SELECT DISTINCT ST_X(geom) AS x, ST_Y(geom) AS y FROM ST_DumpPoints(g)),
		 h AS MATERIALIZED (SELECT ST_Boundary(ST_ConvexHull(g)) AS b, ST_Dimension(ST_ConvexHull(g)) AS dim)
	SELECT CASE WHEN dim < 2 THEN 0 ELSE
		2 * (SELECT count(*) FROM s) - 2 -
		(SELECT count(*) FROM s, h WHERE ST_Intersects(ST_SetSRID(ST_MakePoint(x, y), ST_SRID(g)), h.b)) END
	FROM h $$;
-- normalized triangle set, to compare with PostGIS
CREATE OR REPLACE FUNCTION tdc_hard.norm(g geometry) RETURNS text
LANGUAGE sql AS $$ SELECT coalesce(string_agg(x, ',' ORDER BY x), '')
	FROM (SELECT ST_AsText(ST_Normalize(d.geom)) AS x FROM ST_Dump(g) d WHERE NOT ST_IsEmpty(d.geom)) s $$;
DROP TABLE IF EXISTS tdc_hard.bad_dml;
CREATE TABLE tdc_hard.bad_dml (g geometry);
EOF

RANGE='out(side)? (of )?the supported magnitude range'

echo "-- coordinates at the limits of the exact range [1e-60, 1e60]"
expect_true "the range ends themselves are accepted (5 triangles)" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1e60 0, 0 1e60, -1e60 -1e60, 1e-60 1e-60)')) = 5"
expect_error "next double above 1e60 is rejected" \
	"SELECT ST_TDCDelaunayTriangles(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(1.0000000000000002e60, 0), ST_MakePoint(0, 1)]))" "$RANGE"
expect_error "just below 1e-60 is rejected" \
	"SELECT ST_TDCDelaunayTriangles(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(1, 9.99999999999999e-61), ST_MakePoint(0, 1)]))" "$RANGE"
expect_error "subnormal coordinate is rejected" \
	"SELECT ST_TDCDelaunayTriangles(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(1, 4.9e-324), ST_MakePoint(0, 1)]))" "$RANGE"
expect_error "DBL_MAX is rejected" \
	"SELECT ST_TDCDelaunayTriangles(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(1.7976931348623157e308, 1), ST_MakePoint(0, 1)]))" "$RANGE"
expect_error "-DBL_MAX in the aggregate is rejected" \
	"SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_MakePoint(0, 0)), (ST_MakePoint(-1.7976931348623157e308, 0)), (ST_MakePoint(0, 1))) v(g)" "$RANGE"
expect_error "1e-61 in a Dump query is rejected" \
	"SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT ST_MakePoint(0, 0) UNION ALL SELECT ST_MakePoint(1e-61, 1) UNION ALL SELECT ST_MakePoint(0, 1)\$\$)" "$RANGE"
expect_error "NaN in Z only, aggregate" \
	"SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_MakePoint(0, 0, 1)), (ST_MakePoint(1, 0, 'NaN')), (ST_MakePoint(0, 1, 2))) v(g)" "non-finite|NaN"
expect_error "Infinity in a Dump query" \
	"SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT ST_MakePoint('Infinity', 0) UNION ALL SELECT ST_MakePoint(0, 1)\$\$)" "non-finite|NaN|Infinity"
expect_true "0 and -0 are one site (1 triangle)" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint('-0'::float8, '-0'::float8), ST_MakePoint(1, 0), ST_MakePoint(0, 1)]))) = 1"
for s in 1e-59 1e59 3e-45 7e44; do
	expect_true "square with centre scaled by $s: 4 triangles, same as PostGIS" \
		"SELECT ST_NumGeometries(t) = 4 AND tdc_hard.norm(t) = tdc_hard.norm(ST_DelaunayTriangles(g))
		 FROM (SELECT g, ST_TDCDelaunayTriangles(g) AS t FROM (SELECT ST_Scale('MULTIPOINT(0 0, 2 0, 0 2, 2 2, 1 1)'::geometry, $s, $s) AS g) a) b"
done
expect_true "magnitudes 1e-60 .. 1e60 mixed in one input: 2n - 2 - h" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(1e-60 1e-60, 2e-60 1e-60, 1e-60 3e-60, 1e60 1e60, -1e60 1e60, 0 -1e60, 1e-30 1e-30)')) = 2 * 7 - 2 - 3"

echo "-- tolerance extremes"
expect_true "tolerance 1e300 keeps one site (empty result)" \
	"SELECT ST_IsEmpty(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 1e300))"
expect_true "tolerance DBL_MAX keeps one site" \
	"SELECT ST_IsEmpty(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 1.7976931348623157e308))"
expect_true "tolerance 5e-324 drops nothing" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 5e-324)) = 1"
expect_error "flags INT_MAX" \
	"SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 0, 2147483647)" "flags"
expect_error "flags INT_MIN in the aggregate" \
	"SELECT ST_TDCDelaunay(g, 0, -2147483648) FROM (VALUES ('POINT(0 0)'::geometry)) v(g)" "flags"
expect_error "tolerance -0 ... -1e-300" \
	"SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', -1e-300)" "tolerance"
expect_true "tolerance -0 is 0" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', '-0'::float8)) = 1"

echo "-- empty and degenerate inputs through the aggregate and Dump"
expect_true "aggregate over empties only: empty collection with the SRID" \
	"SELECT ST_AsText(t) = 'GEOMETRYCOLLECTION EMPTY' AND ST_SRID(t) = 4326 FROM (SELECT ST_TDCDelaunay(g) AS t FROM (VALUES ('SRID=4326;POINT EMPTY'::geometry), ('SRID=4326;GEOMETRYCOLLECTION EMPTY'), ('SRID=4326;MULTIPOLYGON EMPTY')) v(g)) s"
expect_true "aggregate over no rows is NULL" \
	"SELECT ST_TDCDelaunay(g) IS NULL FROM (SELECT 'POINT(0 0)'::geometry WHERE false) v(g)"
expect_true "Dump over empties only: no rows" \
	"SELECT count(*) = 0 FROM ST_TDCDelaunayDump(\$\$SELECT 'POINT EMPTY'::geometry UNION ALL SELECT 'GEOMETRYCOLLECTION(POINT EMPTY, LINESTRING EMPTY)'\$\$)"
expect_true "empty parts at every level of a collection: same as PostGIS" \
	"SELECT tdc_hard.norm(ST_TDCDelaunayTriangles(g)) = tdc_hard.norm(ST_DelaunayTriangles(g)) AND ST_NumGeometries(ST_TDCDelaunayTriangles(g)) = 2
	 FROM (SELECT 'GEOMETRYCOLLECTION(GEOMETRYCOLLECTION EMPTY, MULTIPOINT EMPTY, POINT(0 0), LINESTRING EMPTY, POLYGON EMPTY, MULTIPOLYGON(EMPTY, ((1 0, 1 1, 2 0, 1 0))), GEOMETRYCOLLECTION(POINT EMPTY, GEOMETRYCOLLECTION EMPTY))'::geometry AS g) s"
expect_true "one point, every output kind: empty, SRID kept" \
	"SELECT bool_and(ST_IsEmpty(t) AND ST_SRID(t) = 3857) FROM (SELECT ST_TDCDelaunayTriangles('SRID=3857;POINT(1 2)', 0, f) AS t FROM generate_series(0, 2) f) s"
expect_true "10000 copies of one point: empty" \
	"SELECT ST_IsEmpty(ST_TDCDelaunay(g)) FROM (SELECT ST_MakePoint(7, 7) AS g FROM generate_series(1, 10000)) s"
expect_true "10000 copies of two points, then a third: 1 triangle" \
	"SELECT ST_NumGeometries(ST_TDCDelaunay(g)) = 1 FROM (SELECT ST_MakePoint(i % 2, 0) AS g FROM generate_series(1, 10000) i UNION ALL SELECT ST_MakePoint(0.5, 3)) s"
# (not compared with PostGIS: GEOS needs minutes for this input)
expect_true "100000 collinear points: no triangles, a chain of n - 1 edges" \
	"SELECT ST_IsEmpty(ST_TDCDelaunay(g)) AND ST_NumGeometries(ST_TDCDelaunay(g, 0, 1)) = 99999
	 FROM (SELECT ST_MakePoint(i * 3, i * 2) AS g FROM generate_series(1, 100000) i) s"
expect_error "mixed SRIDs where the first row is empty" \
	"SELECT ST_TDCDelaunay(g) FROM (VALUES ('SRID=4326;POINT EMPTY'::geometry), ('SRID=3857;POINT(0 0)')) v(g)" "mixed SRIDs"
expect_error "mixed dimensions where one side is empty" \
	"SELECT ST_TDCDelaunay(g) FROM (VALUES ('POINT Z EMPTY'::geometry), ('POINT(0 0)')) v(g)" "mixed dimensions"

echo "-- huge collections"
expect_true "1,000,000 empty members and 3 points: 1 triangle" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(ST_Collect(ARRAY(SELECT 'POINT EMPTY'::geometry FROM generate_series(1, 1000000)) || ARRAY['POINT(0 0)'::geometry, 'POINT(1 0)', 'POINT(0 1)']))) = 1"
expect_true "one MULTIPOINT value of 400,000 points: 2n - 2 - h" \
	"WITH p AS MATERIALIZED (SELECT ST_Collect(ST_MakePoint((hashint4(i) & 1048575), (hashint4(-i) & 1048575))) AS g FROM generate_series(1, 400000) i),
		  u AS MATERIALIZED (SELECT DISTINCT ST_X(d.geom) AS x, ST_Y(d.geom) AS y FROM p, ST_Dump(p.g) d),
		  h AS MATERIALIZED (SELECT ST_Boundary(ST_ConvexHull(g)) AS b FROM p)
	 SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(p.g)) = 2 * (SELECT count(*) FROM u) - 2 -
			(SELECT count(*) FROM u, h WHERE ST_Intersects(ST_MakePoint(x, y), h.b)) FROM p"
expect_true "a toasted (external, uncompressed) 100k-point value, directly and through the aggregate" \
	"CREATE TEMP TABLE t (g geometry); ALTER TABLE t ALTER COLUMN g SET STORAGE EXTERNAL;
	 INSERT INTO t SELECT ST_Collect(ST_MakePoint(i, (i * 7919) % 100003)) FROM generate_series(1, 100000) i;
	 INSERT INTO t SELECT g FROM t;
	 SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) = tdc_hard.expected(g) FROM t LIMIT 1;
	 SELECT bool_and(n = (SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM t LIMIT 1)) FROM (SELECT ST_NumGeometries(ST_TDCDelaunay(g)) AS n FROM t) s"
expect_true "a compressed in-line value" \
	"CREATE TEMP TABLE t (g geometry); ALTER TABLE t ALTER COLUMN g SET STORAGE MAIN;
	 INSERT INTO t SELECT ST_Collect(ST_MakePoint(i % 50, i / 50)) FROM generate_series(0, 2499) i;
	 SELECT pg_column_size(g) < ST_NPoints(g) * 16 AND ST_NumGeometries(ST_TDCDelaunayTriangles(g)) = tdc_hard.expected(g) FROM t"

echo "-- ST_TDCDelaunayDump with unusual queries"
expect_error "query raising an error after 50000 rows" \
	"SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT CASE WHEN i < 50000 THEN ST_MakePoint(i, i % 7) ELSE ST_MakePoint(1 / (i - i), 0) END FROM generate_series(1, 60000) i\$\$)" "division by zero"
expect_error "empty query text" "SELECT count(*) FROM ST_TDCDelaunayDump('')" "single SELECT|empty"
expect_error "query with a parameter" "SELECT count(*) FROM ST_TDCDelaunayDump('SELECT \$1::geometry')" "parameter"
expect_error "geography column" "SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT 'POINT(0 0)'::geography\$\$)" "geography"
expect_error "bytea column" "SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT '\\x00'::bytea\$\$)" "type geometry"
expect_error "query ending in a semicolon plus a second statement" \
	"SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT 'POINT(0 0)'::geometry; DROP TABLE tdc_hard.bad_dml\$\$)" "single SELECT|one|multiple"
expect_true "... and the table is still there" "SELECT to_regclass('tdc_hard.bad_dml') IS NOT NULL"
expect_true "nested: a Dump query that runs Dump itself" \
	"SELECT (SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT geom FROM ST_TDCDelaunayDump('SELECT ST_MakePoint(i, (i * i) % 17) FROM generate_series(1, 500) i')\$\$))
		  = tdc_hard.expected((SELECT ST_Collect(ST_MakePoint(i, (i * i) % 17)) FROM generate_series(1, 500) i))"
expect_error "data-modifying CTE in the query: refused" \
	"SELECT count(*) > 0 FROM ST_TDCDelaunayDump(\$\$WITH d AS (INSERT INTO tdc_hard.bad_dml SELECT ST_MakePoint(i, i * i % 11) FROM generate_series(1, 20) i RETURNING g) SELECT g FROM d\$\$)" "only reads"
expect_true "... and nothing was inserted" "SELECT count(*) = 0 FROM tdc_hard.bad_dml"
expect_true "fill the table for the next cases" \
	"INSERT INTO tdc_hard.bad_dml SELECT ST_MakePoint(i, i * i % 11) FROM generate_series(1, 20) i; SELECT true"
expect_error "data-modifying CTE in a read-only transaction" \
	"BEGIN READ ONLY; SELECT count(*) FROM ST_TDCDelaunayDump(\$\$WITH d AS (INSERT INTO tdc_hard.bad_dml VALUES ('POINT(0 0)') RETURNING g) SELECT g FROM d\$\$)" "read-only|only reads"
expect_error "FOR UPDATE query: refused" \
	"SELECT count(*) > 0 FROM ST_TDCDelaunayDump('SELECT g FROM tdc_hard.bad_dml FOR UPDATE')" "only reads"
expect_true "query returning the aggregate's triangulation: same count again" \
	"SELECT (SELECT count(*) FROM ST_TDCDelaunayDump('SELECT ST_TDCDelaunay(g) FROM tdc_hard.bad_dml')) = ST_NumGeometries(ST_TDCDelaunay(g)) FROM tdc_hard.bad_dml"
expect_true "query with LIMIT 0" "SELECT count(*) = 0 FROM ST_TDCDelaunayDump('SELECT g FROM tdc_hard.bad_dml LIMIT 0')"
expect_true "1 MB of whitespace around the query" \
	"SELECT count(*) = 1 FROM ST_TDCDelaunayDump(repeat(' ', 1000000) || \$\$SELECT 'MULTIPOINT(0 0, 1 0, 0 1)'::geometry\$\$ || repeat(E'\\n', 1000))"
expect_true "Dump in a cursor, fetched partly, then closed" \
	"BEGIN; DECLARE c CURSOR FOR SELECT * FROM ST_TDCDelaunayDump('SELECT g FROM tdc_hard.bad_dml'); FETCH 3 FROM c; CLOSE c; COMMIT;
	 SELECT true"
expect_true "Dump in a LATERAL join, once per outer row" \
	"SELECT bool_and(n = tdc_hard.expected(ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(k, 0), ST_MakePoint(0, k), ST_MakePoint(k, k), ST_MakePoint(k / 3.0, k / 7.0)])))
	 FROM generate_series(1, 30) k, LATERAL (SELECT count(*) AS n FROM ST_TDCDelaunayDump(format('SELECT ST_Collect(ARRAY[ST_MakePoint(0, 0), ST_MakePoint(%1\$s, 0), ST_MakePoint(0, %1\$s), ST_MakePoint(%1\$s, %1\$s), ST_MakePoint(%1\$s / 3.0, %1\$s / 7.0)])', k))) d"

expect_error "query is FETCH from an open cursor: refused, not a plain SELECT" \
	"BEGIN; DECLARE c CURSOR FOR SELECT ST_MakePoint(i, i * i % 11) FROM generate_series(1, 20) i; FETCH 2 FROM c;
	 SELECT count(*) FROM ST_TDCDelaunayDump('FETCH ALL FROM c'); COMMIT" "only reads"
expect_error "query is EXECUTE of a prepared statement: refused (it could be DML)" \
	"PREPARE p AS SELECT ST_MakePoint(i, i * i % 11) FROM generate_series(1, 20) i;
	 SELECT count(*) FROM ST_TDCDelaunayDump('EXECUTE p')" "only reads"
expect_true "query is TABLE or VALUES" \
	"SELECT (SELECT count(*) FROM ST_TDCDelaunayDump('TABLE tdc_hard.bad_dml')) > 0
		AND (SELECT count(*) FROM ST_TDCDelaunayDump(\$\$VALUES ('POINT(0 0)'::geometry), ('POINT(1 0)'), ('POINT(0 1)')\$\$)) = 1"
expect_error "SELECT INTO" "SELECT count(*) FROM ST_TDCDelaunayDump('SELECT g INTO tdc_hard.bad_into FROM tdc_hard.bad_dml')" "single SELECT"
expect_error "EXPLAIN: refused, not a plain SELECT" "SELECT count(*) FROM ST_TDCDelaunayDump('EXPLAIN SELECT g FROM tdc_hard.bad_dml')" "only reads"
expect_error "a function whose Dump query calls itself: stack depth error, no crash" \
	"CREATE FUNCTION pg_temp.selfdump(n int) RETURNS SETOF geometry LANGUAGE sql AS
		\$f\$ SELECT geom FROM ST_TDCDelaunayDump(format('SELECT * FROM pg_temp.selfdump(%s)', n + 1)) \$f\$;
	 SELECT count(*) FROM pg_temp.selfdump(0)" "stack depth"
expect_error "the Dump query cancels its own backend half-way" \
	"SELECT count(*) FROM ST_TDCDelaunayDump(\$\$SELECT CASE WHEN i = 5000 THEN (SELECT ST_MakePoint(0, 0) FROM (SELECT pg_cancel_backend(pg_backend_pid())) x) ELSE ST_MakePoint(i, i % 7) END FROM generate_series(1, 100000) i\$\$)" "canceling statement"

echo "-- the aggregate in unusual places"
expect_true "window, growing and sliding frames: 2n - 2 - h on every row" \
	"SELECT bool_and(a = tdc_hard.expected(b) AND c = tdc_hard.expected(d)) FROM (
		SELECT ST_NumGeometries(ST_TDCDelaunay(g) OVER w1) AS a, ST_Collect(g) OVER w1 AS b,
			   ST_NumGeometries(ST_TDCDelaunay(g) OVER w2) AS c, ST_Collect(g) OVER w2 AS d
		FROM (SELECT i, ST_MakePoint((hashint4(i) & 65535), (hashint4(-i) & 65535)) AS g FROM generate_series(1, 300) i) s
		WINDOW w1 AS (ORDER BY i), w2 AS (ORDER BY i ROWS BETWEEN 10 PRECEDING AND CURRENT ROW)) x"
expect_true "DISTINCT, ORDER BY and FILTER inside the aggregate" \
	"SELECT ST_NumGeometries(ST_TDCDelaunay(DISTINCT g)) = tdc_hard.expected(ST_Collect(g))
		AND ST_NumGeometries(ST_TDCDelaunay(g ORDER BY i DESC)) = tdc_hard.expected(ST_Collect(g))
		AND ST_NumGeometries(ST_TDCDelaunay(g) FILTER (WHERE i % 2 = 0)) = tdc_hard.expected(ST_Collect(g) FILTER (WHERE i % 2 = 0))
	 FROM (SELECT i, ST_MakePoint((hashint4(i) & 4095), (hashint4(-i) & 4095)) AS g FROM generate_series(1, 3000) i) s"
expect_true "GROUPING SETS" \
	"SELECT count(*) = 9 AND bool_and(ST_NumGeometries(t) = tdc_hard.expected(c)) FROM (
		SELECT ST_TDCDelaunay(g) AS t, ST_Collect(g) AS c
		FROM (SELECT i % 3 AS a, i % 5 AS b, ST_MakePoint((hashint4(i) & 4095), (hashint4(-i) & 4095)) AS g FROM generate_series(1, 3000) i) s
		GROUP BY GROUPING SETS ((a), (b), ())) x"
expect_true "hash aggregate with many groups and a tiny work_mem (spills)" \
	"SET work_mem = '64kB'; SET enable_sort = off;
	 SELECT count(*) = 2000 AND bool_and(n = 1) FROM (
		SELECT k, ST_NumGeometries(ST_TDCDelaunay(g)) AS n
		FROM (SELECT i % 2000 AS k, ST_MakePoint(i % 2000 + (i / 2000) * 0.25, (i / 2000) * ((i / 2000) % 2) * 0.5) AS g FROM generate_series(0, 5999) i) s
		GROUP BY k) x"
expect_true "the session-level library state is fine after all of this" \
	"SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1, 1 1)')) = 2"

check "postmaster not restarted" test "$(postmaster_start)" = "$START0"
hpsql -c "DROP TABLE tdc_hard.bad_dml; DROP FUNCTION tdc_hard.postgis_count(geometry, int), tdc_hard.norm(geometry), tdc_hard.expected(geometry);" >/dev/null
finish
