/*
 * fuzz_gserialized.c
 *		libFuzzer target for the PostGIS geometry reader and writer of
 *		tdc_delaunay (src/pg/formats/gser_read.c, gser_write.c, and
 *		src/pg/runtime/pointbuf.c), linked with the PostgreSQL shims of
 *		pg_shim.c and the real core.
 *
 * Input: one serialized geometry value without its 4-byte varlena header
 * (srid[3], flags, [extended flags], [bbox], geometry); the harness puts it
 * into an exactly sized malloc'd varlena so that AddressSanitizer sees any
 * read beyond the value.
 *
 * Checks:
 *	- tdc_gser_append() either succeeds or raises an ERROR (longjmp through
 *	  the shim); never a crash, hang or out-of-bounds read;
 *	- differential: an independent reader below (ref_walk) must accept
 *	  exactly the values the real one accepts, with the same vertex count,
 *	  SRID, Z flag and bit-identical coordinates (the only accepted
 *	  differences are the stack-depth and memory-limit errors the reference
 *	  does not model; stack depth only from MIN_TOO_DEEP levels of nesting);
 *	- curves, by the input's length: refused (the constrained functions),
 *	  read as their stored vertices (Voronoi: the reference then reads
 *	  arc strings as point lists and the other curve types as
 *	  collections), or stroked (Delaunay: read the same way first; a
 *	  value with a non-empty arc string is then stroked, which the shim's
 *	  ST_CurveToLine refuses, so it must be rejected; empty ones add
 *	  nothing);
 *	- appending the value twice to one buffer doubles it; the second time
 *	  with a 1-byte varlena header when it fits, as stored small values
 *	  arrive (PG_DETOAST_DATUM_PACKED);
 *	- writer round trip: for 3..4000 acceptable vertices the core
 *	  triangulates them; every result kind (tdc_gser_result, flags 0, 1,
 *	  2), one triangle (tdc_gser_write_triangle) and the empty results are
 *	  read back with tdc_gser_append and must have the announced size,
 *	  SRID, dimensions and vertex count; the triangle results written by
 *	  the core's threads (tdc_gser_emit) must be byte-identical to the
 *	  serial writer's.
 */
#include "postgres.h"

#include <math.h>
#include <stdlib.h>

#include "utils/memutils.h"

#include "pg_shim.h"
#include "tdc_pg.h"

/* ----------------------------------------------------------------
 *		independent reference reader
 * ----------------------------------------------------------------
 */

typedef struct Ref
{
	const uint8 *end;
	int			ndims;
	bool		hasz;
	bool		nonfinite;
	uint64		count;
	double	   *xy;				/* NULL: count only */
	double	   *z;
	bool		curves;			/* curves read as their vertices */
	bool		arcs;			/* met an arc string with vertices */
	int			maxdepth;		/* deepest nesting walked (0: not nested) */
} Ref;

static uint32
ru32(const uint8 *p)
{
	return (uint32) p[0] | (uint32) p[1] << 8 | (uint32) p[2] << 16 | (uint32) p[3] << 24;
}

static double
rdbl(const uint8 *p)
{
	double		d;

	memcpy(&d, p, 8);
	return d;
}

/*
 * The reader's check_stack_depth() (1.5 MB in the shim) stops it between
 * 2,000 and 5,000 levels of nesting (measured: 2,000 pass and 3,000 stop
 * with clang 14 and with clang 21; 3,000 pass and 5,000 stop with clang
 * 19).  An ERROR for stack depth at fewer levels than this means the shim
 * measures the stack wrongly (as it did under clang 15 and later's fake
 * stacks, where every input was "too deep") and is a finding.
 */
#define MIN_TOO_DEEP	256

/*
 * Deeper than this the reference rejects, to stay inside its own 8 MB stack
 * (ASan overflows it near 50,000 levels).  Inputs of fuzz/run.sh (8 KB) nest
 * at most 1,023 levels.
 */
#define REF_MAX_DEPTH	10000

/* Returns the end of the geometry at p, or NULL when it is not acceptable. */
static const uint8 *
ref_walk(Ref *r, const uint8 *p, int depth)
{
	uint32		type,
				count;

	if (depth > REF_MAX_DEPTH || r->end - p < 8)
		return NULL;
	r->maxdepth = Max(r->maxdepth, depth);
	type = ru32(p);
	count = ru32(p + 4);
	p += 8;
	if (type == 1 || type == 2 || type == 14 || (r->curves && type == 8))
	{
		if (type == 8 && count > 0)
			r->arcs = true;
		size_t		vb = (size_t) r->ndims * 8;

		if (type == 1 && count > 1)
			return NULL;
		if ((uint64) count * vb > (uint64) (r->end - p))
			return NULL;
		for (uint32 i = 0; i < count; i++, p += vb)
		{
			double		x = rdbl(p),
						y = rdbl(p + 8),
						z = r->hasz ? rdbl(p + 16) : 0;

			if (!isfinite(x) || !isfinite(y) || !isfinite(z))
				r->nonfinite = true;
			if (r->xy)
			{
				r->xy[2 * r->count] = x;
				r->xy[2 * r->count + 1] = y;
				if (r->hasz)
					r->z[r->count] = z;
			}
			r->count++;
		}
		return p;
	}
	if (type == 3)
	{
		const uint8 *rings = p;
		uint64		hdr = 4 * (uint64) count + (count & 1 ? 4 : 0);

		if (hdr > (uint64) (r->end - p))
			return NULL;
		p += hdr;
		for (uint32 i = 0; i < count; i++)
		{
			uint32		np = ru32(rings + 4 * (size_t) i);
			size_t		vb = (size_t) r->ndims * 8;

			if ((uint64) np * vb > (uint64) (r->end - p))
				return NULL;
			for (uint32 k = 0; k < np; k++, p += vb)
			{
				double		x = rdbl(p),
							y = rdbl(p + 8),
							z = r->hasz ? rdbl(p + 16) : 0;

				if (!isfinite(x) || !isfinite(y) || !isfinite(z))
					r->nonfinite = true;
				if (r->xy)
				{
					r->xy[2 * r->count] = x;
					r->xy[2 * r->count + 1] = y;
					if (r->hasz)
						r->z[r->count] = z;
				}
				r->count++;
			}
		}
		return p;
	}
	if ((type >= 4 && type <= 7) || type == 13 || type == 15 ||
		(r->curves && type >= 9 && type <= 12))
	{
		for (uint32 i = 0; i < count; i++)
		{
			p = ref_walk(r, p, depth + 1);
			if (p == NULL)
				return NULL;
		}
		return p;
	}
	return NULL;				/* curves and unknown types */
}

/* Header: returns the start of the geometry or NULL. */
static const uint8 *
ref_header(Ref *r, const uint8 *v, size_t len, int32 *srid)
{
	uint8		f;
	int32		s;
	const uint8 *p = v + 4;

	if (len < 4)
		return NULL;
	r->end = v + len;
	f = v[3];
	s = ((int32) (v[0] & 0x1f) << 16) | ((int32) v[1] << 8) | v[2];
	if (s >= (1 << 20))
		s -= (1 << 21);
	*srid = s;
	r->hasz = (f & 1) != 0;
	r->ndims = 2 + (f & 1) + ((f >> 1) & 1);
	if ((f & 0x40) && (f & 0x10))
	{
		if (r->end - p < 8)
			return NULL;
		p += 8;
	}
	if (f & 0x04)
	{
		size_t		bb = (f & 0x08) ? 24 : 8 * (size_t) r->ndims;

		if ((size_t) (r->end - p) < bb)
			return NULL;
		p += bb;
	}
	return p;
}

/* ----------------------------------------------------------------
 *		harness
 * ----------------------------------------------------------------
 */

static struct varlena *
make_value(const uint8 *data, size_t size)
{
	struct varlena *v = malloc(VARHDRSZ + size);

	SET_VARSIZE(v, VARHDRSZ + size);
	memcpy(VARDATA(v), data, size);
	return v;
}

/*
 * The same value with a 1-byte header, as PostgreSQL stores small values on
 * disk and hands them to PG_DETOAST_DATUM_PACKED callers; NULL when too long.
 */
static struct varlena *
make_short_value(const uint8 *data, size_t size)
{
	struct varlena *v;

	if (VARHDRSZ_SHORT + size > VARATT_SHORT_MAX)
		return NULL;
	v = malloc(VARHDRSZ_SHORT + size);
	SET_VARSIZE_SHORT(v, VARHDRSZ_SHORT + size);
	memcpy(VARDATA_SHORT(v), data, size);
	return v;
}

static void
fail(const char *what, const char *detail)
{
	fprintf(stderr, "fuzz_gserialized: %s%s%s\n", what, detail ? ": " : "",
			detail ? detail : "");
	abort();
}

/* Read a value written by the writer back; checks and returns vertex count. */
static uint64
read_back(const struct varlena *v, int32 srid, bool hasz, const char *what)
{
	TdcPointBuf b;
	sigjmp_buf	jb;
	sigjmp_buf *save = fuzz_pg_jmp;

	tdc_pointbuf_init(&b, CurrentMemoryContext);
	if (sigsetjmp(jb, 0) != 0)
	{
		fuzz_pg_jmp = save;
		fail(what, fuzz_pg_message);
	}
	fuzz_pg_jmp = &jb;
	tdc_gser_append(&b, v, "read_back");
	fuzz_pg_jmp = save;
	if (b.srid != srid)
		fail(what, "SRID changed");
	if (b.hasz != hasz)
		fail(what, "Z flag changed");
	return b.n;
}

static void
writer_roundtrip(const TdcPointBuf *buf)
{
	tdc_options opt;
	tdc_job    *job = NULL;
	char		err[256];
	int			rc;

	for (uint64 i = 0; i < 2 * buf->n; i++)
	{
		double		c = fabs(buf->xy[i]);

		if (c != 0 && (c < TDC_COORD_MIN || c > TDC_COORD_MAX))
			return;
	}
	tdc_options_init(&opt);
	opt.threads = 2;			/* the parallel writer below runs on these */
	rc = tdc_triangulate(buf->xy, (size_t) buf->n, &opt, &job, err, sizeof(err));
	if (rc != TDC_OK)
		fail("core failed on reader output", err);

	for (int flags = 0; flags <= 2; flags++)
	{
		struct varlena *out = tdc_gser_result(job, flags, buf, "writer");
		uint64		m = flags == TDC_OUT_EDGES ? tdc_num_edges(job) : tdc_num_triangles(job);
		uint64		per = flags == TDC_OUT_EDGES ? 2 : 4;
		uint64		got;

		if (VARSIZE(out) != tdc_gser_result_size(job, flags, buf->hasz))
			fail("result size differs from tdc_gser_result_size", NULL);
		if (VARSIZE(out) > tdc_gser_result_bound(buf->n, flags, buf->hasz))
			fail("result larger than tdc_gser_result_bound", NULL);
		got = read_back(out, buf->srid, buf->hasz && m > 0, "result read back");
		if (got != m * per)
			fail("result vertex count differs", NULL);
		/* written in parallel by the core's threads: the same bytes */
		if (flags != TDC_OUT_EDGES && m > 0)
		{
			TdcGserWriter w;
			struct varlena *par = tdc_gser_result_alloc(job, flags, buf, "writer", &w);

			memset(w.members, 0xAA, (size_t) (m * w.member_size));
			if (tdc_job_emit_start(job, tdc_gser_emit, &w, err, sizeof(err)) != TDC_OK ||
				tdc_job_wait(job, -1) != TDC_OK)
				fail("parallel writer failed", err);
			if (VARSIZE(par) != VARSIZE(out) || memcmp(par, out, VARSIZE(out)) != 0)
				fail("parallel writer's bytes differ from the serial writer's", NULL);
		}
	}
	{
		tdc_iter	it = {0};
		uint32		v[3];

		if (tdc_next_triangle(job, &it, v))
		{
			Size		sz = tdc_gser_triangle_size(buf->hasz);
			struct varlena *t = palloc(sz);

			tdc_gser_write_triangle(t, job, v, buf);
			if (VARSIZE(t) != sz)
				fail("triangle size", NULL);
			if (read_back(t, buf->srid, buf->hasz, "triangle read back") != 4)
				fail("triangle vertex count", NULL);
		}
	}
	for (int flags = 0; flags <= 2; flags++)
		if (read_back(tdc_gser_empty(flags, buf->srid), buf->srid, false,
					  "empty read back") != 0)
			fail("empty result has vertices", NULL);
	tdc_job_free(job);
}

int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	struct varlena *v = make_value(data, size);
	struct varlena *sv = make_short_value(data, size);
	TdcPointBuf buf;
	sigjmp_buf	jb;
	Ref			ref;
	const uint8 *rp;
	int32		rsrid = 0;
	bool		ref_ok;
	volatile int stage = 0;
	volatile uint64 n1 = 0;
	TdcCurves	curves;

	FUZZ_PG_STACK_BASE();
	fuzz_pg_max_memory_mb = (size % 7 == 3) ? 1 : 0;

	/* reference: count, then copy */
	/* how curves are read: see the top of this file */
	curves = size % 3 == 0 ? TDC_CURVES_REFUSE :
		size % 3 == 1 ? TDC_CURVES_VERTICES : TDC_CURVES_STROKE;
	memset(&ref, 0, sizeof(ref));
	ref.curves = curves != TDC_CURVES_REFUSE;
	rp = ref_header(&ref, data, size, &rsrid);
	if (rp != NULL)
		rp = ref_walk(&ref, rp, 0);
	ref_ok = rp != NULL && rp == data + size && !ref.nonfinite;
	/* a value to stroke goes to the shim's ST_CurveToLine, which refuses */
	if (curves == TDC_CURVES_STROKE && ref.arcs)
		ref_ok = false;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = curves;
	if (sigsetjmp(jb, 0) == 0)
	{
		fuzz_pg_jmp = &jb;
		tdc_gser_append(&buf, v, "fuzz");
		stage = 1;
		n1 = buf.n;
		/* again, packed when short enough: it must read the same */
		tdc_gser_append(&buf, sv ? sv : v, "fuzz");
		stage = 2;
	}
	fuzz_pg_jmp = NULL;

	if (getenv("FUZZ_VERBOSE"))
		fprintf(stderr, "stage %d: %llu vertices, srid %d, z %d, nesting %d%s%s\n",
				stage, (unsigned long long) n1, (int) buf.srid, (int) buf.hasz,
				ref.maxdepth, stage < 2 ? ", error: " : "",
				stage < 2 ? fuzz_pg_message : "");

	if (stage == 0)
	{
		/* rejected: the reference must reject too, unless a limit applies */
		if (ref_ok &&
			fuzz_pg_sqlstate != ERRCODE_STATEMENT_TOO_COMPLEX &&
			fuzz_pg_sqlstate != ERRCODE_PROGRAM_LIMIT_EXCEEDED &&
			fuzz_pg_sqlstate != ERRCODE_OUT_OF_MEMORY)
			fail("reader rejected a value the reference accepts", fuzz_pg_message);
		if (ref_ok && fuzz_pg_sqlstate == ERRCODE_STATEMENT_TOO_COMPLEX &&
			ref.maxdepth < MIN_TOO_DEEP)
			fail("stack depth limit at a shallow nesting", fuzz_pg_message);
	}
	else if (stage == 1)
	{
		/* the second append can only hit the memory limit */
		if (fuzz_pg_sqlstate != ERRCODE_PROGRAM_LIMIT_EXCEEDED &&
			fuzz_pg_sqlstate != ERRCODE_OUT_OF_MEMORY)
			fail("second append of an accepted value failed", fuzz_pg_message);
	}
	else
	{
		if (!ref_ok)
			fail("reader accepted a value the reference rejects", NULL);
		if (buf.n != 2 * n1 || n1 != ref.count)
			fail("vertex count differs from the reference", NULL);
		if (buf.srid != rsrid || buf.hasz != ref.hasz)
			fail("SRID or Z differs from the reference", NULL);
		if (buf.n > buf.cap)
			fail("buffer overfilled", NULL);
		if (n1 > 0)
		{
			ref.xy = malloc(16 * n1);
			ref.z = malloc(8 * n1);
			ref.count = 0;
			(void) ref_walk(&ref, ref_header(&ref, data, size, &rsrid), 0);
			if (memcmp(ref.xy, buf.xy, 16 * n1) != 0 ||
				memcmp(ref.xy, buf.xy + 2 * n1, 16 * n1) != 0)
				fail("coordinates differ from the reference", NULL);
			if (buf.hasz && (memcmp(ref.z, buf.z, 8 * n1) != 0 ||
							 memcmp(ref.z, buf.z + n1, 8 * n1) != 0))
				fail("Z values differ from the reference", NULL);
			free(ref.xy);
			free(ref.z);
		}
		if (buf.n >= 3 && buf.n <= 4000)
		{
			if (sigsetjmp(jb, 0) == 0)
			{
				fuzz_pg_jmp = &jb;
				writer_roundtrip(&buf);
			}
			else
				fail("writer raised an ERROR", fuzz_pg_message);
			fuzz_pg_jmp = NULL;
		}
	}
	fuzz_pg_reset();
	free(v);
	free(sv);
	return 0;
}
