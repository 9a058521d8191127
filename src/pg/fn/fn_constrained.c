/*
 * fn_constrained.c
 *		ST_TDCConstrainedDelaunayTriangles, its aggregate
 *		ST_TDCConstrainedDelaunay and ST_TDCConstrainedDelaunayDump: the
 *		constrained Delaunay triangulation of a geometry's vertices, its
 *		linework as constraints; adapters over the runtime plus the
 *		segments.
 *
 * The vertices are read by the runtime's reader (tdc_read_geometry: a big
 * TOASTed value a slice at a time, NaN and infinities rejected, Z kept, M
 * dropped, SRID carried), in the order they are stored.  The segments come
 * from the same read (seglist.c): every linestring and polygon ring gives
 * the segments between its consecutive vertices, as indices into that
 * vertex order.
 *
 * The triangulation runs as usual (tdc_run), then the segments are inserted
 * (tdc_constrain, seglist.c) while this backend waits and watches for
 * interrupts.  A proper crossing is an ERROR that names both segments by
 * their end points: an exact triangulation cannot invent the crossing
 * point, so the lines must be noded first.
 *
 * ST_TDCConstrainedDelaunayDump(query) reads its query with the Dump
 * functions' collector (dump_query.c), taking each row's segments as its
 * vertices arrive, and returns one row per triangle like
 * ST_TDCDelaunayDump, so no single value bounds the result.
 */
#include "postgres.h"

#include <math.h>

#include "funcapi.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

/* tdc_gser_edge_list's next() over the constraint edges. */
typedef struct CdtEdgeWalk
{
	const tdc_cdt *cdt;
	tdc_iter	it;
} CdtEdgeWalk;

static bool
next_constraint_edge(void *arg, uint32 v[2])
{
	CdtEdgeWalk *walk = arg;

	return tdc_next_constraint_edge(walk->cdt, &walk->it, v) != 0;
}

/*
 * The constrained triangulation of buf's vertices and the segments, as one
 * geometry value of the given kind.
 */
static Datum
constrained_to_datum(const TdcPointBuf *buf, const TdcSegList *segs, int flags,
					 const char *fname)
{
	TdcRun	   *run;
	TdcCdtHold *hold;
	TdcGserWriter wr;
	struct varlena *result;
	uint64		extra;

	if (buf->n == 0)
		return PointerGetDatum(tdc_gser_empty(flags, buf->srid));

	/*
	 * The result, for max_memory (the segments count with the vertices);
	 * tdc_cdt_start adds the insertion's own arrays (tdc_cdt_memory) to the
	 * engine's estimate.
	 */
	extra = tdc_gser_result_bound(buf->n, flags == TDC_OUT_CONSTRAINTS ?
								  TDC_OUT_EDGES : flags, buf->hasz);
	run = tdc_run(buf, 0.0, extra, fname);
	hold = tdc_constrain(run, buf, segs, fname);
	if (flags == TDC_OUT_CONSTRAINTS)
	{
		CdtEdgeWalk walk = {hold->cdt, {0}};

		result = tdc_gser_edge_list(run->job, buf,
									tdc_cdt_num_constraint_edges(hold->cdt),
									next_constraint_edge, &walk, fname);
		tdc_constrain_release(hold);
		tdc_run_free(run);
		return PointerGetDatum(result);
	}
	tdc_constrain_release(hold);

	result = tdc_gser_result_alloc(run->job, flags, buf, fname, &wr);
	if (flags == TDC_OUT_EDGES || wr.count == 0 ||
		!tdc_run_emit(run, tdc_gser_emit, &wr, fname))
		tdc_gser_fill(&wr);
	CHECK_FOR_INTERRUPTS();
	tdc_run_free(run);
	return PointerGetDatum(result);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunaytriangles);

/*
 * ST_TDCConstrainedDelaunayTriangles(geometry, flags int4)
 *		comparable to SFCGAL's ST_ConstrainedDelaunayTriangles; STRICT.
 */
Datum
st_tdcconstraineddelaunaytriangles(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCConstrainedDelaunayTriangles";
	int32		flags = PG_NARGS() > 1 ? PG_GETARG_INT32(1) : 0;
	TdcPointBuf buf;
	TdcSegList	segs;

	tdc_signal_guard();
	tdc_check_flags(flags, true, fname);
	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	tdc_seg_init(&segs, CurrentMemoryContext, &buf, fname);
	(void) tdc_read_geometry(&buf, PG_GETARG_DATUM(0), fname);
	tdc_seg_flush(&segs);
	PG_RETURN_DATUM(constrained_to_datum(&buf, &segs, flags, fname));
}

/* ----------------------------------------------------------------
 *		the aggregate ST_TDCConstrainedDelaunay(geometry [, flags])
 * ----------------------------------------------------------------
 *
 * Its state is ST_TDCDelaunay's (the point buffer and the flags, tolerance
 * 0) plus the segments, as indices into that buffer, both in the aggregate
 * context.  Combining appends the second state's vertices and its segments
 * shifted by the first state's vertex count.  Serialized for parallel plans
 * in ST_TDCDelaunay's form (agg_state.c) under magic "TDC2", followed
 * by k*2 uint32 segment ends (k from the length); the deserializer checks
 * ST_TDCDelaunay's part as for that aggregate, then that the rest is whole
 * segments whose ends are below n.
 */
#define CDT_AGG_NAME		"ST_TDCConstrainedDelaunay"

static const TdcStateFormat cdt_format = {
	0x32434454,					/* "TDC2" little-endian */
	1, CDT_AGG_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0).",
	TDC_OUT_CONSTRAINTS
};

typedef struct CdtAggState
{
	TdcAggState *base;			/* the vertices and the flags */
	TdcSegList	segs;
} CdtAggState;

/* A state in cxt around base, or around a new empty one when base is NULL. */
static CdtAggState *
cdt_state_new(MemoryContext cxt, TdcAggState *base)
{
	CdtAggState *st = MemoryContextAllocZero(cxt, sizeof(CdtAggState));

	st->base = base ? base : tdc_agg_state_new(cxt);
	tdc_seg_init(&st->segs, cxt, &st->base->pts, CDT_AGG_NAME);
	return st;
}

static void
cdt_state_set_flags(CdtAggState *st, int32 flags)
{
	if (st->base->params_set && st->base->flags != flags)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: flags must be the same for all rows (%d versus %d)",
						CDT_AGG_NAME, st->base->flags, flags)));
	tdc_agg_state_set_params(st->base, 0.0, flags);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunay_transfn);

/* st_tdcconstraineddelaunay_transfn(internal, geometry [, int4]) */
Datum
st_tdcconstraineddelaunay_transfn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcconstraineddelaunay_transfn");
	CdtAggState *st = PG_ARGISNULL(0) ? NULL : (CdtAggState *) PG_GETARG_POINTER(0);
	int32		flags = TDC_OUT_POLYGONS;

	tdc_signal_guard();
	if (PG_ARGISNULL(1) || (PG_NARGS() > 2 && PG_ARGISNULL(2)))
	{
		if (st == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st);
	}
	if (PG_NARGS() > 2)
	{
		flags = PG_GETARG_INT32(2);
		tdc_check_flags(flags, true, CDT_AGG_NAME);
	}
	if (st == NULL)
		st = cdt_state_new(aggcxt, NULL);
	cdt_state_set_flags(st, flags);

	(void) tdc_read_geometry(&st->base->pts, PG_GETARG_DATUM(1), CDT_AGG_NAME);
	tdc_seg_flush(&st->segs);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunay_combinefn);

Datum
st_tdcconstraineddelaunay_combinefn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcconstraineddelaunay_combinefn");
	CdtAggState *st1 = PG_ARGISNULL(0) ? NULL : (CdtAggState *) PG_GETARG_POINTER(0);
	CdtAggState *st2 = PG_ARGISNULL(1) ? NULL : (CdtAggState *) PG_GETARG_POINTER(1);
	uint64		base;

	tdc_signal_guard();
	if (st2 == NULL)
	{
		if (st1 == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st1);
	}
	if (st1 == NULL)
		st1 = cdt_state_new(aggcxt, NULL);
	if (st2->base->params_set)
		cdt_state_set_flags(st1, st2->base->flags);
	base = st1->base->pts.n;
	tdc_pointbuf_append_buf(&st1->base->pts, &st2->base->pts, CDT_AGG_NAME);
	tdc_seg_append(&st1->segs, &st2->segs, base);
	PG_RETURN_POINTER(st1);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunay_serialfn);

Datum
st_tdcconstraineddelaunay_serialfn(PG_FUNCTION_ARGS)
{
	CdtAggState *st;
	uint64		k;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcconstraineddelaunay_serialfn");
	st = (CdtAggState *) PG_GETARG_POINTER(0);
	k = st->segs.nseg;
	/* segments in a state are bounded by MaxAllocHugeSize: no overflow */
	PG_RETURN_BYTEA_P(tdc_agg_state_serialize_with(st->base, &cdt_format,
												   st->segs.seg,
												   (Size) k * 2 * sizeof(uint32),
												   psprintf("%llu vertices and %llu segments",
															(unsigned long long) st->base->pts.n,
															(unsigned long long) k)));
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunay_deserialfn);

Datum
st_tdcconstraineddelaunay_deserialfn(PG_FUNCTION_ARGS)
{
	TdcAggState *base;
	CdtAggState *st;
	const char *extra;
	Size		extra_len;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcconstraineddelaunay_deserialfn");
	base = tdc_agg_state_deserialize_with(PG_GETARG_BYTEA_P(0), &cdt_format,
										  CurrentMemoryContext,
										  &extra, &extra_len);
	st = cdt_state_new(CurrentMemoryContext, base);
	tdc_seg_read(&st->segs, extra, extra_len, base->pts.n);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunay_finalfn);

Datum
st_tdcconstraineddelaunay_finalfn(PG_FUNCTION_ARGS)
{
	CdtAggState *st;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcconstraineddelaunay_finalfn");
	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (CdtAggState *) PG_GETARG_POINTER(0);
	PG_RETURN_DATUM(constrained_to_datum(&st->base->pts, &st->segs,
										 st->base->params_set ? st->base->flags : 0,
										 CDT_AGG_NAME));
}

/* ----------------------------------------------------------------
 *		ST_TDCConstrainedDelaunayDump(query text)
 * ----------------------------------------------------------------
 */

/* TdcDumpRowFn: the segments of one row of the query. */
static void
cdt_dump_row(void *arg, uint64 first)
{
	tdc_seg_flush((TdcSegList *) arg);
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunaydump);

/*
 * ST_TDCConstrainedDelaunayDump(query text) RETURNS TABLE(id bigint,
 * geom geometry): one POLYGON row per triangle, numbered from 1.  STRICT.
 */
Datum
st_tdcconstraineddelaunaydump(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCConstrainedDelaunayDump";
	ReturnSetInfo *rsinfo = (ReturnSetInfo *) fcinfo->resultinfo;
	char	   *query;
	Oid			geomoid;
	TdcPointBuf buf;
	TdcSegList	segs;
	TdcRun	   *run;

	tdc_signal_guard();
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	InitMaterializedSRF(fcinfo, 0);
	geomoid = TupleDescAttr(rsinfo->setDesc, 1)->atttypid;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	tdc_seg_init(&segs, CurrentMemoryContext, &buf, fname);
	tdc_dump_collect(&buf, NULL, query, geomoid, fname, cdt_dump_row, &segs);
	if (buf.n == 0)
		return (Datum) 0;

	run = tdc_run(&buf, 0.0, 0, fname);
	tdc_constrain_release(tdc_constrain(run, &buf, &segs, fname));
	tdc_dump_triangles(rsinfo, run, &buf);
	tdc_run_free(run);
	return (Datum) 0;
}
