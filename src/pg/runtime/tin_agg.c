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
 * The serialized form is agg_state.c's, under the aggregate's magic: the
 * vertices, then an extra part that is the aggregate's fixed parameters
 * and, last, the segments as k * 2 uint32 ends.  The segments go last so
 * that their count follows from the length, and so that each aggregate
 * lays out (and checks, when read) only its own part.  A segment must
 * have both ends among the state's vertices, a state without breaklines
 * no segment, and a state with vertices their heights: whatever a worker
 * sends is checked as if it came from outside.
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

/* src's samples after dst's; the caller has made their parameters agree. */
void
tdc_tin_agg_merge(TdcTinAgg *dst, const TdcTinAgg *src, const char *fname)
{
	uint64		base = dst->base->pts.n;

	tdc_agg_rows_add(&dst->rows, src->rows, fname);
	tdc_agg_state_merge(dst->base, src->base);
	if (dst->breaklines)
		tdc_seg_append(&dst->segs, &src->segs, base);
}

/*
 * The body of every TIN aggregate's combine function: the second state's
 * samples after the first's, once params has made the first's parameters
 * the second's (or checked that they agree).  A state whose parameters
 * are unset read no row and adds nothing.  NULL: no state yet.
 */
TdcTinAgg *
tdc_tin_agg_combine(FunctionCallInfo fcinfo, const char *fn, const char *fname, Size size,
					TdcCurves curves, TdcTinAggParams params)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, fn);
	TdcTinAgg  *a = PG_ARGISNULL(0) ? NULL : (TdcTinAgg *) PG_GETARG_POINTER(0);
	TdcTinAgg  *b = PG_ARGISNULL(1) ? NULL : (TdcTinAgg *) PG_GETARG_POINTER(1);

	if (b == NULL || !b->params_set)
		return a;
	if (a == NULL)
		a = tdc_tin_agg_new(aggcxt, size, curves);
	params(a, b, aggcxt);
	tdc_tin_agg_merge(a, b, fname);
	return a;
}

/*
 * A zeroed extra part of plen bytes for the aggregate's parameters, with
 * room for the segments after them; *len is its whole length.
 */
char *
tdc_tin_agg_extra(const TdcTinAgg *a, Size plen, Size *len)
{
	Size		slen = a->breaklines ? (Size) a->segs.nseg * 2 * sizeof(uint32) : 0;

	*len = plen + slen;
	return palloc_extended(*len, MCXT_ALLOC_HUGE | MCXT_ALLOC_ZERO);
}

/* The state serialized, extra's first plen bytes filled by the caller. */
bytea *
tdc_tin_agg_serialize(const TdcTinAgg *a, const TdcStateFormat *fmt, char *extra, Size plen)
{
	Size		slen = a->breaklines ? (Size) a->segs.nseg * 2 * sizeof(uint32) : 0;

	if (slen > 0)
		memcpy(extra + plen, a->segs.seg, slen);
	return tdc_agg_state_serialize_with(a->base, fmt, extra, plen + slen,
										slen == 0 ? NULL :
										psprintf("%llu vertices and %llu breakline segments",
												 (unsigned long long) a->base->pts.n,
												 (unsigned long long) a->segs.nseg));
}

/*
 * A serialized state's vertices into a (zeroed); returns its extra part, of
 * *extra_len bytes, for the aggregate to read its parameters from.
 */
const char *
tdc_tin_agg_deserialize(TdcTinAgg *a, const bytea *in, const TdcStateFormat *fmt,
						TdcCurves curves, Size *extra_len)
{
	const char *extra;

	a->base = tdc_agg_state_deserialize_with(in, fmt, CurrentMemoryContext, &extra, extra_len);
	a->base->pts.curves = curves;
	return extra;
}

/*
 * The rest of a serialized state, after the aggregate's parameters have
 * been read and its breaklines set: len bytes of segments, then the
 * checks that hold for every state.
 */
void
tdc_tin_agg_read_segments(TdcTinAgg *a, const char *rest, Size len, const char *fname)
{
	if (!a->breaklines && len != 0)
		tdc_agg_state_corrupt(fname, "segments without breaklines");
	if (a->breaklines)
		tdc_seg_read(&a->segs, rest, len, a->base->pts.n);
	if (a->base->pts.n > 0 && !a->base->pts.hasz)
		tdc_agg_state_corrupt(fname, "samples without Z");
}
