-- src/sql/tiled.sql: the procedure tdc_delaunay_tiled, in PL/pgSQL over the
-- internal functions of src/sql/tiled_internals.sql

-- The procedure.  Without a tile column it makes the target and hands the
-- source to _tdc_tiled_write (src/pg/fn/fn_tiled_bounded.c): one pass, or when
-- that would not fit tdc_delaunay.max_memory the core's bounded run (the
-- tiles of ./tdc --max-memory), squares of tile_size labelling the
-- triangles.  With a tile column it runs in rounds over staging tables: pts
-- (every vertex, with the tile owning it and its position in the source),
-- tiles (one row per tile: label, extent, known box K), halo (for every
-- pending tile, the points inside its K) and the target.  A round runs every
-- pending tile; a tile whose stars are not all final writes one marker row
-- (id -1, its needed box) instead of triangles, and the next round reruns
-- it with a larger K.  On Citus, when source is distributed by tile_column,
-- pts, halo and the target are distributed on it and co-located with
-- source, tiles is a reference table, and a round is one INSERT ... SELECT
-- ... GROUP BY tile that runs on the workers.  On plain PostgreSQL the same
-- statement runs once per tile, so that a backend holds one tile and its
-- halo at a time.  Everything happens in the caller's transaction: an error
-- or a cancel leaves no target behind.
CREATE PROCEDURE tdc_delaunay_tiled(source regclass, target text, geom_column name DEFAULT 'geom',
									tile_column name DEFAULT NULL, tile_size float8 DEFAULT NULL)
LANGUAGE plpgsql
-- a tile's statement is estimated at millions of rows, and compiling it
-- cost a second per tile; boxes and the hull pass through the statements'
-- text, so floats must print exactly
SET jit = off
SET extra_float_digits = 3
-- the one-tile pass reads the source in its order, as the staging table does
SET synchronize_seqscans = off
AS $proc$
DECLARE
	fn constant text := 'tdc_delaunay_tiled';
	gtyp name;
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
	hasz boolean;
	tparts text[];
	tschema text; tname text; qtarget text;
	pts text; tiles text; rt text; halo text;
	ntiles bigint; done bigint; pending bigint; reported int; i bigint; rerun bigint;
	round int := 0;
	has_null boolean;
	halo_pts bigint := 0;
	ntri bigint;
	r record;
	tile_sql text;
	tile_box text;
	px text := 'ST_X(g)';
	py text := 'ST_Y(g)';
	cells text;
	cell float8;				-- side of the halo join's grid cells
	ncx bigint;
	ncy bigint;
	cell_of text;				-- SQL of a staged point's cell
	nparts bigint;
	one_row text[];				-- plain PostgreSQL: tiles whose statement wrote one row
	written bigint := 0;		-- plain PostgreSQL: rows written, boxes included
	nrows bigint;
BEGIN
	-- the geometry column
	SELECT t.typname INTO gtyp
	  FROM pg_attribute a JOIN pg_type t ON t.oid = a.atttypid
	 WHERE a.attrelid = source AND a.attname = geom_column AND a.attnum > 0 AND NOT a.attisdropped;
	IF NOT FOUND THEN
		RAISE EXCEPTION '%: column "%" of relation % does not exist', fn, geom_column, source
			USING ERRCODE = 'undefined_column';
	END IF;
	IF gtyp <> 'geometry' THEN
		RAISE EXCEPTION '%: column "%" of relation % is of type %, not geometry', fn, geom_column, source, gtyp
			USING ERRCODE = 'datatype_mismatch';
	END IF;
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
	tparts := parse_ident(target);
	IF cardinality(tparts) = 1 THEN
		tschema := current_schema();
		tname := tparts[1];
	ELSIF cardinality(tparts) = 2 THEN
		tschema := tparts[1];
		tname := tparts[2];
	ELSE
		RAISE EXCEPTION '%: target "%" is not a table name', fn, target
			USING ERRCODE = 'invalid_name';
	END IF;
	qtarget := format('%I.%I', tschema, tname);
	IF to_regclass(qtarget) IS NOT NULL THEN
		RAISE EXCEPTION '%: target % already exists', fn, qtarget
			USING ERRCODE = 'duplicate_table', HINT = 'Drop it or choose another name; it is never overwritten.';
	END IF;
	-- Citus: source distributed by hash of tile_column
	IF tile_column IS NOT NULL AND to_regclass('pg_catalog.pg_dist_partition') IS NOT NULL THEN
		EXECUTE 'SELECT EXISTS (SELECT 1 FROM pg_dist_partition WHERE logicalrelid = $1 AND partmethod = ''h''
					AND column_to_column_name(logicalrelid, partkey) = $2)'
		   INTO citus USING source, tile_column;
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

	-- a value with arcs is stroked as ST_TDCDelaunayDump strokes it (see
	-- tdc_curves.c); GeometryType reads only the header, so only
	-- collections and curve types are looked into
	stroked := format('CASE WHEN GeometryType(s.%1$I) IN (''CIRCULARSTRING'', ''COMPOUNDCURVE'', ''CURVEPOLYGON'',
															 ''MULTICURVE'', ''MULTISURFACE'', ''GEOMETRYCOLLECTION'')
							 THEN _tdc_curve_to_line(s.%1$I) ELSE s.%1$I END', geom_column);

	-- Without a tile column: _tdc_tiled_write (src/pg/fn_tiled_bounded.c)
	-- reads the source once, as ST_TDCDelaunayDump reads it, and triangulates
	-- it in one pass while that fits tdc_delaunay.max_memory, else tile by
	-- tile through the core's bounded run, as ./tdc --max-memory does (tiles
	-- cut by counts, halos and reruns in files under pgsql_tmp); it writes
	-- the rows straight into the target, which must exist first.  The first
	-- row's SRID and dimensions give the target's type (M is dropped, as the
	-- Delaunay functions drop it), and every other row must agree.  Squares
	-- of tile_size only label the triangles: each is kept by the square
	-- holding its smallest vertex, as a run tiled by the squares keeps it,
	-- labelled column * 2^32 + row counted from the vertices' lower left
	-- corner (_tdc_square_label).
	IF tile_column IS NULL THEN
		EXECUTE format('SELECT ST_SRID(s.%1$I), ST_Zmflag(s.%1$I) FROM %2$s s WHERE s.%1$I IS NOT NULL LIMIT 1',
					   geom_column, source)
		   INTO srid_lo, zm_lo;
		EXECUTE format('CREATE TABLE %s (id bigint, tile bigint, geom geometry(%s, %s))', qtarget,
					   CASE WHEN zm_lo IN (2, 3) THEN 'PolygonZ' ELSE 'Polygon' END, coalesce(srid_lo, 0));
		PERFORM _tdc_tiled_write(format('SELECT %I FROM %s', geom_column, source), qtarget::regclass, tile_size);
		RETURN;
	END IF;

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
	hasz := zm_lo IN (2, 3);

	-- staging tables: temporary on plain PostgreSQL, distributed on Citus
	IF citus THEN
		pts := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_pts');
		tiles := 'pg_temp.tdc_tiled_tiles';
		rt := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_tiles');
		halo := format('%I.%I', tschema, 'tdc_tiled_' || pg_backend_pid() || '_halo');
		EXECUTE format('CREATE TABLE %s (tile %s, seq bigint, vi bigint, g geometry)', pts, ttype);
		EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', pts, 'tile', source::text);
	ELSE
		pts := 'pg_temp.tdc_tiled_pts';
		tiles := 'pg_temp.tdc_tiled_tiles';
		rt := tiles;
		halo := 'pg_temp.tdc_tiled_halo';
		cells := 'pg_temp.tdc_tiled_cells';
		EXECUTE format('CREATE TEMP TABLE %s (tile %s, seq bigint, vi bigint, g geometry, x float8, y float8)',
					   'tdc_tiled_pts', ttype);
		px := 'x';
		py := 'y';
	END IF;

	-- every vertex, in the source's order (block, offset, vertex), with its
	-- tile: the tile column's value
	tv := format('s.%I', tile_column);
	IF citus THEN
		EXECUTE format('INSERT INTO %s (tile, seq, vi, g)
						SELECT %s, ((s.ctid::text::point)[0])::bigint * 65536 + ((s.ctid::text::point)[1])::bigint,
							   d.vi, d.geom
						  FROM %s s, LATERAL ST_DumpPoints(%s) WITH ORDINALITY AS d(path, geom, vi)
						 WHERE s.%I IS NOT NULL', pts, tv, source, stroked, geom_column);
	ELSE
		-- a row that is one point is its own vertex: ST_DumpPoints is most
		-- of the cost of a point table, and only the other rows need it
		EXECUTE format('INSERT INTO %1$s (tile, seq, vi, g, x, y)
						SELECT %2$s, (d.c[0])::bigint * 65536 + (d.c[1])::bigint, 1, d.geom, ST_X(d.geom), ST_Y(d.geom)
						  FROM %3$s s, LATERAL (SELECT s.%4$I AS geom, s.ctid::text::point AS c) d
						 WHERE ST_GeometryType(s.%4$I) = ''ST_Point'' AND NOT ST_IsEmpty(s.%4$I)',
					   pts, tv, source, geom_column);
		EXECUTE format('INSERT INTO %1$s (tile, seq, vi, g, x, y)
						SELECT %2$s, ((s.ctid::text::point)[0])::bigint * 65536 + ((s.ctid::text::point)[1])::bigint,
							   d.vi, d.geom, ST_X(d.geom), ST_Y(d.geom)
						  FROM %3$s s, LATERAL ST_DumpPoints(%5$s) WITH ORDINALITY AS d(path, geom, vi)
						 WHERE ST_GeometryType(s.%4$I) <> ''ST_Point''',
					   pts, tv, source, geom_column, stroked);
	END IF;
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
					  FROM (SELECT tile, count(*) AS n, min(%3$s) AS x0, min(%4$s) AS y0,
								   max(%3$s) AS x1, max(%4$s) AS y1
							  FROM %2$s GROUP BY tile) t',
				   'tdc_tiled_tiles', pts, px, py);
	EXECUTE format('SELECT count(*) FROM %s', tiles) INTO ntiles;
	-- C, a convex polygon containing every point: their exact convex hull,
	-- from the hulls of the tiles (on the workers on Citus)
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

	-- the target
	EXECUTE format('CREATE TABLE %s (id bigint, tile %s, geom geometry(%s, %s))', qtarget, ttype,
				   CASE WHEN zm_lo = 2 THEN 'PolygonZ' WHEN zm_lo = 1 THEN 'PolygonM'
						WHEN zm_lo = 3 THEN 'PolygonZM' ELSE 'Polygon' END, coalesce(srid_lo, 0));
	IF citus THEN
		EXECUTE format('CREATE TABLE %s (tile %s, label bigint, seq bigint, vi bigint, g geometry)', halo, ttype);
		EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', halo, 'tile', source::text);
		EXECUTE format('SELECT create_distributed_table(%L, %L, colocate_with => %L)', qtarget, 'tile', source::text);
		-- the tiles, for the workers: a copy of the coordinator's table
		EXECUTE format('CREATE TABLE %s (tile %s, label bigint, known float8[], extra float8[], pending boolean)',
					   rt, ttype);
		EXECUTE format('SELECT create_reference_table(%L)', rt);
	ELSE
		-- The halo, partitioned by the label of its tile (tl): a tile's
		-- statement reads its own partition from end to end, where an index
		-- on a table of every tile's rows, in the points' order, sent it
		-- to almost every block.  One partition per tile, or per run of
		-- consecutive labels beyond 64 tiles.
		EXECUTE format('CREATE TEMP TABLE %s (tile %s, label bigint, seq bigint, vi bigint, g geometry, tl bigint)
						PARTITION BY RANGE (tl)', 'tdc_tiled_halo', ttype);
		nparts := least(ntiles, 64);
		FOR part IN 0 .. nparts - 1 LOOP
			EXECUTE format('CREATE TEMP TABLE %I PARTITION OF %s FOR VALUES FROM (%s) TO (%s)',
						   'tdc_tiled_halo_' || part, halo, 1 + part * ntiles / nparts,
						   1 + (part + 1) * ntiles / nparts);
		END LOOP;
		-- the halo join's grid: a row per box and grid cell it meets (below)
		EXECUTE format('CREATE TEMP TABLE %s (cell bigint, tile %s, tl bigint, nprior int, boxes float8[])',
					   'tdc_tiled_cells', ttype);
	END IF;
	IF npts > 0 THEN
		IF citus THEN
			EXECUTE format('CREATE INDEX ON %s USING gist (g)', pts);
		END IF;
		EXECUTE format('ANALYZE %s', pts);
	END IF;

	-- the per-tile statement: on Citus one for all tiles, the function in
	-- FROM; on plain PostgreSQL one tile ($1, its label $2) at a time, the
	-- function in the select list, where its rows stream into the INSERT
	-- (in FROM the executor first collects a tile's rows in a tuplestore)
	IF citus THEN
		tile_sql := format('INSERT INTO %s (id, tile, geom)
			SELECT CASE WHEN t.k = 0 THEN -1 ELSE s.label * 4294967296 + t.k END, s.tile, t.geom
			  FROM (SELECT h.tile, k.label,
						   _tdc_tile(h.g, h.label, k.label, k.known, %L::float8[], k.extra, h.seq, h.vi) AS r
					  FROM %s h JOIN %s k ON k.tile = h.tile
					 WHERE k.pending
					 GROUP BY h.tile, k.label) s,
				   LATERAL _tdc_tile_triangles(s.r) t',
			qtarget, hull, halo, rt);
	ELSE
		-- (the tile's label, known box and extra boxes come as $2 to $4,
		-- not from a join with the tiles: the halo's partitions have no
		-- statistics, and with a thousand tiles the planner's nested loop
		-- over the tiles for every halo row took most of the time)
		tile_sql := format('INSERT INTO %s (id, tile, geom)
			SELECT CASE WHEN (q.t).k = 0 THEN -1 ELSE $2 * 4294967296 + (q.t).k END, q.tile, (q.t).geom
			  FROM (SELECT s.tile, _tdc_tile_triangles(s.r) AS t
					  FROM (SELECT h.tile, _tdc_tile(h.g, h.label, $2, $3, %L::float8[], $4, h.seq, h.vi) AS r
							  FROM %s h
							 WHERE h.tile = $1::%s AND h.tl = $2
							 GROUP BY h.tile) s) q',
			qtarget, hull, halo, ttype);
	END IF;

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
		one_row := '{}';
		IF citus THEN
			EXECUTE format('DELETE FROM %s', rt);
			EXECUTE format('INSERT INTO %s SELECT tile, label, known, extra, pending FROM %s', rt, tiles);
		END IF;
		-- the halo of every pending tile: every point in its closed K, with its owner
		EXECUTE format('DELETE FROM %s', halo);
		-- (K and the extra boxes: a point is taken from the first box that holds it)
		tile_box := format('SELECT k.tile, k.label, k.bx, i, k.bx[4*i+1] AS x0, k.bx[4*i+2] AS y0,
								   k.bx[4*i+3] AS x1, k.bx[4*i+4] AS y1
							  FROM (SELECT tile, label, known || extra AS bx FROM %s WHERE pending) k,
								   generate_series(0, cardinality(k.bx) / 4 - 1) i', rt);
		IF citus THEN
			-- each box against the points' GiST index; Citus pushes the
			-- statement down only with the subquery inline
			EXECUTE format('INSERT INTO %1$s (tile, label, seq, vi, g)
							SELECT b.tile, o.label, p.seq, p.vi, p.g
							  FROM (%5$s) b
							  JOIN %2$s p ON p.g && ST_MakeEnvelope(b.x0, b.y0, b.x1, b.y1, %4$s)
										AND _tdc_first_box(ST_X(p.g), ST_Y(p.g), b.bx, b.i)
							  JOIN %3$s o ON o.tile = p.tile',
						   halo, pts, rt, coalesce(srid_lo, 0), tile_box);
		ELSE
			-- One pass over the points, hashed against a grid: every box
			-- lists the cells it meets, with the tile's earlier boxes that
			-- overlap it (a point in box i and in no earlier box of its tile
			-- comes from box i; an earlier box holding it must overlap box i).
			-- The cell side is about 32 point spacings, coarser where the
			-- boxes together would make more than npts / 64 + 1000 cells, and
			-- at least 2^-20 of the extent, so that both cell numbers fit one
			-- key.  A point's cell number rises with its coordinate (each
			-- step rounds monotonically), so a point in a box is in one of its
			-- cells; the exact test is _tdc_first_box.  Cells outside the
			-- extent (gx0 .. gx1: the values' boxes, rounded outward) hold
			-- no point and are left out.  (OFFSET 0: a tile's boxes, known ||
			-- extra, are built once, and the earlier boxes each box overlaps once
			-- per box, not at every use and for every cell: with the 90 hull
			-- bands of a ring of 90 points this statement took 8 s, not 0.1 s.)
			EXECUTE format('SELECT coalesce(sum(greatest(least(b.x1, %3$L::float8) - greatest(b.x0, %1$L::float8), 0)
												* greatest(least(b.y1, %4$L::float8) - greatest(b.y0, %2$L::float8), 0)), 0)
							  FROM (%5$s) b',
						   gx0, gy0, gx1, gy1, tile_box) INTO cell;
			cell := greatest(32 * spacing, sqrt(cell / (npts::float8 / 64 + 1000)),
							 (gx1 - gx0) / 1048576, (gy1 - gy0) / 1048576);
			ncx := floor((gx1 - gx0) / cell);
			ncy := floor((gy1 - gy0) / cell);
			EXECUTE format('DELETE FROM %s', cells);
			EXECUTE format('INSERT INTO %1$s (cell, tile, tl, nprior, boxes)
							SELECT cx * 2097152 + cy, b.tile, b.label, cardinality(b.boxes) / 4 - 1, b.boxes
							  FROM (SELECT k.tile, k.label, k.x0, k.y0, k.x1, k.y1,
										   coalesce((SELECT array_agg(k.bx[4*j+m] ORDER BY j, m)
													   FROM generate_series(0, k.i - 1) j, generate_series(1, 4) m
													  WHERE k.bx[4*j+1] <= k.x1 AND k.x0 <= k.bx[4*j+3]
														AND k.bx[4*j+2] <= k.y1 AND k.y0 <= k.bx[4*j+4]),
													''{}'') || k.bx[4*k.i+1:4*k.i+4] AS boxes
									  FROM (SELECT * FROM (%2$s) k0 OFFSET 0) k
									OFFSET 0) b,
								   generate_series(greatest(floor((b.x0 - %3$L::float8) / %5$L::float8), 0)::bigint,
												   least(floor((b.x1 - %3$L::float8) / %5$L::float8), %6$s)::bigint) cx,
								   generate_series(greatest(floor((b.y0 - %4$L::float8) / %5$L::float8), 0)::bigint,
												   least(floor((b.y1 - %4$L::float8) / %5$L::float8), %7$s)::bigint) cy',
						   cells, tile_box, gx0, gy0, cell, ncx, ncy);
			EXECUTE format('ANALYZE %s', cells);
			cell_of := format('floor((p.x - %1$L::float8) / %3$L::float8)::bigint * 2097152
							   + floor((p.y - %2$L::float8) / %3$L::float8)::bigint', gx0, gy0, cell);
			EXECUTE format('INSERT INTO %1$s (tile, label, seq, vi, g, tl)
							SELECT c.tile, o.label, p.seq, p.vi, p.g, c.tl
							  FROM %2$s p
							  JOIN %3$s c ON c.cell = %5$s AND _tdc_first_box(p.x, p.y, c.boxes, c.nprior)
							  JOIN %4$s o ON o.tile = p.tile',
						   halo, pts, cells, tiles, cell_of);
		END IF;
		GET DIAGNOSTICS ntri = ROW_COUNT;
		halo_pts := halo_pts + ntri;
		IF citus THEN
			EXECUTE tile_sql;
		ELSE
			reported := 0;
			i := 0;
			FOR r IN EXECUTE format('SELECT tile::text AS tile, label, known, extra
									   FROM %s WHERE pending ORDER BY label', tiles) LOOP
				EXECUTE tile_sql USING r.tile, r.label, r.known, r.extra;
				GET DIAGNOSTICS nrows = ROW_COUNT;
				written := written + nrows;
				-- a tile that is not final writes one row: its box
				IF nrows = 1 THEN
					one_row := one_row || r.tile;
				END IF;
				i := i + 1;
				IF (i * 10 / pending)::int > reported THEN
					reported := (i * 10 / pending)::int;
					RAISE NOTICE '%: round %: % of % tiles run', fn, round, i, pending;
				END IF;
			END LOOP;
		END IF;
		-- tiles that were not final: the region of their next run, from the
		-- row they wrote (_tdc_tile_regrow: the hull bands they lack, else K
		-- grown to the box they need and half the halo beyond), as ./tdc
		-- grows a tile
		-- (on plain PostgreSQL only the tiles that wrote one row can be
		-- among them: the target is scanned for their boxes only if there
		-- are such tiles)
		EXECUTE format('UPDATE %s SET pending = false WHERE pending', tiles);
		FOR r IN EXECUTE format('SELECT tile::text AS tile, geom FROM %s WHERE id = -1 %s', qtarget,
								CASE WHEN citus THEN '' WHEN cardinality(one_row) = 0 THEN 'AND false'
									 ELSE 'AND tile::text = ANY($1)' END)
						 USING one_row LOOP
			EXECUTE format('UPDATE %1$s SET pending = true, region = g.r, known = g.r[2:5], extra = g.r[6:cardinality(g.r)]
							  FROM (SELECT _tdc_tile_regrow(region, $2, $3, $4, $5) AS r FROM %1$s WHERE tile = $1::%2$s) g
							 WHERE tile = $1::%2$s', tiles, ttype)
			USING r.tile, r.geom, extent, npts, hull;
			rerun := rerun + 1;
		END LOOP;
		IF citus OR rerun > 0 THEN
			EXECUTE format('DELETE FROM %s WHERE id = -1', qtarget);
		END IF;
		written := written - rerun;
		done := done + pending - rerun;
		RAISE NOTICE '%: round %: % of % tiles final', fn, round, done, ntiles;
	END LOOP;

	IF citus THEN
		EXECUTE format('SELECT count(*) FROM %s', qtarget) INTO ntri;
	ELSE
		ntri := written;
	END IF;
	EXECUTE format('DROP TABLE %s, %s, %s', halo, tiles, pts);
	IF citus THEN
		EXECUTE format('DROP TABLE %s', rt);
	ELSE
		EXECUTE format('DROP TABLE %s', cells);
	END IF;
	RAISE NOTICE '%: % triangles from % points in % tiles, % rounds, % halo points', fn, ntri, npts, ntiles,
		round, halo_pts;
END
$proc$;

COMMENT ON PROCEDURE tdc_delaunay_tiled(regclass, text, name, name, float8) IS
'Triangulates the vertices of source.geom_column (duplicates merged, Z of the first copy, one SRID) tile by tile '
'into a new table target(id bigint, tile, geom geometry(Polygon)): the same triangles as ST_TDCDelaunayDump, each once. '
'Tiles: the groups of tile_column, run in rounds of SQL statements; else tiles split by counts so that each fits '
'tdc_delaunay.max_memory, as ./tdc --max-memory plans and runs them, each triangle then labelled with the square of '
'tile_size (counted from the data''s lower left corner) that holds its smallest vertex, when tile_size is given. '
'On Citus, with source distributed by tile_column, the tiles run on the workers.';
