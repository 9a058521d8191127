/*
 * tin_contour.c
 *		Contour lines of a TIN at the levels base + k * interval, merged into
 *		maximal lines.
 *
 * The level set.  Inside a triangle the surface is a plane, so the level
 * set of a level L is a segment between the two edges whose ends lie on
 * either side of L.  A height exactly equal to L would put a site on the
 * level and make the rule ambiguous (a segment through a corner, along an
 * edge, or a flat triangle), so heights equal to the level count as above
 * it: the level is taken as L - e with e infinitesimal (simulation of
 * simplicity on the level).  Then every site is strictly above or below,
 * every triangle is crossed by 0 or 2 of its edges, and the crossings are a
 * set of paths and cycles on the edges: an interior edge joins the two
 * triangles beside it, a hull edge ends a line.  A crossing at a site at
 * height L is the site itself: several edges meet there, all at the same
 * point, and the consecutive repeats are dropped; so a line through a
 * sample, or along an edge at the level between higher and lower ground,
 * appears once, with no gap, and a peak exactly at a level gives no line
 * (its cycle shrinks to the site).  A ridge exactly at a level, with lower
 * ground on both sides, is the limit of a ring squeezed onto it: the ring
 * runs along the ridge and back.
 *
 * A crossing of edge (b, a), b below and a above, is a itself when its
 * height is the level, and otherwise b + t (a - b) with
 * t = (L - zb) / (za - zb) in [0, 1] (fl(L - zb) <= fl(za - zb) since
 * rounding is monotone): a function of the edge and the level alone, so
 * the two triangles beside an edge give the same bits.
 *
 * Orientation: a triangle's segment runs from the crossing of its edge
 * that goes down (counter-clockwise, from an above corner to a below one)
 * to that of its edge that goes up, which puts the higher ground on its
 * left; the next triangle is the one across the up edge, where that edge
 * goes down.  Rings around hills are counter-clockwise, around pits
 * clockwise.
 *
 * The work.  First (parallel over triangle ranges) each triangle's levels:
 * klo, the lowest k with L_k above its lowest corner, to khi, the highest
 * with L_k not above its highest corner, counted; a prefix sum gives each
 * triangle the offset of its (triangle, level) segments, which are marked
 * when a line takes them.  Then per level the list of its triangles, in
 * triangle order, by a counting sort (per range and level histograms).
 * Then one task per level walks its lines: from each segment not yet taken,
 * in its list's order, forward until the line returns (a ring, which starts
 * there) or leaves the hull, then, for an open line, backward from the
 * start to the hull, so each segment is walked once.  Levels are
 * independent, so their tasks share nothing but the marks, one byte each.
 * The mesh's numbering (and so which segment a line is found from) depends
 * on the triangulation's subdivision, which depends on the thread count;
 * the output does not: an open line starts at its end where the higher
 * ground is on the left, a ring at its point first in (x, y) order (the
 * rotation whose points come first in that order, should it pass a site
 * twice), and the lines of a level are sorted by their points.  So the
 * lines are the same, bit for bit, for any thread count, level by level.
 *
 * max_edge (tdc_tin_contours_start_spec): a first pass marks the triangles
 * the mask drops (an edge longer than max_edge, tin_interp.c's exact
 * rule), which then have no segment, and a line that would step into one
 * stops on the edge between, as it stops on a hull edge: the kept region's
 * boundary ends lines the way the hull does, and a ring around a hole
 * opens there.  Without the option there is no pass and no mark to test.
 *
 * Memory: 8 bytes of offset per triangle, 5 per segment (its place in the
 * level lists and its mark), the histograms (at most 16 M counters), with
 * max_edge one bit per triangle, and the lines: 16 bytes a point, at most
 * two points per segment, and 32 a line, all charged against max_memory
 * before they are taken.
 */
#include <stdio.h>
#include <string.h>

#include "tin_cut.h"
#include "tin_int.h"

#define TRI_PER_TASK	65536
#define HIST_MAX		((size_t) 16 << 20)		/* counters of the level histograms */
#define MAX_LEVELS		TIN_MAX_LEVELS

typedef struct contour_line
{
	double		level;
	size_t		first;			/* in the points (per level, then all) */
	size_t		n;
	bool		closed;
} contour_line;

/* The lines of one level, as its task builds them. */
typedef struct level_out
{
	double	   *xy;
	size_t		n,
				cap;
	contour_line *lines;
	size_t		nlines,
				lcap;
} level_out;

typedef struct contour_op
{
	double		interval,
				base;
	double		max_edge;		/* > 0: the mask's (tdc_interp_spec) */
	uint64_t   *drop;			/* with max_edge: bit t set when triangle t is dropped */
	int64_t		k0;				/* the lowest level any triangle crosses */
	size_t		nlevels;
	size_t		ntask;			/* triangle ranges */
	uint64_t   *off;			/* triangle -> its first segment */
	size_t	   *hist;			/* range x level counts, then positions */
	size_t		hist_bytes;
	size_t	   *lev_start;		/* level -> its list's start in list[] */
	uint32_t   *list;			/* triangles per level, in triangle order */
	uint8_t    *mark;			/* segment taken */
	uint64_t	nseg;
	level_out  *out;			/* per level */
	size_t		charged;		/* bytes charged so far (the fixed arrays) */

	/* the result */
	double	   *xy;
	size_t		npoints;
	contour_line *lines;
	size_t		nlines;
} contour_op;

static inline double
level_of(const contour_op *op, int64_t k)
{
	return tin_level(op->base, op->interval, k);
}

/* The lowest k with L_k > z. */
static inline int64_t
k_above(const contour_op *op, double z)
{
	return tin_k_above(op->base, op->interval, z);
}

/* The highest k with L_k <= z. */
static inline int64_t
k_not_above(const contour_op *op, double z)
{
	return k_above(op, z) - 1;
}

/* Does max_edge drop triangle t (never without the option)? */
static inline bool
dropped(const contour_op *op, size_t t)
{
	return op->drop != NULL && ((op->drop[t >> 6] >> (t & 63)) & 1);
}

static inline void
tri_levels(const tdc_tin *tin, const contour_op *op, size_t t, int64_t *klo, int64_t *khi)
{
	uint32_t	h = tin->tri_he[t],
				h1 = tin_lnext(tin, h);
	double		za = tin->sz[tin_org(tin, h)],
				zb = tin->sz[tin_org(tin, h1)],
				zc = tin->sz[tin_dest(tin, h1)],
				lo = fmin(za, fmin(zb, zc)),
				hi = fmax(za, fmax(zb, zc));

	if (dropped(op, t))
	{
		/* no level: no segment */
		*klo = 1;
		*khi = 0;
		return;
	}
	*klo = k_above(op, lo);
	*khi = k_not_above(op, hi);
}

/* ----------------------------------------------------------------
 *		counting
 * ----------------------------------------------------------------
 */

/* max_edge: the range's dropped triangles (TRI_PER_TASK whole words). */
static void
drop_task(void *arg, size_t r, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	size_t		lo = r * TRI_PER_TASK,
				hi = lo + TRI_PER_TASK < tin->ntri ? lo + TRI_PER_TASK : tin->ntri;

	if (tin_cancelled(tin))
		return;
	memset(op->drop + lo / 64, 0, (hi - lo + 63) / 64 * sizeof(uint64_t));
	for (size_t t = lo; t < hi; t++)
		if (!tin_face_kept(tin, tin->tri_he[t], op->max_edge))
			op->drop[t >> 6] |= (uint64_t) 1 << (t & 63);
}

static void
count_task(void *arg, size_t r, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	size_t		lo = r * TRI_PER_TASK,
				hi = lo + TRI_PER_TASK < tin->ntri ? lo + TRI_PER_TASK : tin->ntri;
	uint64_t	sum = 0;

	if (tin_cancelled(tin))
		return;
	for (size_t t = lo; t < hi; t++)
	{
		int64_t		klo,
					khi;

		tri_levels(tin, op, t, &klo, &khi);
		op->off[t] = sum;
		if (khi >= klo)
			sum += (uint64_t) (khi - klo + 1);
	}
	op->off[tin->ntri + r] = sum;	/* the range's total, past the triangles */
}

/* Offsets made global, and each range's row of the level histogram. */
static void
hist_task(void *arg, size_t r, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	size_t		lo = r * TRI_PER_TASK,
				hi = lo + TRI_PER_TASK < tin->ntri ? lo + TRI_PER_TASK : tin->ntri;
	uint64_t	base = op->off[tin->ntri + r];

	if (tin_cancelled(tin))
		return;
	for (size_t t = lo; t < hi; t++)
		op->off[t] += base;
}

/*
 * The histogram rows are per group of ranges (ntask groups), so that
 * ntask x levels stays within HIST_MAX: group g counts and then places the
 * triangles of its ranges.
 */
static inline void
group_span(const tdc_tin *tin, const contour_op *op, size_t g, size_t *lo, size_t *hi)
{
	size_t		per = (tin->ntri + op->ntask - 1) / op->ntask;

	*lo = g * per;
	*hi = *lo + per < tin->ntri ? *lo + per : tin->ntri;
	if (*lo > tin->ntri)
		*lo = tin->ntri;
}

static void
group_count_task(void *arg, size_t g, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	size_t	   *row = op->hist + g * op->nlevels,
				lo,
				hi;

	group_span(tin, op, g, &lo, &hi);
	for (size_t t = lo; t < hi; t++)
	{
		int64_t		klo,
					khi;

		if ((t & 4095) == 0 && tin_cancelled(tin))
			return;
		tri_levels(tin, op, t, &klo, &khi);
		for (int64_t k = klo; k <= khi; k++)
			row[k - op->k0]++;
	}
}

static void
group_place_task(void *arg, size_t g, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	size_t	   *row = op->hist + g * op->nlevels,
				lo,
				hi;

	group_span(tin, op, g, &lo, &hi);
	for (size_t t = lo; t < hi; t++)
	{
		int64_t		klo,
					khi;

		if ((t & 4095) == 0 && tin_cancelled(tin))
			return;
		tri_levels(tin, op, t, &klo, &khi);
		for (int64_t k = klo; k <= khi; k++)
			op->list[row[k - op->k0]++] = (uint32_t) t;
	}
}

/* ----------------------------------------------------------------
 *		tracing one level
 * ----------------------------------------------------------------
 */

/* The crossing of edge h at level L (its ends on either side): tin_cut.c's. */
static inline void
crossing(const tdc_tin *tin, uint32_t h, double L, double *p)
{
	uint32_t	a = tin_org(tin, h),
				b = tin_dest(tin, h);

	tin_cut_xy(tin_pt(tin, a), tin->sz[a], tin_pt(tin, b), tin->sz[b], L, p);
}

/* The down and up edges of triangle t at level L (it is crossed). */
static void
tri_edges(const tdc_tin *tin, size_t t, double L, uint32_t *down, uint32_t *up)
{
	uint32_t	e = tin->tri_he[t];

	for (int k = 0; k < 3; k++, e = tin_lnext(tin, e))
	{
		bool		ao = tin->sz[tin_org(tin, e)] >= L,
					ad = tin->sz[tin_dest(tin, e)] >= L;

		if (ao && !ad)
			*down = e;
		else if (!ao && ad)
			*up = e;
	}
}

static inline uint8_t *
mark_of(const tdc_tin *tin, const contour_op *op, size_t t, int64_t k)
{
	int64_t		klo,
				khi;

	tri_levels(tin, op, t, &klo, &khi);
	return &op->mark[op->off[t] + (uint64_t) (k - klo)];
}

static bool
out_point(tdc_tin *tin, level_out *o, const double *p)
{
	if (o->n == o->cap)
	{
		size_t		cap = o->cap ? 2 * o->cap : 256;
		double	   *xy;

		if (!tin_charge(tin, (cap - o->cap) * 2 * sizeof(double), "the contour lines"))
			return false;
		xy = realloc(o->xy, cap * 2 * sizeof(double));
		if (xy == NULL)
		{
			tin_fail(tin, TDC_ENOMEM, "out of memory for the contour lines");
			return false;
		}
		tdc_prefault(xy + 2 * o->cap, (cap - o->cap) * 2 * sizeof(double));
		o->xy = xy;
		o->cap = cap;
	}
	o->xy[2 * o->n] = p[0];
	o->xy[2 * o->n + 1] = p[1];
	o->n++;
	return true;
}

/* Reverse the points [i, j) in place. */
static void
out_reverse(level_out *o, size_t i, size_t j)
{
	for (j--; i < j && j != (size_t) -1; i++, j--)
	{
		double		x = o->xy[2 * i],
					y = o->xy[2 * i + 1];

		o->xy[2 * i] = o->xy[2 * j];
		o->xy[2 * i + 1] = o->xy[2 * j + 1];
		o->xy[2 * j] = x;
		o->xy[2 * j + 1] = y;
	}
}

/*
 * The line through segment (t, k), which is not taken: appended to o.
 * Returns false on failure (the TIN failed) or cancel.
 */
static bool
trace(tdc_tin *tin, contour_op *op, level_out *o, size_t t0, int64_t k)
{
	double		L = level_of(op, k),
				p[2];
	size_t		start = o->n,
				t = t0,
				steps = 0,
				back_from;
	uint32_t	down,
				up;
	bool		closed = false;

	/* forward: P(down of t0), then P(up) of every triangle on the way */
	tri_edges(tin, t0, L, &down, &up);
	crossing(tin, down, L, p);
	if (!out_point(tin, o, p))
		return false;
	for (;;)
	{
		uint32_t	next;

		*mark_of(tin, op, t, k) = 1;
		tri_edges(tin, t, L, &down, &up);
		crossing(tin, up, L, p);
		if (!out_point(tin, o, p))
			return false;
		next = up ^ 1u;
		if (tin_outer(tin, next) || dropped(op, tin->he_tri[next]))
			break;
		t = tin->he_tri[next];
		if (t == t0)
		{
			closed = true;
			break;
		}
		if ((++steps & 4095) == 0 && tin_cancelled(tin))
			return false;
	}

	if (!closed)
	{
		/* backward from t0, then [forward, backward] turned into [backward reversed, forward] */
		back_from = o->n;
		tri_edges(tin, t0, L, &down, &up);
		while (!tin_outer(tin, down ^ 1u) && !dropped(op, tin->he_tri[down ^ 1u]))
		{
			t = tin->he_tri[down ^ 1u];
			*mark_of(tin, op, t, k) = 1;
			tri_edges(tin, t, L, &down, &up);
			crossing(tin, down, L, p);
			if (!out_point(tin, o, p))
				return false;
			if ((++steps & 4095) == 0 && tin_cancelled(tin))
				return false;
		}
		out_reverse(o, start, o->n);
		out_reverse(o, start + (o->n - back_from), o->n);
	}

	/* consecutive repeats (crossings at a site at the level) go */
	{
		size_t		w = start + 1;

		for (size_t i = start + 1; i < o->n; i++)
			if (o->xy[2 * i] != o->xy[2 * (w - 1)] || o->xy[2 * i + 1] != o->xy[2 * (w - 1) + 1])
			{
				o->xy[2 * w] = o->xy[2 * i];
				o->xy[2 * w + 1] = o->xy[2 * i + 1];
				w++;
			}
		o->n = w;
	}

	/* fewer than two distinct points (a peak at the level): no line */
	{
		size_t		n = o->n - start;

		if (n < 2 || (closed && n < 3))
		{
			o->n = start;
			return true;
		}
		if (closed)
			tin_ring_canon(o->xy + 2 * start, n - 1);
	}
	if (o->nlines == o->lcap)
	{
		size_t		cap = o->lcap ? 2 * o->lcap : 16;
		contour_line *l;

		if (!tin_charge(tin, (cap - o->lcap) * sizeof(contour_line), "the contour lines"))
			return false;
		l = realloc(o->lines, cap * sizeof(contour_line));
		if (l == NULL)
		{
			tin_fail(tin, TDC_ENOMEM, "out of memory for the contour lines");
			return false;
		}
		o->lines = l;
		o->lcap = cap;
	}
	o->lines[o->nlines].level = L;
	o->lines[o->nlines].first = start;
	o->lines[o->nlines].n = o->n - start;
	o->lines[o->nlines].closed = closed;
	o->nlines++;
	return true;
}

static void
level_task(void *arg, size_t l, int worker)
{
	tdc_tin    *tin = arg;
	contour_op *op = tin->op_state;
	int64_t		k = op->k0 + (int64_t) l;

	for (size_t i = op->lev_start[l]; i < op->lev_start[l + 1]; i++)
	{
		size_t		t = op->list[i];

		if (tin_cancelled(tin))
			return;
		if (*mark_of(tin, op, t, k))
			continue;
		if (!trace(tin, op, &op->out[l], t, k))
			return;
	}
}

/* ----------------------------------------------------------------
 *		the operation
 * ----------------------------------------------------------------
 */
static void
free_fixed(tdc_tin *tin, contour_op *op)
{
	tdc_big_free(tin->cache, op->off);
	tdc_big_free(tin->cache, op->list);
	tdc_big_free(tin->cache, op->mark);
	free(op->drop);
	free(op->hist);
	free(op->lev_start);
	op->off = NULL;
	op->list = NULL;
	op->mark = NULL;
	op->drop = NULL;
	op->hist = NULL;
	op->lev_start = NULL;
}

/* Two lines of a level by their points, in (x, y) order, then by length. */
static int
cmp_line(const void *x, const void *y, void *arg)
{
	const level_out *o = arg;
	const contour_line *a = x,
			   *b = y;

	return tin_line_cmp(o->xy + 2 * a->first, a->n, o->xy + 2 * b->first, b->n);
}

static int
contour_run(tdc_tin *tin)
{
	contour_op *op = tin->op_state;
	size_t		nr = (tin->ntri + TRI_PER_TASK - 1) / TRI_PER_TASK,
				pos = 0,
				need;
	int64_t		k1;
	uint64_t	total = 0;

	if (tin->ntri == 0)
		return TDC_OK;
	op->k0 = k_above(op, tin->zmin);
	k1 = k_not_above(op, tin->zmax);
	if (k1 < op->k0)
		return TDC_OK;
	if (k1 - op->k0 + 1 > MAX_LEVELS)
	{
		tin_fail(tin, TDC_EINVAL, "more than 2^31 contour levels between the lowest and highest sample");
		return TDC_EINVAL;
	}
	op->nlevels = (size_t) (k1 - op->k0 + 1);

	/* the triangles max_edge drops, before anything counts their segments */
	if (op->max_edge > 0)
	{
		need = (tin->ntri + 63) / 64 * sizeof(uint64_t);
		if (!tin_charge(tin, need, "the contours' dropped triangles"))
			return TDC_EMEMLIMIT;
		op->charged += need;
		op->drop = malloc(need);
		if (op->drop == NULL)
			goto oom;
		tdc_pool_for(tin_pool(tin), nr, drop_task, tin);
		if (tin_cancelled(tin))
			return TDC_ECANCELED;
	}

	/* segments per triangle, then their offsets */
	need = (tin->ntri + nr + 1) * sizeof(uint64_t);
	if (!tin_charge(tin, need, "the contour levels"))
		return TDC_EMEMLIMIT;
	op->charged += need;
	op->off = tdc_big_alloc_uninit(tin->cache, need);
	if (op->off == NULL)
		goto oom;
	tdc_pool_for(tin_pool(tin), nr, count_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;
	for (size_t r = 0; r < nr; r++)
	{
		uint64_t	s = op->off[tin->ntri + r];

		op->off[tin->ntri + r] = total;
		total += s;
	}
	op->nseg = total;
	tdc_pool_for(tin_pool(tin), nr, hist_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;

	/* the per level lists: histograms per group of triangles */
	op->ntask = HIST_MAX / op->nlevels;
	if (op->ntask > (size_t) tin->threads * 4)
		op->ntask = (size_t) tin->threads * 4;
	if (op->ntask < 1)
		op->ntask = 1;
	need = op->ntask * op->nlevels * sizeof(size_t) + (op->nlevels + 1) * (sizeof(size_t) + sizeof(level_out)) +
		(size_t) total * (sizeof(uint32_t) + 1);
	if (!tin_charge(tin, need, "the contour segments"))
		return TDC_EMEMLIMIT;
	op->charged += need;
	op->hist = calloc(op->ntask * op->nlevels, sizeof(size_t));
	op->lev_start = calloc(op->nlevels + 1, sizeof(size_t));
	op->out = calloc(op->nlevels + 1, sizeof(level_out));
	op->list = tdc_big_alloc_uninit(tin->cache, (size_t) total * sizeof(uint32_t) + 4);
	op->mark = tdc_big_alloc(tin->cache, (size_t) total + 1);
	if (!op->hist || !op->lev_start || !op->out || !op->list || !op->mark)
		goto oom;
	tdc_pool_for(tin_pool(tin), op->ntask, group_count_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;
	for (size_t l = 0; l < op->nlevels; l++)
	{
		op->lev_start[l] = pos;
		for (size_t g = 0; g < op->ntask; g++)
		{
			size_t		c = op->hist[g * op->nlevels + l];

			op->hist[g * op->nlevels + l] = pos;
			pos += c;
		}
	}
	op->lev_start[op->nlevels] = pos;
	tdc_pool_for(tin_pool(tin), op->ntask, group_place_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;

	/* the lines, level by level */
	tdc_pool_for(tin_pool(tin), op->nlevels, level_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;

	/* all of them together, in level order */
	{
		size_t		np = 0,
					nl = 0;

		for (size_t l = 0; l < op->nlevels; l++)
		{
			np += op->out[l].n;
			nl += op->out[l].nlines;
		}
		free_fixed(tin, op);
		tin_uncharge(tin, op->charged);
		op->charged = 0;
		need = np * 2 * sizeof(double) + nl * sizeof(contour_line);
		if (!tin_charge(tin, need, "the contour lines"))
			return TDC_EMEMLIMIT;
		op->charged = need;
		op->xy = tdc_big_alloc_uninit(tin->cache, np * 2 * sizeof(double) + 16);
		op->lines = malloc(nl * sizeof(contour_line) + 1);
		if (op->xy == NULL || op->lines == NULL)
			goto oom;
		tdc_prefault(op->xy, np * 2 * sizeof(double));
		for (size_t l = 0; l < op->nlevels; l++)
		{
			level_out  *o = &op->out[l];

			/*
			 * a level's lines in the order of their points, not of the
			 * mesh's numbering (a level may have none: max_edge dropped its
			 * triangles, or a peak at the level; then no array either)
			 */
			if (o->nlines > 1)
				qsort_r(o->lines, o->nlines, sizeof(contour_line), cmp_line, o);
			for (size_t i = 0; i < o->nlines; i++)
			{
				contour_line *ln = &o->lines[i];

				memcpy(op->xy + 2 * op->npoints, o->xy + 2 * ln->first, ln->n * 2 * sizeof(double));
				op->lines[op->nlines] = *ln;
				op->lines[op->nlines].first = op->npoints;
				op->nlines++;
				op->npoints += ln->n;
			}
			tin_uncharge(tin, o->cap * 2 * sizeof(double) + o->lcap * sizeof(contour_line));
			free(o->xy);
			free(o->lines);
			memset(o, 0, sizeof(*o));
			if ((l & 63) == 0 && tin_cancelled(tin))
				return TDC_ECANCELED;
		}
	}
	return TDC_OK;

oom:
	tin_fail(tin, TDC_ENOMEM, "out of memory for the contour lines");
	return TDC_ENOMEM;
}

static void
contour_free(tdc_tin *tin)
{
	contour_op *op = tin->op_state;

	if (op == NULL)
		return;
	free_fixed(tin, op);
	if (op->out)
		for (size_t l = 0; l < op->nlevels; l++)
		{
			tin_uncharge(tin, op->out[l].cap * 2 * sizeof(double) +
						 op->out[l].lcap * sizeof(contour_line));
			free(op->out[l].xy);
			free(op->out[l].lines);
		}
	free(op->out);
	tdc_big_free(tin->cache, op->xy);
	free(op->lines);
	tin_uncharge(tin, op->charged);
	free(op);
	tin->op_state = NULL;
	tin->op_free = NULL;
}

int
tdc_tin_contours_start(tdc_tin *tin, double interval, double base, char *err, size_t errlen)
{
	return tdc_tin_contours_start_spec(tin, interval, base, NULL, err, errlen);
}

int
tdc_tin_contours_spec_check(const tdc_interp_spec *spec, char *err, size_t errlen)
{
#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (spec == NULL)
		return TDC_OK;
	if (spec->method != TDC_INTERP_LINEAR)
		FAIL(TDC_EINVAL, "contour lines are those of the linear surface: the method must be linear, not %s",
			 spec->method == TDC_INTERP_NEAREST ? "nearest" :
			 spec->method == TDC_INTERP_NATURAL ? "natural_neighbor" : "an unknown one");
	if (spec->breaklines)
		FAIL(TDC_EINVAL, "contour lines take the Delaunay TIN: the option breaklines is not taken here");
	if (spec->options & ~(TDC_INTERP_OPT_MAX_EDGE | TDC_INTERP_OPT_BREAKLINES))
		FAIL(TDC_EINVAL, "contour lines take only the option max_edge: %s concerns values outside the triangles",
			 (spec->options & TDC_INTERP_OPT_RADIUS) ? "radius" : "nodata");
	if (!(spec->max_edge >= 0))
		FAIL(TDC_EINVAL, "max_edge must be a length > 0, or 0 for none");
	return TDC_OK;
#undef FAIL
}

int
tdc_tin_contours_start_spec(tdc_tin *tin, double interval, double base,
							const tdc_interp_spec *spec, char *err, size_t errlen)
{
	contour_op *op;
	int			rc = tdc_tin_contours_spec_check(spec, err, errlen);

	if (rc != TDC_OK)
		return rc;
#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (!(interval > 0) || !isfinite(interval))
		FAIL(TDC_EINVAL, "the contour interval must be a finite number > 0, not %g", interval);
	if (!isfinite(base))
		FAIL(TDC_EINVAL, "the contour base must be finite, not %g", base);
	op = calloc(1, sizeof(contour_op));
	if (op == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	op->interval = interval;
	op->base = base;
	op->max_edge = spec != NULL ? spec->max_edge : 0;
	if (tin->built && tin->nsites > 0 && tin->ntri > 0)
	{
		/* every level between the heights must be a double of its own (tin_cut.c) */
		if ((rc = tin_levels_check(interval, base, tin->zmin, tin->zmax, err, errlen)) != TDC_OK)
		{
			free(op);
			return rc;
		}
	}
#undef FAIL
	return tin_op_start(tin, contour_run, op, contour_free,
						tin->nsite_ids <= TDC_INLINE_MAX, err, errlen);
}

size_t
tdc_tin_contour_count(const tdc_tin *tin, size_t *points)
{
	const contour_op *op = tin->op_state;

	if (op == NULL || tin->op != contour_run || tdc_runner_wait((tdc_runner *) &tin->run, 0) != TDC_OK)
	{
		if (points)
			*points = 0;
		return 0;
	}
	if (points)
		*points = op->npoints;
	return op->nlines;
}

const double *
tdc_tin_contour_line(const tdc_tin *tin, size_t i, double *level, size_t *n, bool *closed)
{
	const contour_op *op = tin->op_state;
	const contour_line *l;

	if (op == NULL || tin->op != contour_run || i >= op->nlines)
		return NULL;
	l = &op->lines[i];
	*level = l->level;
	*n = l->n;
	*closed = l->closed;
	return op->xy + 2 * l->first;
}
