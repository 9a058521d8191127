/*
 * tin_agg.c
 *		The samples of the TIN aggregates (ST_TDCContours, ST_TDCDrape,
 *		ST_TDCInterpolate): what their states share, and how it is added
 *		to, combined and passed between parallel workers.
 *
 * Each TIN aggregate's state begins with a TdcTinAgg: the Delaunay
 * aggregate's point buffer with the heights (agg_state.c), the count of
 * non-NULL rows read (which names a row without Z, tin_run.c), whether the
 * first row's parameters are set, and with 'linear:breaklines=true' the
 * samples' linework as segments (seglist.c).  What follows it is the
 * aggregate's own parameters: levels, a target, a raster template.
 *
 * The serial, deserial and combine functions of the three aggregates are
 * written once, here (tdc_tin_agg_serialfn and the others, which each
 * aggregate's SQL entry points call through TDC_TIN_AGG_SUPPORT), from a
 * TdcTinAggKind that says what differs: the format's magic and version,
 * the state's size, how a curved sample is read, and the aggregate's own
 * parameters (how long they are, how they are written, read and checked,
 * and how two states' parameters are reconciled).
 *
 * The serialized form is agg_state.c's, under the aggregate's magic: the
 * vertices, then an extra part that is the aggregate's parameters and,
 * last, the segments as k * 2 uint32 ends.  The parameters begin with a
 * fixed part whose first uint32 says whether they are set (0 or 1) and
 * which holds the int64 count of rows at an offset of the aggregate's
 * choosing; a variable part (a method's text, a target) may follow.  The
 * segments go last so that their count follows from the length, and so
 * that each aggregate lays out (and checks, when read) only its own part.
 * A segment must have both ends among the state's vertices, a state
 * without breaklines no segment, a state without parameters nothing at
 * all, and a state with vertices their heights: whatever a worker sends is
 * checked as if it came from outside.
 *
 * Combining appends the second state's vertices after the first's, so its
 * segments' ends shift by the first's vertex count before the merge.
 */
#include "postgres.h"

#include "fmgr.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

/*
 * A new state of size bytes, which begin with its TdcTinAgg; curves is how
 * the aggregate reads a curved sample (its owner's choice, tdc_pg.h).
 */
TdcTinAgg *
tdc_tin_agg_new(MemoryContext cxt, Size size, TdcCurves curves)
{
	TdcTinAgg  *a = MemoryContextAllocZero(cxt, size);

	a->base = tdc_agg_state_new(cxt);
	a->base->pts.curves = curves;
	return a;
}

/*
 * From the parameters of the first row (or of a state read back): keep the
 * samples' linework as segments if the method asks for breaklines, and
 * refuse curves then, as the constrained functions do.
 */
void
tdc_tin_agg_breaklines(TdcTinAgg *a, bool breaklines, MemoryContext cxt, const char *fname)
{
	a->breaklines = breaklines;
	if (breaklines)
	{
		tdc_seg_init(&a->segs, cxt, &a->base->pts, fname);
		a->base->pts.curves = TDC_CURVES_REFUSE;
	}
}

/* One more non-NULL row: its vertices, and its linework as segments. */
void
tdc_tin_agg_add(TdcTinAgg *a, Datum geom, const char *fname)
{
	a->rows++;
	tdc_tin_read_sample(&a->base->pts, geom, a->rows, fname);
	if (a->breaklines)
		tdc_seg_flush(&a->segs);
}

/*
 * One more non-NULL row of the pcpatch overloads: its points (those that
 * pass the filter).  A patch has no linework, so breaklines are refused.
 */
void
tdc_tin_agg_add_patch(TdcTinAgg *a, FmgrInfo *flinfo, Datum patch, text *filter, const char *fname)
{
	if (a->breaklines)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: breaklines=true needs linework, and a pcpatch has none", fname),
				 errhint("Drop breaklines=true from the method, or give the breaklines as geometries.")));
	a->rows++;
	tdc_pc_read_patch(a->base, flinfo, patch, filter, fname);
}

/* src's samples after dst's; the caller has made their parameters agree. */
static void
tin_agg_merge(TdcTinAgg *dst, const TdcTinAgg *src, const char *fname)
{
	uint64		base = dst->base->pts.n;

	tdc_agg_rows_add(&dst->rows, src->rows, fname);
	tdc_agg_state_merge(dst->base, src->base);
	if (dst->breaklines)
		tdc_seg_append(&dst->segs, &src->segs, base);
}

/*
 * The combine function: the second state's samples after the first's,
 * once the kind's params has made the first's parameters the second's (or
 * checked that they agree).  A state whose parameters are unset read no
 * row and adds nothing.  NULL: no state yet.
 */
Datum
tdc_tin_agg_combinefn(FunctionCallInfo fcinfo, const TdcTinAggKind *k, const char *fn)
{
	MemoryContext aggcxt;
	TdcTinAgg  *a,
			   *b;

	tdc_signal_guard();
	aggcxt = tdc_agg_context(fcinfo, fn);
	a = PG_ARGISNULL(0) ? NULL : (TdcTinAgg *) PG_GETARG_POINTER(0);
	b = PG_ARGISNULL(1) ? NULL : (TdcTinAgg *) PG_GETARG_POINTER(1);
	if (b != NULL && b->params_set)
	{
		if (a == NULL)
			a = tdc_tin_agg_new(aggcxt, k->size, k->curves);
		k->params(a, b, aggcxt);
		tin_agg_merge(a, b, k->fmt->fname);
	}
	if (a == NULL)
		PG_RETURN_NULL();
	PG_RETURN_POINTER(a);
}

/*
 * The serial function: the vertices, then the parameters (the set flag and
 * the rows here, the rest by the kind's write into a zeroed part, whether
 * set or not: a field the format ignores goes back as it came), then the
 * segments.
 */
Datum
tdc_tin_agg_serialfn(FunctionCallInfo fcinfo, const TdcTinAggKind *k, const char *fn)
{
	TdcTinAgg  *a;
	Size		plen,
				slen;
	char	   *extra;
	uint32		set;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, fn);
	a = (TdcTinAgg *) PG_GETARG_POINTER(0);
	plen = k->fixed + k->var_len(a);
	slen = a->breaklines ? (Size) a->segs.nseg * 2 * sizeof(uint32) : 0;
	extra = palloc_extended(plen + slen, MCXT_ALLOC_HUGE | MCXT_ALLOC_ZERO);
	set = a->params_set ? 1 : 0;
	memcpy(extra, &set, sizeof(set));
	memcpy(extra + k->rows_at, &a->rows, sizeof(a->rows));
	k->write(a, extra);
	if (slen > 0)
		memcpy(extra + plen, a->segs.seg, slen);
	PG_RETURN_BYTEA_P(tdc_agg_state_serialize_with(a->base, k->fmt, extra, plen + slen,
												   slen == 0 ? NULL :
												   psprintf("%llu vertices and %llu breakline segments",
															(unsigned long long) a->base->pts.n,
															(unsigned long long) a->segs.nseg)));
}

/*
 * The deserial function: the vertices (agg_state.c checks them), the set
 * flag and the rows, the kind's parameters (its read checks their lengths
 * and values, and sets the breaklines), then the segments, and the checks
 * that hold for every state.
 */
Datum
tdc_tin_agg_deserialfn(FunctionCallInfo fcinfo, const TdcTinAggKind *k, const char *fn)
{
	const char *fname = k->fmt->fname;
	TdcTinAgg  *a;
	const char *extra;
	Size		len,
				plen;
	uint32		set;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, fn);
	a = palloc0(k->size);
	a->base = tdc_agg_state_deserialize_with(PG_GETARG_BYTEA_P(0), k->fmt, CurrentMemoryContext,
											 &extra, &len);
	a->base->pts.curves = k->curves;
	if (len < k->fixed)
		tdc_agg_state_corrupt(fname, psprintf("%zu bytes of parameters, fewer than %zu",
											  len, k->fixed));
	memcpy(&set, extra, sizeof(set));
	memcpy(&a->rows, extra + k->rows_at, sizeof(a->rows));
	if (set > 1 || a->rows < 0)
		tdc_agg_state_corrupt(fname, "bad parameter flag or row count");
	a->params_set = set == 1;
	tdc_agg_state_check_unset(a->base, a->params_set, a->rows, fname);
	plen = k->read(a, extra, len);
	if (!a->breaklines && len != plen)
		tdc_agg_state_corrupt(fname, "segments without breaklines");
	if (a->breaklines)
		tdc_seg_read(&a->segs, extra + plen, len - plen, a->base->pts.n);
	if (a->base->pts.n > 0 && !a->base->pts.hasz)
		tdc_agg_state_corrupt(fname, "samples without Z");
	PG_RETURN_POINTER(a);
}
