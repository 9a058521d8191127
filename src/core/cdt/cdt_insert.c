/*
 * cdt_insert.c
 *		Constrained Delaunay triangulation, one segment: a constraint
 *		inserted into the triangulation by flips, with exact predicates.
 *		How the segments are shared out and run is cdt.c's.
 *
 * Method: the edge flipping scheme of Sloan (1993, "A fast algorithm for
 * generating constrained Delaunay triangulations", Computers & Structures
 * 47(3)): walk from a towards b listing the edges the open segment crosses
 * (tdc_cdt_insert_segment), flip them until a-b is an edge (Sloan's step 2,
 * remove_crossings), then restore the Delaunay property by Lawson flips
 * among the new edges only (restore_delaunay): inserting a-b changes the
 * CDT only inside the triangles it crosses (Anglada 1997).  Exact
 * cocircularity is broken by the kernel's symbolic rule, as in merge.c, so
 * the result depends on the sites and the segments only.  The ends are
 * input indices mapped to sites; a zero-length segment is ignored, a site
 * on the open segment splits it (no site is ever created), collinear
 * overlaps are found as existing edges, and a proper crossing is
 * TDC_ECROSS naming both segments.  Between segments the mesh triangulates
 * the sites' hull (hull edges are never flipped, so the job's outer-face
 * bitmap and triangle count stay right), every constraint edge carries the
 * smallest number (+ 1) of the segments that made it and every other edge
 * NO_SEG, vedge[s] leaves site s, and no edge slot is added or freed.  The
 * mesh is written in place: the one writer of mesh_view.h.
 *
 * The design note, with the reasons, the rules and the references, is
 * docs/design/constrained.md.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cdt_int.h"

int
tdc_cdt_ctx_fail(cdt_ctx *x, int code, const char *fmt,...)
{
	va_list		ap;

	va_start(ap, fmt);
	vsnprintf(x->err, sizeof(x->err), fmt, ap);
	va_end(ap);
	return code;
}

static bool
cdt_poll(cdt_ctx *x)
{
	if (++x->steps % POLL_STEPS != 0)
		return false;
	return atomic_load_explicit(&x->c->cancel, memory_order_relaxed) != 0;
}

static inline bool
is_outer(const tdc_cdt *c, uint32_t h)
{
	return c->mesh.outer != NULL && tdc_he_outer(c->mesh.outer, h);
}

static inline double
orient(const tdc_cdt *c, uint32_t a, uint32_t b, uint32_t p)
{
	return tdc_orient2d(tdc_pt(&c->m, a), tdc_pt(&c->m, b), tdc_pt(&c->m, p));
}

/*
 * In-circle with the merge's tie rule (the kernel's tdc_incircle_sos): is d
 * inside the circle through the counter-clockwise a, b, c, exact zeros
 * decided by perturbing the lift of the lexicographically smallest of the
 * four distinct sites.
 */
static inline bool
incircle_sos(const tdc_cdt *c, uint32_t a, uint32_t b, uint32_t cc, uint32_t d)
{
	return tdc_incircle_sos(tdc_pt(&c->m, a), tdc_pt(&c->m, b),
							tdc_pt(&c->m, cc), tdc_pt(&c->m, d));
}

/*
 * p lies exactly on the line of a-b: is it on the same side of a as b?
 * Coordinate comparisons only, so exact.
 */
static bool
same_dir(const tdc_cdt *c, uint32_t a, uint32_t p, uint32_t b)
{
	const double *pa = tdc_pt(&c->m, a),
			   *pp = tdc_pt(&c->m, p),
			   *pb = tdc_pt(&c->m, b);

	if (pb[0] != pa[0])
		return (pp[0] > pa[0]) == (pb[0] > pa[0]) && pp[0] != pa[0];
	return (pp[1] > pa[1]) == (pb[1] > pa[1]) && pp[1] != pa[1];
}

/* May inserter x touch site v?  The serial one any, a stripe's its own. */
static inline bool
owns(const cdt_ctx *x, uint32_t v)
{
	return x->part < 0 || site_part(x->c, v) == x->part;
}

/*
 * Flip edge h, the diagonal of the strictly convex quadrilateral of its two
 * triangles, to the other diagonal (Guibas & Stolfi's Swap).  The edge slot
 * stays; vedge[] of h's old ends moves to edges that still leave them.
 */
static void
flip(tdc_cdt *c, uint32_t h)
{
	tdc_mesh   *m = &c->m;
	uint32_t	a = tdc_oprev(m, h),
				b = tdc_oprev(m, SYM(h)),
				u = tdc_org(m, h),
				v = tdc_dest(m, h);

	if (c->vedge[u] == h)
		c->vedge[u] = a;
	if (c->vedge[v] == SYM(h))
		c->vedge[v] = b;
	tdc_splice(m, h, a);
	tdc_splice(m, SYM(h), b);
	tdc_splice(m, h, tdc_lnext(m, a));
	tdc_splice(m, SYM(h), tdc_lnext(m, b));
	m->he[h].org = tdc_dest(m, a);
	m->he[SYM(h)].org = tdc_dest(m, b);
}

static const double *
input_xy(const tdc_cdt *c, size_t i)
{
	return c->mesh.input + 2 * i;
}

static int
crossing_error(cdt_ctx *x, size_t s1, size_t s2)
{
	const tdc_cdt *c = x->c;
	const double *a = input_xy(c, c->seg[2 * s2]),
			   *b = input_xy(c, c->seg[2 * s2 + 1]),
			   *p = input_xy(c, c->seg[2 * s1]),
			   *q = input_xy(c, c->seg[2 * s1 + 1]);

	x->cross[0] = s2;
	x->cross[1] = s1;
	return tdc_cdt_ctx_fail(x, TDC_ECROSS,
					"constraint segments cross: segment %zu from (%.17g %.17g) to (%.17g %.17g) and segment %zu from (%.17g %.17g) to (%.17g %.17g)",
					s2, a[0], a[1], b[0], b[1], s1, p[0], p[1], q[0], q[1]);
}

int
tdc_cdt_internal_error(cdt_ctx *x, size_t s, const char *what)
{
	return tdc_cdt_ctx_fail(x, TDC_EINVAL, "internal error inserting segment %zu: %s", s, what);
}

/*
 * Sloan's step 2 on the n crossed edges in x->list (a circular queue) for
 * the piece a-e: afterwards a-e is an edge, and x->fresh holds the *nfresh
 * other edges made here, all inside the region the piece crossed.
 */
static int
remove_crossings(cdt_ctx *x, size_t s, uint32_t a, uint32_t e, size_t n,
				 size_t *nfresh)
{
	tdc_cdt    *c = x->c;
	tdc_mesh   *m = &c->m;
	size_t		head = 0,
				count = n,
				idle = 0;

	*nfresh = 0;
	while (count > 0)
	{
		uint32_t	h = 2 * x->list[head],
					u = tdc_org(m, h),
					v = tdc_dest(m, h),
					p = tdc_dest(m, tdc_lnext(m, h)),
					q = tdc_dest(m, tdc_lnext(m, SYM(h)));
		double		ou = orient(c, p, q, u),
					ov = orient(c, p, q, v);

		head = (head + 1) % x->cap;
		count--;
		if (cdt_poll(x))
			return TDC_ECANCELED;
		if ((ou > 0 && ov < 0) || (ou < 0 && ov > 0))
		{
			double		op,
						oq;

			flip(c, h);
			idle = 0;
			op = orient(c, a, e, p);
			oq = orient(c, a, e, q);
			if ((op > 0 && oq < 0) || (op < 0 && oq > 0))
			{
				x->list[(head + count) % x->cap] = h >> 1;
				count++;
			}
			else
				x->fresh[(*nfresh)++] = h >> 1;
		}
		else
		{
			x->list[(head + count) % x->cap] = h >> 1;
			count++;
			/* Sloan: some quadrilateral is always convex; never loop */
			if (++idle > count)
				return tdc_cdt_internal_error(x, s, "no crossed edge can be flipped");
		}
	}
	return TDC_OK;
}

/*
 * Lawson's flips among the n new edges of a cavity, marked CAV in cons[];
 * the constraint and the cavity's border are not listed, so never flipped
 * (only the new edges can fail: Anglada 1997, docs/design/constrained.md).
 */
static int
restore_delaunay(cdt_ctx *x, size_t n)
{
	tdc_cdt    *c = x->c;
	tdc_mesh   *m = &c->m;
	size_t		top = n;

	for (size_t i = 0; i < n; i++)
		c->cons[x->fresh[i]] = CAVQ;
	while (top > 0)
	{
		uint32_t	e = x->fresh[--top],
					h = 2 * e,
					u = tdc_org(m, h),
					v = tdc_dest(m, h),
					p = tdc_dest(m, tdc_lnext(m, h)),
					q = tdc_dest(m, tdc_lnext(m, SYM(h)));

		c->cons[e] = CAV;
		if (cdt_poll(x))
			return TDC_ECANCELED;
		if (incircle_sos(c, u, v, p, q))
		{
			uint32_t	around[4];

			flip(c, h);
			around[0] = tdc_lnext(m, h);
			around[1] = tdc_lnext(m, around[0]);
			around[2] = tdc_lnext(m, SYM(h));
			around[3] = tdc_lnext(m, around[2]);
			for (int k = 0; k < 4; k++)
			{
				uint32_t	f = around[k] >> 1;

				if (c->cons[f] == CAV)
				{
					c->cons[f] = CAVQ;
					x->fresh[top++] = f;
				}
			}
		}
	}
	return TDC_OK;
}

/*
 * Is there an edge a-b?  Returns a half-edge a->b or TDC_NIL.  Each step
 * around a is a cache miss (a's edges lie anywhere in the mesh), and this is
 * most of the insertion's time for contour lines, whose segments are mostly
 * edges already.  So it turns both ways at once, Onext from one side and
 * Oprev from the other: the two chains of loads do not depend on each other,
 * and the one that meets b is about half as long as a one-way turn (1M
 * contour segments: 3.6 half-edges looked at per segment one way, all in a
 * chain).  The half-edge a->b is unique, so the answer is the same.
 */
static uint32_t
find_edge(const tdc_cdt *c, uint32_t a, uint32_t b)
{
	const tdc_mesh *m = &c->m;
	uint32_t	f = c->vedge[a],
				r = f;

	if (tdc_dest(m, f) == b)
		return f;
	for (;;)
	{
		f = tdc_onext(m, f);
		if (f == r)
			return TDC_NIL;		/* all of the ring seen */
		if (tdc_dest(m, f) == b)
			return f;
		r = tdc_oprev(m, r);
		if (r == f)
			return TDC_NIL;
		if (tdc_dest(m, r) == b)
			return r;
	}
}

/*
 * Edge h is (part of) segment s.  An edge covered by several segments keeps
 * the smallest number, so the numbers do not depend on which inserter came
 * first.
 */
static void
mark(cdt_ctx *x, uint32_t h, size_t s)
{
	uint32_t   *k = &x->c->cons[h >> 1];

	if (*k == NO_SEG)
	{
		*k = (uint32_t) s + 1;
		x->nconstraint++;
	}
	else if (*k > (uint32_t) s + 1)
		*k = (uint32_t) s + 1;
}

/*
 * The serial inserter's lists start small (most segments cross few edges)
 * and double when a walk fills them, up to one entry per edge, so that a
 * million segments do not fault in 24 bytes a point they never use.  A
 * stripe's lists are fixed: a longer walk is left to the serial pass.
 */
static int
grow_lists(cdt_ctx *x, size_t s)
{
	tdc_cdt    *c = x->c;
	size_t		cap = 2 * x->cap < c->nslots ? 2 * x->cap : c->nslots;
	uint32_t   *l,
			   *f;

	if (x->part >= 0)
		return TDC_DEFER;
	if (cap <= x->cap)
		return tdc_cdt_internal_error(x, s, "more crossed edges than edges");
	l = realloc(c->list, cap * sizeof(uint32_t));
	if (l != NULL)
		c->list = x->list = l;
	f = l ? realloc(c->fresh, cap * sizeof(uint32_t)) : NULL;
	if (f == NULL)
		return tdc_cdt_ctx_fail(x, TDC_ENOMEM, "out of memory for the crossed edges of segment %zu", s);
	c->fresh = x->fresh = f;
	x->cap = cap;
	return TDC_OK;
}

/*
 * Insert segment s from site a to site b (a != b), piece by piece: Sloan's
 * walk (step 1) to list the crossed edges, then remove_crossings and
 * restore_delaunay (steps 2 and 3, docs/design/constrained.md).  A
 * stripe's inserter returns TDC_DEFER, before it changes anything of the
 * piece at hand, when that piece would touch a triangle with a corner
 * outside its stripe (or needs more crossed edges than its lists hold); the
 * pieces already in place stay, and the serial pass finds them as edges.
 */
int
tdc_cdt_insert_segment(cdt_ctx *x, size_t s, uint32_t a, uint32_t b)
{
	tdc_cdt    *c = x->c;
	tdc_mesh   *m = &c->m;

	while (a != b)
	{
		uint32_t	g = c->vedge[a],
					start = g,
					t = TDC_NIL,
					e = TDC_NIL;
		size_t		n = 0,
					nfresh;
		int			rc;

		/*
		 * Most segments of contour-like input are Delaunay edges already:
		 * look for a-b without a predicate first.
		 */
		g = find_edge(c, a, b);
		if (g != TDC_NIL)
		{
			mark(x, g, s);
			break;
		}
		g = start;

		/* the edge out of a along a-b, or the triangle a-b leaves a into */
		do
		{
			uint32_t	p = tdc_dest(m, g),
						gn = tdc_onext(m, g);
			double		o;

			if (p == b)
			{
				e = b;
				break;
			}
			o = orient(c, a, b, p);
			if (o == 0 && same_dir(c, a, p, b))
			{
				e = p;			/* a site on the segment: split there */
				break;
			}
			if (o < 0 && gn != g && !is_outer(c, g) &&
				orient(c, a, b, tdc_dest(m, gn)) > 0)
			{
				t = tdc_lnext(m, g);
				break;
			}
			g = gn;
		} while (g != start);

		if (e != TDC_NIL)
		{
			if (!owns(x, e))
				return TDC_DEFER;
			mark(x, g, s);
			a = e;
			continue;
		}
		if (t == TDC_NIL)
			return tdc_cdt_internal_error(x, s, "no triangle around its start");
		if (!owns(x, tdc_dest(m, g)) || !owns(x, tdc_dest(m, tdc_onext(m, g))))
			return TDC_DEFER;

		/* walk; t is a crossed edge from the right of a-b to its left */
		for (;;)
		{
			uint32_t	sym = SYM(t),
						r;
			double		o;

			if (c->cons[t >> 1] != NO_SEG)
				return crossing_error(x, s, c->cons[t >> 1] - 1);
			if (n == x->cap && (rc = grow_lists(x, s)) != TDC_OK)
				return rc;
			x->list[n++] = t >> 1;
			if (is_outer(c, sym))
				return tdc_cdt_internal_error(x, s, "the walk left the convex hull");
			r = tdc_dest(m, tdc_lnext(m, sym));
			if (!owns(x, r))
				return TDC_DEFER;
			if (r == b)
			{
				e = b;
				break;
			}
			o = orient(c, a, b, r);
			if (o == 0)
			{
				e = r;			/* a site on the segment: split there */
				break;
			}
			t = o > 0 ? tdc_lnext(m, sym) : tdc_lnext(m, tdc_lnext(m, sym));
			if (cdt_poll(x))
				return TDC_ECANCELED;
		}

		rc = remove_crossings(x, s, a, e, n, &nfresh);
		if (rc != TDC_OK)
			return rc;
		g = find_edge(c, a, e);
		if (g == TDC_NIL)
			return tdc_cdt_internal_error(x, s, "the constraint is no edge after the flips");
		/* the last flip may have made a-e itself: it is no new edge to flip */
		for (size_t i = 0; i < nfresh; i++)
			if (x->fresh[i] == g >> 1)
				x->fresh[i--] = x->fresh[--nfresh];
		/* the Lawson stack overwrites fresh[]: keep the set in list[] */
		memcpy(x->list, x->fresh, nfresh * sizeof(uint32_t));
		rc = restore_delaunay(x, nfresh);
		for (size_t i = 0; i < nfresh; i++)
			c->cons[x->list[i]] = NO_SEG;
		if (rc != TDC_OK)
			return rc;
		mark(x, g, s);
		a = e;
	}
	return TDC_OK;
}

/* The end sites of segment s, checked. */
int
tdc_cdt_seg_sites(cdt_ctx *x, size_t s, uint32_t *a, uint32_t *b)
{
	const tdc_cdt *c = x->c;
	const tdc_mesh_view *mesh = &c->mesh;

	if (c->seg[2 * s] >= mesh->n || c->seg[2 * s + 1] >= mesh->n)
		return tdc_cdt_ctx_fail(x, TDC_EINVAL, "segment %zu has an end point index out of range (%u %u, %zu points)",
						s, c->seg[2 * s], c->seg[2 * s + 1], mesh->n);
	*a = tdc_input_site(c->job, c->seg[2 * s]);
	*b = tdc_input_site(c->job, c->seg[2 * s + 1]);
	if (*a == UINT32_MAX || *b == UINT32_MAX)
		return tdc_cdt_ctx_fail(x, TDC_ENOMEM, "out of memory for the input map");
	return TDC_OK;
}

/* The status of inserter x, its message and crossing moved to c. */
int
tdc_cdt_take_error(tdc_cdt *c, const cdt_ctx *x, int rc)
{
	memcpy(c->err, x->err, sizeof(c->err));
	c->cross[0] = x->cross[0];
	c->cross[1] = x->cross[1];
	return rc;
}

