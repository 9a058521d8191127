/*
 * cdt.c
 *		Constrained Delaunay triangulation: constraint segments inserted into
 *		a finished Delaunay triangulation, in place, with exact predicates.
 *
 * Method.  Segments are inserted one at a time by the edge
 * flipping scheme of Sloan (1993, "A fast algorithm for generating
 * constrained Delaunay triangulations", Computers & Structures 47(3)):
 *
 *	1. walk from the segment's first end point a towards its other end b
 *	   through the triangles the open segment crosses, listing the edges it
 *	   crosses properly;
 *	2. take listed edges in turn: an edge whose two triangles form a strictly
 *	   convex quadrilateral is flipped, and if the new diagonal still crosses
 *	   the segment it goes back to the end of the list, otherwise it is kept
 *	   aside as a new edge; an edge whose quadrilateral is not convex goes back
 *	   to the end of the list.  Sloan shows some listed edge always has a
 *	   convex quadrilateral, so the list empties and a-b is an edge;
 *	3. restore the Delaunay property by Lawson flips (incircle) among the new
 *	   edges only; the constraint itself is never flipped.
 *
 * Why only the new edges: inserting a-b changes the constrained Delaunay
 * triangulation (CDT) only inside the union of the triangles a-b crosses
 * (Anglada 1997, "An improved incremental algorithm for constructing
 * restricted Delaunay triangulations"), whose two halves are then
 * triangulated Delaunay-wise relative to the constraint.  Every flip stays
 * inside that region, and a triangulation of a polygon whose inner edges are
 * all locally Delaunay is its CDT (the constrained Delaunay lemma), which is
 * what Lawson's flips reach.
 *
 * Ties.  The in-circle test breaks exact cocircularity with the same
 * symbolic perturbation of the lifting map as merge.c (simulation of
 * simplicity on the lift, smaller sites lifted more), so the perturbed sites
 * admit exactly one CDT for a given set of segments: the result depends on
 * the site set and the constraint set only, not on the insertion order or the
 * thread count of the unconstrained triangulation.
 *
 * Rules for the segments (the endpoints are input indices; the job already
 * merged exact duplicates, so they are mapped to sites first):
 *	- both ends on the same site: ignored (zero length);
 *	- a site lying exactly on the open segment splits it there: the walk
 *	  meets that site (as the far end of an edge out of the current end, or
 *	  as the apex of a crossed triangle) and continues from it; no site is
 *	  ever created;
 *	- collinear overlaps: the shared stretch is already a chain of
 *	  constraint edges, found as existing edges by the walk;
 *	- a proper crossing with an earlier segment is found when the walk
 *	  would cross one of its edges: TDC_ECROSS, naming both segments.
 *
 * Parallel pass.  With at least PART_MIN_SEG segments, the sites are cut
 * into NPART vertical stripes of equal width (a function of the sites alone,
 * never of the thread count).  A segment with both ends in stripe k goes to
 * stripe k's inserter, which takes its segments in input order and may only
 * change triangles whose three corners lie in stripe k: the moment a piece
 * would touch another triangle (a corner, a split site or a crossed triangle
 * outside the stripe, or more crossed edges than its fixed lists hold), it
 * leaves the segment, before changing anything of that piece, to the serial
 * pass.  Such triangles are never flipped by anyone in this pass (a flip
 * stays inside the union of the triangles a segment crosses), and an
 * inserter reads only edges with an end in its stripe, so inserters of
 * different stripes share nothing they write: the stripes run on a pool of
 * the job's thread count, in any order, and leave the same mesh, half-edge
 * for half-edge, as one thread running them one after the other.  Then the
 * serial pass inserts, in input order, every segment not done (ends in two
 * stripes, or left over), finding the pieces already in place as edges.
 * An error is the one of the lowest stripe that failed, else the serial
 * pass's, so it does not depend on the thread count either.  A counting
 * sort in the preparation lists each stripe's segments (and those with ends
 * in two stripes) in input order, so no inserter reads the others'.
 *
 * Speed.  Contour lines are mostly Delaunay edges already, so the insertion
 * of a million of them is mostly find_edge: turning around a segment's first
 * end to meet the other, a cache miss a step, each step depending on the
 * last.  find_edge turns both ways at once, and a stripe's inserter fetches
 * the first steps of its next segments ahead (part_task), so that several
 * misses are in flight at a time.
 *
 * Invariants between segments: the mesh is a triangulation of the convex
 * hull of the sites (hull edges are never crossed, so never flipped, so the
 * job's outer-face bitmap and triangle count stay right); every constraint
 * edge carries the smallest number (+ 1) of the segments that made it,
 * every other edge NO_SEG; vedge[s] is a half-edge leaving site s.  The
 * number of edges never changes (a flip keeps its edge slot), so the mesh
 * needs no memory.
 *
 * Memory: 4 bytes per edge slot for the constraint numbers (12 per point),
 * 4 per site for vedge, the job's input map (4 per input point), and the
 * serial lists of crossed and new edges, which start small and double up to
 * one entry per edge slot (12 bytes per point each, counted in full); the
 * parallel pass adds 6 bytes per segment (its stripe, whether it is done,
 * and its place in the stripes' order), 1 per point and NPART fixed lists.
 * Cancel is polled before every segment and every 4096 steps inside one.  The
 * insertion runs like a triangulation, on the caller's thread when it is
 * small, otherwise on a thread with every signal blocked that the host
 * waits for and cancels (the runner of runner.c), whose pool threads
 * inherit that mask.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"

/* cons[] holds segment number + 1, so that the zeroed array means "none" */
#define NO_SEG		0					/* edge is no constraint */
#define CAV			UINT32_MAX			/* new edge of the current cavity */
#define CAVQ		(UINT32_MAX - 1)	/* ... and on the Lawson stack */
#define MAX_SEG		((size_t) UINT32_MAX - 3)
#define POLL_STEPS	4096

/*
 * The parallel pass: NPART vertical stripes of equal width over the sites'
 * x range, a number fixed so that the work, the mesh and the error reported
 * are the same for every thread count.  Below PART_MIN_SEG segments the
 * pass would cost more than it saves.
 */
#define NPART		16
#define PART_MIN_SEG 8192
#define PART_CAP	4096			/* crossed edges a stripe's walk may list */
#define LIST_MIN	4096			/* the serial lists' first size */
#define SEG_SERIAL	0xfe			/* seg_part[]: ends in two stripes */
#define SEG_NONE	0xff			/* ... both ends on one site */
#define TDC_DEFER	1				/* insert_segment: leave it to the serial pass */

/*
 * One inserter: the serial one (part < 0, any site), or the one of stripe
 * "part" in the parallel pass, which may only touch triangles whose three
 * corners lie in its stripe.  Each has its own lists, poll counter and
 * error, so inserters of different stripes share nothing they write.
 */
typedef struct cdt_ctx
{
	struct tdc_cdt *c;
	int			part;			/* stripe, or -1: serial */
	uint32_t   *list;			/* crossed edges, used as a circular queue */
	uint32_t   *fresh;			/* new edges, then the Lawson stack */
	size_t		cap;
	size_t		nconstraint;	/* constraint edges this inserter made */
	size_t		ndone;			/* a stripe's: segments it inserted */
	size_t		ndeferred;		/* ... and left to the serial pass */
	size_t		cross[2];		/* the two segments of a TDC_ECROSS */
	long		steps;
	int			rc;
	char		err[512];
} cdt_ctx;

struct tdc_cdt
{
	tdc_job    *job;
	tdc_cache  *cache;			/* the job's, kept: the job may be freed first */
	const uint32_t *seg;		/* caller's pairs of input indices */
	size_t		nseg;
	tdc_mesh	m;
	uint32_t   *cons;			/* per edge slot: segment number + 1, or NO_SEG/CAV/CAVQ */
	uint32_t   *vedge;			/* per site: a half-edge leaving it */
	uint32_t   *list;			/* the serial inserter's lists (grow_lists) */
	uint32_t   *fresh;
	size_t		nslots;			/* edge slots: the most any list needs */
	uint32_t   *part_lists;		/* the stripes' lists, PART_CAP each, 2 per stripe */
	size_t		nconstraint;	/* constraint edges */
	size_t		cross[2];		/* the two segments of a TDC_ECROSS */
	size_t		npar_done;		/* segments the stripes inserted */
	size_t		npar_deferred;	/* ... and left to the serial pass */
	size_t		npar_serial;	/* segments with ends in two stripes */

	/* the parallel pass (only for at least PART_MIN_SEG segments) */
	uint8_t    *spart;			/* per site: its stripe (x_part) */
	uint8_t    *seg_part;		/* per segment: its stripe, SEG_SERIAL or SEG_NONE */
	uint8_t    *seg_done;		/* per segment: inserted by its stripe's inserter */
	uint32_t   *order;			/* the segments of stripe 0, then of 1, ..., each in input order */
	size_t		part_off[NPART + 2];	/* stripe k's: order[part_off[k] .. part_off[k + 1]);
										 * k = NPART: those with ends in two stripes */
	double		part_x0;		/* stripe of x: (x - part_x0) * part_scale */
	double		part_scale;
	cdt_ctx    *parts;			/* NPART inserters */
	cdt_ctx		serial;

	atomic_int	cancel;
	bool		inline_run;
	tdc_runner	run;			/* the job's lifecycle (runner.c) */
	char		err[512];
};

static int	cdt_fail(cdt_ctx *x, int code, const char *fmt,...)
			__attribute__((format(printf, 3, 4)));

static int
cdt_fail(cdt_ctx *x, int code, const char *fmt,...)
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
	return c->job->outer != NULL && ((c->job->outer[h >> 6] >> (h & 63)) & 1);
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

/* The stripe of site v: a function of its x alone, never of the threads. */
static inline int
site_part(const tdc_cdt *c, uint32_t v)
{
	return c->spart[v];
}

/* The stripe of an x coordinate. */
static inline uint8_t
x_part(const tdc_cdt *c, double x)
{
	double		t = (x - c->part_x0) * c->part_scale;

	if (!(t > 0))
		return 0;
	if (t >= NPART)
		return NPART - 1;
	return (uint8_t) t;
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
	return c->job->input + 2 * i;
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
	return cdt_fail(x, TDC_ECROSS,
					"constraint segments cross: segment %zu from (%.17g %.17g) to (%.17g %.17g) and segment %zu from (%.17g %.17g) to (%.17g %.17g)",
					s2, a[0], a[1], b[0], b[1], s1, p[0], p[1], q[0], q[1]);
}

static int
internal_error(cdt_ctx *x, size_t s, const char *what)
{
	return cdt_fail(x, TDC_EINVAL, "internal error inserting segment %zu: %s", s, what);
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
				return internal_error(x, s, "no crossed edge can be flipped");
		}
	}
	return TDC_OK;
}

/*
 * Lawson's flips among the n new edges of a cavity, marked CAV in cons[];
 * the constraint and the cavity's border are not listed, so never flipped.
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
		return internal_error(x, s, "more crossed edges than edges");
	l = realloc(c->list, cap * sizeof(uint32_t));
	if (l != NULL)
		c->list = x->list = l;
	f = l ? realloc(c->fresh, cap * sizeof(uint32_t)) : NULL;
	if (f == NULL)
		return cdt_fail(x, TDC_ENOMEM, "out of memory for the crossed edges of segment %zu", s);
	c->fresh = x->fresh = f;
	x->cap = cap;
	return TDC_OK;
}

/*
 * Insert segment s from site a to site b (a != b), piece by piece.  A
 * stripe's inserter returns TDC_DEFER, before it changes anything of the
 * piece at hand, when that piece would touch a triangle with a corner
 * outside its stripe (or needs more crossed edges than its lists hold); the
 * pieces already in place stay, and the serial pass finds them as edges.
 */
static int
insert_segment(cdt_ctx *x, size_t s, uint32_t a, uint32_t b)
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
			return internal_error(x, s, "no triangle around its start");
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
				return internal_error(x, s, "the walk left the convex hull");
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
			return internal_error(x, s, "the constraint is no edge after the flips");
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
static int
seg_sites(cdt_ctx *x, size_t s, uint32_t *a, uint32_t *b)
{
	const tdc_cdt *c = x->c;
	const tdc_job *job = c->job;

	if (c->seg[2 * s] >= job->n || c->seg[2 * s + 1] >= job->n)
		return cdt_fail(x, TDC_EINVAL, "segment %zu has an end point index out of range (%u %u, %zu points)",
						s, c->seg[2 * s], c->seg[2 * s + 1], job->n);
	*a = tdc_input_site(job, c->seg[2 * s]);
	*b = tdc_input_site(job, c->seg[2 * s + 1]);
	if (*a == UINT32_MAX || *b == UINT32_MAX)
		return cdt_fail(x, TDC_ENOMEM, "out of memory for the input map");
	return TDC_OK;
}

/* The status of inserter x, its message and crossing moved to c. */
static int
take_error(tdc_cdt *c, const cdt_ctx *x, int rc)
{
	memcpy(c->err, x->err, sizeof(c->err));
	c->cross[0] = x->cross[0];
	c->cross[1] = x->cross[1];
	return rc;
}

/*
 * The preparation of the parallel pass, as tasks: task 0 sets vedge[],
 * task k > 0 sorts chunk k - 1 of the segments by stripe: both ends in
 * stripe i gives i, ends in two stripes SEG_SERIAL, one site SEG_NONE, and
 * counts the chunk's segments of each stripe.  A chunk stops at its first
 * bad segment and notes it in bad[k - 1].  Then order_task lists each
 * stripe's segments in order[], so that a stripe's inserter reads its own
 * segments only, not every segment's stripe (16 passes over them cost more
 * instructions than the insertion of contour lines).
 */
#define PREP_CHUNK	65536

/* order[]'s range of a seg_part[] value other than SEG_NONE: its stripe, or NPART */
static inline int
bucket(uint8_t part)
{
	return part < NPART ? part : NPART;
}

typedef struct cdt_prep
{
	tdc_cdt    *c;
	size_t	   *bad;
	size_t	   *pos;			/* per chunk and stripe: its count, then where it goes in order[] */
} cdt_prep;

/* Task k: the stripes of sites [k * PREP_CHUNK, (k + 1) * PREP_CHUNK). */
static void
spart_task(void *arg, size_t k, int worker)
{
	tdc_cdt    *c = arg;
	size_t		lo = k * PREP_CHUNK,
				hi = lo + PREP_CHUNK < c->job->nin ? lo + PREP_CHUNK : c->job->nin;

	for (size_t p = lo; p < hi; p++)
		c->spart[p] = x_part(c, c->job->xy[2 * p]);
}

static void
prep_task(void *arg, size_t k, int worker)
{
	cdt_prep   *pp = arg;
	tdc_cdt    *c = pp->c;
	const tdc_job *job = c->job;
	size_t		lo,
				hi;
	const uint32_t *map;

	if (k == 0)
	{
		for (size_t h = 0; h < 6 * job->nin; h++)
		{
			if (job->he[h].org != TDC_NIL)
				c->vedge[job->he[h].org] = (uint32_t) h;
			if ((h & ((1 << 20) - 1)) == 0 &&
				atomic_load_explicit(&c->cancel, memory_order_relaxed))
				return;
		}
		return;
	}
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return;
	lo = (k - 1) * PREP_CHUNK;
	hi = lo + PREP_CHUNK < c->nseg ? lo + PREP_CHUNK : c->nseg;
	/* the first call builds the map, under the job's lock */
	if (tdc_input_site(job, 0) == UINT32_MAX)
	{
		pp->bad[k - 1] = lo;
		return;
	}
	map = atomic_load_explicit(&((tdc_job *) job)->map, memory_order_acquire);
	for (size_t s = lo; s < hi; s++)
	{
		uint32_t	i = c->seg[2 * s],
					j = c->seg[2 * s + 1],
					a,
					b;
		int			pa;

		if (i >= job->n || j >= job->n)
		{
			pp->bad[k - 1] = s;
			return;
		}
		a = map[i];
		b = map[j];
		pa = site_part(c, a);
		c->seg_part[s] = a == b ? SEG_NONE : pa == site_part(c, b) ? (uint8_t) pa : SEG_SERIAL;
		if (c->seg_part[s] != SEG_NONE)
			pp->pos[(k - 1) * (NPART + 1) + bucket(c->seg_part[s])]++;
	}
}

/*
 * Task k: chunk k's segments into order[], each to its stripe's range (or
 * the range of those with ends in two stripes) at the place prepare()
 * computed for this chunk, so that every range holds its segments in input
 * order.
 */
static void
order_task(void *arg, size_t k, int worker)
{
	cdt_prep   *pp = arg;
	tdc_cdt    *c = pp->c;
	size_t		lo = k * PREP_CHUNK,
				hi = lo + PREP_CHUNK < c->nseg ? lo + PREP_CHUNK : c->nseg,
			   *pos = pp->pos + k * (NPART + 1);

	for (size_t s = lo; s < hi; s++)
		if (c->seg_part[s] != SEG_NONE)
			c->order[pos[bucket(c->seg_part[s])]++] = (uint32_t) s;
}

/* Set vedge[] and sort the segments by stripe (prep_task), on the pool. */
static int
prepare(tdc_cdt *c, tdc_pool *pool, cdt_ctx *ser)
{
	const tdc_job *job = c->job;
	size_t		nchunks = (c->nseg + PREP_CHUNK - 1) / PREP_CHUNK;
	cdt_prep	pp = {c, malloc(nchunks * sizeof(size_t)), calloc(nchunks * (NPART + 1), sizeof(size_t))};
	double		lo = INFINITY,
				hi = -INFINITY;
	size_t		at = 0;

	if (pp.bad == NULL || pp.pos == NULL)
	{
		free(pp.bad);
		free(pp.pos);
		return cdt_fail(ser, TDC_ENOMEM, "out of memory for the constraints");
	}
	for (size_t p = 0; p < job->nin; p++)
	{
		double		v = job->xy[2 * p];

		lo = v < lo ? v : lo;
		hi = v > hi ? v : hi;
	}
	c->part_x0 = lo;
	c->part_scale = hi > lo ? NPART / (hi - lo) : 0;
	tdc_pool_for(pool, (job->nin + PREP_CHUNK - 1) / PREP_CHUNK, spart_task, c);
	for (size_t k = 0; k < nchunks; k++)
		pp.bad[k] = SIZE_MAX;
	tdc_pool_for(pool, nchunks + 1, prep_task, &pp);
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
	{
		free(pp.bad);
		free(pp.pos);
		return TDC_ECANCELED;
	}
	for (size_t k = 0; k < nchunks; k++)
		if (pp.bad[k] != SIZE_MAX)
		{
			uint32_t	a,
						b;
			int			rc = seg_sites(ser, pp.bad[k], &a, &b);

			free(pp.bad);
			free(pp.pos);
			return rc != TDC_OK ? rc : internal_error(ser, pp.bad[k], "a segment was misread");
		}
	/* range by range, chunk by chunk: where each chunk's part of a range goes */
	for (int p = 0; p <= NPART; p++)
	{
		c->part_off[p] = at;
		for (size_t k = 0; k < nchunks; k++)
		{
			size_t		n = pp.pos[k * (NPART + 1) + p];

			pp.pos[k * (NPART + 1) + p] = at;
			at += n;
		}
	}
	c->part_off[NPART + 1] = at;
	tdc_pool_for(pool, nchunks, order_task, &pp);
	free(pp.bad);
	free(pp.pos);
	return TDC_OK;
}

/* How far ahead part_task fetches (see there). */
#define PF_DIST		8

/* The pool's task k: stripe k's segments, in input order. */
static void
part_task(void *arg, size_t k, int worker)
{
	tdc_cdt    *c = arg;
	cdt_ctx    *x = &c->parts[k];
	/* prepare() checked the ends and built the input map */
	const uint32_t *map = atomic_load_explicit(&c->job->map, memory_order_acquire);
	const tdc_he *he = c->m.he;
	size_t		end = c->part_off[k + 1];

	for (size_t i = c->part_off[k]; i < end; i++)
	{
		size_t		s = c->order[i];
		uint32_t	a,
					b;
		int			rc;

		if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		{
			x->rc = TDC_ECANCELED;
			return;
		}

		/*
		 * Fetch ahead what insert_segment will need for the segments to
		 * come: they are mostly edges already (contour lines), found by
		 * turning around their first end (find_edge), each step a cache miss
		 * that the next depends on.  vedge[] of the segment 2 * PF_DIST ahead,
		 * that half-edge's line PF_DIST ahead, and PF_DIST / 2 ahead the
		 * lines of its two neighbours around the site (find_edge turns both
		 * ways) and the three constraint slots: these misses are then in
		 * flight while earlier segments are inserted.  Edges around the
		 * stripe's own sites only, which no other inserter changes.  (1M
		 * contour segments, one thread: the insertion's CPU time -25%.)  In
		 * line, not in a function: GCC deletes a call whose body only
		 * prefetches.
		 */
		if (i + PF_DIST < end)
			__builtin_prefetch(&he[c->vedge[map[c->seg[2 * (size_t) c->order[i + PF_DIST]]]]]);
		if (i + PF_DIST / 2 < end)
		{
			uint32_t	v = c->vedge[map[c->seg[2 * (size_t) c->order[i + PF_DIST / 2]]]],
						n = he[v].next,
						p = he[v].prev;

			__builtin_prefetch(&he[n]);
			__builtin_prefetch(&he[p]);
			__builtin_prefetch(&c->cons[v >> 1]);
			__builtin_prefetch(&c->cons[n >> 1]);
			__builtin_prefetch(&c->cons[p >> 1]);
		}
		if (i + 2 * PF_DIST < end)
			__builtin_prefetch(&c->vedge[map[c->seg[2 * (size_t) c->order[i + 2 * PF_DIST]]]]);
		a = map[c->seg[2 * s]];
		b = map[c->seg[2 * s + 1]];
		rc = insert_segment(x, s, a, b);
		if (rc == TDC_OK)
		{
			c->seg_done[s] = 1;
			x->ndone++;
		}
		else if (rc == TDC_DEFER)
			c->order[c->part_off[k] + x->ndeferred++] = (uint32_t) s;	/* behind i */
		else
		{
			x->rc = rc;
			return;
		}
	}
}

/*
 * The parallel pass.  Stripe k's inserter only changes triangles whose three
 * corners lie in stripe k, and only reads edges with an end in stripe k or
 * triangles no inserter changes (those with corners in two stripes), so the
 * stripes' inserters touch disjoint parts of the mesh: run in any order or
 * at once, they leave the same mesh, and the first stripe with an error
 * names the same error.  With one thread they run one after the other, and
 * stop at the first error, as the threads' result is read.
 */
static int
run_parts(tdc_cdt *c, tdc_pool *pool)
{
	for (int k = 0; k < NPART; k++)
	{
		cdt_ctx    *x = &c->parts[k];

		x->c = c;
		x->part = k;
		x->list = c->part_lists + (size_t) 2 * k * PART_CAP;
		x->fresh = x->list + PART_CAP;
		x->cap = PART_CAP;
		x->cross[0] = x->cross[1] = SIZE_MAX;
	}
	if (pool != NULL)
		tdc_pool_for(pool, NPART, part_task, c);
	else
	{
		for (int k = 0; k < NPART; k++)
		{
			part_task(c, (size_t) k, 0);
			if (c->parts[k].rc != TDC_OK)
				break;
		}
	}
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return TDC_ECANCELED;
	for (int k = 0; k < NPART; k++)
	{
		c->nconstraint += c->parts[k].nconstraint;
		c->npar_done += c->parts[k].ndone;
		c->npar_deferred += c->parts[k].ndeferred;
		if (c->parts[k].rc != TDC_OK)
			return take_error(c, &c->parts[k], c->parts[k].rc);
	}
	return TDC_OK;
}

/* The serial inserter on segment s; an error is taken into c. */
static int
serial_insert(tdc_cdt *c, cdt_ctx *ser, size_t s)
{
	uint32_t	a,
				b;
	int			rc;

	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return TDC_ECANCELED;
	rc = seg_sites(ser, s, &a, &b);
	if (rc == TDC_OK && a != b)
		rc = insert_segment(ser, s, a, b);
	return rc == TDC_OK ? TDC_OK : take_error(c, ser, rc);
}

/*
 * Many segments: the parallel pass then the serial one for what it left;
 * few: the serial one alone.  The pool is the job's thread count (none for
 * one thread: tdc_pool_for then runs the tasks itself).
 */
static int
cdt_run(tdc_cdt *c)
{
	tdc_job    *job = c->job;
	size_t		nslots = job->nin * 3;
	cdt_ctx    *ser = &c->serial;
	int			rc,
				threads = tdc_threads_used(job);

	c->m.xy = job->xy;
	c->m.he = job->he;
	c->m.cancel = &c->cancel;
	c->nslots = nslots;
	ser->c = c;
	ser->part = -1;
	ser->cross[0] = ser->cross[1] = SIZE_MAX;
	c->cons = tdc_big_alloc(c->cache, nslots * sizeof(uint32_t) + 4);
	c->vedge = tdc_big_alloc(c->cache, job->nin * sizeof(uint32_t) + 4);
	ser->cap = nslots < LIST_MIN ? nslots : LIST_MIN;
	c->list = malloc(ser->cap * sizeof(uint32_t) + 4);
	c->fresh = malloc(ser->cap * sizeof(uint32_t) + 4);
	if (c->nseg >= PART_MIN_SEG)
	{
		c->seg_part = tdc_big_alloc(c->cache, 2 * c->nseg + job->nin);
		c->order = tdc_big_alloc(c->cache, c->nseg * sizeof(uint32_t));
		c->parts = calloc(NPART, sizeof(cdt_ctx));
		c->part_lists = malloc((size_t) 2 * NPART * PART_CAP * sizeof(uint32_t));
	}
	if (!c->cons || !c->vedge || !c->list || !c->fresh ||
		(c->nseg >= PART_MIN_SEG && (!c->seg_part || !c->order || !c->parts || !c->part_lists)))
		return take_error(c, ser, cdt_fail(ser, TDC_ENOMEM, "out of memory for the constraints of %zu points", job->nin));
	ser->list = c->list;
	ser->fresh = c->fresh;

	/* tdc_big_alloc's memory is zeroed: every cons[] is NO_SEG */
	if (c->seg_part != NULL)
	{
		tdc_pool   *pool = NULL;

		c->seg_done = c->seg_part + c->nseg;
		c->spart = c->seg_done + c->nseg;
		if (threads > 1 &&
			(rc = tdc_pool_create(&pool, threads < NPART ? threads : NPART)) != TDC_OK)
			return take_error(c, ser, cdt_fail(ser, rc, "could not create the insertion's threads"));
		rc = prepare(c, pool, ser);
		if (rc == TDC_OK)
			rc = run_parts(c, pool);
		else
			rc = take_error(c, ser, rc);
		tdc_pool_destroy(pool);
		if (rc != TDC_OK)
			return rc;
	}
	else
		for (size_t h = 0; h < 2 * nslots; h++)
			if (job->he[h].org != TDC_NIL)
				c->vedge[job->he[h].org] = (uint32_t) h;

	/*
	 * The serial pass, in input order.  After the parallel pass with no
	 * segment left over (contour lines: the common case), the ones with ends
	 * in two stripes are all there is, already listed in input order.
	 */
	if (c->seg_done != NULL)
		c->npar_serial = c->part_off[NPART + 1] - c->part_off[NPART];
	if (c->seg_done != NULL && c->npar_deferred == 0)
	{
		for (size_t i = c->part_off[NPART]; i < c->part_off[NPART + 1]; i++)
		{
			if ((rc = serial_insert(c, ser, c->order[i])) != TDC_OK)
				return rc;
		}
		return TDC_OK;
	}
	for (size_t s = 0; s < c->nseg; s++)
	{
		if (c->seg_done != NULL && (c->seg_done[s] || c->seg_part[s] == SEG_NONE))
			continue;
		if ((rc = serial_insert(c, ser, s)) != TDC_OK)
			return rc;
	}
	return TDC_OK;
}

/* The work, on the runner's thread or the caller's; returns the status. */
static int
cdt_work(void *arg)
{
	tdc_cdt    *c = arg;
	int			rc = cdt_run(c);

	c->nconstraint += c->serial.nconstraint;
	/* the lists are only needed while inserting */
	free(c->list);
	free(c->fresh);
	tdc_big_free(c->cache, c->vedge);
	tdc_big_free(c->cache, c->seg_part);
	tdc_big_free(c->cache, c->order);
	free(c->parts);
	free(c->part_lists);
	c->list = c->fresh = c->vedge = c->part_lists = c->order = NULL;
	c->seg_part = c->seg_done = c->spart = NULL;
	c->parts = NULL;
	if (rc == TDC_ECANCELED)
		snprintf(c->err, sizeof(c->err), "constraint insertion cancelled");
	else if (rc == TDC_OK)
		c->err[0] = '\0';
	return rc;
}

size_t
tdc_cdt_memory(size_t n)
{
	/* cons, vedge, list, fresh, and the job's input map */
	return n * (3 * 4 + 4 + 3 * 4 + 3 * 4 + 4) + 64;
}

/* The parallel pass's own arrays, for nseg segments and n points. */
static size_t
cdt_seg_memory(size_t nseg, size_t n)
{
	return nseg >= PART_MIN_SEG ?
		(2 + sizeof(uint32_t)) * nseg + n + NPART * (sizeof(cdt_ctx) + 2 * PART_CAP * sizeof(uint32_t)) +
		((nseg + PREP_CHUNK - 1) / PREP_CHUNK) * (NPART + 2) * sizeof(size_t) : 0;
}

int
tdc_cdt_start(tdc_job *job, const uint32_t *seg, size_t nseg, tdc_cdt **out,
			  char *err, size_t errlen)
{
	tdc_cdt    *c;
	int			rc;

#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	*out = NULL;
	if (err && errlen)
		err[0] = '\0';
	if (tdc_job_wait(job, 0) != TDC_OK)
		FAIL(TDC_EINVAL, "the triangulation has not finished successfully");
	if (nseg > MAX_SEG)
		FAIL(TDC_ETOOBIG, "%zu constraint segments exceed the limit of %zu", nseg, MAX_SEG);
	if (nseg > 0 && seg == NULL)
		FAIL(TDC_EINVAL, "no end points given for %zu segments", nseg);
	if (job->opt.max_memory > 0 &&
		tdc_estimate_memory(job->n, &job->opt) + tdc_cdt_memory(job->n) +
		cdt_seg_memory(nseg, job->n) > job->opt.max_memory)
		FAIL(TDC_EMEMLIMIT, "constraining %zu points needs about %zu MB, more than the limit of %zu MB",
			 job->n, (tdc_estimate_memory(job->n, &job->opt) + tdc_cdt_memory(job->n) +
					  cdt_seg_memory(nseg, job->n)) >> 20,
			 job->opt.max_memory >> 20);
	c = calloc(1, sizeof(tdc_cdt));
	if (c == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	c->job = job;
	c->cache = job->opt.cache;
	c->seg = seg;
	c->nseg = nseg;
	c->cross[0] = c->cross[1] = SIZE_MAX;
	tdc_runner_init(&c->run, &c->cancel);

	/* like the triangulation: small work runs on the caller's thread */
	c->inline_run = job->n < TDC_INLINE_MAX && nseg < TDC_INLINE_MAX;
	rc = tdc_runner_start(&c->run, c->inline_run, cdt_work, c, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&c->run);
		free(c);
		return rc;
	}
	*out = c;
	return TDC_OK;
#undef FAIL
}

int
tdc_cdt_wait(tdc_cdt *c, int timeout_ms)
{
	return tdc_runner_wait(&c->run, timeout_ms);
}

void
tdc_cdt_cancel(tdc_cdt *c)
{
	if (c)
		tdc_runner_cancel(&c->run);
}

const char *
tdc_cdt_error(const tdc_cdt *c)
{
	return c->err;
}

int
tdc_cdt_crossing(const tdc_cdt *c, size_t *s1, size_t *s2)
{
	if (c->run.status != TDC_ECROSS)
		return 0;
	*s1 = c->cross[0];
	*s2 = c->cross[1];
	return 1;
}

size_t
tdc_cdt_num_constraint_edges(const tdc_cdt *c)
{
	return c->nconstraint;
}

void
tdc_cdt_pass_counts(const tdc_cdt *c, size_t *parallel, size_t *deferred, size_t *serial)
{
	*parallel = c->npar_done;
	*deferred = c->npar_deferred;
	*serial = c->npar_serial;
}

void
tdc_cdt_free(tdc_cdt *c)
{
	if (c == NULL)
		return;
	tdc_runner_destroy(&c->run);
	tdc_big_free(c->cache, c->cons);
	free(c->list);
	free(c->fresh);
	tdc_big_free(c->cache, c->vedge);
	tdc_big_free(c->cache, c->seg_part);
	tdc_big_free(c->cache, c->order);
	free(c->parts);
	free(c->part_lists);
	free(c);
}

int
tdc_cdt_run(tdc_job *job, const uint32_t *seg, size_t nseg, tdc_cdt **out,
			char *err, size_t errlen)
{
	int			rc = tdc_cdt_start(job, seg, nseg, out, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_cdt_wait(*out, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", tdc_cdt_error(*out));
	return rc;
}

int
tdc_next_constraint_edge(const tdc_cdt *c, tdc_iter *it, uint32_t v[2])
{
	const tdc_job *job = c->job;
	size_t		nslots = job->nin * 3;

	if (c->cons == NULL || c->run.status != TDC_OK)
		return 0;
	for (size_t e = it->pos; e < nslots; e++)
	{
		uint32_t	a,
					b;

		if (c->cons[e] == NO_SEG || c->cons[e] >= CAVQ)
			continue;
		a = job->he[2 * e].org;
		b = job->he[2 * e + 1].org;
		if (tdc_key_less(job->xy + 2 * (size_t) b, job->xy + 2 * (size_t) a, 0))
			v[0] = b, v[1] = a;
		else
			v[0] = a, v[1] = b;
		it->pos = e + 1;
		return 1;
	}
	it->pos = nslots;
	return 0;
}

/*
 * Validate a finished constrained job: its sites, triangles and the input
 * segments, renumbered densely, through tdc_validate_cdt().
 */
int
tdc_cdt_validate(const tdc_cdt *c, char *err, size_t errlen)
{
	const tdc_job *job = c->job;
	size_t		n = tdc_num_input(job),
				m = 0,
				t = 0,
				ns = 0;
	uint32_t	lim = tdc_site_id_limit(job),
			   *dense = malloc(sizeof(uint32_t) * ((size_t) lim + 1)),
			   *tri = malloc(12 * (tdc_num_triangles(job) + 1)),
			   *seg = malloc(8 * (c->nseg + 1)),
				v[3];
	double	   *sites = malloc(16 * (tdc_num_sites(job) + 1));
	tdc_iter	it = {0};
	int			rc = -1;

	if (!dense || !tri || !sites || !seg)
	{
		snprintf(err, errlen, "out of memory for validation");
		goto done;
	}
	for (uint32_t s = 0; s < lim; s++)
		dense[s] = UINT32_MAX;
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);

		if (s >= lim || (dense[s] == UINT32_MAX && m == tdc_num_sites(job)))
		{
			snprintf(err, errlen, "input %zu maps to a bad site %u", i, s);
			goto done;
		}
		if (dense[s] == UINT32_MAX)
		{
			dense[s] = (uint32_t) m;
			memcpy(sites + 2 * m++, tdc_site_xy(job, s), 16);
		}
	}
	while (tdc_next_triangle(job, &it, v))
	{
		if (t == tdc_num_triangles(job))
		{
			snprintf(err, errlen, "more triangles than the %zu reported", tdc_num_triangles(job));
			goto done;
		}
		for (int k = 0; k < 3; k++)
		{
			if (v[k] >= lim || dense[v[k]] == UINT32_MAX)
			{
				snprintf(err, errlen, "a triangle uses site %u, which no input reaches", v[k]);
				goto done;
			}
			tri[3 * t + k] = dense[v[k]];
		}
		t++;
	}
	for (size_t s = 0; s < c->nseg; s++)
	{
		uint32_t	a = dense[tdc_input_site(job, c->seg[2 * s])],
					b = dense[tdc_input_site(job, c->seg[2 * s + 1])];

		if (a != b)
		{
			seg[2 * ns] = a;
			seg[2 * ns++ + 1] = b;
		}
	}
	if (t != tdc_num_triangles(job))
		snprintf(err, errlen, "%zu triangles iterated, %zu reported", t, tdc_num_triangles(job));
	else
		rc = tdc_validate_cdt(sites, m, tri, t, seg, ns, err, errlen);
done:
	free(dense);
	free(tri);
	free(sites);
	free(seg);
	return rc;
}
