/*
 * gser_read.c
 *		Read PostGIS geometry values into a point buffer.
 *
 * A triangulation only needs the vertices of its input, and going through
 * liblwgeom for that (deserialize to an LWGEOM, walk it, copy points out)
 * costs more than the triangulation of a small geometry.  So we read the
 * on-disk format (gser_format.h) directly.
 *
 * A value is read once, front to back, and may arrive in pieces: a value in
 * memory is one piece, a big TOASTed value read by ST_TDCDelaunayTriangles
 * comes a slice at a time (toast_stream.c), so it is never whole in memory and
 * an interrupt is answered between slices.  Every count read from a value is
 * checked against the bytes that remain in the whole value before it is
 * used, with 64-bit arithmetic, whether those bytes have arrived or not, so
 * a corrupt value gives an ERROR (with the same byte offset however it was
 * split) and never a read outside the value.  Vertices go straight from the
 * piece into the point buffer (pointbuf.c), which grows as point lists are
 * met; NaN and infinities are rejected.  An ERROR half-way leaves the
 * vertices read so far in the buffer: every caller gives the buffer up on an
 * ERROR.  A curve is read as its function's PostGIS counterpart reads it
 * (the buffer's "curves", see curves.c): refused, read as its stored
 * vertices, or, for the Delaunay functions, read as its stored vertices
 * and noted: once the value is read (and so known to be sound), its
 * vertices are dropped and the value is read again as PostGIS strokes it.
 */
#include "postgres.h"

#include <math.h>

#include "miscadmin.h"

#include "tdc_pg.h"
#include "gser_format.h"

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
	bool		arcs;			/* met a CIRCULARSTRING with vertices */
	bool		empty_arc;		/* met an empty CIRCULARSTRING */
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

/*
 * The vertices of one point list, appended to the buffer.  chain: the list
 * is a linestring, a triangle or a ring, whose consecutive vertices the
 * buffer's chain function (if any) hears about.
 */
static void
walk_points(GserWalk *w, uint32 npoints, bool chain)
{
	TdcPointBuf *buf = w->buf;
	uint32		left = npoints;
	uint64		first = buf->n;

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
	if (chain && npoints > 1 && buf->chain != NULL)
		buf->chain(buf->chain_arg, first, npoints);
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
			walk_points(w, count, false);
			return;
		case G_LINE:
		case G_TRIANGLE:
			walk_points(w, count, true);
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
					walk_points(w, rings[i], true);
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
			if (w->buf->curves == TDC_CURVES_REFUSE)
				ereport(ERROR,
						(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
						 errmsg("%s: curved geometries (%s) are not supported",
								w->fname, curve_name(type)),
						 errhint("Convert them to line segments first with ST_CurveToLine.")));
			/*
			 * The stored vertices (to be stroked later, if the buffer
			 * strokes): an arc string's are a point list, and the others
			 * hold their parts (arc strings, line strings, compound curves,
			 * rings, curve polygons) as whole geometries, as a collection
			 * does.
			 */
			if (type == G_CIRCSTRING)
			{
				if (count > 0)
					w->arcs = true;
				else
					w->empty_arc = true;
				walk_points(w, count, false);
			}
			else
				for (i = 0; i < count; i++)
					walk_geom(w);
			return;
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

/*
 * Does a value just read need stroking?  Only when it has arcs and the
 * buffer strokes them.  An empty CIRCULARSTRING has no vertices to give
 * and needs nothing, alone; but beside arcs it cannot be stroked:
 * ST_CurveToLine (PostGIS 3.3) turns it into a vertex of uninitialized
 * memory, which ST_DelaunayTriangles then triangulates.
 */
static bool
needs_stroke(const GserWalk *w)
{
	if (!w->arcs || w->buf->curves != TDC_CURVES_STROKE)
		return false;
	if (w->empty_arc)
		ereport(ERROR,
				(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
				 errmsg("%s: an empty CIRCULARSTRING beside arcs cannot be stroked",
						w->fname),
				 errdetail("PostGIS's ST_CurveToLine, which strokes the arcs as ST_DelaunayTriangles does, makes a vertex of uninitialized memory of it."),
				 errhint("Remove the empty CIRCULARSTRING from the geometry.")));
	return true;
}

/*
 * A value with arcs, for a buffer that strokes them: its vertices (from
 * index first on) are dropped and the value stroked by PostGIS is read
 * instead.  A stroked value has no curves left; if it had, that would be
 * refused, not stroked again.
 */
static void
append_stroked(TdcPointBuf *buf, uint64 first, Datum whole, const char *fname)
{
	struct varlena *lin;

	buf->n = first;
	lin = tdc_curve_to_line(whole, fname);
	/* an ERROR leaves the mode changed, but callers give the buffer up then */
	buf->curves = TDC_CURVES_REFUSE;
	tdc_gser_append(buf, lin, fname);
	buf->curves = TDC_CURVES_STROKE;
	pfree(lin);
}

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
 * Returns true when the value had arcs and was read stroked (see the top).
 */
bool
tdc_gser_append(TdcPointBuf *buf, const struct varlena *geom,
				const char *fname)
{
	GserWalk	w;
	int32		srid;
	uint64		first;

	Assert(!VARATT_IS_EXTERNAL(geom) && !VARATT_IS_COMPRESSED(geom));

	/*
	 * A 2D point with no box and no extended flags, into a buffer that has
	 * room and holds 2D vertices of its SRID: the row of a point table
	 * after the first.  Its exact length rules out every optional part, so
	 * the type, the count, the SRID and the coordinates are all left to
	 * check (append_point below does the same for any point, after the
	 * header walk and with the buffer's checks).
	 * Anything else, or a coordinate that is not finite (for the error),
	 * takes the walk below.
	 */
	if (VARSIZE_ANY_EXHDR(geom) == G_HEADER + 8 + 2 * sizeof(double) &&
		buf->n < buf->cap && buf->have_first && !buf->hasz)
	{
		const char *d = VARDATA_ANY(geom);
		double		c[2];

		memcpy(c, d + G_HEADER + 8, sizeof(c));
		if (((unsigned char) d[3] & (GF_Z | GF_M | GF_BBOX | GF_GEODETIC)) == 0 &&
			read_u32(d + G_HEADER) == G_POINT && read_u32(d + G_HEADER + 4) == 1 &&
			read_srid((const unsigned char *) d) == buf->srid &&
			isfinite(c[0]) && isfinite(c[1]))
		{
			buf->xy[2 * buf->n] = c[0];
			buf->xy[2 * buf->n + 1] = c[1];
			buf->n++;
			return false;
		}
	}

	memset(&w, 0, sizeof(w));
	w.buf = buf;
	w.fname = fname;
	w.p = VARDATA_ANY(geom);
	w.pend = (const char *) geom + VARSIZE_ANY(geom);
	w.hdrsz = (int) (w.p - (const char *) geom);
	w.size = w.pend_pos = (uint64) (w.pend - w.p);
	first = buf->n;

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
		return false;
	}
	walk_value(&w, srid);
	if (needs_stroke(&w))
	{
		append_stroked(buf, first, PointerGetDatum(geom), fname);
		return true;
	}
	return false;
}

/*
 * The same for a value that arrives in pieces (a big TOASTed value read a
 * slice at a time, see toast_stream.c): the vertices go from each piece
 * straight into the buffer, so the value is never whole in memory.  The
 * value is read once, front to back: the buffer grows as point lists are
 * met (by doubling, see tdc_pointbuf_reserve), and an ERROR half-way leaves
 * the vertices read so far in it, which is fine for callers that give up
 * the buffer on an ERROR.  The source checks for interrupts between pieces.
 * Returns true when the value had arcs to stroke: it was then read again,
 * stroked, from src->whole.
 */
bool
tdc_gser_append_source(TdcPointBuf *buf, TdcGserSource *src,
					   const char *fname)
{
	GserWalk	w;
	uint64		first = buf->n;

	memset(&w, 0, sizeof(w));
	w.buf = buf;
	w.fname = fname;
	w.src = src;
	w.hdrsz = VARHDRSZ;
	w.size = src->size;
	walk_value(&w, walk_header(&w));
	if (!needs_stroke(&w))
		return false;
	append_stroked(buf, first, src->whole, fname);
	return true;
}

