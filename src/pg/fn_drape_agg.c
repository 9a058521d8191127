/*
 * fn_drape_agg.c
 *		The ST_TDCDrape aggregates: a target geometry with Z from the TIN of
 *		all rows' vertices (the samples).
 *
 * ST_TDCDrape(geom, target [, method]) returns target with a height at
 * every vertex, by 'linear' (the default), 'nearest' or 'natural_neighbor';
 * with 'linear' every segment of a line or ring also gets a vertex where it
 * crosses a triangle edge, so the draped line follows the TIN exactly
 * (tin_drape.c).  The outside-hull rule: every vertex of the target must
 * lie in the closed convex hull of the samples, for every method; a vertex
 * outside it is an ERROR naming the vertex, with a hint to clip the target
 * first.  (GDAL's radius would make the result depend on an option for
 * vertices the surface does not reach; a draped road that silently leaves
 * the survey is a worse surprise than an error.)  So the method takes no
 * GDAL options; it takes 'linear:breaklines=true', which makes the
 * samples' linestrings and polygon rings hard breaklines of the TIN
 * (tin_run.c), kept from the first row on beside the vertices and
 * combined with them.
 *
 * The state is the Delaunay aggregate's point buffer (agg_state.c) with the
 * heights, plus the method and the target, which must be the same in every
 * row (a target that is not a constant of the statement is compared with
 * the first row's byte for byte), and the count of rows read.
 * Rows with a NULL argument are skipped.  Under a parallel plan a worker's
 * state travels in the Delaunay state's serialized form under magic "TDR1",
 * followed by
 *
 *		uint32 params_set (0 or 1), uint32 method length, uint64 target
 *		length, int64 rows, the method's bytes, the target's bytes, then
 *		with breaklines (version 2) k * 2 uint32 segment ends
 *
 * (k from the length; both ends among the state's vertices, and no
 * segment without breaklines).
 *
 * The result keeps the target's SRID, which must be the samples'.
 */
#include "postgres.h"

#include <math.h>

#include "fmgr.h"
#include "nodes/primnodes.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

#define DRAPE_NAME			"ST_TDCDrape"
#define DRAPE_FIXED			24		/* the fixed part after the vertices */
#define METHOD_MAX			64

static const TdcStateFormat drape_format = {
	0x31524454,					/* "TDR1" little-endian */
	2, DRAPE_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0).",
	-1
};

typedef struct DrapeState
{
	TdcAggState *base;
	int64		rows;
	bool		params_set;
	char	   *method;			/* as given, checked */
	bool		breaklines;		/* the method's: segs holds the samples' linework */
	TdcSegList	segs;
	struct varlena *target;		/* detoasted, in the aggregate context */
	bool		target_const;	/* the target is a constant: no need to compare */
} DrapeState;

static DrapeState *
drape_state_new(MemoryContext cxt)
{
	DrapeState *st = MemoryContextAllocZero(cxt, sizeof(DrapeState));

	st->base = tdc_agg_state_new(cxt);
	st->base->pts.curves = TDC_CURVES_STROKE;
	return st;
}

/* Does the method have an option other than breaklines (GDAL's radius, nodata)? */
static bool
has_gdal_option(const char *method)
{
	for (const char *p = strchr(method, ':'); p != NULL; p = strchr(p + 1, ':'))
		if (pg_strncasecmp(p + 1, "breaklines=", 11) != 0)
			return true;
	return false;
}

/*
 * The method, checked: a name of tdc_interp_parse's, with no option but
 * linear's breaklines.
 */
static void
check_method(const char *method, tdc_interp_spec *spec)
{
	char		err[256];
	bool		gdal_option = strlen(method) <= METHOD_MAX && has_gdal_option(method);

	err[0] = '\0';
	if (strlen(method) > METHOD_MAX || gdal_option ||
		tdc_interp_parse(method, spec, err, sizeof(err)) != TDC_OK)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid method \"%s\"", DRAPE_NAME, method),
				 gdal_option ? errdetail("%s takes no options but linear's breaklines: every vertex of the target must lie in the samples' convex hull.",
										 DRAPE_NAME) : (err[0] ? errdetail("%s.", err) : 0),
				 errhint("Use 'linear', 'linear:breaklines=true', 'nearest' or 'natural_neighbor'.")));
	/* outside the hull there is no value: an error, raised by the final function */
	spec->radius = 0;
}

/*
 * From the first row, whose method fixes every row's: keep the samples'
 * linework as segments if the method asks for breaklines, and refuse
 * curves then, as the constrained functions do.
 */
static void
drape_breaklines(DrapeState *st, MemoryContext cxt)
{
	tdc_interp_spec spec;

	check_method(st->method, &spec);
	st->breaklines = spec.breaklines;
	if (st->breaklines)
	{
		tdc_seg_init(&st->segs, cxt, &st->base->pts, DRAPE_NAME);
		st->base->pts.curves = TDC_CURVES_REFUSE;
	}
}

static void
drape_params(DrapeState *st, MemoryContext cxt, const char *method,
			 const struct varlena *target, Size target_len)
{
	if (!st->params_set)
	{
		st->params_set = true;
		st->method = MemoryContextStrdup(cxt, method);
		st->target = MemoryContextAlloc(cxt, target_len);
		memcpy(st->target, target, target_len);
		drape_breaklines(st, cxt);
		return;
	}
	if (strcmp(st->method, method) != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: method must be the same for all rows (\"%s\" versus \"%s\")",
						DRAPE_NAME, st->method, method)));
	if (VARSIZE_ANY(st->target) != target_len || memcmp(st->target, target, target_len) != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: target must be the same geometry for all rows", DRAPE_NAME),
				 errhint("Drape one target per aggregate, or collect the targets first with ST_Collect.")));
}

PG_FUNCTION_INFO_V1(st_tdcdrape_transfn);

/*
 * st_tdcdrape_transfn(internal, geometry, geometry [, text])
 */
Datum
st_tdcdrape_transfn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcdrape_transfn");
	DrapeState *st = PG_ARGISNULL(0) ? NULL : (DrapeState *) PG_GETARG_POINTER(0);
	char	   *method = "linear";
	tdc_interp_spec spec;

	tdc_signal_guard();
	if (PG_ARGISNULL(1) || PG_ARGISNULL(2) || (PG_NARGS() > 3 && PG_ARGISNULL(3)))
	{
		if (st == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st);
	}
	if (PG_NARGS() > 3)
		method = text_to_cstring(PG_GETARG_TEXT_PP(3));
	if (st == NULL)
		st = drape_state_new(aggcxt);

	/*
	 * A constant target (a literal, or a parameter of the statement) is
	 * the same in every row; any other is compared with the first row's,
	 * byte for byte.
	 */
	if (!st->params_set || !st->target_const || strcmp(st->method, method) != 0)
	{
		struct varlena *target = PG_DETOAST_DATUM(PG_GETARG_DATUM(2));

		if (!st->params_set)
		{
			check_method(method, &spec);
			st->target_const = tdc_agg_arg_is_constant(fcinfo, 1);
		}
		drape_params(st, aggcxt, method, target, VARSIZE_ANY(target));
	}
	st->rows++;
	tdc_tin_read_sample(&st->base->pts, PG_GETARG_DATUM(1), st->rows, DRAPE_NAME);
	if (st->breaklines)
		tdc_seg_flush(&st->segs);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcdrape_combinefn);

Datum
st_tdcdrape_combinefn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcdrape_combinefn");
	DrapeState *st1 = PG_ARGISNULL(0) ? NULL : (DrapeState *) PG_GETARG_POINTER(0);
	DrapeState *st2 = PG_ARGISNULL(1) ? NULL : (DrapeState *) PG_GETARG_POINTER(1);
	uint64		base;

	tdc_signal_guard();
	if (st2 == NULL || !st2->params_set)
	{
		if (st1 == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st1);
	}
	if (st1 == NULL)
		st1 = drape_state_new(aggcxt);
	drape_params(st1, aggcxt, st2->method, st2->target, VARSIZE_ANY(st2->target));
	tdc_agg_rows_add(&st1->rows, st2->rows, DRAPE_NAME);
	base = st1->base->pts.n;
	tdc_agg_state_merge(st1->base, st2->base);
	if (st1->breaklines)
		tdc_seg_append(&st1->segs, &st2->segs, base);
	PG_RETURN_POINTER(st1);
}

PG_FUNCTION_INFO_V1(st_tdcdrape_serialfn);

Datum
st_tdcdrape_serialfn(PG_FUNCTION_ARGS)
{
	DrapeState *st;
	char	   *extra;
	Size		mlen,
				tlen,
				slen,
				len;
	uint32		u[2];
	uint64		tl;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcdrape_serialfn");
	st = (DrapeState *) PG_GETARG_POINTER(0);
	mlen = st->params_set ? strlen(st->method) : 0;
	tlen = st->params_set ? VARSIZE_ANY(st->target) : 0;
	slen = st->breaklines ? (Size) st->segs.nseg * 2 * sizeof(uint32) : 0;
	len = DRAPE_FIXED + mlen + tlen + slen;
	extra = palloc_extended(len, MCXT_ALLOC_HUGE);
	u[0] = st->params_set ? 1 : 0;
	u[1] = (uint32) mlen;
	tl = tlen;
	memcpy(extra, u, 8);
	memcpy(extra + 8, &tl, 8);
	memcpy(extra + 16, &st->rows, 8);
	if (mlen > 0)
		memcpy(extra + DRAPE_FIXED, st->method, mlen);
	if (tlen > 0)
		memcpy(extra + DRAPE_FIXED + mlen, st->target, tlen);
	if (slen > 0)
		memcpy(extra + DRAPE_FIXED + mlen + tlen, st->segs.seg, slen);
	PG_RETURN_BYTEA_P(tdc_agg_state_serialize_with(st->base, &drape_format, extra, len,
												   slen == 0 ? NULL :
												   psprintf("%llu vertices and %llu breakline segments",
															(unsigned long long) st->base->pts.n,
															(unsigned long long) st->segs.nseg)));
}

PG_FUNCTION_INFO_V1(st_tdcdrape_deserialfn);

Datum
st_tdcdrape_deserialfn(PG_FUNCTION_ARGS)
{
	DrapeState *st;
	const char *extra;
	Size		extra_len,
				rest;
	uint32		u[2];
	uint64		tl;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcdrape_deserialfn");
	st = palloc0(sizeof(DrapeState));
	st->base = tdc_agg_state_deserialize_with(PG_GETARG_BYTEA_P(0), &drape_format,
											  CurrentMemoryContext, &extra, &extra_len);
	st->base->pts.curves = TDC_CURVES_STROKE;
	if (extra_len < DRAPE_FIXED)
		tdc_agg_state_corrupt(DRAPE_NAME, "its parameters are truncated");
	memcpy(u, extra, 8);
	memcpy(&tl, extra + 8, 8);
	memcpy(&st->rows, extra + 16, 8);
	if (u[0] > 1 || st->rows < 0 || u[1] > METHOD_MAX || tl > extra_len ||
		(uint64) extra_len < DRAPE_FIXED + (uint64) u[1] + tl ||
		(u[0] == 0 && (u[1] != 0 || tl != 0)) ||
		(u[0] == 1 && (u[1] == 0 || tl < VARHDRSZ)))
		tdc_agg_state_corrupt(DRAPE_NAME, "bad method or target lengths");
	st->params_set = u[0] == 1;
	tdc_agg_state_check_unset(st->base, st->params_set, st->rows, DRAPE_NAME);
	if (st->params_set)
	{
		tdc_interp_spec spec;

		st->method = pnstrdup(extra + DRAPE_FIXED, u[1]);
		if (strlen(st->method) != u[1])
			tdc_agg_state_corrupt(DRAPE_NAME, "a NUL in the method");
		check_method(st->method, &spec);
		st->target = palloc((Size) tl);
		memcpy(st->target, extra + DRAPE_FIXED + u[1], (Size) tl);
		if (VARATT_IS_EXTENDED(st->target) || VARSIZE(st->target) != tl)
			tdc_agg_state_corrupt(DRAPE_NAME, "the target's length");
		drape_breaklines(st, CurrentMemoryContext);
	}
	rest = extra_len - DRAPE_FIXED - u[1] - (Size) tl;
	if (!st->breaklines && rest != 0)
		tdc_agg_state_corrupt(DRAPE_NAME, "segments without breaklines");
	if (st->breaklines)
		tdc_seg_read(&st->segs, extra + DRAPE_FIXED + u[1] + tl, rest, st->base->pts.n);
	if (st->base->pts.n > 0 && !st->base->pts.hasz)
		tdc_agg_state_corrupt(DRAPE_NAME, "samples without Z");
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcdrape_finalfn);

Datum
st_tdcdrape_finalfn(PG_FUNCTION_ARGS)
{
	DrapeState *st;
	TdcPointBuf *pts;
	TdcDrapeTarget t;
	TdcTinRun  *tr;
	tdc_interp_spec spec;
	const tdc_drape_vertex *v;
	const size_t *off;
	size_t		nv;
	struct varlena *out;
	char		err[256];
	int			rc;
	uint64		limit = tdc_max_memory_bytes(),
				room = PG_UINT64_MAX;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcdrape_finalfn");
	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (DrapeState *) PG_GETARG_POINTER(0);
	if (!st->params_set)
		PG_RETURN_NULL();
	pts = &st->base->pts;
	check_method(st->method, &spec);
	tdc_drape_target_read(&t, st->target, DRAPE_NAME);
	if (pts->have_first && pts->srid != t.srid)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the target's SRID %d is not the samples' SRID %d", DRAPE_NAME,
						t.srid, pts->srid),
				 errhint("Transform one of them with ST_Transform, or set the SRID with ST_SetSRID.")));

	tr = tdc_tin_run_start(pts, st->breaklines ? &st->segs : NULL,
						   VARSIZE_ANY(st->target) + tdc_drape_target_bytes(&t), DRAPE_NAME);
	err[0] = '\0';
	rc = tdc_tin_drape_start(tr->tin, &spec, t.xy, t.chain_end, t.nchains, err, sizeof(err));
	tdc_tin_run_wait(tr, rc, err, DRAPE_NAME);
	nv = tdc_tin_drape_result(tr->tin, &v, &off);
	for (size_t i = 0; i < nv; i++)
		if (!v[i].inside)
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: vertex (%.17g %.17g) of the target lies outside the convex hull of the %llu sample vertices",
							DRAPE_NAME, v[i].x, v[i].y, (unsigned long long) pts->n),
					 errhint("Clip the target to the samples' hull first, with ST_Intersection(target, ST_ConvexHull(ST_Collect(samples))).")));
	if (limit > 0)
	{
		uint64		used = tdc_pointbuf_bytes(pts) + tr->run->engine_bytes +
			tdc_tin_memory((size_t) pts->n) + VARSIZE_ANY(st->target) +
			tdc_drape_target_bytes(&t) + (uint64) nv * sizeof(tdc_drape_vertex);

		room = limit > used ? limit - used : 0;
	}
	out = tdc_drape_target_write(&t, v, off, room, DRAPE_NAME);
	tdc_tin_run_free(tr);
	PG_RETURN_POINTER(out);
}
