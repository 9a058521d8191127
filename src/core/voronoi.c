/*
 * voronoi.c
 *		The Voronoi diagram of a finished triangulation, clipped to a
 *		rectangle: one convex cell per site.
 *
 * Duality.  The Voronoi diagram of a point set is the planar dual of its
 * Delaunay triangulation (Delaunay 1934; see de Berg, Cheong, van Kreveld and
 * Overmars, "Computational Geometry", 3rd ed., section 9.2, theorem 9.6, or
 * Okabe, Boots, Sugihara and Chiu, "Spatial Tessellations", 2nd ed.,
 * section 2.4): every Delaunay triangle is a Voronoi vertex, its
 * circumcenter; every Delaunay edge st is the Voronoi edge between the cells
 * of s and t, joining the circumcenters of the two triangles beside it, or a
 * ray perpendicular to st when st is on the convex hull; every site is a
 * cell, whose vertices are the circumcenters of the triangles around the
 * site, in the same counter-clockwise order.  So the cells are read off the
 * mesh by walking the ring of half-edges around each site, and their
 * adjacency is exactly the Delaunay adjacency that the exact predicates
 * decided: only the vertex coordinates are rounded.
 *
 * Cocircular sites.  When four or more sites lie on one empty circle the
 * triangulation splits that circle's polygon into triangles whose
 * circumcenters are the same point: the Voronoi edges dual to the inner
 * diagonals have length zero.  Such an edge is recognised exactly (the
 * incircle determinant of its two triangles is exactly zero), and the
 * triangles are merged into one class by a lock-free union-find whose root
 * is the smallest triangle number, so the class has one vertex, computed
 * once, and a cell never repeats it.  Testing every edge costs a tenth of
 * the diagram, and on data in general position finds nothing; so the edges
 * are tested where it is cheap and can matter: the walks that build the
 * cells compare the vertices of consecutive triangles around each site,
 * and only when the two are within rounding of each other (2^-48 of the
 * coordinate, far above the bound below) is the edge between them tested.
 * Every inner edge is between consecutive triangles around its end points,
 * so none is missed.  If one is cocircular, the classes are joined (every
 * edge tested, as above) and the cells are built again.
 *
 * One vertex, one value.  A Voronoi vertex is computed once per triangle,
 * with the vertices rotated to start at the lexicographically smallest, and
 * a class reads its root's: every cell that uses it reads the same double
 * pair, so neighbouring cells share their vertices bit for bit and the cells
 * form a coverage with no gap and no overlap beyond that rounding.  Points
 * made by clipping are computed from the segment's end points taken in
 * lexicographic order, so both cells of a clipped edge get the same point
 * too.
 *
 * Error bound.  The circumcenter is first computed in plain double
 * arithmetic with a forward error bound (circumcenter_fast); when that
 * bound proves the exact coordinate rounds to the computed one, as it does
 * for some 95 percent of the triangles of uniform input, that correctly
 * rounded value is the vertex: within 1/2 ulp.  Otherwise it is computed
 * in double-double arithmetic
 * (Dekker's error-free product and Knuth's two-sum, no FMA needed) relative
 * to the triangle's first vertex a, with b - a and c - a exact, and rounded
 * once at the end.  With L the longest of |b - a| and |c - a|,
 * D = (b - a) x (c - a), K = (|bx cy| + |by cx|) / |D| (the condition of
 * the orientation; 1 for a right angle at a, large for a flat triangle) and
 * u the exact offset of the circumcenter from a, each coordinate of the
 * double-double result is within
 *
 *		1/2 ulp(result) + 2^-98 * (L^3 / |D| + K * |u|)
 *
 * of the exact rational circumcenter.  Every double-double operation has a
 * relative error below 2^-104 * small constant; the only cancellations are
 * in D and in the two numerators, whose absolute errors are bounded by
 * 2^-103 times the sums of the magnitudes of their terms (at most L^3 / 2
 * and K |D|), which gives the second term.  That term is small against the
 * first for any triangle not within about 1e-14 radian of flat, but
 * not for the triangles that sites an ulp apart, or collinear up to ulps,
 * make: there it can exceed the result itself (D can even vanish, giving
 * NaN), and a coordinate near 0 is swamped by the size of u.  So the
 * function bounds its own error from the computed terms and, unless that
 * is below 2^-56 of each coordinate, recomputes exactly: D and the
 * numerators 2 a D + N as expansions (Shewchuk 1997; b - a and c - a are
 * exact double-doubles, so every product is a sum of exact two-products),
 * rounded to double-double only for the final division.  Either way each
 * coordinate is also within
 *
 *		1/2 ulp(result) + 2^-55 * |result|
 *
 * (under 5/8 ulp).  The first bound is the double-double path's; the exact
 * path replaces it only where it is looser than this one, except for the
 * exact path's final double-double division, good to 2^-100 of the
 * result.  test/test_voronoi.c checks both bounds against exact rational
 * arithmetic (GMP) on random, skinny, near-collinear and near-duplicate
 * triangles over the whole coordinate range.  Coordinates within [TDC_COORD_MIN, TDC_COORD_MAX] keep every
 * intermediate (cubes of coordinate differences and the exact path's
 * two-product tails) inside the normal double range, so the expansions are
 * exact.
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
 * Collinear sites.  With no triangle (every site on one line, or two sites),
 * the cells are slabs between the perpendicular bisectors of consecutive
 * sites, as GEOS (and so PostGIS) gives them; each bisector is cut to B the
 * same way and the slabs are closed along B's boundary, then clipped.  One
 * site: its cell is E.
 *
 * Parallelism and cancel.  Numbering the triangles (with their vertices, in
 * one walk over the half-edges), joining cocircular ones and building the
 * cells are parallel loops on a pool of the job's thread count, run by a
 * driver thread with all signals blocked, like a triangulation, so the
 * host's thread stays free to cancel.  Every loop polls the cancel flag at
 * least once per 4096 items, or, for the loops of a few loads an item (the
 * offsets' prefix sums), once per task of 65536.  The cells of a mesh are built by ranges of
 * half-edges, each site in the range of its smallest half-edge, so the walks
 * follow the mesh's memory order; each range writes its cells into one
 * buffer of its own (tdc_voronoi_cell reads them there).
 *
 * Writing straight into the host's value (tdc_voronoi_start_emit).  A host
 * that wants all cells as one value in input order would otherwise copy a
 * million cells, some 130 MB, on its own thread, from buffers the kernel
 * first had to clear.  Instead the first phase only sizes the cells: one
 * walk around each site (the rings of 16 sites walked a step at a time
 * together, so that their random loads overlap) records an inner cell that
 * lies inside E (almost all of them) as its classes, a few words, and any
 * other cell, built and clipped as a ring, as its coordinates.  The host
 * allocates the total; the second phase computes every cell's offset by a
 * parallel prefix sum over the input points (a cell sits at its site's
 * first input point; the offsets reuse the triangle numbers' pages, which
 * writing no longer needs), maps the value in block by block on the
 * workers, and writes the cells from the records by the host's writer, a
 * pure function that copies bytes.  The bytes do not depend on the thread
 * count: the cells and the offsets do not.
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "exact.h"
#include "job.h"

#define SITES_PER_TASK	4096	/* cells built per task, and per cancel poll */
#define ITEMS_PER_TASK	65536	/* half-edges or triangles per task */
#define CELL_RANGE_MIN	262144	/* half-edges per cell task, at least */
#define TRI_CHUNK		1024	/* triangle numbers claimed at a time */

struct tdc_voronoi
{
	const tdc_job *job;
	tdc_cache  *cache;			/* the job's, kept: the job may be freed first */
	double		env[4];			/* E: xmin, ymin, xmax, ymax */
	double		box[4];			/* B, strictly around E, sites and vertices */
	int			threads;

	/* triangle structure */
	size_t		nhe;
	size_t		ntri;
	uint32_t   *tri_id;			/* half-edge -> triangle left of it, or NIL */
	_Atomic(uint32_t) *parent;	/* union-find over triangles, root = class min;
								 * NULL when no two triangles are cocircular */
	atomic_int	need_join;		/* two cocircular triangles' vertices differ */
	double	   *cc;				/* circumcenter of each class root, 2 per tri */
	_Atomic(uint32_t) *site_he; /* site -> smallest outgoing half-edge */
	size_t	   *range_ntri;		/* half-edge range -> triangles numbered */
	size_t		nchunks;		/* triangle numbers come in chunks (number_task) */
	size_t		ntri_cap;		/* nchunks * TRI_CHUNK: triangle numbers below */
	uint32_t   *chunk_fill;		/* chunk -> numbers used */
	atomic_size_t chunks_claimed;
	uint32_t   *tri_he;			/* joining: triangle -> its smallest half-edge */
	double	   *range_box;		/* 4 per range: bounding box of its vertices */

	/* collinear input */
	uint32_t   *line;			/* the sites sorted by (x, y) */
	uint32_t   *line_pos;		/* site -> its place in line[] */
	size_t		nline;

	/* cells */
	size_t		nsites;			/* site id limit */
	double	  **cell_xy;		/* site -> its ring, or NULL */
	uint32_t   *cell_n;			/* site -> vertices in its ring */
	size_t		nranges;
	size_t		cell_range;		/* half-edges per cell range (mesh input) */
	bool		big_bufs;		/* range_buf from tdc_big_alloc, not malloc */
	double	  **range_buf;		/* ring storage of each site range */
	size_t		total_vertices;

	/* tdc_voronoi_start_emit: sizes, then the cells straight to the writer */
	bool		emit;
	bool		writing;		/* the second phase (tdc_voronoi_emit) */
	tdc_cell_writer writer;
	uint64_t	emit_bytes;
	size_t		emit_cells;
	uint64_t   *range_bytes;	/* per cell range: bytes of its cells */
	size_t	   *range_cells;
	char	   *dst;
	size_t		ninput;
	uint32_t   *first_in;		/* site -> first input (tolerance only) */
	uint64_t   *inpos;			/* input -> its cell's size, then offset */
	uint64_t   *site_off;		/* site -> its cell's offset */
	bool		offsets_in_tri_id;	/* inpos and site_off live in tri_id's pages */
	uint32_t  **range_rec;		/* cell range -> its record (mesh_size_task) */
	size_t	   *range_rec_len;
	uint64_t   *block_start;	/* input block -> offset of its first cell */

	tdc_pool   *pool;
	atomic_int	cancel;
	atomic_int	failed;
	char		task_err[256];

	tdc_runner	run;			/* the driver and its status (runner.c) */
	char		err[256];
};

/*
 * Circumcenter of the counter-clockwise, non-degenerate triangle a, b, c,
 * rounded once per coordinate (the bound is in the header comment).  The
 * result depends on the order of the arguments: callers pass a canonical
 * rotation.
 *
 * The double-double result is kept when its error bound is below 2^-56 of
 * each of its coordinates (about 1/16 ulp).  Otherwise D and the
 * numerators of the coordinates themselves, 2 a D + N, are computed exactly
 * as expansions (the differences b - a and c - a are exact double-doubles,
 * so every product is a sum of exact two-products: at most 16 parts for D,
 * TDC_EXP_PRODUCT_MAX for a numerator) and rounded to double-double only for the
 * division, so a coordinate near 0 keeps its own digits.  Without it, a
 * triangle 2^-250 thin (two sites 1e-37 apart under a third at 1e40:
 * fuzz/known/voronoi_box_exit_side) lost D entirely, divided by zero and
 * gave NaN, and the cells of its sites came out empty; and the y of a
 * circumcenter at x = -2.3e59 was 2e7 off instead of 0.054
 * (voronoi_thin_strips_far_vertex), which wound a thin cell backwards.
 */
/*
 * Half the gap from x (normal, |x| >= 2^-900) to its nearer neighbour: x's
 * exponent with the mantissa cleared is 2^e <= |x|; the gap above is 2^(e-52),
 * the one below the same unless |x| is a power of 2, then half of it.
 */
static void circumcenter_careful(const double *a, const double *b, const double *c,
								 double out[2]);

static inline double
half_gap(double x)
{
	uint64_t	bits,
				e;
	double		p;

	memcpy(&bits, &x, sizeof(bits));
	e = bits & 0x7ff0000000000000u;
	memcpy(&p, &e, sizeof(p));
	return (bits & 0x000fffffffffffffu) ? p * 0x1p-53 : p * 0x1p-54;
}

/*
 * The circumcenter in plain double arithmetic, when it can prove the
 * result correctly rounded.  Relative to a, with eps = 2^-53, gamma_k =
 * k eps / (1 - k eps) and every quantity the computed one (Higham,
 * "Accuracy and Stability of Numerical Algorithms", 2nd ed., chapter 3):
 * b - a and friends are within eps of themselves; |b - a|^2 within
 * gamma_4 (two for the squared difference, one product, one sum, all terms
 * positive); each of bx cy and by cx within gamma_3, so D within gamma_3
 * P + eps P <= 4.0001 eps P_D of the exact D, where P_D = |bx cy| + |by cx|
 * bounds both the exact terms (to gamma_4) and |D|; each term of a
 * numerator, cy |b - a|^2 and the like, within gamma_6, so the numerator
 * within 7.0001 eps of P_N, the sum of its terms' magnitudes.  The
 * constants used, 0x1.01p-51 = 4.03 eps and 0x1.c1p-51 = 7.016 eps, are
 * above these.  Then the offset ux = nx / 2D (2D exact, the quotient
 * within eps) is within
 *
 *		e_u = q + r (|ux| + q) + eps |ux|,   q = e_N / 2|D|,  r = e_D / |D|
 *
 * of the exact offset U, to first order in r, which must be below 2^-20;
 * the factor 1.01 covers the second order and the rounding of e_u itself.
 * The exact coordinate is a + U = s + t + (U - ux) with s + t = a + ux
 * exactly (two-sum); if |t| + e_u is below half the gap from s to its
 * nearer neighbour (a power of 2: rounding is monotonic, so a computed sum
 * below it proves the exact one is), the exact
 * coordinate rounds to s, which is returned: within 1/2 ulp, tighter than
 * the careful path.  The range guard keeps every product of up to three
 * differences within [2^-900, 2^750] or exactly 0, and their differences 0
 * or above 2^-952, so no step underflows and the relative bounds hold;
 * results below 2^-900 are left to the careful path.  Fails for a triangle
 * within about 2^-20 of flat, for a coordinate near 0 against the
 * triangle's size, and otherwise with probability about 2 e_u / ulp (a
 * coordinate within e_u of a rounding boundary): 5 to 10 percent of the
 * triangles of a million uniform points.
 */
/* 0, or a magnitude in [2^-300, 2^250]: see circumcenter_fast */
static inline bool
in_fast_range(double x)
{
	double		m = fabs(x);

	return x == 0 || (m >= 0x1p-300 && m <= 0x1p250);
}

static inline bool
circumcenter_fast(const double *a, const double *b, const double *c,
				  double out[2])
{
	double		bx = b[0] - a[0],
				by = b[1] - a[1],
				cx = c[0] - a[0],
				cy = c[1] - a[1];
	double		bb,
				cc,
				t1,
				t2,
				d,
				pd,
				ed,
				n[2],
				pn[2];

	if (!(in_fast_range(bx) && in_fast_range(by) && in_fast_range(cx) && in_fast_range(cy)))
		return false;
	bb = bx * bx + by * by;
	cc = cx * cx + cy * cy;
	t1 = bx * cy;
	t2 = by * cx;
	d = t1 - t2;
	pd = fabs(t1) + fabs(t2);
	ed = 0x1.01p-51 * pd;
	if (!(ed < 0x1p-20 * fabs(d)))
		return false;
	t1 = cy * bb;
	t2 = by * cc;
	n[0] = t1 - t2;
	pn[0] = fabs(t1) + fabs(t2);
	t1 = bx * cc;
	t2 = cx * bb;
	n[1] = t1 - t2;
	pn[1] = fabs(t1) + fabs(t2);
	for (int k = 0; k < 2; k++)
	{
		double		u = n[k] / (2 * d),
					q = 0x1.c1p-51 * pn[k] / (2 * fabs(d)),
					eu = 1.01 * (q + (ed / fabs(d)) * (fabs(u) + q) + 0x1.01p-53 * fabs(u)) + 0x1p-1000;
		dd			s = dd_two_sum(a[k], u);

		/* NaN fails every comparison */
		if (!(fabs(s.hi) >= 0x1p-900 && fabs(s.hi) < INFINITY &&
			  fabs(s.lo) + eu < half_gap(s.hi)))
			return false;
		out[k] = s.hi;
	}
	return true;
}

void
tdc_circumcenter(const double *a, const double *b, const double *c,
				 double out[2])
{
	if (circumcenter_fast(a, b, c, out))
		return;
	circumcenter_careful(a, b, c, out);
}

/*
 * The double-double path, with its exact fallback: the bounds of the
 * header comment.
 */
static void
circumcenter_careful(const double *a, const double *b, const double *c,
						 double out[2])
{
	dd			bx = dd_two_sum(b[0], -a[0]),
				by = dd_two_sum(b[1], -a[1]),
				cx = dd_two_sum(c[0], -a[0]),
				cy = dd_two_sum(c[1], -a[1]);
	dd			bb = dd_add(dd_mul(bx, bx), dd_mul(by, by));
	dd			cc = dd_add(dd_mul(cx, cx), dd_mul(cy, cy));
	dd			d = dd_add(dd_mul(bx, cy), dd_neg(dd_mul(by, cx)));
	dd			d2,
				nx = dd_add(dd_mul(cy, bb), dd_neg(dd_mul(by, cc))),
				ny = dd_add(dd_mul(bx, cc), dd_neg(dd_mul(cx, bb))),
				ux,
				uy;
	/*
	 * Absolute error bounds of D and the numerators (2^-100 covers the
	 * few double-double roundings of 2^-104 relative each, with slack)
	 */
	double		err_d = 0x1p-100 * (fabs(bx.hi * cy.hi) + fabs(by.hi * cx.hi)),
				err_n = 0x1p-100 * fmax(fabs(cy.hi) * bb.hi + fabs(by.hi) * cc.hi,
										fabs(bx.hi) * cc.hi + fabs(cx.hi) * bb.hi);
	double		err_u;

	d2 = (dd) {2 * d.hi, 2 * d.lo};
	ux = dd_div(nx, d2);
	uy = dd_div(ny, d2);
	out[0] = dd_add((dd) {a[0], 0}, ux).hi;
	out[1] = dd_add((dd) {a[1], 0}, uy).hi;
	/* first order, valid while D is known to 2^-20 of itself */
	err_u = (err_n + fmax(fabs(ux.hi), fabs(uy.hi)) * 2 * err_d) / fabs(d2.hi);
	if (err_d <= 0x1p-20 * fabs(d.hi) &&
		err_u <= 0x1p-56 * fabs(out[0]) && err_u <= 0x1p-56 * fabs(out[1]))
		return;

	{
		double		ex[2],
					ey[2],
					fx[2],
					fy[2],
					two_a[2] = {2 * a[0], 2 * a[1]},
					eb[16],
					ec[16],
					ed[16],
					en[TDC_EXP_PRODUCT_MAX];
		int			nex = dd_exp(bx, ex),
					ney = dd_exp(by, ey),
					nfx = dd_exp(cx, fx),
					nfy = dd_exp(cy, fy),
					nb,
					nc,
					nd,
					nn;

		nb = expansion_add_product(0, eb, nex, ex, nex, ex, 1);
		nb = expansion_add_product(nb, eb, ney, ey, ney, ey, 1);
		nc = expansion_add_product(0, ec, nfx, fx, nfx, fx, 1);
		nc = expansion_add_product(nc, ec, nfy, fy, nfy, fy, 1);
		nd = expansion_add_product(0, ed, nex, ex, nfy, fy, 1);
		nd = expansion_add_product(nd, ed, ney, ey, nfx, fx, -1);
		d = expansion_to_dd(nd, ed);
		d2 = (dd) {2 * d.hi, 2 * d.lo};
		/* x = (2 ax D + Nx) / 2D: a coordinate near 0 keeps its own digits */
		nn = expansion_add_product(0, en, nfy, fy, nb, eb, 1);
		nn = expansion_add_product(nn, en, ney, ey, nc, ec, -1);
		nn = expansion_add_product(nn, en, 1, two_a, nd, ed, 1);
		out[0] = dd_div(expansion_to_dd(nn, en), d2).hi;
		nn = expansion_add_product(0, en, nex, ex, nc, ec, 1);
		nn = expansion_add_product(nn, en, nfx, fx, nb, eb, -1);
		nn = expansion_add_product(nn, en, 1, two_a + 1, nd, ed, 1);
		out[1] = dd_div(expansion_to_dd(nn, en), d2).hi;
	}
}

/* ----------------------------------------------------------------
 *		helpers
 * ----------------------------------------------------------------
 */
static bool
vor_cancelled(const tdc_voronoi *v)
{
	return atomic_load_explicit(&v->cancel, memory_order_relaxed) != 0;
}

static void
vor_fail(tdc_voronoi *v, int code, const char *msg)
{
	int			expected = 0;

	if (atomic_compare_exchange_strong(&v->failed, &expected, code))
		snprintf(v->task_err, sizeof(v->task_err), "%s", msg);
	atomic_store(&v->cancel, 1);
}

static inline const double *
site_pt(const tdc_voronoi *v, uint32_t s)
{
	return v->job->xy + 2 * (size_t) s;
}

static inline bool
is_outer(const tdc_job *job, size_t h)
{
	return (job->outer[h >> 6] >> (h & 63)) & 1;
}

static void
grow_box(double *box, const double *p)
{
	box[0] = fmin(box[0], p[0]);
	box[1] = fmin(box[1], p[1]);
	box[2] = fmax(box[2], p[0]);
	box[3] = fmax(box[3], p[1]);
}

/*
 * The walks over the half-edges look at the next half-edge around each face
 * (tdc_tri_at), a random load in a mesh far bigger than the caches: ask for
 * it PREFETCH half-edges early, as emit.c does.  A free slot's link may be
 * anything: only prefetch inside the mesh.
 */
#define PREFETCH	16

static inline void
prefetch_face(const tdc_voronoi *v, size_t h, size_t hi)
{
	if (h + PREFETCH < hi)
	{
		uint32_t	ahead = v->job->he[SYM(h + PREFETCH)].prev;

		if (ahead < v->nhe)
			__builtin_prefetch(&v->job->he[SYM(ahead)]);
	}
}

static size_t
nranges_for(size_t n, size_t per)
{
	return n == 0 ? 0 : (n + per - 1) / per;
}

/* ----------------------------------------------------------------
 *		triangles: numbering, cocircular classes, circumcenters
 * ----------------------------------------------------------------
 */

/* The Voronoi vertex of a triangle: its circumcenter, from its canonical rotation. */
static inline void
triangle_vertex(const tdc_voronoi *v, const uint32_t s[3], double out[2])
{
	const double *p[3];
	int			k = 0;

	for (int i = 0; i < 3; i++)
		p[i] = site_pt(v, s[i]);
	if (tdc_lex_less(p[1], p[k]))
		k = 1;
	if (tdc_lex_less(p[2], p[k]))
		k = 2;
	tdc_circumcenter(p[k], p[(k + 1) % 3], p[(k + 2) % 3], out);
}

/* Are the two triangles beside edge h, h + 1 (h even) cocircular? */
static inline bool
edge_cocircular(const tdc_voronoi *v, size_t h)
{
	const tdc_job *job = v->job;
	uint32_t	a = job->he[h].org,
				b = job->he[h + 1].org,
				c,
				d;

	if (a == TDC_NIL || b == TDC_NIL || is_outer(job, h) || is_outer(job, h + 1))
		return false;
	c = job->he[job->he[h + 1].prev ^ 1].org;	/* apex left of h */
	d = job->he[job->he[h].prev ^ 1].org;	/* apex left of h + 1 */
	return tdc_incircle(site_pt(v, a), site_pt(v, b), site_pt(v, c), site_pt(v, d)) == 0;
}

/*
 * One walk over half-edge range r: note each site's smallest half-edge,
 * number the range's triangles, record each triangle's number on its three
 * half-edges, compute its circumcenter and the range's bounding box of them.
 * The numbers come in chunks of TRI_CHUNK claimed with one atomic add, as
 * emit.c collects triangles, so no walk is needed first to count them; the
 * numbers then depend on the timing, so nothing may be ordered by them (see
 * uf_union).  Cocircular triangles are found later, by the cell walks
 * (note_pair).
 */
static void
number_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_job *job = v->job;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe,
				n = 0,
				chunk = 0,
				used = TRI_CHUNK;
	uint32_t	t[3];
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h < hi; h++)
	{
		uint32_t	o = job->he[h].org;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			break;
		prefetch_face(v, h, hi);
		if (o == TDC_NIL)
			continue;
		/* smallest half-edge out of o: a CAS loop, contention is rare */
		{
			uint32_t	cur = atomic_load_explicit(&v->site_he[o], memory_order_relaxed);

			while ((uint32_t) h < cur &&
				   !atomic_compare_exchange_weak_explicit(&v->site_he[o], &cur, (uint32_t) h,
														  memory_order_relaxed,
														  memory_order_relaxed))
				;
		}
		if (tdc_tri_at(job, h, t))
		{
			uint32_t	h1 = job->he[SYM(h)].prev,
						h2 = job->he[SYM(h1)].prev,
						id;
			double	   *c;

			if (used == TRI_CHUNK)
			{
				if (n > 0)
					v->chunk_fill[chunk] = (uint32_t) used;
				chunk = atomic_fetch_add_explicit(&v->chunks_claimed, 1, memory_order_relaxed);
				if (chunk >= v->nchunks)
				{
					vor_fail(v, TDC_EINVAL, "the mesh holds more triangles than it counted");
					return;
				}
				used = 0;
			}
			id = (uint32_t) (chunk * TRI_CHUNK + used++);
			c = v->cc + 2 * (size_t) id;
			v->tri_id[h] = v->tri_id[h1] = v->tri_id[h2] = id;
			triangle_vertex(v, t, c);
			grow_box(box, c);
			n++;
		}
	}
	if (n > 0)
		v->chunk_fill[chunk] = (uint32_t) used;
	v->range_ntri[r] = n;
	memcpy(v->range_box + 4 * r, box, sizeof(box));
}

static void
parent_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ntri_cap ? lo + ITEMS_PER_TASK : v->ntri_cap;

	for (size_t t = lo; t < hi; t++)
		atomic_init(&v->parent[t], (uint32_t) t);
}

/* The join's order of the triangles: by their smallest half-edges. */
static void
tri_he_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe;
	uint32_t	t[3];

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h < hi; h++)
		if (tdc_tri_at(v->job, h, t))
			v->tri_he[v->tri_id[h]] = (uint32_t) h;
}

static uint32_t
uf_find(tdc_voronoi *v, uint32_t x)
{
	for (;;)
	{
		uint32_t	p = atomic_load_explicit(&v->parent[x], memory_order_relaxed);

		if (p == x)
			return x;
		x = p;
	}
}

/*
 * Lock-free union: the later root, in the order of the triangles' smallest
 * half-edges (not of their numbers, which depend on the timing), is linked
 * below the earlier with a CAS, so a root only ever moves earlier and every
 * class ends with its first triangle as root, whatever the order of the
 * unions: the same class vertex whatever the thread count.
 */
static void
uf_union(tdc_voronoi *v, uint32_t a, uint32_t b)
{
	for (;;)
	{
		uint32_t	big,
					small;

		a = uf_find(v, a);
		b = uf_find(v, b);
		if (a == b)
			return;
		big = v->tri_he[a] > v->tri_he[b] ? a : b;
		small = big == a ? b : a;
		if (atomic_compare_exchange_strong_explicit(&v->parent[big], &big, small,
													memory_order_relaxed,
													memory_order_relaxed))
			return;
	}
}

/* Join the two triangles of every cocircular edge of range r. */
static void
cocircular_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe;

	if (vor_cancelled(v))
		return;
	for (size_t h = lo & ~(size_t) 1; h < hi; h += 2)
		if (edge_cocircular(v, h))
			uf_union(v, v->tri_id[h], v->tri_id[h + 1]);
}

/*
 * Flatten the classes of the triangles of chunks [r * FLATTEN_CHUNKS, ...),
 * and the bounding box of its roots' circumcenters: a class's vertex is its
 * root's.
 */
#define FLATTEN_CHUNKS	64

static void
flatten_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * FLATTEN_CHUNKS,
				hi = lo + FLATTEN_CHUNKS < v->nchunks ? lo + FLATTEN_CHUNKS : v->nchunks;
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	if (vor_cancelled(v))
		return;
	for (size_t c = lo; c < hi; c++)
		for (size_t t = c * TRI_CHUNK; t < c * TRI_CHUNK + v->chunk_fill[c]; t++)
		{
			uint32_t	root = uf_find(v, (uint32_t) t);

			/* safe: other tasks only read parents while flattening */
			atomic_store_explicit(&v->parent[t], root, memory_order_relaxed);
			if (root == t)
				grow_box(box, v->cc + 2 * t);
		}
	memcpy(v->range_box + 4 * r, box, sizeof(box));
}

/* ----------------------------------------------------------------
 *		cells
 * ----------------------------------------------------------------
 */
/*
 * A ring being built.  A tagged ring also records, for each vertex, the
 * site across the edge that starts there (the neighbour whose bisector the
 * edge lies on), or TDC_NIL for an edge along B or E: clipping computes a
 * crossing from that bisector, not from the edge's end points, which may be
 * far away and rounded at their own, much larger, scale.
 */
typedef struct ring
{
	double	   *p;				/* 2 per vertex */
	uint32_t   *tag;			/* tagged rings: 1 per vertex */
	size_t		n;
	size_t		cap;
	bool		tagged;
	tdc_cache  *cache;			/* untagged: where p comes from (tdc_big_alloc) */
} ring;

static bool
ring_reserve(ring *r, size_t extra)
{
	if (r->n + extra > r->cap)
	{
		size_t		cap = (r->n + extra) + (r->n + extra) / 2 + 16;
		double	   *p = realloc(r->p, cap * 2 * sizeof(double));

		if (p == NULL)
			return false;
		r->p = p;
		if (r->tagged)
		{
			uint32_t   *t = realloc(r->tag, cap * sizeof(uint32_t));

			if (t == NULL)
				return false;
			r->tag = t;
		}
		r->cap = cap;
	}
	return true;
}

/*
 * Append a vertex whose outgoing edge has the given tag, dropping a repeat
 * of the previous vertex (which then takes the tag: the edge that starts
 * there is now this one); room was reserved.
 */
static inline void
ring_push(ring *r, double x, double y, uint32_t tag)
{
	if (r->n > 0 && r->p[2 * r->n - 2] == x && r->p[2 * r->n - 1] == y)
	{
		if (r->tagged)
			r->tag[r->n - 1] = tag;
		return;
	}
	r->p[2 * r->n] = x;
	r->p[2 * r->n + 1] = y;
	if (r->tagged)
		r->tag[r->n] = tag;
	r->n++;
}

/* Drop a closing repeat of the first vertex. */
static inline void
ring_close(ring *r)
{
	while (r->n > 1 && r->p[0] == r->p[2 * r->n - 2] && r->p[1] == r->p[2 * r->n - 1])
		r->n--;
}

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
static bool
clip_to_env(const tdc_voronoi *v, uint32_t site, ring *a, ring *b)
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

/* The class of the triangle left of h: its root, whose vertex is the class's. */
static inline uint32_t
class_of(const tdc_voronoi *v, uint32_t h)
{
	uint32_t	t = v->tri_id[h];

	return v->parent ? atomic_load_explicit(&v->parent[t], memory_order_relaxed) : t;
}

static inline const double *
vertex_of(const tdc_voronoi *v, uint32_t h)
{
	return v->cc + 2 * (size_t) class_of(v, h);
}

/*
 * Consecutive triangles ta and tb around a site, beside edge h: if their
 * vertices are close enough that the two triangles may be cocircular
 * (within the documented bound of each, 1/2 ulp + 2^-55 of the coordinate,
 * with room to spare), and they are, the classes are joined (vor_run).
 * Two cocircular triangles whose vertices came out as the same doubles
 * would need no join (the rings drop the repeat, as they must), but they
 * are joined all the same: it is what makes exactly cocircular input
 * (lattices) take, and so test, the path that the rare cocircular pair
 * with different roundings needs, and it costs nothing on input with no
 * four sites on a circle.  Once joined, every class has one vertex.
 */
static inline bool
close_coordinate(double a, double b)
{
	return fabs(a - b) <= 0x1p-48 * fmax(fabs(a), fabs(b));
}

static inline void
note_pair(const tdc_voronoi *v, uint32_t ta, uint32_t tb, uint32_t h)
{
	const double *a = v->cc + 2 * (size_t) ta,
			   *b = v->cc + 2 * (size_t) tb;

	if (v->parent)
		return;
	if (close_coordinate(a[0], b[0]) && close_coordinate(a[1], b[1]) &&
		edge_cocircular(v, h & ~(uint32_t) 1))
		atomic_store_explicit((atomic_int *) &v->need_join, 1, memory_order_relaxed);
}

/*
 * The ring of half-edges out of site s: its degree, and the one with the
 * outer face on its left (s is on the hull), or TDC_NIL.
 */
static size_t
site_degree(const tdc_voronoi *v, uint32_t s, uint32_t *ho)
{
	const tdc_job *job = v->job;
	uint32_t	h0 = atomic_load_explicit(&v->site_he[s], memory_order_relaxed),
				h = h0;
	size_t		deg = 0;

	*ho = TDC_NIL;
	if (h0 == TDC_NIL)
		return 0;
	do
	{
		if (is_outer(job, h))
			*ho = h;
		deg++;
		h = job->he[h].next;
	} while (h != h0);
	return deg;
}

/*
 * Cell of site s of a mesh with triangles, uncut, into r (cell ∩ B), which
 * has room for deg + 8 vertices (deg and ho from site_degree).  An
 * untagged r is for inner sites only: it skips the neighbours' lookups.
 */
static void
cell_of_mesh(const tdc_voronoi *v, uint32_t s, size_t deg, uint32_t ho, ring *r)
{
	const tdc_job *job = v->job;
	uint32_t	h0 = atomic_load_explicit(&v->site_he[s], memory_order_relaxed),
				h,
				prev_t = TDC_NIL;

	r->n = 0;
	/* start right after the outer face, if any, so the chain is open there */
	h = ho == TDC_NIL ? h0 : job->he[ho].next;
	for (size_t i = 0; i < deg; i++)
	{
		uint32_t	t,
					g = TDC_NIL,
					hn = job->he[h].next;

		if (h == ho)
		{
			h = hn;
			continue;
		}
		/* the edge to the next vertex is dual to onext(h) */
		if (r->tagged)
			g = job->he[SYM(hn)].org;
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
		uint32_t	hin = job->he[ho].next;
		const double *first = vertex_of(v, hin),
				   *last = vertex_of(v, job->he[ho].prev);
		double		pout[2],
					pin[2];
		int			sout,
					sin;
		unsigned	owned = 15;

		/* the corners of B in the cell: nearer to s than to every neighbour */
		h = h0;
		do
		{
			uint32_t	g = job->he[SYM(h)].org;

			for (int k = 0; k < 4; k++)
				if ((owned & (1u << k)) && !corner_closer(v, k, s, g))
					owned &= ~(1u << k);
			h = job->he[h].next;
		} while (h != h0);
		hull_ray(v, last, s, job->he[SYM(ho)].org, pout, &sout);
		hull_ray(v, first, job->he[SYM(hin)].org, s, pin, &sin);
		ring_push(r, pout[0], pout[1], TDC_NIL);
		push_arc(r, v->box, sout, sin, owned);
		ring_push(r, pin[0], pin[1], job->he[SYM(hin)].org);
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
static void
cell_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_job *job = v->job;
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
		if (job->site_of[s] != s)
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
		if (!ok || !clip_to_env(v, (uint32_t) s, &a, &b) || !ring_reserve(&out, a.n))
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
static void
mesh_cell_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_job *job = v->job;
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
		uint32_t	s = job->he[h].org,
					ho;
		size_t		deg,
					start = out.n;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			goto done;
		if (s == TDC_NIL ||
			atomic_load_explicit(&v->site_he[s], memory_order_relaxed) != (uint32_t) h)
			continue;
		deg = site_degree(v, s, &ho);
		if (!out_reserve(&out, deg + 8))
			goto oom;
		if (ho == TDC_NIL)
		{
			ring		w = {.p = out.p + 2 * start, .cap = out.cap - start};
			bool		inside = true;

			cell_of_mesh(v, s, deg, ho, &w);
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
		cell_of_mesh(v, s, deg, ho, &a);
		if (!clip_to_env(v, s, &a, &b) || !out_reserve(&out, a.n))
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

#define FAIL_OOM(msg) do { vor_fail(v, TDC_ENOMEM, msg); return TDC_ENOMEM; } while (0)

/* ----------------------------------------------------------------
 *		writing the cells straight into the host's value
 * ----------------------------------------------------------------
 */
/*
 * Site s's final cell (cut to E) into scratch, as mesh_cell_task builds it:
 * an inner site untagged into w, kept when inside E; otherwise tagged into
 * a and clipped (b scratch).  *res is w or a; false when out of memory.
 */
static bool
build_mesh_cell(const tdc_voronoi *v, uint32_t s, ring *w, ring *a, ring *b,
				const ring **res)
{
	uint32_t	ho;
	size_t		deg = site_degree(v, s, &ho);

	if (ho == TDC_NIL)
	{
		bool		inside = true;

		if (!ring_reserve(w, deg + 8))
			return false;
		cell_of_mesh(v, s, deg, ho, w);
		for (size_t i = 0; i < w->n && inside; i++)
			inside = w->p[2 * i] >= v->env[0] && w->p[2 * i] <= v->env[2] &&
				w->p[2 * i + 1] >= v->env[1] && w->p[2 * i + 1] <= v->env[3];
		if (inside)
		{
			*res = w;
			return true;
		}
	}
	if (!ring_reserve(a, deg + 8))
		return false;
	cell_of_mesh(v, s, deg, ho, a);
	if (!clip_to_env(v, s, a, b))
		return false;
	*res = a;
	return true;
}

/* Where site s's cell goes: the first input point that became s. */
static inline size_t
first_input(const tdc_voronoi *v, uint32_t s)
{
	return v->first_in ? v->first_in[s] : v->job->idx[s];
}

/* Room for n more words in a range's record. */
static bool
rec_reserve(uint32_t **rec, size_t *cap, size_t len, size_t n)
{
	if (len + n > *cap)
	{
		size_t		c = (len + n) + (len + n) / 2 + 1024;
		uint32_t   *p = realloc(*rec, c * sizeof(uint32_t));

		if (p == NULL)
			return false;
		*rec = p;
		*cap = c;
	}
	return true;
}

/*
 * An inner site's cell as its classes, from its ring of half-edges hs (from
 * its smallest, counter-clockwise) and their triangles' classes ts: the
 * vertices cell_of_mesh would give an untagged ring (a class once, a vertex
 * equal to the one before dropped, then a closing repeat of the first), as
 * class numbers into ids (room for cap).  Returns the count, or 0 when a
 * vertex lies outside E (or there are more than cap): then the cell is
 * built and clipped as a ring.
 */
static size_t
inner_cell_ids(const tdc_voronoi *v, const uint32_t *hs, const uint32_t *ts, size_t deg,
			   uint32_t *ids, size_t cap)
{
	uint32_t	prev_t = TDC_NIL;
	size_t		n = 0;
	const double *last = NULL;

	for (size_t j = 0; j < deg; j++)
	{
		uint32_t	t = ts[j];
		const double *c;

		if (t == prev_t)
			continue;
		if (prev_t != TDC_NIL)
			note_pair(v, prev_t, t, hs[j]);
		prev_t = t;
		c = v->cc + 2 * (size_t) t;
		if (last && c[0] == last[0] && c[1] == last[1])
			continue;
		if (!(c[0] >= v->env[0] && c[0] <= v->env[2] && c[1] >= v->env[1] && c[1] <= v->env[3]) ||
			n == cap)
			return 0;
		ids[n++] = t;
		last = c;
	}
	if (ts[0] != prev_t)
		note_pair(v, prev_t, ts[0], hs[0]);
	while (n > 1)
	{
		const double *f = v->cc + 2 * (size_t) ids[0],
				   *l = v->cc + 2 * (size_t) ids[n - 1];

		if (f[0] != l[0] || f[1] != l[1])
			break;
		n--;
	}
	return n;
}


/*
 * Sizing: the sites whose smallest half-edge lies in half-edge range rg, in
 * mesh order (see mesh_cell_task), each cell's vertex count and the range's
 * bytes, and a record of the range's cells for the writing phase: per site
 * its number, its count m and, for an inner cell inside E (almost all of
 * them), its m classes; for any other cell (on the hull, or crossing E),
 * built as a ring and clipped, m | REC_XY and its coordinates.  Writing then
 * reads the record in order and looks up the vertices, with no walk around
 * the sites and no mesh: keeping all cells' coordinates instead would cost
 * some 100 MB of fresh memory for a million points, which the kernel must
 * clear, and walking twice, the mesh's random loads twice.
 */
#define BATCH		16			/* sites walked together (mesh_size_task) */
#define REC_XY		0x80000000u	/* record: the cell's coordinates follow */
#define RING_MAX	32			/* longer rings go the ring's way */

static void
mesh_size_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_job *job = v->job;
	size_t		lo = rg * v->cell_range,
				hi = lo + v->cell_range < v->nhe ? lo + v->cell_range : v->nhe,
				len = 0,
				cap = 0,
				nb = 0;
	ring		w = {0},
				a = {.tagged = true},
				b = {.tagged = true};
	uint64_t	bytes = 0;
	size_t		cells = 0;
	uint32_t   *rec = NULL;
	uint32_t	site[BATCH],
				hs[BATCH][RING_MAX],
				ts[BATCH][RING_MAX],
				deg[BATCH];
	bool		open[BATCH],
				inner[BATCH];

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h <= hi; h++)
	{
		uint32_t	s = h < hi ? job->he[h].org : TDC_NIL;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			goto done;
		if (h < hi && (s == TDC_NIL ||
					   atomic_load_explicit(&v->site_he[s], memory_order_relaxed) != (uint32_t) h))
			continue;
		if (h < hi)
		{
			site[nb] = s;
			hs[nb][0] = (uint32_t) h;
			deg[nb] = 1;
			open[nb] = true;
			inner[nb] = true;
			nb++;
			if (nb < BATCH)
				continue;
		}
		if (nb == 0)
			continue;

		/*
		 * The batch's rings, one step of every site at a time: the walks'
		 * random loads are independent across the sites, so they overlap
		 * instead of waiting for each other.  A ring with the outer face
		 * or longer than RING_MAX goes the ring's way.
		 */
		for (bool any = true; any;)
		{
			any = false;
			for (size_t i = 0; i < nb; i++)
			{
				uint32_t	hn;

				if (!open[i])
					continue;
				hn = job->he[hs[i][deg[i] - 1]].next;
				if (hn == hs[i][0])
					open[i] = false;
				else if (deg[i] == RING_MAX)
				{
					open[i] = false;
					inner[i] = false;
				}
				else
				{
					hs[i][deg[i]++] = hn;
					__builtin_prefetch(&v->tri_id[hn]);
					any = true;
				}
			}
		}
		for (size_t i = 0; i < nb; i++)
			for (size_t j = 0; j < deg[i] && inner[i]; j++)
			{
				if (is_outer(job, hs[i][j]))
					inner[i] = false;
				else
				{
					ts[i][j] = class_of(v, hs[i][j]);
					__builtin_prefetch(v->cc + 2 * (size_t) ts[i][j]);
				}
			}
		for (size_t i = 0; i < nb; i++)
		{
			size_t		m = 0;
			const ring *c;

			if (!rec_reserve(&rec, &cap, len, 2 + RING_MAX))
				goto oom;
			if (inner[i])
				m = inner_cell_ids(v, hs[i], ts[i], deg[i], rec + len + 2, RING_MAX);
			rec[len] = site[i];
			rec[len + 1] = (uint32_t) m;
			if (m == 0)
			{
				/* built as a ring and clipped: its coordinates, 4 words a vertex */
				if (!build_mesh_cell(v, site[i], &w, &a, &b, &c) ||
					!rec_reserve(&rec, &cap, len, 2 + 4 * c->n))
					goto oom;
				m = c->n;
				rec[len + 1] = (uint32_t) m | REC_XY;
				memcpy(rec + len + 2, c->p, 16 * m);
				len += 2 + 4 * m;
			}
			else
				len += 2 + m;
			v->cell_n[site[i]] = (uint32_t) m;
			bytes += v->writer.size(v->writer.arg, m);
			cells++;
		}
		nb = 0;
	}
	v->range_bytes[rg] = bytes;
	v->range_cells[rg] = cells;
	v->range_rec[rg] = rec;
	v->range_rec_len[rg] = len;
	rec = NULL;
	goto done;
oom:
	vor_fail(v, TDC_ENOMEM, "out of memory sizing the Voronoi cells");
done:
	free(rec);
	free(w.p);
	free(a.p);
	free(a.tag);
	free(b.p);
	free(b.tag);
}

/* Writing: range rg's cells, as its record lists them, to the writer. */
static void
mesh_write_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const uint32_t *rec = v->range_rec[rg];
	size_t		len = v->range_rec_len[rg];
	ring		w = {0};
	double		xy[2 * RING_MAX];

	if (vor_cancelled(v))
		return;
	for (size_t i = 0, k = 0; i < len; k++)
	{
		uint32_t	s = rec[i];
		size_t		m = rec[i + 1] & ~REC_XY;
		char	   *dst = v->dst + v->site_off[s];

		if ((k & 4095) == 4095 && vor_cancelled(v))
			break;
		if (rec[i + 1] & REC_XY)
		{
			/* the record's words are not aligned for doubles */
			if (!ring_reserve(&w, m))
			{
				vor_fail(v, TDC_ENOMEM, "out of memory writing the Voronoi cells");
				break;
			}
			memcpy(w.p, rec + i + 2, 16 * m);
			v->writer.write(v->writer.arg, dst, w.p, m);
			i += 2 + 4 * m;
		}
		else
		{
			for (size_t j = 0; j < m; j++)
				memcpy(xy + 2 * j, v->cc + 2 * (size_t) rec[i + 2 + j], 2 * sizeof(double));
			v->writer.write(v->writer.arg, dst, xy, m);
			i += 2 + m;
		}
	}
	free(w.p);
}

/* Collinear input: the cells of site range rg, kept by cell_task, to the writer. */
static void
line_emit_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = rg * SITES_PER_TASK,
				hi = lo + SITES_PER_TASK < v->nsites ? lo + SITES_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->writer.write(v->writer.arg, v->dst + v->site_off[s], v->cell_xy[s], v->cell_n[s]);
}

/* Each cell's bytes at the place of its site's first input point. */
static void
scatter_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nsites ? lo + ITEMS_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->inpos[first_input(v, (uint32_t) s)] = v->writer.size(v->writer.arg, v->cell_n[s]);
}

/* The bytes of the cells of input block r. */
static void
block_sum_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ninput ? lo + ITEMS_PER_TASK : v->ninput;
	uint64_t	sum = 0;

	if (vor_cancelled(v))
		return;
	for (size_t i = lo; i < hi; i++)
		sum += v->inpos[i];
	v->block_start[r + 1] = sum;
}

/*
 * Sizes to offsets in input block r, and the block's part of the value
 * mapped in now, in parallel, rather than a page fault at a time by the
 * scattered writes that follow.
 */
static void
offset_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ninput ? lo + ITEMS_PER_TASK : v->ninput;
	uint64_t	off = v->block_start[r];

	if (vor_cancelled(v))
		return;
	for (size_t i = lo; i < hi; i++)
	{
		uint64_t	size = v->inpos[i];

		v->inpos[i] = off;
		off += size;
	}
	tdc_prefault(v->dst + v->block_start[r], (size_t) (off - v->block_start[r]));
}

/*
 * Each site's offset, from its first input point's: a loop of independent
 * random loads, which overlap, rather than one in the middle of every
 * cell's writing.
 */
static void
gather_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nsites ? lo + ITEMS_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->site_off[s] = v->inpos[first_input(v, (uint32_t) s)];
}

/*
 * The writing phase, on the driver thread: offsets in input order (the
 * sites' first input points, for a tolerance found through the input map),
 * then every cell to the writer.
 */
static int
vor_emit_run(tdc_voronoi *v)
{
	const tdc_job *job = v->job;
	size_t		nb;
	int			rc;

	rc = tdc_pool_create(&v->pool, v->threads);
	if (rc != 0)
	{
		vor_fail(v, rc, rc == TDC_ETHREAD ? "could not create worker threads" : "out of memory");
		return rc;
	}
	v->ninput = tdc_num_input(job);
	if (job->opt.tolerance > 0)
	{
		v->first_in = malloc(v->nsites * sizeof(uint32_t) + 1);
		if (v->first_in == NULL)
			FAIL_OOM("out of memory ordering the Voronoi cells");
		memset(v->first_in, 0xff, v->nsites * sizeof(uint32_t));
		for (size_t i = 0; i < v->ninput; i++)
		{
			uint32_t	s = tdc_input_site(job, i);

			if (s == UINT32_MAX)
				FAIL_OOM("out of memory mapping the input to its sites");
			if (v->first_in[s] == TDC_NIL)
				v->first_in[s] = (uint32_t) i;
			if ((i & 65535) == 65535 && vor_cancelled(v))
				return TDC_ECANCELED;
		}
	}
	nb = nranges_for(v->ninput, ITEMS_PER_TASK);
	v->block_start = calloc(nb + 1, sizeof(uint64_t));
	if (v->block_start == NULL)
		FAIL_OOM("out of memory ordering the Voronoi cells");

	/*
	 * Writing a mesh's cells reads only the records and the vertices: the
	 * triangle numbers' pages, mapped and cleared already, hold the offsets
	 * (the input's, then the sites'), when they fit, rather than fresh pages
	 * the kernel must clear.
	 */
	if (v->tri_id && (v->ninput + v->nsites) * sizeof(uint64_t) <= v->nhe * sizeof(uint32_t))
	{
		v->inpos = (uint64_t *) (void *) v->tri_id;
		v->site_off = v->inpos + v->ninput;
		v->offsets_in_tri_id = true;
		memset(v->inpos, 0, v->ninput * sizeof(uint64_t));
	}
	else
	{
		v->inpos = tdc_big_alloc(v->cache, v->ninput * sizeof(uint64_t) + 1);
		v->site_off = tdc_big_alloc(v->cache, v->nsites * sizeof(uint64_t) + 1);
		if (v->inpos == NULL || v->site_off == NULL)
			FAIL_OOM("out of memory ordering the Voronoi cells");
	}
	tdc_pool_for(v->pool, nranges_for(v->nsites, ITEMS_PER_TASK), scatter_task, v);
	tdc_pool_for(v->pool, nb, block_sum_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	for (size_t r = 0; r < nb; r++)
		v->block_start[r + 1] += v->block_start[r];
	if (v->block_start[nb] != v->emit_bytes)
	{
		vor_fail(v, TDC_EINVAL, "the Voronoi cells' offsets do not add up to their size");
		return TDC_EINVAL;
	}
	tdc_pool_for(v->pool, nb, offset_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	/* by site now; the input's offsets are no longer needed */
	tdc_pool_for(v->pool, nranges_for(v->nsites, ITEMS_PER_TASK), gather_task, v);
	if (!v->offsets_in_tri_id)
		tdc_big_free(v->cache, v->inpos);
	v->inpos = NULL;
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	tdc_pool_for(v->pool, v->nranges, v->ntri > 0 ? mesh_write_task : line_emit_task, v);
	return vor_cancelled(v) ? TDC_ECANCELED : TDC_OK;
}

static int
cmp_site(const void *x, const void *y, void *arg)
{
	const tdc_voronoi *v = arg;
	const double *p = site_pt(v, *(const uint32_t *) x),
			   *q = site_pt(v, *(const uint32_t *) y);

	return tdc_lex_less(p, q) ? -1 : tdc_lex_less(q, p) ? 1 : 0;
}


/*
 * B: around E, the sites (base) and the vertices of the ranges' boxes,
 * widened on every side by its larger extent.
 */
static void
set_outer_box(tdc_voronoi *v, const double base[4], size_t nboxes)
{
	double		box[4] = {base[0], base[1], base[2], base[3]},
				w;

	for (size_t r = 0; r < nboxes; r++)
	{
		if (v->range_box[4 * r] <= v->range_box[4 * r + 2])
		{
			grow_box(box, v->range_box + 4 * r);
			grow_box(box, v->range_box + 4 * r + 2);
		}
	}
	w = fmax(box[2] - box[0], box[3] - box[1]);
	if (!(w > 0))
		w = fmax(fabs(box[2]), fabs(box[3])) + 1;
	v->box[0] = box[0] - w;
	v->box[1] = box[1] - w;
	v->box[2] = box[2] + w;
	v->box[3] = box[3] + w;
}

/*
 * The cells, into buffers or (emit) sized and recorded; every site's count
 * in cell_n.  Run again from scratch after the classes were joined.
 */
static int
build_cells(tdc_voronoi *v)
{
	size_t		nr = v->nranges;

	v->total_vertices = 0;
	v->emit_bytes = 0;
	v->emit_cells = 0;
	if (v->emit && v->ntri > 0)
	{
		for (size_t r = 0; r < nr; r++)
		{
			free(v->range_rec[r]);
			v->range_rec[r] = NULL;
			v->range_rec_len[r] = 0;
		}
		tdc_pool_for(v->pool, nr, mesh_size_task, v);
		if (vor_cancelled(v))
			return TDC_ECANCELED;
		for (size_t r = 0; r < nr; r++)
		{
			v->emit_bytes += v->range_bytes[r];
			v->emit_cells += v->range_cells[r];
		}
		for (size_t s = 0; s < v->nsites; s++)
			v->total_vertices += v->cell_n[s];
		return TDC_OK;
	}
	for (size_t r = 0; r < nr; r++)
	{
		if (v->big_bufs)
			tdc_big_free(v->cache, v->range_buf[r]);
		else
			free(v->range_buf[r]);
		v->range_buf[r] = NULL;
	}
	tdc_pool_for(v->pool, nr, v->ntri > 0 ? mesh_cell_task : cell_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	for (size_t s = 0; s < v->nsites; s++)
	{
		v->total_vertices += v->cell_n[s];
		if (v->emit && v->cell_n[s] > 0)
		{
			v->emit_bytes += v->writer.size(v->writer.arg, v->cell_n[s]);
			v->emit_cells++;
		}
	}
	return TDC_OK;
}

/*
 * Join the triangles of every cocircular edge into classes, each with its
 * root's vertex, and B again from the roots' vertices.
 */
static int
join_cocircular(tdc_voronoi *v, const double base[4])
{
	size_t		nr = nranges_for(v->nhe, ITEMS_PER_TASK),
				ntr = nranges_for(v->ntri_cap, ITEMS_PER_TASK),
				nfr = nranges_for(v->nchunks, FLATTEN_CHUNKS);

	v->parent = tdc_big_alloc(v->cache, v->ntri_cap * sizeof(uint32_t));
	v->tri_he = tdc_big_alloc(v->cache, v->ntri_cap * sizeof(uint32_t));
	if (v->parent == NULL || v->tri_he == NULL)
		FAIL_OOM("out of memory joining cocircular triangles");
	tdc_pool_for(v->pool, ntr, parent_task, v);
	tdc_pool_for(v->pool, nr, tri_he_task, v);
	tdc_pool_for(v->pool, nr, cocircular_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	tdc_pool_for(v->pool, nfr, flatten_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	set_outer_box(v, base, nfr);
	return TDC_OK;
}

/* Everything, on the driver thread (or the caller's for small jobs). */
static int
vor_run(tdc_voronoi *v)
{
	const tdc_job *job = v->job;
	size_t		nr = 0,
				nboxes = 0;
	double		base[4] = {v->env[0], v->env[1], v->env[2], v->env[3]},
				lo[2],
				hi[2];
	int			rc;

	rc = tdc_pool_create(&v->pool, v->threads);
	if (rc != 0)
	{
		vor_fail(v, rc, rc == TDC_ETHREAD ? "could not create worker threads" : "out of memory");
		return rc;
	}
	v->nsites = job->nin;
	v->nhe = job->nin * 6;
	v->ntri = job->ntri;

	/* B: around E, the sites and (below) every vertex, then widened */
	if (job->nsites > 0)
	{
		tdc_site_extent(job, lo, hi);
		grow_box(base, lo);
		grow_box(base, hi);
	}

	if (v->ntri > 0)
	{
		size_t		ntri = 0;

		nr = nranges_for(v->nhe, ITEMS_PER_TASK);
		/* every range but one chunk per range fills its chunks */
		v->nchunks = v->ntri / TRI_CHUNK + nr;
		v->ntri_cap = v->nchunks * TRI_CHUNK;
		v->site_he = tdc_big_alloc(v->cache, job->nin * sizeof(uint32_t));
		v->range_ntri = calloc(nr + 1, sizeof(size_t));
		v->chunk_fill = calloc(v->nchunks + 1, sizeof(uint32_t));
		/* a half-edge outside every triangle keeps a number never read */
		v->tri_id = tdc_big_alloc(v->cache, v->nhe * sizeof(uint32_t));
		v->cc = tdc_big_alloc(v->cache, v->ntri_cap * 2 * sizeof(double));
		v->range_box = malloc((nr > v->nchunks ? nr : v->nchunks) * 4 * sizeof(double) + 1);
		if (!v->site_he || !v->range_ntri || !v->chunk_fill || !v->tri_id || !v->cc ||
			!v->range_box)
			FAIL_OOM("out of memory for the Voronoi vertices");
		atomic_init(&v->chunks_claimed, 0);
		for (size_t s = 0; s < job->nin; s++)
			atomic_init(&v->site_he[s], TDC_NIL);
		tdc_pool_for(v->pool, nr, number_task, v);
		if (vor_cancelled(v))
			return TDC_ECANCELED;
		for (size_t r = 0; r < nr; r++)
			ntri += v->range_ntri[r];
		if (ntri != v->ntri)
		{
			vor_fail(v, TDC_EINVAL, "the mesh does not hold the triangles counted");
			return TDC_EINVAL;
		}
		nboxes = nr;
	}
	else if (job->nsites >= 2)
	{
		size_t		k = 0;

		v->line = malloc(job->nsites * sizeof(uint32_t));
		v->line_pos = malloc(job->nin * sizeof(uint32_t));
		if (v->line == NULL || v->line_pos == NULL)
			FAIL_OOM("out of memory sorting collinear sites");
		for (size_t s = 0; s < job->nin; s++)
			if (job->site_of[s] == s)
				v->line[k++] = (uint32_t) s;
		v->nline = k;
		qsort_r(v->line, k, sizeof(uint32_t), cmp_site, v);
		for (size_t i = 0; i < k; i++)
			v->line_pos[v->line[i]] = (uint32_t) i;
	}
	set_outer_box(v, base, nboxes);

	/*
	 * Cells of a mesh by half-edge ranges of at least 2^18 (a few MB of
	 * cells each: few buffers to map and grow), yet eight ranges per
	 * thread where there is enough, for balance.
	 */
	v->cell_range = v->nhe / ((size_t) v->threads * 8) + 1;
	if (v->cell_range < CELL_RANGE_MIN)
		v->cell_range = CELL_RANGE_MIN;
	v->big_bufs = v->ntri > 0;
	nr = v->ntri > 0 ? nranges_for(v->nhe, v->cell_range) : nranges_for(v->nsites, SITES_PER_TASK);
	v->nranges = nr;
	/* zeroed: a site without a cell (a duplicate) keeps 0 */
	v->cell_n = tdc_big_alloc(v->cache, v->nsites * sizeof(uint32_t) + 1);
	if (v->cell_n == NULL)
		FAIL_OOM("out of memory for the Voronoi cells");
	if (v->emit && v->ntri > 0)
	{
		v->range_bytes = calloc(nr + 1, sizeof(uint64_t));
		v->range_cells = calloc(nr + 1, sizeof(size_t));
		v->range_rec = calloc(nr + 1, sizeof(uint32_t *));
		v->range_rec_len = calloc(nr + 1, sizeof(size_t));
		if (v->range_bytes == NULL || v->range_cells == NULL || v->range_rec == NULL ||
			v->range_rec_len == NULL)
			FAIL_OOM("out of memory for the Voronoi cells");
	}
	else
	{
		v->cell_xy = tdc_big_alloc(v->cache, v->nsites * sizeof(double *) + 1);
		v->range_buf = calloc(nr + 1, sizeof(double *));
		if (v->cell_xy == NULL || v->range_buf == NULL)
			FAIL_OOM("out of memory for the Voronoi cells");
	}
	rc = build_cells(v);
	if (rc != TDC_OK)
		return rc;

	/*
	 * Two cocircular triangles whose vertices came out different (see the
	 * header comment): join the classes and build every cell again.
	 */
	if (atomic_load(&v->need_join))
	{
		rc = join_cocircular(v, base);
		if (rc == TDC_OK)
			rc = build_cells(v);
		if (rc != TDC_OK)
			return rc;
	}

	/* what only the build needed (emit: writing builds some cells again) */
	if (!(v->emit && v->ntri > 0))
	{
		tdc_big_free(v->cache, v->tri_id);
		v->tri_id = NULL;
	}
	return TDC_OK;
}

/* ----------------------------------------------------------------
 *		lifecycle (the same as a job's)
 * ----------------------------------------------------------------
 */
/*
 * The work, on the driver or the caller's thread: the status, its message in
 * v->err (a task's error wins, then a cancel).  The pool goes first.
 */
static int
vor_work(void *arg)
{
	tdc_voronoi *v = arg;
	int			rc = v->writing ? vor_emit_run(v) : vor_run(v);

	tdc_pool_destroy(v->pool);
	v->pool = NULL;
	if (atomic_load(&v->failed))
	{
		snprintf(v->err, sizeof(v->err), "%s", v->task_err);
		return atomic_load(&v->failed);
	}
	if (rc == TDC_ECANCELED || (rc == TDC_OK && atomic_load(&v->cancel)))
	{
		snprintf(v->err, sizeof(v->err), "Voronoi diagram cancelled");
		return TDC_ECANCELED;
	}
	return rc;
}

size_t
tdc_voronoi_memory(size_t n, int threads)
{
	/*
	 * Per input point: 6 half-edges' triangle numbers (24), at most 2
	 * triangles' parents, smallest half-edges (joining) and circumcenters
	 * (8 + 8 + 32, and a partly used chunk of numbers per 2^16 half-edges,
	 * under 2 bytes a point), the
	 * smallest half-edge, ring pointer and count of its site (4 + 8 + 4);
	 * ring storage: every triangle is in at most 3 rings (6 vertices per
	 * point), clipping adds at most 4 per cell, a hull cell 2 exit points
	 * and 4 corners of B: 16 vertices of 16 bytes per point, and a range's
	 * buffer grows by half its size at a time (x 1.5).  Plus the collinear
	 * sort (8) and per thread scratch rings.  A diagram written straight
	 * into the host's value (tdc_voronoi_start_emit) has no ring storage
	 * but, per point, its records (a site, a count and 6 classes on
	 * average; a clipped cell's coordinates instead, at most as many as
	 * the ring storage's; x 1.5 for growing), the input's sizes and
	 * offsets (8) and the sites' offsets (8), in the triangle numbers'
	 * pages when they fit, and with a tolerance the sites' first inputs
	 * (4): less.
	 */
	return n * (24 + 48 + 2 + 16 + 8 + 8 + 16 * 16 * 3 / 2) + (size_t) (threads + 1) * 65536 + 4096;
}

static int
voronoi_start(const tdc_job *job, const double env[4], int threads,
			  const tdc_cell_writer *writer, tdc_voronoi **out, char *err,
			  size_t errlen)
{
	tdc_voronoi *v;
	int			rc;

	*out = NULL;
	if (err && errlen)
		err[0] = '\0';
#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (tdc_job_wait((tdc_job *) job, 0) != TDC_OK)
		FAIL(TDC_EINVAL, "the triangulation has not finished successfully");
	if (!(env[0] <= env[2] && env[1] <= env[3]) || !isfinite(env[0]) ||
		!isfinite(env[1]) || !isfinite(env[2]) || !isfinite(env[3]))
		FAIL(TDC_EINVAL, "the clip envelope must be a finite rectangle");
	if (job->nsites > 0)
	{
		double		lo[2],
					hi[2];

		tdc_site_extent(job, lo, hi);
		if (lo[0] < env[0] || lo[1] < env[1] || hi[0] > env[2] || hi[1] > env[3])
			FAIL(TDC_EINVAL, "the clip envelope must contain every site");
	}
	if (threads < 0 || threads > 1024)
		FAIL(TDC_EINVAL, "threads must be between 0 and 1024, not %d", threads);
	v = calloc(1, sizeof(tdc_voronoi));
	if (v == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	v->job = job;
	v->cache = job->opt.cache;
	if (writer)
	{
		v->emit = true;
		v->writer = *writer;
	}
	memcpy(v->env, env, sizeof(v->env));
	v->threads = threads > 0 ? threads : tdc_threads_used(job);
	if (v->threads < 1)
		v->threads = 1;
	atomic_init(&v->failed, 0);
	tdc_runner_init(&v->run, &v->cancel);

	if (job->nin <= TDC_INLINE_MAX)
		v->threads = 1;
	rc = tdc_runner_start(&v->run, job->nin <= TDC_INLINE_MAX, vor_work, v, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&v->run);
		free(v);
		return rc;
	}
	*out = v;
	return TDC_OK;
#undef FAIL
}

int
tdc_voronoi_start(const tdc_job *job, const double env[4], int threads,
				  tdc_voronoi **out, char *err, size_t errlen)
{
	return voronoi_start(job, env, threads, NULL, out, err, errlen);
}

int
tdc_voronoi_start_emit(const tdc_job *job, const double env[4], int threads,
					   const tdc_cell_writer *writer, tdc_voronoi **out,
					   char *err, size_t errlen)
{
	if (writer == NULL || writer->size == NULL || writer->write == NULL)
	{
		*out = NULL;
		if (err && errlen)
			snprintf(err, errlen, "a Voronoi cell writer needs its size and write functions");
		return TDC_EINVAL;
	}
	return voronoi_start(job, env, threads, writer, out, err, errlen);
}

uint64_t
tdc_voronoi_emit_size(const tdc_voronoi *v, size_t *cells)
{
	if (cells)
		*cells = v->emit_cells;
	return v->emit_bytes;
}

int
tdc_voronoi_emit(tdc_voronoi *v, char *dst, char *err, size_t errlen)
{
	int			rc;

	if (err && errlen)
		err[0] = '\0';
	if (!v->emit || v->writing || tdc_runner_wait(&v->run, 0) != TDC_OK)
	{
		if (err && errlen)
			snprintf(err, errlen, "the Voronoi cells cannot be written: %s",
					 !v->emit ? "not started for writing" : v->writing ? "already written" :
					 "their sizing has not finished successfully");
		return TDC_EINVAL;
	}
	tdc_runner_rearm(&v->run);
	v->dst = dst;
	v->writing = true;
	rc = tdc_runner_start(&v->run, v->job->nin <= TDC_INLINE_MAX, vor_work, v, err, errlen);
	if (rc != TDC_OK)
		tdc_runner_finish(&v->run, rc);
	return rc;
}

int
tdc_voronoi_wait(tdc_voronoi *v, int timeout_ms)
{
	return tdc_runner_wait(&v->run, timeout_ms);
}

void
tdc_voronoi_cancel(tdc_voronoi *v)
{
	if (v)
		tdc_runner_cancel(&v->run);
}

const char *
tdc_voronoi_error(const tdc_voronoi *v)
{
	return v->err;
}

void
tdc_voronoi_free(tdc_voronoi *v)
{
	if (v == NULL)
		return;
	tdc_runner_destroy(&v->run);
	tdc_big_free(v->cache, v->tri_id);
	tdc_big_free(v->cache, v->parent);
	tdc_big_free(v->cache, v->cc);
	tdc_big_free(v->cache, v->site_he);
	free(v->range_ntri);
	free(v->chunk_fill);
	tdc_big_free(v->cache, v->tri_he);
	free(v->range_box);
	free(v->line);
	free(v->line_pos);
	if (v->range_buf)
		for (size_t r = 0; r < v->nranges; r++)
		{
			if (v->big_bufs)
				tdc_big_free(v->cache, v->range_buf[r]);
			else
				free(v->range_buf[r]);
		}
	free(v->range_buf);
	tdc_big_free(v->cache, v->cell_xy);
	tdc_big_free(v->cache, v->cell_n);
	free(v->range_bytes);
	free(v->range_cells);
	free(v->first_in);
	if (!v->offsets_in_tri_id)
	{
		tdc_big_free(v->cache, v->inpos);
		tdc_big_free(v->cache, v->site_off);
	}
	free(v->block_start);
	if (v->range_rec)
		for (size_t r = 0; r < v->nranges; r++)
			free(v->range_rec[r]);
	free(v->range_rec);
	free(v->range_rec_len);
	free(v);
}

int
tdc_voronoi_build(const tdc_job *job, const double env[4], int threads,
				  tdc_voronoi **out, char *err, size_t errlen)
{
	int			rc = tdc_voronoi_start(job, env, threads, out, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_voronoi_wait(*out, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", (*out)->err);
	return rc;
}

size_t
tdc_voronoi_cell(const tdc_voronoi *v, uint32_t site, const double **xy)
{
	if (site >= v->nsites || v->cell_xy == NULL || v->cell_n[site] == 0)
	{
		*xy = NULL;
		return 0;
	}
	*xy = v->cell_xy[site];
	return v->cell_n[site];
}

size_t
tdc_voronoi_num_vertices(const tdc_voronoi *v)
{
	return v->total_vertices;
}

void
tdc_voronoi_env(const tdc_voronoi *v, double env[4])
{
	memcpy(env, v->env, sizeof(v->env));
}

void
tdc_voronoi_default_env(const tdc_job *job, double env[4])
{
	double		w;

	if (job->nsites == 0)
	{
		env[0] = env[1] = env[2] = env[3] = 0;
		return;
	}

	/*
	 * The box of every input point, not only of the sites a tolerance kept:
	 * GEOS merges only exact duplicates before taking the envelope.
	 */
	w = fmax(job->bmax[0] - job->bmin[0], job->bmax[1] - job->bmin[1]);
	env[0] = job->bmin[0] - w;
	env[1] = job->bmin[1] - w;
	env[2] = job->bmax[0] + w;
	env[3] = job->bmax[1] + w;
}
