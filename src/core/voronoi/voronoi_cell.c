/*
 * voronoi_cell.c
 *		The cells: walked around each site, clipped to the rectangle.
 *
 * Unbounded cells and clipping.  The diagram is clipped to the caller's
 * rectangle E, which must contain every site.  A hull site's cell is
 * unbounded: its ring of triangles is open at the outer face, and the two
 * hull edges there give two rays, perpendicular to them, pointing out.
 * The cell is first cut to a box B that strictly contains E, the sites
 * and every Voronoi vertex: each ray is followed to where it leaves B (the
 * hitting coordinate is set to B's side exactly), and the cell's boundary
 * is closed along B's boundary counter-clockwise through those corners of
 * B that lie in the cell.  Which corners those are is decided exactly (the
 * corner is nearer to the site than to each Delaunay neighbour), not from
 * the order of the two exits: B grows with the farthest Voronoi vertex,
 * 1e16 times the sites' extent for sites collinear up to ulps, and the
 * exits, rounded at that scale, can swap (see push_arc).  That is
 * cell ∩ B, a convex polygon, up to rounding at B's scale, far outside E;
 * and B is common to all cells, so a ray's exit point is the same double
 * pair in both cells beside it.  Then
 * every cell is clipped to E by Sutherland-Hodgman against E's four sides;
 * inside tests are exact comparisons, a crossing point is computed from the
 * crossing segment's end point nearer to the side (ties: the lexicographic
 * order), which does not depend on the cell, and gets the side's
 * coordinate exactly, so it lies on E's boundary and is shared by the two
 * cells of that edge.  A cell lying inside E is not touched.
 *
 *
 * Collinear sites.  With no triangle (every site on one line, or two sites),
 * the cells are slabs between the perpendicular bisectors of consecutive
 * sites, as GEOS (and so PostGIS) gives them; each bisector is cut to B the
 * same way and the slabs are closed along B's boundary, then clipped.  One
 * site: its cell is E.
 *
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "voronoi_int.h"

/* ----------------------------------------------------------------
 *		cells
 * ----------------------------------------------------------------
 */
/*
 * Where the ray from p (strictly inside B) along d leaves B, with the
 * coordinate of the side it hits set to that side exactly.  *side: 0 bottom,
 * 1 right, 2 top, 3 left, the counter-clockwise order of B's boundary.
 */
static void
box_exit(const double *box, const double *p, double dx, double dy,
		 double out[2], int *side)
{
	double		tx = INFINITY,
				ty = INFINITY;
	int			sx = -1,
				sy = -1;

	if (dx > 0)
		tx = (box[2] - p[0]) / dx, sx = 1;
	else if (dx < 0)
		tx = (box[0] - p[0]) / dx, sx = 3;
	if (dy > 0)
		ty = (box[3] - p[1]) / dy, sy = 2;
	else if (dy < 0)
		ty = (box[1] - p[1]) / dy, sy = 0;
	/*
	 * A direction component can be so small against the box that its time
	 * overflows to infinity like that of a zero component: only a side the
	 * ray moves towards may be taken (found by fuzz_voronoi: side -1).
	 */
	if (sx == -1 && sy == -1)
	{
		/* no direction at all: cannot happen for distinct sites; stay put */
		out[0] = fmin(fmax(p[0], box[0]), box[2]);
		out[1] = box[1];
		*side = 0;
	}
	else if (sy == -1 || (sx != -1 && tx <= ty))
	{
		out[0] = sx == 1 ? box[2] : box[0];
		out[1] = fmin(fmax(p[1] + tx * dy, box[1]), box[3]);
		*side = sx;
	}
	else
	{
		out[1] = sy == 2 ? box[3] : box[1];
		out[0] = fmin(fmax(p[0] + ty * dx, box[0]), box[2]);
		*side = sy;
	}
}

static const int box_cx[4] = {2, 2, 0, 0},
			box_cy[4] = {1, 3, 3, 1};

/*
 * Is B's corner k (the end of side k going counter-clockwise: 0 bottom
 * right, 1 top right, 2 top left, 3 bottom left) in the cell of site s
 * rather than in that of site g?  Exact: the nearer site, ties to the
 * lexicographically smaller, so of two neighbours exactly one claims it.
 * |c - s|^2 - |c - g|^2 = (g - s) . (2c - s - g), summed as an exact
 * expansion: no squares of B's size (B can be 1e16 times the sites'
 * extent and more), so nothing overflows or needs a range.
 */
static bool
corner_closer(const tdc_voronoi *v, int k, uint32_t s, uint32_t g)
{
	const double c[2] = {v->box[box_cx[k]], v->box[box_cy[k]]};
	const double *ps = site_pt(v, s),
			   *pg = site_pt(v, g);
	double		e[24];
	int			n = 0;

	for (int i = 0; i < 2; i++)
	{
		double		d[2],
					t1[2],
					t2[3];
		int			nd = dd_exp(dd_two_sum(pg[i], -ps[i]), d),
					n1 = dd_exp(dd_two_sum(2 * c[i], -ps[i]), t1),
					n2 = grow_expansion(n1, t1, -pg[i], t2);

		n = expansion_add_product(n, e, nd, d, n2, t2, 1);
	}
	if (n > 0)
		return e[n - 1] < 0;
	return tdc_lex_less(ps, pg);
}

/*
 * Append, going counter-clockwise along B's boundary from a point on side
 * sf to a point on side st, the corners passed that lie in the cell
 * ("owned", bit k for corner k, decided exactly by the caller).  Never the
 * full loop: with sf == st no corner is passed.
 *
 * Why the ownership and not the two points' order: the points are exits of
 * rays from Voronoi vertices that may lie 1e16 times farther out than the
 * sites (nearly collinear sites), so B is that large and the exits are
 * rounded at B's scale, while the cell may be a strip only a few units
 * wide.  Rounded, two exits can swap along a side, or one can slip round a
 * corner; walking by their order then went round all of B and wound the
 * cell twice (fuzz/known/voronoi_flat_hull_double_wound).  The exact cell
 * never contains all four corners (it would contain B and the other
 * sites), the corners it does contain are exactly those between its exits,
 * and a rounded exit can slip past a corner only if it is within rounding
 * of that corner: so the walk pushes every corner the cell owns, none it
 * does not, and what rounding still misplaces stays within an ulp of B's
 * boundary, far outside E, where clipping cuts it off.
 */
static void
push_arc(ring *r, const double *box, int sf, int st, unsigned owned)
{
	for (int s = sf; s != st; s = (s + 1) & 3)
		if (owned & (1u << s))
			ring_push(r, box[box_cx[s]], box[box_cy[s]], TDC_NIL);
}

/*
 * Clip ring "in" to the half-plane coord[axis] >= c (keep_ge) or <= c into
 * "out" (Sutherland-Hodgman).  A crossing point is computed from the
 * crossing segment's end points in an order fixed by their coordinates, so
 * it does not depend on which of the two cells beside the segment asks.
 */
static void
clip_side(const tdc_voronoi *v, uint32_t site, const ring *in, ring *out,
		  int axis, double c, bool keep_ge)
{
	out->n = 0;
	for (size_t i = 0; i < in->n; i++)
	{
		const double *p = in->p + 2 * i,
				   *q = in->p + 2 * ((i + 1) % in->n);
		bool		pin = keep_ge ? p[axis] >= c : p[axis] <= c,
					qin = keep_ge ? q[axis] >= c : q[axis] <= c;

		uint32_t	g = in->tag[i];

		if (pin)
			ring_push(out, p[0], p[1], g);
		if (pin != qin)
		{
			/*
			 * From the end point nearer to the line: the other may be a ray's
			 * exit from B, far away (B grows with the farthest Voronoi
			 * vertex), and interpolating from there would lose the digits
			 * of the crossing.  Ties go to the lexicographically smaller.
			 */
			double		dp = fabs(p[axis] - c),
						dq = fabs(q[axis] - c);
			bool		p_first = dp < dq || (dp == dq && tdc_lex_less(p, q));
			const double *a = p_first ? p : q,
					   *b = p_first ? q : p;
			int			o = 1 - axis;
			double		t = (c - a[axis]) / (b[axis] - a[axis]);
			double		w = a[o] + t * (b[o] - a[o]);
			double		pt[2];

			if (g != TDC_NIL)
			{
				/*
				 * On the bisector of the site and its neighbour g, taken in
				 * lexicographic order so that both cells agree: exact
				 * differences of sites near E, where the end points may be
				 * Voronoi vertices 1e16 away, rounded at that scale.
				 */
				const double *s0 = site_pt(v, site),
						   *s1 = site_pt(v, g),
						   *sa = tdc_lex_less(s0, s1) ? s0 : s1,
						   *sb = tdc_lex_less(s0, s1) ? s1 : s0;
				double		m[2] = {sa[0] * 0.5 + sb[0] * 0.5, sa[1] * 0.5 + sb[1] * 0.5};
				double		da = sb[axis] - sa[axis],
							dn = sb[o] - sa[o];

				if (dn != 0)
					w = m[o] + (m[axis] - c) * (da / dn);
			}
			w = fmin(fmax(w, fmin(a[o], b[o])), fmax(a[o], b[o]));
			pt[axis] = c;
			pt[o] = w;
			/* leaving: the next edge runs along the side; entering: along g's */
			ring_push(out, pt[0], pt[1], pin ? TDC_NIL : g);
		}
	}
	ring_close(out);
}

/* Clip cell "a" to E in place ("b" is scratch); false when out of memory. */
bool
tdc_vor_clip_to_env(const tdc_voronoi *v, uint32_t site, ring *a, ring *b)
{
	const double *e = v->env;
	bool		inside = true;

	for (size_t i = 0; i < a->n && inside; i++)
		inside = a->p[2 * i] >= e[0] && a->p[2 * i] <= e[2] &&
			a->p[2 * i + 1] >= e[1] && a->p[2 * i + 1] <= e[3];
	if (inside)
		return true;
	for (int k = 0; k < 4; k++)
	{
		ring		t;

		/* one half-plane adds at most one vertex */
		if (!ring_reserve(b, a->n + 2))
			return false;
		clip_side(v, site, a, b, k & 1, e[k], k < 2);
		t = *a;
		*a = *b;
		*b = t;
	}
	return true;
}

/* Exit points of the bisector ray of hull edge a -> b (outer face on its left), from p. */
static void
hull_ray(const tdc_voronoi *v, const double *p, uint32_t a, uint32_t b,
		 double out[2], int *side)
{
	const double *pa = site_pt(v, a),
			   *pb = site_pt(v, b);

	box_exit(v->box, p, -(pb[1] - pa[1]), pb[0] - pa[0], out, side);
}

/*
 * The ring of half-edges out of site s: its degree, and the one with the
 * outer face on its left (s is on the hull), or TDC_NIL.
 */
size_t
tdc_vor_site_degree(const tdc_voronoi *v, uint32_t s, uint32_t *ho)
{
	const tdc_mesh_view *mesh = &v->mesh;
	uint32_t	h0 = atomic_load_explicit(&v->site_he[s], memory_order_relaxed),
				h = h0;
	size_t		deg = 0;

	*ho = TDC_NIL;
	if (h0 == TDC_NIL)
		return 0;
	do
	{
		if (is_outer(mesh, h))
			*ho = h;
		deg++;
		h = mesh->he[h].next;
	} while (h != h0);
	return deg;
}

/*
 * Cell of site s of a mesh with triangles, uncut, into r (cell ∩ B), which
 * has room for deg + 8 vertices (deg and ho from tdc_vor_site_degree).  An
 * untagged r is for inner sites only: it skips the neighbours' lookups.
 */
void
tdc_vor_cell_of_mesh(const tdc_voronoi *v, uint32_t s, size_t deg, uint32_t ho, ring *r)
{
	const tdc_mesh_view *mesh = &v->mesh;
	uint32_t	h0 = atomic_load_explicit(&v->site_he[s], memory_order_relaxed),
				h,
				prev_t = TDC_NIL;

	r->n = 0;
	/* start right after the outer face, if any, so the chain is open there */
	h = ho == TDC_NIL ? h0 : mesh->he[ho].next;
	for (size_t i = 0; i < deg; i++)
	{
		uint32_t	t,
					g = TDC_NIL,
					hn = mesh->he[h].next;

		if (h == ho)
		{
			h = hn;
			continue;
		}
		/* the edge to the next vertex is dual to onext(h) */
		if (r->tagged)
			g = mesh->he[SYM(hn)].org;
		t = class_of(v, h);
		if (t != prev_t)
		{
			if (prev_t != TDC_NIL)
				note_pair(v, prev_t, t, h);
			ring_push(r, v->cc[2 * (size_t) t], v->cc[2 * (size_t) t + 1], g);
			prev_t = t;
		}
		else if (r->tagged)
			r->tag[r->n - 1] = g;	/* a zero-length edge collapsed */
		h = hn;
	}
	if (ho == TDC_NIL && prev_t != TDC_NIL)
	{
		uint32_t	first = class_of(v, h0);

		if (first != prev_t)
			note_pair(v, prev_t, first, h0);
	}
	if (ho != TDC_NIL)
	{
		/*
		 * The chain runs from the triangle after ho to the one before it.
		 * Out along hull edge ho = s -> u (outer face on its left), in along
		 * the hull edge after it, whose reverse w -> s has the outer face on
		 * its left.
		 */
		uint32_t	hin = mesh->he[ho].next;
		const double *first = vertex_of(v, hin),
				   *last = vertex_of(v, mesh->he[ho].prev);
		double		pout[2],
					pin[2];
		int			sout,
					sin;
		unsigned	owned = 15;

		/* the corners of B in the cell: nearer to s than to every neighbour */
		h = h0;
		do
		{
			uint32_t	g = mesh->he[SYM(h)].org;

			for (int k = 0; k < 4; k++)
				if ((owned & (1u << k)) && !corner_closer(v, k, s, g))
					owned &= ~(1u << k);
			h = mesh->he[h].next;
		} while (h != h0);
		hull_ray(v, last, s, mesh->he[SYM(ho)].org, pout, &sout);
		hull_ray(v, first, mesh->he[SYM(hin)].org, s, pin, &sin);
		ring_push(r, pout[0], pout[1], TDC_NIL);
		push_arc(r, v->box, sout, sin, owned);
		ring_push(r, pin[0], pin[1], mesh->he[SYM(hin)].org);
	}
	ring_close(r);
}

/*
 * The bisector of line[i] and line[i + 1], cut to B: lo then hi, with
 * line[i] on the left of lo -> hi.
 */
static void
line_bisector(const tdc_voronoi *v, size_t i, double lo[2], int *slo,
			  double hi[2], int *shi)
{
	const double *a = site_pt(v, v->line[i]),
			   *b = site_pt(v, v->line[i + 1]);
	double		m[2] = {a[0] * 0.5 + b[0] * 0.5, a[1] * 0.5 + b[1] * 0.5};
	double		dx = -(b[1] - a[1]),
				dy = b[0] - a[0];

	box_exit(v->box, m, -dx, -dy, lo, slo);
	box_exit(v->box, m, dx, dy, hi, shi);
}

/* Cell of site s of collinear input (a slab), uncut, into r (cell ∩ B). */
static bool
cell_of_line(const tdc_voronoi *v, uint32_t s, ring *r)
{
	size_t		i = v->line_pos[s];
	double		a0[2],
				a1[2],
				b0[2],
				b1[2];
	int			sa0,
				sa1,
				sb0,
				sb1;

	unsigned	owned = 15;

	r->n = 0;
	if (!ring_reserve(r, 16))
		return false;
	for (int k = 0; k < 4; k++)
		if ((i > 0 && !corner_closer(v, k, s, v->line[i - 1])) ||
			(i + 1 < v->nline && !corner_closer(v, k, s, v->line[i + 1])))
			owned &= ~(1u << k);
	if (i + 1 < v->nline && i > 0)
	{
		line_bisector(v, i, a0, &sa0, a1, &sa1);
		line_bisector(v, i - 1, b1, &sb1, b0, &sb0);
		/* right bisector a0 -> a1, arc, left bisector reversed b0 -> b1, arc */
		ring_push(r, a0[0], a0[1], v->line[i + 1]);
		ring_push(r, a1[0], a1[1], TDC_NIL);
		push_arc(r, v->box, sa1, sb0, owned);
		ring_push(r, b0[0], b0[1], v->line[i - 1]);
		ring_push(r, b1[0], b1[1], TDC_NIL);
		push_arc(r, v->box, sb1, sa0, owned);
	}
	else
	{
		if (i + 1 < v->nline)
			line_bisector(v, i, a0, &sa0, a1, &sa1);
		else
			line_bisector(v, i - 1, a1, &sa1, a0, &sa0);
		ring_push(r, a0[0], a0[1], v->line[i + 1 < v->nline ? i + 1 : i - 1]);
		ring_push(r, a1[0], a1[1], TDC_NIL);
		push_arc(r, v->box, sa1, sa0, owned);
	}
	ring_close(r);
	return true;
}

/* Build the cells of the sites [r * SITES_PER_TASK, ...) into one buffer. */
void
tdc_vor_cell_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		lo = rg * SITES_PER_TASK,
				hi = lo + SITES_PER_TASK < v->nsites ? lo + SITES_PER_TASK : v->nsites;
	ring		a = {.tagged = true},
				b = {.tagged = true},
				out = {0};
	size_t	   *off = NULL;

	if (vor_cancelled(v))
		return;
	off = malloc((hi - lo) * sizeof(size_t));
	/* about 6 vertices per cell: growing from there rarely copies */
	if (off == NULL || !ring_reserve(&out, 7 * (hi - lo)))
		goto oom;
	for (size_t s = lo; s < hi; s++)
	{
		bool		ok;

		off[s - lo] = out.n;
		v->cell_n[s] = 0;
		if (mesh->site_of[s] != s)
			continue;
		if (v->nline > 1)
			ok = cell_of_line(v, (uint32_t) s, &a);
		else
		{
			ok = ring_reserve(&a, 4);
			if (ok)
			{
				a.n = 0;
				ring_push(&a, v->env[0], v->env[1], TDC_NIL);
				ring_push(&a, v->env[2], v->env[1], TDC_NIL);
				ring_push(&a, v->env[2], v->env[3], TDC_NIL);
				ring_push(&a, v->env[0], v->env[3], TDC_NIL);
				ring_close(&a);
			}
		}
		if (!ok || !tdc_vor_clip_to_env(v, (uint32_t) s, &a, &b) || !ring_reserve(&out, a.n))
			goto oom;
		memcpy(out.p + 2 * out.n, a.p, a.n * 2 * sizeof(double));
		out.n += a.n;
		v->cell_n[s] = (uint32_t) a.n;
	}
	for (size_t s = lo; s < hi; s++)
		v->cell_xy[s] = v->cell_n[s] ? out.p + 2 * off[s - lo] : NULL;
	v->range_buf[rg] = out.p;
	out.p = NULL;
	goto done;

oom:
	vor_fail(v, TDC_ENOMEM, "out of memory building the Voronoi cells");
done:
	free(a.p);
	free(a.tag);
	free(b.p);
	free(b.tag);
	free(out.p);
	free(off);
}

/*
 * Room for extra more vertices in a range's untagged buffer, which comes
 * from tdc_big_alloc (mapped, or kept from an earlier run: a million
 * points' cells are some 100 MB written once, and a 4 kB page fault costs
 * microseconds on a virtual machine).  Grows by half, copying;
 * the first size is meant to make that rare.
 */
static bool
out_reserve(ring *r, size_t extra)
{
	if (r->n + extra > r->cap)
	{
		size_t		cap = (r->n + extra) + (r->n + extra) / 2 + 16;
		double	   *p = tdc_big_alloc(r->cache, cap * 2 * sizeof(double));

		if (p == NULL)
			return false;
		if (r->n > 0)
			memcpy(p, r->p, r->n * 2 * sizeof(double));
		tdc_big_free(r->cache, r->p);
		r->p = p;
		r->cap = cap;
	}
	return true;
}

/*
 * Build the cells of the sites whose smallest half-edge lies in half-edge
 * range rg into one buffer.  The half-edges are in the triangulation's
 * spatial order, so taking the sites in that order, rather than in input
 * order (random for unsorted input), keeps the mesh walks, the triangle
 * numbers and the circumcenters in cache.  An inner site's cell is built
 * untagged straight into the buffer and kept there when it lies inside E,
 * as almost every inner cell does; hull cells, and cells crossing E, go
 * through the tagged scratch ring and are clipped.
 */
void
tdc_vor_mesh_cell_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		lo = rg * v->cell_range,
				hi = lo + v->cell_range < v->nhe ? lo + v->cell_range : v->nhe;
	ring		a = {.tagged = true},
				b = {.tagged = true},
				out = {.cache = v->cache};
	uint32_t   *sites = NULL;
	size_t		nsites = 0;

	if (vor_cancelled(v))
		return;

	/*
	 * At most one site per two half-edges.  A cell has as many vertices as
	 * its site has edges, 6 on average, give or take a few for clipping:
	 * about one per half-edge, and a quarter more is rarely outgrown.
	 */
	sites = malloc(((hi - lo) / 2 + 1) * sizeof(uint32_t));
	if (sites == NULL || !out_reserve(&out, (hi - lo) + (hi - lo) / 4 + 64))
		goto oom;
	for (size_t h = lo; h < hi; h++)
	{
		uint32_t	s = mesh->he[h].org,
					ho;
		size_t		deg,
					start = out.n;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			goto done;
		if (s == TDC_NIL ||
			atomic_load_explicit(&v->site_he[s], memory_order_relaxed) != (uint32_t) h)
			continue;
		deg = tdc_vor_site_degree(v, s, &ho);
		if (!out_reserve(&out, deg + 8))
			goto oom;
		if (ho == TDC_NIL)
		{
			ring		w = {.p = out.p + 2 * start, .cap = out.cap - start};
			bool		inside = true;

			tdc_vor_cell_of_mesh(v, s, deg, ho, &w);
			for (size_t i = 0; i < w.n && inside; i++)
				inside = w.p[2 * i] >= v->env[0] && w.p[2 * i] <= v->env[2] &&
					w.p[2 * i + 1] >= v->env[1] && w.p[2 * i + 1] <= v->env[3];
			if (inside)
			{
				out.n += w.n;
				v->cell_n[s] = (uint32_t) w.n;
				sites[nsites++] = s;
				continue;
			}
		}
		if (!ring_reserve(&a, deg + 8))
			goto oom;
		tdc_vor_cell_of_mesh(v, s, deg, ho, &a);
		if (!tdc_vor_clip_to_env(v, s, &a, &b) || !out_reserve(&out, a.n))
			goto oom;
		memcpy(out.p + 2 * out.n, a.p, a.n * 2 * sizeof(double));
		out.n += a.n;
		v->cell_n[s] = (uint32_t) a.n;
		sites[nsites++] = s;
	}
	{
		size_t		off = 0;

		for (size_t i = 0; i < nsites; i++)
		{
			v->cell_xy[sites[i]] = out.p + 2 * off;
			off += v->cell_n[sites[i]];
		}
	}
	v->range_buf[rg] = out.p;
	out.p = NULL;
	goto done;

oom:
	vor_fail(v, TDC_ENOMEM, "out of memory building the Voronoi cells");
done:
	free(a.p);
	free(a.tag);
	free(b.p);
	free(b.tag);
	tdc_big_free(out.cache, out.p);
	free(sites);
}

