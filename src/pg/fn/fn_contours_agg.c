/*
 * fn_contours_agg.c
 *		The ST_TDCContours aggregates: contour lines of the TIN of all rows'
 *		vertices, at the levels base + k * interval, as one MULTILINESTRING Z.
 *
 * ST_TDCContours(geom, interval, base, method) (1.2.0) draws them on the
 * triangles the method keeps: 'linear', or 'linear:max_edge=L', which
 * drops the triangles with an edge longer than L (tdc.h), so that a lake
 * or a building with no sample inside gets no contour across it: a line
 * stops where it would enter such a triangle.  The one method parser
 * (tdc_interp_parse) reads it, as for ST_TDCDrape and the raster
 * functions, and tdc_tin_contours_spec_check refuses other methods and
 * options (nothing else concerns contours).
 *
 * The state is the samples every TIN aggregate keeps (tin_agg.c), plus the
 * interval, the base and max_edge (0 without the method or the option),
 * which must be the same in every row.  Rows whose geometry, interval,
 * base or method is NULL are skipped; an EMPTY sample is skipped too.
 * Under a parallel plan a worker's state travels in the Delaunay state's
 * serialized form under magic "TCN1", version 2, followed by
 *
 *		uint32 params_set (0 or 1), uint32 zero, float8 interval,
 *		float8 base, int64 rows, float8 max_edge (finite, >= 0)
 *
 * The lines are the core's (tin_contour.c: merged into maximal lines,
 * closed where they do not end on the hull or on a dropped triangle, a
 * level at a sample's height counted once), written by gser_contour.c with
 * the samples' SRID.
 */
#include "postgres.h"

#include <math.h>

#include "fmgr.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

#define CONTOUR_NAME		"ST_TDCContours"
#define CONTOUR_EXTRA		40

static const TdcStateFormat contour_format = {
	0x314e4354,					/* "TCN1" little-endian */
	2, CONTOUR_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0).",
	-1
};

typedef struct ContourState
{
	TdcTinAgg	s;				/* the samples (tin_agg.c) */
	double		interval;
	double		level0;			/* the base level */
	double		max_edge;		/* the method's, 0: none */
} ContourState;

static ContourState *
contour_state_new(MemoryContext cxt)
{
	return (ContourState *) tdc_tin_agg_new(cxt, sizeof(ContourState), TDC_CURVES_STROKE);
}

static void
check_levels(double interval, double base)
{
	if (!(interval > 0) || isinf(interval))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: interval must be a finite number > 0, not %g", CONTOUR_NAME, interval)));
	if (!isfinite(base))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: base must be a finite number, not %g", CONTOUR_NAME, base)));
}

/* The method: 'linear' with max_edge only; its max_edge (0: none). */
static double
contour_method(const char *method)
{
	tdc_interp_spec spec;
	char		err[256];

	err[0] = '\0';
	if (tdc_interp_parse(method, &spec, err, sizeof(err)) != TDC_OK ||
		tdc_tin_contours_spec_check(&spec, err, sizeof(err)) != TDC_OK)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid method \"%s\"", CONTOUR_NAME, method),
				 err[0] ? errdetail("%s.", err) : 0,
				 errhint("Use 'linear', or 'linear:max_edge=L' to leave out the triangles with an edge longer than L.")));
	return spec.max_edge;
}

static void
contour_params(ContourState *st, double interval, double base, double max_edge)
{
	if (!st->s.params_set)
	{
		st->s.params_set = true;
		st->interval = interval;
		st->level0 = base;
		st->max_edge = max_edge;
		return;
	}
	if (st->interval != interval || st->level0 != base)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: interval and base must be the same for all rows (%g, %g versus %g, %g)",
						CONTOUR_NAME, st->interval, st->level0, interval, base)));
	if (st->max_edge != max_edge)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the method must be the same for all rows (max_edge %g versus %g)",
						CONTOUR_NAME, st->max_edge, max_edge)));
}

/*
 * st_tdccontours_transfn(internal, geometry, float8 [, float8 [, text]]), and with patch
 * st_tdccontours_pc_transfn(internal, pcpatch, float8 [, float8 [, text [, text filter]]]) (pcpatch_source.c;
 * a NULL filter is no filter)
 */
static Datum
contours_trans(FunctionCallInfo fcinfo, bool patch)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdccontours_transfn");
	ContourState *st = PG_ARGISNULL(0) ? NULL : (ContourState *) PG_GETARG_POINTER(0);
	double		interval,
				base = 0,
				max_edge = 0;

	tdc_signal_guard();
	if (PG_ARGISNULL(1) || PG_ARGISNULL(2) || (PG_NARGS() > 3 && PG_ARGISNULL(3)) ||
		(PG_NARGS() > 4 && PG_ARGISNULL(4)))
	{
		if (st == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st);
	}
	interval = PG_GETARG_FLOAT8(2);
	if (PG_NARGS() > 3)
		base = PG_GETARG_FLOAT8(3);
	check_levels(interval, base);
	if (PG_NARGS() > 4)
		max_edge = contour_method(text_to_cstring(PG_GETARG_TEXT_PP(4)));
	if (st == NULL)
		st = contour_state_new(aggcxt);
	contour_params(st, interval, base, max_edge);
	if (patch)
		tdc_tin_agg_add_patch(&st->s, fcinfo->flinfo, PG_GETARG_DATUM(1), tdc_pc_filter_arg(fcinfo, 5), CONTOUR_NAME);
	else
		tdc_tin_agg_add(&st->s, PG_GETARG_DATUM(1), CONTOUR_NAME);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdccontours_transfn);

Datum
st_tdccontours_transfn(PG_FUNCTION_ARGS)
{
	return contours_trans(fcinfo, false);
}

PG_FUNCTION_INFO_V1(st_tdccontours_pc_transfn);

Datum
st_tdccontours_pc_transfn(PG_FUNCTION_ARGS)
{
	return contours_trans(fcinfo, true);
}

static void
contour_combine_params(TdcTinAgg *dst, const TdcTinAgg *src, MemoryContext cxt)
{
	const ContourState *b = (const ContourState *) src;

	contour_params((ContourState *) dst, b->interval, b->level0, b->max_edge);
}

/* The parameters: uint32 params_set, uint32 zero, interval, base, rows, max_edge. */
static Size
contour_var_len(const TdcTinAgg *a)
{
	return 0;
}

static void
contour_write(const TdcTinAgg *a, char *extra)
{
	const ContourState *st = (const ContourState *) a;

	memcpy(extra + 8, &st->interval, 8);
	memcpy(extra + 16, &st->level0, 8);
	memcpy(extra + 32, &st->max_edge, 8);
}

static Size
contour_read(TdcTinAgg *a, const char *extra, Size len)
{
	ContourState *st = (ContourState *) a;
	uint32		zero;

	memcpy(&zero, extra + 4, 4);
	memcpy(&st->interval, extra + 8, 8);
	memcpy(&st->level0, extra + 16, 8);
	memcpy(&st->max_edge, extra + 32, 8);
	if (zero != 0)
		tdc_agg_state_corrupt(CONTOUR_NAME, "bad parameter flags");
	if (st->s.params_set && (!(st->interval > 0) || isinf(st->interval) || !isfinite(st->level0)))
		tdc_agg_state_corrupt(CONTOUR_NAME, "bad interval or base");
	if (st->s.params_set && !(st->max_edge >= 0 && st->max_edge < INFINITY))
		tdc_agg_state_corrupt(CONTOUR_NAME, "bad max_edge");
	return CONTOUR_EXTRA;
}

static const TdcTinAggKind contour_kind = {
	&contour_format, sizeof(ContourState), TDC_CURVES_STROKE,
	CONTOUR_EXTRA, 24, contour_combine_params, contour_var_len, contour_write, contour_read
};

/* st_tdccontours_combinefn, _serialfn and _deserialfn */
TDC_TIN_AGG_SUPPORT(st_tdccontours, contour_kind);

PG_FUNCTION_INFO_V1(st_tdccontours_finalfn);

Datum
st_tdccontours_finalfn(PG_FUNCTION_ARGS)
{
	ContourState *st;
	TdcTinRun  *tr;
	TdcPointBuf *pts;
	tdc_interp_spec spec;
	struct varlena *out;
	char		err[256];
	int			rc;
	uint64		limit = tdc_max_memory_bytes(),
				room = PG_UINT64_MAX;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdccontours_finalfn");
	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (ContourState *) PG_GETARG_POINTER(0);
	if (!st->s.params_set)
		PG_RETURN_NULL();
	pts = &st->s.base->pts;
	tr = tdc_tin_run_start(pts, NULL, 0, CONTOUR_NAME);
	err[0] = '\0';
	memset(&spec, 0, sizeof(spec));
	spec.method = TDC_INTERP_LINEAR;
	spec.max_edge = st->max_edge;
	rc = tdc_tin_contours_start_spec(tr->tin, st->interval, st->level0, &spec, err, sizeof(err));
	tdc_tin_run_wait(tr, rc, err, CONTOUR_NAME);
	if (limit > 0)
	{
		size_t		npoints,
					nlines = tdc_tin_contour_count(tr->tin, &npoints);
		uint64		used = tdc_pointbuf_bytes(pts) + tr->run->engine_bytes +
			tdc_tin_memory((size_t) pts->n) + (uint64) npoints * 2 * sizeof(double) +
			(uint64) nlines * 32;

		room = limit > used ? limit - used : 0;
	}
	out = tdc_gser_contours(tr->tin, pts->srid, room, CONTOUR_NAME);
	tdc_tin_run_free(tr);
	PG_RETURN_POINTER(out);
}
