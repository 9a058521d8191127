/*
 * predicates.h
 *		Exact orientation and in-circle predicates.
 *
 * Each predicate first evaluates the determinant in plain double arithmetic
 * and accepts its sign when the magnitude exceeds a forward error bound
 * (Shewchuk 1997, "Adaptive Precision Floating-Point Arithmetic and Fast
 * Robust Geometric Predicates", stage A bounds).  An absolute term is added to
 * the bound so that underflow in the products can never let a wrong sign
 * through.  Otherwise predicates.c evaluates the determinant exactly with
 * expansion arithmetic on the raw coordinates, which is exact for every
 * coordinate that is 0 or of magnitude in [1e-60, 1e60] (the driver rejects
 * others).
 *
 * Conventions (as Shewchuk's):
 *	tdc_orient2d(a,b,c) > 0  iff a,b,c are in counter-clockwise order.
 *	tdc_incircle(a,b,c,d) > 0 iff d lies inside the circle through a,b,c,
 *	given a,b,c counter-clockwise.
 * Only the sign of the result is meaningful.
 */
#ifndef TDC_PREDICATES_H
#define TDC_PREDICATES_H

#include <stdbool.h>

/* (3 + 16 eps) eps and (10 + 96 eps) eps with eps = 2^-53 */
#define TDC_CCW_ERRBOUND	(3.3306690738754716e-16)
#define TDC_ICC_ERRBOUND	(1.1102230246251577e-15)
/* Absolute slack: covers the rounding of products that fall below 2^-960. */
#define TDC_UNDERFLOW_SLACK	(0x1p-900)

/* Exact signs (-1.0, 0.0 or +1.0); called only when the filter fails. */
extern double tdc_orient2d_exact(const double *a, const double *b, const double *c);
extern double tdc_incircle_exact(const double *a, const double *b,
								 const double *c, const double *d);

/*
 * Exact sign (-1, 0 or +1) of |a - b|^2 - |c - d|^2, for the tolerance pass
 * (tolerance.c), which filters in double arithmetic first.  Exact when every
 * coordinate is 0 or of magnitude in [2^-252, 2^202]: a wider range than the
 * input's, so that a clamped tolerance can be passed as a point (t, 0).
 */
extern int	tdc_sqdist_cmp_exact(const double *a, const double *b,
								 const double *c, const double *d);

/*
 * Exact sign of |a - b|^2 - |c - d|^2 for coordinates that are 0 or of
 * magnitude within [TDC_COORD_MIN, TDC_COORD_MAX] (the TIN's nearest-site
 * decisions, tin_locate.c).  Filter: each squared distance in double has a
 * relative error below 5 * 2^-53 (two differences, two squares and a sum,
 * each rounded once), since within that range a nonzero difference is at
 * least 2^-251 and its square is a normal number, and no square overflows;
 * so two values apart by more than 2^-49 relative are ordered as their
 * exact counterparts.  The rest goes to tdc_sqdist_cmp_exact, whose range
 * contains this one.
 */
static inline int
tdc_sqdist_cmp(const double *a, const double *b, const double *c, const double *d)
{
	double		ax = a[0] - b[0],
				ay = a[1] - b[1],
				cx = c[0] - d[0],
				cy = c[1] - d[1];
	double		s = ax * ax + ay * ay,
				t = cx * cx + cy * cy;

	if (s < t * (1 - 0x1p-49))
		return -1;
	if (t < s * (1 - 0x1p-49))
		return 1;
	return tdc_sqdist_cmp_exact(a, b, c, d);
}

static inline double
tdc_orient2d(const double *a, const double *b, const double *c)
{
	double		detleft = (a[0] - c[0]) * (b[1] - c[1]);
	double		detright = (a[1] - c[1]) * (b[0] - c[0]);
	double		det = detleft - detright;
	double		bound;

	bound = TDC_CCW_ERRBOUND * (__builtin_fabs(detleft) + __builtin_fabs(detright))
		+ TDC_UNDERFLOW_SLACK;
	if (det > bound || -det > bound)
		return det;
	return tdc_orient2d_exact(a, b, c);
}

static inline double
tdc_incircle(const double *a, const double *b, const double *c, const double *d)
{
	double		adx = a[0] - d[0],
				ady = a[1] - d[1],
				bdx = b[0] - d[0],
				bdy = b[1] - d[1],
				cdx = c[0] - d[0],
				cdy = c[1] - d[1];
	double		bdxcdy = bdx * cdy,
				cdxbdy = cdx * bdy,
				cdxady = cdx * ady,
				adxcdy = adx * cdy,
				adxbdy = adx * bdy,
				bdxady = bdx * ady;
	double		alift = adx * adx + ady * ady,
				blift = bdx * bdx + bdy * bdy,
				clift = cdx * cdx + cdy * cdy;
	double		det = alift * (bdxcdy - cdxbdy)
		+ blift * (cdxady - adxcdy)
		+ clift * (adxbdy - bdxady);
	double		permanent = (__builtin_fabs(bdxcdy) + __builtin_fabs(cdxbdy)) * alift
		+ (__builtin_fabs(cdxady) + __builtin_fabs(adxcdy)) * blift
		+ (__builtin_fabs(adxbdy) + __builtin_fabs(bdxady)) * clift;
	double		bound = TDC_ICC_ERRBOUND * permanent + TDC_UNDERFLOW_SLACK;

	if (det > bound || -det > bound)
		return det;
	return tdc_incircle_exact(a, b, c, d);
}

/*
 * The lexicographic order of points, (x, y): the order of the tie rule
 * below, of the merge's axis 0 and of the Voronoi diagram's ties.
 */
static inline bool
tdc_lex_less(const double *p, const double *q)
{
	return p[0] < q[0] || (p[0] == q[0] && p[1] < q[1]);
}

/*
 * The sign of the in-circle test of four distinct, exactly cocircular sites,
 * by symbolic perturbation (predicates.c): true when d counts as inside the
 * circle through counter-clockwise a, b, c.
 */
extern bool tdc_incircle_tie(const double *a, const double *b,
							 const double *c, const double *d);

/*
 * Is d inside the circle through counter-clockwise a, b, c, exact zeros
 * decided by tdc_incircle_tie?  The four sites must be distinct; the callers
 * make sure of it.  Every in-circle decision that shapes a triangulation
 * (merge.c, cdt.c) goes through here, so that they agree on every tie.
 */
static inline __attribute__((always_inline)) bool
tdc_incircle_sos(const double *a, const double *b, const double *c,
				 const double *d)
{
	double		det = tdc_incircle(a, b, c, d);

	if (det != 0)
		return det > 0;
	return tdc_incircle_tie(a, b, c, d);
}

#endif							/* TDC_PREDICATES_H */
