--
-- tdc_bigvalue: ST_TDCDelaunayTriangles reads a value stored out of line or
-- compressed a slice at a time (decompressing pglz and lz4 itself) instead
-- of detoasting it whole.  Every way a value can be stored must give exactly
-- the triangles of the same bytes read in memory, errors must be the same,
-- and an interrupt is answered while the value is being read.
--
-- Parallel plans would change the order in which the aggregate below gets
-- its rows (and so its triangles' order).
SET max_parallel_workers_per_gather = 0;

-- Pseudo-random coordinates (hashint4: the same on every run).  The source
-- values are kept uncompressed, so that a copy is compressed (or not) by the
-- settings of the column it is inserted into.
CREATE TABLE tdc_bv_src (name text, g geometry);
ALTER TABLE tdc_bv_src ALTER g SET STORAGE EXTERNAL;
INSERT INTO tdc_bv_src
SELECT '2d', ST_Collect(ST_MakePoint((hashint4(i) & 1048575)::float8 / 1024, (hashint4(-i) & 1048575)::float8 / 1024) ORDER BY i)
FROM generate_series(1, 30000) i;
INSERT INTO tdc_bv_src
SELECT '3d', ST_Collect(ST_MakePoint((hashint4(i) & 1048575)::float8 / 1024, (hashint4(-i) & 1048575)::float8 / 1024, i % 100) ORDER BY i)
FROM generate_series(1, 15000) i;
-- XYM and XYZM: 3 and 4 doubles a vertex, M dropped
INSERT INTO tdc_bv_src SELECT '3dm', ST_Force3DM(g) FROM tdc_bv_src WHERE name = '3d';
INSERT INTO tdc_bv_src SELECT '4d', ST_Force4D(g) FROM tdc_bv_src WHERE name = '3d';
-- lines and polygons (one with 5000 holes: its ring sizes alone take 20 kB)
INSERT INTO tdc_bv_src
SELECT 'lines', ST_Collect(ST_MakeLine(ST_MakePoint(i, (hashint4(i) & 1023) / 8.0), ST_MakePoint(i + 0.5, (hashint4(-i) & 1023) / 8.0)) ORDER BY i)
FROM generate_series(1, 10000) i;
INSERT INTO tdc_bv_src
SELECT 'holes', ST_MakePolygon('LINESTRING(-1 -1, 201 -1, 201 101, -1 101, -1 -1)',
	array_agg(ST_MakeLine(ARRAY[ST_MakePoint(i % 200, i / 200), ST_MakePoint(i % 200 + 0.5, i / 200),
		ST_MakePoint(i % 200 + 0.25, i / 200 + 0.5 + (hashint4(i) & 255) / 1024.0), ST_MakePoint(i % 200, i / 200)]) ORDER BY i))
FROM generate_series(0, 4999) i;
-- long runs: 10000 copies of one point (240 kB) between others, long
-- matches in both compressors
INSERT INTO tdc_bv_src
SELECT 'runs', ST_Collect(CASE WHEN i % 10000 = 0 THEN ST_MakePoint(i / 1000.0, (hashint4(i) & 255) / 256.0)
	ELSE ST_MakePoint(0.5, 0.5) END ORDER BY i)
FROM generate_series(0, 40000) i;
-- small ones: compressible (a grid) and not
INSERT INTO tdc_bv_src SELECT 'grid', ST_Collect(ST_MakePoint(i % 20, i / 20) ORDER BY i) FROM generate_series(0, 299) i;
INSERT INTO tdc_bv_src SELECT 'small', 'MULTIPOINT(0 0, 1 0, 0 1, 1 1)';
INSERT INTO tdc_bv_src SELECT 'sized', ST_Collect(ST_MakePoint(hashint4(i)::float8 / 1e6, hashint4(-i)::float8 / 1e6) ORDER BY i) FROM generate_series(1, 50) i;

-- Every storage: out of line uncompressed, out of line compressed with pglz
-- and lz4, compressed in line with both, in line with a 4-byte and with a
-- 1-byte header.
CREATE TABLE tdc_bv (name text, storage text, g geometry);
ALTER TABLE tdc_bv ALTER g SET STORAGE EXTERNAL;
INSERT INTO tdc_bv SELECT name, 'external', g FROM tdc_bv_src WHERE name NOT IN ('grid', 'small', 'sized');
ALTER TABLE tdc_bv ALTER g SET STORAGE EXTENDED, ALTER g SET COMPRESSION pglz;
INSERT INTO tdc_bv SELECT name, 'external pglz', g FROM tdc_bv_src WHERE name NOT IN ('grid', 'small', 'sized');
ALTER TABLE tdc_bv ALTER g SET COMPRESSION lz4;
INSERT INTO tdc_bv SELECT name, 'external lz4', g FROM tdc_bv_src WHERE name NOT IN ('grid', 'small', 'sized');
ALTER TABLE tdc_bv ALTER g SET STORAGE MAIN, ALTER g SET COMPRESSION pglz;
INSERT INTO tdc_bv SELECT name, 'inline pglz', g FROM tdc_bv_src WHERE name = 'grid';
ALTER TABLE tdc_bv ALTER g SET COMPRESSION lz4;
INSERT INTO tdc_bv SELECT name, 'inline lz4', g FROM tdc_bv_src WHERE name = 'grid';
ALTER TABLE tdc_bv ALTER g SET STORAGE EXTERNAL;
INSERT INTO tdc_bv SELECT name, 'inline', g FROM tdc_bv_src WHERE name IN ('small', 'sized');

-- What was stored: compression method and stored size (in line: under 2 kB).
SELECT name, storage, pg_column_compression(g) AS method,
	   CASE WHEN pg_column_size(g) < 127 THEN 'in line, 1-byte header'
			WHEN pg_column_size(g) < 2000 THEN 'in line' ELSE 'out of line' END AS stored
FROM tdc_bv ORDER BY name, storage;

-- The same triangles as from the same value in memory (ST_SetSRID returns
-- a detoasted copy), and (once per value) as the aggregate over its
-- vertices in their order: all three collect the same vertices in the same
-- order, so the results are byte for byte the same.
WITH r AS MATERIALIZED (
	SELECT name, storage, g, ST_AsEWKB(ST_TDCDelaunayTriangles(g)) AS tri
	FROM tdc_bv)
SELECT r.name, r.storage, ST_NumGeometries(r.tri::geometry) AS triangles,
	   r.tri = ST_AsEWKB(ST_TDCDelaunayTriangles(ST_SetSRID(r.g, ST_SRID(r.g)))) AS same_as_memory,
	   CASE WHEN r.storage IN ('external', 'inline', 'inline pglz') THEN
		   r.tri = (SELECT ST_AsEWKB(ST_TDCDelaunay(d.geom ORDER BY d.path)) FROM ST_DumpPoints(r.g) d)
	   END AS same_as_aggregate
FROM r ORDER BY r.name, r.storage;

-- The other output forms, and a tolerance.
SELECT storage,
	   ST_AsEWKB(ST_TDCDelaunayTriangles(g, 0, 1)) = ST_AsEWKB(ST_TDCDelaunayTriangles(ST_SetSRID(g, ST_SRID(g)), 0, 1)) AS edges,
	   ST_AsEWKB(ST_TDCDelaunayTriangles(g, 0.01, 2)) = ST_AsEWKB(ST_TDCDelaunayTriangles(ST_SetSRID(g, ST_SRID(g)), 0.01, 2)) AS tin
FROM tdc_bv WHERE name = '3d' ORDER BY storage;

-- Z survives: the result has it, from the right vertices.
SELECT v.storage, ST_ZMax(ST_TDCDelaunayTriangles(v.g)) AS zmax, ST_ZMin(ST_TDCDelaunayTriangles(v.g)) AS zmin
FROM tdc_bv v WHERE v.name = '3d' ORDER BY v.storage;

-- Errors inside a big value are the same as in memory (same offsets), with a
-- CONTEXT line telling how the value was stored.
CREATE TABLE tdc_bv_bad (name text, storage text, g geometry);
ALTER TABLE tdc_bv_bad ALTER g SET STORAGE EXTERNAL;
-- the last vertex cut off: a vertex list longer than the value
INSERT INTO tdc_bv_bad
SELECT 'truncated', 'external', tdc_mkgeom(substr(tdc_raw(g, ''), 1, length(tdc_raw(g, '')) - 8), '')
FROM tdc_bv_src WHERE name = '2d';
-- bytes after the geometry
INSERT INTO tdc_bv_bad
SELECT 'trailing', 'external', tdc_mkgeom(tdc_raw(g, ''), '\x0000000000000000')
FROM tdc_bv_src WHERE name = '2d';
-- a NaN at the end, a curve at the end
INSERT INTO tdc_bv_bad
SELECT 'nan', 'external', ST_Collect(g, 'POINT(NaN 1)') FROM tdc_bv_src WHERE name = '2d';
INSERT INTO tdc_bv_bad
SELECT 'curve', 'external', ST_Collect(g, 'CIRCULARSTRING(0 0, 1 1, 2 0)') FROM tdc_bv_src WHERE name = '2d';
ALTER TABLE tdc_bv_bad ALTER g SET STORAGE EXTENDED, ALTER g SET COMPRESSION pglz;
INSERT INTO tdc_bv_bad SELECT name, 'external pglz', g FROM tdc_bv_bad;
ALTER TABLE tdc_bv_bad ALTER g SET COMPRESSION lz4;
INSERT INTO tdc_bv_bad SELECT name, 'external lz4', g FROM tdc_bv_bad WHERE storage = 'external';
SELECT name, storage, pg_column_compression(g) AS method FROM tdc_bv_bad ORDER BY name, storage;

\set VERBOSITY default
SELECT ST_TDCDelaunayTriangles(ST_SetSRID(g, 0)) FROM tdc_bv_bad WHERE name = 'truncated' AND storage = 'external';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'truncated' AND storage = 'external';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'truncated' AND storage = 'external pglz';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'truncated' AND storage = 'external lz4';
SELECT ST_TDCDelaunayTriangles(ST_SetSRID(g, 0)) FROM tdc_bv_bad WHERE name = 'trailing' AND storage = 'external';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'trailing' AND storage = 'external';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'trailing' AND storage = 'external lz4';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'nan' AND storage = 'external';
SELECT ST_TDCDelaunayTriangles(g) FROM tdc_bv_bad WHERE name = 'nan' AND storage = 'external pglz';
-- a curve at the end is not an error: it is met after the first slices,
-- and the whole value is read again as PostGIS strokes it, which gives the
-- triangles of the stroked value read in memory, byte for byte
SELECT storage, md5(ST_AsBinary(ST_TDCDelaunayTriangles(g))) = md5(ST_AsBinary(ST_TDCDelaunayTriangles(ST_CurveToLine(g)))) AS as_stroked,
	   ST_NPoints(ST_CurveToLine(g)) - ST_NPoints(g) AS vertices_added_by_stroking
FROM tdc_bv_bad WHERE name = 'curve' ORDER BY storage;

-- An interrupt is answered while the value is being read: this cancel is
-- pending when the function starts (pg_cancel_backend of the backend
-- itself, evaluated first), and it takes effect before the first slice is
-- fetched, so the CONTEXT line says so.  (Detoasting the whole value first
-- would only notice it once the value was read.)
SELECT pg_cancel_backend(pg_backend_pid()), ST_TDCDelaunayTriangles(g) IS NULL FROM tdc_bv WHERE name = '2d' AND storage = 'external';
SELECT pg_cancel_backend(pg_backend_pid()), ST_TDCDelaunayTriangles(g) IS NULL FROM tdc_bv WHERE name = '2d' AND storage = 'external pglz';
SELECT pg_cancel_backend(pg_backend_pid()), ST_TDCDelaunayTriangles(g) IS NULL FROM tdc_bv WHERE name = '2d' AND storage = 'external lz4';

-- statement_timeout on a bigger value (300000 points, 7 MB, 3.7 MB with pglz): a
-- timeout this short fires while the value is read on any machine but a
-- very fast one (there, in the engine); only that the statement is canceled
-- is checked, whatever the phase.
CREATE TABLE tdc_bv_big AS
SELECT ST_Collect(ST_MakePoint((hashint4(i)::float8 + 2147483648) / 4294967296, (hashint4(-i)::float8 + 2147483648) / 4294967296) ORDER BY i) AS g
FROM generate_series(1, 300000) i;
SELECT pg_column_compression(g) AS method, pg_column_size(g) > 3000000 AS big FROM tdc_bv_big;
\set VERBOSITY terse
SET statement_timeout = '10ms';
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) FROM tdc_bv_big;
RESET statement_timeout;
\set VERBOSITY default
-- the session goes on, and the value gives its triangles when given time
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles(g)) AS triangles FROM tdc_bv_big;

DROP TABLE tdc_bv_big, tdc_bv_bad, tdc_bv, tdc_bv_src;
RESET max_parallel_workers_per_gather;
