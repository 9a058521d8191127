/*
 * fn_tiled_bounded.c
 *		tdc_delaunay_tiled without a tile column: the query's vertices
 *		triangulated in one pass, or tile by tile through the core's bounded
 *		run, and written straight into the target: _tdc_tiled_write.
 *
 * The procedure creates the target (id bigint, tile bigint, geom
 * geometry(Polygon[Z], srid)) and calls this function once.  It reads the
 * query's geometry column the way ST_TDCDelaunayDump reads it (dump_query.c:
 * a cursor in batches, curves stroked, the SRID and dimensions checked).
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
#include "commands/tablespace.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "storage/fd.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "tiles/tile_plan.h"


/* Vertices collected before they are appended to the files: 1.5 MB of xy. */
#define STAGE_CHUNK			65536

/* Rows written between two interrupt checks (a power of two). */
#define ROWS_POLL			65536

/* A final tile's record in the triangles file: then ntri * 3 * dim doubles. */
typedef struct TileRecord
{
	int64		tile;			/* from 0, in the plan's order */
	int64		ntri;
} TileRecord;

/* Everything a run holds outside PostgreSQL's memory, freed by the callback. */
typedef struct BoundedRun
{
	char		dir[MAXPGPATH];	/* "" until made */
	char		xypath[MAXPGPATH],
				zpath[MAXPGPATH],
				tripath[MAXPGPATH];
	FILE	   *fxy,
			   *fz,
			   *ftri;
	uint64		n;				/* vertices staged */
	bool		hasz;
	int			dim;
	tdc_bounded_job *job;
	int			write_errno;	/* emit: the errno of a failed write (run's thread) */
	MemoryContextCallback cb;
} BoundedRun;

TDC_WORK_OPS(bounded_ops, tdc_bounded_job, tdc_bounded, "tiled triangulation");

/* The phase an error or a cancel came in, for its CONTEXT line. */
static void
phase_context(void *arg)
{
	errcontext("%s: %s", TILED_FNAME, *(const char **) arg);
}

static void
close_file(FILE **f)
{
	if (*f != NULL)
	{
		fclose(*f);
		*f = NULL;
	}
}

/* The run freed (canceled and joined), the files closed, the directory removed. */
static void
bounded_run_release(void *arg)
{
	BoundedRun *br = (BoundedRun *) arg;

	if (br->job != NULL)
	{
		tdc_bounded_free(br->job);
		br->job = NULL;
	}
	close_file(&br->fxy);
	close_file(&br->fz);
	close_file(&br->ftri);
	if (br->dir[0] != '\0')
	{
		(void) unlink(br->xypath);
		(void) unlink(br->zpath);
		(void) unlink(br->tripath);
		/* the run removes its own files; anything else is a leftover */
		(void) rmdir(br->dir);
		br->dir[0] = '\0';
	}
}

/* This backend's directory under the temporary tablespace's pgsql_tmp. */
static void
make_run_dir(BoundedRun *br, const char *fname)
{
	char		base[MAXPGPATH];
	Oid			tblspc;

	PrepareTempTablespaces();
	tblspc = GetNextTempTableSpace();
	TempTablespacePath(base, OidIsValid(tblspc) ? tblspc : DEFAULTTABLESPACE_OID);
	if (MakePGDirectory(base) != 0 && errno != EEXIST)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not create directory \"%s\": %m", fname, base)));
	snprintf(br->dir, sizeof(br->dir), "%s/%s%d.tdc.XXXXXX", base, PG_TEMP_FILE_PREFIX, MyProcPid);
	if (mkdtemp(br->dir) == NULL)
	{
		int			save = errno;

		br->dir[0] = '\0';
		errno = save;
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not create a temporary directory in \"%s\": %m", fname, base)));
	}
	snprintf(br->xypath, sizeof(br->xypath), "%s/input.xy", br->dir);
	snprintf(br->zpath, sizeof(br->zpath), "%s/input.z", br->dir);
	snprintf(br->tripath, sizeof(br->tripath), "%s/triangles", br->dir);
}

static FILE *
open_file(const char *path, const char *mode, const char *fname)
{
	FILE	   *f = fopen(path, mode);

	if (f == NULL)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not open file \"%s\": %m", fname, path)));
	return f;
}

static void
write_all(FILE *f, const void *p, size_t size, size_t count, const char *path, const char *fname)
{
	if (count > 0 && fwrite(p, size, count, f) != count)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not write file \"%s\": %m", fname, path)));
}

/*
 * What the staging row callback needs: where the vertices go, and whether
 * they still fit one pass.
 */
typedef struct StageArg
{
	BoundedRun *br;
	TdcPointBuf *buf;
	const tdc_options *opt;
	uint64		limit;			/* bytes; 0: none */
	bool		to_files;		/* past one pass: every chunk goes to the files */
	uint64		next_check;		/* vertex count at which the fit is checked again */
	double		lo[2],			/* the vertices' box so far */
				hi[2];
	const char *fname;
} StageArg;

/* Whether n vertices and the engine's run on them fit the limit (the Dump's check). */
static bool
one_pass_fits(const StageArg *sa, uint64 n)
{
	return sa->limit == 0 ||
		tdc_pointbuf_bytes_after(n, sa->buf->hasz) + tdc_estimate_memory((size_t) n, sa->opt) <= sa->limit;
}

/* The collected vertices appended to the files, and the buffer emptied. */
static void
stage_flush(StageArg *sa)
{
	BoundedRun *br = sa->br;
	TdcPointBuf *buf = sa->buf;

	if (buf->n == 0)
		return;
	if (br->fxy == NULL)
	{
		br->fxy = open_file(br->xypath, "wb", sa->fname);
		if (br->hasz)
			br->fz = open_file(br->zpath, "wb", sa->fname);
	}
	write_all(br->fxy, buf->xy, 2 * sizeof(double), (size_t) buf->n, br->xypath, sa->fname);
	if (br->hasz)
		write_all(br->fz, buf->z, sizeof(double), (size_t) buf->n, br->zpath, sa->fname);
	br->n += buf->n;
	buf->n = 0;
}

/*
 * One pass no longer fits: the directory made, the buffer's vertices to the
 * files, and its arrays given back.  The buffer has a context of its own
 * (made for it in _tdc_tiled_write), so resetting that context frees its
 * arrays and unmaps its mappings; the SRID and dimensions stay.
 */
static void
stage_to_files(StageArg *sa)
{
	TdcPointBuf *buf = sa->buf;

	sa->br->hasz = buf->hasz;
	sa->br->dim = buf->hasz ? 3 : 2;
	make_run_dir(sa->br, sa->fname);
	sa->to_files = true;
	stage_flush(sa);
	MemoryContextReset(buf->cxt);
	buf->map = NULL;
	buf->xy = buf->z = NULL;
	buf->n = buf->cap = 0;
	buf->side_bytes = 0;
}

/*
 * After each row (tdc_dump_collect's row_fn): its vertices' corner, and
 * every STAGE_CHUNK vertices, once one pass no longer fits, the buffer to
 * the files.  The first switch gives the buffer's big arrays back.
 */
static void
stage_row(void *arg, uint64 first)
{
	StageArg   *sa = (StageArg *) arg;
	TdcPointBuf *buf = sa->buf;

	for (uint64 i = first; i < buf->n; i++)
	{
		sa->lo[0] = Min(sa->lo[0], buf->xy[2 * i]);
		sa->lo[1] = Min(sa->lo[1], buf->xy[2 * i + 1]);
		sa->hi[0] = Max(sa->hi[0], buf->xy[2 * i]);
		sa->hi[1] = Max(sa->hi[1], buf->xy[2 * i + 1]);
	}
	if (!sa->to_files)
	{
		if (buf->n < sa->next_check)
			return;
		sa->next_check = buf->n + STAGE_CHUNK;
		if (!one_pass_fits(sa, buf->n))
			stage_to_files(sa);
		return;
	}
	if (buf->n >= STAGE_CHUNK)
		stage_flush(sa);
}

static void
finish_file(FILE **f, const char *path, const char *fname)
{
	FILE	   *g = *f;

	*f = NULL;
	if (g != NULL && fclose(g) != 0)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not write file \"%s\": %m", fname, path)));
}

/*
 * The run's emit, on its thread: a final tile's triangles to the
 * triangles file as coordinates.  No PostgreSQL call here; a failed write
 * keeps its errno for the backend's message and stops the run.
 */
static int
emit_triangles(void *arg, int tile, const double *q, const double *qz, const size_t *tri, size_t ntri)
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

/* The bounded run's triangles file into the target: ids (t + 1) * 2^32 + k. */
static void
write_rows_from_file(BoundedRun *br, TdcTableWriter *tw, const double origin[2], double size,
					 const char *fname)
{
	double		v[9];
	TileRecord	rec;

	br->ftri = open_file(br->tripath, "rb", fname);
	while (fread(&rec, sizeof(rec), 1, br->ftri) == 1)
	{
		int64		label = rec.tile + 1;

		for (int64 k = 1; k <= rec.ntri; k++)
		{
			read_all(br->ftri, v, sizeof(double) * 3 * br->dim, br->tripath, fname);
			tdc_table_writer_put(tw, (label << 32) + k, row_tile(v, br->dim, origin, size, label), v);
		}
	}
	if (ferror(br->ftri))
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not read file \"%s\": %m", fname, br->tripath)));
	close_file(&br->ftri);
}

/* One pass's triangles into the target: ids 2^32 + k, tile 0, in the Dump's order. */
static void
write_rows_from_job(const TdcRun *run, const TdcPointBuf *buf, TdcTableWriter *tw,
					const double origin[2], double size)
{
	int			dim = buf->hasz ? 3 : 2;
	tdc_iter	it = {0};
	uint32		t[3];
	double		v[9];
	int64		k = 0;

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
		tdc_table_writer_put(tw, ((int64) 1 << 32) + ++k, row_tile(v, dim, origin, size, 0), v);
	}
}

/* The bounded run on the staged files, waited on with interrupts watched. */
static void
run_tiles(BoundedRun *br, const tdc_options *opt, uint64 limit_mb, const char *setting,
		  uint64 outside, tdc_bounded_stats *st, const char *fname)
{
	tdc_bounded_params p;
	char		err[640];
	int			rc;

	br->ftri = open_file(br->tripath, "wb", fname);
	memset(&p, 0, sizeof(p));
	p.xypath = br->xypath;
	p.zpath = br->hasz ? br->zpath : NULL;
	p.n = (size_t) br->n;
	p.opt = opt;
	p.limit = (size_t) (limit_mb << 20);
	p.outside = (size_t) outside;
	p.tmpdir = br->dir;
	p.limit_name = setting;
	p.emit = emit_triangles;
	p.arg = br;
	rc = tdc_bounded_start(&p, &br->job, err, sizeof(err));
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	rc = tdc_wait_work(br->job, &bounded_ops, fname);
	if (rc != TDC_OK)
	{
		if (br->write_errno != 0)
		{
			errno = br->write_errno;
			ereport(ERROR,
					(errcode_for_file_access(),
					 errmsg("%s: could not write file \"%s\": %m", fname, br->tripath)));
		}
		snprintf(err, sizeof(err), "%s", tdc_bounded_error(br->job));
		tdc_report_status(rc, err, fname);
	}
	*st = *tdc_bounded_stats_of(br->job);
	tdc_bounded_free(br->job);
	br->job = NULL;
	finish_file(&br->ftri, br->tripath, fname);
}

PG_FUNCTION_INFO_V1(_tdc_tiled_write);

/*
 * _tdc_tiled_write(query text, target regclass, tile_size float8) RETURNS int8
 * The Delaunay triangles of the query's vertices (its one geometry column,
 * as ST_TDCDelaunayDump takes it) into target, which the caller created in
 * this transaction (table_write.c); tile_size NULL: no squares.  Returns
 * the rows written; see the top of this file.  Internal to
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
	br->cb.func = bounded_run_release;
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
	memset(&sa, 0, sizeof(sa));
	sa.br = br;
	sa.buf = &buf;
	sa.opt = &opt;
	sa.limit = limit_mb << 20;
	sa.next_check = STAGE_CHUNK;
	sa.lo[0] = sa.lo[1] = INFINITY;
	sa.hi[0] = sa.hi[1] = -INFINITY;
	sa.fname = fname;
	tdc_dump_collect(&buf, NULL, query, tw.geomoid, fname, stage_row, &sa);
	if (!sa.to_files && buf.n > 0 && !one_pass_fits(&sa, buf.n))
		stage_to_files(&sa);
	if (sa.to_files)
	{
		stage_flush(&sa);
		finish_file(&br->fxy, br->xypath, fname);
		finish_file(&br->fz, br->zpath, fname);
	}
	npts = sa.to_files ? br->n : buf.n;
	read_s = tdc_ms_since(t0) / 1000;
	if (npts > 0)
		tdc_table_writer_shape(&tw, buf.hasz ? 3 : 2, buf.srid, fname);
	/* squares too small for the data are refused before the work */
	if (npts > 0 && size > 0)
		(void) tdc_tiled_square_label(sa.hi[0], sa.hi[1], sa.lo, size);

	if (!sa.to_files)
	{
		/* one pass, the Dump's run */
		TdcRun	   *run;

		phase = "triangulating";
		INSTR_TIME_SET_CURRENT(t0);
		if (npts > 0)
		{
			run = tdc_run(&buf, 0, 0, fname);
			tiles_s = tdc_ms_since(t0) / 1000;
			phase = "writing the rows";
			INSTR_TIME_SET_CURRENT(t0);
			write_rows_from_job(run, &buf, &tw, sa.lo, size);
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
						size > 0 ? psprintf(" (labelled by squares of tile_size %.17g)", size) : " in 1 tile"),
				 tdc_guc_stats ? errdetail("Phases in seconds: read %.3f, triangulate %.3f, rows %.3f.",
										   read_s, tiles_s, rows_s) : 0));
		PG_RETURN_INT64((int64) tw.rows);
	}

	/* the tiles, on the run's thread, while this one watches its interrupts */
	phase = "running the tiles";
	INSTR_TIME_SET_CURRENT(t0);
	/* the staging buffer, still allocated, is beside the run */
	run_tiles(br, &opt, limit_mb, setting, tdc_pointbuf_bytes(&buf), &st, fname);
	tiles_s = tdc_ms_since(t0) / 1000;

	phase = "writing the rows";
	INSTR_TIME_SET_CURRENT(t0);
	write_rows_from_file(br, &tw, sa.lo, size, fname);
	rows_s = tdc_ms_since(t0) / 1000;
	tdc_table_writer_close(&tw);
	bounded_run_release(br);
	error_context_stack = errcb.previous;

	ereport(NOTICE,
			(errmsg("%s: %llu triangles from %llu points%s in %d tile%s under %s = %llu MB, "
					"%zu tile run%s, %zu halo points",
					fname, (unsigned long long) tw.rows, (unsigned long long) npts,
					size > 0 ? psprintf(" (labelled by squares of tile_size %.17g)", size) : "",
					st.tiles, st.tiles == 1 ? "" : "s", setting, (unsigned long long) limit_mb,
					st.runs, st.runs == 1 ? "" : "s", st.halo),
			 errdetail("Phases in seconds: read %.3f, scan %.3f, bin %.3f, gather %.3f, engine %.3f, "
					   "finish %.3f, rows %.3f (the tiles %.3f in all).",
					   read_s, st.scan, st.bin, st.gather, st.engine, st.finish, rows_s, tiles_s)));
	PG_RETURN_INT64((int64) tw.rows);
}
