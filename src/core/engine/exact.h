/*
 * exact.h
 *		The core's one exact-arithmetic kernel: error-free transformations,
 *		double-double values and floating-point expansions.
 *
 * Everything that must be exact, or rounded exactly once, is built from the
 * functions of this file and no others: the exact predicates (predicates.c,
 * used by the leaves, the merge, the constrained insertion and the tiles),
 * the circumcenters and the corner tests of the Voronoi diagram.  "The same
 * triangles whatever the thread count" and "the same cell whoever computes
 * it" rest on every caller doing the same arithmetic, so it is written once.
 *
 * The algorithms are those published by J. R. Shewchuk, "Adaptive Precision
 * Floating-Point Arithmetic and Fast Robust Geometric Predicates", Discrete &
 * Computational Geometry 18:305-363, 1997 (after Dekker 1971, Knuth, Moller,
 * Veltkamp and Priest 1991), written independently and cited by the names
 * the paper gives them (Fast-Two-Sum, Two-Sum, Two-Diff, Split,
 * Two-Product, Grow-Expansion, Fast-Expansion-Sum, Scale-Expansion).
 *
 * An expansion is an array of doubles, ordered by increasing magnitude and
 * pairwise non-overlapping, whose exact (unrounded) sum is the value it
 * represents; its largest component carries the sign of the whole.  Every
 * routine here drops zero components as it goes, and an expansion of length
 * 0 represents zero.  A double-double (dd) is the unevaluated sum hi + lo
 * with |lo| at most half an ulp of hi.
 *
 * Requirements on the floating-point environment: IEEE double with round to
 * nearest, ties to even (Fast-Expansion-Sum needs it), no extended precision
 * (FLT_EVAL_METHOD == 0, true with SSE2 on x86-64), and no contraction of
 * a*b+c into a fused multiply-add, which would break Two-Product and Two-Sum.
 * The build passes -ffp-contract=off; -ffast-math is rejected below.  We do
 * not use fma() on purpose: baseline x86-64 has no hardware FMA and the
 * library fallback is slow.  Exactness in the presence of a bounded exponent
 * range (no underflow, no overflow) is argued where each caller bounds its
 * inputs (predicates.c, voronoi_geom.c).
 *
 * All functions are static inline: the hot callers (the predicates' exact
 * path, the circumcenters) need them inlined, and there is one definition.
 * They never allocate and keep no state.
 */
#ifndef TDC_EXACT_H
#define TDC_EXACT_H

#include <float.h>
#include <string.h>

#if defined(__FAST_MATH__)
#error "the exact kernel must not be compiled with -ffast-math: exactness depends on IEEE semantics"
#endif
#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "the exact kernel needs FLT_EVAL_METHOD == 0 (no extended precision intermediates)"
#endif

/*
 * Belt and braces for builds that forget -ffp-contract=off: clang honours
 * the standard pragma (GCC ignores it, but contracts only in GNU mode, and
 * the core is built with -std=c11).
 */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* ------------------------------------------------------------------------
 * Error-free transformations
 * ------------------------------------------------------------------------
 */

/*
 * 2^27 + 1: Veltkamp splitting of a 53-bit significand into two 26-bit
 * halves.
 */
#define TDC_SPLITTER	134217729.0

/*
 * Fast-Two-Sum (after Dekker): x + y == a + b exactly with
 * x = fl(a + b), provided |a| >= |b|.
 */
static inline void
fast_two_sum(double a, double b, double *x, double *y)
{
	double		s = a + b;
	double		bvirt = s - a;

	*x = s;
	*y = b - bvirt;
}

/*
 * Two-Sum (after Knuth and Moller): same as above with no precondition on
 * the magnitudes, at the price of three extra operations.
 */
static inline void
two_sum(double a, double b, double *x, double *y)
{
	double		s = a + b;
	double		bvirt = s - a;
	double		avirt = s - bvirt;
	double		bround = b - bvirt;
	double		around = a - avirt;

	*x = s;
	*y = around + bround;
}

/* Two-Diff: Two-Sum of a and -b, written out so that no negation is needed. */
static inline void
two_diff(double a, double b, double *x, double *y)
{
	double		s = a - b;
	double		bvirt = a - s;
	double		avirt = s + bvirt;
	double		bround = bvirt - b;
	double		around = a - avirt;

	*x = s;
	*y = around + bround;
}

/*
 * Split (after Veltkamp): a == hi + lo where hi and lo each fit in 26
 * bits (one of them borrowing the sign bit), so that products of halves are
 * exact in double precision.  Exact unless |a| > 2^996 (the splitter would
 * overflow), far beyond anything the core multiplies.  lo is +0, never -0,
 * when a splits evenly.
 */
static inline void
split(double a, double *hi, double *lo)
{
	double		c = TDC_SPLITTER * a;
	double		abig = c - a;
	double		h = c - abig;

	*hi = h;
	*lo = a - h;
}

/*
 * Two-Product (after Dekker): x + y == a * b exactly with x = fl(a*b).
 * b arrives already split because Scale-Expansion multiplies many
 * components by the same b.
 */
static inline void
two_prod_presplit(double a, double b, double bhi, double blo,
				  double *x, double *y)
{
	double		p = a * b;
	double		ahi,
				alo;
	double		err1,
				err2,
				err3;

	split(a, &ahi, &alo);
	err1 = p - ahi * bhi;
	err2 = err1 - alo * bhi;
	err3 = err2 - ahi * blo;
	*x = p;
	*y = alo * blo - err3;
}

static inline void
two_prod(double a, double b, double *x, double *y)
{
	double		bhi,
				blo;

	split(b, &bhi, &blo);
	two_prod_presplit(a, b, bhi, blo, x, y);
}

/* ------------------------------------------------------------------------
 * Double-double values (the circumcenters' careful path)
 * ------------------------------------------------------------------------
 */
typedef struct dd
{
	double		hi,
				lo;
} dd;

static inline dd
dd_two_sum(double a, double b)
{
	dd			r;

	two_sum(a, b, &r.hi, &r.lo);
	return r;
}

static inline dd
dd_fast_two_sum(double a, double b)
{
	dd			r;

	fast_two_sum(a, b, &r.hi, &r.lo);
	return r;
}

/*
 * The exact product as a double-double.  An exact product's error term is
 * zero, and Two-Product then gives -0 when the low halves' product is -0;
 * "+ 0.0" makes every zero error +0, as the circumcenters have always seen
 * it (a zero's sign can reach an output coordinate that is exactly 0).
 */
static inline dd
dd_two_prod(double a, double b)
{
	dd			r;

	two_prod(a, b, &r.hi, &r.lo);
	r.lo += 0.0;
	return r;
}

static inline dd
dd_add(dd a, dd b)
{
	dd			s = dd_two_sum(a.hi, b.hi);
	dd			t = dd_two_sum(a.lo, b.lo);

	s.lo += t.hi;
	s = dd_fast_two_sum(s.hi, s.lo);
	s.lo += t.lo;
	return dd_fast_two_sum(s.hi, s.lo);
}

static inline dd
dd_neg(dd a)
{
	return (dd) {-a.hi, -a.lo};
}

static inline dd
dd_mul(dd a, dd b)
{
	dd			p = dd_two_prod(a.hi, b.hi);

	p.lo += a.hi * b.lo + a.lo * b.hi;
	return dd_fast_two_sum(p.hi, p.lo);
}

static inline dd
dd_div(dd a, dd b)
{
	double		q1 = a.hi / b.hi;
	dd			r = dd_add(a, dd_neg(dd_mul((dd) {q1, 0}, b)));
	double		q2 = r.hi / b.hi;

	r = dd_add(r, dd_neg(dd_mul((dd) {q2, 0}, b)));
	return dd_add(dd_fast_two_sum(q1, q2), (dd) {r.hi / b.hi, 0});
}

/* ------------------------------------------------------------------------
 * Expansion arithmetic (all with zero elimination; length 0 means zero)
 * ------------------------------------------------------------------------
 */

/*
 * Store the two-component expansion hi + lo (lo the smaller, as produced by
 * the transformations above) without its zero components.  Returns the
 * length, 0..2.
 */
static inline int
pack2(double hi, double lo, double *h)
{
	int			n = 0;

	if (lo != 0.0)
		h[n++] = lo;
	if (hi != 0.0)
		h[n++] = hi;
	return n;
}

/* A double-double as an expansion of at most 2 parts, increasing. */
static inline int
dd_exp(dd x, double *e)
{
	return pack2(x.hi, x.lo, e);
}

/*
 * Expansion sum by merging (Fast-Expansion-Sum): merge the
 * components of e and f by increasing magnitude, then run them through one
 * Fast-Two-Sum and a chain of Two-Sums, emitting each nonzero error term.  If
 * e and f are strongly non-overlapping (as all our expansions are), so is h,
 * under round-to-even.  h must have room for elen + flen components and must
 * not alias e or f.
 */
static inline int
expansion_sum(int elen, const double *e, int flen, const double *f, double *h)
{
	int			i = 0,
				j = 0,
				hlen = 0;
	double		q,
				g,
				hh;

	if (elen == 0 || flen == 0)
	{
		const double *src = (elen == 0) ? f : e;
		int			n = (elen == 0) ? flen : elen;

		for (i = 0; i < n; i++)
			h[i] = src[i];
		return n;
	}

	/* The two smallest components start the chain with a Fast-Two-Sum. */
	if (__builtin_fabs(e[0]) <= __builtin_fabs(f[0]))
		q = e[i++];
	else
		q = f[j++];
	if (j >= flen || (i < elen && __builtin_fabs(e[i]) <= __builtin_fabs(f[j])))
		g = e[i++];
	else
		g = f[j++];
	fast_two_sum(g, q, &q, &hh);
	if (hh != 0.0)
		h[hlen++] = hh;

	while (i < elen || j < flen)
	{
		if (j >= flen || (i < elen && __builtin_fabs(e[i]) <= __builtin_fabs(f[j])))
			g = e[i++];
		else
			g = f[j++];
		two_sum(q, g, &q, &hh);
		if (hh != 0.0)
			h[hlen++] = hh;
	}
	if (q != 0.0)
		h[hlen++] = q;
	return hlen;
}

/*
 * Scale-Expansion: h = b * e exactly.  Each component product
 * is split into two by Two-Product and folded into the running sum with a
 * Two-Sum and a Fast-Two-Sum.  h needs room for 2 * elen components and
 * must not alias e.
 */
static inline int
scale_expansion(int elen, const double *e, double b, double *h)
{
	double		bhi,
				blo,
				q,
				sum,
				hh,
				p1,
				p0;
	int			i,
				hlen = 0;

	if (elen == 0 || b == 0.0)
		return 0;

	split(b, &bhi, &blo);
	two_prod_presplit(e[0], b, bhi, blo, &q, &hh);
	if (hh != 0.0)
		h[hlen++] = hh;
	for (i = 1; i < elen; i++)
	{
		two_prod_presplit(e[i], b, bhi, blo, &p1, &p0);
		two_sum(q, p0, &sum, &hh);
		if (hh != 0.0)
			h[hlen++] = hh;
		fast_two_sum(p1, sum, &q, &hh);
		if (hh != 0.0)
			h[hlen++] = hh;
	}
	if (q != 0.0)
		h[hlen++] = q;
	return hlen;
}

/* Sign of an expansion: that of its largest (last) component. */
static inline double
expansion_sign(int elen, const double *e)
{
	if (elen == 0)
		return 0.0;
	return (e[elen - 1] > 0.0) ? 1.0 : -1.0;
}

/*
 * Grow-Expansion: h = e + b; h has room for elen + 1 and may not alias e;
 * returns the length of h.
 */
static inline int
grow_expansion(int elen, const double *e, double b, double *h)
{
	int			n = 0;
	double		q = b;

	for (int i = 0; i < elen; i++)
	{
		dd			s = dd_two_sum(q, e[i]);

		if (s.lo != 0)
			h[n++] = s.lo;
		q = s.hi;
	}
	if (q != 0)
		h[n++] = q;
	return n;
}

/*
 * The longest expansion expansion_add_product builds (its scratch): the
 * circumcenters' numerators 2 a D + N need at most this many parts.
 */
#define TDC_EXP_PRODUCT_MAX	160

/*
 * e += sign * (f * g), in place, one Grow-Expansion per half of each exact
 * two-product: kept simple, every sum grows one component at a time
 * (quadratic, on at most 128 components; only the circumcenters' rare
 * exact path uses it); e has
 * room for elen + 2 * flen * glen, at most TDC_EXP_PRODUCT_MAX.  sign is
 * +1 or -1.
 */
static inline int
expansion_add_product(int elen, double *e, int flen, const double *f, int glen,
					  const double *g, double sign)
{
	double		t[TDC_EXP_PRODUCT_MAX + 1];

	for (int i = 0; i < flen; i++)
		for (int j = 0; j < glen; j++)
		{
			dd			p = dd_two_prod(f[i], g[j]);

			elen = grow_expansion(elen, e, sign * p.lo, t);
			memcpy(e, t, elen * sizeof(double));
			elen = grow_expansion(elen, e, sign * p.hi, t);
			memcpy(e, t, elen * sizeof(double));
		}
	return elen;
}

/* The expansion rounded to double-double: summed from its smallest part. */
static inline dd
expansion_to_dd(int elen, const double *e)
{
	dd			s = {0, 0};

	for (int i = 0; i < elen; i++)
		s = dd_add(s, (dd) {e[i], 0});
	return s;
}

#endif							/* TDC_EXACT_H */
