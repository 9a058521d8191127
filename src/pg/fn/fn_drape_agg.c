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
 * combined with them, and max_edge=L with any method, which drops the
 * triangles with an edge longer than L (tdc.h) and extends the rule: a
 * vertex where no kept triangle holds it (strictly inside a dropped one)
 * is an ERROR naming it, like one outside the hull, and with 'linear' so
 * is a segment running through a dropped triangle, naming the point where
 * it enters it: the draped line would cross the hole on facets the option
 * asked to leave out.  'nearest' and 'natural_neighbor' give heights at the
 * vertices only, so only the vertices are checked there.
 *
 * The state is the samples every TIN aggregate keeps (tin_agg.c), plus the
 * method and the target, which must be the same in every row (a target
 * that is not a constant of the statement is compared with the first
 * row's byte for byte).
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
	TdcTinAgg	s;				/* the samples (tin_agg.c) */
	char	   *method;			/* as given, checked */
	struct varlena *target;		/* detoasted, in the aggregate context */
	bool		target_const;	/* the target is a constant: no need to compare */
} DrapeState;

static DrapeState *
drape_state_new(MemoryContext cxt)
{
	return (DrapeState *) tdc_tin_agg_new(cxt, sizeof(DrapeState), TDC_CURVES_STROKE);
}

/*
 * The method, checked: a name of tdc_interp_parse's, with no option but
 * linear's breaklines and max_edge (not GDAL's radius or nodata).
 */
static void
check_method(const char *method, tdc_interp_spec *spec)
{
	char		err[256];
	bool		parsed,
				gdal_option;

	err[0] = '\0';
	parsed = strlen(method) <= METHOD_MAX && tdc_interp_parse(method, spec, err, sizeof(err)) == TDC_OK;
	gdal_option = parsed && (spec->options & (TDC_INTERP_OPT_RADIUS | TDC_INTERP_OPT_NODATA));
	if (!parsed || gdal_option)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid method \"%s\"", DRAPE_NAME, method),
				 gdal_option ? errdetail("%s takes no options but linear's breaklines and max_edge: every vertex of the target must lie in the samples' convex hull.",
										 DRAPE_NAME) : (err[0] ? errdetail("%s.", err) : 0),
				 errhint("Use 'linear', 'linear:breaklines=true', 'nearest' or 'natural_neighbor'.")));
	/*
	 * Outside the hull there is no value: an error, raised by the final
	 * function from where each vertex lies, not from its value.  In the
	 * core's terms radius 0 is "never" and -1 "at any distance": linear and
	 * natural neighbour take no site outside the hull, and nearest takes the
	 * nearest site wherever the vertex is (0 there would give every vertex
	 * nodata, Z = 0: issue 36).
	 */
	spec->radius = spec->method == TDC_INTERP_NEAREST ? -1 : 0;
}

/* From the first row, whose method fixes every row's: breaklines or not. */
static void
drape_breaklines(DrapeState *st, MemoryContext cxt)
{
	tdc_interp_spec spec;

	check_method(st->method, &spec);
	tdc_tin_agg_breaklines(&st->s, spec.breaklines, cxt, DRAPE_NAME);
}

static void
drape_params(DrapeState *st, MemoryContext cxt, const char *method,
			 const struct varlena *target, Size target_len)
{
	if (!st->s.params_set)
	{
		st->s.params_set = true;
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

/*
 * st_tdcdrape_transfn(internal, geometry, geometry [, text]), and with patch
 * st_tdcdrape_pc_transfn(internal, pcpatch, geometry [, text [, text filter]]) (pcpatch_source.c;
 * a NULL filter is no filter)
 */
static Datum
drape_trans(FunctionCallInfo fcinfo, bool patch)
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
	if (!st->s.params_set || !st->target_const || strcmp(st->method, method) != 0)
	{
		struct varlena *target = PG_DETOAST_DATUM(PG_GETARG_DATUM(2));

		if (!st->s.params_set)
		{
			check_method(method, &spec);
			st->target_const = tdc_agg_arg_is_constant(fcinfo, 1);
		}
		drape_params(st, aggcxt, method, target, VARSIZE_ANY(target));
	}
	if (patch)
		tdc_tin_agg_add_patch(&st->s, fcinfo->flinfo, PG_GETARG_DATUM(1), tdc_pc_filter_arg(fcinfo, 4), DRAPE_NAME);
	else
		tdc_tin_agg_add(&st->s, PG_GETARG_DATUM(1), DRAPE_NAME);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcdrape_transfn);

Datum
st_tdcdrape_transfn(PG_FUNCTION_ARGS)
{
	return drape_trans(fcinfo, false);
}

PG_FUNCTION_INFO_V1(st_tdcdrape_pc_transfn);

Datum
st_tdcdrape_pc_transfn(PG_FUNCTION_ARGS)
{
	return drape_trans(fcinfo, true);
}

static void
drape_combine_params(TdcTinAgg *dst, const TdcTinAgg *src, MemoryContext cxt)
{
	const DrapeState *b = (const DrapeState *) src;

	drape_params((DrapeState *) dst, cxt, b->method, b->target, VARSIZE_ANY(b->target));
}

/*
 * The parameters: uint32 params_set, uint32 method length, uint64 target
 * length, int64 rows, then the method and the target.
 */
static Size
drape_var_len(const TdcTinAgg *a)
{
	const DrapeState *st = (const DrapeState *) a;

	return a->params_set ? strlen(st->method) + VARSIZE_ANY(st->target) : 0;
}

static void
drape_write(const TdcTinAgg *a, char *extra)
{
	const DrapeState *st = (const DrapeState *) a;
	uint32		mlen;
	uint64		tl;

	if (!a->params_set)
		return;
	mlen = (uint32) strlen(st->method);
	tl = VARSIZE_ANY(st->target);
	memcpy(extra + 4, &mlen, 4);
	memcpy(extra + 8, &tl, 8);
	memcpy(extra + DRAPE_FIXED, st->method, mlen);
	memcpy(extra + DRAPE_FIXED + mlen, st->target, tl);
}

static Size
drape_read(TdcTinAgg *a, const char *extra, Size len)
{
	DrapeState *st = (DrapeState *) a;
	uint32		mlen;
	uint64		tl;

	memcpy(&mlen, extra + 4, 4);
	memcpy(&tl, extra + 8, 8);
	if (mlen > METHOD_MAX || tl > len || (uint64) len < DRAPE_FIXED + (uint64) mlen + tl ||
		(!a->params_set && (mlen != 0 || tl != 0)) ||
		(a->params_set && (mlen == 0 || tl < VARHDRSZ)))
		tdc_agg_state_corrupt(DRAPE_NAME, "bad method or target lengths");
	if (a->params_set)
	{
		tdc_interp_spec spec;

		st->method = pnstrdup(extra + DRAPE_FIXED, mlen);
		if (strlen(st->method) != mlen)
			tdc_agg_state_corrupt(DRAPE_NAME, "a NUL in the method");
		check_method(st->method, &spec);
		st->target = palloc((Size) tl);
		memcpy(st->target, extra + DRAPE_FIXED + mlen, (Size) tl);
		if (VARATT_IS_EXTENDED(st->target) || VARSIZE(st->target) != tl)
			tdc_agg_state_corrupt(DRAPE_NAME, "the target's length");
		drape_breaklines(st, CurrentMemoryContext);
	}
	return DRAPE_FIXED + mlen + (Size) tl;
}

static const TdcTinAggKind drape_kind = {
	&drape_format, sizeof(DrapeState), TDC_CURVES_STROKE,
	DRAPE_FIXED, 16, drape_combine_params, drape_var_len, drape_write, drape_read
};

/* st_tdcdrape_combinefn, _serialfn and _deserialfn */
TDC_TIN_AGG_SUPPORT(st_tdcdrape, drape_kind);

/*
 * max_edge: every draped vertex must have a value, and with linear every
 * piece between two of them (tdc_tin_drape_result's valid and gap): the
 * first that has none is an ERROR naming where.
 */
static void
drape_check_max_edge(const tdc_drape_vertex *v, size_t nv, double max_edge)
{
	for (size_t i = 0; i < nv; i++)
	{
		if (!v[i].valid)
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: %s (%.17g %.17g) of the target lies in no triangle that max_edge %g keeps",
							DRAPE_NAME, v[i].t == 0 ? "vertex" : "point", v[i].x, v[i].y, max_edge),
					 errdetail("Every triangle around it has an edge longer than %g.", max_edge),
					 errhint("Raise max_edge, or clip the target to the kept triangles first.")));
		if (v[i].gap)
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: the target runs from (%.17g %.17g) across a triangle that max_edge %g drops",
							DRAPE_NAME, v[i].x, v[i].y, max_edge),
					 errdetail("The triangle has an edge longer than %g: the draped line would cross it on the facets max_edge leaves out.",
							   max_edge),
					 errhint("Raise max_edge, or clip the target to the kept triangles first.")));
	}
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
	if (!st->s.params_set)
		PG_RETURN_NULL();
	pts = &st->s.base->pts;
	check_method(st->method, &spec);
	tdc_drape_target_read(&t, st->target, DRAPE_NAME);
	if (pts->have_first && pts->srid != t.srid)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the target's SRID %d is not the samples' SRID %d", DRAPE_NAME,
						t.srid, pts->srid),
				 errhint("Transform one of them with ST_Transform, or set the SRID with ST_SetSRID.")));

	tr = tdc_tin_run_start(pts, st->s.breaklines ? &st->s.segs : NULL,
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
	if (spec.max_edge > 0)
		drape_check_max_edge(v, nv, spec.max_edge);
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
