/*
 * leaf.c
 *		Guibas-Stolfi divide and conquer inside one subset (step 2 of Wu et
 *		al. 2014), with Dwyer's alternating cuts.
 *
 * Guibas and Stolfi's merge needs halves separated along an axis, not
 * sorted ones, and Dwyer (1987) showed that cutting alternately along x and
 * y keeps the halves round and the merges short: far fewer edges are created
 * and then deleted than with vertical cuts only.  A subset is a rectangle of
 * grid cells whose points subdivide.c already laid out in depth-first order
 * of the cell splits, so the recursion first goes on halving the rectangle
 * alternately along columns and rows (tdc_rect_split_inner, the same splits
 * the layout used) down to single cells, and merges the halves along the
 * axis of their split.
 *
 * Inside a cell, which holds a handful of points unless the data cluster,
 * the alternation goes on along the axis key (x, y) or (y, -x), cutting at
 * the middle of the range's extent when that splits well enough
 * (range_split), else at the exact median by quickselect; the halves are
 * triangulated along the other axis and merged along this one, down to at
 * most three points.
 *
 * Duplicates.  Exact duplicates have equal keys, and a split keeps equal
 * keys together, so they end up in one base case of at most three points
 * (sorted there by x, y, input index) or in a range that no split can
 * separate because all its points are equal.  Either way the point with the
 * smallest input index is kept as the site, at the lowest position, and
 * site_of[] records, at each position of the range, its site: writes that
 * stay in the subset's own memory.  The input-indexed map is only built if a
 * caller asks for it (tdc_input_site).
 *
 * Edge slots: the subset owns 3 per point of [lo, hi), more than a planar
 * graph on its sites can use.  Deleted edges are reused first, then
 * untouched slots in increasing order; on return every unused slot is on
 * out->fl, marked free, for the merges above.
 */
#include "job_int.h"

#define SPLIT_MIN		12		/* below, quickselect's exact median is cheap */

/*
 * Ranges of fewer points than this do not look at the cancel flag: they are
 * triangulated in well under a millisecond, and the range that holds them
 * has looked already.  Polling every small range would put a shared load on
 * the hottest path of the recursion.
 */
#define LEAF_POLL_MIN	1024

typedef struct leaf_ctx
{
	tdc_job    *job;
	tdc_mesh	m;
	double	   *xy;
	uint32_t   *idx;
	uint32_t   *site_of;		/* position -> position of its site */
} leaf_ctx;

static inline bool
same_point(const double *xy, size_t i, size_t j)
{
	return xy[2 * i] == xy[2 * j] && xy[2 * i + 1] == xy[2 * j + 1];
}

static inline void
swap_pt(double *xy, uint32_t *idx, size_t i, size_t j)
{
	double		x = xy[2 * i],
				y = xy[2 * i + 1];
	uint32_t	t = idx[i];

	xy[2 * i] = xy[2 * j];
	xy[2 * i + 1] = xy[2 * j + 1];
	idx[i] = idx[j];
	xy[2 * j] = x;
	xy[2 * j + 1] = y;
	idx[j] = t;
}

/*
 * Quickselect on [a, b): afterwards position a + r holds the element of
 * rank r by the axis key, smaller-or-equal ones before it, greater-or-equal
 * ones after (Hoare 1961).
 */
static inline __attribute__((always_inline)) void
select_rank(double *xy, uint32_t *idx, size_t a, size_t b, size_t r, int axis)
{
	size_t		k = a + r;

	while (b - a > 3)
	{
		size_t		mid = a + (b - a) / 2;
		size_t		i,
					j;
		double		p[2];

		/* median of three as pivot, and as sentinels for the scans */
		if (tdc_key_less(&xy[2 * mid], &xy[2 * a], axis))
			swap_pt(xy, idx, mid, a);
		if (tdc_key_less(&xy[2 * (b - 1)], &xy[2 * a], axis))
			swap_pt(xy, idx, b - 1, a);
		if (tdc_key_less(&xy[2 * (b - 1)], &xy[2 * mid], axis))
			swap_pt(xy, idx, b - 1, mid);
		p[0] = xy[2 * mid];
		p[1] = xy[2 * mid + 1];

		i = a;
		j = b - 1;
		for (;;)
		{
			while (tdc_key_less(&xy[2 * i], p, axis))
				i++;
			while (tdc_key_less(p, &xy[2 * j], axis))
				j--;
			if (i >= j)
				break;
			swap_pt(xy, idx, i, j);
			i++;
			j--;
		}
		/* now [a, j] <= p <= [j + 1, b), and j + 1 - a, b - j - 1 < b - a */
		if (k <= j)
			b = j + 1;
		else
			a = j + 1;
	}
	for (size_t i = a + 1; i < b; i++)
		for (size_t j = i; j > a && tdc_key_less(&xy[2 * j], &xy[2 * (j - 1)], axis); j--)
			swap_pt(xy, idx, j, j - 1);
}

/*
 * Split [lo, hi) at the middle of its extent along the axis: two passes (the
 * extent, then one partition) instead of quickselect's expected three or so
 * for the exact median.  Clustered data leave cells of tens to thousands of
 * points, where the exact median took a fifth of the engine's time.  The
 * halves need only be separated along the axis, not equal: balance bounds
 * the recursion's cost and depth, so a split leaving less than an eighth of
 * the points on a side is refused (false) and the caller takes the exact
 * median instead, which keeps the worst case O(n log n).  The cut depends on
 * the set of points only, never on their positions, so neither does the
 * recursion, and the output stays the same for any input order.  Points
 * whose first coordinate is at most the cut go left: every key on the left
 * is below every key on the right, and duplicates stay together.  On true,
 * *mid is the first position of the right half.
 */
static bool
range_split(leaf_ctx *c, uint32_t lo, uint32_t hi, int axis, uint32_t *mid)
{
	double	   *xy = c->xy;
	uint32_t	n = hi - lo;
	double		mn = xy[2 * (size_t) lo + axis],
				mx = mn,
				cut;
	size_t		i,
				j;

	for (i = lo + 1; i < hi; i++)
	{
		double		v = xy[2 * i + axis];

		mn = v < mn ? v : mn;
		mx = v > mx ? v : mx;
	}
	cut = mn + (mx - mn) / 2;	/* coordinates are below 1e60: no overflow */

	/* afterwards [lo, i) <= cut < [i, hi) */
	i = lo;
	j = hi;
	for (;;)
	{
		while (i < j && xy[2 * i + axis] <= cut)
			i++;
		while (i < j && xy[2 * (j - 1) + axis] > cut)
			j--;
		if (i >= j)
			break;
		swap_pt(xy, c->idx, i, j - 1);
		i++;
		j--;
	}
	if (i - lo < n / 8 || hi - i < n / 8)
		return false;
	*mid = (uint32_t) i;
	return true;
}

static inline bool
rec_less(const leaf_ctx *c, size_t i, size_t j)
{
	const double *p = c->xy + 2 * i,
			   *q = c->xy + 2 * j;

	if (p[0] != q[0])
		return p[0] < q[0];
	if (p[1] != q[1])
		return p[1] < q[1];
	return c->idx[i] < c->idx[j];
}

static void
empty_sub(tdc_sub *out)
{
	out->ext[0] = out->ext[1] = out->ext[2] = out->ext[3] = TDC_NIL;
	out->vert = TDC_NIL;
	out->nsites = 0;
}

/* A range of equal points: keep the earliest input as the single site. */
static void
single_site(leaf_ctx *c, uint32_t lo, uint32_t n, tdc_sub *out)
{
	uint32_t	best = lo;

	for (uint32_t i = lo + 1; i < lo + n; i++)
		if (c->idx[i] < c->idx[best])
			best = i;
	swap_pt(c->xy, c->idx, lo, best);
	for (uint32_t i = lo; i < lo + n; i++)
		c->site_of[i] = lo;
	empty_sub(out);
	out->vert = lo;
	out->nsites = 1;
}

/* At most three points: sort, drop duplicates, triangulate directly (GS 1985). */
static void
base_case(leaf_ctx *c, tdc_freelist *fl, uint32_t lo, uint32_t n, tdc_sub *out)
{
	tdc_mesh   *m = &c->m;
	uint32_t	v[3] = {lo, lo + 1, lo + 2};
	uint32_t	ccw[3];
	uint32_t	u = 0;

	for (uint32_t i = lo + 1; i < lo + n; i++)
		for (uint32_t j = i; j > lo && rec_less(c, j, j - 1); j--)
			swap_pt(c->xy, c->idx, j, j - 1);
	for (uint32_t i = lo; i < lo + n; i++)
	{
		if (u == 0 || !same_point(c->xy, i, lo + u - 1))
		{
			swap_pt(c->xy, c->idx, lo + u, i);
			u++;
		}
	}
	/* sites first, then their duplicates, which no longer move */
	for (uint32_t k = lo; k < lo + u; k++)
		c->site_of[k] = k;
	for (uint32_t i = lo + u; i < lo + n; i++)
		for (uint32_t k = lo; k < lo + u; k++)
			if (same_point(c->xy, i, k))
				c->site_of[i] = k;

	if (u == 1)
	{
		empty_sub(out);
		out->vert = lo;
		out->nsites = 1;
		return;
	}
	if (u == 2)
	{
		uint32_t	a = tdc_make_edge(m, fl, lo, lo + 1);

		ccw[0] = a;
		ccw[1] = SYM(a);
	}
	else
	{
		uint32_t	a = tdc_make_edge(m, fl, lo, lo + 1);
		uint32_t	b = tdc_make_edge(m, fl, lo + 1, lo + 2);
		double		o;

		tdc_splice(m, SYM(a), b);
		o = tdc_orient2d(tdc_pt(m, lo), tdc_pt(m, lo + 1), tdc_pt(m, lo + 2));
		if (o > 0)
		{
			uint32_t	e = tdc_connect(m, fl, b, a);

			ccw[0] = a;
			ccw[1] = b;
			ccw[2] = e;
		}
		else if (o < 0)
		{
			uint32_t	e = tdc_connect(m, fl, b, a);

			ccw[0] = SYM(e);
			ccw[1] = SYM(a);
			ccw[2] = SYM(b);
		}
		else
		{
			/* a chain: the middle site is never extreme in a lexicographic order */
			ccw[0] = a;
			ccw[1] = b;
			ccw[2] = SYM(b);
		}
	}
	tdc_sub_from_sites(m, v, ccw, (int) u, out);
}

static void
gs_recurse(leaf_ctx *c, tdc_freelist *fl, uint32_t lo, uint32_t n, int axis,
		   tdc_sub *out)
{
	tdc_sub		L,
				R;
	uint32_t	hi = lo + n,
				mid,
				med;

	if (n <= 3)
	{
		base_case(c, fl, lo, n, out);
		return;
	}
	/* A cancelled job's mesh is garbage: stop before touching it again. */
	if (n >= LEAF_POLL_MIN && tdc_cancelled(&c->m))
	{
		empty_sub(out);
		return;
	}

	if (n >= SPLIT_MIN &&
		(axis == 0 ? range_split(c, lo, hi, 0, &mid) :
		 range_split(c, lo, hi, 1, &mid)))
		goto split;

	/* median split; duplicates of the median stay on its left */
	med = lo + n / 2;
	if (axis == 0)
		select_rank(c->xy, c->idx, lo, hi, n / 2, 0);
	else
		select_rank(c->xy, c->idx, lo, hi, n / 2, 1);
	mid = med + 1;
	for (uint32_t i = mid; i < hi; i++)
		if (same_point(c->xy, i, med))
			swap_pt(c->xy, c->idx, i, mid++);
	if (mid == hi)
	{
		/* the median is the largest key: put its copies on the right instead */
		mid = hi;
		for (uint32_t i = hi; i-- > lo;)
			if (same_point(c->xy, i, hi - 1))
				swap_pt(c->xy, c->idx, i, --mid);
		if (mid == lo)
		{
			single_site(c, lo, n, out);
			return;
		}
	}

split:
	gs_recurse(c, fl, lo, mid - lo, axis ^ 1, &L);
	gs_recurse(c, fl, mid, hi - mid, axis ^ 1, &R);
	if (n >= LEAF_POLL_MIN && tdc_cancelled(&c->m))
	{
		empty_sub(out);
		return;
	}
	tdc_merge(&c->m, fl, &L, &R, axis, out);
}

/* A rectangle of cells whose points start at position lo. */
static void
rect_recurse(leaf_ctx *c, tdc_freelist *fl, const tdc_rect *r, int axis,
			 uint32_t lo, tdc_sub *out)
{
	uint32_t	n = tdc_rect_count(c->job, r);
	tdc_rect	a,
				b;
	tdc_sub		L,
				R;
	int			split;

	if (n == 0)
	{
		empty_sub(out);
		return;
	}
	if (n >= LEAF_POLL_MIN && tdc_cancelled(&c->m))
	{
		empty_sub(out);
		return;
	}
	split = tdc_rect_split_inner(c->job, r, axis, &a, &b);
	if (split < 0)
	{
		gs_recurse(c, fl, lo, n, 0, out);
		return;
	}
	rect_recurse(c, fl, &a, axis ^ 1, lo, &L);
	rect_recurse(c, fl, &b, axis ^ 1, lo + tdc_rect_count(c->job, &a), &R);
	if (n >= LEAF_POLL_MIN && tdc_cancelled(&c->m))
	{
		empty_sub(out);
		return;
	}
	tdc_merge(&c->m, fl, &L, &R, split, out);
}

void
tdc_triangulate_leaf(tdc_job *job, size_t k, tdc_sub *out)
{
	leaf_ctx	c;
	tdc_freelist fl;
	uint32_t	lo = job->node_lo[k],
				hi = job->node_hi[k];

	c.job = job;
	c.m.xy = job->xy;
	c.m.he = job->he;
	c.m.cancel = &job->cancel;
	c.xy = job->xy;
	c.idx = job->idx;
	c.site_of = job->site_of;

	fl.head = TDC_NIL;
	fl.tail = TDC_NIL;
	fl.bump = 3 * lo;
	fl.limit = 3 * hi;

	/* the subset writes every one of its slots, at the latest below */
	tdc_prefault(job->he + 6 * (size_t) lo, 6 * (size_t) (hi - lo) * sizeof(tdc_he));

	/* the same first axis as the layout in subdivide.c */
	rect_recurse(&c, &fl, &job->node_rect[k], job->d & 1, lo, out);

	/*
	 * Leftover slots go on the list: the merges above have no bump range.
	 * Not after a cancel, when the mesh is thrown away: that would touch
	 * most of a subset's untouched slots.
	 */
	if (!tdc_cancelled(&c.m))
		while (fl.bump < fl.limit)
			tdc_free_edge(&c.m, &fl, 2 * fl.bump++);
	out->fl = fl;
}
