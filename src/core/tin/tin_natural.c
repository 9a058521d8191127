/*
 * tin_natural.c
 *		Sibson's natural neighbour interpolation on a Delaunay TIN.
 *
 * Sibson (1981): insert the query point q into the Voronoi diagram of the
 * sites; its new cell V(q) takes a piece from the cell of each of its
 * natural neighbours, and the weight of neighbour v is the area of the
 * piece taken from v's cell over the area of V(q).  The value is the
 * weighted mean of the neighbours' heights.  It reproduces planes, equals
 * the sample at a sample, and is continuous, with no facets.
 *
 * The construction (Watson, "Contouring", 1992; Sukumar's notes on natural
 * neighbour Galerkin methods describe the same): the triangles whose open
 * circumdisk contains q are those that inserting q would destroy (the
 * Bowyer-Watson cavity).  They form a region star-shaped from q whose
 * boundary vertices v_0 .. v_{k-1} (counter-clockwise) are the natural
 * neighbours, and every site of a cavity triangle is on the boundary.  With
 * g_i the circumcenter of (v_i, v_i+1, q), V(q) is the polygon g_0 .. g_k-1,
 * and the piece taken from v_i is the convex polygon
 *
 *		g_i-1, g_i, c(t_1), .., c(t_m)
 *
 * counter-clockwise, where t_1 .. t_m are the cavity triangles around v_i
 * from its boundary edge v_i -> v_i+1 counter-clockwise to v_i -> v_i-1, and
 * c(t) their circumcenters (the Voronoi vertices that q destroys): V(q)'s
 * edge g_i-1 g_i lies on the bisector of q and v_i, and the rest of the
 * piece's boundary is v_i's old cell boundary inside V(q), which passes its
 * Voronoi vertices in the counter-clockwise order of the triangles around
 * v_i.
 *
 * Exactness.  Which triangles are in the cavity is decided by the exact
 * in-circle test (q strictly inside: a triangle whose circle passes through
 * q contributes a piece of zero area either way, and leaving it out keeps
 * the cavity's boundary simple).  So the cavity as a region, and the
 * natural neighbours, do not depend on how the triangulation split
 * cocircular sites: every triangle of a cocircular polygon has the same
 * circle, so all of them are in the cavity or none is, and their common
 * circumcenter appears once per triangle, which adds zero-length edges to a
 * piece, not area.  The areas are computed in double-double from q's exact
 * offsets to the sites (Two-Diff), the circumcenters relative to q divided
 * once in double-double, the shoelace sums accumulated in double-double:
 * near the hull V(q) grows long and thin (a point at distance d from a hull
 * edge of length L has a cell of diameter about L^2 / d), and the
 * cancellation in its area costs about log2(L / d) bits, which double-double
 * has to spare.  The weights are the areas rounded to double and the value
 * the mean of the heights in double, summed in the order of the boundary
 * from its first vertex in (x, y) order, and each circumcenter is computed
 * from its triangle's first corner in (x, y) order: so the value depends on
 * the cavity's triangles as geometry only, the same whatever triangle the
 * walk located q in and however the mesh numbers its half-edges (a bounded
 * run's tile computes it on its own triangulation, terrain/raster_natural.c,
 * to the same bits), and a cocircular tie-break changes it by no more than
 * rounding (tested on lattices against their mirror images).
 *
 * A point on an edge of the hull (exactly) has an unbounded cell; the
 * interpolation is then linear along the edge, its limit from inside
 * (tin_interp.c).  Outside the hull there is no natural neighbour value.
 */
#include <stdio.h>
#include <string.h>

#include "tin_int.h"

/* ----------------------------------------------------------------
 *		scratch: the cavity's triangles, a set of them, its boundary
 * ----------------------------------------------------------------
 */
void
tin_scratch_free(tin_scratch *sc)
{
	free(sc->tri);
	free(sc->cc);
	free(sc->hash);
	free(sc->bnd);
	free(sc->w);
	free(sc->g);
	free(sc->px);
	free(sc->py);
	memset(sc, 0, sizeof(*sc));
}

bool
tin_scratch_charge(tdc_tin *tin, tin_scratch *sc)
{
	if (sc->bytes <= sc->charged)
		return true;
	if (!tin_charge(tin, sc->bytes - sc->charged, "a natural neighbour cavity"))
		return false;
	sc->charged = sc->bytes;
	return true;
}

void
tin_scratch_release(tdc_tin *tin, tin_scratch *sc)
{
	tin_uncharge(tin, sc->charged);
	tin_scratch_free(sc);
}

/* What the arrays hold now. */
static void
scratch_count(tin_scratch *sc)
{
	sc->bytes = sc->cap * sizeof(uint32_t) + sc->cccap * 2 * sizeof(dd) +
		sc->hcap * sizeof(uint32_t) + sc->bcap * 2 * sizeof(uint32_t) +
		sc->wcap * (sizeof(double) + 2 * sizeof(dd)) + sc->pcap * 2 * sizeof(dd);
}

static inline size_t
hash_slot(uint32_t h, size_t cap)
{
	return (size_t) ((h * 2654435761u) >> 7) & (cap - 1);
}

/* The index of triangle k in the cavity, or TDC_NIL. */
static uint32_t
hash_find(const tin_scratch *sc, uint32_t k)
{
	for (size_t i = hash_slot(k, sc->hcap);; i = (i + 1) & (sc->hcap - 1))
	{
		uint32_t	e = sc->hash[i];

		if (e == 0)
			return TDC_NIL;
		if (sc->tri[e - 1] == k)
			return e - 1;
	}
}

static void
hash_put(tin_scratch *sc, uint32_t idx)
{
	size_t		i = hash_slot(sc->tri[idx], sc->hcap);

	while (sc->hash[i] != 0)
		i = (i + 1) & (sc->hcap - 1);
	sc->hash[i] = idx + 1;
}

/* Room for one more cavity triangle (and a set at most half full). */
static bool
scratch_grow(tin_scratch *sc)
{
	if (sc->ntri + 1 > sc->cap)
	{
		size_t		cap = sc->cap ? 2 * sc->cap : 32;
		uint32_t   *t = realloc(sc->tri, cap * sizeof(uint32_t));

		if (t == NULL)
			return false;
		sc->tri = t;
		sc->cap = cap;
	}
	if (2 * (sc->ntri + 1) > sc->hcap)
	{
		size_t		hcap = sc->hcap ? 2 * sc->hcap : 128;
		uint32_t   *nh = calloc(hcap, sizeof(uint32_t));

		if (nh == NULL)
			return false;
		free(sc->hash);
		sc->hash = nh;
		sc->hcap = hcap;
		for (size_t i = 0; i < sc->ntri; i++)
			hash_put(sc, (uint32_t) i);
	}
	scratch_count(sc);
	return true;
}

/* Room for nb boundary edges (and their order), areas and V(q)'s vertices. */
static bool
scratch_boundary(tin_scratch *sc, size_t nb)
{
	if (nb > sc->bcap)
	{
		uint32_t   *b = realloc(sc->bnd, nb * 2 * sizeof(uint32_t));

		if (b == NULL)
			return false;
		sc->bnd = b;
		sc->bcap = nb;
	}
	if (nb > sc->wcap)
	{
		double	   *w = realloc(sc->w, nb * sizeof(double));
		dd		   *g;

		if (w == NULL)
			return false;
		sc->w = w;
		g = realloc(sc->g, nb * 2 * sizeof(dd));
		if (g == NULL)
			return false;
		sc->g = g;
		sc->wcap = nb;
	}
	if (sc->ntri > sc->cccap)
	{
		dd		   *c = realloc(sc->cc, sc->cap * 2 * sizeof(dd));

		if (c == NULL)
			return false;
		sc->cc = c;
		sc->cccap = sc->cap;
	}
	scratch_count(sc);
	return true;
}

/* Room for a piece of n vertices. */
static bool
scratch_piece(tin_scratch *sc, size_t n)
{
	if (n > sc->pcap)
	{
		size_t		cap = n < 32 ? 32 : 2 * n;
		dd		   *x = realloc(sc->px, cap * sizeof(dd)),
				   *y;

		if (x == NULL)
			return false;
		sc->px = x;
		y = realloc(sc->py, cap * sizeof(dd));
		if (y == NULL)
			return false;
		sc->py = y;
		sc->pcap = cap;
		scratch_count(sc);
	}
	return true;
}

/* The smallest half-edge of the triangle left of h: the triangle's name. */
static inline uint32_t
tri_key(const tdc_tin *tin, uint32_t h)
{
	return tin->tri_he[tin->he_tri[h]];
}

static bool
cavity_add(const tdc_tin *tin, tin_scratch *sc, uint32_t h)
{
	if (!scratch_grow(sc))
		return false;
	sc->tri[sc->ntri] = tri_key(tin, h);
	hash_put(sc, (uint32_t) sc->ntri);
	sc->ntri++;
	return true;
}

static inline bool
in_cavity(const tdc_tin *tin, const tin_scratch *sc, uint32_t h)
{
	return !tin_outer(tin, h) && hash_find(sc, tri_key(tin, h)) != TDC_NIL;
}

/* ----------------------------------------------------------------
 *		double-double geometry relative to q
 * ----------------------------------------------------------------
 */

/* p - q exactly, as two double-doubles. */
static inline void
offset(const double *p, const double *q, dd *x, dd *y)
{
	two_diff(p[0], q[0], &x->hi, &x->lo);
	two_diff(p[1], q[1], &y->hi, &y->lo);
}

static inline dd
dd_sub(dd a, dd b)
{
	return dd_add(a, dd_neg(b));
}

/*
 * Circumcenter of the triangle (a, b, c), given by their offsets from q,
 * relative to q: a + (|u|^2 v - |v|^2 u)^perp / (2 u x v) with u = b - a,
 * v = c - a.  Returns false for a flat triangle (it has no center).
 */
static bool
circumcenter_dd(dd ax, dd ay, dd bx, dd by, dd cx, dd cy, dd *ox, dd *oy)
{
	dd			ux = dd_sub(bx, ax),
				uy = dd_sub(by, ay),
				vx = dd_sub(cx, ax),
				vy = dd_sub(cy, ay);
	dd			uu = dd_add(dd_mul(ux, ux), dd_mul(uy, uy)),
				vv = dd_add(dd_mul(vx, vx), dd_mul(vy, vy)),
				d = dd_sub(dd_mul(ux, vy), dd_mul(uy, vx));

	if (d.hi == 0)
		return false;
	d = dd_add(d, d);
	*ox = dd_add(ax, dd_div(dd_sub(dd_mul(vy, uu), dd_mul(uy, vv)), d));
	*oy = dd_add(ay, dd_div(dd_sub(dd_mul(ux, vv), dd_mul(vx, uu)), d));
	return true;
}

/* Twice the signed area of the polygon x[0..n), y[0..n), in double-double. */
static dd
area2(const dd *x, const dd *y, size_t n)
{
	dd			s = {0, 0};

	for (size_t i = 0; i < n; i++)
	{
		size_t		j = i + 1 == n ? 0 : i + 1;

		s = dd_add(s, dd_sub(dd_mul(x[i], y[j]), dd_mul(x[j], y[i])));
	}
	return s;
}

/* ----------------------------------------------------------------
 *		the value
 * ----------------------------------------------------------------
 */

/* The boundary edge leaving site v (the boundary is short: a scan). */
static uint32_t
bnd_from(const tdc_tin *tin, const tin_scratch *sc, uint32_t v)
{
	for (size_t i = 0; i < sc->nbnd; i++)
		if (tin_org(tin, sc->bnd[i]) == v)
			return (uint32_t) i;
	return TDC_NIL;
}

static int
cmp_bnd(const void *x, const void *y, void *arg)
{
	const tdc_tin *tin = arg;
	uint32_t	a = tin_org(tin, *(const uint32_t *) x),
				b = tin_org(tin, *(const uint32_t *) y);

	return a < b ? -1 : a > b;
}

/* The boundary edge leaving v in a long boundary (sorted by origin). */
static uint32_t
bnd_from_sorted(const tdc_tin *tin, const tin_scratch *sc, uint32_t v)
{
	size_t		lo = 0,
				hi = sc->nbnd;

	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo) / 2;

		if (tin_org(tin, sc->bnd[mid]) < v)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < sc->nbnd && tin_org(tin, sc->bnd[lo]) == v ? (uint32_t) lo : TDC_NIL;
}

/*
 * The natural neighbour value at q (strictly inside the hull, not at a
 * site), located in loc; TDC_OK, TDC_ENOMEM, or TDC_EINVAL where the
 * cavity is not what the theory says it is (a bug: the caller reports it).
 */
int
tin_natural(const tdc_tin *tin, tin_scratch *sc, const double *q,
			const tin_loc *loc, double *z)
{
	size_t		nb,
				first = 0;
	uint32_t   *order;
	double		num = 0,
				den = 0;
	dd			zero = {0, 0};

	/* the cavity: from q's triangle(s), across edges while q is in the circle */
	sc->ntri = 0;
	sc->nbnd = 0;
	if (sc->hash)
		memset(sc->hash, 0, sc->hcap * sizeof(uint32_t));
	if (!cavity_add(tin, sc, loc->h))
		return TDC_ENOMEM;
	if (loc->kind == LOC_EDGE && !in_cavity(tin, sc, loc->h ^ 1u) &&
		!tin_outer(tin, loc->h ^ 1u) && !cavity_add(tin, sc, loc->h ^ 1u))
		return TDC_ENOMEM;
	for (size_t i = 0; i < sc->ntri; i++)
	{
		uint32_t	h = sc->tri[i];

		for (int k = 0; k < 3; k++, h = tin_lnext(tin, h))
		{
			uint32_t	s = h ^ 1u,
						c;

			if (tin_outer(tin, s) || in_cavity(tin, sc, s))
				continue;
			/* s = b -> a: its triangle is (b, a, c) counter-clockwise */
			c = tin_dest(tin, tin_lnext(tin, s));
			if (tdc_incircle(tin_pt(tin, tin_org(tin, s)), tin_pt(tin, tin_dest(tin, s)),
							 tin_pt(tin, c), q) > 0 && !cavity_add(tin, sc, s))
				return TDC_ENOMEM;
		}
	}

	/* the boundary: cavity edges whose other side is not in the cavity */
	nb = sc->ntri + 2;
	if (!scratch_boundary(sc, nb))
		return TDC_ENOMEM;
	for (size_t i = 0; i < sc->ntri; i++)
	{
		uint32_t	h = sc->tri[i];

		for (int k = 0; k < 3; k++, h = tin_lnext(tin, h))
			if (!in_cavity(tin, sc, h ^ 1u))
			{
				if (sc->nbnd == nb)
					return TDC_EINVAL;	/* not a disk: cannot happen */
				sc->bnd[sc->nbnd++] = h;
			}
	}
	if (sc->nbnd != nb)
		return TDC_EINVAL;

	/*
	 * circumcenters of the cavity triangles, relative to q, each from its
	 * first corner in (x, y) order: the rounding then depends on the
	 * triangle, not on how its half-edges are numbered
	 */
	for (size_t i = 0; i < sc->ntri; i++)
	{
		uint32_t	h = sc->tri[i],
					h1,
					g = h;
		dd			ax,
					ay,
					bx,
					by,
					cx,
					cy;

		for (int k = 0; k < 2; k++)
		{
			g = tin_lnext(tin, g);
			if (tdc_lex_less(tin_pt(tin, tin_org(tin, g)), tin_pt(tin, tin_org(tin, h))))
				h = g;
		}
		h1 = tin_lnext(tin, h);
		offset(tin_pt(tin, tin_org(tin, h)), q, &ax, &ay);
		offset(tin_pt(tin, tin_org(tin, h1)), q, &bx, &by);
		offset(tin_pt(tin, tin_dest(tin, h1)), q, &cx, &cy);
		if (!circumcenter_dd(ax, ay, bx, by, cx, cy, &sc->cc[2 * i], &sc->cc[2 * i + 1]))
			return TDC_EINVAL;
	}

	/*
	 * The boundary in order around q, from its first vertex in (x, y)
	 * order: order[j] is the j-th boundary edge, v_j -> v_j+1.
	 */
	if (nb > 16)
		qsort_r(sc->bnd, nb, sizeof(uint32_t), cmp_bnd, (void *) tin);
	order = sc->bnd + nb;
	for (size_t i = 1; i < nb; i++)
		if (tdc_lex_less(tin_pt(tin, tin_org(tin, sc->bnd[i])),
						 tin_pt(tin, tin_org(tin, sc->bnd[first]))))
			first = i;
	order[0] = sc->bnd[first];
	for (size_t j = 1; j < nb; j++)
	{
		uint32_t	v = tin_dest(tin, order[j - 1]),
					i = nb > 16 ? bnd_from_sorted(tin, sc, v) : bnd_from(tin, sc, v);

		if (i == TDC_NIL)
			return TDC_EINVAL;
		order[j] = sc->bnd[i];
	}
	if (tin_dest(tin, order[nb - 1]) != tin_org(tin, order[0]))
		return TDC_EINVAL;

	/* g_j: circumcenter of (v_j, v_j+1, q), relative to q (the origin) */
	for (size_t j = 0; j < nb; j++)
	{
		dd			ax,
					ay,
					bx,
					by;

		offset(tin_pt(tin, tin_org(tin, order[j])), q, &ax, &ay);
		offset(tin_pt(tin, tin_dest(tin, order[j])), q, &bx, &by);
		if (!circumcenter_dd(ax, ay, bx, by, zero, zero, &sc->g[2 * j], &sc->g[2 * j + 1]))
			return TDC_EINVAL;
	}

	/* the piece of each v_j: g_j-1, g_j, then the cavity triangles around v_j */
	for (size_t j = 0; j < nb; j++)
	{
		size_t		jp = j == 0 ? nb - 1 : j - 1,
					n = 2;
		uint32_t	h = order[j],
					stop = order[jp] ^ 1u;
		dd			a;

		if (!scratch_piece(sc, 2))
			return TDC_ENOMEM;
		sc->px[0] = sc->g[2 * jp];
		sc->py[0] = sc->g[2 * jp + 1];
		sc->px[1] = sc->g[2 * j];
		sc->py[1] = sc->g[2 * j + 1];
		while (h != stop)
		{
			uint32_t	i = hash_find(sc, tri_key(tin, h));

			if (i == TDC_NIL || n > sc->ntri + 2)
				return TDC_EINVAL;
			if (!scratch_piece(sc, n + 1))
				return TDC_ENOMEM;
			sc->px[n] = sc->cc[2 * i];
			sc->py[n] = sc->cc[2 * i + 1];
			n++;
			h = tin_onext(tin, h);
		}
		a = area2(sc->px, sc->py, n);
		sc->w[j] = a.hi + a.lo;
	}
	for (size_t j = 0; j < nb; j++)
	{
		num += sc->w[j] * tin->sz[tin_org(tin, order[j])];
		den += sc->w[j];
	}
	*z = num / den;
	return TDC_OK;
}
