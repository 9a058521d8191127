/*
 * fn_voronoi_agg.c
 *		The ST_TDCVoronoi aggregates: the Voronoi cells of the vertices of
 *		all rows, the same as ST_TDCVoronoiPolygons(ST_Collect(geom),
 *		tolerance, extend_to) without the collection.
 *
 * The state is the Delaunay aggregate's (the collected vertices and the
 * tolerance, agg_state.c) plus extend_to's bounding box, which must be
 * the same in every row, as the tolerance must.  Rows whose geometry or
 * tolerance is NULL are skipped; a NULL extend_to means none.  Under a
 * parallel plan a worker's state travels in the Delaunay state's serialized
 * form (agg_state.c) under magic "VRN2", followed by
 *
 *		uint32 has_extend_to (0 or 1), uint32 zero, 4 float8 (xmin, ymin,
 *		xmax, ymax; a box with min <= max when has_extend_to)
 */
#include "postgres.h"

#include <math.h>

#include "fmgr.h"
#include "utils/memutils.h"

#include "fn_voronoi.h"

#define VOR_AGG_NAME		"ST_TDCVoronoi"
#define VOR_EXTRA			40		/* bytes after the vertices */

static const TdcStateFormat vor_format = {
	0x324e5256,					/* "VRN2" little-endian */
	1, VOR_AGG_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0).",
	-1
};

typedef struct VorAggState
{
	TdcAggState *base;
	bool		ext_set;		/* a row has been accumulated: has_ext is known */
	bool		has_ext;
	double		ext[4];
} VorAggState;

static VorAggState *
vor_state_new(MemoryContext cxt)
{
	VorAggState *st = MemoryContextAllocZero(cxt, sizeof(VorAggState));

	st->base = tdc_agg_state_new(cxt);
	return st;
}

/* Every row must give the same tolerance and extend_to. */
static void
vor_state_params(VorAggState *st, double tolerance, bool has_ext, const double *ext)
{
	if (st->base->params_set && st->base->tolerance != tolerance)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tolerance must be the same for all rows (%g versus %g)",
						VOR_AGG_NAME, st->base->tolerance, tolerance)));
	tdc_agg_state_set_params(st->base, tolerance, TDC_OUT_POLYGONS);
	if (!st->ext_set)
	{
		st->ext_set = true;
		st->has_ext = has_ext;
		if (has_ext)
			memcpy(st->ext, ext, sizeof(st->ext));
		return;
	}
	if (st->has_ext != has_ext ||
		(has_ext && (st->ext[0] != ext[0] || st->ext[1] != ext[1] ||
					 st->ext[2] != ext[2] || st->ext[3] != ext[3])))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: extend_to must have the same bounding box in all rows",
						VOR_AGG_NAME)));
}

PG_FUNCTION_INFO_V1(st_tdcvoronoi_transfn);

Datum
st_tdcvoronoi_transfn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcvoronoi_transfn");
	VorAggState *st = PG_ARGISNULL(0) ? NULL : (VorAggState *) PG_GETARG_POINTER(0);
	double		tolerance = 0.0,
				ext[4];
	bool		has_ext = false;

	tdc_signal_guard();
	if (PG_ARGISNULL(1) || (PG_NARGS() > 2 && PG_ARGISNULL(2)))
	{
		if (st == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st);
	}
	if (PG_NARGS() > 2)
	{
		tolerance = PG_GETARG_FLOAT8(2);
		tdc_check_tolerance(false, tolerance, VOR_AGG_NAME);
		if (!PG_ARGISNULL(3))
		{
			tdc_voronoi_extend_to_box(PG_GETARG_DATUM(3),
									  ext, VOR_AGG_NAME);
			has_ext = true;
		}
	}
	if (st == NULL)
	{
		st = vor_state_new(aggcxt);
		st->base->pts.curves = TDC_CURVES_VERTICES;
	}
	vor_state_params(st, tolerance, has_ext, ext);

	(void) tdc_read_geometry(&st->base->pts, PG_GETARG_DATUM(1), VOR_AGG_NAME);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcvoronoi_combinefn);

Datum
st_tdcvoronoi_combinefn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcvoronoi_combinefn");
	VorAggState *st1 = PG_ARGISNULL(0) ? NULL : (VorAggState *) PG_GETARG_POINTER(0);
	VorAggState *st2 = PG_ARGISNULL(1) ? NULL : (VorAggState *) PG_GETARG_POINTER(1);

	tdc_signal_guard();
	if (st2 == NULL || !st2->ext_set)
	{
		if (st1 == NULL)
			PG_RETURN_NULL();
		PG_RETURN_POINTER(st1);
	}
	if (st1 == NULL)
		st1 = vor_state_new(aggcxt);
	vor_state_params(st1, st2->base->tolerance, st2->has_ext, st2->ext);
	tdc_agg_state_merge(st1->base, st2->base);
	PG_RETURN_POINTER(st1);
}

PG_FUNCTION_INFO_V1(st_tdcvoronoi_serialfn);

Datum
st_tdcvoronoi_serialfn(PG_FUNCTION_ARGS)
{
	VorAggState *st;
	char		extra[VOR_EXTRA];
	uint32		u[2];

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcvoronoi_serialfn");
	st = (VorAggState *) PG_GETARG_POINTER(0);
	u[0] = st->has_ext ? 1 : 0;
	u[1] = 0;
	memcpy(extra, u, sizeof(u));
	memcpy(extra + sizeof(u), st->ext, sizeof(st->ext));
	PG_RETURN_BYTEA_P(tdc_agg_state_serialize_with(st->base, &vor_format,
												   extra, VOR_EXTRA, NULL));
}

PG_FUNCTION_INFO_V1(st_tdcvoronoi_deserialfn);

Datum
st_tdcvoronoi_deserialfn(PG_FUNCTION_ARGS)
{
	VorAggState *st;
	const char *extra;
	Size		extra_len;
	uint32		u[2];

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcvoronoi_deserialfn");
	st = palloc0(sizeof(VorAggState));
	st->base = tdc_agg_state_deserialize_with(PG_GETARG_BYTEA_P(0), &vor_format,
											  CurrentMemoryContext,
											  &extra, &extra_len);
	if (extra_len != VOR_EXTRA)
		tdc_agg_state_corrupt(VOR_AGG_NAME,
							  psprintf("%zu bytes of extend_to, not %d",
									   extra_len, VOR_EXTRA));
	memcpy(u, extra, sizeof(u));
	if (u[0] > 1 || u[1] != 0)
		tdc_agg_state_corrupt(VOR_AGG_NAME, "bad extend_to flag");
	st->has_ext = u[0] == 1;
	memcpy(st->ext, extra + sizeof(u), sizeof(st->ext));
	if (st->has_ext && !(st->ext[0] <= st->ext[2] && st->ext[1] <= st->ext[3]))
		tdc_agg_state_corrupt(VOR_AGG_NAME, "bad extend_to box");
	st->ext_set = true;
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcvoronoi_finalfn);

Datum
st_tdcvoronoi_finalfn(PG_FUNCTION_ARGS)
{
	VorAggState *st;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcvoronoi_finalfn");
	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (VorAggState *) PG_GETARG_POINTER(0);
	PG_RETURN_POINTER(tdc_voronoi_to_value(&st->base->pts, st->base->tolerance,
										   st->has_ext ? st->ext : NULL, false,
										   VOR_AGG_NAME));
}
