/*
 * test_predicates.c
 *		Exactness tests of tdc_orient2d / tdc_incircle (the filtered inline
 *		versions) and of their exact fallbacks, against rational arithmetic.
 *
 * Every double is a dyadic rational, so GMP's mpq_set_d converts it exactly
 * and the determinants computed with mpq_t are the true values.  Each case
 * checks that the exact function returns exactly sign(det) as -1.0, 0.0 or
 * +1.0 and that the filtered function returns a value of that same sign.
 *
 * The inputs are adversarial on purpose: exactly collinear and cocircular
 * configurations (integer lattices, lattice points on circles of radius 5,
 * 25, 65 and 1105, scaled by powers of two and translated by large offsets),
 * near-degenerate ones (Shewchuk's ulp grid around (0.5, 0.5), points rounded
 * onto lines and circles, sites one ulp apart), random doubles with
 * magnitudes spread over [1e-60, 1e60], the extreme values themselves and
 * zeros, projected coordinates around 5e6 with sub-millimetre offsets, and
 * longitude/latitude data.  A deterministic PRNG (splitmix64) makes every
 * run identical.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <gmp.h>

#include "harness.h"
#include "splitmix.h"
#include "engine/predicates.h"

/* ------------------------------------------------------------------------
 * Deterministic PRNG and random doubles
 * ------------------------------------------------------------------------
 */

static uint64_t rng_state;

static uint64_t
rng_next(void)
{
	return tdc_splitmix64(&rng_state);
}

/* uniform integer in [lo, hi] */
static long
rng_int(long lo, long hi)
{
	return lo + (long) (rng_next() % (uint64_t) (hi - lo + 1));
}

/* uniform double in [0, 1) with 53 random bits */
static double
rng_unit(void)
{
	return (double) (rng_next() >> 11) * 0x1p-53;
}

/* uniform double in [lo, hi) */
static double
rng_range(double lo, double hi)
{
	return lo + (hi - lo) * rng_unit();
}

/*
 * Random double with a full random significand, a random sign and a binary
 * exponent uniform in [-199, 198], i.e. magnitude in [2^-199, 2^199), which
 * lies inside [1e-60, 1e60].
 */
static double
rng_wide(void)
{
	uint64_t	m = (rng_next() >> 11) | (UINT64_C(1) << 52);
	double		x = ldexp((double) m, (int) rng_int(-199, 198) - 52);

	return (rng_next() & 1) ? -x : x;
}

/* x moved by k ulps (k may be negative) */
static double
ulps(double x, int k)
{
	while (k > 0)
	{
		x = nextafter(x, INFINITY);
		k--;
	}
	while (k < 0)
	{
		x = nextafter(x, -INFINITY);
		k++;
	}
	return x;
}

/* ------------------------------------------------------------------------
 * Rational reference determinants
 * ------------------------------------------------------------------------
 */

static int
ref_orient2d(const double *a, const double *b, const double *c)
{
	mpq_t		acx,
				acy,
				bcx,
				bcy,
				t1,
				t2;
	int			s;

	mpq_inits(acx, acy, bcx, bcy, t1, t2, NULL);
	mpq_set_d(acx, a[0]);
	mpq_set_d(t1, c[0]);
	mpq_sub(acx, acx, t1);
	mpq_set_d(bcx, b[0]);
	mpq_sub(bcx, bcx, t1);
	mpq_set_d(acy, a[1]);
	mpq_set_d(t1, c[1]);
	mpq_sub(acy, acy, t1);
	mpq_set_d(bcy, b[1]);
	mpq_sub(bcy, bcy, t1);
	mpq_mul(t1, acx, bcy);
	mpq_mul(t2, acy, bcx);
	mpq_sub(t1, t1, t2);
	s = mpq_sgn(t1);
	mpq_clears(acx, acy, bcx, bcy, t1, t2, NULL);
	return s;
}

static int
ref_incircle(const double *a, const double *b, const double *c, const double *d)
{
	const double *p[3] = {a, b, c};
	mpq_t		dx[3],
				dy[3],
				lift[3],
				t,
				u,
				m,
				det;
	int			i,
				s;

	mpq_inits(t, u, m, det, NULL);
	for (i = 0; i < 3; i++)
	{
		mpq_inits(dx[i], dy[i], lift[i], NULL);
		mpq_set_d(dx[i], p[i][0]);
		mpq_set_d(t, d[0]);
		mpq_sub(dx[i], dx[i], t);
		mpq_set_d(dy[i], p[i][1]);
		mpq_set_d(t, d[1]);
		mpq_sub(dy[i], dy[i], t);
		mpq_mul(lift[i], dx[i], dx[i]);
		mpq_mul(t, dy[i], dy[i]);
		mpq_add(lift[i], lift[i], t);
	}
	mpq_set_ui(det, 0, 1);
	for (i = 0; i < 3; i++)
	{
		int			j = (i + 1) % 3,
					k = (i + 2) % 3;

		/* lift[i] * (dx[j] dy[k] - dx[k] dy[j]): cyclic cofactor expansion */
		mpq_mul(t, dx[j], dy[k]);
		mpq_mul(u, dx[k], dy[j]);
		mpq_sub(m, t, u);
		mpq_mul(m, m, lift[i]);
		mpq_add(det, det, m);
	}
	s = mpq_sgn(det);
	for (i = 0; i < 3; i++)
		mpq_clears(dx[i], dy[i], lift[i], NULL);
	mpq_clears(t, u, m, det, NULL);
	return s;
}

/* ------------------------------------------------------------------------
 * Case checkers
 * ------------------------------------------------------------------------
 */

static long n_orient,
			n_incircle,
			n_orient_zero,
			n_incircle_zero;

static int
sign_of(double x)
{
	return (x > 0.0) - (x < 0.0);
}

/* Checks one orient2d case; returns the reference sign. */
static int
check_orient(const double *a, const double *b, const double *c, const char *what)
{
	int			ref = ref_orient2d(a, b, c);
	double		ex = tdc_orient2d_exact(a, b, c);
	double		fl = tdc_orient2d(a, b, c);

	n_orient++;
	if (ref == 0)
		n_orient_zero++;
	CHECK(ex == (double) ref,
		  "%s: orient2d_exact(%a,%a; %a,%a; %a,%a) = %g, exact sign %d",
		  what, a[0], a[1], b[0], b[1], c[0], c[1], ex, ref);
	CHECK(sign_of(fl) == ref,
		  "%s: orient2d(%a,%a; %a,%a; %a,%a) = %g, exact sign %d",
		  what, a[0], a[1], b[0], b[1], c[0], c[1], fl, ref);
	return ref;
}

static int
check_incircle(const double *a, const double *b, const double *c,
			   const double *d, const char *what)
{
	int			ref = ref_incircle(a, b, c, d);
	double		ex = tdc_incircle_exact(a, b, c, d);
	double		fl = tdc_incircle(a, b, c, d);

	n_incircle++;
	if (ref == 0)
		n_incircle_zero++;
	CHECK(ex == (double) ref,
		  "%s: incircle_exact(%a,%a; %a,%a; %a,%a; %a,%a) = %g, exact sign %d",
		  what, a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1], ex, ref);
	CHECK(sign_of(fl) == ref,
		  "%s: incircle(%a,%a; %a,%a; %a,%a; %a,%a) = %g, exact sign %d",
		  what, a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1], fl, ref);
	return ref;
}

/*
 * Symmetry of the exact functions: swapping two points negates the sign,
 * cyclic rotation of the triangle keeps it.  Cheap, so done on many cases.
 */
static void
check_symmetry(const double *a, const double *b, const double *c, const double *d)
{
	double		o = tdc_orient2d_exact(a, b, c);
	double		i = tdc_incircle_exact(a, b, c, d);

	CHECK(tdc_orient2d_exact(b, a, c) == -o && tdc_orient2d_exact(a, c, b) == -o &&
		  tdc_orient2d_exact(b, c, a) == o && tdc_orient2d_exact(c, a, b) == o,
		  "orient2d symmetry (%a,%a; %a,%a; %a,%a)", a[0], a[1], b[0], b[1], c[0], c[1]);
	CHECK(tdc_incircle_exact(b, a, c, d) == -i && tdc_incircle_exact(a, c, b, d) == -i &&
		  tdc_incircle_exact(c, b, a, d) == -i &&
		  tdc_incircle_exact(b, c, a, d) == i && tdc_incircle_exact(c, a, b, d) == i,
		  "incircle symmetry (%a,%a; %a,%a; %a,%a; %a,%a)",
		  a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]);
}

static void
check_all(const double *a, const double *b, const double *c, const double *d,
		  const char *what)
{
	check_orient(a, b, c, what);
	check_orient(a, b, d, what);
	check_incircle(a, b, c, d, what);
}

/* ------------------------------------------------------------------------
 * Exactly degenerate inputs
 * ------------------------------------------------------------------------
 */

/* (power-of-two exponent, translation) pairs applied to lattice points */
static const struct
{
	int			k;
	double		off;
} transforms[] = {
	{0, 0.0}, {-3, 0.0}, {7, 0.0}, {-190, 0.0}, {-100, 0.0}, {120, 0.0},
	{180, 0.0}, {-20, 5e6}, {-29, 5e6}, {-10, -5e6}, {0, 1e15}, {-3, 1e15},
	{-3, -1e15}, {2, 3e15}, {-40, 1.0}, {-52, 0.5}, {-60, 5e6},	/* last: rounds */
	{-8, 4e6}, {-30, 180.0}, {-40, -33.5},
};
#define N_TRANSFORMS ((int) (sizeof(transforms) / sizeof(transforms[0])))

static void
transform(double *p, long x, long y, int t)
{
	p[0] = ldexp((double) x, transforms[t].k) + transforms[t].off;
	p[1] = ldexp((double) y, transforms[t].k) - transforms[t].off * 0.75;
}

/* Lattice points in [-r, r]^2: plenty of collinear and cocircular quadruples. */
static void
test_lattice(int n)
{
	long		zeros_before = n_orient_zero + n_incircle_zero;
	int			i;

	for (i = 0; i < n; i++)
	{
		int			t = (int) rng_int(0, N_TRANSFORMS - 1);
		static const long radii[] = {3, 12, 3, 12, 2047, 2048, 4096, 70000,
		(1L << 25) - 1, 1L << 25, 1L << 30};
		long		r = radii[rng_int(0, 10)];
		double		a[2],
					b[2],
					c[2],
					d[2];

		/* keep coordinates below 2^199 < 1e60 */
		while (r > 4096 && transforms[t].k > 160)
			t = (int) rng_int(0, N_TRANSFORMS - 1);

		transform(a, rng_int(-r, r), rng_int(-r, r), t);
		transform(b, rng_int(-r, r), rng_int(-r, r), t);
		transform(c, rng_int(-r, r), rng_int(-r, r), t);
		transform(d, rng_int(-r, r), rng_int(-r, r), t);
		check_all(a, b, c, d, "lattice");
		if (i % 8 == 0)
			check_symmetry(a, b, c, d);
	}
	CHECK(n_orient_zero + n_incircle_zero - zeros_before > n / 8,
		  "lattice: too few degenerate cases (%ld)",
		  n_orient_zero + n_incircle_zero - zeros_before);
}

/* Points p + j*v on a line, v with power-of-two scaled integer steps. */
static void
test_collinear(int n)
{
	int			i;
	long		zeros = 0;

	for (i = 0; i < n; i++)
	{
		int			t = (int) rng_int(0, N_TRANSFORMS - 1);
		long		px = rng_int(-50, 50),
					py = rng_int(-50, 50),
					vx = rng_int(-7, 7),
					vy = rng_int(-7, 7);
		long		j1 = rng_int(-9, 9),
					j2 = rng_int(-9, 9),
					j3 = rng_int(-9, 9);
		double		a[2],
					b[2],
					c[2];

		transform(a, px + j1 * vx, py + j1 * vy, t);
		transform(b, px + j2 * vx, py + j2 * vy, t);
		transform(c, px + j3 * vx, py + j3 * vy, t);
		if (check_orient(a, b, c, "collinear") == 0)
			zeros++;
	}
	CHECK(zeros > n * 3 / 4, "collinear: only %ld of %d exactly collinear", zeros, n);
}

/*
 * Lattice points on circles x^2 + y^2 = r^2.  Radii up to 1105 keep the
 * differences below 2^12 (the exact function's small-lattice shortcut); the
 * two largest force the expansion arithmetic on exactly cocircular input.
 */
#define N_CIRCLES 6
static long circle_pts[N_CIRCLES][400][2];
static int	circle_npts[N_CIRCLES];
static const long circle_r[N_CIRCLES] = {5, 25, 65, 1105, 5525, 32045};

static void
build_circles(void)
{
	int			ci;

	for (ci = 0; ci < N_CIRCLES; ci++)
	{
		long		r = circle_r[ci],
					x;

		circle_npts[ci] = 0;
		for (x = -r; x <= r; x++)
		{
			long		y = (long) sqrt((double) (r * r - x * x));

			while (y * y > r * r - x * x)
				y--;
			while ((y + 1) * (y + 1) <= r * r - x * x)
				y++;
			if (x * x + y * y != r * r || circle_npts[ci] >= 398)
				continue;
			circle_pts[ci][circle_npts[ci]][0] = x;
			circle_pts[ci][circle_npts[ci]][1] = y;
			circle_npts[ci]++;
			if (y != 0)
			{
				circle_pts[ci][circle_npts[ci]][0] = x;
				circle_pts[ci][circle_npts[ci]][1] = -y;
				circle_npts[ci]++;
			}
		}
	}
	CHECK(circle_npts[0] == 12 && circle_npts[3] == 108 && circle_npts[5] == 324,
		  "lattice circles: %d %d %d points", circle_npts[0], circle_npts[3],
		  circle_npts[5]);
}

static void
test_cocircular(int n)
{
	int			i;
	long		zeros = 0;

	build_circles();
	for (i = 0; i < n; i++)
	{
		int			ci = (int) rng_int(0, N_CIRCLES - 1);
		int			t = (int) rng_int(0, N_TRANSFORMS - 1);
		long		cx = rng_int(-10, 10),
					cy = rng_int(-10, 10);
		int			idx[4],
					j,
					k;
		double		p[4][2];

		/* four distinct points of the circle */
		for (j = 0; j < 4; j++)
		{
			int			dup;

			do
			{
				idx[j] = (int) rng_int(0, circle_npts[ci] - 1);
				dup = 0;
				for (k = 0; k < j; k++)
					if (idx[k] == idx[j])
						dup = 1;
			} while (dup);
			transform(p[j], cx + circle_pts[ci][idx[j]][0],
					  cy + circle_pts[ci][idx[j]][1], t);
		}
		if (check_incircle(p[0], p[1], p[2], p[3], "cocircular") == 0)
			zeros++;
		check_orient(p[0], p[1], p[2], "cocircular");
		if (i % 8 == 0)
			check_symmetry(p[0], p[1], p[2], p[3]);
	}
	CHECK(zeros > n / 2, "cocircular: only %ld of %d exactly cocircular", zeros, n);
}

/* ------------------------------------------------------------------------
 * Nearly degenerate inputs
 * ------------------------------------------------------------------------
 */

/*
 * Shewchuk's classic experiment: orient2d of a point on an ulp grid around
 * (0.5, 0.5) against the line through (12, 12) and (24, 24).  Naive double
 * evaluation gets the sign wrong over large parts of the grid.
 */
static void
test_ulp_grid(int side)
{
	double		b[2] = {12.0, 12.0},
				c[2] = {24.0, 24.0};
	double		x0 = 0.5;
	int			i,
				j;

	for (i = 0; i < side; i++)
	{
		double		a[2];

		a[0] = ulps(x0, i);
		a[1] = 0.5;
		for (j = 0; j < side; j++)
		{
			check_orient(a, b, c, "ulp grid");
			a[1] = nextafter(a[1], INFINITY);
		}
	}

	/*
	 * The same idea for incircle: d on an ulp grid around a lattice point of
	 * the circle through a, b, c, plain and translated to projected
	 * coordinates.
	 */
	for (int v = 0; v < 3; v++)
	{
		double		off = (v == 0) ? 0.0 : (v == 1) ? 5e6 : 1e15;
		double		s = (v == 0) ? 1.0 : (v == 1) ? 0x1p-20 : 0.5;
		double		a[2] = {off + 5 * s, off + 0 * s},
					bb[2] = {off + 0 * s, off + 5 * s},
					cc[2] = {off - 5 * s, off + 0 * s};
		int			half = side / 8;

		for (i = -half; i < half; i++)
			for (j = -half; j < half; j++)
			{
				double		d[2];

				d[0] = ulps(off + 3 * s, i);
				d[1] = ulps(off - 4 * s, j);
				check_incircle(a, bb, cc, d, "incircle ulp grid");
			}
	}
}

/*
 * Points rounded onto a line and onto a circle, at many scales and offsets:
 * the determinants are tiny but mostly nonzero.  scale and off define the
 * region; the PRNG picks everything else.
 */
static void
near_degenerate_case(double scale, double offx, double offy, const char *what)
{
	double		a[2],
				b[2],
				c[2],
				d[2],
				e[2];
	double		t = rng_range(-2.0, 3.0);
	double		cx = offx + scale * rng_range(-1, 1),
				cy = offy + scale * rng_range(-1, 1),
				r = scale * rng_range(0.01, 1);
	double		th[4];
	int			k;

	a[0] = offx + scale * rng_range(-1, 1);
	a[1] = offy + scale * rng_range(-1, 1);
	b[0] = offx + scale * rng_range(-1, 1);
	b[1] = offy + scale * rng_range(-1, 1);
	c[0] = a[0] + t * (b[0] - a[0]);
	c[1] = a[1] + t * (b[1] - a[1]);
	check_orient(a, b, c, what);

	/* a ulp-perturbed copy of c */
	e[0] = ulps(c[0], (int) rng_int(-2, 2));
	e[1] = ulps(c[1], (int) rng_int(-2, 2));
	check_orient(a, b, e, what);

	for (k = 0; k < 4; k++)
		th[k] = rng_range(0, 6.283185307179586);
	a[0] = cx + r * cos(th[0]);
	a[1] = cy + r * sin(th[0]);
	b[0] = cx + r * cos(th[1]);
	b[1] = cy + r * sin(th[1]);
	c[0] = cx + r * cos(th[2]);
	c[1] = cy + r * sin(th[2]);
	d[0] = cx + r * cos(th[3]);
	d[1] = cy + r * sin(th[3]);
	check_incircle(a, b, c, d, what);
	if (rng_next() & 1)
	{
		d[0] = ulps(d[0], (int) rng_int(-3, 3));
		d[1] = ulps(d[1], (int) rng_int(-3, 3));
		check_incircle(a, b, c, d, what);
	}
	if ((rng_next() & 7) == 0)
		check_symmetry(a, b, c, d);
}

static void
test_near_degenerate(int n)
{
	static const double scales[] = {1e-58, 1e-40, 1e-12, 1e-3, 1.0, 1e3, 1e20, 1e55};
	int			i;

	for (i = 0; i < n; i++)
	{
		double		s = scales[rng_int(0, 7)];

		/* centred on the origin, so coordinates straddle the axes */
		near_degenerate_case(s, 0.0, 0.0, "near-degenerate (origin)");
		/* well away from the origin */
		near_degenerate_case(s, 3 * s, -7 * s, "near-degenerate (offset)");
	}
}

/* Projected metres around (5e6, 4e6) with sub-millimetre detail; lon/lat. */
static void
test_geographic(int n)
{
	int			i;

	for (i = 0; i < n; i++)
	{
		near_degenerate_case(1e-4, 5e6, 4e6, "projected, sub-mm");
		near_degenerate_case(1e-1, 5e6 + rng_range(0, 1e5), 4e6, "projected, dm");
		near_degenerate_case(rng_range(1e-7, 1e-2), rng_range(-180, 180),
							 rng_range(-90, 90), "lon/lat");
		/* lon/lat straddling the equator and the prime meridian */
		near_degenerate_case(1e-5, 0.0, 0.0, "lon/lat near (0,0)");
	}

	/* Projected grid: exact multiples of 1 mm and 2^-10 m near 5e6. */
	for (i = 0; i < n; i++)
	{
		double		q = (i & 1) ? 0x1p-10 : 1e-3;
		double		p[4][2];
		int			k;

		for (k = 0; k < 4; k++)
		{
			p[k][0] = 5e6 + q * (double) rng_int(-4, 4);
			p[k][1] = 4e6 + q * (double) rng_int(-4, 4);
		}
		check_all(p[0], p[1], p[2], p[3], "projected grid");
	}
}

/* ------------------------------------------------------------------------
 * Wide magnitudes, extreme values, ulp neighbours
 * ------------------------------------------------------------------------
 */

static void
test_wide(int n)
{
	int			i;

	for (i = 0; i < n; i++)
	{
		double		p[4][2];
		int			k;

		for (k = 0; k < 4; k++)
		{
			p[k][0] = rng_wide();
			p[k][1] = rng_wide();
			/* zeros now and then */
			if ((rng_next() & 7) == 0)
				p[k][rng_next() & 1] = 0.0;
		}
		check_all(p[0], p[1], p[2], p[3], "wide magnitudes");
		if (i % 8 == 0)
			check_symmetry(p[0], p[1], p[2], p[3]);
	}
}

static void
test_extremes(int n)
{
	double		vals[24];
	int			nv = 0,
				i;

	vals[nv++] = 0.0;
	vals[nv++] = 1e-60;
	vals[nv++] = 1e60;
	vals[nv++] = nextafter(1e-60, INFINITY);
	vals[nv++] = nextafter(1e60, 0.0);
	vals[nv++] = 2e-60;
	vals[nv++] = 0x1p-199;
	vals[nv++] = 0x1p199;
	vals[nv++] = 1.0;
	vals[nv++] = 3e-60;
	vals[nv++] = 7e59;
	vals[nv++] = 1e-30;
	{
		int			m = nv;

		for (i = 1; i < m; i++)
			vals[nv++] = -vals[i];
	}

	for (i = 0; i < n; i++)
	{
		double		p[4][2];
		int			k;

		for (k = 0; k < 4; k++)
		{
			p[k][0] = vals[rng_int(0, nv - 1)];
			p[k][1] = vals[rng_int(0, nv - 1)];
		}
		check_all(p[0], p[1], p[2], p[3], "extreme values");
		if (i % 8 == 0)
			check_symmetry(p[0], p[1], p[2], p[3]);
	}
}

/*
 * Sites one ulp apart: the corners of an ulp rectangle are exactly
 * cocircular (rectangle) and three of them never collinear; small ulp
 * offsets give extreme near-degeneracy at every magnitude.
 */
static void
test_ulp_neighbours(int n)
{
	int			i;

	for (i = 0; i < n; i++)
	{
		double		x = rng_wide(),
					y = ((i & 3) == 0) ? x : rng_wide();	/* sometimes same binade */
		double		a[2] = {x, y},
					b[2] = {nextafter(x, INFINITY), y},
					c[2] = {nextafter(x, INFINITY), nextafter(y, INFINITY)},
					d[2] = {x, nextafter(y, INFINITY)};
		double		e[2],
					f[2];

		check_all(a, b, c, d, "ulp rectangle");
		check_incircle(a, c, b, d, "ulp rectangle");

		e[0] = ulps(x, (int) rng_int(-3, 3));
		e[1] = ulps(y, (int) rng_int(-3, 3));
		f[0] = ulps(x, (int) rng_int(-3, 3));
		f[1] = ulps(y, (int) rng_int(-3, 3));
		check_all(a, e, f, c, "ulp neighbours");
		if (i % 8 == 0)
			check_symmetry(a, e, f, c);
	}
}

/*
 * Rectangles: the four corners (x1,y1), (x2,y1), (x2,y2), (x1,y2) are exactly
 * cocircular whatever the doubles are, so rounded decimal coordinates (a
 * millimetre grid at 5e6, lon/lat in 1e-7 degrees) still give exact zeros.
 */
static void
test_rectangles(int n)
{
	int			i;
	long		zeros = 0;

	for (i = 0; i < n; i++)
	{
		double		x1,
					x2,
					y1,
					y2;
		int			kind = (int) rng_int(0, 3);

		if (kind == 0)
		{
			x1 = 5e6 + 1e-3 * (double) rng_int(0, 100000);
			x2 = 5e6 + 1e-3 * (double) rng_int(0, 100000);
			y1 = 4e6 + 1e-3 * (double) rng_int(0, 100000);
			y2 = 4e6 + 1e-3 * (double) rng_int(0, 100000);
		}
		else if (kind == 1)
		{
			x1 = 1e-7 * (double) rng_int(-1800000000, 1800000000);
			x2 = x1 + 1e-7 * (double) rng_int(-100, 100);
			y1 = 1e-7 * (double) rng_int(-900000000, 900000000);
			y2 = y1 + 1e-7 * (double) rng_int(-100, 100);
		}
		else if (kind == 2)
		{
			x1 = rng_wide();
			x2 = rng_wide();
			y1 = rng_wide();
			y2 = rng_wide();
		}
		else
		{
			x1 = rng_wide();
			x2 = ulps(x1, (int) rng_int(1, 1000));
			y1 = rng_range(-1, 1);
			y2 = y1 * 3.0;
		}
		{
			double		a[2] = {x1, y1},
						b[2] = {x2, y1},
						c[2] = {x2, y2},
						d[2] = {x1, y2};

			if (check_incircle(a, b, c, d, "rectangle") == 0)
				zeros++;
			check_incircle(a, c, d, b, "rectangle");
			check_orient(a, b, c, "rectangle");
		}
	}
	CHECK(zeros == n, "rectangles: %ld of %d cocircular", zeros, n);
}

/* A few hand-made cases with known answers. */
static void
test_known(void)
{
	double		o[2] = {0, 0},
				x[2] = {1, 0},
				y[2] = {0, 1},
				xy[2] = {1, 1},
				in[2] = {0.5, 0.5},
				out[2] = {2, 2};

	CHECK(tdc_orient2d_exact(o, x, y) == 1.0, "ccw triangle");
	CHECK(tdc_orient2d_exact(o, y, x) == -1.0, "cw triangle");
	CHECK(tdc_orient2d_exact(o, xy, out) == 0.0, "collinear");
	CHECK(tdc_orient2d(o, x, y) > 0.0, "ccw triangle (filtered)");
	CHECK(tdc_incircle_exact(o, x, y, in) == 1.0, "inside");
	CHECK(tdc_incircle_exact(o, x, y, out) == -1.0, "outside");
	CHECK(tdc_incircle_exact(o, x, y, xy) == 0.0, "cocircular square");
	CHECK(tdc_incircle_exact(o, x, xy, y) == 0.0, "cocircular square (2)");
	CHECK(tdc_incircle_exact(o, o, x, y) == 0.0, "repeated point");
	CHECK(tdc_orient2d_exact(o, o, o) == 0.0 && tdc_incircle_exact(o, o, o, o) == 0.0,
		  "all equal");
	CHECK(tdc_incircle(o, x, y, in) > 0.0 && tdc_incircle(o, x, y, out) < 0.0,
		  "filtered inside / outside");
}

void
test_predicates(void)
{
	int			q = tdc_test_quick ? 4 : 1;
	long		failed_before = tdc_test_failed;

	rng_state = UINT64_C(0x5EED00D1CE);
	n_orient = n_incircle = n_orient_zero = n_incircle_zero = 0;

	test_known();
	test_lattice(20000 / q);
	test_collinear(10000 / q);
	test_cocircular(20000 / q);
	test_ulp_grid(tdc_test_quick ? 64 : 256);
	test_near_degenerate(10000 / q);
	test_geographic(5000 / q);
	test_wide(20000 / q);
	test_extremes(10000 / q);
	test_ulp_neighbours(10000 / q);
	test_rectangles(10000 / q);

	printf("predicates: %ld orient2d cases (%ld exactly 0), %ld incircle cases (%ld exactly 0), %ld failures\n",
		   n_orient, n_orient_zero, n_incircle, n_incircle_zero,
		   tdc_test_failed - failed_before);
}
