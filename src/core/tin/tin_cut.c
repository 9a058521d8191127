/*
 * tin_cut.c
 *		Contour levels, crossings, and the order of lines (tin_cut.h).
 *
 * Plain floating point, so the order of the operations is part of the
 * result: the whole TIN's contours and a bounded run's agree to the bit
 * only because both take their levels and their crossings from here, with
 * the ends of an edge put in the same order (the one above first) by the
 * function itself, whichever triangle asks.  The build never contracts
 * a * b + c into a fused multiply-add (-ffp-contract=off).
 */
#include <math.h>
#include <stdio.h>

#include "tdc.h"
#include "tin_cut.h"

int64_t
tin_k_above(double base, double interval, double z)
{
	double		f = floor((z - base) / interval);
	int64_t		k;

	/* a start near the answer; the two loops make it exact */
	if (f < -(double) TIN_MAX_LEVELS * 4)
		f = -(double) TIN_MAX_LEVELS * 4;
	if (f > (double) TIN_MAX_LEVELS * 4)
		f = (double) TIN_MAX_LEVELS * 4;
	k = (int64_t) f;
	while (tin_level(base, interval, k) <= z)
		k++;
	while (tin_level(base, interval, k - 1) > z)
		k--;
	return k;
}

void
tin_cut_xy(const double *p0, double z0, const double *p1, double z1, double L, double *c)
{
	const double *pa = p0,
			   *pb = p1;
	double		za = z0,
				zb = z1,
				t;

	/* a: the end above (height >= L), b: the end below */
	if (za < L)
	{
		pa = p1;
		pb = p0;
		za = z1;
		zb = z0;
	}
	if (za == L)
	{
		c[0] = pa[0];
		c[1] = pa[1];
		return;
	}
	t = (L - zb) / (za - zb);
	c[0] = pb[0] + t * (pa[0] - pb[0]);
	c[1] = pb[1] + t * (pa[1] - pb[1]);
}

/* Reverse the points [i, j). */
static void
reverse_pts(double *xy, size_t i, size_t j)
{
	for (; i + 1 < j; i++, j--)
	{
		double		x = xy[2 * i],
					y = xy[2 * i + 1];

		xy[2 * i] = xy[2 * (j - 1)];
		xy[2 * i + 1] = xy[2 * (j - 1) + 1];
		xy[2 * (j - 1)] = x;
		xy[2 * (j - 1) + 1] = y;
	}
}

void
tin_ring_canon(double *xy, size_t m)
{
	size_t		best = 0;

	/* should the ring pass a point twice, the first rotation of the least sequence */
	for (size_t r = 1; r < m; r++)
	{
		int			c = tin_pt_cmp(xy + 2 * r, xy + 2 * best);

		for (size_t i = 1; c == 0 && i < m; i++)
			c = tin_pt_cmp(xy + 2 * ((r + i) % m), xy + 2 * ((best + i) % m));
		if (c < 0)
			best = r;
	}
	if (best == 0)
		return;
	/* the rotation in place, by three reversals: no scratch to allocate */
	reverse_pts(xy, 0, best);
	reverse_pts(xy, best, m);
	reverse_pts(xy, 0, m);
	xy[2 * m] = xy[0];
	xy[2 * m + 1] = xy[1];
}

int
tin_line_cmp(const double *a, size_t na, const double *b, size_t nb)
{
	for (size_t i = 0; i < na && i < nb; i++)
	{
		int			c = tin_pt_cmp(a + 2 * i, b + 2 * i);

		if (c != 0)
			return c;
	}
	return na < nb ? -1 : na > nb ? 1 : 0;
}

int
tin_levels_check(double interval, double base, double zmin, double zmax, char *err, size_t errlen)
{
	/*
	 * L_k = fl(base + fl(k interval)) is off by at most eps (|k interval| +
	 * |L_k|), so an interval above 4 eps times the largest such term keeps
	 * consecutive levels apart.
	 */
	double		k0 = floor((zmin - base) / interval) - 1,
				k1 = floor((zmax - base) / interval) + 1,
				a = fmax(fabs(k0) * interval + fabs(base + k0 * interval),
						 fabs(k1) * interval + fabs(base + k1 * interval));
	bool		many = !(fabs(k1 - k0) < (double) TIN_MAX_LEVELS);

	if (!many && interval > 0x1p-50 * a)
		return TDC_OK;
	if (err && errlen)
		snprintf(err, errlen, "the contour interval %g is too small for heights from %g to %g "
				 "(base %g): %s", interval, zmin, zmax, base,
				 many ? "more than 2^31 levels" : "consecutive levels would round to the same number");
	return TDC_EINVAL;
}
