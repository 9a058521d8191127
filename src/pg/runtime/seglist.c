/*
 * seglist.c
 *		Constraint segments taken from the linework of geometry values, and
 *		their insertion into a finished triangulation: what the constrained
 *		functions (fn_constrained.c) and the breaklines of the TIN functions
 *		(tin_run.c, "linear:breaklines=true") share.
 *
 * Segments are pairs of vertex indices into a point buffer, in a memory
 * context of their owner's choosing; they count with the buffer's vertices
 * against tdc_delaunay.max_memory (tdc_pointbuf_side_grow).  While a value
 * is read, the reader reports its chains (TdcChainFn: every linestring and
 * every polygon ring, triangles and the faces of TINs and polyhedral
 * surfaces included; points are no chain) and they are only noted:
 * tdc_seg_flush makes them segments, each chain of k vertices k - 1 of
 * them, once the value's vertices are all in the buffer, so that the
 * vertices of a value are counted before its segments.
 *
 * The insertion (tdc_constrain) runs the core's (cdt.c) on a thread of its
 * own while this backend waits and watches for interrupts (tdc_wait_work).
 * A proper crossing is an ERROR that names both segments by their end
 * points: an exact triangulation cannot invent the crossing point, so the
 * lines must be noded first.  The insertion's own arrays go with
 * tdc_constrain_release (or, on an error, with the buffer's context,
 * before the job: its reset callback is registered after the job's).
 *
 * Aggregates carry their segments between processes after their own
 * parameters: tdc_seg_read checks them (whole pairs, ends below the vertex
 * count) as strictly as the vertices are checked.
 */
#include "postgres.h"

#include "portability/instr_time.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

/* Room for "more" segments. */
void
tdc_seg_reserve(TdcSegList *l, uint64 more)
{
	if (l->nseg + more > l->cap)
	{
		uint64		cap = Max(l->cap * 2, l->nseg + more);

		tdc_pointbuf_side_grow(l->buf, l->cap * 2 * sizeof(uint32),
							   cap * 2 * sizeof(uint32), "their segments", l->fname);
		l->seg = l->seg ? repalloc_huge(l->seg, cap * 2 * sizeof(uint32))
			: MemoryContextAllocHuge(l->cxt, cap * 2 * sizeof(uint32));
		l->cap = cap;
	}
}

/* TdcChainFn: a chain of k vertices from index first, noted for tdc_seg_flush. */
static void
seg_note_chain(void *arg, uint64 first, uint32 k)
{
	TdcSegList *l = (TdcSegList *) arg;

	if (l->nchain == l->chaincap)
	{
		Size		cap = Max(l->chaincap * 2, 64);

		l->chain = l->chain ? repalloc_huge(l->chain, cap * 2 * sizeof(uint64))
			: MemoryContextAllocHuge(l->cxt, cap * 2 * sizeof(uint64));
		l->chaincap = cap;
	}
	l->chain[2 * l->nchain] = first;
	l->chain[2 * l->nchain + 1] = k;
	l->nchain++;
}

/* The noted chains as segments: each chain of k vertices gives k - 1. */
void
tdc_seg_flush(TdcSegList *l)
{
	for (Size c = 0; c < l->nchain; c++)
	{
		uint64		first = l->chain[2 * c];
		uint32		k = (uint32) l->chain[2 * c + 1];

		if (first + k > TDC_MAX_POINTS)
			ereport(ERROR,
					(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
					 errmsg("%s: more than %zu vertices", l->fname, TDC_MAX_POINTS)));
		tdc_seg_reserve(l, k - 1);
		for (uint32 i = 0; i + 1 < k; i++)
		{
			l->seg[2 * l->nseg] = (uint32) (first + i);
			l->seg[2 * l->nseg + 1] = (uint32) (first + i + 1);
			l->nseg++;
		}
	}
	l->nchain = 0;
}

/* An empty list for the vertices of buf, which from now on reports its chains. */
void
tdc_seg_init(TdcSegList *l, MemoryContext cxt, TdcPointBuf *buf, const char *fname)
{
	memset(l, 0, sizeof(*l));
	l->cxt = cxt;
	l->buf = buf;
	l->fname = fname;
	buf->chain = seg_note_chain;
	buf->chain_arg = l;
}

/*
 * The segments of src after those of dst, their ends shifted by base (the
 * vertex count of dst's buffer before src's vertices were appended).
 */
void
tdc_seg_append(TdcSegList *dst, const TdcSegList *src, uint64 base)
{
	tdc_seg_reserve(dst, src->nseg);
	for (uint64 i = 0; i < 2 * src->nseg; i++)
		dst->seg[2 * dst->nseg + i] = (uint32) (src->seg[i] + base);
	dst->nseg += src->nseg;
}

/*
 * Segments from a serialized state: len bytes at data, whole pairs of
 * uint32 ends below n (the state's vertex count), else the state is
 * corrupt.
 */
void
tdc_seg_read(TdcSegList *l, const char *data, Size len, uint64 n)
{
	uint64		k;

	if (len % (2 * sizeof(uint32)) != 0)
		tdc_agg_state_corrupt(l->fname,
							  psprintf("%zu bytes after %llu vertices are not whole segments",
									   len, (unsigned long long) n));
	k = len / (2 * sizeof(uint32));
	if (k == 0)
		return;
	tdc_seg_reserve(l, k);
	memcpy(l->seg + 2 * l->nseg, data, len);
	for (uint64 i = 2 * l->nseg; i < 2 * (l->nseg + k); i++)
		if (l->seg[i] >= n)
			tdc_agg_state_corrupt(l->fname, "segment end beyond the vertices");
	l->nseg += k;
}

/* ----------------------------------------------------------------
 *		running the insertion
 * ----------------------------------------------------------------
 */

/* On error or cancel: stop and free the insertion before the job goes. */
static void
cdt_reset_callback(void *arg)
{
	TdcCdtHold *hold = (TdcCdtHold *) arg;

	if (hold->cdt != NULL)
	{
		tdc_cdt_free(hold->cdt);
		hold->cdt = NULL;
	}
}

static void
report_crossing(const TdcCdtHold *hold, const TdcPointBuf *buf, const TdcSegList *w,
				const char *fname)
{
	size_t		s1,
				s2;

	if (tdc_cdt_crossing(hold->cdt, &s1, &s2))
	{
		const double *a = buf->xy + 2 * (size_t) w->seg[2 * s1],
				   *b = buf->xy + 2 * (size_t) w->seg[2 * s1 + 1],
				   *c = buf->xy + 2 * (size_t) w->seg[2 * s2],
				   *d = buf->xy + 2 * (size_t) w->seg[2 * s2 + 1];

		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: segments LINESTRING(%.17g %.17g,%.17g %.17g) and LINESTRING(%.17g %.17g,%.17g %.17g) cross",
						fname, a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]),
				 errdetail("An exact constrained triangulation cannot create their crossing point."),
				 errhint("Node the lines first, with ST_Node or ST_UnaryUnion.")));
	}
}

TDC_WORK_OPS(cdt_ops, tdc_cdt, tdc_cdt, "triangulation");

/*
 * Insert the segments into the finished job of run, waiting interruptibly.
 * Any failure is an ERROR.  The caller frees the insertion with
 * tdc_constrain_release once it no longer needs the constraint edges; on
 * error it goes with buf's context.
 */
TdcCdtHold *
tdc_constrain(TdcRun *run, const TdcPointBuf *buf, const TdcSegList *w,
			  const char *fname)
{
	TdcCdtHold *hold;
	MemoryContextCallback *cb;
	char		err[512];
	int			rc;
	instr_time	start,
				stop;

	INSTR_TIME_SET_CURRENT(start);
	hold = MemoryContextAllocZero(buf->cxt, sizeof(TdcCdtHold));
	cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
	cb->func = cdt_reset_callback;
	cb->arg = hold;
	/* registered after the job's: runs before it, so the job outlives it */
	MemoryContextRegisterResetCallback(buf->cxt, cb);

	err[0] = '\0';
	rc = tdc_cdt_start(run->job, w->seg, (size_t) w->nseg, &hold->cdt, err,
					   sizeof(err));
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	rc = tdc_wait_work(hold->cdt, &cdt_ops, fname);
	if (rc == TDC_ECROSS)
		report_crossing(hold, buf, w, fname);
	if (rc != TDC_OK)
		tdc_report_status(rc, tdc_cdt_error(hold->cdt), fname);
	if (tdc_guc_stats)
	{
		INSTR_TIME_SET_CURRENT(stop);
		INSTR_TIME_SUBTRACT(stop, start);
		ereport(NOTICE,
				(errmsg("%s: %llu segments, %zu constraint edges, insertion %.3f ms",
						fname, (unsigned long long) w->nseg,
						tdc_cdt_num_constraint_edges(hold->cdt),
						INSTR_TIME_GET_MILLISEC(stop))));
	}
	return hold;
}

/* Free the insertion now (its memory is big); the job stays. */
void
tdc_constrain_release(TdcCdtHold *hold)
{
	tdc_cdt_free(hold->cdt);
	hold->cdt = NULL;
}
