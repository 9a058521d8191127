-- src/sql/contours_tiled.sql: tdc_contours_tiled, the contour lines of a
-- table's samples into a table (C side: src/pg/fn/fn_contours_tiled.c)

CREATE FUNCTION _tdc_contours_tiled_write(query text, target regclass, "interval" float8, base float8,
										  geom_type regtype)
RETURNS bigint
AS 'MODULE_PATHNAME', '_tdc_contours_tiled_write'
LANGUAGE C VOLATILE PARALLEL UNSAFE
COST 10000;

COMMENT ON FUNCTION _tdc_contours_tiled_write(text, regclass, float8, float8, regtype) IS
'Internal, for tdc_contours_tiled: the contour lines at base + k * interval of the TIN of the query''s vertices '
'(its geometry column, of type geom_type) written into target (id bigint, level float8, geom geometry(LineStringZ)), '
'one row per line: in one pass when it fits tdc_delaunay.max_memory, else tile by tile through the core''s bounded run. '
'Returns the lines written.';

-- The procedure: the arguments checked, the target made with the first
-- row's SRID, and the work done by _tdc_contours_tiled_write in one call,
-- in the caller's transaction: an error or a cancel leaves no target.
--
-- On Citus the source may be distributed (or a reference table): the SRID
-- probe and the read are two distributed SELECTs, whatever the tiles, and
-- the target is a plain table of the coordinator, where the lines are made
-- (the TIN covers all the samples): test/citus/run.sh.
CREATE PROCEDURE tdc_contours_tiled(source text, target text, geom_column text, "interval" float8,
									base float8 DEFAULT 0, filter text DEFAULT NULL)
LANGUAGE plpgsql
-- the source is read in its order, as ST_TDCContours reads it (the first
-- copy of a duplicate gives its Z)
SET synchronize_seqscans = off
AS $proc$
DECLARE
	fn constant text := 'tdc_contours_tiled';
	src regclass;
	gtyp regtype;
	pc boolean;
	srid int;
	tparts text[];
	qtarget text;
BEGIN
	IF source IS NULL OR target IS NULL OR geom_column IS NULL THEN
		RAISE EXCEPTION '%: source, target and geom_column must not be NULL', fn
			USING ERRCODE = 'null_value_not_allowed';
	END IF;
	IF "interval" IS NULL OR NOT ("interval" > 0 AND "interval" < 'infinity'::float8) THEN
		RAISE EXCEPTION '%: interval must be a finite number > 0, not %', fn, coalesce("interval"::text, 'NULL')
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	IF base IS NULL OR NOT (base > '-infinity'::float8 AND base < 'infinity'::float8) THEN
		RAISE EXCEPTION '%: base must be a finite number, not %', fn, coalesce(base::text, 'NULL')
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	src := to_regclass(source);
	IF src IS NULL THEN
		RAISE EXCEPTION '%: source "%" does not exist', fn, source
			USING ERRCODE = 'undefined_table';
	END IF;
	gtyp := _tdc_tiled_geometry(fn, src, geom_column, filter);
	pc := (SELECT t.typname = 'pcpatch' FROM pg_type t WHERE t.oid = gtyp);
	-- the target: never overwritten
	tparts := _tdc_tiled_target(fn, target);
	qtarget := format('%I.%I', tparts[1], tparts[2]);
	IF pc THEN
		-- the first patch's format (tdc_delaunay_pointcloud)
		srid := _tdc_pc_column_srid(src, geom_column);
	ELSE
		EXECUTE format('SELECT ST_SRID(s.%1$I) FROM %2$s s WHERE s.%1$I IS NOT NULL LIMIT 1', geom_column, src)
		   INTO srid;
	END IF;
	EXECUTE format('CREATE TABLE %s (id bigint, level float8, geom %s(LineStringZ, %s))', qtarget,
				   CASE WHEN pc THEN 'geometry'::regtype ELSE gtyp END, coalesce(srid, 0));
	IF pc THEN
		-- the pcpatch form of the internal function (tdc_delaunay_pointcloud)
		PERFORM _tdc_contours_tiled_write(format('SELECT %I FROM %s', geom_column, src), qtarget::regclass,
										  "interval", base, gtyp, filter);
	ELSE
		PERFORM _tdc_contours_tiled_write(format('SELECT %I FROM %s', geom_column, src), qtarget::regclass,
										  "interval", base, gtyp);
	END IF;
END
$proc$;

COMMENT ON PROCEDURE tdc_contours_tiled(text, text, text, float8, float8, text) IS
'Contour lines at the levels base + k * interval of the TIN of the vertices of source.geom_column (heights from Z; '
'a pcpatch column with tdc_delaunay_pointcloud: its points'' X, Y, Z, those the filter ''dimension=value[,...]'' keeps) '
'into a new table target(id bigint, level float8, geom geometry(LineStringZ, srid)), one row per line, id 1.. in '
'the order of ST_TDCContours''s lines (levels increasing), each its level as Z: the lines of ST_TDCContours, in one '
'pass or, when that would not fit tdc_delaunay.max_memory, through the core''s bounded run.';
