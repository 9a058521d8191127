/*
 * gserialized.c
 *		Read PostGIS geometry values into a point buffer, write
 *		triangulations back as geometry values.
 *
 * A triangulation only needs the vertices of its input, and going through
 * liblwgeom for that (deserialize to an LWGEOM, walk it, copy points out)
 * costs more than the triangulation of a small geometry.  So we read the
 * on-disk format directly.  PostGIS 3 stores a geometry as
 *
 *	varlena header (4 bytes after detoasting)
 *	srid[3]			21-bit signed SRID, big-endian-ish: high 5 bits first
 *	gflags			Z 0x01, M 0x02, BBOX 0x04, GEODETIC 0x08,
 *					EXTENDED 0x10 (v2), VERSION 0x40 (set = v2)
 *	[uint64]		extended flags, v2 only, when EXTENDED is set
 *	[float box]		when BBOX is set: 2 floats per dimension (6 if geodetic)
 *	geometry		uint32 type, uint32 count, then
 *					  point/line/triangle/circularstring: count vertices
 *					  polygon: count ring sizes, padded to 8 bytes, then the
 *						rings' vertices
 *					  multi and collection types: count nested geometries
 *
 * Vertices are doubles, 2 to 4 per vertex (XY, XYZ, XYM, XYZM).  Version 1
 * (PostGIS 2, possibly still on disk after pg_upgrade) differs only in the
 * flags byte: no EXTENDED flag, 0x10 is a read-only bit we ignore.
 *
 * A value is read once, front to back, and may arrive in pieces: a value in
 * memory is one piece, a big TOASTed value read by ST_TDCDelaunayTriangles
 * comes a slice at a time (tdc_funcs.c), so it is never whole in memory and
 * an interrupt is answered between slices.  Every count read from a value is
 * checked against the bytes that remain in the whole value before it is
 * used, with 64-bit arithmetic, whether those bytes have arrived or not, so
 * a corrupt value gives an ERROR (with the same byte offset however it was
 * split) and never a read outside the value.  Vertices go straight from the
 * piece into the point buffer, which grows as point lists are met (by
 * doubling, with mremap); NaN and infinities are rejected.  An ERROR half-way
 * leaves the vertices read so far in the buffer: every caller gives the
 * buffer up on an ERROR.  Curves are rejected: PostGIS would stroke them
 * into segments first, with a precision we should not guess for the user,
 * so we ask for an explicit ST_CurveToLine.
 *
 * Results are written in version 2 with the Z flag when the input had Z.
 * Non-empty collections carry a bounding box, as PostGIS writes them: float
 * bounds rounded outward from the exact extent of the vertices.  Without
 * one, every PostGIS function that deserializes the result (even
 * ST_NumGeometries) first walks all its vertices to compute it.  All parts
 * of the format are multiples of 8 bytes, so the doubles stay aligned.
 */
#include "postgres.h"

#include <math.h>
#include <sys/mman.h>

#include "miscadmin.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

/* Geometry type numbers of the serialized format. */
#define G_POINT				1
#define G_LINE				2
#define G_POLYGON			3
#define G_MULTIPOINT		4
#define G_MULTILINE			5
#define G_MULTIPOLYGON		6
#define G_COLLECTION		7
#define G_CIRCSTRING		8
#define G_COMPOUND			9
#define G_CURVEPOLY			10
#define G_MULTICURVE		11
#define G_MULTISURFACE		12
#define G_POLYHEDRAL		13
#define G_TRIANGLE			14
#define G_TIN				15

/* Flag bits. */
#define GF_Z				0x01
#define GF_M				0x02
#define GF_BBOX				0x04
#define GF_GEODETIC			0x08
#define GF_EXTENDED			0x10
#define GF_VERSION			0x40

/* srid[3] + gflags */
#define G_HEADER			4

/*
 * A value being walked.  Its bytes arrive in pieces: one piece for a value
 * in memory, a slice at a time for a big TOASTed value (TdcGserSource).
 * p .. pend are the unread bytes of the current piece and pend_pos is the
 * offset of pend in the value, so the bytes left in the whole value are
 * always known, and every count is checked against them before it is used,
 * whether or not those bytes have arrived yet.
 */
typedef struct GserWalk
{
	const char *p;				/* unread bytes of the current piece */
	const char *pend;
	uint64		pend_pos;		/* offset of pend in the value */
	uint64		size;			/* bytes of the value after its varlena header */
	TdcGserSource *src;			/* the further pieces; NULL: there are none */
	int			hdrsz;			/* bytes of the varlena header (for messages) */
	int			ndims;			/* doubles per vertex */
	Size		vsize;			/* bytes per vertex */
	bool		hasz;
	TdcPointBuf *buf;
	const char *fname;
} GserWalk;

/*
 * Vertices stored between two interrupt checks when a piece holds more: a
 * value in memory is one piece of up to 1 GB.  A few ms of work.
 */
#define WALK_BATCH			65536

/* Vertices worth a system call to map in their pages ahead (64 kB). */
#define PREFAULT_MIN		4096

static const char *
curve_name(uint32 type)
{
	switch (type)
	{
		case G_CIRCSTRING:
			return "CIRCULARSTRING";
		case G_COMPOUND:
			return "COMPOUNDCURVE";
		case G_CURVEPOLY:
			return "CURVEPOLYGON";
		case G_MULTICURVE:
			return "MULTICURVE";
		case G_MULTISURFACE:
			return "MULTISURFACE";
	}
	return "curve";
}

/* pos: offset in the value (after its varlena header) of what is wrong */
static void
corrupt(const GserWalk *w, uint64 pos, const char *what)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: corrupt geometry value: %s at byte %llu of %llu",
					w->fname, what, (unsigned long long) (pos + w->hdrsz),
					(unsigned long long) (w->size + w->hdrsz))));
}

static void
nonfinite(const GserWalk *w)
{
	ereport(ERROR,
			(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
			 errmsg("%s: input has a non-finite coordinate (NaN or Infinity)",
					w->fname)));
}

static inline uint32
read_u32(const char *p)
{
	uint32		v;

	memcpy(&v, p, sizeof(v));
	return v;
}

/* Offset in the value of the next unread byte. */
static inline uint64
walk_pos(const GserWalk *w)
{
	return w->pend_pos - (uint64) (w->pend - w->p);
}

static inline uint64
walk_left(const GserWalk *w)
{
	return w->size - walk_pos(w);
}

/*
 * Move on to the next non-empty piece.  Only called when the value has
 * bytes left, so a source that runs dry, or hands over more than the value
 * holds, is a bug in the source, not a corrupt value.
 */
static void
next_piece(GserWalk *w)
{
	while (w->p == w->pend)
	{
		const char *data;
		Size		len;

		if (w->src == NULL || !w->src->next(w->src, &data, &len))
			elog(ERROR, "%s: geometry value ended after %llu of its %llu bytes",
				 w->fname, (unsigned long long) w->pend_pos,
				 (unsigned long long) w->size);
		if (len > w->size - w->pend_pos)
			elog(ERROR, "%s: geometry value longer than its %llu bytes",
				 w->fname, (unsigned long long) w->size);
		w->p = data;
		w->pend = data + len;
		w->pend_pos += len;
	}
}

/* Copy the next n bytes to dst (or skip them: dst NULL); they must remain. */
static void
read_bytes(GserWalk *w, void *dst, uint64 n)
{
	char	   *d = dst;

	Assert(n <= walk_left(w));
	while (n > 0)
	{
		Size		k;

		if (w->p == w->pend)
			next_piece(w);
		k = (Size) Min(n, (uint64) (w->pend - w->p));
		if (d != NULL)
		{
			memcpy(d, w->p, k);
			d += k;
		}
		w->p += k;
		n -= k;
	}
}

/*
 * Store the vertex at v at xy (and z): x and y for the core, z aside, m
 * dropped.  Returns false when a coordinate kept is not finite (the caller
 * raises the error, so that loops over many vertices have no branch).
 */
static inline bool
store_vertex(const char *v, double *xy, double *z)
{
	double		c[3];

	memcpy(c, v, 2 * sizeof(double));
	xy[0] = c[0];
	xy[1] = c[1];
	if (z == NULL)
		return isfinite(c[0]) & isfinite(c[1]);
	memcpy(&c[2], v + 2 * sizeof(double), sizeof(double));
	z[0] = c[2];
	return isfinite(c[0]) & isfinite(c[1]) & isfinite(c[2]);
}

/* The same for n vertices in a row. */
static bool
store_vertices(const GserWalk *w, const char *v, Size n, double *xy,
			   double *z)
{
	bool		ok = true;

	if (w->ndims == 2)
	{
		memcpy(xy, v, n * 2 * sizeof(double));
		for (Size i = 0; i < 2 * n; i++)
			ok &= isfinite(xy[i]);
		return ok;
	}
	for (Size i = 0; i < n; i++)
		ok &= store_vertex(v + i * w->vsize, xy + 2 * i, z ? z + i : NULL);
	return ok;
}

/*
 * About to store n vertices at the end of the buffer: map in their pages in
 * one call rather than a page fault at a time (the buffer of a big value is
 * fresh memory, tens of MB).  Small batches are left to fault as usual.
 */
static void
prefault_batch(const TdcPointBuf *buf, Size n)
{
	if (n < PREFAULT_MIN)
		return;
	tdc_prefault(buf->xy + 2 * buf->n, n * 2 * sizeof(double));
	if (buf->z != NULL)
		tdc_prefault(buf->z + buf->n, n * sizeof(double));
}

/* The vertices of one point list, appended to the buffer. */
static void
walk_points(GserWalk *w, uint32 npoints)
{
	TdcPointBuf *buf = w->buf;
	uint32		left = npoints;

	if ((uint64) npoints * w->vsize > walk_left(w))
		corrupt(w, walk_pos(w), "vertex list longer than the value");
	if (npoints == 0)
		return;
	tdc_pointbuf_reserve(buf, npoints, w->fname);

	while (left > 0)
	{
		double	   *xy = buf->xy + 2 * buf->n;
		double	   *z = w->hasz ? buf->z + buf->n : NULL;
		Size		k;
		bool		ok;

		if (w->p == w->pend)
			next_piece(w);
		k = Min(Min((Size) left, WALK_BATCH), (Size) (w->pend - w->p) / w->vsize);
		if (k > 0)
		{
			prefault_batch(buf, k);
			ok = store_vertices(w, w->p, k, xy, z);
			w->p += k * w->vsize;
		}
		else
		{
			/* a vertex split between two pieces */
			char		v[4 * sizeof(double)];

			read_bytes(w, v, w->vsize);
			ok = store_vertices(w, v, 1, xy, z);
			k = 1;
		}
		if (!ok)
			nonfinite(w);
		buf->n += k;
		left -= (uint32) k;
		CHECK_FOR_INTERRUPTS();
	}
}

static void walk_geom(GserWalk *w);

/*
 * The members of a MULTIPOINT.  Each one is a whole geometry, in principle
 * of any type, but nearly always a point with one vertex: those are stored
 * straight from the piece, a batch at a time, with fixed-size copies, and
 * anything else (an empty point, a member split between pieces, a member of
 * another type) goes through walk_geom.  (Storing each point through the
 * general path, a variable-size memcpy per point, took half the samples of
 * reading a 5-million-point value, page faults of the buffer included.)
 */
static void
walk_multipoint(GserWalk *w, uint32 count)
{
	TdcPointBuf *buf = w->buf;
	Size		msize = 8 + w->vsize;
	uint32		left = count;

	/* each point of one vertex takes msize bytes: no more can be there */
	tdc_pointbuf_reserve(buf, Min((uint64) count, walk_left(w) / msize),
						 w->fname);
	while (left > 0)
	{
		Size		k = Min(Min((Size) left, WALK_BATCH),
							(Size) (w->pend - w->p) / msize);
		Size		i = 0;

		if (k > 0)
		{
			double	   *xy;
			double	   *z;
			bool		ok = true;

			tdc_pointbuf_reserve(buf, k, w->fname);
			prefault_batch(buf, k);
			xy = buf->xy + 2 * buf->n;
			z = w->hasz ? buf->z + buf->n : NULL;
			for (; i < k; i++)
			{
				const char *m = w->p + i * msize;

				if (read_u32(m) != G_POINT || read_u32(m + 4) != 1)
					break;
				ok &= store_vertex(m + 8, xy + 2 * i, z ? z + i : NULL);
			}
			if (!ok)
				nonfinite(w);
			w->p += i * msize;
			buf->n += i;
			left -= (uint32) i;
		}
		if (i < k || k == 0)
		{
			/* one member the loop does not take */
			walk_geom(w);
			left--;
		}
		CHECK_FOR_INTERRUPTS();
	}
}

/* One nested geometry starting at the next unread byte. */
static void
walk_geom(GserWalk *w)
{
	uint64		at = walk_pos(w);
	uint32		type;
	uint32		count;
	uint32		i;

	check_stack_depth();
	CHECK_FOR_INTERRUPTS();

	if (walk_left(w) < 8)
		corrupt(w, at, "truncated geometry header");
	if (w->pend - w->p >= 8)
	{
		type = read_u32(w->p);
		count = read_u32(w->p + 4);
		w->p += 8;
	}
	else
	{
		char		h[8];

		read_bytes(w, h, 8);
		type = read_u32(h);
		count = read_u32(h + 4);
	}

	switch (type)
	{
		case G_POINT:
			if (count > 1)
				corrupt(w, at, "point with more than one vertex");
			/* FALLTHROUGH */
		case G_LINE:
		case G_TRIANGLE:
			walk_points(w, count);
			return;

		case G_POLYGON:
			{
				uint32		small[16];
				uint32	   *rings = small;
				uint64		hdr = (uint64) count * 4;

				if (count % 2)
					hdr += 4;	/* padding to 8 bytes */
				if (hdr > walk_left(w))
					corrupt(w, walk_pos(w), "ring count larger than the value");
				/* the ring sizes come first, the rings after all of them */
				if (hdr > sizeof(small))
					rings = palloc((Size) hdr);
				read_bytes(w, rings, hdr);
				for (i = 0; i < count; i++)
					walk_points(w, rings[i]);
				if (rings != small)
					pfree(rings);
				return;
			}

		case G_MULTIPOINT:
			walk_multipoint(w, count);
			return;

		case G_MULTILINE:
		case G_MULTIPOLYGON:
		case G_COLLECTION:
		case G_POLYHEDRAL:
		case G_TIN:
			/* every member takes at least 8 bytes: the loop is bounded */
			for (i = 0; i < count; i++)
				walk_geom(w);
			return;

		case G_CIRCSTRING:
		case G_COMPOUND:
		case G_CURVEPOLY:
		case G_MULTICURVE:
		case G_MULTISURFACE:
			ereport(ERROR,
					(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
					 errmsg("%s: curved geometries (%s) are not supported",
							w->fname, curve_name(type)),
					 errhint("Convert them to line segments first with ST_CurveToLine.")));
	}
	corrupt(w, at, psprintf("unknown geometry type %u", type));
}

static int32
read_srid(const unsigned char *s)
{
	int32		srid = ((int32) (s[0] & 0x1f) << 16) | ((int32) s[1] << 8) | s[2];

	/* sign-extend the 21-bit value */
	if (srid & 0x100000)
		srid -= 0x200000;
	return srid;
}

/*
 * Read the value's header (SRID, flags, optional extended flags and box) and
 * set the vertex layout; returns the SRID.
 */
static int32
walk_header(GserWalk *w)
{
	unsigned char hdr[G_HEADER];
	uint8		gflags;
	bool		hasm;

	if (w->size < G_HEADER)
		corrupt(w, 0, "value shorter than its header");
	read_bytes(w, hdr, G_HEADER);
	gflags = hdr[3];
	w->hasz = (gflags & GF_Z) != 0;
	hasm = (gflags & GF_M) != 0;
	w->ndims = 2 + (w->hasz ? 1 : 0) + (hasm ? 1 : 0);
	w->vsize = w->ndims * sizeof(double);

	if ((gflags & GF_VERSION) && (gflags & GF_EXTENDED))
	{
		if (walk_left(w) < 8)
			corrupt(w, walk_pos(w), "truncated extended flags");
		read_bytes(w, NULL, 8);
	}
	if (gflags & GF_BBOX)
	{
		uint64		boxbytes = sizeof(float) *
			((gflags & GF_GEODETIC) ? 6 : 2 * w->ndims);

		if (walk_left(w) < boxbytes)
			corrupt(w, walk_pos(w), "truncated bounding box");
		read_bytes(w, NULL, boxbytes);
	}
	return read_srid(hdr);
}

/* The geometry after the header: all its vertices into the buffer. */
static void
walk_value(GserWalk *w, int32 srid)
{
	tdc_pointbuf_check_meta(w->buf, srid, w->hasz, w->fname);
	walk_geom(w);
	if (walk_left(w) != 0)
		corrupt(w, walk_pos(w), "trailing bytes after the geometry");
}

/* ----------------------------------------------------------------
 *		point buffer
 * ----------------------------------------------------------------
 */

/*
 * Big coordinate arrays are mapped directly, not palloc'd: a big aggregate
 * grows them to hundreds of megabytes, and once freed, malloc keeps blocks
 * below its (self-raising) mmap threshold in the backend's heap, so a
 * session's memory would depend on the sizes of the inputs it saw before.
 * Mappings grow with mremap, which moves pages instead of copying bytes,
 * and go back to the system when the buffer's context is reset or deleted.
 * The release callback is registered before any triangulation job's (whose
 * workers read the array) and so runs after it.
 *
 * Arrays below POINTMAP_MIN_BYTES are palloc'd in the buffer's context
 * instead: one call per row on a small geometry would otherwise pay a map,
 * its page faults and an unmap (with a TLB flush on every CPU the process
 * ran threads on) for a few dozen bytes of coordinates.
 */
#define POINTMAP_MIN_BYTES	((Size) 256 * 1024)

static void
pointmap_release(void *arg)
{
	TdcPointMap *map = (TdcPointMap *) arg;

	/* palloc'd arrays go with the context */
	if (map->xy != NULL && map->xy_bytes >= POINTMAP_MIN_BYTES)
		munmap(map->xy, map->xy_bytes);
	if (map->z != NULL && map->z_bytes >= POINTMAP_MIN_BYTES)
		munmap(map->z, map->z_bytes);
	map->xy = map->z = NULL;
}

static double *
pointmap_grow(MemoryContext cxt, double **ptr, Size *bytes, Size want)
{
	void	   *p;

	if (want < POINTMAP_MIN_BYTES)
		p = *ptr == NULL ? MemoryContextAlloc(cxt, want) : repalloc(*ptr, want);
	else if (*ptr != NULL && *bytes >= POINTMAP_MIN_BYTES)
		p = mremap(*ptr, *bytes, want, MREMAP_MAYMOVE);
	else
	{
		p = mmap(NULL, want, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
		if (p != MAP_FAILED && *ptr != NULL)
		{
			memcpy(p, *ptr, *bytes);
			pfree(*ptr);
		}
	}
	if (p == MAP_FAILED)
		ereport(ERROR,
				(errcode(ERRCODE_OUT_OF_MEMORY),
				 errmsg("out of memory"),
				 errdetail("Failed on request of size %zu for input vertices.", want)));
	*ptr = p;
	*bytes = want;
	return p;
}

void
tdc_pointbuf_init(TdcPointBuf *buf, MemoryContext cxt)
{
	memset(buf, 0, sizeof(*buf));
	buf->cxt = cxt;
}

static uint64
pointbuf_bytes_for(uint64 cap, bool hasz)
{
	return cap * (hasz ? 3 : 2) * sizeof(double);
}

uint64
tdc_pointbuf_bytes(const TdcPointBuf *buf)
{
	return pointbuf_bytes_for(buf->cap, buf->hasz);
}

/* Make room for "extra" more vertices, honouring tdc_delaunay.max_memory. */
void
tdc_pointbuf_reserve(TdcPointBuf *buf, uint64 extra, const char *fname)
{
	uint64		need = buf->n + extra;
	uint64		newcap;
	uint64		limit;

	if (need <= buf->cap)
		return;
	limit = tdc_max_memory_bytes();
	if (need > TDC_MAX_POINTS)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: too many input vertices (more than %zu)",
						fname, (size_t) TDC_MAX_POINTS)));

	newcap = Max(buf->cap, 16);
	while (newcap < need)
		newcap *= 2;
	if (newcap > TDC_MAX_POINTS)
		newcap = TDC_MAX_POINTS;
	/* don't let doubling alone trip the memory limit */
	if (limit > 0 && pointbuf_bytes_for(newcap, buf->hasz) > limit)
		newcap = Max(need, limit / ((buf->hasz ? 3 : 2) * sizeof(double)));
	if (limit > 0 && pointbuf_bytes_for(newcap, buf->hasz) > limit)
		tdc_report_memory_limit(fname,
								psprintf("the input of %llu vertices",
										 (unsigned long long) need),
								pointbuf_bytes_for(need, buf->hasz));

	if (buf->map == NULL)
	{
		MemoryContextCallback *cb;

		buf->map = MemoryContextAllocZero(buf->cxt, sizeof(TdcPointMap));
		cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
		cb->func = pointmap_release;
		cb->arg = buf->map;
		MemoryContextRegisterResetCallback(buf->cxt, cb);
	}
	buf->xy = pointmap_grow(buf->cxt, &buf->map->xy, &buf->map->xy_bytes,
							(Size) newcap * 2 * sizeof(double));
	if (buf->hasz)
		buf->z = pointmap_grow(buf->cxt, &buf->map->z, &buf->map->z_bytes,
							   (Size) newcap * sizeof(double));
	buf->cap = newcap;
}

/* The first input fixes SRID and dimensions; later ones must agree. */
void
tdc_pointbuf_check_meta(TdcPointBuf *buf, int32 srid, bool hasz,
						const char *fname)
{
	if (!buf->have_first)
	{
		Assert(buf->n == 0 && buf->xy == NULL);
		buf->have_first = true;
		buf->srid = srid;
		buf->hasz = hasz;
		return;
	}
	if (buf->srid != srid)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: geometries have mixed SRIDs %d and %d",
						fname, Min(buf->srid, srid), Max(buf->srid, srid)),
				 errhint("Transform them to one SRID with ST_Transform or set it with ST_SetSRID.")));
	if (buf->hasz != hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: geometries have mixed dimensions (XY and XYZ)",
						fname),
				 errhint("Use ST_Force2D or ST_Force3DZ to give all inputs the same dimensions.")));
}

/* Append all vertices of src (another aggregate state) to dst. */
void
tdc_pointbuf_append_buf(TdcPointBuf *dst, const TdcPointBuf *src,
						const char *fname)
{
	if (!src->have_first)
		return;
	tdc_pointbuf_check_meta(dst, src->srid, src->hasz, fname);
	if (src->n == 0)
		return;
	tdc_pointbuf_reserve(dst, src->n, fname);
	memcpy(dst->xy + 2 * dst->n, src->xy, (Size) src->n * 2 * sizeof(double));
	if (dst->hasz)
		memcpy(dst->z + dst->n, src->z, (Size) src->n * sizeof(double));
	dst->n += src->n;
}

/* ----------------------------------------------------------------
 *		reading
 * ----------------------------------------------------------------
 */

/* Store the one vertex at v of a point value (tdc_gser_append's fast path). */
static void
append_point(TdcPointBuf *buf, const GserWalk *w, int32 srid, const char *v)
{
	double		c[3];

	tdc_pointbuf_check_meta(buf, srid, w->hasz, w->fname);
	memcpy(c, v, (w->hasz ? 3 : 2) * sizeof(double));
	if (!isfinite(c[0]) || !isfinite(c[1]) || (w->hasz && !isfinite(c[2])))
		nonfinite(w);
	tdc_pointbuf_reserve(buf, 1, w->fname);
	buf->xy[2 * buf->n] = c[0];
	buf->xy[2 * buf->n + 1] = c[1];
	if (w->hasz)
		buf->z[buf->n] = c[2];
	buf->n++;
}

/*
 * Append the vertices of one geometry value to buf.  The value must be
 * detoasted but may keep a short (1-byte) header: small values such as
 * points are stored that way, and PG_DETOAST_DATUM_PACKED spares a palloc
 * and copy per row.  Nothing here needs alignment, every read is a memcpy.
 */
void
tdc_gser_append(TdcPointBuf *buf, const struct varlena *geom,
				const char *fname)
{
	GserWalk	w;
	int32		srid;

	Assert(!VARATT_IS_EXTERNAL(geom) && !VARATT_IS_COMPRESSED(geom));
	memset(&w, 0, sizeof(w));
	w.buf = buf;
	w.fname = fname;
	w.p = VARDATA_ANY(geom);
	w.pend = (const char *) geom + VARSIZE_ANY(geom);
	w.hdrsz = (int) (w.p - (const char *) geom);
	w.size = w.pend_pos = (uint64) (w.pend - w.p);

	srid = walk_header(&w);

	/*
	 * A lone point, one row of a point table, is by far the commonest input:
	 * its exact length already proves what the walk would check, so it is
	 * stored directly (a fifth less time reading a table of points).
	 */
	if (w.pend - w.p == 8 + (long) w.vsize &&
		read_u32(w.p) == G_POINT && read_u32(w.p + 4) == 1)
	{
		append_point(buf, &w, srid, w.p + 8);
		return;
	}
	walk_value(&w, srid);
}

/*
 * The same for a value that arrives in pieces (a big TOASTed value read a
 * slice at a time, see tdc_funcs.c): the vertices go from each piece
 * straight into the buffer, so the value is never whole in memory.  The
 * value is read once, front to back: the buffer grows as point lists are
 * met (by doubling, see tdc_pointbuf_reserve), and an ERROR half-way leaves
 * the vertices read so far in it, which is fine for callers that give up
 * the buffer on an ERROR.  The source checks for interrupts between pieces.
 */
void
tdc_gser_append_source(TdcPointBuf *buf, TdcGserSource *src,
					   const char *fname)
{
	GserWalk	w;

	memset(&w, 0, sizeof(w));
	w.buf = buf;
	w.fname = fname;
	w.src = src;
	w.hdrsz = VARHDRSZ;
	w.size = src->size;
	walk_value(&w, walk_header(&w));
}

/* ----------------------------------------------------------------
 *		writing
 * ----------------------------------------------------------------
 */

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
static float
float_down(double d)
{
	float		f = (float) d;

	return (double) f <= d ? f : nextafterf(f, -INFINITY);
}

static float
float_up(double d)
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
	box[0] = float_down(lo[0]);
	box[1] = float_up(hi[0]);
	box[2] = float_down(lo[1]);
	box[3] = float_up(hi[1]);
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
			if ((i & 0xfffff) == 0)
				CHECK_FOR_INTERRUPTS();
		}
		box[4] = float_down(zlo);
		box[5] = float_up(zhi);
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

/* One triangle as a member of a collection (POLYGON) or of a TIN (TRIANGLE). */
static inline char *
put_triangle(char *p, const TdcGserWriter *w, const uint32 *v)
{
	if (w->flags == TDC_OUT_POLYGONS)
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
	p = put_vertex(p, w->job, v[0], w->buf, w->hasz);
	p = put_vertex(p, w->job, v[1], w->buf, w->hasz);
	p = put_vertex(p, w->job, v[2], w->buf, w->hasz);
	return put_vertex(p, w->job, v[0], w->buf, w->hasz);
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
		p = put_triangle(p, w, v + 3 * i);
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
			if ((written & 0xffff) == 0)
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
			if ((written & 0xffff) == 0)
				CHECK_FOR_INTERRUPTS();
			p = put_triangle(p, w, v);
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
				flags == TDC_OUT_EDGES ? G_MULTILINE : G_TIN);
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
	p = put_u32(p, G_POLYGON);
	p = put_u32(p, 1);
	p = put_u32(p, 4);
	p = put_u32(p, 0);
	p = put_vertex(p, job, v[0], buf, buf->hasz);
	p = put_vertex(p, job, v[1], buf, buf->hasz);
	p = put_vertex(p, job, v[2], buf, buf->hasz);
	(void) put_vertex(p, job, v[0], buf, buf->hasz);
}
