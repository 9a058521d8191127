-- tdc_delaunay_tiled: the tiled triangulation of a table is the triangle set
-- of ST_TDCDelaunayDump on the same vertices, each triangle once.
SET client_min_messages = warning;
CREATE EXTENSION IF NOT EXISTS postgis;
CREATE EXTENSION IF NOT EXISTS tdc_delaunay;
SET extra_float_digits = 0;

-- the triangles of a tiled target and of the one-shot dump, as canonical
-- WKB (ring start and orientation normalized, Z included); a and b count
-- the triangles missing from each side (with multiplicity)
CREATE FUNCTION tiled_vs_dump(target regclass, query text,
	OUT tiled bigint, OUT dump bigint, OUT only_tiled bigint, OUT only_dump bigint, OUT ids_unique boolean)
LANGUAGE plpgsql AS $$
BEGIN
	EXECUTE format('CREATE TEMP TABLE tv_a AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g FROM %s', target);
	EXECUTE format('CREATE TEMP TABLE tv_b AS SELECT ST_AsEWKB(ST_Normalize(geom)) AS g FROM ST_TDCDelaunayDump(%L)', query);
	SELECT count(*) INTO tiled FROM tv_a;
	SELECT count(*) INTO dump FROM tv_b;
	SELECT count(*) INTO only_tiled FROM (SELECT g FROM tv_a EXCEPT ALL SELECT g FROM tv_b) x;
	SELECT count(*) INTO only_dump FROM (SELECT g FROM tv_b EXCEPT ALL SELECT g FROM tv_a) x;
	EXECUTE format('SELECT count(DISTINCT id) = count(*) AND count(*) = count(id) FROM %s', target) INTO ids_unique;
	DROP TABLE tv_a, tv_b;
END $$;

-- With a tile column, each triangle is kept once, labelled by the tile that
-- owns its smallest vertex (x, then y), a vertex being owned by the least
-- tile value among its copies (what the rounds of SQL statements gave,
-- each tile run with its halo), and its id is rank * 2^32 + k, rank the
-- tile's from 1 in the order of the values of the rows with vertices, k
-- from 1 within the tile.  The reference is made here from the Dump's
-- triangles and the source's vertices; only_tiled and only_ref count the
-- (triangle, tile) pairs missing from each side, a triangle as its
-- vertices from the smallest on, counter-clockwise (as both sides write it).
CREATE FUNCTION tiled_vs_ref(target regclass, src regclass, tile_column name,
	OUT only_tiled bigint, OUT only_ref bigint, OUT ids_by_tile boolean)
LANGUAGE plpgsql AS $$
DECLARE
	key constant text := 'CASE WHEN (x1, y1) <= (x2, y2) AND (x1, y1) <= (x3, y3) THEN ARRAY[x1, y1, x2, y2, x3, y3]
						   WHEN (x2, y2) <= (x3, y3) THEN ARRAY[x2, y2, x3, y3, x1, y1]
						   ELSE ARRAY[x3, y3, x1, y1, x2, y2] END';
	corners constant text := 'SELECT geom, %s AS t, ST_X(ST_PointN(r, 1)) AS x1, ST_Y(ST_PointN(r, 1)) AS y1,
								  ST_X(ST_PointN(r, 2)) AS x2, ST_Y(ST_PointN(r, 2)) AS y2,
								  ST_X(ST_PointN(r, 3)) AS x3, ST_Y(ST_PointN(r, 3)) AS y3
							 FROM %s, ST_ExteriorRing(geom) r';
BEGIN
	EXECUTE format('CREATE TEMP TABLE tr_v AS
					SELECT ST_X(d.geom) AS x, ST_Y(d.geom) AS y, s.%2$I AS t
					  FROM %1$s s, LATERAL ST_DumpPoints(_tdc_curve_to_line(s.geom)) d
					 WHERE s.geom IS NOT NULL', src, tile_column);
	CREATE TEMP TABLE tr_owner AS SELECT x, y, min(t) AS t FROM tr_v GROUP BY x, y;
	EXECUTE format('CREATE TEMP TABLE tr_ref AS SELECT k, o.t FROM (SELECT %s AS k FROM (%s) c) v
					  JOIN tr_owner o ON o.x = v.k[1] AND o.y = v.k[2]',
				   key, format(corners, 'NULL', format('ST_TDCDelaunayDump(%L)', 'SELECT geom FROM ' || src)));
	EXECUTE format('CREATE TEMP TABLE tr_out AS SELECT %s AS k, t FROM (%s) c', key, format(corners, 'tile', target));
	SELECT count(*) INTO only_tiled FROM (SELECT * FROM tr_out EXCEPT ALL SELECT * FROM tr_ref) x;
	SELECT count(*) INTO only_ref FROM (SELECT * FROM tr_ref EXCEPT ALL SELECT * FROM tr_out) x;
	EXECUTE format('SELECT coalesce(bool_and(id >> 32 = r.rank AND id & 4294967295 = k), true)
					  FROM (SELECT id, tile, row_number() OVER (PARTITION BY tile ORDER BY id) AS k FROM %s) o
					  JOIN (SELECT t, dense_rank() OVER (ORDER BY t) AS rank FROM (SELECT DISTINCT t FROM tr_v) v) r
						ON r.t = o.tile', target) INTO ids_by_tile;
	DROP TABLE tr_v, tr_owner, tr_ref, tr_out;
END $$;

-- uniform points, tiles from an integer column (a 4 x 4 grid)
SELECT setseed(0.25);
CREATE TABLE tt_uni AS
	SELECT i AS id, ST_MakePoint(x, y) AS geom, (floor(x / 25) * 4 + floor(y / 25))::int AS t
	  FROM (SELECT i, random() * 100 AS x, random() * 100 AS y FROM generate_series(1, 4000) i) s;
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_tri', tile_column => 't');
SELECT * FROM tiled_vs_dump('tt_uni_tri', 'SELECT geom FROM tt_uni');
SELECT * FROM tiled_vs_ref('tt_uni_tri', 'tt_uni', 't');
-- the target's shape: tile of the column's type, Polygon with the SRID
SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute
 WHERE attrelid = 'tt_uni_tri'::regclass AND attnum > 0 ORDER BY attnum;
SELECT count(DISTINCT tile) AS tiles FROM tt_uni_tri;
-- the staging tables are gone
SELECT count(*) AS staging FROM pg_class WHERE relname LIKE 'tdc_tiled%';

-- the same points as squares of tile_size, and with the automatic size
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_sq', tile_size => 15);
SELECT * FROM tiled_vs_dump('tt_uni_sq', 'SELECT geom FROM tt_uni');
SELECT count(DISTINCT tile) AS tiles FROM tt_uni_sq;
CALL tdc_delaunay_tiled('tt_uni', 'public.tt_uni_auto');
SELECT * FROM tiled_vs_dump('tt_uni_auto', 'SELECT geom FROM tt_uni');
-- Squares label the triangles of the core's run: each triangle has the
-- square a run tiled by the squares keeps it in.  The squares' labels as
-- a tile column (each tile keeps the triangles whose smallest vertex it
-- owns) give the same (triangle, tile) pairs.
ALTER TABLE tt_uni ADD COLUMN sq bigint;
UPDATE tt_uni SET sq = _tdc_square_label(ST_X(geom), ST_Y(geom), b.x0, b.y0, 15)
  FROM (SELECT min(ST_XMin(geom)) AS x0, min(ST_YMin(geom)) AS y0 FROM tt_uni) b;
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_sqcol', tile_column => 'sq');
SELECT * FROM tiled_vs_ref('tt_uni_sqcol', 'tt_uni', 'sq');
SELECT (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tt_uni_sq
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tt_uni_sqcol) x) AS only_squares,
	   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tt_uni_sqcol
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tt_uni_sq) x) AS only_column;
-- squares of any size: 40,000 squares of 0.5 for 4,000 points, 100 of 10
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_tiny', tile_size => 0.5);
SELECT * FROM tiled_vs_dump('tt_uni_tiny', 'SELECT geom FROM tt_uni');
SELECT count(DISTINCT tile) AS tiles FROM tt_uni_tiny;
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_ten', tile_size => 10);
SELECT * FROM tiled_vs_dump('tt_uni_ten', 'SELECT geom FROM tt_uni');
SELECT count(DISTINCT tile) AS tiles FROM tt_uni_ten;
-- 100 tiles
ALTER TABLE tt_uni ADD COLUMN t10 int;
UPDATE tt_uni SET t10 = floor(ST_X(geom) / 10) * 10 + floor(ST_Y(geom) / 10);
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_many', tile_column => 't10');
SELECT * FROM tiled_vs_dump('tt_uni_many', 'SELECT geom FROM tt_uni');
SELECT * FROM tiled_vs_ref('tt_uni_many', 'tt_uni', 't10');
SELECT count(DISTINCT tile) AS tiles FROM tt_uni_many;
-- tiles of text, whose order is not that of their numbers: 't10' < 't2'
ALTER TABLE tt_uni ADD COLUMN ttext text;
UPDATE tt_uni SET ttext = 't' || t10;
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_text', tile_column => 'ttext');
SELECT * FROM tiled_vs_ref('tt_uni_text', 'tt_uni', 'ttext');
SELECT (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), 't' || tile FROM tt_uni_many
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tt_uni_text) x) AS other_labels;
-- of varchar(4) (the target's column the same type), and of a type without
-- an ordering (refused before any row is written)
ALTER TABLE tt_uni ADD COLUMN tvar varchar(4);
UPDATE tt_uni SET tvar = 'q' || (t % 3);
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_var', tile_column => 'tvar');
SELECT * FROM tiled_vs_ref('tt_uni_var', 'tt_uni', 'tvar');
SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = 'tt_uni_var'::regclass AND attname = 'tile';
ALTER TABLE tt_uni ADD COLUMN tpt point;
UPDATE tt_uni SET tpt = point(t, 0);
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_column => 'tpt');
\set VERBOSITY default
SELECT to_regclass('tt_err') AS no_target;

-- the summary is a NOTICE, in one pass and in the core's run
-- (its DETAIL, the phases' seconds, is left out here)
SET client_min_messages = notice;
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_notice', tile_column => 't');
SET tdc_delaunay.max_memory = 100;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_notice_sq', tile_size => 50);
\set VERBOSITY default
RESET tdc_delaunay.max_memory;
SET client_min_messages = warning;

-- exact duplicates split across tiles, with different Z: one vertex, the Z
-- of its first copy in the source, as ST_TDCDelaunayDump keeps it
CREATE TABLE tt_dup (id int, geom geometry, t text);
INSERT INTO tt_dup
	SELECT i, ST_MakePoint(x, y, i), CASE WHEN x < 5 THEN 'west' ELSE 'east' END
	  FROM (SELECT i, (i * 7919 % 1000) / 100.0 AS x, (i * 104729 % 1000) / 100.0 AS y
			  FROM generate_series(1, 600) i) s;
-- copies of 100 points in the other tile, later in the source, other Z
INSERT INTO tt_dup
	SELECT 1000 + id, ST_MakePoint(ST_X(geom), ST_Y(geom), -id), CASE WHEN t = 'west' THEN 'east' ELSE 'west' END
	  FROM tt_dup WHERE id <= 100;
CALL tdc_delaunay_tiled('tt_dup', 'tt_dup_tri', tile_column => 't');
SELECT * FROM tiled_vs_dump('tt_dup_tri', 'SELECT geom FROM tt_dup');
-- a copied vertex belongs to the least tile among its copies ('east'),
-- not to its first copy's
SELECT * FROM tiled_vs_ref('tt_dup_tri', 'tt_dup', 't');
SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute
 WHERE attrelid = 'tt_dup_tri'::regclass AND attnum > 0 ORDER BY attnum;
SELECT tile, count(*) FROM tt_dup_tri GROUP BY tile ORDER BY tile;
-- no vertex has a negative Z (every copy with one came second)
SELECT count(*) AS negative_z FROM tt_dup_tri, ST_DumpPoints(geom) d WHERE ST_Z(d.geom) < 0;
-- the same without a tile column: one tile, in one pass, the same Z rule
SET client_min_messages = notice;
CALL tdc_delaunay_tiled('tt_dup', 'tt_dup_one');
SET client_min_messages = warning;
SELECT * FROM tiled_vs_dump('tt_dup_one', 'SELECT geom FROM tt_dup');
SELECT count(*) AS negative_z FROM tt_dup_one, ST_DumpPoints(geom) d WHERE ST_Z(d.geom) < 0;
SELECT DISTINCT tile FROM tt_dup_one;
-- squares of tile_size that hold every point are one tile too, named by its square
CALL tdc_delaunay_tiled('tt_dup', 'tt_dup_sq', tile_size => 20);
SELECT * FROM tiled_vs_dump('tt_dup_sq', 'SELECT geom FROM tt_dup');
SELECT DISTINCT tile FROM tt_dup_sq;

-- the tile aggregate takes its rows in any order and puts them back in
-- source order (seq, vi): the duplicate's Z is that of the smallest position
-- whatever order the rows come in
SELECT t.k, ST_AsText(t.geom) AS triangle
  FROM (SELECT _tdc_tile(g, 1, 1, '{-1,-1,3,3}', '{0,0,2,0,0,2}', '{}', seq, vi) AS r
		  FROM (SELECT * FROM (VALUES ('POINT Z (0 0 7)'::geometry, 9, 1), ('POINT Z (2 0 5)', 3, 2),
									  ('POINT Z (0 0 8)', 3, 1), ('POINT Z (0 2 6)', 3, 3),
									  ('POINT Z (0 0 9)', 3, 4)) v(g, seq, vi)
				 ORDER BY seq DESC, vi DESC) o) s,
	   LATERAL _tdc_tile_triangles(s.r) t;

-- a lattice: collinear rows and cocircular squares lying exactly on the tile
-- borders (tile_size 4 divides the spacing's multiples), as multipoints
CREATE TABLE tt_lat AS
	SELECT y AS id, ST_Collect(ST_MakePoint(x, y)) AS geom
	  FROM generate_series(0, 24) x, generate_series(0, 24) y GROUP BY y;
CALL tdc_delaunay_tiled('tt_lat', 'tt_lat_tri', tile_size => 4);
SELECT * FROM tiled_vs_dump('tt_lat_tri', 'SELECT geom FROM tt_lat');
-- a tile whose points are all collinear, and tiles of one point
CREATE TABLE tt_col (geom geometry, t int);
INSERT INTO tt_col SELECT ST_MakePoint(i, 0), 1 FROM generate_series(0, 20) i;
INSERT INTO tt_col VALUES ('POINT(3 5)', 2), ('POINT(15 -4)', 3), ('POINT(30 30)', 4);
CALL tdc_delaunay_tiled('tt_col', 'tt_col_tri', tile_column => 't');
SELECT * FROM tiled_vs_dump('tt_col_tri', 'SELECT geom FROM tt_col');
SELECT * FROM tiled_vs_ref('tt_col_tri', 'tt_col', 't');
-- curves, whole or inside collections, in several tiles: stroked as the
-- one-shot dump (and ST_DelaunayTriangles) strokes them, not their control
-- points
CREATE TABLE tt_curve (geom geometry, t int);
INSERT INTO tt_curve VALUES
	('CIRCULARSTRING(0 0, 10 10, 20 0)', 1),
	('GEOMETRYCOLLECTION(POINT(30 5), CURVEPOLYGON(CIRCULARSTRING(25 -10, 35 -10, 35 0, 25 0, 25 -10)))', 2),
	('MULTIPOINT(5 -5, 12 -8, 40 12)', 3), ('LINESTRING(-5 12, 22 14)', 3);
CALL tdc_delaunay_tiled('tt_curve', 'tt_curve_tri', tile_column => 't');
SELECT * FROM tiled_vs_dump('tt_curve_tri', 'SELECT geom FROM tt_curve');
SELECT * FROM tiled_vs_ref('tt_curve_tri', 'tt_curve', 't');
SELECT count(*) > 2 * (SELECT sum(ST_NPoints(geom)) FROM tt_curve) AS more_than_control_points FROM tt_curve_tri;
-- all collinear: no triangle, no error
CREATE TABLE tt_line AS SELECT ST_MakePoint(i, 2 * i) AS geom, i % 3 AS t FROM generate_series(1, 30) i;
CALL tdc_delaunay_tiled('tt_line', 'tt_line_tri', tile_column => 't');
SELECT count(*) FROM tt_line_tri;
-- an empty source: an empty target; an empty geometry names no tile, so
-- its tile may be NULL
CREATE TABLE tt_empty (geom geometry(Point, 4326), t int);
CALL tdc_delaunay_tiled('tt_empty', 'tt_empty_tri', tile_column => 't');
SELECT count(*), (SELECT format_type(atttypid, atttypmod) FROM pg_attribute
				   WHERE attrelid = 'tt_empty_tri'::regclass AND attname = 'geom') FROM tt_empty_tri;
INSERT INTO tt_col VALUES ('POINT EMPTY', NULL);
CALL tdc_delaunay_tiled('tt_col', 'tt_col_empty', tile_column => 't');
SELECT * FROM tiled_vs_ref('tt_col_empty', 'tt_col', 't');

-- a dense cluster inside a ring, tiles by quadrant: the triangles across
-- the empty annulus have circles far wider than a quadrant (the rounds on
-- Citus run some quadrants again with the box they ask for)
CREATE TABLE tt_ring (geom geometry, q int);
INSERT INTO tt_ring
	SELECT ST_MakePoint(x, y), (x >= 0)::int * 2 + (y >= 0)::int
	  FROM (SELECT 100 * cos(2 * pi() * i / 90) AS x, 100 * sin(2 * pi() * i / 90) AS y
			  FROM generate_series(0, 89) i
			UNION ALL
			SELECT (i % 40) / 20.0 - 1, (i / 40) / 20.0 - 1 FROM generate_series(0, 1599) i) s;
SET client_min_messages = notice;
CALL tdc_delaunay_tiled('tt_ring', 'tt_ring_tri', tile_column => 'q');
SET client_min_messages = warning;
SELECT * FROM tiled_vs_dump('tt_ring_tri', 'SELECT geom FROM tt_ring');
SELECT * FROM tiled_vs_ref('tt_ring_tri', 'tt_ring', 'q');


-- labels of squares count from the data's lower left corner: 5,000 points
-- at 5e6 + [0, 1e-3)^2 (floor(x / size) passes 2^31 there), squares of
-- 0.0006 and of 0.00025, and squares too small to count
SELECT setseed(0.375);
CREATE TABLE tt_far AS
	SELECT ST_MakePoint(5e6 + random() * 1e-3, 5e6 + random() * 1e-3) AS geom FROM generate_series(1, 5000);
CALL tdc_delaunay_tiled('tt_far', 'tt_far_tri', 'geom', NULL, 0.0006);
SELECT * FROM tiled_vs_dump('tt_far_tri', 'SELECT geom FROM tt_far');
SELECT DISTINCT tile FROM tt_far_tri ORDER BY tile;
CALL tdc_delaunay_tiled('tt_far', 'tt_far_tiny', 'geom', NULL, 0.00025);
SELECT * FROM tiled_vs_dump('tt_far_tiny', 'SELECT geom FROM tt_far');
SELECT count(DISTINCT tile) AS tiles, min(tile), max(tile) FROM tt_far_tiny;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tt_far', 'tt_err', 'geom', NULL, 1e-13);
\set VERBOSITY default

-- Clustered sets through a tile column and through automatic tiles: the
-- core's bounded run under tdc_delaunay.max_memory, as ./tdc --max-memory
-- runs it (_tdc_tiled_write), each the Dump's set.  The bounded run holds some
-- 9 MB of its own (the counting grid and its sums), and its grid is
-- uniform below 2^18 points and at the quantiles of a sample from there
-- on, so the automatic sets have 2^18 points: their one pass needs 38 MB.
-- (the plan depends on the engine's memory estimate, which depends on
-- the thread count: one thread, the same plan on every machine)
SET tdc_delaunay.threads = 1;
SELECT setseed(0.125);
-- 9 tight clusters
CREATE TABLE tt_c9 AS
	SELECT ST_MakePoint(cx + 0.3 * (random() - 0.5), cy + 0.3 * (random() - 0.5)) AS geom, k AS t
	  FROM (SELECT i AS k, (i % 3) * 100 AS cx, ((i / 3) % 3) * 100 AS cy FROM generate_series(0, 8) i) c,
		   generate_series(1, 1500);
-- a dense town in sparse country
CREATE TABLE tt_town AS
	SELECT ST_MakePoint(x, y) AS geom, (floor(x / 250) * 4 + floor(y / 250))::int AS t
	  FROM (SELECT random() * 1000 AS x, random() * 1000 AS y FROM generate_series(1, 5000)
			UNION ALL
			SELECT 600 + random() * 4, 400 + random() * 4 FROM generate_series(1, 5000)) s;
-- a strip with gaps
CREATE TABLE tt_strip AS
	SELECT ST_MakePoint(x, y) AS geom, floor(x / 100)::int AS t
	  FROM (SELECT random() * 2000 AS x, random() * 10 AS y FROM generate_series(1, 13000)) s
	 WHERE x::int % 200 NOT BETWEEN 60 AND 110;
-- a coastline: a wiggly line of dense points, a few inland
CREATE TABLE tt_coast AS
	SELECT ST_MakePoint(x, y) AS geom, floor(x / 200)::int AS t
	  FROM (SELECT u * 1000 AS x, 80 * sin(u * 9) + 25 * sin(u * 57) + 6 * sin(u * 301) + 0.01 * random() AS y
			  FROM (SELECT random() AS u FROM generate_series(1, 10000)) a
			UNION ALL
			SELECT random() * 1000, -400 + random() * 300 FROM generate_series(1, 1000)) s;
CALL tdc_delaunay_tiled('tt_c9', 'tt_c9_col', tile_column => 't');
CALL tdc_delaunay_tiled('tt_town', 'tt_town_col', tile_column => 't');
CALL tdc_delaunay_tiled('tt_strip', 'tt_strip_col', tile_column => 't');
CALL tdc_delaunay_tiled('tt_coast', 'tt_coast_col', tile_column => 't');
-- the same shapes with 2^18 points
SELECT setseed(0.375);
CREATE TABLE tb_c9 AS
	SELECT ST_MakePoint(cx + 0.3 * (random() - 0.5), cy + 0.3 * (random() - 0.5)) AS geom
	  FROM (SELECT (i % 3) * 100 AS cx, ((i / 3) % 3) * 100 AS cy FROM generate_series(0, 8) i) c,
		   generate_series(1, 29200);
CREATE TABLE tb_town AS
	SELECT ST_MakePoint(x, y) AS geom
	  FROM (SELECT random() * 1000 AS x, random() * 1000 AS y FROM generate_series(1, 131072)
			UNION ALL
			SELECT 600 + random() * 4, 400 + random() * 4 FROM generate_series(1, 131072)) s;
CREATE TABLE tb_strip AS
	SELECT ST_MakePoint(x, y) AS geom
	  FROM (SELECT random() * 2000 AS x, random() * 10 AS y FROM generate_series(1, 350000)) s
	 WHERE x::int % 200 NOT BETWEEN 60 AND 110;
CREATE TABLE tb_coast AS
	SELECT ST_MakePoint(x, y) AS geom
	  FROM (SELECT u * 1000 AS x, 80 * sin(u * 9) + 25 * sin(u * 57) + 6 * sin(u * 301) + 0.01 * random() AS y
			  FROM (SELECT random() AS u FROM generate_series(1, 240000)) a
			UNION ALL
			SELECT random() * 1000, -400 + random() * 300 FROM generate_series(1, 22144)) s;
-- one pass does not fit these limits; tiles do (the summary is a NOTICE,
-- its phases' seconds in the DETAIL)
SET tdc_delaunay.max_memory = 12;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tb_c9', 'tb_c9_auto');
\set VERBOSITY default
SET client_min_messages = warning;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_auto');
SET tdc_delaunay.max_memory = 10;
CALL tdc_delaunay_tiled('tb_strip', 'tb_strip_auto');
-- (the line and the far inland points make triangles that reach across
-- many tiles: the coast needs a larger limit)
SET tdc_delaunay.max_memory = 24;
CALL tdc_delaunay_tiled('tb_coast', 'tb_coast_auto');
RESET tdc_delaunay.max_memory;
SELECT s.name, v.*
  FROM (VALUES ('tb_c9_auto', 'tb_c9'), ('tt_c9_col', 'tt_c9'), ('tb_town_auto', 'tb_town'), ('tt_town_col', 'tt_town'),
			   ('tb_strip_auto', 'tb_strip'), ('tt_strip_col', 'tt_strip'),
			   ('tb_coast_auto', 'tb_coast'), ('tt_coast_col', 'tt_coast')) s(name, src),
	   LATERAL tiled_vs_dump(s.name::regclass, 'SELECT geom FROM ' || s.src) v;
-- each automatic plan has several tiles, numbered from 1 in the ids
SELECT s.name, (SELECT count(DISTINCT tile) > 1 FROM tb_c9_auto WHERE s.name = 'c9') OR
			   (SELECT count(DISTINCT tile) > 1 FROM tb_town_auto WHERE s.name = 'town') OR
			   (SELECT count(DISTINCT tile) > 1 FROM tb_strip_auto WHERE s.name = 'strip') OR
			   (SELECT count(DISTINCT tile) > 1 FROM tb_coast_auto WHERE s.name = 'coast') AS several
  FROM (VALUES ('c9'), ('town'), ('strip'), ('coast')) s(name);
SELECT bool_and(id >> 32 = tile AND tile >= 1) AS ids_by_tile FROM tb_c9_auto;
SELECT s.name, v.*
  FROM (VALUES ('tt_c9_col', 'tt_c9'), ('tt_town_col', 'tt_town'), ('tt_strip_col', 'tt_strip'),
			   ('tt_coast_col', 'tt_coast')) s(name, src),
	   LATERAL tiled_vs_ref(s.name::regclass, s.src::regclass, 't') v;
-- A tile column with the core's run in tiles: the tiles' labels ride with
-- the points through its files, and each vertex comes out with the least
-- of its copies'.  The town in quarters of an int column, and points with
-- Z, a third of them copies of earlier ones with another Z in another
-- tile, in tiles of text; each against the reference (the Dump's triangles,
-- each once, with their tiles) and against one pass, and no vertex with
-- the Z of a later copy.
ALTER TABLE tb_town ADD COLUMN t int;
UPDATE tb_town SET t = floor(ST_X(geom) / 500) * 2 + floor(ST_Y(geom) / 500);
SELECT setseed(0.625);
CREATE TABLE tb_dupz AS
	SELECT i, ST_MakePoint(random() * 1000, random() * 1000, i) AS geom FROM generate_series(1, 120000) i;
INSERT INTO tb_dupz
	SELECT 200000 + i, ST_MakePoint(ST_X(geom), ST_Y(geom), -i) FROM tb_dupz WHERE i % 2 = 0;
ALTER TABLE tb_dupz ADD COLUMN t text;
UPDATE tb_dupz SET t = 'band ' || ((i * 7) % 13);
SET tdc_delaunay.threads = 1;
-- (the town's labels, 8 bytes a vertex, leave no margin at 12 MB around its
-- dense square: PostgreSQL 17's backend, larger at the start, refused a
-- tile there.  Under 16 MB, far below one pass of its 262,144 points, it
-- runs in tiles, but how many reruns its dense square takes depends on the
-- backend's own memory, which differs between majors: no NOTICE here.)
SET tdc_delaunay.max_memory = 16;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_col', tile_column => 't');
SET tdc_delaunay.max_memory = 12;
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tb_dupz', 'tb_dupz_col', tile_column => 't');
\set VERBOSITY default
SET client_min_messages = warning;
RESET tdc_delaunay.max_memory;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_col1', tile_column => 't');
CALL tdc_delaunay_tiled('tb_dupz', 'tb_dupz_col1', tile_column => 't');
RESET tdc_delaunay.threads;
SELECT s.name, v.*
  FROM (VALUES ('tb_town_col', 'tb_town'), ('tb_dupz_col', 'tb_dupz')) s(name, src),
	   LATERAL tiled_vs_ref(s.name::regclass, s.src::regclass, 't') v;
SELECT (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile, id >> 32 FROM tb_dupz_col
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile, id >> 32 FROM tb_dupz_col1) x) AS only_tiles,
	   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile, id >> 32 FROM tb_dupz_col1
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile, id >> 32 FROM tb_dupz_col) x) AS only_one_pass,
	   (SELECT count(*) FROM tb_dupz_col, ST_DumpPoints(geom) d WHERE ST_Z(d.geom) < 0) AS negative_z;
-- squares label the same in tiles as in one pass
SET tdc_delaunay.max_memory = 12;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_sq', tile_size => 100);
RESET tdc_delaunay.max_memory;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_sq1', tile_size => 100);
SELECT (SELECT count(DISTINCT tile) FROM tb_town_sq) AS squares,
	   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tb_town_sq
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tb_town_sq1) x) AS only_tiles,
	   (SELECT count(*) FROM (SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tb_town_sq1
							  EXCEPT ALL SELECT ST_AsEWKB(ST_Normalize(geom)), tile FROM tb_town_sq) x) AS only_one_pass,
	   (SELECT count(DISTINCT id) = count(*) FROM tb_town_sq) AS ids_unique;
SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute
 WHERE attrelid = 'tb_c9_auto'::regclass AND attnum > 0 ORDER BY attnum;
-- 2^18 points, half of them uniform over a 100 square and half in a unit
-- square inside it: the plan's grid at the quantiles of the sample has
-- cells of about 1/256 in the dense square, where the uniform grid's cells
-- of 100/512 would hold some 5,000 points each.  The limits below the
-- floors are refused before any tile runs, with the numbers; a floor made
-- by exact copies of one point says so.
SELECT setseed(0.125);
CREATE TABLE tt_q AS
	SELECT ST_MakePoint(x, y) AS geom
	  FROM (SELECT random() * 100 AS x, random() * 100 AS y FROM generate_series(1, 131072)
			UNION ALL
			SELECT 50 + random(), 50 + random() FROM generate_series(1, 131072)) s;
CREATE TABLE tt_spot AS
	SELECT CASE WHEN i % 2 = 0 THEN ST_MakePoint(500, 500) ELSE ST_MakePoint(random() * 1000, random() * 1000) END AS geom
	  FROM generate_series(1, 262144) i;
SET tdc_delaunay.max_memory = 5;
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tt_q', 'tt_err');
SET tdc_delaunay.max_memory = 12;
CALL tdc_delaunay_tiled('tt_spot', 'tt_err');
-- a tile that cannot take what its triangles need within the limit
SET tdc_delaunay.max_memory = 9;
CALL tdc_delaunay_tiled('tb_c9', 'tt_err');
\set VERBOSITY default
RESET tdc_delaunay.max_memory;
RESET tdc_delaunay.threads;
SELECT to_regclass('tt_err') AS no_target, count(*) AS staging FROM pg_class WHERE relname LIKE 'tdc_tiled%';
-- nothing left in the temporary directory
SELECT count(*) AS tmp_left FROM pg_ls_dir('base/pgsql_tmp', true, false) f WHERE f LIKE 'pgsql_tmp%.tdc.%';

-- errors: each leaves no target behind
\set VERBOSITY terse
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', geom_column => 'nosuch');
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', geom_column => 'id');
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_column => 'nosuch');
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_column => 't', tile_size => 10);
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_size => -1);
CALL tdc_delaunay_tiled('tt_uni', 'tt_uni_tri');
CALL tdc_delaunay_tiled('nosuch_table', 'tt_err');
CREATE TABLE tt_srid (geom geometry);
INSERT INTO tt_srid VALUES ('SRID=4326;POINT(0 0)'), ('SRID=3857;POINT(1 1)'), ('SRID=4326;POINT(1 0)');
CALL tdc_delaunay_tiled('tt_srid', 'tt_err');
CREATE TABLE tt_nulltile AS SELECT geom, CASE WHEN id > 10 THEN t END AS t FROM tt_uni;
CALL tdc_delaunay_tiled('tt_nulltile', 'tt_err', tile_column => 't');
-- a limit below what the tiles need, for one square and for several
-- (the core's run is refused before any work, with the floor)
SET tdc_delaunay.max_memory = 1;
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_size => 1000);
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_size => 50);
-- the same limit with a tile column (quarters): the core's run is refused the same way
ALTER TABLE tt_uni ADD COLUMN q4 int;
UPDATE tt_uni SET q4 = floor(ST_X(geom) / 50) * 2 + floor(ST_Y(geom) / 50);
CALL tdc_delaunay_tiled('tt_uni', 'tt_err', tile_column => 'q4');
RESET tdc_delaunay.max_memory;
SELECT to_regclass('tt_err') AS no_target, count(*) AS staging FROM pg_class WHERE relname LIKE 'tdc_tiled%';
-- the existing target was not touched
SELECT count(*) FROM tt_uni_tri;
-- _tdc_tiled_write inserts rows without INSERT's checks: it takes only a
-- table its caller created in this transaction, with nothing that could
-- react to or restrict a row
CREATE TABLE tt_w (id bigint, tile bigint, geom geometry);
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w', NULL);
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile bigint, geom geometry);
CREATE INDEX ON tt_w2 (id);
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile bigint, geom geometry CHECK (ST_Area(geom) > 1));
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, geom geometry, tile bigint);
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile bigint, geom geometry(PolygonZ, 4326));
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
-- a tile column's type must be the target's, typmod included; without
-- one the target's is bigint; a query of (geom, tile) and nothing else;
-- not with squares
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile text, geom geometry);
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile bigint, geom geometry);
SELECT _tdc_tiled_write('SELECT geom, ttext FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile varchar(2), geom geometry);
SELECT _tdc_tiled_write('SELECT geom, tvar FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile int, geom geometry);
SELECT _tdc_tiled_write('SELECT geom, t, t FROM tt_uni', 'tt_w2', NULL);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile int, geom geometry);
SELECT _tdc_tiled_write('SELECT geom, t FROM tt_uni', 'tt_w2', 10);
ROLLBACK;
BEGIN;
CREATE TABLE tt_w2 (id bigint, tile bigint, geom geometry(Polygon));
SELECT _tdc_tiled_write('SELECT geom FROM tt_uni', 'tt_w2', NULL) AS written;
SELECT count(*) AS rows, count(DISTINCT id) AS ids FROM tt_w2;
ROLLBACK;
-- an XYM source: M is dropped, as the Delaunay functions drop it
CREATE TABLE tt_m AS SELECT ST_MakePointM(ST_X(geom), ST_Y(geom), id) AS geom FROM tt_uni;
CALL tdc_delaunay_tiled('tt_m', 'tt_m_tri');
SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = 'tt_m_tri'::regclass AND attname = 'geom';
SELECT * FROM tiled_vs_dump('tt_m_tri', 'SELECT geom FROM tt_m');

-- cancel (statement_timeout) during a tile: no target, no staging table,
-- no temporary file, server alive; for the core's run with a tile column
-- (16 tiles, their labels in its files) and without (automatic tiles).
-- Where the tiles fall in a call, and how long a call takes, vary with the
-- machine's load, so the timeout is found by bisection: a try cancelled
-- before the tiles (its context is a staging statement of the procedure,
-- or the bounded run reading the source) raises the lower bound, a try
-- that finished, or was cancelled after the tiles (the bounded run writing
-- its rows), lowers the upper bound,
-- and the next try waits halfway between the latest of each.  It stops at
-- the first cancel whose context shows a tile running: "running the
-- tiles".
CREATE TABLE tt_bigger AS
	SELECT geom, (floor(ST_X(geom) * 4) * 4 + floor(ST_Y(geom) * 4))::int AS t
	  FROM (SELECT ST_MakePoint(random(), random()) AS geom FROM generate_series(1, 300000)) s;
CREATE TEMP TABLE tt_cancel (kind text, try serial, ms int, outcome text);
-- the call of each kind, under tdc_delaunay.max_memory = 12 (one pass of
-- tt_bigger would need 43 MB)
CREATE FUNCTION tt_call(kind text, target text) RETURNS void LANGUAGE plpgsql AS $$
BEGIN
	IF kind = 'column' THEN
		CALL tdc_delaunay_tiled('tt_bigger', target, tile_column => 't');
	ELSE
		CALL tdc_delaunay_tiled('tt_bigger', target);
	END IF;
END $$;
CREATE FUNCTION tt_call_ms(kind text) RETURNS int LANGUAGE plpgsql AS $$
DECLARE
	t0 timestamptz := clock_timestamp();
BEGIN
	PERFORM tt_call(kind, 'tt_big_ok');
	DROP TABLE tt_big_ok;
	RETURN ceil(extract(epoch FROM clock_timestamp() - t0) * 1000);
END $$;
CREATE FUNCTION tt_arm(kind text) RETURNS void LANGUAGE plpgsql AS $$
DECLARE
	lo int := coalesce((SELECT ms FROM tt_cancel c WHERE c.kind = tt_arm.kind AND outcome = 'before'
						ORDER BY try DESC LIMIT 1), 0);
	hi int := coalesce((SELECT ms FROM tt_cancel c WHERE c.kind = tt_arm.kind AND outcome = 'after'
						ORDER BY try DESC LIMIT 1), current_setting('tt.call_ms_' || kind)::int);
BEGIN
	PERFORM set_config('statement_timeout', greatest((lo + hi) / 2, 1)::text, false);
END $$;
CREATE FUNCTION tt_try_cancel(kind text) RETURNS void LANGUAGE plpgsql AS $$
DECLARE
	ms int := (SELECT setting::int FROM pg_settings WHERE name = 'statement_timeout');
	ctx text;
BEGIN
	IF EXISTS (SELECT 1 FROM tt_cancel c WHERE c.kind = tt_try_cancel.kind AND outcome = 'tile') THEN
		RETURN;
	END IF;
	PERFORM tt_call(kind, 'tt_big_tri');
	DROP TABLE tt_big_tri;
	INSERT INTO tt_cancel (kind, ms, outcome) VALUES (kind, ms, 'after');
EXCEPTION WHEN query_canceled THEN
	GET STACKED DIAGNOSTICS ctx = PG_EXCEPTION_CONTEXT;
	INSERT INTO tt_cancel (kind, ms, outcome)
		VALUES (kind, ms, CASE WHEN ctx LIKE '%tdc_delaunay_tiled: running the tiles%' THEN 'tile'
							   WHEN ctx LIKE '%tdc_delaunay_tiled: reading the source%' THEN 'before'
							   WHEN ctx LIKE '%tdc_delaunay_tiled: writing the rows%' THEN 'after'
							   WHEN ctx LIKE '%PL/pgSQL function tdc_delaunay_tiled(%' THEN 'before'
							   ELSE 'after' END);
END $$;
SET tdc_delaunay.max_memory = 12;
SELECT set_config('tt.call_ms_column', tt_call_ms('column')::text, false) IS NOT NULL AS measured,
	   set_config('tt.call_ms_bounded', tt_call_ms('bounded')::text, false) IS NOT NULL AS measured_bounded;
-- (each try prints an empty row: only the statements are shown)
\o /dev/null
SELECT q FROM generate_series(1, 16) i, (VALUES ('column'), ('bounded')) k(kind),
	   (VALUES (1, 'SELECT tt_arm(%L)'), (2, 'SELECT tt_try_cancel(%L)')) v(o, q0),
	   LATERAL format(v.q0, k.kind) q
 ORDER BY k.kind DESC, i, o \gexec
\o
RESET statement_timeout;
RESET tdc_delaunay.max_memory;
SELECT kind, bool_or(outcome = 'tile') AS cancelled_during_a_tile FROM tt_cancel GROUP BY kind ORDER BY kind;
SELECT to_regclass('tt_big_tri') AS no_target, count(*) AS staging FROM pg_class WHERE relname LIKE 'tdc_tiled%';
SELECT count(*) AS tmp_left FROM pg_ls_dir('base/pgsql_tmp', true, false) f WHERE f LIKE 'pgsql_tmp%.tdc.%';
SELECT 1 AS alive;
\set VERBOSITY default

-- Memory: with a tile column the backend stays within
-- tdc_delaunay.max_memory beside the shared buffers it touched.  In a new
-- backend, after its libraries are loaded, the private memory it holds
-- (VmRSS less the shared memory it maps, RssShmem), then the 2^18 points
-- of the town in 4 tiles under max_memory = 16 MB, then its peak (VmHWM,
-- which counts the shared memory it touched, never more than it maps at
-- the end): peak <= private memory before + limit + shared memory after.
-- (One thread: the plan depends on the thread count.)
\c
SET client_min_messages = warning;
SELECT ST_X(ST_MakePoint(1, 2)) AS x, tdc_delaunay_full_version() IS NOT NULL AS loaded;
CREATE TEMP TABLE tt_mem AS
	SELECT substring(s FROM 'VmRSS:\s*([0-9]+) kB')::bigint - substring(s FROM 'RssShmem:\s*([0-9]+) kB')::bigint AS private_kb
	  FROM pg_read_file('/proc/self/status') s;
SET tdc_delaunay.threads = 1;
SET tdc_delaunay.max_memory = 16;
CALL tdc_delaunay_tiled('tb_town', 'tb_town_mem', tile_column => 't');
SELECT substring(s FROM 'VmHWM:\s*([0-9]+) kB')::bigint
		 <= m.private_kb + 16 * 1024 + substring(s FROM 'RssShmem:\s*([0-9]+) kB')::bigint AS within_limit,
	   (SELECT count(*) FROM tb_town_mem) = (SELECT count(*) FROM tb_town_col1) AS all_triangles
  FROM pg_read_file('/proc/self/status') s, tt_mem m;
RESET tdc_delaunay.max_memory;
RESET tdc_delaunay.threads;

DROP TABLE tt_uni, tt_uni_tri, tt_uni_sq, tt_uni_auto, tt_uni_many, tt_uni_notice, tt_uni_notice_sq, tt_uni_sqcol, tt_uni_tiny, tt_uni_ten, tt_dup, tt_dup_tri, tt_dup_one, tt_dup_sq, tt_lat, tt_lat_tri,
	tt_col, tt_col_tri, tt_line, tt_line_tri, tt_empty, tt_empty_tri, tt_ring, tt_ring_tri, tt_srid, tt_nulltile,
	tt_far, tt_far_tri, tt_far_tiny, tt_c9, tt_c9_col, tt_town, tt_town_col,
	tt_strip, tt_strip_col, tt_coast, tt_coast_col, tt_q, tt_spot, tt_bigger, tt_w, tt_m, tt_m_tri,
	tb_c9, tb_c9_auto, tb_town, tb_town_auto, tb_town_sq, tb_town_sq1, tb_strip, tb_strip_auto, tb_coast, tb_coast_auto,
	tt_uni_text, tt_uni_var, tt_col_empty, tb_town_col, tb_town_col1, tb_town_mem, tb_dupz, tb_dupz_col, tb_dupz_col1;
DROP FUNCTION tiled_vs_dump(regclass, text);
DROP FUNCTION tiled_vs_ref(regclass, regclass, name);
DROP FUNCTION tt_call(text, text);
DROP FUNCTION tt_call_ms(text);
DROP FUNCTION tt_try_cancel(text);
DROP FUNCTION tt_arm(text);
