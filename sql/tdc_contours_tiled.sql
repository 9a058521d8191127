--
-- tdc_contours_tiled: the contour lines of a table's samples into a table
-- of lines, equal as a set (and in order) to the lines of ST_TDCContours
-- over all the samples: in one pass, and through the core's bounded run
-- under a tdc_delaunay.max_memory that one pass does not fit.  Then its
-- refusals, none of which leaves a target.
--
-- (the plan depends on the engine's memory estimate, which depends on the
-- thread count: one thread, the same plan on every machine)
SET tdc_delaunay.threads = 1;

-- A table of lines against ST_TDCContours over the same samples: lines
-- (exact, as WKB) in the table and not among ST_TDCContours's, the other
-- way round, rows whose id is not the position of their line there or
-- whose level is not their points' Z, and the geometry column's type.
CREATE FUNCTION ct_check(lines regclass, src text, "interval" float8, base float8)
RETURNS TABLE (nlines bigint, extra bigint, missing bigint, bad_id bigint, bad_level bigint, coltype text)
LANGUAGE plpgsql AS $$
BEGIN
	RETURN QUERY EXECUTE format($q$
		WITH one AS (SELECT d.path[1] AS id, ST_AsBinary(d.geom) AS g
					   FROM (SELECT (ST_Dump(ST_TDCContours(geom, $1, $2))).* FROM %2$s) d),
			 t AS (SELECT id, level, geom, ST_AsBinary(geom) AS g FROM %1$s)
		SELECT (SELECT count(*) FROM t),
			   (SELECT count(*) FROM (SELECT g FROM t EXCEPT ALL SELECT g FROM one) a),
			   (SELECT count(*) FROM (SELECT g FROM one EXCEPT ALL SELECT g FROM t) a),
			   (SELECT count(*) FROM t LEFT JOIN one USING (id) WHERE one.g IS DISTINCT FROM t.g),
			   (SELECT count(*) FROM t WHERE EXISTS (SELECT FROM ST_DumpPoints(t.geom) p WHERE ST_Z(p.geom) <> t.level)),
			   (SELECT format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = %3$L::regclass AND attname = 'geom')$q$,
		lines, src, lines)
	  USING "interval", base;
END $$;

-- The samples: 4 clusters of 500, then 9 clusters of 29,200 (2^18 and a
-- few: below 2^18 points the bounded run's grid is uniform, and it holds
-- some 9 MB of its own, so one pass of a small set always fits a limit the
-- run fits).
SELECT setseed(0.5);
CREATE TABLE ct_small AS
	SELECT ST_SetSRID(ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5), 3006) AS geom
	  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
			  FROM (SELECT (i % 2) * 60 AS cx, (i / 2) * 50 AS cy FROM generate_series(0, 3) i) c,
				   generate_series(1, 500)) q;
CREATE TABLE ct_c9 AS
	SELECT ST_MakePoint(x, y, sin(x / 7) * 10 + cos(y / 5) * 5) AS geom
	  FROM (SELECT cx + 30 * (random() - 0.5) AS x, cy + 30 * (random() - 0.5) AS y
			  FROM (SELECT (i % 3) * 100 AS cx, ((i / 3) % 3) * 100 AS cy FROM generate_series(0, 8) i) c,
				   generate_series(1, 29200)) q;

-- one pass (the summary is a NOTICE)
SET client_min_messages = notice;
\set VERBOSITY terse
CALL tdc_contours_tiled('ct_small', 'ct_small_lines', 'geom', 2.5, 0.3);
-- the bounded run: one pass of ct_c9 does not fit 16 MB
SET tdc_delaunay.max_memory = 16;
CALL tdc_contours_tiled('ct_c9', 'ct_c9_lines', 'geom', 1.25);
RESET tdc_delaunay.max_memory;
\set VERBOSITY default
SET client_min_messages = warning;
SELECT 'small' AS src, * FROM ct_check('ct_small_lines', 'ct_small', 2.5, 0.3)
UNION ALL
SELECT 'c9', * FROM ct_check('ct_c9_lines', 'ct_c9', 1.25, 0);

-- Refusals: each a clear error, and none leaves its target.
\set VERBOSITY terse
CALL tdc_contours_tiled('ct_small', 'ct_bad', 'geom', 0);
CALL tdc_contours_tiled('ct_small', 'ct_bad', 'geom', 'infinity');
CALL tdc_contours_tiled('ct_small', 'ct_bad', 'geom', 1, 'NaN');
CALL tdc_contours_tiled('ct_small', 'ct_bad', 'geom', NULL);
CALL tdc_contours_tiled('ct_small', 'ct_small_lines', 'geom', 1);
CALL tdc_contours_tiled('ct_nosuch', 'ct_bad', 'geom', 1);
CALL tdc_contours_tiled('ct_small', 'ct_bad', 'nosuch', 1);
CREATE TABLE ct_flat AS SELECT ST_MakePoint(i, i * i % 7) AS geom FROM generate_series(1, 10) i;
CALL tdc_contours_tiled('ct_flat', 'ct_bad', 'geom', 1);
-- a cancel (here a statement timeout) stops it, in the read or the run
SET tdc_delaunay.max_memory = 16;
SET statement_timeout = '300ms';
CALL tdc_contours_tiled('ct_c9', 'ct_bad', 'geom', 1.25);
RESET statement_timeout;
RESET tdc_delaunay.max_memory;
\set VERBOSITY default
SELECT to_regclass('ct_bad') IS NULL AS no_target_left;
-- nor any file: the runs' directories under pgsql_tmp are gone
SELECT count(*) AS tmp_left FROM pg_ls_dir('base/pgsql_tmp', true, false) f WHERE f LIKE 'pgsql_tmp%.tdc.%';

DROP TABLE ct_small, ct_c9, ct_flat, ct_small_lines, ct_c9_lines;
DROP FUNCTION ct_check(regclass, text, float8, float8);
RESET tdc_delaunay.threads;
RESET client_min_messages;
