/*
 * fuzz_raster.c
 *		libFuzzer target for the PostGIS raster reader and writer of
 *		tdc_delaunay (src/pg/formats/raster_read.c, raster_write.c), linked with the
 *		PostgreSQL shims of pg_shim.c.
 *
 * Input: byte 0 picks the mode (bit 0).
 *
 * Read mode (bit 0 clear): byte 1 is the band number (byte % 8 - 1, so -1
 * to 6), the rest a raster value without its 4-byte varlena header; the
 * harness puts it into an exactly sized malloc'd varlena so that
 * AddressSanitizer sees any read beyond it.  Checks:
 *	- tdc_raster_read (a prefix at a time, through the shim's
 *	  pg_detoast_datum_slice) either fills the band's description or raises
 *	  an ERROR; never a crash or a read outside the slices;
 *	- tdc_raster_parse given the whole value says the same (same fields,
 *	  or the same SQLSTATE and message);
 *	- differential: an independent reader below (ref_read) accepts exactly
 *	  the same values, with the same SQLSTATE class when it refuses (band
 *	  number, out-of-database band, corrupt value) and the same fields
 *	  when it accepts.
 *
 * Write mode (bit 0 set): byte 1 pixel type (% 12), bytes 2, 3 width and
 * height (% 33), byte 4 options (bit 0: a 64BF band filled in place; bit 1:
 * no mask; bit 2: a raw geotransform), then the nodata value, an SRID, the
 * geotransform and the pixels (a value and a mask bit each).  A value is
 * one byte, an index into a list of values around every type's limits, or
 * 0xFF and 8 raw bytes.  Checks:
 *	- the value has PostGIS's size for one in-database band (header, type
 *	  byte and padding, nodata, pixels, zeros to a multiple of 8);
 *	- its header holds the geometry bit for bit, the band byte the type,
 *	  HASNODATA, and ISNODATA exactly when no pixel holds a value that
 *	  PostGIS does not take for nodata (rt_band_clamped_value_is_nodata);
 *	- the nodata value and every pixel are, byte for byte, what a second
 *	  model of PostGIS's rt_band_set_nodata and rt_band_set_pixel below
 *	  (ref_set_pixel: written after PostGIS's own code paths, C casts and
 *	  all, where raster_write.c uses trunc; a half conversion by a different
 *	  route) stores, and tdc_raster_pixel_value agrees;
 *	- tdc_raster_read reads the value back with the same geometry, type
 *	  and nodata.
 *
 * Before the first input, known answers (check_known): values at every
 * type's limits whose stored value follows from PostGIS's code by hand,
 * among them the nodata correction's surprises.  The pg_regress test
 * tdc_raster checks the same conversions against PostGIS itself.
 */
#include "postgres.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "pg_shim.h"
#include "tdc_pg.h"
#include "formats/raster_format.h"

static void
fail(const char *what, const char *detail)
{
	fprintf(stderr, "fuzz_raster: %s%s%s\n", what, detail ? ": " : "",
			detail ? detail : "");
	abort();
}

/* ----------------------------------------------------------------
 *		independent reference reader
 * ----------------------------------------------------------------
 */

typedef enum RefVerdict
{
	REF_OK,
	REF_BAD_BAND,				/* ERRCODE_INVALID_PARAMETER_VALUE */
	REF_OFFDB,					/* ERRCODE_FEATURE_NOT_SUPPORTED */
	REF_CORRUPT					/* ERRCODE_DATA_CORRUPTED */
} RefVerdict;

static size_t
ref_pixbytes(int t)
{
	switch (t)
	{
		case 0: case 1: case 2: case 3: case 4:
			return 1;
		case 5: case 6: case 9:
			return 2;
		case 7: case 8: case 10:
			return 4;
		case 11:
			return 8;
	}
	return 0;
}

static double
ref_half_to_double(uint16 h)
{
	int			e = (h >> 10) & 31;
	int			m = h & 1023;
	double		v;

	if (e == 31)
		v = m ? NAN : INFINITY;
	else if (e == 0)
		v = m * pow(2, -24);
	else
		v = (1 + m / 1024.0) * pow(2, e - 15);
	return (h & 0x8000) ? -v : v;
}

/* the nodata value at p as PostGIS's rt_raster_deserialize reads it */
static double
ref_nodata(const uint8 *p, int t)
{
	int16		s16;
	uint16		u16;
	int32		s32;
	uint32		u32;
	float		f;
	double		d;

	switch (t)
	{
		case 0: return p[0] & 1;
		case 1: return p[0] & 3;
		case 2: return p[0] & 15;
		case 3: return (int8) p[0];
		case 4: return p[0];
		case 5: memcpy(&s16, p, 2); return s16;
		case 6: memcpy(&u16, p, 2); return u16;
		case 7: memcpy(&s32, p, 4); return s32;
		case 8: memcpy(&u32, p, 4); return u32;
		case 9: memcpy(&u16, p, 2); return ref_half_to_double(u16);
		case 10: memcpy(&f, p, 4); return f;
		default: memcpy(&d, p, 8); return d;
	}
}

static RefVerdict
ref_read(const uint8 *v, size_t size, int band, TdcRasterInfo *r)
{
	uint16		version,
				nbands,
				w,
				h;
	size_t		off = 64;

	if (size < 64)
		return REF_CORRUPT;
	memcpy(&version, v + 4, 2);
	memcpy(&nbands, v + 6, 2);
	memcpy(&w, v + 60, 2);
	memcpy(&h, v + 62, 2);
	if (version != 0)
		return REF_CORRUPT;
	if (band < 1 || band > nbands)
		return REF_BAD_BAND;
	memcpy(&r->gt[1], v + 8, 8);
	memcpy(&r->gt[5], v + 16, 8);
	memcpy(&r->gt[0], v + 24, 8);
	memcpy(&r->gt[3], v + 32, 8);
	memcpy(&r->gt[2], v + 40, 8);
	memcpy(&r->gt[4], v + 48, 8);
	memcpy(&r->srid, v + 56, 4);
	r->width = w;
	r->height = h;
	r->nbands = nbands;
	for (int k = 1; k <= band; k++)
	{
		uint8		b;
		size_t		pb;
		size_t		datasz = (size_t) w * h;

		if (off >= size)
			return REF_CORRUPT;
		b = v[off];
		pb = ref_pixbytes(b & 15);
		if (pb == 0 || off + 2 * pb > size)
			return REF_CORRUPT;
		datasz *= pb;
		if (k == band)
		{
			if (b & 0x80)
				return REF_OFFDB;
			if (off + 2 * pb + datasz > size)
				return REF_CORRUPT;
			r->band = band;
			r->b.pixtype = b & 15;
			r->b.hasnodata = (b & 0x40) != 0;
			r->b.isnodata = (b & 0x40) && (b & 0x20);
			r->b.nodata = ref_nodata(v + off + pb, b & 15);
			return REF_OK;
		}
		if (b & 0x80)
		{
			size_t		path = off + 2 * pb + 1;
			const uint8 *nul;

			if (path >= size)
				return REF_CORRUPT;
			nul = memchr(v + path, 0, size - path);
			if (nul == NULL)
				return REF_CORRUPT;
			off = (size_t) (nul - v) + 1;
		}
		else
		{
			if (off + 2 * pb + datasz > size)
				return REF_CORRUPT;
			off += 2 * pb + datasz;
		}
		off = (off + 7) / 8 * 8;
	}
	return REF_CORRUPT;			/* not reached */
}

/* ----------------------------------------------------------------
 *		second model of PostGIS's pixel and nodata conversions
 * ----------------------------------------------------------------
 */

#define REF_FLT_EQ(x, y) ((x == y) || (isnan(x) && isnan(y)) || (fabs(x - y) <= FLT_EPSILON))

static uint8 c1BB(double v) { return (uint8) fmin(fmax(v, 0), 1); }
static uint8 c2BUI(double v) { return (uint8) fmin(fmax(v, 0), 3); }
static uint8 c4BUI(double v) { return (uint8) fmin(fmax(v, 0), 15); }
static int8 c8BSI(double v) { return (int8) fmin(fmax(v, SCHAR_MIN), SCHAR_MAX); }
static uint8 c8BUI(double v) { return (uint8) fmin(fmax(v, 0), UCHAR_MAX); }
static int16 c16BSI(double v) { return (int16) fmin(fmax(v, SHRT_MIN), SHRT_MAX); }
static uint16 c16BUI(double v) { return (uint16) fmin(fmax(v, 0), USHRT_MAX); }
static int32 c32BSI(double v) { return (int32) fmin(fmax(v, INT_MIN), INT_MAX); }
static uint32 c32BUI(double v) { return (uint32) fmin(fmax(v, 0), UINT_MAX); }
static float c32F(double v) { return isnan(v) ? (float) v : (float) fmin(fmax(v, -FLT_MAX), FLT_MAX); }
static float c16F(double v) { return isnan(v) ? (float) v : (float) fmin(fmax(v, -65504.0F), 65504.0F); }

/*
 * A float (within +-65504, or NaN) to half bits: the magnitude divided by
 * the half's unit in the last place at its binade, rounded half up.
 */
static uint16
ref_half(float f)
{
	double		a = fabs((double) f);
	uint16		sign = signbit(f) ? 0x8000 : 0;
	int			e;
	double		ulp,
				q;

	if (isnan(f))
		return sign | 0x7E00;
	if (a == 0)
		return sign;
	frexp(a, &e);				/* a in [2^(e-1), 2^e) */
	ulp = ldexp(1, Max(e - 1 - 10, -24));
	q = floor(a / ulp + 0.5);	/* exact: a / ulp has at most 24 + 10 bits */
	a = q * ulp;
	if (a < ldexp(1, -14))
		return sign | (uint16) q;	/* subnormal (or the smallest normal) */
	frexp(a, &e);
	return sign | (uint16) ((e - 1 + 15) << 10) | (uint16) (ldexp(a, -(e - 1)) * 1024 - 1024);
}

static double
ref_min(int t)
{
	switch (t)
	{
		case 0: return c1BB(CHAR_MIN);
		case 3: return c8BSI(SCHAR_MIN);
		case 5: return c16BSI(SHRT_MIN);
		case 7: return c32BSI(INT_MIN);
		case 9: return -65504.0F;
		case 10: return -FLT_MAX;
		case 11: return -DBL_MAX;
	}
	return 0;
}

/* rt_pixtype_compare_clamped_values */
static bool
ref_clamped_equal(int t, double a, double b)
{
	switch (t)
	{
		case 0: return c1BB(a) == c1BB(b);
		case 1: return c2BUI(a) == c2BUI(b);
		case 2: return c4BUI(a) == c4BUI(b);
		case 3: return c8BSI(a) == c8BSI(b);
		case 4: return c8BUI(a) == c8BUI(b);
		case 5: return c16BSI(a) == c16BSI(b);
		case 6: return c16BUI(a) == c16BUI(b);
		case 7: return c32BSI(a) == c32BSI(b);
		case 8: return c32BUI(a) == c32BUI(b);
		case 9:
			{
				float		x = c16F(a),
							y = c16F(b);

				return REF_FLT_EQ(x, y);
			}
		case 10:
			{
				float		x = c32F(a),
							y = c32F(b);

				return REF_FLT_EQ(x, y);
			}
	}
	return REF_FLT_EQ(a, b);
}

/* the bytes rt_band_set_pixel's switch stores for val */
static void
ref_store(int t, double val, uint8 *p)
{
	switch (t)
	{
		case 0: p[0] = c1BB(val); break;
		case 1: p[0] = c2BUI(val); break;
		case 2: p[0] = c4BUI(val); break;
		case 3: p[0] = (uint8) c8BSI(val); break;
		case 4: p[0] = c8BUI(val); break;
		case 5: { int16 x = c16BSI(val); memcpy(p, &x, 2); break; }
		case 6: { uint16 x = c16BUI(val); memcpy(p, &x, 2); break; }
		case 7: { int32 x = c32BSI(val); memcpy(p, &x, 4); break; }
		case 8: { uint32 x = c32BUI(val); memcpy(p, &x, 4); break; }
		case 9: { uint16 x = ref_half(c16F(val)); memcpy(p, &x, 2); break; }
		case 10: { float x = c32F(val); memcpy(p, &x, 4); break; }
		default: memcpy(p, &val, 8); break;
	}
}

/* rt_band_set_nodata: the band's nodata value after setting nd */
static double
ref_set_nodata(int t, double nd)
{
	uint8		b[8];

	ref_store(t, nd, b);
	return ref_nodata(b, t);
}

/*
 * rt_band_set_pixel in a band with nodata value nodataval (as stored); the
 * value after the nodata correction in *corr (may be NULL)
 */
static void
ref_set_pixel(int t, double nodataval, double val, uint8 *p, double *corr)
{
	if (t != 11)
	{
		/* rt_band_corrected_clamped_value */
		int			isnodata;

		if (REF_FLT_EQ(val, nodataval))
			isnodata = 2;
		else
			isnodata = ref_clamped_equal(t, val, nodataval) ? 1 : 0;
		if (isnodata == 1)
		{
			double		minval = ref_min(t);

			if (t == 0)
				val = !nodataval;
			else if (t == 9 || t == 10)
			{
				if (ref_clamped_equal(t, val, minval))
					val += FLT_EPSILON;
				else
					val -= FLT_EPSILON;
			}
			else if (ref_clamped_equal(t, val, minval))
				val++;
			else
				val--;
		}
	}
	if (corr)
		*corr = val;
	ref_store(t, val, p);
}

/* ----------------------------------------------------------------
 *		known answers
 * ----------------------------------------------------------------
 */

typedef struct Known
{
	int			pixtype;
	double		nodata;
	double		in;
	double		out;			/* the pixel's value as PostGIS stores it */
} Known;

static void
check_known(void)
{
	static const Known k[] = {
		/* truncation toward zero, clamping */
		{RT_PT_8BUI, 200, 1.9, 1}, {RT_PT_8BUI, 200, 255.9, 255},
		{RT_PT_8BUI, 200, 1e9, 255}, {RT_PT_8BUI, 200, -7, 0},
		{RT_PT_8BSI, 100, -2.9, -2}, {RT_PT_8BSI, 100, -1e9, -128},
		{RT_PT_16BSI, 0, 40000, 32767}, {RT_PT_16BUI, 0, 65535.99, 65535},
		{RT_PT_32BSI, 0, -3e9, -2147483648.0}, {RT_PT_32BUI, 0, 5e9, 4294967295.0},
		{RT_PT_1BB, 0, 0.99, 1}, {RT_PT_1BB, 1, 0.99, 0},
		/* 1BB: clamped onto nodata 1, so the other bit */
		{RT_PT_1BB, 1, 7, 0},
		{RT_PT_2BUI, 0, 9, 3}, {RT_PT_4BUI, 0, 15.5, 15},
		/* NaN: the lowest value of an integer type */
		{RT_PT_8BSI, 0, NAN, -128}, {RT_PT_16BUI, 9, NAN, 0},
		/* the nodata correction: moved by one off the nodata value... */
		{RT_PT_8BUI, 0, 0.5, 1}, {RT_PT_8BUI, 255, 255.5, 254},
		{RT_PT_16BSI, 0, -0.5, -1},
		{RT_PT_8BSI, -128, -128.5, -127}, {RT_PT_8BSI, -128, -200, -128},
		/* ...and not far enough: -3 + 1 is still 0 in 8BUI */
		{RT_PT_8BUI, 0, -3, 0}, {RT_PT_8BUI, 255, 1000, 255},
		/* within FLT_EPSILON of nodata: nodata, uncorrected */
		{RT_PT_8BUI, 0, 1e-8, 0},
		/* 32BF: rounding to float, the range, NaN */
		{RT_PT_32BF, -9999, 0.1, (float) 0.1}, {RT_PT_32BF, -9999, 1e39, FLT_MAX},
		{RT_PT_32BF, -9999, -1e39, -FLT_MAX}, {RT_PT_32BF, 0, 5e-8, (float) 5e-8},
		/* a correction of FLT_EPSILON does not move -9999.00001 off -9999 */
		{RT_PT_32BF, -9999, -9999.00001, -9999}, {RT_PT_32BF, 1, 1 + 1.5e-7, 1},
		/* 16BF: rounding, ties away from zero, the range, the carry */
		{RT_PT_16BF, -1, 1.0004882812500, 1.0009765625}, {RT_PT_16BF, -1, 70000, 65504},
		{RT_PT_16BF, -1, 2047.9, 2048}, {RT_PT_16BF, -1, 1e-8, 0},
		{RT_PT_16BF, -1, 3e-8, 5.9604644775390625e-8},
		/* 64BF: as is, never corrected */
		{RT_PT_64BF, 0, 1e-300, 1e-300}, {RT_PT_64BF, 5, 5 + 1e-12, 5 + 1e-12},
	};

	for (size_t i = 0; i < lengthof(k); i++)
	{
		double		nd = tdc_raster_nodata_value(k[i].pixtype, k[i].nodata);
		double		got = tdc_raster_pixel_value(k[i].pixtype, nd, k[i].in);
		uint8		b[8];

		ref_set_pixel(k[i].pixtype, ref_set_nodata(k[i].pixtype, k[i].nodata), k[i].in, b, NULL);
		if (!(got == k[i].out) || !(ref_nodata(b, k[i].pixtype) == k[i].out))
		{
			char		msg[200];

			snprintf(msg, sizeof(msg), "%s nodata %.17g: %.17g gives %.17g, model %.17g, expected %.17g",
					 tdc_raster_pixtype_name(k[i].pixtype), k[i].nodata, k[i].in, got,
					 ref_nodata(b, k[i].pixtype), k[i].out);
			fail("known answer", msg);
		}
	}
}

/* ----------------------------------------------------------------
 *		harness
 * ----------------------------------------------------------------
 */

static bool verbose;

int			LLVMFuzzerInitialize(int *argc, char ***argv);
int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerInitialize(int *argc, char ***argv)
{
	verbose = getenv("FUZZ_VERBOSE") != NULL;
	check_known();
	return 0;
}

static bool
same_double(double a, double b)
{
	return a == b ? signbit(a) == signbit(b) : (isnan(a) && isnan(b));
}

static void
same_info(const TdcRasterInfo *a, const TdcRasterInfo *b, const char *what)
{
	if (a->srid != b->srid || a->width != b->width || a->height != b->height ||
		a->nbands != b->nbands || a->band != b->band ||
		a->b.pixtype != b->b.pixtype || a->b.hasnodata != b->b.hasnodata ||
		a->b.isnodata != b->b.isnodata || !same_double(a->b.nodata, b->b.nodata))
		fail(what, "band or geometry differ");
	if (memcmp(a->gt, b->gt, sizeof(a->gt)) != 0)
		fail(what, "geotransform differs");
}

/* Read band "band" of v; 0 with *info or the SQLSTATE with the message. */
static int
try_read(struct varlena *v, int band, bool whole, TdcRasterInfo *info, char *msg)
{
	sigjmp_buf	jb;
	volatile int rc = 0;

	memset(info, 0, sizeof(*info));
	if (sigsetjmp(jb, 0) == 0)
	{
		fuzz_pg_jmp = &jb;
		if (whole)
		{
			Size		need = tdc_raster_parse(VARDATA(v), VARSIZE(v) - VARHDRSZ,
												VARSIZE(v), band, info, "fuzz");

			if (need != 0)
				fail("parse of the whole value asks for more", NULL);
		}
		else
			tdc_raster_read(PointerGetDatum(v), band, info, "fuzz");
	}
	else
	{
		rc = fuzz_pg_sqlstate;
		strcpy(msg, fuzz_pg_message);
	}
	fuzz_pg_jmp = NULL;
	return rc;
}

static void
read_mode(const uint8 *data, size_t size)
{
	int			band;
	struct varlena *v;
	TdcRasterInfo a,
				b,
				r;
	char		ma[1024] = "",
				mb[1024] = "";
	int			ra,
				rb;
	RefVerdict	ref;
	int			want;

	if (size < 2)
		return;
	band = data[1] % 8 - 1;
	data += 2;
	size -= 2;
	v = malloc(VARHDRSZ + size);
	SET_VARSIZE(v, VARHDRSZ + size);
	memcpy(VARDATA(v), data, size);

	ra = try_read(v, band, false, &a, ma);
	rb = try_read(v, band, true, &b, mb);
	if (ra != rb || strcmp(ma, mb) != 0)
		fail("sliced and whole reads disagree", ma[0] ? ma : mb);
	if (ra == 0)
		same_info(&a, &b, "sliced and whole reads");

	memset(&r, 0, sizeof(r));
	ref = ref_read((const uint8 *) v, VARSIZE(v), band, &r);
	want = ref == REF_OK ? 0 : ref == REF_BAD_BAND ? ERRCODE_INVALID_PARAMETER_VALUE :
		ref == REF_OFFDB ? ERRCODE_FEATURE_NOT_SUPPORTED : ERRCODE_DATA_CORRUPTED;
	if (verbose)
		fprintf(stderr, "band %d, %zu bytes: %s\n", band, size, ra ? ma : "accepted");
	if (ra != want)
		fail("reader and reference disagree", ra ? ma : "accepted");
	if (ra == 0)
		same_info(&a, &r, "reader and reference");
	free(v);
}

/* The fuzzer's bytes as values. */
typedef struct Bytes
{
	const uint8 *p;
	size_t		left;
} Bytes;

static uint8
next_byte(Bytes *b)
{
	if (b->left == 0)
		return 0;
	b->left--;
	return *b->p++;
}

static double
next_value(Bytes *b)
{
	static const double vals[] = {
		0, -0.0, 0.5, -0.5, 1, 1.5, 2.9, -2.9, 3, 3.5, 15, 15.5, 16, -1,
		127, 127.5, 128, -128, -128.5, -129, 255, 255.5, 256, -255,
		32767, 32767.5, 32768, -32768, -32768.5, -32769, 65535, 65535.5, 65536,
		65504, 65519, 65520, 2047.9, 4095.9, 1.00048828125, 6e-8, 3e-8, 1e-8,
		2147483647.0, 2147483647.5, 2147483648.0, -2147483648.0, -2147483648.5,
		-2147483649.0, 4294967295.0, 4294967295.5, 4294967296.0,
		FLT_MAX, -FLT_MAX, 3.5e38, -3.5e38, DBL_MAX, -DBL_MAX, INFINITY, -INFINITY,
		NAN, FLT_EPSILON, -FLT_EPSILON, 1.1e-7, -9999, -9999.00001, -9998.99999,
		1e-40, 1e-300, 0.1, 1e15, -1e15
	};
	uint8		k = next_byte(b);
	double		d = 0;

	if (k != 0xFF)
		return vals[k % lengthof(vals)];
	for (int i = 0; i < 8; i++)
		((uint8 *) &d)[i] = next_byte(b);
	return d;
}

static void
write_mode(const uint8 *data, size_t size)
{
	Bytes		in = {data + 1, size - 1};
	int			pt = next_byte(&in) % RT_PT_COUNT;
	int			pb = tdc_raster_pixel_bytes(pt);
	TdcRasterInfo g,
				back;
	uint8		opt;
	double		nd;
	Size		n;
	double	   *vals;
	uint8	   *valid;
	bool		any = false;
	TdcRasterWriter w;
	sigjmp_buf	jb;
	const uint8 *out;
	uint64		size_want;
	double		nd_stored;
	uint8		expect[8];
	char		msg[1024];

	memset(&g, 0, sizeof(g));
	g.width = next_byte(&in) % 33;
	g.height = next_byte(&in) % 33;
	opt = next_byte(&in);
	nd = next_value(&in);
	for (int i = 0; i < 4; i++)
		((uint8 *) &g.srid)[i] = next_byte(&in);
	for (int i = 0; i < 6; i++)
		g.gt[i] = (opt & 4) ? next_value(&in) : (i == 1 ? 2.5 : i == 5 ? -0.5 : i * 1000.0);
	n = (Size) g.width * g.height;
	vals = malloc(n * sizeof(double) + 1);
	valid = malloc(n + 1);
	for (Size i = 0; i < n; i++)
	{
		vals[i] = next_value(&in);
		valid[i] = (opt & 2) ? 1 : next_byte(&in) & 1;
	}

	if (sigsetjmp(jb, 0) != 0)
		fail("writer raised an ERROR", fuzz_pg_message);
	fuzz_pg_jmp = &jb;
	tdc_raster_alloc(&g, pt, nd, "fuzz", &w);
	if (pt == RT_PT_64BF && (opt & 1))
	{
		/* in place: the doubles written into the value first */
		memcpy(w.pixels, vals, n * sizeof(double));
		tdc_raster_fill(&w, (const double *) w.pixels, (opt & 2) ? NULL : valid);
	}
	else
		tdc_raster_fill(&w, vals, (opt & 2) ? NULL : valid);
	fuzz_pg_jmp = NULL;

	/* size and header */
	out = (const uint8 *) w.value;
	size_want = (64 + 2 * (uint64) pb + n * pb + 7) / 8 * 8;
	if (tdc_raster_value_size(g.width, g.height, pt) != size_want ||
		VARSIZE(w.value) != size_want)
		fail("raster value has the wrong size", NULL);
	{
		TdcRasterInfo h;

		if (ref_read(out, size_want, 1, &h) != REF_OK)
			fail("reference cannot read the written value", NULL);
		h.band = 0;
		g.nbands = 1;
		h.b = g.b;
		same_info(&g, &h, "written header");
	}
	/* ISNODATA: rt_band_set_pixel clears it for a value not taken for nodata */
	nd_stored = ref_set_nodata(pt, nd);
	for (Size i = 0; i < n; i++)
		if (valid[i] || (opt & 2))
		{
			double		v = vals[i];

			ref_set_pixel(pt, nd_stored, v, expect, &v);
			if (!(REF_FLT_EQ(v, nd_stored) || ref_clamped_equal(pt, v, nd_stored)))
				any = true;
		}
	if (out[64] != (pt | 0x40 | (!any && n > 0 ? 0x20 : 0)))
		fail("band byte", NULL);
	for (int i = 1; i < pb; i++)
		if (out[64 + i] != 0)
			fail("band padding not zero", NULL);
	for (uint64 i = 64 + 2 * pb + n * pb; i < size_want; i++)
		if (out[i] != 0)
			fail("trailing padding not zero", NULL);

	/* nodata and pixels against the second model */
	ref_store(pt, nd_stored, expect);
	if (memcmp(out + 64 + pb, expect, pb) != 0)
		fail("nodata bytes", NULL);
	if (!same_double(tdc_raster_nodata_value(pt, nd), nd_stored))
		fail("tdc_raster_nodata_value", NULL);
	for (Size i = 0; i < n; i++)
	{
		const uint8 *px = out + 64 + 2 * pb + i * pb;

		if (valid[i] || (opt & 2))
			ref_set_pixel(pt, nd_stored, vals[i], expect, NULL);
		else
			ref_store(pt, nd_stored, expect);
		if (memcmp(px, expect, pb) != 0)
		{
			snprintf(msg, sizeof(msg), "%s nodata %.17g, value %.17g (valid %d): got %.17g, model %.17g",
					 tdc_raster_pixtype_name(pt), nd, vals[i], valid[i],
					 ref_nodata(px, pt), ref_nodata(expect, pt));
			fail("pixel", msg);
		}
		if ((valid[i] || (opt & 2)) &&
			!same_double(tdc_raster_pixel_value(pt, nd_stored, vals[i]), ref_nodata(expect, pt)))
			fail("tdc_raster_pixel_value", NULL);
	}

	/* read back */
	if (try_read(w.value, 1, false, &back, msg) != 0)
		fail("written value does not read back", msg);
	g.band = 1;
	g.b.pixtype = pt;
	g.b.hasnodata = true;
	g.b.isnodata = !any && n > 0;
	g.b.nodata = nd_stored;
	same_info(&g, &back, "read back");
	free(vals);
	free(valid);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	int			base;

	fuzz_pg_stack_base(&base);
	if (size < 1)
		return 0;
	if (data[0] & 1)
		write_mode(data, size);
	else
		read_mode(data, size);
	fuzz_pg_reset();
	return 0;
}
