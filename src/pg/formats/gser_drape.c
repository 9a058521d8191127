/*
 * gser_drape.c
 *		A target geometry draped on a TIN: its vertices read as the chains
 *		the core drapes, and the value written again with the same
 *		structure, every vertex with Z and every split segment with its new
 *		vertices.
 *
 * The target is one value (detoasted whole: it is bounded by 1 GB like any
 * value, and what the drape writes is larger still).  It is walked twice
 * with the same walker (gser_format.h), which checks every count against
 * the bytes left before it uses it, so a corrupt value is an ERROR:
 *
 *	- reading, each point list becomes a chain: a linestring and a polygon
 *	  ring a chain of their vertices, whose segments the linear method
 *	  splits at the triangle edges; a point a chain of one vertex; a
 *	  TRIANGLE's four vertices four chains of one, since a triangle has
 *	  exactly three corners and cannot take new vertices (a TIN or a
 *	  triangle gets its heights at its corners only);
 *	- writing, the same walk puts every header as it was, every count of a
 *	  point list as its chain's output count, and every vertex as x, y, Z
 *	  (and M, when the target has it: a new vertex takes M interpolated
 *	  along its segment at the same parameter as its position).  The size is
 *	  found by a first, dry walk.
 *
 * The value keeps the target's SRID and its extended flags, and gets the Z
 * flag; a value that is not a point gets a float box over all its vertices,
 * Z (and M) included, rounded outward as PostGIS writes it.  Curves are
 * refused (ST_CurveToLine first): a drape of an arc would have to stroke it.
 */
#include "postgres.h"

#include <math.h>

#include "miscadmin.h"

#include "tdc_pg.h"
#include "gser_format.h"

typedef struct DrapeWalk
{
	const char *p;				/* the input, at the next unread byte */
	const char *end;
	const char *start;
	int			ndims;			/* input doubles per vertex */
	const char *fname;

	/* reading */
	TdcDrapeTarget *t;
	size_t		xcap,
				ccap;

	/* writing (out NULL: sizing only) */
	char	   *out;
	uint64		size;
	const tdc_drape_vertex *v;
	const size_t *off;
	size_t		chain;			/* the next chain */
	double		box[8];			/* lo/hi per output dimension */
} DrapeWalk;

static void
corrupt(const DrapeWalk *w, const char *what)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: corrupt target geometry: %s at byte %ld", w->fname, what,
					(long) (w->p - w->start))));
}

static uint32
take_u32(DrapeWalk *w)
{
	uint32		v;

	if (w->end - w->p < 4)
		corrupt(w, "truncated");
	memcpy(&v, w->p, 4);
	w->p += 4;
	return v;
}

static void
emit(DrapeWalk *w, const void *src, size_t n)
{
	if (w->out)
		memcpy(w->out + w->size, src, n);
	w->size += n;
}

static void
emit_u32(DrapeWalk *w, uint32 v)
{
	emit(w, &v, 4);
}

/* ----------------------------------------------------------------
 *		reading: the chains
 * ----------------------------------------------------------------
 */
static void
add_vertex(DrapeWalk *w, const char *src)
{
	TdcDrapeTarget *t = w->t;
	double		c[4];

	memcpy(c, src, w->ndims * sizeof(double));
	if (!isfinite(c[0]) || !isfinite(c[1]))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the target has a non-finite coordinate (NaN or Infinity)", w->fname)));
	if (t->nvert == w->xcap)
	{
		w->xcap = w->xcap ? 2 * w->xcap : 64;
		t->xy = t->xy ? repalloc_huge(t->xy, w->xcap * 2 * sizeof(double)) :
			palloc_extended(w->xcap * 2 * sizeof(double), MCXT_ALLOC_HUGE);
		if (t->hasm)
			t->m = t->m ? repalloc_huge(t->m, w->xcap * sizeof(double)) :
				palloc_extended(w->xcap * sizeof(double), MCXT_ALLOC_HUGE);
	}
	t->xy[2 * t->nvert] = c[0];
	t->xy[2 * t->nvert + 1] = c[1];
	if (t->hasm)
		t->m[t->nvert] = c[w->ndims - 1];
	t->nvert++;
}

static void
end_chain(DrapeWalk *w)
{
	TdcDrapeTarget *t = w->t;

	if (t->nchains == w->ccap)
	{
		w->ccap = w->ccap ? 2 * w->ccap : 16;
		t->chain_end = t->chain_end ? repalloc_huge(t->chain_end, w->ccap * sizeof(size_t)) :
			palloc_extended(w->ccap * sizeof(size_t), MCXT_ALLOC_HUGE);
	}
	t->chain_end[t->nchains++] = t->nvert;
}

/* ----------------------------------------------------------------
 *		writing: a chain's output vertices
 * ----------------------------------------------------------------
 */
static inline void
grow_box(double *box, int k, double v)
{
	box[2 * k] = Min(box[2 * k], v);
	box[2 * k + 1] = Max(box[2 * k + 1], v);
}

static void
emit_chain(DrapeWalk *w)
{
	const TdcDrapeTarget *t = w->t;
	size_t		c = w->chain++;

	for (size_t i = w->off[c]; i < w->off[c + 1]; i++)
	{
		const tdc_drape_vertex *v = &w->v[i];
		double		o[4] = {v->x, v->y, v->z, 0};
		int			nd = t->hasm ? 4 : 3;

		if (t->hasm)
		{
			double		m0 = t->m[v->src];

			/* a new vertex: M at its parameter along its segment */
			o[3] = v->t == 0 ? m0 : m0 + v->t * (t->m[v->src + 1] - m0);
		}
		for (int k = 0; k < nd; k++)
			grow_box(w->box, k, o[k]);
		emit(w, o, nd * sizeof(double));
	}
}

static size_t
chain_count(const DrapeWalk *w, size_t c)
{
	size_t		n = w->off[c + 1] - w->off[c];

	if (n > PG_UINT32_MAX)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: a draped line of %zu vertices is too long for a geometry", w->fname, n)));
	return n;
}

/* ----------------------------------------------------------------
 *		the walk, for both
 * ----------------------------------------------------------------
 */
static void
walk_points(DrapeWalk *w, uint32 type, uint32 count)
{
	Size		vsize = (Size) w->ndims * sizeof(double);

	if ((uint64) count * vsize > (uint64) (w->end - w->p))
		corrupt(w, "vertex list longer than the value");
	if (w->v == NULL)
	{
		/* reading */
		for (uint32 i = 0; i < count; i++)
		{
			add_vertex(w, w->p + i * vsize);
			if (type == G_TRIANGLE || type == G_POINT)
				end_chain(w);
		}
		if (count > 0 && type != G_TRIANGLE && type != G_POINT)
			end_chain(w);
	}
	else if (type == G_TRIANGLE || type == G_POINT)
	{
		for (uint32 i = 0; i < count; i++)
			emit_chain(w);
	}
	else if (count > 0)
		emit_chain(w);
	w->p += count * vsize;
}

/* The output count of the point list that starts with the next chain. */
static uint32
out_count(DrapeWalk *w, uint32 type, uint32 count)
{
	if (w->v == NULL || count == 0 || type == G_TRIANGLE || type == G_POINT)
		return count;
	return (uint32) chain_count(w, w->chain);
}

static void
walk_geom(DrapeWalk *w)
{
	uint32		type,
				count;

	check_stack_depth();
	CHECK_FOR_INTERRUPTS();
	type = take_u32(w);
	count = take_u32(w);
	switch (type)
	{
		case G_POINT:
			if (count > 1)
				corrupt(w, "a point with more than one vertex");
			/* fall through */
		case G_LINE:
		case G_TRIANGLE:
			emit_u32(w, type);
			emit_u32(w, out_count(w, type, count));
			walk_points(w, type, count);
			return;
		case G_POLYGON:
			{
				uint32	   *rings;
				uint64		hdr = (uint64) count * 4 + (count % 2 ? 4 : 0);
				size_t		c = w->chain;

				if (hdr > (uint64) (w->end - w->p))
					corrupt(w, "ring count larger than the value");
				rings = palloc((Size) hdr + 4);
				memcpy(rings, w->p, (Size) hdr);
				w->p += hdr;
				emit_u32(w, type);
				emit_u32(w, count);
				/* each non-empty ring is the next chain, in order */
				for (uint32 i = 0; i < count; i++)
				{
					uint32		n = rings[i];

					if (w->v != NULL && n > 0)
						n = (uint32) chain_count(w, c++);
					emit_u32(w, n);
				}
				if (count % 2)
					emit_u32(w, 0);
				for (uint32 i = 0; i < count; i++)
					walk_points(w, G_LINE, rings[i]);
				pfree(rings);
				return;
			}
		case G_MULTIPOINT:
		case G_MULTILINE:
		case G_MULTIPOLYGON:
		case G_COLLECTION:
		case G_POLYHEDRAL:
		case G_TIN:
			emit_u32(w, type);
			emit_u32(w, count);
			if ((uint64) count * 8 > (uint64) (w->end - w->p))
				corrupt(w, "member count larger than the value");
			for (uint32 i = 0; i < count; i++)
				walk_geom(w);
			return;
		case G_CIRCSTRING:
		case G_COMPOUND:
		case G_CURVEPOLY:
		case G_MULTICURVE:
		case G_MULTISURFACE:
			ereport(ERROR,
					(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
					 errmsg("%s: curved target geometries are not supported", w->fname),
					 errhint("Convert the target to line segments first with ST_CurveToLine.")));
	}
	corrupt(w, psprintf("unknown geometry type %u", type));
}

static int32
read_srid(const unsigned char *s)
{
	int32		srid = ((int32) (s[0] & 0x1f) << 16) | ((int32) s[1] << 8) | s[2];

	if (srid & 0x100000)
		srid -= 0x200000;
	return srid;
}

/* Past the header: the walk's start, the vertex layout, the extended flags. */
static const char *
skip_header(DrapeWalk *w, const unsigned char *h, bool *extended)
{
	uint8		gflags = h[3];
	const char *p = (const char *) h + G_HEADER;

	w->ndims = 2 + ((gflags & GF_Z) ? 1 : 0) + ((gflags & GF_M) ? 1 : 0);
	*extended = (gflags & GF_VERSION) && (gflags & GF_EXTENDED);
	if (*extended)
		p += 8;
	if (gflags & GF_BBOX)
		p += sizeof(float) * ((gflags & GF_GEODETIC) ? 6 : 2 * w->ndims);
	if (p > w->end)
		corrupt(w, "truncated header");
	return p;
}

void
tdc_drape_target_read(TdcDrapeTarget *t, const struct varlena *value, const char *fname)
{
	DrapeWalk	w;
	const unsigned char *h = (const unsigned char *) VARDATA_ANY(value);
	bool		extended;

	memset(t, 0, sizeof(*t));
	memset(&w, 0, sizeof(w));
	w.fname = fname;
	w.t = t;
	w.start = (const char *) h;
	w.p = w.start;
	w.end = w.start + VARSIZE_ANY_EXHDR(value);
	if (w.end - w.p < G_HEADER + 8)
		corrupt(&w, "value shorter than its header");
	t->value = value;
	t->srid = read_srid(h);
	t->hasm = (h[3] & GF_M) != 0;
	w.p = skip_header(&w, h, &extended);
	walk_geom(&w);
	if (w.p != w.end)
		corrupt(&w, "trailing bytes after the geometry");
}

/* What the chains hold, for the memory check. */
uint64
tdc_drape_target_bytes(const TdcDrapeTarget *t)
{
	return (uint64) t->nvert * (t->hasm ? 3 : 2) * sizeof(double) +
		(uint64) t->nchains * sizeof(size_t);
}

/*
 * The draped value; room: the bytes tdc_delaunay.max_memory leaves for it
 * (PG_UINT64_MAX: no limit).
 */
struct varlena *
tdc_drape_target_write(const TdcDrapeTarget *t, const tdc_drape_vertex *v,
					   const size_t *chain_off, uint64 room, const char *fname)
{
	DrapeWalk	w;
	const unsigned char *h = (const unsigned char *) VARDATA_ANY(t->value);
	bool		extended,
				haspoint;
	const char *body;
	uint32		type;
	int			nd = t->hasm ? 4 : 3;
	uint64		size,
				boxbytes;
	unsigned char *oh;

	memset(&w, 0, sizeof(w));
	w.fname = fname;
	w.t = (TdcDrapeTarget *) t;
	w.start = (const char *) h;
	w.end = w.start + VARSIZE_ANY_EXHDR(t->value);
	w.v = v;
	w.off = chain_off;
	body = skip_header(&w, h, &extended);
	memcpy(&type, body, 4);
	/* PostGIS gives every non-empty value but a point a box */
	haspoint = type == G_POINT;
	boxbytes = (!haspoint && t->nvert > 0) ? 2 * nd * sizeof(float) : 0;

	/* the size: a dry walk */
	w.p = body;
	w.size = 0;
	walk_geom(&w);
	size = VARHDRSZ + G_HEADER + (extended ? 8 : 0) + boxbytes + w.size;
	if (size > (uint64) tdc_guc_max_result_bytes)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: the draped target of %llu bytes exceeds the limit of %d bytes for a single value",
						fname, (unsigned long long) size, tdc_guc_max_result_bytes),
				 errhint("Drape the target in parts.")));
	if (size > room)
		tdc_report_memory_limit(fname, psprintf("the draped target's value of %llu bytes",
												(unsigned long long) size), size, 0);

	/* the value */
	w.out = palloc((Size) size);
	tdc_advise_result(w.out, (Size) size);
	oh = (unsigned char *) VARDATA(w.out);
	SET_VARSIZE(w.out, size);
	oh[0] = h[0];
	oh[1] = h[1];
	oh[2] = h[2];
	oh[3] = GF_VERSION | GF_Z | (t->hasm ? GF_M : 0) | (boxbytes ? GF_BBOX : 0) |
		(extended ? GF_EXTENDED : 0);
	w.size = VARHDRSZ + G_HEADER;
	if (extended)
		emit(&w, h + G_HEADER, 8);
	w.size += boxbytes;			/* the box, once the vertices are known */
	for (int k = 0; k < nd; k++)
	{
		w.box[2 * k] = INFINITY;
		w.box[2 * k + 1] = -INFINITY;
	}
	w.p = body;
	w.chain = 0;
	walk_geom(&w);
	Assert(w.size == size);
	if (boxbytes)
	{
		float		box[8];

		for (int k = 0; k < nd; k++)
		{
			box[2 * k] = tdc_float_down(w.box[2 * k]);
			box[2 * k + 1] = tdc_float_up(w.box[2 * k + 1]);
		}
		memcpy(VARDATA(w.out) + G_HEADER + (extended ? 8 : 0), box, boxbytes);
	}
	return (struct varlena *) w.out;
}
