/*
 * fuzz_state.c
 *		libFuzzer target for the serialized ST_TDCDelaunay aggregate state
 *		(src/pg/runtime/agg_state.c: tdc_agg_state_deserialize, _serialize,
 *		_merge), the bytes that travel between parallel workers.
 *
 * Linked with agg_state.c and pointbuf.c (and, for fuzz_state_tin.c, the
 * TIN aggregates' entry points and what they call), compiled against the
 * real server headers, and with the shims of pg_shim.c and pg_shim_agg.c.
 *
 * Input: uint16 little-endian length L, then L bytes of a first serialized
 * state (without the varlena header), then the rest as a second state.
 *
 * Checks:
 *	- deserializing never crashes; it raises an ERROR exactly when an
 *	  independent check of the documented format (ref_valid) rejects;
 *	- an accepted state serializes back to the input, up to the fields
 *	  the format ignores (srid without vertices/dimensions, tolerance and
 *	  flags when no parameters were set);
 *	- when both states are accepted, the combine step either raises an ERROR
 *	  (mixed SRID, dimensions or parameters) or concatenates the vertices,
 *	  and the merged state survives another serialize/deserialize round;
 *	- an accepted state written with the second input as the extra part of
 *	  another format (tdc_agg_state_serialize_with, as the constrained and
 *	  Voronoi aggregates do) reads back with the same vertices and exactly
 *	  that extra part, and is refused by ST_TDCDelaunay's deserializer and,
 *	  when the extra part is not empty, by one that expects none.
 *
 * A first state with the magic number of ST_TDCContours, ST_TDCDrape or
 * ST_TDCInterpolate goes to fuzz_state_tin.c instead, which fuzzes those
 * aggregates' own serial, deserial and combine functions.
 */
#include "postgres.h"

#include <math.h>
#include <stdlib.h>

#include "miscadmin.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "pg_shim.h"
#include "fuzz_state.h"

void
fuzz_state_fail(const char *what, const char *detail)
{
	fprintf(stderr, "fuzz_state: %s%s%s\n", what, detail ? ": " : "",
			detail ? detail : "");
	abort();
}

bytea *
fuzz_state_bytea(const uint8 *data, size_t size)
{
	bytea	   *v = malloc(VARHDRSZ + size);

	SET_VARSIZE(v, VARHDRSZ + size);
	memcpy(VARDATA(v), data, size);
	return v;
}

/* The documented format, checked independently. */
static bool
ref_valid(const uint8 *d, size_t len)
{
	uint32		magic,
				version,
				bits,
				pad;
	int32		flags;
	double		tol;
	uint64		n,
				per;

	if (len < 40)
		return false;
	memcpy(&magic, d, 4);
	memcpy(&version, d + 4, 4);
	memcpy(&bits, d + 8, 4);
	memcpy(&flags, d + 16, 4);
	memcpy(&pad, d + 20, 4);
	memcpy(&tol, d + 24, 8);
	memcpy(&n, d + 32, 8);
	if (magic != 0x41434454 || version != 1 || bits > 7 || pad != 0)
		return false;
	if (!(bits & 1) && ((bits & 2) || n != 0))
		return false;
	if ((bits & 4) && (flags < 0 || flags > 2 || !(tol >= 0) || isinf(tol)))
		return false;
	per = (bits & 2) ? 24 : 16;
	if (n > TDC_MAX_POINTS || n * per != len - 40)
		return false;
	for (uint64 i = 0; i < 2 * n; i++)
	{
		double		c;

		memcpy(&c, d + 40 + 8 * i, 8);
		if (!isfinite(c))
			return false;
	}
	return true;
}

/* What tdc_agg_state_serialize must give back for an accepted input. */
static void
normalize(uint8 *d)
{
	uint32		bits;

	memcpy(&bits, d + 8, 4);
	if (!(bits & 1))
		memset(d + 12, 0, 4);	/* srid */
	if (!(bits & 4))
	{
		memset(d + 16, 0, 4);	/* flags */
		memset(d + 24, 0, 8);	/* tolerance */
	}
}

static TdcAggState *
try_deserialize(const uint8 *data, size_t size, bool *ok)
{
	bytea	   *v = fuzz_state_bytea(data, size);
	sigjmp_buf	jb;
	TdcAggState *volatile st = NULL;

	*ok = false;
	if (sigsetjmp(jb, 0) == 0)
	{
		fuzz_pg_jmp = &jb;
		st = tdc_agg_state_deserialize(v, CurrentMemoryContext);
		*ok = true;
	}
	fuzz_pg_jmp = NULL;
	free(v);
	if (*ok != ref_valid(data, size))
		fuzz_state_fail(*ok ? "accepted a state the format check rejects" :
			 "rejected a state the format check accepts", fuzz_pg_message);
	if (*ok)
	{
		bytea	   *out = tdc_agg_state_serialize(st);
		uint8	   *norm = malloc(size);

		memcpy(norm, data, size);
		normalize(norm);
		if (VARSIZE(out) != VARHDRSZ + size ||
			memcmp(VARDATA(out), norm, size) != 0)
			fuzz_state_fail("serialize(deserialize(x)) differs from x", NULL);
		free(norm);
	}
	return st;
}

/* A format of another aggregate, as fn_constrained.c and fn_voronoi_agg.c have. */
static const TdcStateFormat other_format = {
	0x5a5a4454, 1, "fuzz_other", "a hint", -1
};

/* Raises an ERROR? */
static bool
refuses(const bytea *v, const TdcStateFormat *fmt)
{
	sigjmp_buf	jb;
	volatile bool ok = false;

	if (sigsetjmp(jb, 0) == 0)
	{
		fuzz_pg_jmp = &jb;
		if (fmt)
			(void) tdc_agg_state_deserialize_with(v, fmt, CurrentMemoryContext,
												  NULL, NULL);
		else
			(void) tdc_agg_state_deserialize(v, CurrentMemoryContext);
		ok = true;
	}
	fuzz_pg_jmp = NULL;
	if (!ok && fuzz_pg_sqlstate != ERRCODE_DATA_CORRUPTED)
		fuzz_state_fail("refused a state with an unexpected error", fuzz_pg_message);
	return !ok;
}

/* st with "extra" as the extra part of other_format, and back. */
static void
check_extra(const TdcAggState *st, const uint8 *extra, size_t extra_len)
{
	sigjmp_buf	jb;
	bytea	   *volatile ser = NULL;
	TdcAggState *volatile back = NULL;
	const char *volatile got = NULL;
	volatile Size got_len = 0;
	uint64		per = st->pts.hasz ? 3 : 2;

	if (sigsetjmp(jb, 0) == 0)
	{
		const char *g;
		Size		gl;

		fuzz_pg_jmp = &jb;
		ser = tdc_agg_state_serialize_with(st, &other_format, extra, extra_len,
										   NULL);
		back = tdc_agg_state_deserialize_with(ser, &other_format,
											  CurrentMemoryContext, &g, &gl);
		got = g;
		got_len = gl;
	}
	fuzz_pg_jmp = NULL;
	if (back == NULL)
		fuzz_state_fail("a state with an extra part does not read back", fuzz_pg_message);
	if (back->pts.n != st->pts.n || back->pts.hasz != st->pts.hasz ||
		(st->pts.n > 0 &&
		 (memcmp(back->pts.xy, st->pts.xy, 16 * st->pts.n) != 0 ||
		  (st->pts.hasz && memcmp(back->pts.z, st->pts.z, 8 * st->pts.n) != 0))))
		fuzz_state_fail("a state with an extra part reads back other vertices", NULL);
	if (got_len != extra_len ||
		(extra_len > 0 && memcmp(got, extra, extra_len) != 0))
		fuzz_state_fail("the extra part reads back different", NULL);
	if (got != (const char *) VARDATA(ser) + 40 + 8 * per * st->pts.n)
		fuzz_state_fail("the extra part is not right after the vertices", NULL);
	if (!refuses(ser, NULL))
		fuzz_state_fail("ST_TDCDelaunay's deserializer accepted another format", NULL);
	if (extra_len > 0 && !refuses(ser, &other_format))
		fuzz_state_fail("a deserializer that expects no extra part accepted one", NULL);
}

int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	uint16		split = 0;
	const uint8 *a,
			   *b;
	size_t		alen,
				blen;
	TdcAggState *sa,
			   *sb;
	bool		oka,
				okb;

	FUZZ_PG_STACK_BASE();
	fuzz_pg_max_memory_mb = 0;
	if (size < 2)
		return 0;
	memcpy(&split, data, 2);
	a = data + 2;
	alen = Min((size_t) split, size - 2);
	b = a + alen;
	blen = size - 2 - alen;

	/* the TIN aggregates' states: fuzz_state_tin.c */
	if (fuzz_state_tin(a, alen, b, blen))
	{
		fuzz_pg_reset();
		return 0;
	}

	sa = try_deserialize(a, alen, &oka);
	sb = blen > 0 ? try_deserialize(b, blen, &okb) : NULL;
	if (sa != NULL)
		check_extra(sa, b, blen);

	if (sa != NULL && sb != NULL)
	{
		sigjmp_buf	jb;
		uint64		na = sa->pts.n,
					nb = sb->pts.n;
		double	   *axy = malloc(16 * na + 16);
		volatile bool merged = false;

		memcpy(axy, sa->pts.xy ? sa->pts.xy : axy, 16 * na);
		if (sigsetjmp(jb, 0) == 0)
		{
			fuzz_pg_jmp = &jb;
			tdc_agg_state_merge(sa, sb);
			merged = true;
		}
		fuzz_pg_jmp = NULL;
		if (!merged && fuzz_pg_sqlstate != ERRCODE_INVALID_PARAMETER_VALUE)
			fuzz_state_fail("combine failed with an unexpected error", fuzz_pg_message);
		if (merged)
		{
			bytea	   *ser;
			bool		ok2;

			if (sa->pts.n != na + nb)
				fuzz_state_fail("combined state has the wrong vertex count", NULL);
			if (na > 0 && memcmp(sa->pts.xy, axy, 16 * na) != 0)
				fuzz_state_fail("combine changed the first state's vertices", NULL);
			if (nb > 0 && memcmp(sa->pts.xy + 2 * na, sb->pts.xy, 16 * nb) != 0)
				fuzz_state_fail("combine did not append the second state's vertices", NULL);
			if (nb > 0 && sa->pts.hasz &&
				memcmp(sa->pts.z + na, sb->pts.z, 8 * nb) != 0)
				fuzz_state_fail("combine did not append the second state's Z values", NULL);
			ser = tdc_agg_state_serialize(sa);
			(void) try_deserialize((const uint8 *) VARDATA(ser),
								   VARSIZE(ser) - VARHDRSZ, &ok2);
			if (!ok2)
				fuzz_state_fail("combined state does not deserialize", NULL);
		}
		free(axy);
	}
	fuzz_pg_reset();
	return 0;
}
