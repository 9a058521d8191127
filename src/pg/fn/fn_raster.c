/*
 * fn_raster.c
 *		ST_TDCInterpolateRaster, and the interpolation into a raster that
 *		it and the ST_TDCInterpolate aggregates share (tdc_raster_interpolate).
 *		SQL objects: the tdc_delaunay_raster extension (src/sql/raster.sql).
 *
 * A drop-in for PostGIS's ST_InterpolateRaster(input_points, method,
 * template, band), which runs GDAL's gridding: the Z of the input's
 * vertices (as stored: a curve's control points, as PostGIS's point
 * iterator gives them to GDAL) interpolated at the pixel centres of the
 * template's grid, into a one-band raster with the template's size,
 * geotransform and SRID and the pixel type of its band.  Here the samples
 * are triangulated exactly, the TIN is built and the values come from the
 * core's grid operation (tdc_tin_grid_start) on the worker threads, under
 * the usual cancel and tdc_delaunay.max_memory rules (tin_run.c).  method
 * is GDAL's text ('linear', 'nearest', 'natural_neighbor', with options
 * such as ':radius=0:nodata=-9999', parsed by tdc_interp_parse); unknown
 * methods and options are ERRORs (PostGIS passes GDAL's other algorithms
 * on).  One option is not GDAL's: 'linear:breaklines=true' takes the
 * input's linestrings and polygon rings as hard breaklines, inserted into
 * the triangulation as ST_TDCConstrainedDelaunay inserts its lines, so the
 * surface follows ridges and streams (crossing lines are an ERROR, curves
 * refused); nearest and natural_neighbor refuse it (tdc_interp_parse).
 * Another, ':max_edge=L' with any method, drops the triangles with an edge
 * longer than L (tdc.h): their pixels are empty, a lake or a roof with no
 * sample stays a hole.
 *
 * The result band.  Its pixel type is the template band's; values are
 * stored as PostGIS's own raster functions store them (raster_write.c:
 * clamped, integers truncated).  It always has a nodata value, which
 * pixels without a value get (outside the hull beyond the method's radius,
 * or in a triangle max_edge drops):
 *	1. the method's nodata option, when the text gives one;
 *	2. else the template band's nodata value, when it has one;
 *	3. else the method's default nodata, GDAL's 0.
 * So with a template band that has a nodata value the empty pixels read as
 * NULL, and with none they hold 0 as with ST_InterpolateRaster, but read as
 * NULL here too (a true 0 in such a band also does: give the template a
 * nodata value, or the method a nodata option, to keep it).  PostGIS
 * writes GDAL's nodata option into the pixels and keeps the template
 * band's flag, so its empty pixels read as NULL only when the two agree.
 * A 64BF band is written in place: the grid operation writes its doubles
 * straight into the result value.
 *
 * Differences from ST_InterpolateRaster beyond the methods: a skewed
 * template is fine (PostGIS refuses it: GDAL's gridding knows no skew);
 * the template band must be stored in the database (raster_read.c);
 * pixel centres are gt[0] + (col + 0.5) gt[1] + (row + 0.5) gt[2], and
 * GDAL's are the extent's minimum plus (col + 0.5) times its width over
 * the column count, which may differ in the last bits; integer pixel types
 * are truncated (PostGIS's rule) where GDAL rounds to nearest.  NULL
 * arguments give NULL (STRICT) and an EMPTY input too, as PostGIS; a
 * non-empty input without Z is an ERROR.  The input's SRID is not compared
 * with the template's, as in PostGIS.
 */
#include "postgres.h"

#include "fmgr.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "formats/raster_format.h"
#include "fn_raster.h"

#define INTERPOLATE_RASTER_NAME	"ST_TDCInterpolateRaster"

/* Does the method's text give a nodata option ("...:nodata=V...")? */
bool
tdc_raster_method_sets_nodata(const char *method)
{
	for (const char *p = strchr(method, ':'); p != NULL; p = strchr(p + 1, ':'))
		if (pg_strncasecmp(p + 1, "nodata=", 7) == 0)
			return true;
	return false;
}

/* The method, parsed: an ERROR for an unknown one or a bad option. */
void
tdc_raster_method(const char *method, tdc_interp_spec *spec, const char *fname)
{
	char		err[256];

	err[0] = '\0';
	if (tdc_interp_parse(method, spec, err, sizeof(err)) != TDC_OK)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid method \"%s\"", fname, method),
				 err[0] ? errdetail("%s.", err) : 0,
				 errhint("Use GDAL's syntax: 'linear', 'nearest' or 'natural_neighbor', "
						 "with options such as 'linear:radius=0:nodata=-9999' or 'linear:max_edge=50'.")));
}

/*
 * The samples in pts interpolated by method at the pixel centres of the
 * template's grid, as a one-band raster of the template band's pixel type
 * (see the top of the file).  pts holds at least one sample, with Z;
 * breaklines their linework's segments, inserted when the method asks for
 * them (tdc_raster_breaklines).
 */
struct varlena *
tdc_raster_interpolate(const TdcPointBuf *pts, const TdcSegList *breaklines,
					   const TdcRasterInfo *tmpl, const char *method, const char *fname)
{
	tdc_interp_spec spec;
	tdc_grid_spec grid;
	TdcRasterWriter w;
	TdcTinRun  *tr;
	int			pt = tmpl->b.pixtype;
	Size		n = (Size) tmpl->width * tmpl->height;
	uint64		out_bytes = tdc_raster_value_size(tmpl->width, tmpl->height, pt);
	uint64		values_bytes = pt == RT_PT_64BF ? 0 : (uint64) n * sizeof(double);
	double		nodata;
	double	   *values;
	uint8	   *valid;
	char		err[256];
	int			rc;

	tdc_raster_method(method, &spec, fname);
	if (tdc_raster_method_sets_nodata(method) || !tmpl->b.hasnodata)
		nodata = spec.nodata;
	else
		nodata = tmpl->b.nodata;
	if (out_bytes > (uint64) tdc_guc_max_result_bytes)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: a %u x %u raster of %s pixels takes %llu bytes, more than the limit of %d bytes for a single value",
						fname, tmpl->width, tmpl->height, tdc_raster_pixtype_name(pt),
						(unsigned long long) out_bytes, tdc_guc_max_result_bytes),
				 errhint("Interpolate into tiles of the raster, e.g. the tiles of ST_Tile(template, 1, 1000, 1000).")));

	/* the result, its values and their mask: counted with the TIN */
	tr = tdc_tin_run_start(pts, spec.breaklines ? breaklines : NULL,
						   out_bytes + values_bytes + n, fname);
	tdc_raster_alloc(tmpl, pt, nodata, fname, &w);
	/* the empty pixels get the band's nodata value as stored */
	spec.nodata = w.nodata;
	values = pt == RT_PT_64BF ? (double *) w.pixels :
		palloc_extended(Max(values_bytes, 1), MCXT_ALLOC_HUGE);
	valid = palloc_extended(Max(n, 1), MCXT_ALLOC_HUGE);
	if (n > 0)
	{
		memcpy(grid.gt, tmpl->gt, sizeof(grid.gt));
		grid.width = tmpl->width;
		grid.height = tmpl->height;
		err[0] = '\0';
		rc = tdc_tin_grid_start(tr->tin, &spec, &grid, values, valid, err, sizeof(err));
		tdc_tin_run_wait(tr, rc, err, fname);
	}
	tdc_tin_run_free(tr);
	tdc_raster_fill(&w, values, valid);
	if ((Pointer) values != w.pixels)
		pfree(values);
	pfree(valid);
	return w.value;
}

/*
 * Does the method ask for breaklines?  Then the samples' linework is
 * reported into l as they are read into pts, and curves are refused, as by
 * the constrained functions (a curve's stored vertices are control points,
 * whose segments are no line of the surface).
 */
bool
tdc_raster_breaklines(const tdc_interp_spec *spec, TdcSegList *l, MemoryContext cxt,
					  TdcPointBuf *pts, const char *fname)
{
	if (!spec->breaklines)
		return false;
	tdc_seg_init(l, cxt, pts, fname);
	pts->curves = TDC_CURVES_REFUSE;
	return true;
}

PG_FUNCTION_INFO_V1(st_tdcinterpolateraster);

/*
 * ST_TDCInterpolateRaster(input_points geometry, method text,
 *						   template raster, template_band_num int4 DEFAULT 1)
 */
Datum
st_tdcinterpolateraster(PG_FUNCTION_ARGS)
{
	char	   *method;
	TdcRasterInfo tmpl;
	TdcPointBuf pts;
	TdcSegList	segs;
	tdc_interp_spec spec;

	tdc_signal_guard();
	method = text_to_cstring(PG_GETARG_TEXT_PP(1));
	/* as ST_InterpolateRaster: the arguments first, then the samples */
	tdc_raster_method(method, &spec, INTERPOLATE_RASTER_NAME);
	tdc_raster_read(PG_GETARG_DATUM(2), PG_GETARG_INT32(3), &tmpl, INTERPOLATE_RASTER_NAME);

	tdc_pointbuf_init(&pts, CurrentMemoryContext);
	pts.curves = TDC_CURVES_VERTICES;
	(void) tdc_raster_breaklines(&spec, &segs, CurrentMemoryContext, &pts, INTERPOLATE_RASTER_NAME);
	(void) tdc_read_geometry(&pts, PG_GETARG_DATUM(0), INTERPOLATE_RASTER_NAME);
	if (spec.breaklines)
		tdc_seg_flush(&segs);
	if (pts.n == 0)
		PG_RETURN_NULL();
	if (!pts.hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: input_points has no Z coordinate", INTERPOLATE_RASTER_NAME),
				 errhint("Every sample needs a height: make the samples XYZ, with ST_MakePoint(x, y, z) or "
						 "ST_Force3DZ(geom, z).")));
	PG_RETURN_POINTER(tdc_raster_interpolate(&pts, &segs, &tmpl, method, INTERPOLATE_RASTER_NAME));
}
