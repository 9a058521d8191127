/*
 * tin_locate.c
 *		Where a point lies in a TIN (a triangle, an edge, a site, or outside
 *		the hull), the site nearest to it, and the linear height at it.
 *
 * Location is a walk: from a start triangle (the previous query's, or the
 * one at the site the locate grid of tin.c names for the point's cell), cross
 * an edge that has the point strictly on its far side, until no edge does.
 * The sides are exact orientations (predicates.h), so the answer is exact:
 * the point is strictly inside the last triangle, or strictly inside one of
 * its edges (one zero), or at one of its corners (two zeros); crossing a
 * hull edge means it is strictly outside the hull, which is convex.  In a
 * Delaunay triangulation such a visibility walk always ends (Edelsbrunner,
 * "An acyclicity theorem for cell complexes in d dimensions", 1990), with
 * any choice of edge; the walk starts each step at a different edge all the
 * same, as a remembering stochastic walk does (Devillers, Pion and
 * Teillaud, "Walking in a triangulation", 2002), so that it ends on a
 * constrained triangulation too, where the theorem does not hold.  A step
 * bound guards the host all the same: past it the triangles are scanned,
 * which gives the same exact answer slowly.
 *
 * Which triangle holds a point on an edge or at a site is not unique; the
 * callers never depend on it: an edge is reported by its two sites and its
 * height is linear along it from the end first in (x, y) order, a site by
 * itself.  A triangle's height is computed from its first vertex in (x, y)
 * order.  So a value depends on the point and the mesh only, never on where
 * the walk started, and so not on the thread count.
 *
 * Nearest site: in a Delaunay triangulation, a site that is not nearest to
 * q has a neighbour nearer to q (q lies beyond an edge of the site's
 * Voronoi cell, on the side of the neighbour across it), so a greedy walk
 * from any site ends at a nearest one; distances are compared exactly
 * (tdc_sqdist_cmp).  Sites equally near to q lie on an empty circle around
 * q, whose consecutive sites are joined by Delaunay edges, so they are all
 * reached from one of them through equally near neighbours; the one first
 * in (x, y) order wins.  Collinear sites (no triangle) are sorted along
 * their line: the distance to q is unimodal along it, and a binary search
 * on exact comparisons of neighbours finds the first nearest.  A
 * constrained mesh is not Delaunay, and the greedy walk may stop at a site
 * whose nearer neighbour a constraint cut off: there a k-d tree of the
 * sites (tin.c) is searched instead, with the same exact comparisons and
 * the same tie rule, so it gives the same site.
 *
 * Heights.  Linear inside a triangle (a, b, c), a the first in (x, y)
 * order: z = za + s (zb - za) + t (zc - za), with s and t the barycentric
 * coordinates from the doubles b - a, c - a and q - a (each rounded once)
 * and their cross products; along an edge a-b: z = za + u (zb - za) with
 * u = (q - a).(b - a) / |b - a|^2 clamped to [0, 1].  Both reproduce a
 * plane to within a few rounding errors of its heights in a well-shaped
 * triangle; a sliver loses what its area's rounding loses.
 */
#include <stdio.h>
#include <math.h>
#include <string.h>

#include "tin_int.h"
#include "tin_lerp.h"

static inline double
orient(const double *a, const double *b, const double *c)
{
	return tdc_orient2d(a, b, c);
}

/* The start for a walk to q: a half-edge with a triangle on its left. */
uint32_t
tin_start_he(const tdc_tin *tin, const double *q)
{
	double		fx = (q[0] - tin->lo[0]) * tin->gscale[0],
				fy = (q[1] - tin->lo[1]) * tin->gscale[1];
	uint32_t	cx = !(fx > 0) ? 0 : fx >= tin->gw ? tin->gw - 1 : (uint32_t) fx,
				cy = !(fy > 0) ? 0 : fy >= tin->gh ? tin->gh - 1 : (uint32_t) fy,
				s = atomic_load_explicit(&tin->cell_site[(size_t) cy * tin->gw + cx],
										 memory_order_relaxed),
				h;

	h = atomic_load_explicit(&tin->site_he[s], memory_order_relaxed);
	return tin_outer(tin, h) ? h ^ 1u : h;
}

/* The triangles one by one: the exact answer when a walk would not end. */
static void
locate_scan(const tdc_tin *tin, const double *q, tin_loc *loc)
{
	uint32_t	hull = TDC_NIL;

	for (size_t t = 0; t < tin->ntri; t++)
	{
		uint32_t	e[3];
		double		o[3];
		int			zeros = 0,
					neg = 0;

		e[0] = tin->tri_he[t];
		e[1] = tin_lnext(tin, e[0]);
		e[2] = tin_lnext(tin, e[1]);
		for (int k = 0; k < 3; k++)
		{
			o[k] = orient(tin_pt(tin, tin_org(tin, e[k])), tin_pt(tin, tin_dest(tin, e[k])), q);
			zeros += o[k] == 0;
			neg += o[k] < 0;
			if (o[k] < 0 && tin_outer(tin, e[k] ^ 1u))
				hull = e[k];
		}
		if (neg > 0)
			continue;
		for (int k = 0; k < 3; k++)
		{
			if (zeros == 1 && o[k] == 0)
			{
				loc->kind = LOC_EDGE;
				loc->h = e[k];
				loc->a = tin_org(tin, e[k]);
				loc->b = tin_dest(tin, e[k]);
				return;
			}
			if (zeros == 2 && o[k] == 0 && o[(k + 2) % 3] == 0)
			{
				loc->kind = LOC_VERTEX;
				loc->h = e[k];
				loc->a = tin_org(tin, e[k]);
				return;
			}
		}
		loc->kind = LOC_FACE;
		loc->h = e[0];
		return;
	}
	/* in no triangle: outside, and some hull edge has q strictly beyond it */
	loc->kind = LOC_OUTSIDE;
	loc->h = hull;
}

/* Collinear sites: their segment, one site or outside. */
static void
locate_line(const tdc_tin *tin, const double *q, tin_loc *loc)
{
	const uint32_t *ln = tin->line;
	size_t		m = tin->nline,
				lo,
				hi;
	const double *first = tin_pt(tin, ln[0]),
			   *last = tin_pt(tin, ln[m - 1]);

	loc->h = TDC_NIL;
	if (m == 1 || orient(first, last, q) != 0 ||
		tdc_lex_less(q, first) || tdc_lex_less(last, q))
	{
		if (first[0] == q[0] && first[1] == q[1])
		{
			loc->kind = LOC_VERTEX;
			loc->a = ln[0];
			return;
		}
		loc->kind = LOC_OUTSIDE;
		return;
	}
	/* the last site not after q along the line */
	lo = 0;
	hi = m - 1;
	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo + 1) / 2;

		if (tdc_lex_less(q, tin_pt(tin, ln[mid])))
			hi = mid - 1;
		else
			lo = mid;
	}
	if (!tdc_lex_less(tin_pt(tin, ln[lo]), q))
	{
		loc->kind = LOC_VERTEX;
		loc->a = ln[lo];
		return;
	}
	loc->kind = LOC_EDGE;
	loc->a = ln[lo];
	loc->b = ln[lo + 1];
}

/*
 * Is the walk from hint to q short?  Within two cells of the locate grid of
 * hint's origin: a walk costs about one step per triangle it crosses, so a
 * hint from a far point (targets in random order) would cost O(sqrt n)
 * steps, where the grid's start costs O(1).  The answer does not depend on
 * the start (the walk is exact), only the time does.
 */
static bool
hint_is_near(const tdc_tin *tin, uint32_t hint, const double *q)
{
	const double *p = tin_pt(tin, tin_org(tin, hint));

	return fabs(q[0] - p[0]) * tin->gscale[0] + fabs(q[1] - p[1]) * tin->gscale[1] <= 2.0;
}

/*
 * Locate q, starting from hint (a half-edge with a triangle on its left, or
 * TDC_NIL for the locate grid's start) when hint is near q, and from the
 * locate grid's start otherwise.
 */
void
tin_locate(const tdc_tin *tin, const double *q, uint32_t hint, tin_loc *loc)
{
	uint32_t	h0;
	size_t		steps = 0,
				limit = 4 * tin->ntri + 64;

	memset(loc, 0, sizeof(*loc));
	loc->h = TDC_NIL;
	if (tin->nsites == 0)
	{
		loc->kind = LOC_NONE;
		return;
	}
	if (tin->ntri == 0)
	{
		locate_line(tin, q, loc);
		return;
	}
	h0 = hint != TDC_NIL && !tin_outer(tin, hint) && hint_is_near(tin, hint, q) ?
		hint : tin_start_he(tin, q);

	for (;;)
	{
		uint32_t	e[3];
		double		o[3];
		int			r = (int) (steps % 3),
					zeros = 0;
		bool		moved = false;

		e[0] = h0;
		e[1] = tin_lnext(tin, e[0]);
		e[2] = tin_lnext(tin, e[1]);
		for (int k = 0; k < 3; k++)
		{
			int			i = (r + k) % 3;
			uint32_t	sym;

			o[i] = orient(tin_pt(tin, tin_org(tin, e[i])), tin_pt(tin, tin_dest(tin, e[i])), q);
			if (!(o[i] < 0))
				continue;
			sym = e[i] ^ 1u;
			if (tin_outer(tin, sym))
			{
				loc->kind = LOC_OUTSIDE;
				loc->h = e[i];
				return;
			}
			h0 = sym;
			moved = true;
			break;
		}
		if (moved)
		{
			if (++steps > limit)
			{
				locate_scan(tin, q, loc);
				return;
			}
			continue;
		}
		for (int k = 0; k < 3; k++)
			zeros += o[k] == 0;
		if (zeros == 0)
		{
			loc->kind = LOC_FACE;
			loc->h = h0;
			return;
		}
		for (int k = 0; k < 3; k++)
		{
			if (zeros == 1 && o[k] == 0)
			{
				loc->kind = LOC_EDGE;
				loc->h = e[k];
				loc->a = tin_org(tin, e[k]);
				loc->b = tin_dest(tin, e[k]);
				return;
			}
			/* two zeros: the corner the two zero edges share */
			if (zeros == 2 && o[k] == 0 && o[(k + 2) % 3] == 0)
			{
				loc->kind = LOC_VERTEX;
				loc->h = e[k];
				loc->a = tin_org(tin, e[k]);
				return;
			}
		}
		/* three zeros cannot happen in a non-degenerate triangle */
		locate_scan(tin, q, loc);
		return;
	}
}

/* ----------------------------------------------------------------
 *		nearest site
 * ----------------------------------------------------------------
 */

/* The nearest of collinear sites: the first i with d(i) <= d(i + 1). */
static uint32_t
nearest_line(const tdc_tin *tin, const double *q)
{
	const uint32_t *ln = tin->line;
	size_t		lo = 0,
				hi = tin->nline - 1;

	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo) / 2;

		if (tdc_sqdist_cmp(q, tin_pt(tin, ln[mid]), q, tin_pt(tin, ln[mid + 1])) <= 0)
			hi = mid;
		else
			lo = mid + 1;
	}
	return ln[lo];
}

/* Is s nearer to q than *best, or as near and first in (x, y) order? */
static inline void
kd_consider(const tdc_tin *tin, const double *q, uint32_t s, uint32_t *best)
{
	int			c;

	if (*best == TDC_NIL)
	{
		*best = s;
		return;
	}
	c = tdc_sqdist_cmp(q, tin_pt(tin, s), q, tin_pt(tin, *best));
	if (c < 0 || (c == 0 && tdc_lex_less(tin_pt(tin, s), tin_pt(tin, *best))))
		*best = s;
}

/*
 * The nearest site in the k-d range a[0 .. n) at depth (tin_int.h), into
 * *best.  The sites after a range's median have its coordinate along the
 * axis or more, those before it or less, so none on the far side is nearer
 * than the median's line; the far side is skipped only when that line is
 * strictly farther than *best (exactly: the foot of q on it is a point of
 * doubles), so that equally near sites are all seen.
 */
static void
kd_nearest(const tdc_tin *tin, const double *q, const uint32_t *a, size_t n, int depth,
		   uint32_t *best)
{
	while (n > TIN_KD_LEAF)
	{
		size_t		m = n / 2;
		int			axis = depth & 1;
		const double *p = tin_pt(tin, a[m]);
		double		foot[2];
		const uint32_t *near_a,
				   *far_a;
		size_t		near_n,
					far_n;

		kd_consider(tin, q, a[m], best);
		if (q[axis] < p[axis])
		{
			near_a = a, near_n = m;
			far_a = a + m + 1, far_n = n - m - 1;
		}
		else
		{
			near_a = a + m + 1, near_n = n - m - 1;
			far_a = a, far_n = m;
		}
		kd_nearest(tin, q, near_a, near_n, depth + 1, best);
		foot[axis] = p[axis];
		foot[1 - axis] = q[1 - axis];
		if (tdc_sqdist_cmp(q, foot, q, tin_pt(tin, *best)) > 0)
			return;
		a = far_a;
		n = far_n;
		depth++;
	}
	for (size_t i = 0; i < n; i++)
		kd_consider(tin, q, a[i], best);
}

/*
 * The nearest site to q (the first in (x, y) order among equally near
 * ones), from loc's triangle or edge; on a constrained TIN from its k-d
 * tree.
 */
uint32_t
tin_nearest(const tdc_tin *tin, const double *q, const tin_loc *loc)
{
	uint32_t	v,
				best;
	uint32_t	ties[64];
	size_t		nties = 0;

	if (tin->nsites == 0)
		return TDC_NIL;
	if (loc->kind == LOC_VERTEX)
		return loc->a;
	if (tin->ntri == 0)
		return nearest_line(tin, q);
	if (tin->kd != NULL)
	{
		best = TDC_NIL;
		kd_nearest(tin, q, tin->kd, tin->nkd, 0, &best);
		return best;
	}
	v = tin_org(tin, loc->h);

	/* greedy: to the nearest neighbour while it is strictly nearer */
	for (;;)
	{
		uint32_t	h = atomic_load_explicit(&tin->site_he[v], memory_order_relaxed),
					start = h,
					next = v;

		do
		{
			uint32_t	w = tin_dest(tin, h);

			if (tdc_sqdist_cmp(q, tin_pt(tin, w), q, tin_pt(tin, next)) < 0)
				next = w;
			h = tin_onext(tin, h);
		} while (h != start);
		if (next == v)
			break;
		v = next;
	}

	/*
	 * Equally near sites, reached through equally near neighbours; the
	 * first in (x, y) order.  There are rarely more than a few (a lattice
	 * has four); past the list's room, the ones found so far decide.
	 */
	best = v;
	ties[nties++] = v;
	for (size_t i = 0; i < nties; i++)
	{
		uint32_t	u = ties[i],
					h = atomic_load_explicit(&tin->site_he[u], memory_order_relaxed),
					start = h;

		do
		{
			uint32_t	w = tin_dest(tin, h);
			bool		seen = false;

			if (tdc_sqdist_cmp(q, tin_pt(tin, w), q, tin_pt(tin, v)) == 0)
			{
				for (size_t j = 0; j < nties && !seen; j++)
					seen = ties[j] == w;
				if (!seen && nties < sizeof(ties) / sizeof(ties[0]))
				{
					ties[nties++] = w;
					if (tdc_lex_less(tin_pt(tin, w), tin_pt(tin, best)))
						best = w;
				}
			}
			h = tin_onext(tin, h);
		} while (h != start);
	}
	return best;
}

/* ----------------------------------------------------------------
 *		linear heights
 * ----------------------------------------------------------------
 */

/* Linear along edge a-b at q (on it), from the end first in (x, y) order (tin_lerp.c). */
double
tin_lerp_edge(const tdc_tin *tin, uint32_t a, uint32_t b, const double *q)
{
	return tin_lerp_xy(tin_pt(tin, a), tin->sz[a], tin_pt(tin, b), tin->sz[b], q);
}

/* Linear in the triangle left of h at q (inside it), from its first vertex (tin_lerp.c). */
double
tin_linear_face(const tdc_tin *tin, uint32_t h, const double *q)
{
	uint32_t	v[3];
	const double *p[3];
	double		z[3];

	v[0] = tin_org(tin, h);
	h = tin_lnext(tin, h);
	v[1] = tin_org(tin, h);
	v[2] = tin_dest(tin, h);
	for (int k = 0; k < 3; k++)
	{
		p[k] = tin_pt(tin, v[k]);
		z[k] = tin->sz[v[k]];
	}
	return tin_face_xy(p, z, q);
}
