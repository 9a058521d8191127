/*
 * gser_write.c
 *		Write triangulations as PostGIS geometry values.
 *
 * Results are written in version 2 of the format (gser_format.h) with the
 * Z flag when the input had Z.  Non-empty collections carry a bounding box,
 * as PostGIS writes them: float bounds rounded outward from the exact
 * extent of the vertices.  Without one, every PostGIS function that
 * deserializes the result (even ST_NumGeometries) first walks all its
 * vertices to compute it.  All parts of the format are multiples of 8
 * bytes, so the doubles stay aligned.
 *
 * Every member of a collection result has the same size, so member k starts
 * at a known offset and the members can be written in any order, by any
 * thread: the core's workers (tdc_gser_emit) or this thread
 * (tdc_gser_fill).  A triangle is written by put_triangle alone, whether as
 * a member of a collection, of a TIN, or as a POLYGON value of its own
 * (tdc_gser_write_triangle, one row of ST_TDCDelaunayDump), so the three
 * writers cannot disagree on its bytes.
 */
#include "postgres.h"

#include <math.h>

#include "miscadmin.h"

#include "tdc_pg.h"
#include "gser_format.h"

/*
 * Members written between two interrupt checks when this thread writes a
 * result (tdc_gser_fill): a member is a few dozen bytes, so 65536 of them
 * are a few MB and a few ms of work.  A power of two.
 */
#define FILL_POLL_MEMBERS	65536

/*
 * Input vertices looked at between two interrupt checks while the Z range
 * of the bounding box is taken: a vertex costs one lookup in the input map,
 * so checks 2^20 vertices apart are still a few ms apart.  A power of two.
 */
#define ZBOX_POLL_VERTICES	((uint64) 1 << 20)

/* Bytes of one member of a result (without the value's header). */
static uint64
member_size(int flags, bool hasz)
{
	uint64		vtx = (hasz ? 3 : 2) * sizeof(double);

	switch (flags)
	{
		case TDC_OUT_POLYGONS:
			return 16 + 4 * vtx;	/* type, nrings, npoints, pad, ring */
		case TDC_OUT_EDGES:
			return 8 + 2 * vtx; /* type, npoints, 2 vertices */
		case TDC_OUT_TIN:
			return 8 + 4 * vtx; /* type, npoints, closed ring */
	}
	return 0;
}

static uint64
member_count(const tdc_job *job, int flags)
{
	return flags == TDC_OUT_EDGES ? tdc_num_edges(job) : tdc_num_triangles(job);
}

/* Bytes of the float bounding box: min and max per dimension. */
static uint64
box_size(bool hasz)
{
	return (hasz ? 6 : 4) * sizeof(float);
}

static void
write_header(char *out, Size size, int32 srid, bool hasz, bool hasbox)
{
	unsigned char *h = (unsigned char *) VARDATA(out);
	uint32		s = (uint32) srid & 0x1fffff;

	SET_VARSIZE(out, size);
	h[0] = (unsigned char) (s >> 16);
	h[1] = (unsigned char) (s >> 8);
	h[2] = (unsigned char) s;
	h[3] = GF_VERSION | (hasz ? GF_Z : 0) | (hasbox ? GF_BBOX : 0);
}

/*
 * The largest float not above d, and the smallest not below it: a float box
 * must contain the double coordinates it bounds.  Beyond the float range
 * they give +-FLT_MAX and +-Inf, still bounds.
 */
float
tdc_float_down(double d)
{
	float		f = (float) d;

	return (double) f <= d ? f : nextafterf(f, -INFINITY);
}

float
tdc_float_up(double d)
{
	float		f = (float) d;

	return (double) f >= d ? f : nextafterf(f, INFINITY);
}

/*
 * Write the bounding box of a non-empty result at p: xmin, xmax, ymin, ymax
 * and with Z zmin, zmax.  The vertices of a result are exactly the kept
 * sites, and the Z written for a site is that of its first input point, so
 * the Z range is taken over those inputs only: input i is one when the site
 * it became names it as its first.
 */
static char *
put_box(char *p, const tdc_job *job, const TdcPointBuf *buf, bool hasz,
		const char *fname)
{
	double		lo[2],
				hi[2];
	float		box[6];

	tdc_site_extent(job, lo, hi);
	box[0] = tdc_float_down(lo[0]);
	box[1] = tdc_float_up(hi[0]);
	box[2] = tdc_float_down(lo[1]);
	box[3] = tdc_float_up(hi[1]);
	if (hasz)
	{
		double		zlo = INFINITY,
					zhi = -INFINITY;

		for (uint64 i = 0; i < buf->n; i++)
		{
			uint32		site = tdc_input_site(job, (size_t) i);

			if (site == UINT32_MAX)
				ereport(ERROR,
						(errcode(ERRCODE_OUT_OF_MEMORY),
						 errmsg("%s: out of memory for the input-to-site map", fname)));
			if (tdc_site_input(job, site) == i)
			{
				zlo = Min(zlo, buf->z[i]);
				zhi = Max(zhi, buf->z[i]);
			}
			if ((i & (ZBOX_POLL_VERTICES - 1)) == 0)
				CHECK_FOR_INTERRUPTS();
		}
		box[4] = tdc_float_down(zlo);
		box[5] = tdc_float_up(zhi);
	}
	memcpy(p, box, box_size(hasz));
	return p + box_size(hasz);
}

static inline char *
put_u32(char *p, uint32 v)
{
	memcpy(p, &v, sizeof(v));
	return p + sizeof(v);
}

static inline char *
put_vertex(char *p, const tdc_job *job, uint32 site, const TdcPointBuf *buf,
		   bool hasz)
{
	const double *xy = tdc_site_xy(job, site);

	memcpy(p, xy, 2 * sizeof(double));
	p += 2 * sizeof(double);
	if (hasz)
	{
		double		z = buf->z[tdc_site_input(job, site)];

		memcpy(p, &z, sizeof(double));
		p += sizeof(double);
	}
	return p;
}

/*
 * One triangle as a POLYGON (a member of a collection, or a value of its
 * own) or as a TRIANGLE (a member of a TIN); member_size(flags, hasz) bytes.
 * The only place a triangle's bytes are written.
 */
static inline char *
put_triangle(char *p, const tdc_job *job, const TdcPointBuf *buf, int flags,
			 bool hasz, const uint32 *v)
{
	if (flags == TDC_OUT_POLYGONS)
	{
		p = put_u32(p, G_POLYGON);
		p = put_u32(p, 1);
		p = put_u32(p, 4);
		p = put_u32(p, 0);		/* padding */
	}
	else
	{
		p = put_u32(p, G_TRIANGLE);
		p = put_u32(p, 4);
	}
	p = put_vertex(p, job, v[0], buf, hasz);
	p = put_vertex(p, job, v[1], buf, hasz);
	p = put_vertex(p, job, v[2], buf, hasz);
	return put_vertex(p, job, v[0], buf, hasz);
}

/* Size of the whole result value, header included. */
uint64
tdc_gser_result_size(const tdc_job *job, int flags, bool hasz)
{
	uint64		m = member_count(job, flags);

	if (m == 0)
		return VARHDRSZ + G_HEADER + 8;
	return VARHDRSZ + G_HEADER + box_size(hasz) + 8 + m * member_size(flags, hasz);
}

/* Upper bound of the result size for n input vertices (2n triangles, 3n edges). */
uint64
tdc_gser_result_bound(uint64 n, int flags, bool hasz)
{
	uint64		m = (flags == TDC_OUT_EDGES ? 3 : 2) * n;

	return VARHDRSZ + G_HEADER + box_size(hasz) + 8 + m * member_size(flags, hasz);
}

/*
 * Huge pages for a result value just palloc'd, where they map in fast
 * (tdc_advise_huge), a slice at a time with an interrupt check between: a
 * value of a few hundred MB of warm huge pages takes tens of ms to map in,
 * and a cancel must not wait for it.  Slices end on 32 MB boundaries, so no
 * 2 MB page is cut between two of them.
 */
#define RESULT_SLICE	((uintptr_t) 32 << 20)

void
tdc_advise_result(void *out, Size size)
{
	uintptr_t	p = (uintptr_t) out,
				end = p + size;

	while (p < end)
	{
		uintptr_t	next = (p & ~(RESULT_SLICE - 1)) + RESULT_SLICE;

		if (next > end)
			next = end;
		if (!tdc_advise_huge((void *) p, (size_t) (next - p)))
			break;
		p = next;
		CHECK_FOR_INTERRUPTS();
	}
}

void
tdc_gser_check_result_size(uint64 size, const char *fname)
{
	if (size > (uint64) tdc_guc_max_result_bytes)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: result of %llu bytes exceeds the limit of %d bytes for a single value",
						fname, (unsigned long long) size,
						tdc_guc_max_result_bytes),
				 errhint("Use ST_TDCDelaunayDump(query) to get one row per triangle.")));
}

/*
 * Allocate the whole result value and write its header and member count;
 * the members are left to tdc_gser_emit or tdc_gser_fill.  Every member of a
 * result has the same size, so member k starts at a known offset and the
 * members can be written in any order, by any thread.
 */
struct varlena *
tdc_gser_result_alloc(const tdc_job *job, int flags, const TdcPointBuf *buf,
					  const char *fname, TdcGserWriter *w)
{
	uint64		m = member_count(job, flags);
	bool		hasz = buf->hasz && m > 0;
	uint64		size = tdc_gser_result_size(job, flags, buf->hasz);
	char	   *out;
	char	   *p;

	tdc_gser_check_result_size(size, fname);

	out = palloc((Size) size);
	tdc_advise_result(out, (Size) size);
	write_header(out, (Size) size, buf->srid, hasz, m > 0);
	p = VARDATA(out) + G_HEADER;
	if (m > 0)
		p = put_box(p, job, buf, hasz, fname);
	p = put_u32(p, flags == TDC_OUT_POLYGONS ? G_COLLECTION :
				flags == TDC_OUT_EDGES ? G_MULTILINE : G_TIN);
	p = put_u32(p, (uint32) m);

	w->job = job;
	w->buf = buf;
	w->flags = flags;
	w->hasz = hasz;
	w->members = p;
	w->member_size = member_size(flags, hasz);
	w->count = m;
	w->fname = fname;
	return (struct varlena *) out;
}

/*
 * tdc_emit_fn for triangle results: runs on the core's worker threads, so it
 * only copies bytes; the ranges it gets are disjoint and within the count
 * the value was sized for (the core checks both).
 */
void
tdc_gser_emit(void *arg, size_t first, size_t count, const uint32 *v)
{
	const TdcGserWriter *w = arg;
	char	   *p = w->members + first * w->member_size;

	/*
	 * A result of two million triangles is 160 MB of fresh memory: taking
	 * it a page fault at a time cost a third of the writing.
	 */
	tdc_prefault(p, count * w->member_size);
	for (size_t i = 0; i < count; i++)
		p = put_triangle(p, w->job, w->buf, w->flags, w->hasz, v + 3 * i);
}

/* Write all members on this thread, checking for interrupts as it goes. */
void
tdc_gser_fill(const TdcGserWriter *w)
{
	char	   *p = w->members;
	tdc_iter	it;
	uint64		written = 0;

	it.pos = 0;
	if (w->flags == TDC_OUT_EDGES)
	{
		uint32		v[2];

		while (tdc_next_edge(w->job, &it, v))
		{
			if (written++ >= w->count)
				elog(ERROR, "%s: core returned more edges than it counted", w->fname);
			if ((written & (FILL_POLL_MEMBERS - 1)) == 0)
				CHECK_FOR_INTERRUPTS();
			p = put_u32(p, G_LINE);
			p = put_u32(p, 2);
			p = put_vertex(p, w->job, v[0], w->buf, w->hasz);
			p = put_vertex(p, w->job, v[1], w->buf, w->hasz);
		}
	}
	else
	{
		uint32		v[3];

		while (tdc_next_triangle(w->job, &it, v))
		{
			if (written++ >= w->count)
				elog(ERROR, "%s: core returned more triangles than it counted", w->fname);
			if ((written & (FILL_POLL_MEMBERS - 1)) == 0)
				CHECK_FOR_INTERRUPTS();
			p = put_triangle(p, w->job, w->buf, w->flags, w->hasz, v);
		}
	}
	if (written != w->count || p != w->members + w->count * w->member_size)
		elog(ERROR, "%s: core returned %llu of %llu counted %s", w->fname,
			 (unsigned long long) written, (unsigned long long) w->count,
			 w->flags == TDC_OUT_EDGES ? "edges" : "triangles");
}

/*
 * The whole triangulation as one geometry value, written on this thread:
 * GEOMETRYCOLLECTION of POLYGON, MULTILINESTRING or TIN.
 */
struct varlena *
tdc_gser_result(const tdc_job *job, int flags, const TdcPointBuf *buf,
				const char *fname)
{
	TdcGserWriter w;
	struct varlena *out = tdc_gser_result_alloc(job, flags, buf, fname, &w);

	tdc_gser_fill(&w);
	return out;
}

/*
 * A MULTILINESTRING of "count" edges that next() hands out one at a time as
 * pairs of the job's sites: a chosen subset of the triangulation's edges
 * (the constraint edges of a constrained triangulation).  Written without a
 * bounding box, since the edges may span less than the job's sites; PostGIS
 * computes a missing box when it needs one.
 */
struct varlena *
tdc_gser_edge_list(const tdc_job *job, const TdcPointBuf *buf, uint64 count,
				   bool (*next) (void *arg, uint32 v[2]), void *arg,
				   const char *fname)
{
	bool		hasz = buf->hasz && count > 0;
	uint64		msize = member_size(TDC_OUT_EDGES, hasz);
	uint64		size = VARHDRSZ + G_HEADER + 8 + count * msize;
	uint64		written = 0;
	uint32		v[2];
	char	   *out;
	char	   *p;

	tdc_gser_check_result_size(size, fname);
	out = palloc((Size) size);
	tdc_advise_result(out, (Size) size);
	write_header(out, (Size) size, buf->srid, hasz, false);
	p = VARDATA(out) + G_HEADER;
	p = put_u32(p, G_MULTILINE);
	p = put_u32(p, (uint32) count);
	while (next(arg, v))
	{
		if (written++ >= count)
			elog(ERROR, "%s: core returned more edges than it counted", fname);
		if ((written & (FILL_POLL_MEMBERS - 1)) == 0)
			CHECK_FOR_INTERRUPTS();
		p = put_u32(p, G_LINE);
		p = put_u32(p, 2);
		p = put_vertex(p, job, v[0], buf, hasz);
		p = put_vertex(p, job, v[1], buf, hasz);
	}
	if (written != count || p != out + size)
		elog(ERROR, "%s: core returned %llu of %llu counted edges", fname,
			 (unsigned long long) written, (unsigned long long) count);
	return (struct varlena *) out;
}

/* An empty result of the given kind (2D, like PostGIS). */
struct varlena *
tdc_gser_empty(int flags, int32 srid)
{
	Size		size = VARHDRSZ + G_HEADER + 8;
	char	   *out = palloc(size);
	char	   *p;

	write_header(out, size, srid, false, false);
	p = VARDATA(out) + G_HEADER;
	p = put_u32(p, flags == TDC_OUT_POLYGONS ? G_COLLECTION :
				flags == TDC_OUT_EDGES || flags == TDC_OUT_CONSTRAINTS ? G_MULTILINE : G_TIN);
	(void) put_u32(p, 0);
	return (struct varlena *) out;
}

/* Size of one POLYGON value as written by tdc_gser_write_triangle. */
Size
tdc_gser_triangle_size(bool hasz)
{
	return VARHDRSZ + G_HEADER + member_size(TDC_OUT_POLYGONS, hasz);
}

/* Write one triangle as a POLYGON value into out (tdc_gser_triangle_size). */
void
tdc_gser_write_triangle(struct varlena *out, const tdc_job *job,
						const uint32 v[3], const TdcPointBuf *buf)
{
	char	   *p;

	write_header((char *) out, tdc_gser_triangle_size(buf->hasz), buf->srid,
				 buf->hasz, false);
	p = VARDATA(out) + G_HEADER;
	(void) put_triangle(p, job, buf, TDC_OUT_POLYGONS, buf->hasz, v);
}

/*
 * Write the triangle of the three vertices at v (dim = 2 or 3 doubles
 * each, in order) as a POLYGON value into out (tdc_gser_triangle_size):
 * the bytes tdc_gser_write_triangle writes for the same vertices, for
 * callers that hold coordinates rather than a job (the tiled runs).
 */
void
tdc_gser_write_triangle_coords(struct varlena *out, const double *v, int dim, int32 srid)
{
	char	   *p;
	Size		vb = (Size) dim * sizeof(double);

	write_header((char *) out, tdc_gser_triangle_size(dim == 3), srid, dim == 3, false);
	p = VARDATA(out) + G_HEADER;
	p = put_u32(p, G_POLYGON);
	p = put_u32(p, 1);
	p = put_u32(p, 4);
	p = put_u32(p, 0);			/* padding */
	memcpy(p, v, 3 * vb);
	memcpy(p + 3 * vb, v, vb);
}
