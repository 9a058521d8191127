/*
 * fn_tiled_bounded.c
 *		tdc_delaunay_tiled on plain PostgreSQL: the query's vertices
 *		triangulated in one pass, or tile by tile through the core's bounded
 *		run, and written straight into the target: _tdc_tiled_write.
 *
 * The procedure creates the target (id bigint, tile bigint or of the tile
 * column's type, geom geometry(Polygon[Z], srid)) and calls this function
 * once.  It reads the query's geometry column the way ST_TDCDelaunayDump
 * reads it (dump_query.c: a cursor in batches, curves stroked, the SRID and
 * dimensions checked), and the tile column beside it when there is one.
 * While the vertices and the engine's estimate for them fit
 * tdc_delaunay.max_memory they stay in memory, and the triangulation is one
 * tdc_run, as the Dump's.  Past that they are appended, a chunk at a time, to
 * a file, handed to the core's bounded run (tdc_bounded_start,
 * src/core/tiles/bounded*.c), the one ./tdc --max-memory runs: the same plan of
 * tiles cut by counts, the same halos and reruns, so the same triangles,
 * each once, within the limit.  The run works on a thread of its own while
 * this backend waits with its interrupts watched (run.c's wait loop: a
 * cancel stops a tile's engine within milliseconds).  Its emit callback, on
 * the run's thread, never calls PostgreSQL: it appends each final tile's
 * triangles as coordinates to a file, which the backend reads back once the
 * run is done.  Either way the rows go into the target through
 * table_write.c, without a tuplestore or a per-row cast.  The procedure and
 * this function are one transaction: an error or a cancel leaves no target.
 *
 * Tiles and ids: one pass is tile 0 with ids 2^32 + k; the bounded run's
 * tile t (from 0) gives tile t + 1 and ids (t + 1) * 2^32 + k.  With squares
 * of tile_size, a triangle's tile is instead the label of the square
 * (counted from the vertices' lower left corner) that holds its smallest
 * vertex, tdc_tp_owner_vertex: the square a run tiled by the squares would
 * keep it in.
 *
 * With a tile column the triangle's tile is the tile that owns its smallest
 * vertex, a vertex being owned by the least tile value among its copies:
 * the tile a run of the user's tiles with their halos keeps it in (the
 * rounds of SQL statements on Citus, tile_final.c's stars).  Each row's
 * value becomes a number as it is read (tile_values.c), the vertex's label
 * beside its coordinates, in memory or in a file like them; once every
 * value is seen the numbers become ranks in the type's order, a file of
 * them rewritten, and the core hands each vertex of a triangle the least
 * rank of its copies (tdc_least_labels; in the bounded run the labels ride
 * in its files).  The ids have the rounds' form, rank * 2^32 + k, k counting
 * the tile's triangles from 1 in the order they come out (the rounds
 * counted them in the order of the tile's own mesh).  The memory the
 * labels take, 8 bytes a vertex and the distinct values, counts against
 * the limit like the coordinates.  So the user's tiles only name the
 * triangles: the work is bounded by the core's plan, whatever their sizes.
 *
 * The files live in a directory of this backend under the temporary
 * tablespace's pgsql_tmp (removed by the server at restart if a crash left
 * it), made when the first chunk goes to disk and removed with everything
 * in it when the function's memory goes, on success or on error (a reset
 * callback, which first frees the run: that cancels and joins its thread).
 */
#include "postgres.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include "catalog/pg_tablespace_d.h"
#include "catalog/pg_type_d.h"
#include "commands/tablespace.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "storage/fd.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "tiles/tile_plan.h"
#include "fn/tiled_stage.h"


/* Rows written between two interrupt checks (a power of two). */
#define ROWS_POLL			65536

/* A final tile's record in the triangles file: then ntri * 3 * dim doubles. */
typedef struct TileRecord
{
	int64		tile;			/* from 0, in the plan's order */
	int64		ntri;
} TileRecord;


/* The phase an error or a cancel came in, for its CONTEXT line. */
static void
phase_context(void *arg)
{
	errcontext("%s: %s", TILED_FNAME, *(const char **) arg);
}


/*
 * Once the query runs (tdc_dump_collect_tagged's columns): whether it has a
 * tile column, whose type must be the target's tile column's, else the
 * target's must be bigint.
 */
static void
stage_columns(void *arg, const TdcDumpTag *tag)
{
	StageArg   *sa = (StageArg *) arg;
	TdcTableWriter *tw = sa->tw;

	if (tag == NULL)
	{
		if (tw->tiletype != INT8OID)
			ereport(ERROR,
					(errcode(ERRCODE_DATATYPE_MISMATCH),
					 errmsg("%s: the target's tile column is of type %s, not bigint, and the query has no tile column",
							sa->fname, format_type_be(tw->tiletype))));
		return;
	}
	if (sa->size > 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: give tile_column or tile_size, not both", sa->fname)));
	if (tag->typid != tw->tiletype || (tw->tiletypmod != -1 && tw->tiletypmod != tag->typmod))
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the target's tile column is of type %s, the query's tile column \"%s\" of type %s",
						sa->fname, format_type_with_typemod(tw->tiletype, tw->tiletypmod),
						tag->name, format_type_with_typemod(tag->typid, tag->typmod))));
	sa->tagged = true;
	sa->tile_name = MemoryContextStrdup(sa->cxt, tag->name);
	sa->tv = MemoryContextAlloc(sa->cxt, sizeof(TdcTileValues));
	tdc_tile_values_init(sa->tv, AllocSetContextCreate(sa->cxt, "tdc_delaunay_tiled tile values",
													   ALLOCSET_DEFAULT_SIZES),
						 tag->typid, tag->typmod, sa->tile_name, sa->fname);
}

/*
 * After each row (tdc_dump_collect_tagged's row): with a tile column, the
 * number of the row's tile value for each of its vertices; then tdc_stage_row.
 * A row without a vertex (an empty geometry) names no tile; a row with one
 * must have a tile.
 */
static void
stage_tagged_row(void *arg, uint64 first, const TdcDumpTag *tag)
{
	StageArg   *sa = (StageArg *) arg;
	TdcPointBuf *buf = sa->buf;
	uint32		number;

	if (tag != NULL && buf->n > first)
	{
		if (tag->isnull)
			ereport(ERROR,
					(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
					 errmsg("%s: tile column \"%s\" is NULL for a row with a geometry", sa->fname, sa->tile_name)));
		number = tdc_tile_values_number(sa->tv, tag->value);
		/* the labels, as many as the buffer has room for vertices, beside them */
		if (buf->n > sa->lab_cap)
		{
			uint64		cap = Max(buf->cap, 1024);

			tdc_pointbuf_side_grow(buf, sa->lab_cap * sizeof(int64), cap * sizeof(int64),
								   "their tiles", sa->fname);
			sa->lab = sa->lab == NULL ? MemoryContextAllocHuge(buf->cxt, cap * sizeof(int64)) :
				repalloc_huge(sa->lab, cap * sizeof(int64));
			sa->lab_cap = cap;
		}
		for (uint64 i = first; i < buf->n; i++)
			sa->lab[i] = number;
	}
	tdc_stage_row(arg, first);
}

static const TdcDumpTagOps stage_ops = {stage_columns, stage_tagged_row};


/*
 * The run's emit, on its thread: a final tile's triangles to the
 * triangles file as coordinates, each after its label with labels (the
 * rank of its smallest vertex).  No PostgreSQL call here; a failed write
 * keeps its errno for the backend's message and stops the run.
 */
static int
emit_triangles(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
			   const size_t *tri, size_t ntri)
{
	BoundedRun *br = (BoundedRun *) arg;
	TileRecord	rec = {tile, (int64) ntri};
	double		v[9];
	int			dim = br->dim;

	if (fwrite(&rec, sizeof(rec), 1, br->ftri) != 1)
		goto fail;
	for (size_t j = 0; j < ntri; j++)
	{
		for (int k = 0; k < 3; k++)
		{
			size_t		i = tri[3 * j + k];

			v[dim * k] = q[2 * i];
			v[dim * k + 1] = q[2 * i + 1];
			if (qz)
				v[dim * k + 2] = qz[i];
		}
		if (br->hasl)
		{
			int64		l = ql[tri[3 * j + tdc_tp_owner_vertex(v, v + dim, v + 2 * dim)]];

			if (fwrite(&l, sizeof(l), 1, br->ftri) != 1)
				goto fail;
		}
		if (fwrite(v, sizeof(double), 3 * dim, br->ftri) != (size_t) (3 * dim))
			goto fail;
	}
	return 0;
fail:
	br->write_errno = errno ? errno : EIO;
	return TDC_EIO;
}

static void
read_all(FILE *f, void *p, size_t size, const char *path, const char *fname)
{
	if (fread(p, size, 1, f) != 1)
		ereport(ERROR,
				(errcode(ERRCODE_INTERNAL_ERROR),
				 errmsg("%s: file \"%s\" ends early", fname, path)));
}

/* A triangle's tile: the square of its smallest vertex, or the run's tile. */
static inline int64
row_tile(const double *v, int dim, const double origin[2], double size, int64 tile)
{
	const double *o;

	if (size <= 0)
		return tile;
	o = v + dim * tdc_tp_owner_vertex(v, v + dim, v + 2 * dim);
	return tdc_tiled_square_label(o[0], o[1], origin, size);
}

/* A row of a triangle of tile column rank r: the rank's value, id r * 2^32 + its count. */
static inline void
put_ranked(TdcTableWriter *tw, TdcTileValues *tv, int64 r, const double *v)
{
	Assert(r >= 1 && r <= tv->nranks);
	tdc_table_writer_put(tw, (r << 32) + ++tv->count[r], tv->by_rank[r], v);
}

/*
 * The bounded run's triangles file into the target: ids (t + 1) * 2^32 + k,
 * or with a tile column (tv) the rank's.
 */
static void
write_rows_from_file(BoundedRun *br, TdcTableWriter *tw, TdcTileValues *tv, const double origin[2],
					 double size, const char *fname)
{
	double		v[9];
	TileRecord	rec;
	int64		r;

	br->ftri = tdc_stage_open(br->tripath, "rb", fname);
	while (fread(&rec, sizeof(rec), 1, br->ftri) == 1)
	{
		int64		label = rec.tile + 1;

		for (int64 k = 1; k <= rec.ntri; k++)
		{
			if (br->hasl)
				read_all(br->ftri, &r, sizeof(r), br->tripath, fname);
			read_all(br->ftri, v, sizeof(double) * 3 * br->dim, br->tripath, fname);
			if (br->hasl)
				put_ranked(tw, tv, r, v);
			else
				tdc_table_writer_put(tw, (label << 32) + k,
									 Int64GetDatum(row_tile(v, br->dim, origin, size, label)), v);
		}
	}
	if (ferror(br->ftri))
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not read file \"%s\": %m", fname, br->tripath)));
	tdc_stage_close(&br->ftri);
}

/*
 * One pass's triangles into the target: ids 2^32 + k, tile 0, in the
 * Dump's order; or with a tile column (tv, lab the vertices' ranks) the
 * rank of each triangle's smallest vertex, the least of its copies'.
 */
static void
write_rows_from_job(const TdcRun *run, const TdcPointBuf *buf, TdcTableWriter *tw, TdcTileValues *tv,
					int64 *lab, const double origin[2], double size)
{
	int			dim = buf->hasz ? 3 : 2;
	tdc_iter	it = {0};
	uint32		t[3];
	double		v[9];
	int64		k = 0;

	if (tv)
		tdc_least_labels(run->job, lab);
	while (tdc_next_triangle(run->job, &it, t))
	{
		for (int j = 0; j < 3; j++)
		{
			const double *xy = tdc_site_xy(run->job, t[j]);

			v[dim * j] = xy[0];
			v[dim * j + 1] = xy[1];
			if (dim == 3)
				v[dim * j + 2] = buf->z[tdc_site_input(run->job, t[j])];
		}
		if (tv)
			put_ranked(tw, tv, lab[tdc_site_input(run->job, t[tdc_tp_owner_vertex(v, v + dim, v + 2 * dim)])], v);
		else
			tdc_table_writer_put(tw, ((int64) 1 << 32) + ++k, Int64GetDatum(row_tile(v, dim, origin, size, 0)), v);
	}
}

/*
 * The staged file of value numbers rewritten as ranks (tv->rank), a chunk
 * at a time, for the run; the numbers' file removed.
 */
static void
rank_label_file(BoundedRun *br, const TdcTileValues *tv, const char *fname)
{
	int64	   *chunk = palloc(STAGE_CHUNK * sizeof(int64));
	size_t		got;

	br->fin = tdc_stage_open(br->lrawpath, "rb", fname);
	br->fl = tdc_stage_open(br->lpath, "wb", fname);
	while ((got = fread(chunk, sizeof(int64), STAGE_CHUNK, br->fin)) > 0)
	{
		for (size_t i = 0; i < got; i++)
			chunk[i] = tv->rank[chunk[i]];
		tdc_stage_write(br->fl, chunk, sizeof(int64), got, br->lpath, fname);
		CHECK_FOR_INTERRUPTS();
	}
	if (ferror(br->fin))
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not read file \"%s\": %m", fname, br->lrawpath)));
	tdc_stage_close(&br->fin);
	(void) unlink(br->lrawpath);
	tdc_stage_finish(&br->fl, br->lpath, fname);
	pfree(chunk);
}

/* The bounded run on the staged files, its triangles to the triangles file. */
static void
run_tiles(BoundedRun *br, const tdc_options *opt, uint64 limit_mb, const char *setting,
		  uint64 outside, tdc_bounded_stats *st, const char *fname)
{
	tdc_bounded_params p;

	br->ftri = tdc_stage_open(br->tripath, "wb", fname);
	memset(&p, 0, sizeof(p));
	p.emit = emit_triangles;
	p.arg = br;
	tdc_stage_run(br, &p, opt, limit_mb, setting, outside, "tiled triangulation", NULL, st, fname);
	tdc_stage_finish(&br->ftri, br->tripath, fname);
}

PG_FUNCTION_INFO_V1(_tdc_tiled_write);

/*
 * _tdc_tiled_write(query text, target regclass, tile_size float8
 *		[, geom_type regtype, filter text]) RETURNS int8
 * The Delaunay triangles of the query's vertices (its geometry column, as
 * ST_TDCDelaunayDump takes it; in the form tdc_delaunay_pointcloud
 * declares, its pcpatch column of type geom_type, the points the filter
 * keeps) into target, which the caller created in
 * this transaction (table_write.c); tile_size NULL: no squares.  A second
 * column of the query is the tile column, of the type of the target's.
 * Returns the rows written; see the top of this file.  Internal to
 * tdc_delaunay_tiled.
 */
Datum
_tdc_tiled_write(PG_FUNCTION_ARGS)
{
	const char *fname = TILED_FNAME;
	const char *setting;
	uint64		limit_mb = tdc_memory_limit_mb(&setting);
	char	   *query;
	Oid			target;
	double		size = 0;
	MemoryContext cxt = CurrentMemoryContext;
	BoundedRun *br;
	TdcPointBuf buf;
	TdcTableWriter tw;
	StageArg	sa;
	tdc_options opt;
	tdc_bounded_stats st;
	const char *phase = "reading the source";
	ErrorContextCallback errcb;
	instr_time	t0;
	double		read_s,
				tiles_s,
				rows_s;
	uint64		npts;
	char	   *labelled = NULL;	/* how the triangles are labelled, for the NOTICE */

	tdc_signal_guard();
	if (PG_ARGISNULL(0) || PG_ARGISNULL(1))
		ereport(ERROR,
				(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
				 errmsg("%s: the query and the target must not be NULL", fname)));
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	target = PG_GETARG_OID(1);
	if (!PG_ARGISNULL(2))
	{
		size = PG_GETARG_FLOAT8(2);
		if (!(size > 0 && size < INFINITY))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: tile_size must be positive and finite, not %g", fname, size)));
	}
	tdc_session_options(&opt);

	/* the files go with this call's memory, whatever ends it */
	br = MemoryContextAllocZero(cxt, sizeof(BoundedRun));
	br->cb.func = tdc_stage_release;
	br->cb.arg = br;
	MemoryContextRegisterResetCallback(cxt, &br->cb);
	errcb.callback = phase_context;
	errcb.arg = (void *) &phase;
	errcb.previous = error_context_stack;
	error_context_stack = &errcb;

	/* the target, checked before any row is read */
	tdc_table_writer_open(&tw, target, fname);

	/* the vertices: in memory while one pass fits, then to the files */
	INSTR_TIME_SET_CURRENT(t0);
	tdc_pointbuf_init(&buf, AllocSetContextCreate(cxt, "tdc_delaunay_tiled vertices", ALLOCSET_DEFAULT_SIZES));
	buf.curves = TDC_CURVES_STROKE;
	tdc_stage_init(&sa, br, &buf, cxt, &opt, limit_mb, fname);
	sa.tw = &tw;
	sa.size = size;
	if (PG_NARGS() > 3)
		/* the pcpatch form (tdc_delaunay_pointcloud): geom_type, filter */
		tdc_dump_collect_tagged_pc(&buf, query, PG_GETARG_OID(3), tdc_stage_pc_column(fcinfo, 4, cxt), fname,
								   &stage_ops, &sa);
	else
		tdc_dump_collect_tagged(&buf, query, tw.geomoid, fname, &stage_ops, &sa);
	/* the values in their order: the labels become ranks */
	if (sa.tagged)
		tdc_tile_values_rank(sa.tv, fname);
	npts = tdc_stage_done(&sa);
	if (sa.to_files && sa.tagged)
		rank_label_file(br, sa.tv, fname);
	else if (sa.tagged)
		for (uint64 i = 0; i < buf.n; i++)
			sa.lab[i] = sa.tv->rank[sa.lab[i]];
	read_s = tdc_ms_since(t0) / 1000;
	if (npts > 0)
		tdc_table_writer_shape(&tw, buf.hasz ? 3 : 2, buf.srid, fname);
	/* squares too small for the data are refused before the work */
	if (npts > 0 && size > 0)
		(void) tdc_tiled_square_label(sa.hi[0], sa.hi[1], sa.lo, size);
	if (size > 0)
		labelled = psprintf(" (labelled by squares of tile_size %.17g)", size);
	else if (sa.tagged)
		labelled = psprintf(" (labelled by the %u value%s of tile column \"%s\")", sa.tv->nranks,
							sa.tv->nranks == 1 ? "" : "s", sa.tile_name);

	if (!sa.to_files)
	{
		/* one pass, the Dump's run */
		TdcRun	   *run;

		phase = "triangulating";
		INSTR_TIME_SET_CURRENT(t0);
		if (npts > 0)
		{
			/* (the tile values are beside the run, as its result would be) */
			run = tdc_run(&buf, 0, tdc_stage_values_bytes(&sa), fname);
			tiles_s = tdc_ms_since(t0) / 1000;
			phase = "writing the rows";
			INSTR_TIME_SET_CURRENT(t0);
			write_rows_from_job(run, &buf, &tw, sa.tv, sa.lab, sa.lo, size);
			rows_s = tdc_ms_since(t0) / 1000;
			CHECK_FOR_INTERRUPTS();
			tdc_run_free(run);
		}
		else
			tiles_s = rows_s = 0;
		tdc_table_writer_close(&tw);
		error_context_stack = errcb.previous;
		/* (the phases with tdc_delaunay.stats only: a pass is the Dump's, whose stats say the same) */
		ereport(NOTICE,
				(errmsg("%s: %llu triangles from %llu points%s, in one pass", fname,
						(unsigned long long) tw.rows, (unsigned long long) npts,
						labelled ? labelled : " in 1 tile"),
				 tdc_guc_stats ? errdetail("Phases in seconds: read %.3f, triangulate %.3f, rows %.3f.",
										   read_s, tiles_s, rows_s) : 0));
		PG_RETURN_INT64((int64) tw.rows);
	}

	/* the tiles, on the run's thread, while this one watches its interrupts */
	phase = "running the tiles";
	INSTR_TIME_SET_CURRENT(t0);
	/* the staging buffer, still allocated, and the tile values are beside the run */
	run_tiles(br, &opt, limit_mb, setting, tdc_pointbuf_bytes(&buf) + tdc_stage_values_bytes(&sa), &st, fname);
	tiles_s = tdc_ms_since(t0) / 1000;

	phase = "writing the rows";
	INSTR_TIME_SET_CURRENT(t0);
	write_rows_from_file(br, &tw, sa.tv, sa.lo, size, fname);
	rows_s = tdc_ms_since(t0) / 1000;
	tdc_table_writer_close(&tw);
	tdc_stage_release(br);
	error_context_stack = errcb.previous;

	ereport(NOTICE,
			(errmsg("%s: %llu triangles from %llu points%s in %d tile%s under %s = %llu MB, "
					"%zu tile run%s, %zu halo points",
					fname, (unsigned long long) tw.rows, (unsigned long long) npts,
					labelled ? labelled : "",
					st.tiles, st.tiles == 1 ? "" : "s", setting, (unsigned long long) limit_mb,
					st.runs, st.runs == 1 ? "" : "s", st.halo),
			 errdetail("Phases in seconds: read %.3f, scan %.3f, bin %.3f, gather %.3f, engine %.3f, "
					   "finish %.3f, rows %.3f (the tiles %.3f in all).",
					   read_s, st.scan, st.bin, st.gather, st.engine, st.finish, rows_s, tiles_s)));
	PG_RETURN_INT64((int64) tw.rows);
}
