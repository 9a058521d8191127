/*
 * predicates.c
 *		Exact fallback of the orientation and in-circle predicates.
 *
 * The inline filters in predicates.h settle almost every call in plain
 * double arithmetic; what reaches this file are determinants zero or so
 * close to zero that rounding could have flipped their sign.  Their sign is
 * computed exactly with floating-point expansion arithmetic (Priest 1991;
 * J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast
 * Robust Geometric Predicates", Discrete & Computational Geometry
 * 18:305-363, 1997), an independent implementation of the paper's
 * algorithms, cited by its names (Two-Sum, Two-Product, Fast-Expansion-Sum,
 * ...), from the core's one exact kernel, exact.h.  Route 1 evaluates the
 * determinant on coordinate differences when they are exact (Two-Diff
 * tells), with a plain-double shortcut for lattice data; route 2, rare,
 * folds the translation into the algebra on raw coordinates.  Both are exact
 * for every coordinate 0 or of magnitude in [1e-60, 1e60]: every value
 * formed is then a multiple of 2^-1008 and below 2^830, so nothing
 * underflows or overflows.  Zero components are eliminated as they appear,
 * working storage is fixed-size stack arrays, and nothing is allocated or
 * kept.  The symbolic tie-break of the in-circle test (tdc_incircle_tie) is
 * here too, so that the merge, the constrained insertion and the tiles
 * decide cocircular sites by one rule.
 *
 * The design note, with both routes, the proof of exactness and the
 * references, is docs/design/predicates.md.
 */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "exact.h"
#include "predicates.h"


/* ------------------------------------------------------------------------
 * Small-lattice shortcut
 * ------------------------------------------------------------------------
 */

/*
 * Given the largest magnitude m of a set of differences and a bit budget
 * nbits, return the power of two s such that m * s < 2^nbits <= 2 * m * s,
 * or 0 if m is zero, subnormal or so extreme that s would not be a normal
 * double.  The exponent is read from the bits: frexp/ldexp are library calls
 * and would cost more than the arithmetic they enable.
 */
static inline double
lattice_scale(double m, int nbits)
{
	uint64_t	bits;
	int			biased;
	int			sexp;
	double		s;

	memcpy(&bits, &m, sizeof(bits));
	biased = (int) ((bits >> 52) & 0x7ff);
	if (biased == 0 || biased == 0x7ff)
		return 0.0;
	/* m in [2^E, 2^(E+1)) with E = biased - 1023; s = 2^(nbits - 1 - E) */
	sexp = 1023 + (nbits - 1 - (biased - 1023));
	if (sexp < 1 || sexp > 2046)
		return 0.0;
	bits = (uint64_t) sexp << 52;
	memcpy(&s, &bits, sizeof(s));
	return s;
}

/*
 * Scale the n values v[] by s into w[] and report whether all of them became
 * integers.  Multiplying by a power of two is exact unless the result leaves
 * the normal range; a nonzero integer result is normal, and a nonzero input
 * that underflowed to zero is rejected explicitly, so an accepted scaling is
 * exact for any finite input.  Every scaled magnitude is below 2^nbits <=
 * 2^26 when m really was the largest magnitude.
 */
static inline int
scale_to_integers(const double *v, double *w, int n, double s)
{
	int			i;

	for (i = 0; i < n; i++)
	{
		double		x = v[i] * s;

		/* the range test also keeps NaN away from the conversion */
		if (!(__builtin_fabs(x) < 0x1p62))
			return 0;
		if ((double) (int64_t) x != x || (x == 0.0 && v[i] != 0.0))
			return 0;
		w[i] = x;
	}
	return 1;
}

static inline double
max_abs(const double *v, int n)
{
	double		m = 0.0;
	int			i;

	for (i = 0; i < n; i++)
		if (__builtin_fabs(v[i]) > m)
			m = __builtin_fabs(v[i]);
	return m;
}

static inline double
sign_of(double x)
{
	return (x > 0.0) ? 1.0 : (x < 0.0) ? -1.0 : 0.0;
}

/* ------------------------------------------------------------------------
 * Determinant building blocks
 * ------------------------------------------------------------------------
 */

/* h = p*s - q*t exactly, up to 4 components. */
static int
product_diff(double p, double s, double q, double t, double *h)
{
	double		x1,
				y1,
				x2,
				y2;
	double		e[2],
				f[2];
	int			elen,
				flen;

	two_prod(p, s, &x1, &y1);
	two_prod(q, t, &x2, &y2);
	elen = pack2(x1, y1, e);
	flen = pack2(-x2, -y2, f);
	return expansion_sum(elen, e, flen, f, h);
}

/* h = e1 + e2 + e3 for three expansions of up to 4 components: up to 12. */
static int
sum3(int len1, const double *e1, int len2, const double *e2,
	 int len3, const double *e3, double *h)
{
	double		tmp[8];
	int			n;

	n = expansion_sum(len1, e1, len2, e2, tmp);
	return expansion_sum(n, tmp, len3, e3, h);
}

/*
 * h = (u^2 + v^2) * e, computed as u*(u*e) + v*(v*e), or its negation when
 * negative is set (folded into the second scaling, which is free).  With
 * elen <= 12 the result has at most 4*12 + 4*12 = 96 components.
 */
static int
lift_scale(int elen, const double *e, double u, double v, int negative,
		   double *h)
{
	double		t1[24],
				t2[48],
				t3[24],
				t4[48];
	int			n1,
				n2,
				n3,
				n4;

	n1 = scale_expansion(elen, e, u, t1);
	n2 = scale_expansion(n1, t1, negative ? -u : u, t2);
	n3 = scale_expansion(elen, e, v, t3);
	n4 = scale_expansion(n3, t3, negative ? -v : v, t4);
	return expansion_sum(n2, t2, n4, t4, h);
}

/*
 * h = (u^2 + v^2) * e for e of up to 4 components (route 1), computed by
 * forming the lift exactly (up to 4 components) and scaling e by each of
 * its components: 16 Two-Products instead of the 24 of lift_scale, which
 * measured about 13% faster on the whole predicate.  (On the raw route,
 * where lifts of full-precision coordinates rarely compress, lift_scale is
 * the faster of the two.)  At most 4 * 8 = 32 components.
 */
static int
lift_product(int elen, const double *e, double u, double v, double *h)
{
	double		x,
				y,
				uu[2],
				vv[2],
				lift[4];
	double		t[4][8],
				s1[16],
				s2[16];
	int			uulen,
				vvlen,
				liftlen,
				tlen[4] = {0, 0, 0, 0},
				s1len,
				s2len,
				i;

	two_prod(u, u, &x, &y);
	uulen = pack2(x, y, uu);
	two_prod(v, v, &x, &y);
	vvlen = pack2(x, y, vv);
	liftlen = expansion_sum(uulen, uu, vvlen, vv, lift);
	for (i = 0; i < liftlen; i++)
		tlen[i] = scale_expansion(elen, e, lift[i], t[i]);
	s1len = expansion_sum(tlen[0], t[0], tlen[1], t[1], s1);
	s2len = expansion_sum(tlen[2], t[2], tlen[3], t[3], s2);
	return expansion_sum(s1len, s1, s2len, s2, h);
}

/*
 * Route 1 of incircle, on exact differences: the 3x3 determinant
 *	alift * (bdx cdy - cdx bdy) + blift * (cdx ady - adx cdy)
 *		+ clift * (adx bdy - bdx ady).
 * Minors have <= 4 components, each lifted term <= 32, the total <= 96.
 */
static double
incircle_from_differences(double adx, double ady, double bdx, double bdy,
						  double cdx, double cdy)
{
	double		bc[4],
				ca[4],
				ab[4];
	double		aterm[32],
				bterm[32],
				cterm[32];
	double		abterm[64],
				det[96];
	int			bclen,
				calen,
				ablen,
				alen,
				blen,
				clen,
				ablen2,
				detlen;

	bclen = product_diff(bdx, cdy, cdx, bdy, bc);
	calen = product_diff(cdx, ady, adx, cdy, ca);
	ablen = product_diff(adx, bdy, bdx, ady, ab);

	alen = lift_product(bclen, bc, adx, ady, aterm);
	blen = lift_product(calen, ca, bdx, bdy, bterm);
	clen = lift_product(ablen, ab, cdx, cdy, cterm);

	ablen2 = expansion_sum(alen, aterm, blen, bterm, abterm);
	detlen = expansion_sum(ablen2, abterm, clen, cterm, det);
	return expansion_sign(detlen, det);
}

/*
 * Lattice shortcut of route 1: v[] holds adx, ady, bdx, bdy, cdx, cdy scaled
 * by a power of two to integers of magnitude below 2^26.  Then every square
 * and product of two of them is an integer below 2^52, so the lifts and the
 * 2x2 minors (sums or differences of two such) are integers below 2^53 and
 * are computed exactly in plain doubles.  Only the three products lift *
 * minor need Two-Product, and the six resulting components are summed as
 * expansions.  This handles integer grids and coordinates snapped to a
 * millimetre grid far from the origin (whose differences are multiples of
 * the coordinates' ulp) several times faster than the general path.
 */
static double
incircle_small_integers(const double *v)
{
	double		alift = v[0] * v[0] + v[1] * v[1],
				blift = v[2] * v[2] + v[3] * v[3],
				clift = v[4] * v[4] + v[5] * v[5];
	double		bc = v[2] * v[5] - v[4] * v[3],
				ca = v[4] * v[1] - v[0] * v[5],
				ab = v[0] * v[3] - v[2] * v[1];
	double		x,
				y;
	double		e[2],
				f[2],
				g[2],
				ef[4] = {0},	/* gcc 14 cannot see that expansion_sum writes it */
				det[6];
	int			elen,
				flen,
				glen,
				eflen,
				detlen;

	two_prod(alift, bc, &x, &y);
	elen = pack2(x, y, e);
	two_prod(blift, ca, &x, &y);
	flen = pack2(x, y, f);
	two_prod(clift, ab, &x, &y);
	glen = pack2(x, y, g);
	eflen = expansion_sum(elen, e, flen, f, ef);
	detlen = expansion_sum(eflen, ef, glen, g, det);
	return expansion_sign(detlen, det);
}

/*
 * Route 2 of incircle, on raw coordinates.  With l(p) = px^2 + py^2 and the
 * 4x4 determinant |x y l 1| of a, b, c, d (equal to the translated 3x3 one:
 * subtracting row d from the others and then 2*dx times column x and 2*dy
 * times column y from column l leaves it unchanged), expansion along the
 * lift column gives
 *	l(a) O(b,c,d) - l(b) O(a,c,d) + l(c) O(a,b,d) - l(d) O(a,b,c),
 * where O(p,q,r) = pq + qr + rp and pq = px qy - qx py.  Each O has <= 12
 * components, each lifted term <= 96, the total <= 384.
 */
static double
incircle_from_raw(const double *a, const double *b, const double *c,
				  const double *d)
{
	double		ab[4],
				bc[4],
				cd[4],
				da[4],
				ac[4],
				bd[4],
				ca[4],
				db[4];
	int			ablen,
				bclen,
				cdlen,
				dalen,
				aclen,
				bdlen;
	double		obcd[12],
				oacd[12],
				oabd[12],
				oabc[12];
	int			nbcd,
				nacd,
				nabd,
				nabc;
	double		aterm[96],
				bterm[96],
				cterm[96],
				dterm[96];
	int			alen,
				blen,
				clen,
				dlen;
	double		abterm[192],
				cdterm[192] = {0},	/* as ef above; the exact route only */
				det[384];
	int			abtermlen,
				cdtermlen,
				detlen;
	int			i;

	ablen = product_diff(a[0], b[1], b[0], a[1], ab);
	bclen = product_diff(b[0], c[1], c[0], b[1], bc);
	cdlen = product_diff(c[0], d[1], d[0], c[1], cd);
	dalen = product_diff(d[0], a[1], a[0], d[1], da);
	aclen = product_diff(a[0], c[1], c[0], a[1], ac);
	bdlen = product_diff(b[0], d[1], d[0], b[1], bd);
	for (i = 0; i < aclen; i++)
		ca[i] = -ac[i];
	for (i = 0; i < bdlen; i++)
		db[i] = -bd[i];

	nbcd = sum3(bclen, bc, cdlen, cd, bdlen, db, obcd);
	nacd = sum3(aclen, ac, cdlen, cd, dalen, da, oacd);
	nabd = sum3(ablen, ab, bdlen, bd, dalen, da, oabd);
	nabc = sum3(ablen, ab, bclen, bc, aclen, ca, oabc);

	alen = lift_scale(nbcd, obcd, a[0], a[1], 0, aterm);
	blen = lift_scale(nacd, oacd, b[0], b[1], 1, bterm);
	clen = lift_scale(nabd, oabd, c[0], c[1], 0, cterm);
	dlen = lift_scale(nabc, oabc, d[0], d[1], 1, dterm);

	abtermlen = expansion_sum(alen, aterm, blen, bterm, abterm);
	cdtermlen = expansion_sum(clen, cterm, dlen, dterm, cdterm);
	detlen = expansion_sum(abtermlen, abterm, cdtermlen, cdterm, det);
	return expansion_sign(detlen, det);
}

/* ------------------------------------------------------------------------
 * Entry points
 * ------------------------------------------------------------------------
 */

/*
 * Exact sign of (ax-cx)(by-cy) - (ay-cy)(bx-cx): route 1 or 2 of
 * docs/design/predicates.md, in Shewchuk's (1997) expansion arithmetic.
 */
double
tdc_orient2d_exact(const double *a, const double *b, const double *c)
{
	double		acx,
				acy,
				bcx,
				bcy;
	double		acxtail,
				acytail,
				bcxtail,
				bcytail;
	double		ab[4],
				bc[4],
				ca[4],
				det[12];
	int			ablen,
				bclen,
				calen,
				detlen;

	two_diff(a[0], c[0], &acx, &acxtail);
	two_diff(a[1], c[1], &acy, &acytail);
	two_diff(b[0], c[0], &bcx, &bcxtail);
	two_diff(b[1], c[1], &bcy, &bcytail);

	if (acxtail == 0.0 && acytail == 0.0 && bcxtail == 0.0 && bcytail == 0.0)
	{
		double		v[4] = {acx, bcy, acy, bcx};
		double		w[4];
		double		s = lattice_scale(max_abs(v, 4), 26);

		/*
		 * Lattice shortcut: integers below 2^26 have products below 2^52,
		 * whose difference is below 2^53 and therefore exact.
		 */
		if (s != 0.0 && scale_to_integers(v, w, 4, s))
			return sign_of(w[0] * w[1] - w[2] * w[3]);

		/* Route 1: exact differences, one 2x2 minor of up to 4 components. */
		detlen = product_diff(acx, bcy, acy, bcx, det);
		return expansion_sign(detlen, det);
	}

	/* Route 2: raw coordinates, ab + bc + ca (see incircle_from_raw). */
	ablen = product_diff(a[0], b[1], b[0], a[1], ab);
	bclen = product_diff(b[0], c[1], c[0], b[1], bc);
	calen = product_diff(c[0], a[1], a[0], c[1], ca);
	detlen = sum3(ablen, ab, bclen, bc, calen, ca, det);
	return expansion_sign(detlen, det);
}

/*
 * Exact sign of the in-circle determinant of predicates.h: the lattice
 * shortcut, route 1 or route 2 of docs/design/predicates.md, in Shewchuk's
 * (1997) expansion arithmetic.
 */
double
tdc_incircle_exact(const double *a, const double *b, const double *c,
				   const double *d)
{
	double		adx,
				ady,
				bdx,
				bdy,
				cdx,
				cdy;
	double		adxtail,
				adytail,
				bdxtail,
				bdytail,
				cdxtail,
				cdytail;

	two_diff(a[0], d[0], &adx, &adxtail);
	two_diff(a[1], d[1], &ady, &adytail);
	two_diff(b[0], d[0], &bdx, &bdxtail);
	two_diff(b[1], d[1], &bdy, &bdytail);
	two_diff(c[0], d[0], &cdx, &cdxtail);
	two_diff(c[1], d[1], &cdy, &cdytail);

	if (adxtail == 0.0 && adytail == 0.0 && bdxtail == 0.0 &&
		bdytail == 0.0 && cdxtail == 0.0 && cdytail == 0.0)
	{
		double		v[6] = {adx, ady, bdx, bdy, cdx, cdy};
		double		w[6];
		double		m = max_abs(v, 6);
		double		s = lattice_scale(m, 12);

		/*
		 * Lattice shortcut, small: with integers below 2^12 the lifts and
		 * minors are below 2^25, each lifted term below 2^50 and their sum
		 * below 3 * 2^50, so plain double evaluation is exact.
		 */
		if (s != 0.0 && scale_to_integers(v, w, 6, s))
			return sign_of((w[0] * w[0] + w[1] * w[1]) * (w[2] * w[5] - w[4] * w[3])
						   + (w[2] * w[2] + w[3] * w[3]) * (w[4] * w[1] - w[0] * w[5])
						   + (w[4] * w[4] + w[5] * w[5]) * (w[0] * w[3] - w[2] * w[1]));

		/* Lattice shortcut, large: integers below 2^26. */
		s = lattice_scale(m, 26);
		if (s != 0.0 && scale_to_integers(v, w, 6, s))
			return incircle_small_integers(w);
		return incircle_from_differences(adx, ady, bdx, bdy, cdx, cdy);
	}

	return incircle_from_raw(a, b, c, d);
}

/* ------------------------------------------------------------------------
 * Squared distances (the tolerance pass)
 * ------------------------------------------------------------------------
 */

/*
 * h = (a - b)^2 exactly, up to 6 components: with a - b = d + dt from
 * Two-Diff, the square is d^2 + (2d) dt + dt^2, each term a Two-Product.
 */
static int
square_of_difference(double a, double b, double *h)
{
	double		d,
				dt,
				x,
				y,
				e[2],
				f[2],
				g[4];
	int			elen,
				flen,
				glen;

	two_diff(a, b, &d, &dt);
	two_prod(d, d, &x, &y);
	elen = pack2(x, y, e);
	if (dt == 0.0)
	{
		memcpy(h, e, elen * sizeof(double));
		return elen;
	}
	two_prod(2.0 * d, dt, &x, &y);
	flen = pack2(x, y, f);
	glen = expansion_sum(elen, e, flen, f, g);
	two_prod(dt, dt, &x, &y);
	elen = pack2(x, y, e);
	return expansion_sum(glen, g, elen, e, h);
}

/*
 * Why this is exact for coordinates that are 0 or of magnitude in
 * [2^-252, 2^202] (the argument of docs/design/predicates.md, on other
 * bounds): every
 * such coordinate is an integer multiple of 2^-304, and so are the
 * differences, their Two-Diff tails and the Veltkamp halves (|values| below
 * 2^231).  Every product and Two-Product error term is then a multiple of
 * 2^-608, a normal number when nonzero, and below 2^410: no underflow, no
 * overflow, so the expansion arithmetic is exact.
 */
int
tdc_sqdist_cmp_exact(const double *a, const double *b, const double *c,
					 const double *d)
{
	double		sx[6],
				sy[6],
				tx[6],
				ty[6],
				s[12],
				t[12],
				diff[24];
	int			sxlen,
				sylen,
				txlen,
				tylen,
				slen,
				tlen,
				dlen;

	sxlen = square_of_difference(a[0], b[0], sx);
	sylen = square_of_difference(a[1], b[1], sy);
	txlen = square_of_difference(c[0], d[0], tx);
	tylen = square_of_difference(c[1], d[1], ty);
	slen = expansion_sum(sxlen, sx, sylen, sy, s);
	tlen = expansion_sum(txlen, tx, tylen, ty, t);
	for (int i = 0; i < tlen; i++)
		t[i] = -t[i];
	dlen = expansion_sum(slen, s, tlen, t, diff);
	return (int) expansion_sign(dlen, diff);
}

/* ------------------------------------------------------------------------
 * Symbolic tie-break of the in-circle test
 * ------------------------------------------------------------------------
 */

/*
 * Exact in-circle of four distinct, exactly cocircular sites, decided as if
 * every site p were lifted to the paraboloid at |p|^2 + eps_p, with eps
 * infinitesimal and larger for lexicographically smaller sites (simulation
 * of simplicity, Edelsbrunner & Muecke 1990, applied to the lifting
 * coordinate only).  Perturbing the lift of a, b, c, d by eps_a..eps_d adds
 *		eps_a O(b,c,d) - eps_b O(a,c,d) + eps_c O(a,b,d) - eps_d O(a,b,c)
 * to the in-circle determinant (expand along the lift column), where O is
 * orient2d.  The term of the lexicographically smallest site dominates; its
 * orientation is nonzero because no three distinct points of a circle are
 * collinear.  The perturbed lift is in general position, so its lower hull,
 * and hence the triangulation, depends on the site set alone: not on the
 * input order, the thread count, the subdivision or the tiling.
 */
bool
tdc_incircle_tie(const double *pa, const double *pb, const double *pc,
				 const double *pd)
{
	const double *lowest = pa;
	double		s;

	if (tdc_lex_less(pb, lowest))
		lowest = pb;
	if (tdc_lex_less(pc, lowest))
		lowest = pc;
	if (tdc_lex_less(pd, lowest))
		lowest = pd;

	if (lowest == pa)
		s = tdc_orient2d(pb, pc, pd);
	else if (lowest == pb)
		s = -tdc_orient2d(pa, pc, pd);
	else if (lowest == pc)
		s = tdc_orient2d(pa, pb, pd);
	else
		s = -tdc_orient2d(pa, pb, pc);
	return s > 0;
}
