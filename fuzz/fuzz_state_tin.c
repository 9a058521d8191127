/*
 * fuzz_state_tin.c
 *		The TIN aggregates' states in fuzz_state: ST_TDCContours ("TCN1",
 *		fn_contours_agg.c), ST_TDCDrape ("TDR1", fn_drape_agg.c) and
 *		ST_TDCInterpolate ("TRI1", fn_raster_agg.c, extension
 *		tdc_delaunay_raster), whose serial, deserial and combine functions
 *		take bytes from parallel workers.
 *
 * fuzz_state.c hands an input here when its first state starts with one of
 * these magic numbers, so the magic is the selector: the input format stays
 * fuzz_state's (uint16 L, a first state of L bytes, the rest a second), the
 * Delaunay seeds keep their meaning, and CI runs one target for
 * FUZZ_SECONDS, not four.  The functions are called through their fmgr
 * entry points, as the executor calls them (pg_shim_agg.c has the few
 * backend pieces they need), so what is fuzzed is the SQL-level code.
 *
 * Each state is checked against a model of its documented format written
 * here from the comments at the top of the three files, independently of
 * their code: the Delaunay vertex part (agg_state.c), then the aggregate's
 * own part (ST_TDCContours's, version 2, ends with the method's max_edge,
 * a finite length or 0), which for ST_TDCDrape and ST_TDCInterpolate (version 2) ends
 * with the breaklines' segments when the method asks for breaklines
 * ('linear:breaklines=true'): pairs of uint32 vertex indices, whole pairs
 * only, both ends below the state's vertex count, and none at all for a
 * method without breaklines.  The checks:
 *
 *	- the deserial function raises an ERROR exactly when the model rejects
 *	  the bytes; the ERROR is "corrupt serialized aggregate state"
 *	  (DATA_CORRUPTED), or an invalid method (INVALID_PARAMETER_VALUE) when
 *	  the method is one the transition function would refuse too;
 *	- an accepted state serializes back to its bytes, up to the fields the
 *	  format ignores (agg_state.c's; and ST_TDCInterpolate's template fields
 *	  other than the geotransform and nodata when no parameters were set);
 *	- combine(NULL, B) is B, or NULL when B has no parameters;
 *	- combine(A, B) of two accepted states either raises INVALID_PARAMETER_
 *	  VALUE where the model sees a conflict (SRID, dimensions, the
 *	  Delaunay part's parameters, the aggregate's parameters), or gives
 *	  A's vertices then B's, the row counts added, the parameters of
 *	  whichever state had them, and with breaklines A's segments then B's
 *	  with their ends shifted by A's vertex count; the result serializes to
 *	  exactly that and deserializes again;
 *	- a state without parameters holds nothing (no vertices, no
 *	  dimensions, no rows): combine skips such a state, so anything in it
 *	  would be lost (the model rejects one that does);
 *	- row counts whose sum overflows int64 are an ERROR (DATA_CORRUPTED),
 *	  not undefined behaviour (UBSan aborts on signed overflow).
 *
 * The model reads the bytes as little-endian, like the machines this runs on.
 */
#include "postgres.h"

#include <math.h>
#include <stdlib.h>
#include <strings.h>

#include "common/int.h"
#include "fmgr.h"

#include "tdc_pg.h"
#include "pg_shim.h"
#include "fuzz_state.h"

extern Datum st_tdccontours_serialfn(PG_FUNCTION_ARGS);
extern Datum st_tdccontours_deserialfn(PG_FUNCTION_ARGS);
extern Datum st_tdccontours_combinefn(PG_FUNCTION_ARGS);
extern Datum st_tdcdrape_serialfn(PG_FUNCTION_ARGS);
extern Datum st_tdcdrape_deserialfn(PG_FUNCTION_ARGS);
extern Datum st_tdcdrape_combinefn(PG_FUNCTION_ARGS);
extern Datum st_tdcinterpolate_serialfn(PG_FUNCTION_ARGS);
extern Datum st_tdcinterpolate_deserialfn(PG_FUNCTION_ARGS);
extern Datum st_tdcinterpolate_combinefn(PG_FUNCTION_ARGS);

#define HDR				40		/* the Delaunay part's header */
#define SB_HAVE_FIRST	0x01
#define SB_HASZ			0x02
#define SB_PARAMS		0x04

/* What the model reads from a state, and why it rejects one. */
#define R_CORRUPT		0x01	/* the format is broken */
#define R_METHOD		0x02	/* a method the transition function refuses */

typedef struct Model
{
	int			reject;			/* R_* bits; 0: accepted */
	/* the vertex part */
	uint32		bits;
	int32		srid;
	int32		flags;
	double		tol;
	uint64		n;
	const uint8 *xy;
	const uint8 *z;
	/* the aggregate's part */
	const uint8 *extra;
	size_t		extra_len;
	size_t		params_len;		/* of extra, before the segments */
	bool		params_set;
	int64		rows;
	bool		breaklines;		/* the method's; only then segments may follow */
	const uint8 *seg;			/* nseg pairs of uint32 vertex indices */
	uint64		nseg;
} Model;

typedef struct TinFormat
{
	uint32		magic;
	uint32		version;
	const char *name;
	PGFunction	serial;
	PGFunction	deserial;
	PGFunction	combine;
	size_t		rows_at;		/* offset of int64 rows in the extra part */
	/* the aggregate's part: sets m->reject, params_set, rows */
	void		(*read_extra) (Model *m);
	/* the aggregate's part as its serial function writes it back */
	void		(*normalize_extra) (const Model *m, uint8 *extra);
	/* same parameters (the combine function's test)? */
	bool		(*same_params) (const Model *a, const Model *b);
} TinFormat;

static uint32
u32_at(const uint8 *p)
{
	uint32		v;

	memcpy(&v, p, 4);
	return v;
}

static uint64
u64_at(const uint8 *p)
{
	uint64		v;

	memcpy(&v, p, 8);
	return v;
}

static double
f64_at(const uint8 *p)
{
	double		v;

	memcpy(&v, p, 8);
	return v;
}

/*
 * A method the transition functions take: tdc_interp_parse's names, with
 * any of its options, or (ST_TDCDrape, !gdal_options) none but breaklines.
 * *breaklines: whether it asks for them.
 */
static bool
method_ok(const uint8 *p, size_t len, bool gdal_options, bool *breaklines)
{
	char		buf[1100];
	char		err[256];
	tdc_interp_spec spec;

	*breaklines = false;
	if (len >= sizeof(buf) || memchr(p, '\0', len) != NULL)
		return false;
	memcpy(buf, p, len);
	buf[len] = '\0';
	if (!gdal_options)
		for (const char *c = strchr(buf, ':'); c != NULL; c = strchr(c + 1, ':'))
			if (strncasecmp(c + 1, "breaklines=", 11) != 0)
				return false;
	if (tdc_interp_parse(buf, &spec, err, sizeof(err)) != TDC_OK)
		return false;
	*breaklines = spec.breaklines;
	return true;
}

/*
 * The rest bytes at p (after the parameters) as segments: none unless the
 * method asks for breaklines, else whole pairs of ends below the vertex
 * count.
 */
static void
read_segments(Model *m, const uint8 *p, size_t rest)
{
	if (rest == 0)
		return;
	if (!m->breaklines || rest % 8 != 0)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	m->seg = p;
	m->nseg = rest / 8;
	for (uint64 i = 0; i < 2 * m->nseg; i++)
		if (u32_at(p + 4 * i) >= m->n)
		{
			m->reject |= R_CORRUPT;
			return;
		}
}

/* ----------------------------------------------------------------
 *		ST_TDCContours (version 2): uint32 params_set, uint32 zero,
 *		float8 interval, float8 base, int64 rows, float8 max_edge
 * ----------------------------------------------------------------
 */
static void
contour_extra(Model *m)
{
	const uint8 *e = m->extra;
	double		interval,
				base,
				max_edge;

	if (m->extra_len != 40)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	m->params_len = 40;
	m->rows = (int64) u64_at(e + 24);
	if (u32_at(e) > 1 || u32_at(e + 4) != 0 || m->rows < 0)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	m->params_set = u32_at(e) == 1;
	interval = f64_at(e + 8);
	base = f64_at(e + 16);
	max_edge = f64_at(e + 32);
	if (m->params_set && (!(interval > 0) || !isfinite(interval) || !isfinite(base)))
		m->reject |= R_CORRUPT;
	/* max_edge: 0 (none) or a finite length */
	if (m->params_set && !(max_edge >= 0 && isfinite(max_edge)))
		m->reject |= R_CORRUPT;
}

static void
contour_normalize(const Model *m, uint8 *extra)
{
}

static bool
contour_same(const Model *a, const Model *b)
{
	/* compared as numbers, as the combine function does */
	return f64_at(a->extra + 8) == f64_at(b->extra + 8) &&
		f64_at(a->extra + 16) == f64_at(b->extra + 16) &&
		f64_at(a->extra + 32) == f64_at(b->extra + 32);
}

/* ----------------------------------------------------------------
 *		ST_TDCDrape: uint32 params_set, uint32 method length, uint64 target
 *		length, int64 rows, the method, the target (a varlena, 4-byte
 *		header), then with breaklines the segments
 * ----------------------------------------------------------------
 */
static void
drape_extra(Model *m)
{
	const uint8 *e = m->extra;
	uint32		ps,
				ml,
				hdr;
	uint64		tl;

	if (m->extra_len < 24)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	ps = u32_at(e);
	ml = u32_at(e + 4);
	tl = u64_at(e + 8);
	m->rows = (int64) u64_at(e + 16);
	if (ps > 1 || m->rows < 0 || ml > 64 || tl > m->extra_len ||
		m->extra_len < 24 + (uint64) ml + tl ||
		(ps == 0 && (ml != 0 || tl != 0)) || (ps == 1 && (ml == 0 || tl < 4)))
	{
		m->reject |= R_CORRUPT;
		return;
	}
	m->params_set = ps == 1;
	m->params_len = 24 + ml + tl;
	if (m->params_set)
	{
		if (memchr(e + 24, '\0', ml) != NULL)
		{
			m->reject |= R_CORRUPT;
			return;
		}
		if (!method_ok(e + 24, ml, false, &m->breaklines))
		{
			/* whether segments may follow is unknown: the method decides */
			m->reject |= R_METHOD;
			return;
		}
		/* a plain 4-byte header (low two bits 00, little-endian) saying tl */
		hdr = u32_at(e + 24 + ml);
		if ((hdr & 3) != 0 || (hdr >> 2) != tl)
			m->reject |= R_CORRUPT;
	}
	read_segments(m, e + m->params_len, m->extra_len - m->params_len);
}

static void
drape_normalize(const Model *m, uint8 *extra)
{
}

static bool
drape_same(const Model *a, const Model *b)
{
	uint32		ml = u32_at(a->extra + 4);
	uint64		tl = u64_at(a->extra + 8);

	return ml == u32_at(b->extra + 4) && tl == u64_at(b->extra + 8) &&
		memcmp(a->extra + 24, b->extra + 24, ml + tl) == 0;
}

/* ----------------------------------------------------------------
 *		ST_TDCInterpolate: uint32 params_set, uint32 method length, int64
 *		rows, int32 band, int32 SRID, uint32 width, uint32 height, float8
 *		geotransform[6], int32 pixel type, uint32 hasnodata, float8
 *		nodata, the method, then with breaklines the segments
 * ----------------------------------------------------------------
 */
static void
interp_extra(Model *m)
{
	const uint8 *e = m->extra;
	uint32		ps,
				ml;
	int32		band,
				pixtype;

	if (m->extra_len < 96)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	ps = u32_at(e);
	ml = u32_at(e + 4);
	m->rows = (int64) u64_at(e + 8);
	if (ps > 1 || m->rows < 0 || ml > 1024 || m->extra_len < 96 + (uint64) ml ||
		(ps == 0 && (ml != 0 || m->extra_len != 96)) || (ps == 1 && ml == 0))
	{
		m->reject |= R_CORRUPT;
		return;
	}
	m->params_set = ps == 1;
	m->params_len = 96 + ml;
	if (!m->params_set)
		return;
	band = (int32) u32_at(e + 16);
	pixtype = (int32) u32_at(e + 80);
	/* PostGIS's pixel types 1BB .. 64BF are 0 .. 11 */
	if (band < 1 || u32_at(e + 24) > 65535 || u32_at(e + 28) > 65535 ||
		pixtype < 0 || pixtype > 11 || u32_at(e + 84) > 1 ||
		memchr(e + 96, '\0', ml) != NULL)
	{
		m->reject |= R_CORRUPT;
		return;
	}
	if (!method_ok(e + 96, ml, true, &m->breaklines))
	{
		m->reject |= R_METHOD;
		return;
	}
	read_segments(m, e + m->params_len, m->extra_len - m->params_len);
}

/* Without parameters only the geotransform and nodata are kept. */
static void
interp_normalize(const Model *m, uint8 *extra)
{
	if (!m->params_set)
	{
		memset(extra + 16, 0, 16);	/* band, SRID, width, height */
		memset(extra + 80, 0, 8);	/* pixel type, hasnodata */
	}
}

static bool
interp_same(const Model *a, const Model *b)
{
	const uint8 *x = a->extra,
			   *y = b->extra;
	uint32		ml = u32_at(x + 4);
	double		nx = f64_at(x + 88),
				ny = f64_at(y + 88);

	/* method, band, SRID, size, geotransform (bytes), pixel type, hasnodata */
	if (ml != u32_at(y + 4) || memcmp(x + 96, y + 96, ml) != 0 ||
		memcmp(x + 16, y + 16, 16) != 0 || memcmp(x + 32, y + 32, 48) != 0 ||
		memcmp(x + 80, y + 80, 8) != 0)
		return false;
	/* nodata only with hasnodata, NaN equal to NaN */
	return u32_at(x + 84) == 0 || nx == ny || (isnan(nx) && isnan(ny));
}

static const TinFormat formats[] = {
	{0x314e4354, 2, "ST_TDCContours", st_tdccontours_serialfn, st_tdccontours_deserialfn,
	st_tdccontours_combinefn, 24, contour_extra, contour_normalize, contour_same},
	{0x31524454, 2, "ST_TDCDrape", st_tdcdrape_serialfn, st_tdcdrape_deserialfn,
	st_tdcdrape_combinefn, 16, drape_extra, drape_normalize, drape_same},
	{0x31495254, 2, "ST_TDCInterpolate", st_tdcinterpolate_serialfn,
		st_tdcinterpolate_deserialfn, st_tdcinterpolate_combinefn, 8, interp_extra,
	interp_normalize, interp_same},
};

/* ----------------------------------------------------------------
 *		the model
 * ----------------------------------------------------------------
 */
static Model
model_read(const TinFormat *f, const uint8 *d, size_t len)
{
	Model		m;
	uint64		per;

	memset(&m, 0, sizeof(m));
	if (len < HDR || u32_at(d) != f->magic || u32_at(d + 4) != f->version)
	{
		m.reject = R_CORRUPT;
		return m;
	}
	m.bits = u32_at(d + 8);
	m.srid = (int32) u32_at(d + 12);
	m.flags = (int32) u32_at(d + 16);
	m.tol = f64_at(d + 24);
	m.n = u64_at(d + 32);
	per = (m.bits & SB_HASZ) ? 24 : 16;
	if (m.bits > 7 || u32_at(d + 20) != 0 ||
		(!(m.bits & SB_HAVE_FIRST) && ((m.bits & SB_HASZ) || m.n != 0)) ||
		((m.bits & SB_PARAMS) &&
		 (m.flags < 0 || m.flags > 2 || !(m.tol >= 0) || isinf(m.tol))) ||
		m.n > TDC_MAX_POINTS || m.n * per > len - HDR)
	{
		m.reject = R_CORRUPT;
		return m;
	}
	m.xy = d + HDR;
	m.z = d + HDR + 16 * m.n;
	for (uint64 i = 0; i < 2 * m.n; i++)
		if (!isfinite(f64_at(m.xy + 8 * i)))
		{
			m.reject = R_CORRUPT;
			return m;
		}
	m.extra = d + HDR + m.n * per;
	m.extra_len = len - HDR - m.n * per;
	f->read_extra(&m);
	/*
	 * A state without parameters holds nothing (combine skips it: its
	 * samples and rows would be lost; fuzz/known/state_unset_with_samples);
	 * the samples need heights.
	 */
	if (m.reject == 0 && !m.params_set &&
		((m.bits & (SB_HAVE_FIRST | SB_PARAMS)) != 0 || m.rows != 0))
		m.reject = R_CORRUPT;
	if (m.reject == 0 && m.n > 0 && !(m.bits & SB_HASZ))
		m.reject = R_CORRUPT;
	return m;
}

/* The bytes the serial function gives for an accepted state. */
static uint8 *
model_normalized(const TinFormat *f, const Model *m, const uint8 *d, size_t len)
{
	uint8	   *out = malloc(len);

	memcpy(out, d, len);
	if (!(m->bits & SB_HAVE_FIRST))
		memset(out + 12, 0, 4);
	if (!(m->bits & SB_PARAMS))
	{
		memset(out + 16, 0, 4);
		memset(out + 24, 0, 8);
	}
	f->normalize_extra(m, out + (m->extra - d));
	return out;
}

/* ----------------------------------------------------------------
 *		calling the functions
 * ----------------------------------------------------------------
 */
typedef struct Call
{
	bool		ok;				/* returned (no ERROR) */
	bool		isnull;
	Datum		result;
	int			sqlstate;
} Call;

static Call
call2(PGFunction fn, Datum a0, bool null0, Datum a1, bool null1)
{
	LOCAL_FCINFO(fcinfo, 2);
	sigjmp_buf	jb;
	volatile Call c;

	memset((void *) &c, 0, sizeof(c));
	InitFunctionCallInfoData(*fcinfo, NULL, 2, InvalidOid, NULL, NULL);
	fcinfo->args[0].value = a0;
	fcinfo->args[0].isnull = null0;
	fcinfo->args[1].value = a1;
	fcinfo->args[1].isnull = null1;
	if (sigsetjmp(jb, 0) == 0)
	{
		Datum		r;

		fuzz_pg_jmp = &jb;
		r = fn(fcinfo);
		c.result = r;
		c.isnull = fcinfo->isnull;
		c.ok = true;
	}
	fuzz_pg_jmp = NULL;
	if (!c.ok)
		c.sqlstate = fuzz_pg_sqlstate;
	return c;
}

static bytea *
serialize(const TinFormat *f, Datum st)
{
	Call		c = call2(f->serial, st, false, (Datum) 0, true);

	if (!c.ok)
		fuzz_state_fail("the serial function raised an ERROR", fuzz_pg_message);
	if (c.isnull)
		fuzz_state_fail("the serial function returned NULL", NULL);
	return (bytea *) DatumGetPointer(c.result);
}

static void
expect_bytes(const bytea *got, const uint8 *want, size_t len, const char *what)
{
	if (VARSIZE(got) != VARHDRSZ + len || memcmp(VARDATA(got), want, len) != 0)
		fuzz_state_fail(what, NULL);
}

/*
 * Deserialize d (len bytes) and check it against the model; the state, or
 * 0 with *m->reject set.
 */
static Datum
deserialize(const TinFormat *f, const uint8 *d, size_t len, Model *m)
{
	bytea	   *v = fuzz_state_bytea(d, len);
	Call		c = call2(f->deserial, PointerGetDatum(v), false, (Datum) 0, false);

	*m = model_read(f, d, len);
	free(v);
	if (c.ok != (m->reject == 0))
		fuzz_state_fail(c.ok ? "deserial accepted a state the model rejects" :
						"deserial rejected a state the model accepts", fuzz_pg_message);
	if (!c.ok)
	{
		if (c.sqlstate != ERRCODE_DATA_CORRUPTED &&
			!(c.sqlstate == ERRCODE_INVALID_PARAMETER_VALUE && (m->reject & R_METHOD)))
			fuzz_state_fail("deserial refused a state with an unexpected error",
							fuzz_pg_message);
		return (Datum) 0;
	}
	if (c.isnull)
		fuzz_state_fail("deserial returned NULL", NULL);
	{
		uint8	   *norm = model_normalized(f, m, d, len);

		expect_bytes(serialize(f, c.result), norm, len,
					 "serial(deserial(x)) differs from x");
		free(norm);
	}
	return c.result;
}

/* Would combine(a, b) conflict (INVALID_PARAMETER_VALUE)? */
static bool
conflict(const TinFormat *f, const Model *a, const Model *b)
{
	if ((a->bits & SB_HAVE_FIRST) && (b->bits & SB_HAVE_FIRST) &&
		(a->srid != b->srid || ((a->bits ^ b->bits) & SB_HASZ) != 0))
		return true;
	if ((a->bits & SB_PARAMS) && (b->bits & SB_PARAMS) &&
		(a->flags != b->flags || a->tol != b->tol))
		return true;
	return a->params_set && b->params_set && !f->same_params(a, b);
}

/*
 * The serialized combine(A, B) of two accepted states with B's parameters
 * set: the Delaunay part merged, the aggregate's part of whichever has
 * parameters (A's first) with the rows added, then with breaklines A's
 * segments and B's shifted by A's vertex count (a state without
 * parameters has none).
 */
static uint8 *
model_combined(const TinFormat *f, const Model *a, const Model *b, size_t *len)
{
	const Model *p = a->params_set ? a : b;
	uint32		hf = (a->bits | b->bits) & SB_HAVE_FIRST;
	uint32		hasz = ((a->bits & SB_HAVE_FIRST) ? a->bits : b->bits) & SB_HASZ;
	uint32		bits = hf | hasz | ((a->bits | b->bits) & SB_PARAMS);
	/* a state without vertices' dimensions has no SRID: it serializes 0 */
	int32		srid = (a->bits & SB_HAVE_FIRST) ? a->srid :
		(b->bits & SB_HAVE_FIRST) ? b->srid : 0;
	const Model *q = (a->bits & SB_PARAMS) ? a : b;
	int32		flags = (bits & SB_PARAMS) ? q->flags : 0;
	double		tol = (bits & SB_PARAMS) ? q->tol : 0;
	uint64		n = a->n + b->n;
	uint32		zero = 0;
	int64		rows = a->rows + b->rows;	/* no overflow: checked by the caller */
	uint64		nseg = p->breaklines ? a->nseg + b->nseg : 0;
	uint8	   *out,
			   *w;

	*len = HDR + n * (hasz ? 24 : 16) + p->params_len + 8 * nseg;
	out = w = malloc(*len);
	memcpy(w, &f->magic, 4);
	memcpy(w + 4, &f->version, 4);
	memcpy(w + 8, &bits, 4);
	memcpy(w + 12, &srid, 4);
	memcpy(w + 16, &flags, 4);
	memcpy(w + 20, &zero, 4);
	memcpy(w + 24, &tol, 8);
	memcpy(w + 32, &n, 8);
	w += HDR;
	memcpy(w, a->xy, 16 * a->n);
	memcpy(w + 16 * a->n, b->xy, 16 * b->n);
	w += 16 * n;
	if (hasz)
	{
		memcpy(w, a->z, 8 * a->n);
		memcpy(w + 8 * a->n, b->z, 8 * b->n);
		w += 8 * n;
	}
	memcpy(w, p->extra, p->params_len);
	f->normalize_extra(p, w);
	memcpy(w + f->rows_at, &rows, 8);
	w += p->params_len;
	if (nseg > 0)
	{
		if (a->nseg > 0)
			memcpy(w, a->seg, 8 * a->nseg);
		w += 8 * a->nseg;
		for (uint64 i = 0; i < 2 * b->nseg; i++)
		{
			uint32		end = u32_at(b->seg + 4 * i) + (uint32) a->n;

			memcpy(w + 4 * i, &end, 4);
		}
	}
	return out;
}

/* combine(NULL, B) and combine(A, B), A and B accepted. */
static void
check_combine(const TinFormat *f, Datum sa, const Model *a, const uint8 *da, size_t la,
			  Datum sb, const Model *b, const uint8 *db, size_t lb)
{
	Call		c;
	int64		rows;
	bool		overflow = pg_add_s64_overflow(a->rows, b->rows, &rows);

	/* combine(NULL, B): B itself, or NULL for a state without parameters */
	c = call2(f->combine, (Datum) 0, true, sb, false);
	if (!c.ok)
		fuzz_state_fail("combine(NULL, B) raised an ERROR", fuzz_pg_message);
	if (c.isnull != !b->params_set)
		fuzz_state_fail(c.isnull ? "combine(NULL, B) is NULL for a B with parameters" :
						"combine(NULL, B) is not NULL for a B without parameters", NULL);
	if (!c.isnull)
	{
		uint8	   *norm = model_normalized(f, b, db, lb);

		expect_bytes(serialize(f, c.result), norm, lb, "combine(NULL, B) is not B");
		free(norm);
	}

	c = call2(f->combine, sa, false, sb, false);
	if (!c.ok)
	{
		bool		allowed = b->params_set &&
			((c.sqlstate == ERRCODE_INVALID_PARAMETER_VALUE && conflict(f, a, b)) ||
			 (c.sqlstate == ERRCODE_DATA_CORRUPTED && overflow));

		if (!allowed)
			fuzz_state_fail("combine(A, B) raised an unexpected ERROR", fuzz_pg_message);
		return;
	}
	if (c.isnull || c.result != sa)
		fuzz_state_fail("combine(A, B) did not return A", NULL);
	if (!b->params_set)
	{
		uint8	   *norm = model_normalized(f, a, da, la);

		expect_bytes(serialize(f, c.result), norm, la,
					 "combine(A, B) changed A although B has no parameters");
		free(norm);
		return;
	}
	if (conflict(f, a, b))
		fuzz_state_fail("combine(A, B) accepted conflicting states", NULL);
	if (overflow)
		fuzz_state_fail("combine(A, B) accepted row counts whose sum overflows", NULL);
	{
		size_t		len;
		uint8	   *want = model_combined(f, a, b, &len);
		bytea	   *ser = serialize(f, c.result);
		Model		again;

		expect_bytes(ser, want, len, "combine(A, B) is not A's vertices then B's, rows added");
		free(want);
		/* and it travels on */
		(void) deserialize(f, (const uint8 *) VARDATA(ser), len, &again);
		if (again.reject)
			fuzz_state_fail("combine(A, B) does not deserialize", fuzz_pg_message);
	}
}

bool
fuzz_state_tin(const uint8 *a, size_t alen, const uint8 *b, size_t blen)
{
	const TinFormat *f = NULL;
	Model		ma,
				mb;
	Datum		sa,
				sb;

	if (alen < 4)
		return false;
	for (int i = 0; i < lengthof(formats); i++)
		if (u32_at(a) == formats[i].magic)
			f = &formats[i];
	if (f == NULL)
		return false;

	sa = deserialize(f, a, alen, &ma);
	sb = blen > 0 ? deserialize(f, b, blen, &mb) : (Datum) 0;
	if (ma.reject == 0 && blen > 0 && mb.reject == 0)
		check_combine(f, sa, &ma, a, alen, sb, &mb, b, blen);
	return true;
}
