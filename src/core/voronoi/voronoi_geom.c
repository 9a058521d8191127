/*
 * voronoi_geom.c
 *		The Voronoi vertices: circumcenters, rounded once per coordinate.
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
 */
#include <math.h>

#include "engine/exact.h"
#include "engine/engine_int.h"

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

