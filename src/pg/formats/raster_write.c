/*
 * raster_write.c
 *		Writing a one-band PostGIS raster value (raster_format.h) from
 *		doubles and a validity mask, with a template's geometry, converting
 *		every value to the band's pixel type exactly as PostGIS's own raster
 *		functions store a value.
 *
 * The value is written directly, as gser_write.c writes geometries: one
 * palloc of the final size (tdc_raster_value_size), the header and the
 * band's header first (tdc_raster_alloc), then the pixels (tdc_raster_fill).
 * Building it through PostGIS's SQL (ST_MakeEmptyRaster, ST_AddBand,
 * ST_SetValues) would cost a round of SQL and a copy of every pixel, and
 * PostGIS's C library is not ours to link: postgis_raster is a separate
 * extension, and tdc_delaunay must load without it.
 *
 * Conversion.  A value goes into a pixel as PostGIS's rt_band_set_pixel
 * puts it there (ST_SetValue, ST_SetValues, ST_MapAlgebra; the facts are
 * those of rt_pixel.c, rt_band.c and rt_util.c, identical from PostGIS 3.3
 * to 3.7):
 *	- clamped to the type's range with fmin/fmax (so NaN becomes the
 *	  type's lowest value for the integer types), then converted by a C
 *	  cast: the integer types TRUNCATE toward zero (2.9 -> 2, -2.9 -> -2);
 *	  32BF rounds to the nearest float, with NaN kept; 16BF clamps to
 *	  +-65504 as a float, then rounds that float to a half, nearest with
 *	  ties away from zero, as PostGIS's rt_util_float_to_float16 does (its
 *	  one slip, a rounding carry OR-ed instead of added into an odd
 *	  exponent, which halves e.g. 2047.9 to 1024, is not copied: the carry
 *	  goes into the exponent);
 *	- a value that is not the nodata value (as PostGIS's FLT_EQ: not within
 *	  FLT_EPSILON of it) but that the conversion would turn into it is first
 *	  moved away (rt_band_corrected_clamped_value): 1BB takes the other bit;
 *	  the integer types add 1 if the value converts to the type's lowest,
 *	  else subtract 1 (and convert again, so that -3 in an 8BUI band whose
 *	  nodata is 0 still lands on 0: PostGIS does the same); 16BF and 32BF
 *	  add or subtract FLT_EPSILON the same way (which does not move a float
 *	  of magnitude over 1, so there too PostGIS's result is kept); 64BF is
 *	  never moved;
 *	- a pixel whose mask is off gets the nodata value.
 * The nodata value itself is converted as rt_band_set_nodata converts it
 * (clamped and cast, a 16BF one through a half and back), and the band is
 * marked HASNODATA always; and ISNODATA when no pixel holds a value that
 * PostGIS does not take for nodata (rt_band_clamped_value_is_nodata: within
 * FLT_EPSILON of it, or converting to it; for 64BF too), as ST_AddBand
 * marks a band whose initial value is its nodata value and
 * rt_band_set_pixel leaves the mark until a pixel gets another value.  Which
 * nodata value a result band gets is its caller's choice (the template
 * band's, or another when the template has none; see fn_raster.c).
 *
 * Both conversions are exposed for one value (tdc_raster_pixel_value,
 * tdc_raster_nodata_value: the stored value, widened back to double) for
 * the fuzz target, which checks the written bytes against them and them
 * against PostGIS's facts.
 *
 * A 64BF band's pixels are written in place: tdc_raster_fill may be given
 * the pixel array itself as "values" (a 64BF value's pixels start at byte
 * 80, aligned for doubles), so an interpolation can write its doubles
 * straight into the result and only the masked-off pixels are rewritten.
 * The fill checks for interrupts between rows, a few ms apart at most.
 */
#include "postgres.h"

#include <float.h>
#include <math.h>

#include "miscadmin.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "raster_format.h"

/* Pixels converted between two interrupt checks (whole rows). */
#define FILL_POLL_PIXELS	((Size) 1 << 18)

/* PostGIS's FLT_EQ, in double and in float. */
static inline bool
flt_eq(double x, double y)
{
	return x == y || (isnan(x) && isnan(y)) || fabs(x - y) <= FLT_EPSILON;
}

static inline bool
flt_eqf(float x, float y)
{
	return x == y || (isnan(x) && isnan(y)) || fabs(x - y) <= FLT_EPSILON;
}

/* The range of the integer types (PostGIS's rt_util_clamp_to_*). */
static void
int_range(int pixtype, double *lo, double *hi)
{
	static const double ranges[][2] = {
		[RT_PT_1BB] = {0, RT_1BB_MAX},
		[RT_PT_2BUI] = {0, RT_2BUI_MAX},
		[RT_PT_4BUI] = {0, RT_4BUI_MAX},
		[RT_PT_8BSI] = {-128, 127},
		[RT_PT_8BUI] = {0, 255},
		[RT_PT_16BSI] = {-32768, 32767},
		[RT_PT_16BUI] = {0, 65535},
		[RT_PT_32BSI] = {-2147483648.0, 2147483647.0},
		[RT_PT_32BUI] = {0, 4294967295.0},
	};

	*lo = ranges[pixtype][0];
	*hi = ranges[pixtype][1];
}

static inline bool
is_int_type(int pixtype)
{
	return pixtype <= RT_PT_32BUI;
}

/* An integer type's conversion: clamp, then truncate (the C cast). */
static inline double
to_int(int pixtype, double v)
{
	double		lo,
				hi;

	int_range(pixtype, &lo, &hi);
	/* + 0.0: a pixel holds no -0 */
	return trunc(fmin(fmax(v, lo), hi)) + 0.0;
}

/* rt_util_clamp_to_32F and rt_util_clamp_to_16F: a float, NaN kept. */
static inline float
to_f32(double v)
{
	return isnan(v) ? (float) v : (float) fmin(fmax(v, -FLT_MAX), FLT_MAX);
}

static inline float
to_f16_range(double v)
{
	return isnan(v) ? (float) v : (float) fmin(fmax(v, -RT_16BF_MAX), RT_16BF_MAX);
}

/*
 * A float to a half: round to nearest on the magnitude, ties away from
 * zero (PostGIS adds half a unit of the last place and shifts), the carry
 * of a rounding up going into the exponent.  f is within +-65504 or NaN.
 */
static uint16
half_of(float f)
{
	uint32		u;
	uint32		sign;
	uint32		mant;
	int			e;

	memcpy(&u, &f, sizeof(u));
	sign = (u >> 16) & 0x8000;
	mant = u & 0x7FFFFF;
	e = (int) ((u >> 23) & 0xFF) - 127 + 15;
	if (isnan(f))
		return (uint16) (sign | 0x7E00);
	if (e <= 0)
	{
		/* subnormal half, or zero: PostGIS shifts, then rounds */
		if (e < -10)
			return (uint16) sign;
		mant = (mant | 0x800000) >> (1 - e);
		return (uint16) (sign + ((mant + 0x1000) >> 13));
	}
	/* normal: a carry out of the mantissa adds one to the exponent */
	return (uint16) (sign + (((uint32) e << 10) + ((mant + 0x1000) >> 13)));
}

static double
float_of_half(uint16 h)
{
	int			e = (h >> 10) & 0x1F;
	double		m = h & 0x3FF;

	if (e == 0x1F)
		m = m != 0 ? NAN : INFINITY;
	else if (e == 0)
		m = ldexp(m, -24);
	else
		m = ldexp(m + 1024, e - 25);
	return (h & 0x8000) ? -m : m;
}

/* The stored value of v in the type, no nodata correction, as a double. */
static double
convert(int pixtype, double v)
{
	if (is_int_type(pixtype))
		return to_int(pixtype, v);
	switch (pixtype)
	{
		case RT_PT_16BF:
			return float_of_half(half_of(to_f16_range(v)));
		case RT_PT_32BF:
			return to_f32(v);
	}
	return v;
}

/*
 * The nodata value as a band of the type stores it (rt_band_set_nodata):
 * the conversion above, a 16BF one through a half and back.
 */
double
tdc_raster_nodata_value(int pixtype, double nodata)
{
	return convert(pixtype, nodata);
}

/* rt_pixtype_compare_clamped_values: do v and w convert alike? */
static bool
same_clamped(int pixtype, double v, double w)
{
	if (is_int_type(pixtype))
		return to_int(pixtype, v) == to_int(pixtype, w);
	if (pixtype == RT_PT_16BF)
		return flt_eqf(to_f16_range(v), to_f16_range(w));
	if (pixtype == RT_PT_32BF)
		return flt_eqf(to_f32(v), to_f32(w));
	return flt_eq(v, w);
}

/*
 * rt_band_clamped_value_is_nodata: does PostGIS take v, put into the band,
 * for its nodata value?  Such a pixel reads as nodata (ST_Value gives NULL),
 * and a band whose pixels all are keeps its ISNODATA flag.
 */
static inline bool
takes_nodata(int pixtype, double nodata, double v)
{
	return flt_eq(v, nodata) || same_clamped(pixtype, v, nodata);
}

/*
 * rt_band_corrected_clamped_value: v moved off the nodata value when the
 * conversion would turn it into it.  nodata is as stored.
 */
static double
corrected(int pixtype, double nodata, double v)
{
	if (pixtype == RT_PT_64BF || flt_eq(v, nodata) ||
		!same_clamped(pixtype, v, nodata))
		return v;

	if (pixtype == RT_PT_1BB)
		return nodata == 0 ? 1 : 0;
	if (is_int_type(pixtype))
	{
		double		lo,
					hi;

		int_range(pixtype, &lo, &hi);
		return to_int(pixtype, v) == lo ? v + 1 : v - 1;
	}
	if (pixtype == RT_PT_16BF)
		return flt_eqf(to_f16_range(v), -RT_16BF_MAX) ? v + FLT_EPSILON : v - FLT_EPSILON;
	return flt_eqf(to_f32(v), -FLT_MAX) ? v + FLT_EPSILON : v - FLT_EPSILON;
}

/*
 * The value a pixel of the type holds after v is put into it, in a band
 * whose nodata value is nodata (as stored), widened back to double.
 */
double
tdc_raster_pixel_value(int pixtype, double nodata, double v)
{
	return convert(pixtype, corrected(pixtype, nodata, v));
}

/* Bytes of a one-band in-database raster value of the type. */
uint64
tdc_raster_value_size(uint32 width, uint32 height, int pixtype)
{
	uint64		pb = tdc_raster_pixel_bytes(pixtype);

	return TYPEALIGN64(8, RT_HEADER_BYTES + 2 * pb + (uint64) width * height * pb);
}

static char *
put_u16(char *p, uint16 v)
{
	memcpy(p, &v, sizeof(v));
	return p + sizeof(v);
}

static char *
put_f64(char *p, double v)
{
	memcpy(p, &v, sizeof(v));
	return p + sizeof(v);
}

/* The stored form of a value already converted (convert()) into the type. */
static void
store(char *p, int pixtype, double c)
{
	switch (pixtype)
	{
		case RT_PT_1BB:
		case RT_PT_2BUI:
		case RT_PT_4BUI:
		case RT_PT_8BUI:
			*(uint8 *) p = (uint8) c;
			break;
		case RT_PT_8BSI:
			*(int8 *) p = (int8) c;
			break;
		case RT_PT_16BSI:
			*(int16 *) p = (int16) c;
			break;
		case RT_PT_16BUI:
			*(uint16 *) p = (uint16) c;
			break;
		case RT_PT_32BSI:
			*(int32 *) p = (int32) c;
			break;
		case RT_PT_32BUI:
			*(uint32 *) p = (uint32) c;
			break;
		case RT_PT_16BF:
			*(uint16 *) p = half_of((float) c);
			break;
		case RT_PT_32BF:
			*(float *) p = (float) c;
			break;
		case RT_PT_64BF:
			*(double *) p = c;
			break;
	}
}

/*
 * Allocate a one-band raster value with the geometry of "geom" (size,
 * geotransform, SRID), a band of the pixel type with the nodata value
 * (converted to the type), and write its headers; the pixels are left to
 * tdc_raster_fill.
 */
void
tdc_raster_alloc(const TdcRasterInfo *geom, int pixtype, double nodata,
				 const char *fname, TdcRasterWriter *w)
{
	uint64		size = tdc_raster_value_size(geom->width, geom->height, pixtype);
	int			pb = tdc_raster_pixel_bytes(pixtype);
	char	   *out;
	char	   *p;

	if (pb == 0)
		elog(ERROR, "%s: no pixel type %d", fname, pixtype);
	if (size > MaxAllocSize)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: a %u x %u raster of %s pixels takes %llu bytes, more than the 1 GB a value can hold",
						fname, geom->width, geom->height,
						tdc_raster_pixtype_name(pixtype),
						(unsigned long long) size)));

	out = palloc((Size) size);
	SET_VARSIZE(out, size);
	p = out + RT_OFF_VERSION;
	p = put_u16(p, RT_FORMAT_VERSION);
	p = put_u16(p, 1);
	p = put_f64(p, geom->gt[1]);	/* scale x */
	p = put_f64(p, geom->gt[5]);	/* scale y */
	p = put_f64(p, geom->gt[0]);	/* insertion point */
	p = put_f64(p, geom->gt[3]);
	p = put_f64(p, geom->gt[2]);	/* skew x */
	p = put_f64(p, geom->gt[4]);	/* skew y */
	memcpy(p, &geom->srid, sizeof(int32));
	p = put_u16(p + sizeof(int32), geom->width);
	p = put_u16(p, geom->height);
	Assert(p == out + RT_HEADER_BYTES);

	/* the band: type and flags, padding, nodata; ISNODATA is the fill's */
	memset(p, 0, pb);
	*p = (char) (pixtype | RT_BAND_HASNODATA);
	w->nodata = tdc_raster_nodata_value(pixtype, nodata);
	store(p + pb, pixtype, w->nodata);
	w->pixels = p + 2 * pb;
	w->npixels = (Size) geom->width * geom->height;
	/* the padding after the pixels */
	memset(w->pixels + w->npixels * pb, 0,
		   (Size) size - (RT_HEADER_BYTES + 2 * pb + w->npixels * pb));

	w->value = (struct varlena *) out;
	w->pixtype = pixtype;
	w->width = geom->width;
}

/*
 * Fill the pixels: values[i] converted where valid[i] (valid NULL: all),
 * the nodata value elsewhere.  For a 64BF band values may be w->pixels.
 */
void
tdc_raster_fill(TdcRasterWriter *w, const double *values, const uint8 *valid)
{
	int			pt = w->pixtype;
	int			pb = tdc_raster_pixel_bytes(pt);
	double		nodata = w->nodata;
	Size		rows = Max(1, FILL_POLL_PIXELS / Max(w->width, 1));
	Size		step = rows * Max(w->width, 1);
	bool		any = false;

	Assert(values != (const double *) w->pixels || pt == RT_PT_64BF);
	for (Size first = 0; first < w->npixels; first += step)
	{
		Size		last = Min(first + step, w->npixels);

		CHECK_FOR_INTERRUPTS();
		if (pt == RT_PT_64BF)
		{
			double	   *px = (double *) w->pixels;

			/* 64BF: no conversion, no correction; memmove allows in place */
			if (values != px)
				memmove(px + first, values + first, (last - first) * sizeof(double));
			for (Size i = first; i < last; i++)
			{
				if (valid != NULL && !valid[i])
					px[i] = nodata;
				else if (!any && !takes_nodata(pt, nodata, px[i]))
					any = true;
			}
			continue;
		}
		for (Size i = first; i < last; i++)
		{
			double		c = nodata;

			if (valid == NULL || valid[i])
			{
				double		v = corrected(pt, nodata, values[i]);

				c = convert(pt, v);
				if (!any && !takes_nodata(pt, nodata, v))
					any = true;
			}
			store(w->pixels + i * pb, pt, c);
		}
	}
	if (!any && w->npixels > 0)
		w->pixels[-2 * pb] |= RT_BAND_ISNODATA;
}
