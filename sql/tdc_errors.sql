--
-- tdc_errors: every error the extension raises, with its message.
--
\set VERBOSITY default

-- flags
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 0, 3);
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 0, -1);
SELECT ST_TDCDelaunay(geom, 0, 7) FROM (VALUES ('POINT(0 0)'::geometry)) v(geom);

-- tolerance
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', -1);
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 'NaN');
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)', 'Infinity');
SELECT ST_TDCDelaunay(geom, -0.5, 0) FROM (VALUES ('POINT(0 0)'::geometry)) v(geom);
SELECT * FROM ST_TDCDelaunayDump('SELECT ''POINT(0 0)''::geometry', -2);
-- tolerance and flags must not change between rows
SELECT ST_TDCDelaunay(geom, t, 0) FROM (VALUES ('POINT(0 0)'::geometry, 0::float8), ('POINT(1 0)', 1)) v(geom, t);
SELECT ST_TDCDelaunay(geom, 0, f) FROM (VALUES ('POINT(0 0)'::geometry, 0), ('POINT(1 0)', 1)) v(geom, f);

-- mixed SRIDs and dimensions
SELECT ST_TDCDelaunay(geom) FROM (VALUES ('SRID=4326;POINT(0 0)'::geometry), ('SRID=3857;POINT(1 0)')) v(geom);
SELECT ST_TDCDelaunay(geom) FROM (VALUES ('POINT(0 0)'::geometry), ('SRID=3857;POINT(1 0)')) v(geom);
SELECT ST_TDCDelaunay(geom) FROM (VALUES ('POINT(0 0)'::geometry), ('POINT Z(1 0 1)')) v(geom);
SELECT ST_TDCDelaunay(geom) FROM (VALUES ('POINT Z(0 0 0)'::geometry), ('POINT M(1 0 1)')) v(geom);
SELECT * FROM ST_TDCDelaunayDump($$SELECT * FROM (VALUES ('SRID=4326;POINT(0 0)'::geometry), ('SRID=4269;POINT(1 0)')) v$$);
-- (XYM and XY are both 2D: fine)
SELECT ST_NumGeometries(ST_TDCDelaunay(geom)) FROM (VALUES ('POINT(0 0)'::geometry), ('POINT M(1 0 1)'), ('POINT(0 1)')) v(geom);

-- curves, at top level and nested: the constrained functions refuse them,
-- as SFCGAL does (the Delaunay functions stroke them and the Voronoi
-- functions read their vertices, as PostGIS does: see tdc_postgis_cases
-- and tdc_voronoi)
SELECT ST_TDCConstrainedDelaunayTriangles('CIRCULARSTRING(0 0, 1 1, 2 0)');
SELECT ST_TDCConstrainedDelaunayTriangles('COMPOUNDCURVE(CIRCULARSTRING(0 0, 1 1, 1 0), (1 0, 0 1))');
SELECT ST_TDCConstrainedDelaunayTriangles('CURVEPOLYGON(CIRCULARSTRING(0 0, 4 0, 4 4, 0 4, 0 0))');
SELECT ST_TDCConstrainedDelaunayTriangles('MULTICURVE((0 0, 5 5), CIRCULARSTRING(4 0, 4 4, 8 4))');
SELECT ST_TDCConstrainedDelaunayTriangles('MULTISURFACE(CURVEPOLYGON(CIRCULARSTRING(0 0, 4 0, 4 4, 0 4, 0 0)))');
SELECT ST_TDCConstrainedDelaunayTriangles('GEOMETRYCOLLECTION(POINT(0 0), CIRCULARSTRING(0 0, 1 1, 2 0))');
SELECT ST_TDCConstrainedDelaunay(geom) FROM (VALUES ('POINT(0 0)'::geometry), ('CIRCULARSTRING(0 0, 1 1, 2 0)')) v(geom);
-- the hint's advice works
SELECT ST_NumGeometries(ST_TDCConstrainedDelaunayTriangles(ST_CurveToLine('CIRCULARSTRING(0 0, 1 1, 2 0)'))) > 0 AS converted;
-- an empty arc string beside arcs: PostGIS's stroking turns it into a
-- vertex of uninitialized memory, so the Delaunay functions refuse it
-- (alone it is only empty: tdc_postgis_cases)
SELECT ST_TDCDelaunayTriangles('GEOMETRYCOLLECTION(CIRCULARSTRING EMPTY, CIRCULARSTRING(0 0, 1 1, 2 0))');
SELECT ST_TDCDelaunay(geom) FROM (VALUES ('POINT(5 5)'::geometry), ('GEOMETRYCOLLECTION(CIRCULARSTRING(0 0, 1 1, 2 0), CIRCULARSTRING EMPTY)')) v(geom);

-- NaN and infinite coordinates
SELECT ST_TDCDelaunayTriangles(ST_Collect(ST_MakePoint('NaN', 0), ST_MakePoint(1, 1)));
SELECT ST_TDCDelaunayTriangles(ST_Collect(ST_MakePoint(0, 'Infinity'), ST_MakePoint(1, 1)));
SELECT ST_TDCDelaunayTriangles(ST_Collect(ST_MakePoint(0, 0, '-Infinity'), ST_MakePoint(1, 1, 1)));
SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_MakePoint(0, 0)), (ST_MakePoint('NaN', 'NaN'))) v(g);
SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_MakePoint(0, 0, 1)), (ST_MakePoint(1, 0, 'Infinity'))) v(g);
SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_MakePointM(0, 0, 1)), (ST_MakePointM(1, 'Infinity', 1))) v(g);
-- an M that is not finite is dropped, not checked (as in a MULTIPOINT M)
SELECT ST_NumGeometries(ST_TDCDelaunay(g)) AS m_nan_ignored
FROM (VALUES (ST_MakePointM(0, 0, 'NaN')), (ST_MakePointM(1, 0, 1)), (ST_MakePointM(0, 1, 1))) v(g);
-- mixed SRIDs are reported before a bad coordinate, as for any other value
SELECT ST_TDCDelaunay(g) FROM (VALUES (ST_SetSRID(ST_MakePoint(0, 0), 4326)), (ST_MakePoint('NaN', 0))) v(g);
-- out of the core's exact range
SELECT ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1e200 0, 0 1)');

-- corrupt geometry values, built from raw bytes (tdc_mkgeom: see tdc_basic)
-- header only, no geometry
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x00000040', ''));
-- shorter than the header
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000', ''));
-- unknown type 99
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x000000406300000000000000', ''));
-- a point with 2 vertices
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000004001000000020000000000000000000000000000000000000000000000000000000000000000000000', ''));
-- linestring claiming 1000 vertices, holding 1
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000004002000000e8030000000000000000f03f0000000000000040', ''));
-- linestring claiming 2^32-1 vertices
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000004002000000ffffffff000000000000f03f0000000000000040', ''));
-- polygon claiming 2^31 rings
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x000000400300000000000080', ''));
-- polygon whose ring is longer than the value
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x00000040030000000100000004000000000000000000000000000000000000000000000000000000', ''));
-- multipoint claiming 3 members, holding 1
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x00000040040000000300000001000000010000000000000000000000000000000000f03f', ''));
-- collection with a truncated member header
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000004007000000010000000100', ''));
-- trailing garbage after a valid point
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x000000400100000001000000000000000000f03f0000000000000040deadbeef', ''));
-- bounding box flag without the box
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x0000004402000000', ''));
-- extended flags bit without the 8 bytes
SELECT ST_TDCDelaunayTriangles(tdc_mkgeom('\x00000050', ''));
-- deep nesting is bounded by the stack check, not a crash.  (Caught, so
-- that the output does not show the HINT, which quotes the server's
-- max_stack_depth; any other error, or none, shows up as a difference.)
DO $$
BEGIN
	PERFORM ST_TDCDelaunayTriangles(tdc_mkgeom(('\x00000040' || repeat('0700000001000000', 200000) || '0100000000000000')::bytea, ''));
	RAISE NOTICE 'no error';
EXCEPTION WHEN statement_too_complex THEN
	RAISE NOTICE '%: %', SQLSTATE, SQLERRM;
END $$;
-- the same raw reader accepts well-formed hand-made values, v1 and v2
SELECT ST_AsText(ST_TDCDelaunayTriangles(tdc_mkgeom('\x000000400400000003000000010000000100000000000000000000000000000000000000010000000100000000000000000000400000000000000000010000000100000000000000000000000000000000000040', '')));
SELECT ST_AsText(ST_TDCDelaunayTriangles(tdc_mkgeom('\x000000000400000003000000010000000100000000000000000000000000000000000000010000000100000000000000000000400000000000000000010000000100000000000000000000000000000000000040', ''))) AS v1;

-- corrupt serialized aggregate states (what parallel workers send)
CREATE AGGREGATE tdc_test_state(geometry) (SFUNC = st_tdcdelaunay_transfn, STYPE = internal,
	FINALFUNC = st_tdcdelaunay_serialfn);
CREATE TABLE tdc_state AS
	SELECT tdc_test_state(g) AS s FROM (VALUES ('SRID=4326;MULTIPOINT Z(0 0 1, 1 0 2, 0 1 3)'::geometry)) v(g);
SELECT length(s) AS state_bytes, _st_tdcdelaunay_state_check(s) AS vertices FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(substr(s, 1, 20)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(substr(s, 1, length(s) - 8)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(s || '\x00'::bytea) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\x58' from 1)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\x07' from 5)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\xff' from 9)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\x09' from 17)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\xffffffff' from 33)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check(overlay(s placing '\x000000000000f87f' from 41)) FROM tdc_state;
SELECT _st_tdcdelaunay_state_check('\x'::bytea);

-- ST_TDCDelaunayDump: wrong queries
SELECT * FROM ST_TDCDelaunayDump('SELECT 1');
SELECT * FROM ST_TDCDelaunayDump('SELECT ''POINT(0 0)''::geometry, 2');
SELECT * FROM ST_TDCDelaunayDump('SELECT ''POINT(0 0)''::text');
SELECT * FROM ST_TDCDelaunayDump('SELECT FROM generate_series(1, 3)');
SELECT * FROM ST_TDCDelaunayDump('SELECT geom FROM no_such_table');
SELECT * FROM ST_TDCDelaunayDump('SELEKT 1');
SELECT * FROM ST_TDCDelaunayDump('SELECT 1/0');
SELECT * FROM ST_TDCDelaunayDump('SELECT ''POINT(0 0)''::geometry; SELECT ''POINT(0 0)''::geometry');
SELECT * FROM ST_TDCDelaunayDump('CREATE TABLE tdc_nope (g geometry)');
SELECT * FROM ST_TDCConstrainedDelaunayDump($$SELECT 'CIRCULARSTRING(0 0, 1 1, 2 0)'::geometry$$);
-- the session is fine after all this
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)')) AS still_works;
DROP TABLE tdc_state;
DROP AGGREGATE tdc_test_state(geometry);
