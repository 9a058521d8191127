/*
 * tin_run.c
 *		A TIN inside a backend: the triangulation of the samples and its
 *		TIN built and waited for, an operation on the TIN (contours, a
 *		drape) run and waited for, and all of it freed.
 *
 * The samples, with heights, are read by tdc_tin_read_sample
 * (toast_stream.c).  Samples with equal x and y keep the height of the
 * first (the site's first input point; under a parallel plan "first"
 * follows the order in which partial states are combined).
 *
 * Breaklines.  With "linear:breaklines=true" the owner has the samples'
 * linework reported as segments (seglist.c), and they are inserted into
 * the triangulation before the TIN is built on it, as the constrained
 * functions insert theirs: crossing segments are an ERROR naming them, and
 * curves are refused, as there (the owner sets the buffer so).
 *
 * Running.  The triangulation is tdc_run's (run.c), with the TIN's own
 * memory and the caller's extra bytes counted as its result, so one
 * tdc_delaunay.max_memory check covers the vertices, the engine, the TIN
 * and what the caller will hold; the TIN and its operations get what is
 * left as their max_memory.  The TIN is started on the engine's threads and
 * waited for with tdc_wait_work, the one interrupt-watching wait loop, as
 * is every operation on it.  A reset callback on the point buffer's context
 * frees the TIN on an error; it is registered after the job's, so it runs
 * first (callbacks run newest first), and the TIN, which reads the job,
 * goes before it.
 */
#include "postgres.h"

#include "fmgr.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

TDC_WORK_OPS(tin_ops, tdc_tin, tdc_tin, "TIN operation");

/* ----------------------------------------------------------------
 *		the TIN
 * ----------------------------------------------------------------
 */
static void
tin_reset_callback(void *arg)
{
	TdcTinRun  *tr = (TdcTinRun *) arg;

	/* only errors and cancels get here: stop it before the job goes */
	if (tr->tin != NULL)
	{
		tdc_tin_free(tr->tin);
		tr->tin = NULL;
	}
}

/*
 * Triangulate buf's samples and build their TIN, waiting interruptibly;
 * breaklines (or NULL): segments inserted into the triangulation first, so
 * that the TIN is the constrained one; extra: bytes the caller holds beside
 * them (its input and result), for the tdc_delaunay.max_memory check.  Any
 * failure is an ERROR.
 */
TdcTinRun *
tdc_tin_run_start(const TdcPointBuf *buf, const TdcSegList *breaklines, uint64 extra,
				  const char *fname)
{
	TdcTinRun  *tr;
	MemoryContextCallback *cb;
	uint64		limit = tdc_max_memory_bytes(),
				tin_bytes = tdc_tin_memory((size_t) buf->n);
	size_t		room = 0;
	char		err[256];
	int			rc;

	if (buf->n > 0 && !buf->hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the samples have no Z coordinate", fname)));
	tr = MemoryContextAllocZero(buf->cxt, sizeof(TdcTinRun));
	tr->run = tdc_run(buf, 0.0, tin_bytes + extra, fname);
	if (limit > 0)
	{
		uint64		used = tdc_pointbuf_bytes(buf) + tr->run->engine_bytes + extra;

		/* tdc_run checked that the TIN's own arrays fit beside them */
		room = (size_t) (limit > used ? limit - used : 1);
	}
	tr->max_memory = room;

	/*
	 * The breaklines: inserted (tdc_cdt_start checks its own arrays against
	 * the limit beside the job's) and the insertion freed before the TIN is
	 * built, so the two never hold memory at once.
	 */
	if (breaklines != NULL && breaklines->nseg > 0)
		tdc_constrain_release(tdc_constrain(tr->run, buf, breaklines, fname));

	cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
	cb->func = tin_reset_callback;
	cb->arg = tr;
	MemoryContextRegisterResetCallback(buf->cxt, cb);

	err[0] = '\0';
	rc = tdc_tin_start(tr->run->job, buf->z, tdc_effective_threads(), room, &tr->tin,
					   err, sizeof(err));
	if (rc != TDC_OK)
	{
		tr->tin = NULL;
		tdc_report_status(rc, err, fname);
	}
	tdc_finish_work((void **) &tr->tin, &tin_ops, fname);
	return tr;
}

/*
 * Wait for the operation just started on the TIN (rc and err from its
 * start), interruptibly; any failure is an ERROR.
 */
void
tdc_tin_run_wait(TdcTinRun *tr, int rc, const char *err, const char *fname)
{
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	tdc_finish_work((void **) &tr->tin, &tin_ops, fname);
}

/* Free the TIN, then the triangulation (see tdc_run_free). */
void
tdc_tin_run_free(TdcTinRun *tr)
{
	if (tr->tin != NULL)
	{
		tdc_tin_free(tr->tin);
		tr->tin = NULL;
	}
	tdc_run_free(tr->run);
}
