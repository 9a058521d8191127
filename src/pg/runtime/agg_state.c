/*
 * agg_state.c
 *		The state of the ST_TDCDelaunay aggregates, and its serialized form
 *		for parallel aggregation.
 *
 * An "internal" TdcAggState holds the point buffer (x,y interleaved, Z when
 * the inputs have it, SRID, dimensions) and the tolerance and flags, which
 * must be the same on every row.  Its arrays belong to the aggregate memory
 * context (pointbuf.c), so a state may pass 1 GB; tdc_delaunay.max_memory
 * bounds the growth.
 *
 * Merging (the combine function) appends one state's vertices to the
 * other's, copying into the aggregate context: the second state may live in
 * short-lived memory.  States travel between processes as bytea:
 *
 *	uint32 magic 'TDCA', uint32 version, uint32 bits (have_first, hasz,
 *	params_set), int32 srid, int32 flags, uint32 zero, float8 tolerance,
 *	uint64 n, then n*2 float8 x,y, then n float8 z when hasz
 *
 * The deserializer checks the magic, the version, the bits and that n
 * matches the length exactly, raising an ERROR on anything else: the bytes
 * cross a process boundary, and fuzz/fuzz_state.c feeds them arbitrary
 * input.  A serialized state is one bytea, so parallel plans are limited to
 * partial states below 1 GB (about 67 million 2D points per worker); the
 * error says so and how to avoid it.
 *
 * The other aggregates whose state holds a TdcAggState (ST_TDCVoronoi,
 * ST_TDCConstrainedDelaunay) travel in the same form under a magic number
 * and version of their own (a TdcStateFormat), with their own part after
 * the vertices: the _with functions write it and hand it back to be
 * checked, so the vertex part and its checks exist once.
 *
 * This file is linked, without the SQL entry points of fn_delaunay_agg.c, into the
 * fuzz target.
 */
#include "postgres.h"

#include <math.h>

#include "common/int.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

#define STATE_MAGIC			0x41434454	/* "TDCA" little-endian */
#define STATE_VERSION		1
#define STATE_HEADER		40

#define SB_HAVE_FIRST		0x01
#define SB_HASZ				0x02
#define SB_PARAMS			0x04

/* The ST_TDCDelaunay aggregates' own form: the vertices and nothing after. */
static const TdcStateFormat delaunay_format = {
	STATE_MAGIC, STATE_VERSION, TDC_AGG_NAME,
	"Disable parallel aggregation for this query (SET max_parallel_workers_per_gather = 0) or use ST_TDCDelaunayDump.",
	-1
};

void
tdc_agg_state_corrupt(const char *fname, const char *what)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: corrupt serialized aggregate state: %s",
					fname, what)));
}

TdcAggState *
tdc_agg_state_new(MemoryContext cxt)
{
	TdcAggState *st = MemoryContextAllocZero(cxt, sizeof(TdcAggState));

	tdc_pointbuf_init(&st->pts, cxt);
	return st;
}

void
tdc_agg_state_set_params(TdcAggState *st, double tolerance, int32 flags)
{
	if (!st->params_set)
	{
		st->params_set = true;
		st->tolerance = tolerance;
		st->flags = flags;
		return;
	}
	/* bitwise comparison would split 0 and -0; tolerance is >= 0 anyway */
	if (st->tolerance != tolerance || st->flags != flags)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tolerance and flags must be the same for all rows (%g, %d versus %g, %d)",
						TDC_AGG_NAME, st->tolerance, st->flags, tolerance, flags)));
}

/* Everything of src into dst (dst in the aggregate context). */
void
tdc_agg_state_merge(TdcAggState *dst, const TdcAggState *src)
{
	if (src->params_set)
		tdc_agg_state_set_params(dst, src->tolerance, src->flags);
	tdc_pointbuf_append_buf(&dst->pts, &src->pts, TDC_AGG_NAME);
}

/*
 * st in fmt's form, followed by extra_len bytes of "extra" (the aggregate's
 * own part, which its deserializer reads back).  "contents" names what the
 * state holds in the error for a state over 1 GB; NULL: its vertices.
 */
bytea *
tdc_agg_state_serialize_with(const TdcAggState *st, const TdcStateFormat *fmt,
							 const void *extra, Size extra_len,
							 const char *contents)
{
	const TdcPointBuf *p = &st->pts;
	uint64		per = (p->hasz ? 3 : 2) * sizeof(double);
	uint64		size = VARHDRSZ + STATE_HEADER + p->n * per + extra_len;
	bytea	   *out;
	char	   *w;
	uint32		u;
	int32		i;
	uint64		n = p->n;

	if (size > MaxAllocSize)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: partial aggregate state of %s is too large to pass between parallel workers",
						fmt->fname, contents ? contents :
						psprintf("%llu vertices", (unsigned long long) n)),
				 errhint("%s", fmt->hint)));

	out = palloc((Size) size);
	SET_VARSIZE(out, size);
	w = VARDATA(out);
	u = fmt->magic;
	memcpy(w, &u, 4);
	u = fmt->version;
	memcpy(w + 4, &u, 4);
	u = (p->have_first ? SB_HAVE_FIRST : 0) | (p->hasz ? SB_HASZ : 0) |
		(st->params_set ? SB_PARAMS : 0);
	memcpy(w + 8, &u, 4);
	i = p->srid;
	memcpy(w + 12, &i, 4);
	i = st->flags;
	memcpy(w + 16, &i, 4);
	u = 0;
	memcpy(w + 20, &u, 4);
	memcpy(w + 24, &st->tolerance, 8);
	memcpy(w + 32, &n, 8);
	w += STATE_HEADER;
	if (n > 0)
	{
		memcpy(w, p->xy, (Size) n * 2 * sizeof(double));
		if (p->hasz)
			memcpy(w + n * 2 * sizeof(double), p->z, (Size) n * sizeof(double));
		w += n * per;
	}
	if (extra_len > 0)
		memcpy(w, extra, extra_len);
	return out;
}

bytea *
tdc_agg_state_serialize(const TdcAggState *st)
{
	return tdc_agg_state_serialize_with(st, &delaunay_format, NULL, 0, NULL);
}

/*
 * Read a state in fmt's form, checking every field.  With extra NULL the
 * vertices must fill the rest exactly; otherwise *extra and *extra_len are
 * set to the bytes after them (in "in"), which the caller checks.
 */
TdcAggState *
tdc_agg_state_deserialize_with(const bytea *in, const TdcStateFormat *fmt,
							   MemoryContext cxt, const char **extra,
							   Size *extra_len)
{
	const char *fname = fmt->fname;
	const char *r = VARDATA(in);
	uint64		len;
	uint32		magic,
				version,
				bits,
				pad;
	int32		srid,
				flags;
	double		tolerance;
	uint64		n;
	uint64		per;
	TdcAggState *st;

	if (VARSIZE(in) < VARHDRSZ + STATE_HEADER)
		tdc_agg_state_corrupt(fname, "shorter than its header");
	len = VARSIZE(in) - VARHDRSZ - STATE_HEADER;
	memcpy(&magic, r, 4);
	memcpy(&version, r + 4, 4);
	memcpy(&bits, r + 8, 4);
	memcpy(&srid, r + 12, 4);
	memcpy(&flags, r + 16, 4);
	memcpy(&pad, r + 20, 4);
	memcpy(&tolerance, r + 24, 8);
	memcpy(&n, r + 32, 8);
	if (magic != fmt->magic)
		tdc_agg_state_corrupt(fname, "bad magic number");
	if (version != fmt->version)
		tdc_agg_state_corrupt(fname, psprintf("unknown version %u", version));
	if ((bits & ~(SB_HAVE_FIRST | SB_HASZ | SB_PARAMS)) != 0 || pad != 0)
		tdc_agg_state_corrupt(fname, "unknown flag bits");
	if (!(bits & SB_HAVE_FIRST) && ((bits & SB_HASZ) || n != 0))
		tdc_agg_state_corrupt(fname, "vertices without dimensions");
	if ((bits & SB_PARAMS) &&
		(!tdc_flags_valid(flags, fmt->more_flags == TDC_OUT_CONSTRAINTS) ||
		 !(tolerance >= 0) || isinf(tolerance)))
		tdc_agg_state_corrupt(fname, "bad tolerance or flags");
	per = ((bits & SB_HASZ) ? 3 : 2) * sizeof(double);
	if (n > TDC_MAX_POINTS || (extra ? n * per > len : n * per != len))
		tdc_agg_state_corrupt(fname,
							  psprintf("%llu vertices do not match a length of %llu bytes",
									   (unsigned long long) n,
									   (unsigned long long) len));

	st = tdc_agg_state_new(cxt);
	st->params_set = (bits & SB_PARAMS) != 0;
	st->tolerance = st->params_set ? tolerance : 0;
	st->flags = st->params_set ? flags : 0;
	if (bits & SB_HAVE_FIRST)
		tdc_pointbuf_check_meta(&st->pts, srid, (bits & SB_HASZ) != 0, fname);
	if (n > 0)
	{
		const char *data = r + STATE_HEADER;
		uint64		i;

		tdc_pointbuf_reserve(&st->pts, n, fname);
		memcpy(st->pts.xy, data, (Size) n * 2 * sizeof(double));
		if (st->pts.hasz)
			memcpy(st->pts.z, data + n * 2 * sizeof(double),
				   (Size) n * sizeof(double));
		/* the core would reject them too, but say where they came from */
		for (i = 0; i < 2 * n; i++)
			if (!isfinite(st->pts.xy[i]))
				tdc_agg_state_corrupt(fname, "non-finite coordinate");
		st->pts.n = n;
	}
	if (extra)
	{
		*extra = r + STATE_HEADER + n * per;
		*extra_len = (Size) (len - n * per);
	}
	return st;
}

/*
 * The aggregates whose state adds parameters and a row count to the
 * vertices (ST_TDCContours, ST_TDCDrape, ST_TDCInterpolate) check two more
 * things of a state from another process.  A state without parameters
 * holds nothing: their transition functions set the parameters before
 * reading a row, and their combine functions skip such a state, so
 * vertices or rows in one would be lost without a word.  And the row
 * counts of two states add up without overflow (int64: only corrupt counts
 * get there).
 */
void
tdc_agg_state_check_unset(const TdcAggState *st, bool params_set, int64 rows,
						  const char *fname)
{
	if (!params_set && (st->pts.have_first || st->params_set || rows != 0))
		tdc_agg_state_corrupt(fname, "samples or rows without parameters");
}

void
tdc_agg_rows_add(int64 *rows, int64 more, const char *fname)
{
	if (pg_add_s64_overflow(*rows, more, rows))
		tdc_agg_state_corrupt(fname, "the row counts overflow");
}

TdcAggState *
tdc_agg_state_deserialize(const bytea *in, MemoryContext cxt)
{
	return tdc_agg_state_deserialize_with(in, &delaunay_format, cxt, NULL, NULL);
}
