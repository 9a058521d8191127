/*
 * fn_tiled_bounded.c
 *		The tiled triangulation of a query's vertices through the core's
 *		bounded run, for tdc_delaunay_tiled with automatic tiles on plain
 *		PostgreSQL: _tdc_tiled_bounded(query), the rows of the target.
 *
 * tdc_delaunay_tiled runs an input that does not fit one triangulation
 * under tdc_delaunay.max_memory.  With automatic tiles on plain PostgreSQL
 * it makes no staging tables: this function reads the query's geometry
 * column the way ST_TDCDelaunayDump reads it (dump_query.c: a cursor in
 * batches, curves stroked, the SRID and dimensions checked), but instead
 * of keeping the vertices it appends them a chunk at a time to a file, and
 * then hands the file to the core's bounded run (tdc_bounded_start,
 * src/core/bounded*.c), the one ./tdc --max-memory runs: the same plan of
 * tiles cut by counts, the same halos and reruns in the files, so the same
 * triangles, each once, in bounded memory.  The run works on a thread of
 * its own while this backend waits with its interrupts watched (run.c's
 * wait loop: a cancel stops a tile's engine within milliseconds).  Its
 * emit callback, on the run's thread, never calls PostgreSQL: it appends
 * each final tile's triangles as coordinates to a third file, which the
 * backend reads back once the run is done, writing one row per triangle
 * into the function's materialized result (a tuplestore, spilled to disk
 * past work_mem).  The procedure makes the target from these rows with
 * CREATE TABLE AS, which writes in bulk; an error or a cancel anywhere
 * leaves no target, since it is one statement of the caller's transaction.
 *
 * The files live in a directory of this backend under the temporary
 * tablespace's pgsql_tmp (removed by the server at restart if a crash left
 * it), made here and removed with everything in it when the function's
 * memory goes, on success or on error (a reset callback, which first frees
 * the run: that cancels and joins its thread).
 *
 * Memory: the limit handed to the run is tdc_delaunay.max_memory (within
 * tdc_delaunay.memory_ceiling), less the chunk buffer this backend holds;
 * the run plans its tiles within it or refuses before any work, with this
 * input's floor.  A row is one triangle: the result never builds a value.
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
#include "funcapi.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "storage/fd.h"
#include "utils/builtins.h"
#include "utils/tuplestore.h"

#include "tdc_pg.h"
#include "tile_plan.h"


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

/* What the staging row callback needs. */
typedef struct StageArg
{
	BoundedRun *br;
	TdcPointBuf *buf;
	const char *fname;
} StageArg;

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
		/* the first vertices say whether there is z: every row must agree */
		br->hasz = buf->hasz;
		br->dim = buf->hasz ? 3 : 2;
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

/* After each row: a full chunk goes to the files (tdc_dump_collect's row_fn). */
static void
stage_row(void *arg, uint64 first)
{
	StageArg   *sa = (StageArg *) arg;

	(void) first;
	if (sa->buf->n >= STAGE_CHUNK)
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

/*
 * The triangles file as rows (id, tile, geom): ids (t + 1) * 2^32 + k,
 * k = 1.. within the run's tile t, as the procedure's other paths number
 * them; the tile t + 1, or with squares (size > 0) the label of the square
 * of side size from origin that holds the triangle's owning vertex
 * (tdc_tp_owner_vertex): the square a run tiled by squares keeps it in.
 */
static uint64
write_rows(BoundedRun *br, ReturnSetInfo *rsinfo, int32 srid, const double origin[2], double size,
		   const char *fname)
{
	struct varlena *g = palloc(tdc_gser_triangle_size(br->hasz));
	Datum		values[3];
	bool		nulls[3] = {false, false, false};
	double		v[9];
	TileRecord	rec;
	uint64		rows = 0;

	br->ftri = open_file(br->tripath, "rb", fname);
	values[2] = PointerGetDatum(g);
	while (fread(&rec, sizeof(rec), 1, br->ftri) == 1)
	{
		int64		label = rec.tile + 1;

		for (int64 k = 1; k <= rec.ntri; k++)
		{
			read_all(br->ftri, v, sizeof(double) * 3 * br->dim, br->tripath, fname);
			tdc_gser_write_triangle_coords(g, v, br->dim, srid);
			values[0] = Int64GetDatum((label << 32) + k);
			if (size > 0)
			{
				const double *o = v + br->dim * tdc_tp_owner_vertex(v, v + br->dim, v + 2 * br->dim);

				values[1] = Int64GetDatum(tdc_tiled_square_label(o[0], o[1], origin, size));
			}
			else
				values[1] = Int64GetDatum(label);
			tuplestore_putvalues(rsinfo->setResult, rsinfo->setDesc, values, nulls);
			if ((++rows & (ROWS_POLL - 1)) == 0)
				CHECK_FOR_INTERRUPTS();
		}
	}
	if (ferror(br->ftri))
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not read file \"%s\": %m", fname, br->tripath)));
	close_file(&br->ftri);
	pfree(g);
	return rows;
}

PG_FUNCTION_INFO_V1(_tdc_tiled_bounded);

/*
 * _tdc_tiled_bounded(query text [, origin_x float8, origin_y float8, size float8])
 *		RETURNS TABLE(id bigint, tile bigint, geom geometry)
 * The Delaunay triangles of the query's vertices (its one geometry column,
 * as ST_TDCDelaunayDump takes it), tile by tile in bounded memory; see
 * the top of this file.  With squares, each triangle's tile is the label of
 * its square (tdc_tiled_square_label).  Internal to tdc_delaunay_tiled.
 */
Datum
_tdc_tiled_bounded(PG_FUNCTION_ARGS)
{
	const char *fname = TILED_FNAME;
	ReturnSetInfo *rsinfo = (ReturnSetInfo *) fcinfo->resultinfo;
	const char *setting;
	uint64		limit_mb = tdc_memory_limit_mb(&setting);
	char	   *query;
	double		origin[2] = {0, 0},
				size = 0;
	MemoryContext cxt;
	BoundedRun *br;
	TdcPointBuf buf;
	StageArg	sa;
	tdc_options opt;
	tdc_bounded_params p;
	tdc_bounded_stats st;
	const char *phase = "reading the source";
	ErrorContextCallback errcb;
	instr_time	t0;
	double		stage_s,
				tiles_s,
				rows_s;
	uint64		rows;
	char		err[640];
	int			rc;

	tdc_signal_guard();
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	if (PG_NARGS() == 4)
	{
		origin[0] = PG_GETARG_FLOAT8(1);
		origin[1] = PG_GETARG_FLOAT8(2);
		size = PG_GETARG_FLOAT8(3);
		if (!(size > 0 && size < INFINITY))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: tile_size must be positive and finite, not %g", fname, size)));
	}
	InitMaterializedSRF(fcinfo, 0);
	if (limit_mb == 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tiles need a memory limit: set tdc_delaunay.max_memory", fname)));

	/* the files go with this call's memory, whatever ends it */
	cxt = rsinfo->econtext->ecxt_per_query_memory;
	br = MemoryContextAllocZero(cxt, sizeof(BoundedRun));
	br->cb.func = bounded_run_release;
	br->cb.arg = br;
	MemoryContextRegisterResetCallback(cxt, &br->cb);
	make_run_dir(br, fname);
	errcb.callback = phase_context;
	errcb.arg = (void *) &phase;
	errcb.previous = error_context_stack;
	error_context_stack = &errcb;

	/* the vertices to the files, a chunk at a time */
	INSTR_TIME_SET_CURRENT(t0);
	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_STROKE;
	sa.br = br;
	sa.buf = &buf;
	sa.fname = fname;
	tdc_dump_collect(&buf, NULL, query, TupleDescAttr(rsinfo->setDesc, 2)->atttypid, fname,
					 stage_row, &sa);
	stage_flush(&sa);
	finish_file(&br->fxy, br->xypath, fname);
	finish_file(&br->fz, br->zpath, fname);
	stage_s = tdc_ms_since(t0) / 1000;
	if (br->n == 0)
	{
		error_context_stack = errcb.previous;
		return (Datum) 0;
	}

	/* the tiles, on the run's thread, while this one watches its interrupts */
	phase = "running the tiles";
	INSTR_TIME_SET_CURRENT(t0);
	tdc_session_options(&opt);
	br->ftri = open_file(br->tripath, "wb", fname);
	memset(&p, 0, sizeof(p));
	p.xypath = br->xypath;
	p.zpath = br->hasz ? br->zpath : NULL;
	p.n = (size_t) br->n;
	p.opt = &opt;
	p.limit = (size_t) (limit_mb << 20);
	/* the staging chunk, still allocated, is beside the run */
	p.outside = (size_t) tdc_pointbuf_bytes(&buf);
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
	st = *tdc_bounded_stats_of(br->job);
	tdc_bounded_free(br->job);
	br->job = NULL;
	finish_file(&br->ftri, br->tripath, fname);
	tiles_s = tdc_ms_since(t0) / 1000;

	/* the rows */
	phase = "writing the rows";
	INSTR_TIME_SET_CURRENT(t0);
	rows = write_rows(br, rsinfo, buf.srid, origin, size, fname);
	rows_s = tdc_ms_since(t0) / 1000;
	bounded_run_release(br);
	error_context_stack = errcb.previous;

	ereport(NOTICE,
			(errmsg("%s: %llu triangles from %llu points%s in %d tile%s under %s = %llu MB, "
					"%zu tile run%s, %zu halo points",
					fname, (unsigned long long) rows, (unsigned long long) br->n,
					size > 0 ? psprintf(" (labelled by squares of tile_size %.17g)", size) : "",
					st.tiles, st.tiles == 1 ? "" : "s", setting, (unsigned long long) limit_mb,
					st.runs, st.runs == 1 ? "" : "s", st.halo),
			 errdetail("Phases in seconds: read %.3f, scan %.3f, bin %.3f, gather %.3f, engine %.3f, "
					   "finish %.3f, rows %.3f (the tiles %.3f in all).",
					   stage_s, st.scan, st.bin, st.gather, st.engine, st.finish, rows_s, tiles_s)));
	return (Datum) 0;
}

PG_FUNCTION_INFO_V1(_tdc_tiled_fits);

/*
 * _tdc_tiled_fits(npts int8, hasz bool) RETURNS bool
 * Whether ST_TDCDelaunayDump of npts vertices fits tdc_delaunay.max_memory
 * (within tdc_delaunay.memory_ceiling): its collected vertices and the
 * engine's estimate, the figure its run checks.  tdc_delaunay_tiled with
 * automatic tiles then runs it in one pass, and else in tiles here.
 */
Datum
_tdc_tiled_fits(PG_FUNCTION_ARGS)
{
	int64		npts = PG_GETARG_INT64(0);
	bool		hasz = PG_GETARG_BOOL(1);
	uint64		limit = tdc_max_memory_bytes();
	tdc_options opt;

	if (limit == 0 || npts <= 0)
		PG_RETURN_BOOL(true);
	tdc_session_options(&opt);
	PG_RETURN_BOOL(tdc_pointbuf_bytes_after((uint64) npts, hasz) +
				   tdc_estimate_memory((size_t) npts, &opt) <= limit);
}
