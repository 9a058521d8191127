/*
 * tiled_stage.c
 *		A tiled procedure's vertices: in memory while one pass fits, then
 *		appended to files, a chunk at a time, for the core's bounded run.
 *
 * The procedures (tdc_delaunay_tiled, tdc_interpolate_tiled,
 * tdc_contours_tiled) read their source the way the Dump reads it
 * (dump_query.c), into a point buffer: a geometry column, or a pcpatch
 * column through the pointcloud extension's forms of their internal
 * functions (tdc_stage_pc_column).  Every STAGE_CHUNK vertices the
 * row callback checks whether the vertices, the engine's estimate for
 * them, and what the caller will hold beside one pass (a TIN, a grid, the
 * tile column's labels) still fit tdc_delaunay.max_memory; the first time
 * they do not, a directory of this backend is made under the temporary
 * tablespace's pgsql_tmp, the buffer goes to files there (x,y pairs, Z,
 * labels) and every later chunk follows it.  The files and the directory
 * go with the caller's memory context (tdc_stage_release, registered by
 * the caller as a reset callback, which first frees the bounded run: that
 * cancels and joins its thread), on success or on error.
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
#include "storage/fd.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "fn/tiled_stage.h"

TDC_WORK_OPS(bounded_ops, tdc_bounded_job, tdc_bounded, "tiled run");

void
tdc_stage_close(FILE **f)
{
	if (*f != NULL)
	{
		fclose(*f);
		*f = NULL;
	}
}

/* The run freed (canceled and joined), the files closed, the directory removed. */
void
tdc_stage_release(void *arg)
{
	BoundedRun *br = (BoundedRun *) arg;

	tdc_stage_stop(br);
	tdc_stage_close(&br->fxy);
	tdc_stage_close(&br->fz);
	tdc_stage_close(&br->fl);
	tdc_stage_close(&br->fin);
	tdc_stage_close(&br->ftri);
	if (br->dir[0] != '\0')
	{
		(void) unlink(br->xypath);
		(void) unlink(br->zpath);
		(void) unlink(br->lpath);
		(void) unlink(br->lrawpath);
		(void) unlink(br->tripath);
		/* the run removes its own files; anything else is a leftover */
		(void) rmdir(br->dir);
		br->dir[0] = '\0';
	}
}

/* This backend's directory under the temporary tablespace's pgsql_tmp. */
void
tdc_stage_make_dir(BoundedRun *br, const char *fname)
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
	snprintf(br->lpath, sizeof(br->lpath), "%s/input.l", br->dir);
	snprintf(br->lrawpath, sizeof(br->lrawpath), "%s/input.v", br->dir);
	snprintf(br->tripath, sizeof(br->tripath), "%s/triangles", br->dir);
}

FILE *
tdc_stage_open(const char *path, const char *mode, const char *fname)
{
	FILE	   *f = fopen(path, mode);

	if (f == NULL)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not open file \"%s\": %m", fname, path)));
	return f;
}

void
tdc_stage_write(FILE *f, const void *p, size_t size, size_t count, const char *path, const char *fname)
{
	if (count > 0 && fwrite(p, size, count, f) != count)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not write file \"%s\": %m", fname, path)));
}



/* The bytes the labels of n vertices take in memory, grown by doubling as the buffer grows. */
uint64
tdc_stage_labels_bytes(uint64 n)
{
	uint64		cap = 16;

	while (cap < n)
		cap *= 2;
	return cap * sizeof(int64);
}

/* What the tile values hold: counted beside the vertices. */
uint64
tdc_stage_values_bytes(const StageArg *sa)
{
	return sa->tv ? sa->tv->bytes : 0;
}

/*
 * Whether n vertices and the engine's run on them fit the limit (the
 * Dump's check), with their labels and the tile values when tagged.
 */
bool
tdc_stage_fits(const StageArg *sa, uint64 n)
{
	return sa->limit == 0 ||
		tdc_pointbuf_bytes_after(n, sa->buf->hasz) + (sa->tagged ? tdc_stage_labels_bytes(n) : 0) +
		tdc_stage_values_bytes(sa) + tdc_estimate_memory((size_t) n, sa->opt) +
		sa->beside + (sa->tin ? tdc_tin_memory((size_t) n) : 0) <= sa->limit;
}

/* The collected vertices appended to the files, and the buffer emptied. */
void
tdc_stage_flush(StageArg *sa)
{
	BoundedRun *br = sa->br;
	TdcPointBuf *buf = sa->buf;

	if (buf->n == 0)
		return;
	if (br->fxy == NULL)
	{
		br->fxy = tdc_stage_open(br->xypath, "wb", sa->fname);
		if (br->hasz)
			br->fz = tdc_stage_open(br->zpath, "wb", sa->fname);
		if (br->hasl)
			br->fl = tdc_stage_open(br->lrawpath, "wb", sa->fname);
	}
	tdc_stage_write(br->fxy, buf->xy, 2 * sizeof(double), (size_t) buf->n, br->xypath, sa->fname);
	if (br->hasz)
		tdc_stage_write(br->fz, buf->z, sizeof(double), (size_t) buf->n, br->zpath, sa->fname);
	if (br->hasl)
		tdc_stage_write(br->fl, sa->lab, sizeof(int64), (size_t) buf->n, br->lrawpath, sa->fname);
	br->n += buf->n;
	buf->n = 0;
}

/*
 * One pass no longer fits: the directory made, the buffer's vertices to the
 * files, and its arrays given back.  The buffer has a context of its own
 * (made for it in _tdc_tiled_write), so resetting that context frees its
 * arrays and unmaps its mappings; the SRID and dimensions stay.
 */
void
tdc_stage_to_files(StageArg *sa)
{
	TdcPointBuf *buf = sa->buf;

	sa->br->hasz = buf->hasz;
	sa->br->hasl = sa->tagged;
	sa->br->dim = buf->hasz ? 3 : 2;
	tdc_stage_make_dir(sa->br, sa->fname);
	sa->to_files = true;
	tdc_stage_flush(sa);
	MemoryContextReset(buf->cxt);
	buf->map = NULL;
	buf->xy = buf->z = NULL;
	buf->n = buf->cap = 0;
	buf->side_bytes = 0;
	sa->lab = NULL;
	sa->lab_cap = 0;
}

/*
 * After each row (tdc_dump_collect's row_fn): its vertices' corner, and
 * every STAGE_CHUNK vertices, once one pass no longer fits, the buffer to
 * the files.  The first switch gives the buffer's big arrays back.
 */
void
tdc_stage_row(void *arg, uint64 first)
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
		if (!tdc_stage_fits(sa, buf->n))
			tdc_stage_to_files(sa);
		return;
	}
	if (buf->n >= STAGE_CHUNK)
		tdc_stage_flush(sa);
}

void
tdc_stage_finish(FILE **f, const char *path, const char *fname)
{
	FILE	   *g = *f;

	*f = NULL;
	if (g != NULL && fclose(g) != 0)
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not write file \"%s\": %m", fname, path)));
}

/*
 * The bounded run on the staged files, waited on with interrupts watched:
 * p has the caller's callbacks (emit, begin, arg, any_order) and nothing
 * else; what names the work in a cancel's message; cb_err (or NULL) a
 * callback's own message, reported instead of the run's when set.  A
 * failed write of the triangles file (br->write_errno) is reported as
 * such.  *st: the run's stats; the job is freed.
 */
void
tdc_stage_run(BoundedRun *br, tdc_bounded_params *p, const tdc_options *opt, uint64 limit_mb,
			  const char *setting, uint64 outside, const char *what, const char *cb_err,
			  tdc_bounded_stats *st, const char *fname)
{
	TdcWorkOps	ops = bounded_ops;
	char		err[1024];
	int			rc;

	ops.what = what;
	p->xypath = br->xypath;
	p->zpath = br->hasz ? br->zpath : NULL;
	p->lpath = br->hasl ? br->lpath : NULL;
	p->n = (size_t) br->n;
	p->opt = opt;
	p->limit = (size_t) (limit_mb << 20);
	p->outside = (size_t) outside;
	p->tmpdir = br->dir;
	/* the staged files are ours: their disk goes to the tiles once binned */
	p->drop_input = true;
	p->limit_name = setting;
	rc = tdc_bounded_start(p, &br->job, err, sizeof(err));
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	rc = tdc_wait_work(br->job, &ops, fname);
	if (rc != TDC_OK)
	{
		tdc_stage_write_error(br, fname);
		snprintf(err, sizeof(err), "%s", cb_err && cb_err[0] ? cb_err : tdc_bounded_error(br->job));
		tdc_report_status(rc, err, fname);
	}
	*st = *tdc_bounded_stats_of(br->job);
	tdc_bounded_free(br->job);
	br->job = NULL;
}

/*
 * The staging of a call set up: sa for the row callback (tdc_stage_row),
 * br the call's run (zeroed, its release registered by the caller), buf
 * the point buffer, limit_mb the limit in MB (0: none).
 */
void
tdc_stage_init(StageArg *sa, BoundedRun *br, TdcPointBuf *buf, MemoryContext cxt,
			   const tdc_options *opt, uint64 limit_mb, const char *fname)
{
	memset(sa, 0, sizeof(*sa));
	sa->br = br;
	sa->buf = buf;
	sa->cxt = cxt;
	sa->opt = opt;
	sa->limit = limit_mb << 20;
	sa->next_check = STAGE_CHUNK;
	sa->lo[0] = sa->lo[1] = INFINITY;
	sa->hi[0] = sa->hi[1] = -INFINITY;
	sa->fname = fname;
}

/*
 * After the source is read: to the files if one pass does not fit the
 * whole of it, and then the files completed and closed.  Returns the
 * vertices read.
 */
uint64
tdc_stage_done(StageArg *sa)
{
	BoundedRun *br = sa->br;

	if (!sa->to_files && sa->buf->n > 0 && !tdc_stage_fits(sa, sa->buf->n))
		tdc_stage_to_files(sa);
	if (!sa->to_files)
		return sa->buf->n;
	tdc_stage_flush(sa);
	tdc_stage_finish(&br->fxy, br->xypath, sa->fname);
	tdc_stage_finish(&br->fz, br->zpath, sa->fname);
	tdc_stage_finish(&br->fl, br->lrawpath, sa->fname);
	return br->n;
}

/* The run stopped and joined (before what its callbacks use is freed). */
void
tdc_stage_stop(BoundedRun *br)
{
	if (br->job != NULL)
	{
		tdc_bounded_free(br->job);
		br->job = NULL;
	}
}

/* An ERROR for a failed write of br->tripath (br->write_errno), if there was one. */
void
tdc_stage_write_error(BoundedRun *br, const char *fname)
{
	if (br->write_errno != 0)
	{
		errno = br->write_errno;
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not write file \"%s\": %m", fname, br->tripath)));
	}
}

/*
 * The source column of a tiled procedure's call: NULL for geometries; for
 * pgpointcloud patches, the pcpatch reader's state with the filter.  The
 * internal functions' pcpatch forms, declared only by
 * tdc_delaunay_pointcloud, take one argument more than the geometry forms
 * (geometry_nargs): the filter, NULL for none.
 */
TdcPcColumn *
tdc_stage_pc_column(FunctionCallInfo fcinfo, int geometry_nargs, MemoryContext cxt)
{
	TdcPcColumn *pc;

	if (PG_NARGS() <= geometry_nargs)
		return NULL;
	pc = MemoryContextAllocZero(cxt, sizeof(TdcPcColumn));
	pc->cxt = cxt;
	pc->filter = PG_ARGISNULL(geometry_nargs) ? NULL :
		MemoryContextStrdup(cxt, text_to_cstring(PG_GETARG_TEXT_PP(geometry_nargs)));
	return pc;
}

/* The consumer's run set up in cxt: its BoundedRun made, its release registered. */
void
tdc_stage_consumer_init(StageConsumer *sc, MemoryContext cxt, StageTileFn tile, void (*free_obj) (void *obj))
{
	sc->br = MemoryContextAllocZero(cxt, sizeof(BoundedRun));
	sc->obj = NULL;
	sc->tile = tile;
	sc->free_obj = free_obj;
	sc->err[0] = '\0';
	sc->cb.func = tdc_stage_consumer_release;
	sc->cb.arg = sc;
	MemoryContextRegisterResetCallback(cxt, &sc->cb);
}

/* The run's emit, on its thread: a final tile's triangles to the consumer. */
int
tdc_stage_consumer_emit(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
						const size_t *tri, size_t ntri)
{
	StageConsumer *sc = (StageConsumer *) arg;

	(void) tile;
	(void) ql;
	return sc->tile(sc->obj, q, qz, tri, ntri, sc->err, sizeof(sc->err));
}

/* On any end of the call: the run joined, the consumer freed, the files and the directory gone. */
void
tdc_stage_consumer_release(void *arg)
{
	StageConsumer *sc = (StageConsumer *) arg;

	/* the run's thread uses the consumer: it goes first; the consumer's files before the directory */
	tdc_stage_stop(sc->br);
	if (sc->obj != NULL)
	{
		sc->free_obj(sc->obj);
		sc->obj = NULL;
	}
	tdc_stage_release(sc->br);
}
