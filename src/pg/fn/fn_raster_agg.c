/*
 * fn_raster_agg.c
 *		The ST_TDCInterpolate aggregates: the TIN of all rows' vertices (the
 *		samples) interpolated into a raster.
 *
 * ST_TDCInterpolate(geom, template [, method [, template_band_num]]) is
 * ST_TDCInterpolateRaster(ST_Collect(geom), method, template, band) without
 * the collection: the vertices are read row by row into the Delaunay
 * aggregate's point buffer (agg_state.c), heights required (tin_run.c: a
 * row without Z is an ERROR naming the row), and the final function runs
 * fn_raster.c's interpolation.  method defaults to 'linear', the band to 1.
 * Rows with a NULL argument are skipped; no row left gives NULL, as do
 * EMPTY samples only.
 *
 * The template, the method and the band must be the same in every row.
 * Of the template only its geometry (size, geotransform, SRID) and the
 * band's pixel type and nodata value matter, so that is what the state
 * keeps and compares: a template that is a constant of the statement (a
 * literal or a parameter) is read once; any other is read again (its first
 * bytes, raster_read.c) in every row, unless it is the same stored TOAST
 * value as the row before's (a template joined to every row from a table),
 * which would cost a fetch from the TOAST table each time.  A template that
 * differs is an ERROR.
 *
 * Under a parallel plan a worker's state travels in the Delaunay state's
 * serialized form under magic "TRI1", followed by
 *
 *		uint32 params_set (0 or 1), uint32 method length, int64 rows,
 *		int32 band, int32 SRID, uint32 width, uint32 height,
 *		float8 geotransform[6], int32 pixel type, uint32 hasnodata,
 *		float8 nodata, then the method's bytes, then with breaklines
 *		(version 2) k * 2 uint32 segment ends (k from the length)
 *
 * in the machine's byte order, every field checked when read: a segment
 * must have both ends among the state's vertices, and a method without
 * breaklines no segment.
 *
 * Breaklines ('linear:breaklines=true', fn_raster.c): from the first row,
 * whose method fixes every row's, the samples' linework is kept as
 * segments beside the vertices (seglist.c), combined with them (shifted by
 * the vertices before), and inserted before the TIN is built.
 */
#include "postgres.h"

#include <math.h>

#include "access/detoast.h"
#include "fmgr.h"
#include "nodes/primnodes.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "formats/raster_format.h"
#include "fn_raster.h"

#define INTERP_NAME			"ST_TDCInterpolate"
#define INTERP_FIXED		96	/* the fixed part after the vertices */
#define METHOD_MAX			1024

static const TdcStateFormat interp_format = {
	0x31495254,					/* "TRI1" little-endian */
	2, INTERP_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0).",
	-1
};

typedef struct InterpState
{
	TdcTinAgg	s;				/* the samples (tin_agg.c) */
	char	   *method;			/* as given, checked */
	int32		band;
	TdcRasterInfo tmpl;			/* the template's geometry and band */
	bool		tmpl_const;		/* the template is a constant: read once */
	/* the stored template value of the last row read */
	bool		last_ondisk;
	struct varatt_external last_toast;
} InterpState;

/* a curve's stored vertices, as ST_InterpolateRaster */
static InterpState *
interp_state_new(MemoryContext cxt)
{
	return (InterpState *) tdc_tin_agg_new(cxt, sizeof(InterpState), TDC_CURVES_VERTICES);
}

static bool
same_double(double a, double b)
{
	return a == b || (isnan(a) && isnan(b));
}

/* Do two templates give the same result: geometry, pixel type, nodata? */
static bool
same_template(const TdcRasterInfo *a, const TdcRasterInfo *b)
{
	return a->srid == b->srid && a->width == b->width && a->height == b->height &&
		memcmp(a->gt, b->gt, sizeof(a->gt)) == 0 &&
		a->b.pixtype == b->b.pixtype && a->b.hasnodata == b->b.hasnodata &&
		(!a->b.hasnodata || same_double(a->b.nodata, b->b.nodata));
}

static void
interp_params(InterpState *st, MemoryContext cxt, const char *method, int32 band,
			  const TdcRasterInfo *tmpl)
{
	if (!st->s.params_set)
	{
		tdc_interp_spec spec;

		st->s.params_set = true;
		st->method = MemoryContextStrdup(cxt, method);
		st->band = band;
		st->tmpl = *tmpl;
		/* from the first row on, the samples' lines are kept if asked for */
		tdc_raster_method(method, &spec, INTERP_NAME);
		tdc_tin_agg_breaklines(&st->s, spec.breaklines, cxt, INTERP_NAME);
		return;
	}
	if (strcmp(st->method, method) != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: method must be the same for all rows (\"%s\" versus \"%s\")",
						INTERP_NAME, st->method, method)));
	if (st->band != band)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: template_band_num must be the same for all rows (%d versus %d)",
						INTERP_NAME, st->band, band)));
	if (tmpl != NULL && !same_template(&st->tmpl, tmpl))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: template must be the same raster for all rows", INTERP_NAME),
				 errdetail("Its size, geotransform, SRID, or band %d's pixel type or nodata value differ from the first row's.",
						   band),
				 errhint("Interpolate one template per aggregate, e.g. with GROUP BY the template.")));
}

/*
 * Is d the stored TOAST value the state read last?  Remembers it if not.
 * (A TOAST value is named by its table and id; an in-line value has no
 * name, and the same address may hold another row's value later, so it is
 * read again, which costs a copy of its first bytes.)
 */
static bool
same_value_as_last(InterpState *st, Datum d)
{
	struct varlena *v = (struct varlena *) DatumGetPointer(d);
	struct varatt_external t;

	if (!VARATT_IS_EXTERNAL_ONDISK(v))
	{
		st->last_ondisk = false;
		return false;
	}
	VARATT_EXTERNAL_GET_POINTER(t, v);
	if (st->last_ondisk && t.va_valueid == st->last_toast.va_valueid &&
		t.va_toastrelid == st->last_toast.va_toastrelid)
		return true;
	st->last_ondisk = true;
	st->last_toast = t;
	return false;
}

/*
 * st_tdcinterpolate_transfn(internal, geometry, raster [, text [, int4]]), and with patch
 * st_tdcinterpolate_pc_transfn(internal, pcpatch, raster [, text [, int4 [, text filter]]]) (pcpatch_source.c;
 * a NULL filter is no filter)
 */
static Datum
interp_trans(FunctionCallInfo fcinfo, bool patch)
{
	MemoryContext aggcxt = tdc_agg_context(fcinfo, "st_tdcinterpolate_transfn");
	InterpState *st = PG_ARGISNULL(0) ? NULL : (InterpState *) PG_GETARG_POINTER(0);
	char	   *method = "linear";
	int32		band = 1;

	tdc_signal_guard();
	for (int i = 1; i < Min(PG_NARGS(), 5); i++)
		if (PG_ARGISNULL(i))
		{
			if (st == NULL)
				PG_RETURN_NULL();
			PG_RETURN_POINTER(st);
		}
	if (PG_NARGS() > 3)
		method = text_to_cstring(PG_GETARG_TEXT_PP(3));
	if (PG_NARGS() > 4)
		band = PG_GETARG_INT32(4);
	if (st == NULL)
		st = interp_state_new(aggcxt);

	if (!st->s.params_set)
	{
		TdcRasterInfo tmpl;
		tdc_interp_spec spec;

		if (strlen(method) > METHOD_MAX)
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: method of %zu bytes, more than %d", INTERP_NAME,
							strlen(method), METHOD_MAX)));
		tdc_raster_method(method, &spec, INTERP_NAME);
		tdc_raster_read(PG_GETARG_DATUM(2), band, &tmpl, INTERP_NAME);
		st->tmpl_const = tdc_agg_arg_is_constant(fcinfo, 1);
		(void) same_value_as_last(st, PG_GETARG_DATUM(2));
		interp_params(st, aggcxt, method, band, &tmpl);
	}
	else if (!st->tmpl_const && !same_value_as_last(st, PG_GETARG_DATUM(2)))
	{
		TdcRasterInfo tmpl;

		tdc_raster_read(PG_GETARG_DATUM(2), band, &tmpl, INTERP_NAME);
		interp_params(st, aggcxt, method, band, &tmpl);
	}
	else
		interp_params(st, aggcxt, method, band, NULL);

	if (patch)
		tdc_tin_agg_add_patch(&st->s, fcinfo->flinfo, PG_GETARG_DATUM(1), tdc_pc_filter_arg(fcinfo, 5), INTERP_NAME);
	else
		tdc_tin_agg_add(&st->s, PG_GETARG_DATUM(1), INTERP_NAME);
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(st_tdcinterpolate_transfn);

Datum
st_tdcinterpolate_transfn(PG_FUNCTION_ARGS)
{
	return interp_trans(fcinfo, false);
}

PG_FUNCTION_INFO_V1(st_tdcinterpolate_pc_transfn);

Datum
st_tdcinterpolate_pc_transfn(PG_FUNCTION_ARGS)
{
	return interp_trans(fcinfo, true);
}

static void
interp_combine_params(TdcTinAgg *dst, const TdcTinAgg *src, MemoryContext cxt)
{
	const InterpState *b = (const InterpState *) src;

	interp_params((InterpState *) dst, cxt, b->method, b->band, &b->tmpl);
}

/*
 * The parameters: uint32 params_set, uint32 method length, int64 rows,
 * int32 band, int32 SRID, uint32 width, uint32 height, the geotransform,
 * int32 pixel type, uint32 hasnodata, float8 nodata, then the method.
 */
static Size
interp_var_len(const TdcTinAgg *a)
{
	return a->params_set ? strlen(((const InterpState *) a)->method) : 0;
}

static void
interp_write(const TdcTinAgg *a, char *extra)
{
	const InterpState *st = (const InterpState *) a;
	uint32		mlen = (uint32) interp_var_len(a);
	int32		i4[2] = {st->band, st->tmpl.srid};
	uint32		wh[2] = {st->tmpl.width, st->tmpl.height};
	int32		pixtype = st->tmpl.b.pixtype;
	uint32		hasnodata = st->tmpl.b.hasnodata ? 1 : 0;

	memcpy(extra + 4, &mlen, 4);
	memcpy(extra + 16, i4, 8);
	memcpy(extra + 24, wh, 8);
	memcpy(extra + 32, st->tmpl.gt, 48);
	memcpy(extra + 80, &pixtype, 4);
	memcpy(extra + 84, &hasnodata, 4);
	memcpy(extra + 88, &st->tmpl.b.nodata, 8);
	if (mlen > 0)
		memcpy(extra + INTERP_FIXED, st->method, mlen);
}

static Size
interp_read(TdcTinAgg *a, const char *extra, Size len)
{
	InterpState *st = (InterpState *) a;
	uint32		mlen;
	int32		i4[2];
	uint32		wh[2];
	int32		pixtype;
	uint32		hasnodata;

	memcpy(&mlen, extra + 4, 4);
	memcpy(i4, extra + 16, 8);
	memcpy(wh, extra + 24, 8);
	memcpy(st->tmpl.gt, extra + 32, 48);
	memcpy(&pixtype, extra + 80, 4);
	memcpy(&hasnodata, extra + 84, 4);
	memcpy(&st->tmpl.b.nodata, extra + 88, 8);
	if (mlen > METHOD_MAX || (uint64) len < INTERP_FIXED + (uint64) mlen ||
		(!a->params_set && (mlen != 0 || len != INTERP_FIXED)) || (a->params_set && mlen == 0))
		tdc_agg_state_corrupt(INTERP_NAME, "bad method length");
	if (a->params_set)
	{
		tdc_interp_spec spec;

		if (i4[0] < 1 || wh[0] > PG_UINT16_MAX || wh[1] > PG_UINT16_MAX ||
			tdc_raster_pixel_bytes(pixtype) == 0 || hasnodata > 1)
			tdc_agg_state_corrupt(INTERP_NAME, "bad template");
		st->band = i4[0];
		st->tmpl.srid = i4[1];
		st->tmpl.width = (uint16) wh[0];
		st->tmpl.height = (uint16) wh[1];
		st->tmpl.nbands = (uint16) Min(st->band, PG_UINT16_MAX);
		st->tmpl.band = st->band;
		st->tmpl.b.pixtype = pixtype;
		st->tmpl.b.hasnodata = hasnodata == 1;
		st->method = pnstrdup(extra + INTERP_FIXED, mlen);
		if (strlen(st->method) != mlen)
			tdc_agg_state_corrupt(INTERP_NAME, "a NUL in the method");
		tdc_raster_method(st->method, &spec, INTERP_NAME);
		tdc_tin_agg_breaklines(&st->s, spec.breaklines, CurrentMemoryContext, INTERP_NAME);
	}
	return INTERP_FIXED + mlen;
}

static const TdcTinAggKind interp_kind = {
	&interp_format, sizeof(InterpState), TDC_CURVES_VERTICES,
	INTERP_FIXED, 8, interp_combine_params, interp_var_len, interp_write, interp_read
};

/* st_tdcinterpolate_combinefn, _serialfn and _deserialfn */
TDC_TIN_AGG_SUPPORT(st_tdcinterpolate, interp_kind);

PG_FUNCTION_INFO_V1(st_tdcinterpolate_finalfn);

Datum
st_tdcinterpolate_finalfn(PG_FUNCTION_ARGS)
{
	InterpState *st;

	tdc_signal_guard();
	(void) tdc_agg_context(fcinfo, "st_tdcinterpolate_finalfn");
	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (InterpState *) PG_GETARG_POINTER(0);
	if (!st->s.params_set || st->s.base->pts.n == 0)
		PG_RETURN_NULL();
	PG_RETURN_POINTER(tdc_raster_interpolate(&st->s.base->pts, st->s.breaklines ? &st->s.segs : NULL,
											 &st->tmpl, st->method, INTERP_NAME));
}
