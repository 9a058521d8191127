-- src/sql/tiled.sql: the procedure tdc_delaunay_tiled, in PL/pgSQL over the
-- internal functions of src/sql/tiled_internals.sql

-- The procedure.  On plain PostgreSQL it makes the target and hands the
-- source to _tdc_tiled_write (src/pg/fn/fn_tiled_bounded.c), with the tile
-- column beside the geometry when there is one: one pass, or when that
-- would not fit tdc_delaunay.max_memory the core's bounded run (the tiles
-- of ./tdc --max-memory).  The tiles only label the triangles: each is kept
-- once, labelled by the tile that owns its smallest vertex (a vertex owned
-- by the least tile value among its copies), as a run of those tiles with
-- their halos keeps it; or by the square of tile_size holding that vertex.
-- On Citus, when source is distributed by tile_column, the tiles run on the
-- workers in rounds over staging tables: pts (every vertex, with the tile
-- owning it and its position in the source), tiles (one row per tile:
-- label, extent, known box K), halo (for every pending tile, the points
-- inside its K) and the target, pts, halo and the target distributed on
-- the tile column and co-located with source, tiles a reference table.  A
-- round is one INSERT ... SELECT ... GROUP BY tile that runs every pending
-- tile on the workers; a tile whose stars are not all final writes one
-- marker row (id -1, its needed box) instead of triangles, and the next
-- round reruns it with a larger K.  Everything happens in the caller's
-- transaction: an error or a cancel leaves no target behind.
CREATE PROCEDURE tdc_delaunay_tiled(source regclass, target text, geom_column name DEFAULT 'geom',
									tile_column name DEFAULT NULL, tile_size float8 DEFAULT NULL,
									filter text DEFAULT NULL)
LANGUAGE plpgsql
-- a tile's statement is estimated at millions of rows, and compiling it
-- cost a second per tile; boxes and the hull pass through the statements'
-- text, so floats must print exactly
SET jit = off
SET extra_float_digits = 3
-- the source is read in its order, as the Dump reads it (the first copy of
-- a duplicate gives its Z)
SET synchronize_seqscans = off
AS $proc$
DECLARE
	fn constant text := 'tdc_delaunay_tiled';
	gtyp regtype;
	pc boolean;
	ttype text := 'bigint';
	tv text;					-- SQL of a vertex's tile value
	stroked text;				-- SQL of a row's geometry with its arcs stroked
	citus boolean := false;
	npts bigint;
	srid_lo int; srid_hi int; zm_lo int; zm_hi int;
	gx0 float8; gy0 float8; gx1 float8; gy1 float8;
	w float8; h float8; spacing float8;
	hull float8[];
	extent float8[];			-- {xmin, ymin, xmax, ymax} the policy sizes tiles by
	tparts text[];
	tschema text; tname text; qtarget text;
	pts text; tiles text; rt text; halo text;
	ntiles bigint; done bigint; pending bigint; rerun bigint;
	round int := 0;
	has_null boolean;
	halo_pts bigint := 0;
	ntri bigint;
	r record;
	tile_sql text;
	tile_box text;
BEGIN
	-- the geometry column, or a pcpatch column (tdc_delaunay_pointcloud)
	gtyp := _tdc_tiled_geometry(fn, source, geom_column, filter);
	pc := (SELECT t.typname = 'pcpatch' FROM pg_type t WHERE t.oid = gtyp);
	-- the tiles
	IF tile_column IS NOT NULL THEN
		SELECT format_type(a.atttypid, a.atttypmod) INTO ttype
		  FROM pg_attribute a
		 WHERE a.attrelid = source AND a.attname = tile_column AND a.attnum > 0 AND NOT a.attisdropped;
		IF NOT FOUND THEN
			RAISE EXCEPTION '%: tile column "%" of relation % does not exist', fn, tile_column, source
				USING ERRCODE = 'undefined_column';
		END IF;
		IF tile_size IS NOT NULL THEN
			RAISE EXCEPTION '%: give tile_column or tile_size, not both', fn
				USING ERRCODE = 'invalid_parameter_value';
		END IF;
	ELSIF tile_size IS NOT NULL AND NOT (tile_size > 0 AND tile_size < 'infinity'::float8) THEN
		RAISE EXCEPTION '%: tile_size must be positive and finite, not %', fn, tile_size
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	-- the target: never overwritten
	tparts := _tdc_tiled_target(fn, target);
	tschema := tparts[1];
	tname := tparts[2];
	qtarget := format('%I.%I', tschema, tname);
	-- Citus: source distributed by hash of tile_column
	IF tile_column IS NOT NULL AND to_regclass('pg_catalog.pg_dist_partition') IS NOT NULL THEN
		EXECUTE 'SELECT EXISTS (SELECT 1 FROM pg_dist_partition WHERE logicalrelid = $1 AND partmethod = ''h''
					AND column_to_column_name(logicalrelid, partkey) = $2)'
		   INTO citus USING source, tile_column;
	END IF;
	IF citus AND pc THEN
		RAISE EXCEPTION '%: a pcpatch column is not read by the rounds on Citus workers', fn
			USING ERRCODE = 'feature_not_supported',
				  HINT = 'Call tdc_delaunay_tiled without tile_column: the coordinator reads the patches, in tiles '
						 'that fit tdc_delaunay.max_memory.';
	END IF;
	IF citus THEN
		-- The staging tables are written and then read by other statements of
		-- this one transaction (the halo is repartitioned from pts); Citus
		-- allows that only over one connection per worker, chosen before the
		-- transaction's first distributed query.
		PERFORM set_config('citus.multi_shard_modify_mode', 'sequential', true);
		-- the tiles run on the workers: they must see this session's
		-- tdc_delaunay.max_memory (Citus passes on SET LOCAL only)
		PERFORM set_config('citus.propagate_set_commands', 'local', true);
		IF current_setting('tdc_delaunay.max_memory', true) IS NOT NULL THEN
			EXECUTE format('SET LOCAL tdc_delaunay.max_memory = %L', current_setting('tdc_delaunay.max_memory'));
		END IF;
	END IF;

	-- On plain PostgreSQL (and on Citus without a source distributed by
	-- tile_column): _tdc_tiled_write (src/pg/fn/fn_tiled_bounded.c) reads the
	-- source once, as ST_TDCDelaunayDump reads it, with the tile column
	-- beside the geometry when there is one, and triangulates it in one pass
	-- while that fits tdc_delaunay.max_memory, else tile by tile through the
	-- core's bounded run, as ./tdc --max-memory does (tiles cut by counts,
	-- halos and reruns in files under pgsql_tmp); it writes the rows
	-- straight into the target, which must exist first.  The first row's
	-- SRID and dimensions give the target's type (M is dropped, as the
	-- Delaunay functions drop it), and every other row must agree.  A tile
	-- column labels each triangle with the tile owning its smallest vertex
	-- (a vertex is owned by the least tile value among its copies), id
	-- rank * 2^32 + k with rank the tile's from 1 in the values' order;
	-- squares of tile_size label it with the square holding that vertex,
	-- column * 2^32 + row counted from the vertices' lower left corner
	-- (_tdc_square_label).
	IF NOT citus AND pc THEN
		-- patches: X, Y and Z, the SRID of the first patch's format
		srid_lo := _tdc_pc_column_srid(source, geom_column);
		zm_lo := 2;
	ELSIF NOT citus THEN
		EXECUTE format('SELECT ST_SRID(s.%1$I), ST_Zmflag(s.%1$I) FROM %2$s s WHERE s.%1$I IS NOT NULL LIMIT 1',
					   geom_column, source)
		   INTO srid_lo, zm_lo;
	END IF;
	IF NOT citus THEN
		EXECUTE format('CREATE TABLE %s (id bigint, tile %s, geom geometry(%s, %s))', qtarget, ttype,
					   CASE WHEN zm_lo IN (2, 3) THEN 'PolygonZ' ELSE 'Polygon' END, coalesce(srid_lo, 0));
		tile_sql := CASE WHEN tile_column IS NULL THEN format('SELECT %I FROM %s', geom_column, source)
						 ELSE format('SELECT %I, %I FROM %s', geom_column, tile_column, source) END;
		IF pc THEN
			-- the pcpatch form of the internal function (tdc_delaunay_pointcloud)
			PERFORM _tdc_tiled_write(tile_sql, qtarget::regclass, tile_size, gtyp, filter);
		ELSE
			PERFORM _tdc_tiled_write(tile_sql, qtarget::regclass, tile_size);
		END IF;
		RETURN;
	END IF;

	-- Citus, the source distributed by tile_column: the rounds.
	-- A value with arcs is stroked as ST_TDCDelaunayDump strokes it (see
	-- curves.c); GeometryType reads only the header, so only collections
	-- and curve types are looked into.
	stroked := format('CASE WHEN GeometryType(s.%1$I) IN (''CIRCULARSTRING'', ''COMPOUNDCURVE'', ''CURVEPOLYGON'',
															 ''MULTICURVE'', ''MULTISURFACE'', ''GEOMETRYCOLLECTION'')
							 THEN _tdc_curve_to_line(s.%1$I) ELSE s.%1$I END', geom_column);

	-- SRID and dimensions, as ST_TDCDelaunayDump checks them, and the number
	-- and extent of the vertices (the extent from the values' boxes, which
	-- may be rounded outward: it only sizes the tiles)
	EXECUTE format('SELECT min(ST_SRID(s.%1$I)), max(ST_SRID(s.%1$I)), min(ST_Zmflag(s.%1$I)), max(ST_Zmflag(s.%1$I)),
						   coalesce(sum(ST_NPoints(%3$s)), 0), min(ST_XMin(s.%1$I)), min(ST_YMin(s.%1$I)),
						   max(ST_XMax(s.%1$I)), max(ST_YMax(s.%1$I))
					  FROM %2$s s WHERE s.%1$I IS NOT NULL', geom_column, source, stroked)
	   INTO srid_lo, srid_hi, zm_lo, zm_hi, npts, gx0, gy0, gx1, gy1;
	IF srid_lo <> srid_hi THEN
		RAISE EXCEPTION '%: mixed SRIDs in %.% (% and %)', fn, source, geom_column, srid_lo, srid_hi
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	IF zm_lo <> zm_hi THEN
		RAISE EXCEPTION '%: mixed dimensions in %.% (with and without Z or M)', fn, source, geom_column
			USING ERRCODE = 'invalid_parameter_value';
	END IF;
	w := coalesce(gx1 - gx0, 0);
	h := coalesce(gy1 - gy0, 0);
	spacing := CASE WHEN npts > 0 AND w * h > 0 THEN sqrt(w * h / npts)
					WHEN npts > 0 AND w + h > 0 THEN (w + h) / npts
					ELSE 1 END;
	extent := ARRAY[gx0, gy0, gx1, gy1];

	-- the staging tables, distributed
	pts := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_pts');
	tiles := 'pg_temp.tdc_tiled_tiles';
	rt := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_tiles');
	halo := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_halo');
	EXECUTE format('CREATE TABLE %s (tile %s, seq bigint, vi bigint, g geometry)', pts, ttype);
	EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', pts, 'tile', source::text);

	-- every vertex, in the source's order (block, offset, vertex), with its
	-- tile: the tile column's value
	tv := format('s.%I', tile_column);
	EXECUTE format('INSERT INTO %s (tile, seq, vi, g)
					SELECT %s, ((s.ctid::text::point)[0])::bigint * 65536 + ((s.ctid::text::point)[1])::bigint,
						   d.vi, d.geom
					  FROM %s s, LATERAL ST_DumpPoints(%s) WITH ORDINALITY AS d(path, geom, vi)
					 WHERE s.%I IS NOT NULL', pts, tv, source, stroked, geom_column);
	EXECUTE format('SELECT EXISTS (SELECT 1 FROM %s WHERE tile IS NULL)', pts) INTO has_null;
	IF has_null THEN
		RAISE EXCEPTION '%: tile column "%" of % is NULL for some rows with a geometry', fn, tile_column, source
			USING ERRCODE = 'null_value_not_allowed';
	END IF;

	-- the tiles, labelled 1.. in the order of their tile values
	EXECUTE format('CREATE TEMP TABLE %1$s AS
					SELECT tile, row_number() OVER (ORDER BY tile) AS label, n, x0, y0, x1, y1,
						   NULL::float8[] AS region, NULL::float8[] AS known, NULL::float8[] AS extra,
						   true AS pending
					  FROM (SELECT tile, count(*) AS n, min(ST_X(g)) AS x0, min(ST_Y(g)) AS y0,
								   max(ST_X(g)) AS x1, max(ST_Y(g)) AS y1
							  FROM %2$s GROUP BY tile) t',
				   'tdc_tiled_tiles', pts);
	EXECUTE format('SELECT count(*) FROM %s', tiles) INTO ntiles;
	-- C, a convex polygon containing every point: their exact convex hull,
	-- from the hulls of the tiles (on the workers)
	EXECUTE format('SELECT _tdc_hull(h) FROM (SELECT _tdc_hull(g) AS h FROM %s GROUP BY tile) s', pts) INTO hull;

	-- Each tile's first known region {h, K, extra boxes...}, by the core's
	-- policy: K is the box of the tile's points with a halo h of 8 of its
	-- mean spacings, and the extra boxes are the bands along the hull edges
	-- near K.  A long hull edge has a triangle whose circle bulges far out
	-- of C; only its thin part inside C must be known, and the band holds it
	-- without widening K along the whole edge.
	EXECUTE format('UPDATE %s SET region = _tdc_tile_region(ARRAY[x0, y0, x1, y1], n, $1, $2, $3)', tiles)
		USING extent, npts, hull;
	EXECUTE format('UPDATE %s SET known = region[2:5], extra = region[6:cardinality(region)]', tiles);

	-- the target (M is dropped, as the Delaunay functions drop it)
	EXECUTE format('CREATE TABLE %s (id bigint, tile %s, geom geometry(%s, %s))', qtarget, ttype,
				   CASE WHEN zm_lo IN (2, 3) THEN 'PolygonZ' ELSE 'Polygon' END, coalesce(srid_lo, 0));
	EXECUTE format('CREATE TABLE %s (tile %s, label bigint, seq bigint, vi bigint, g geometry)', halo, ttype);
	EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', halo, 'tile', source::text);
	EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', qtarget, 'tile', source::text);
	-- the tiles, for the workers: a copy of the coordinator's table
	EXECUTE format('CREATE TABLE %s (tile %s, label bigint, known float8[], extra float8[], pending boolean)',
				   rt, ttype);
	EXECUTE format('SELECT create_reference_table(%L)', rt);
	IF npts > 0 THEN
		EXECUTE format('CREATE INDEX ON %s USING gist (g)', pts);
		EXECUTE format('ANALYZE %s', pts);
	END IF;

	-- the statement that runs every pending tile, the function in FROM
	tile_sql := format('INSERT INTO %s (id, tile, geom)
		SELECT CASE WHEN t.k = 0 THEN -1 ELSE s.label * 4294967296 + t.k END, s.tile, t.geom
		  FROM (SELECT h.tile, k.label,
					   _tdc_tile(h.g, h.label, k.label, k.known, %L::float8[], k.extra, h.seq, h.vi) AS r
				  FROM %s h JOIN %s k ON k.tile = h.tile
				 WHERE k.pending
				 GROUP BY h.tile, k.label) s,
			   LATERAL _tdc_tile_triangles(s.r) t',
		qtarget, hull, halo, rt);

	done := 0;
	LOOP
		EXECUTE format('SELECT count(*) FROM %s WHERE pending', tiles) INTO pending;
		EXIT WHEN pending = 0;
		round := round + 1;
		IF round > 64 THEN
			RAISE EXCEPTION '%: % tiles still not final after 64 rounds', fn, pending
				USING ERRCODE = 'internal_error';
		END IF;
		rerun := 0;
		EXECUTE format('DELETE FROM %s', rt);
		EXECUTE format('INSERT INTO %s SELECT tile, label, known, extra, pending FROM %s', rt, tiles);
		-- the halo of every pending tile: every point in its closed K, with
		-- its owner; K and the extra boxes each against the points' GiST
		-- index, a point taken from the first box that holds it (Citus
		-- pushes the statement down only with the subquery inline)
		EXECUTE format('DELETE FROM %s', halo);
		tile_box := format('SELECT k.tile, k.label, k.bx, i, k.bx[4*i+1] AS x0, k.bx[4*i+2] AS y0,
								   k.bx[4*i+3] AS x1, k.bx[4*i+4] AS y1
							  FROM (SELECT tile, label, known || extra AS bx FROM %s WHERE pending) k,
								   generate_series(0, cardinality(k.bx) / 4 - 1) i', rt);
		EXECUTE format('INSERT INTO %1$s (tile, label, seq, vi, g)
						SELECT b.tile, o.label, p.seq, p.vi, p.g
						  FROM (%5$s) b
						  JOIN %2$s p ON p.g && ST_MakeEnvelope(b.x0, b.y0, b.x1, b.y1, %4$s)
									AND _tdc_first_box(ST_X(p.g), ST_Y(p.g), b.bx, b.i)
						  JOIN %3$s o ON o.tile = p.tile',
					   halo, pts, rt, coalesce(srid_lo, 0), tile_box);
		GET DIAGNOSTICS ntri = ROW_COUNT;
		halo_pts := halo_pts + ntri;
		EXECUTE tile_sql;
		-- tiles that were not final: the region of their next run, from the
		-- row they wrote (_tdc_tile_regrow: the hull bands they lack, else K
		-- grown to the box they need and half the halo beyond), as ./tdc
		-- grows a tile
		EXECUTE format('UPDATE %s SET pending = false WHERE pending', tiles);
		FOR r IN EXECUTE format('SELECT tile::text AS tile, geom FROM %s WHERE id = -1', qtarget) LOOP
			EXECUTE format('UPDATE %1$s SET pending = true, region = g.r, known = g.r[2:5], extra = g.r[6:cardinality(g.r)]
							  FROM (SELECT _tdc_tile_regrow(region, $2, $3, $4, $5) AS r FROM %1$s WHERE tile = $1::%2$s) g
							 WHERE tile = $1::%2$s', tiles, ttype)
			USING r.tile, r.geom, extent, npts, hull;
			rerun := rerun + 1;
		END LOOP;
		EXECUTE format('DELETE FROM %s WHERE id = -1', qtarget);
		done := done + pending - rerun;
		RAISE NOTICE '%: round %: % of % tiles final', fn, round, done, ntiles;
	END LOOP;

	EXECUTE format('SELECT count(*) FROM %s', qtarget) INTO ntri;
	EXECUTE format('DROP TABLE %s, %s, %s, %s', halo, tiles, pts, rt);
	RAISE NOTICE '%: % triangles from % points in % tiles, % rounds, % halo points', fn, ntri, npts, ntiles,
		round, halo_pts;
END
$proc$;

COMMENT ON PROCEDURE tdc_delaunay_tiled(regclass, text, name, name, float8, text) IS
'Triangulates the vertices of source.geom_column (duplicates merged, Z of the first copy, one SRID; a pcpatch column '
'with tdc_delaunay_pointcloud: its points'' X, Y, Z, those the filter ''dimension=value[,...]'' keeps, not on Citus) '
'into a new table target(id bigint, tile, geom geometry(Polygon)): the same triangles as ST_TDCDelaunayDump, each once, '
'in one pass or, when that would not fit tdc_delaunay.max_memory, in tiles split by counts, as ./tdc --max-memory plans '
'and runs them. Each triangle''s tile: with tile_column, the value (of its type) of the tile owning the triangle''s '
'smallest vertex, a vertex owned by the least value among its copies, ids rank * 2^32 + k; with tile_size, the square '
'(counted from the data''s lower left corner) holding that vertex. On Citus, with source distributed by tile_column, '
'the tiles run on the workers, in rounds of SQL statements.';
