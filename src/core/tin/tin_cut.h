/*
 * tin_cut.h
 *		The contour levels and where a level crosses an edge, from numbers
 *		alone: the one rule of the whole TIN's contours (tin_contour.c) and
 *		a bounded run's (terrain/contour_tiles.c), so that both give the
 *		same levels and the same crossings, bit for bit.
 */
#ifndef TDC_TIN_CUT_H
#define TDC_TIN_CUT_H

#include <stddef.h>
#include <stdint.h>

#define TIN_MAX_LEVELS	((int64_t) 1 << 31)

/* Level k: base + k interval. */
static inline double
tin_level(double base, double interval, int64_t k)
{
	return base + (double) k * interval;
}

/* The lowest k whose level is above z (a height equal to a level counts as above it). */
extern int64_t tin_k_above(double base, double interval, double z);

/*
 * The crossing of level L on the edge p0-p1, whose ends lie on either side
 * of it (one height >= L, the other < L), into c: the end above itself
 * when its height is L, else b + t (a - b), t = (L - zb) / (za - zb), b
 * the end below and a the end above, whichever the caller names first.
 */
extern void tin_cut_xy(const double *p0, double z0, const double *p1, double z1, double L,
					   double *c);

/* Two points in (x, y) order: -1, 0 or 1. */
static inline int
tin_pt_cmp(const double *a, const double *b)
{
	return a[0] < b[0] ? -1 : a[0] > b[0] ? 1 : a[1] < b[1] ? -1 : a[1] > b[1] ? 1 : 0;
}

/*
 * A ring of m points (x,y pairs), its closing repeat after them, turned in
 * place to start at the rotation whose points come first in (x, y) order,
 * so that it starts where it would whatever triangle it was found from.
 */
extern void tin_ring_canon(double *xy, size_t m);

/* Two lines (na and nb points) by their points in (x, y) order, then the shorter first. */
extern int	tin_line_cmp(const double *a, size_t na, const double *b, size_t nb);

/*
 * The check that every level between zmin and zmax is a double of its own
 * and that there are at most 2^31 of them: TDC_OK, or TDC_EINVAL with the
 * message in err.
 */
extern int	tin_levels_check(double interval, double base, double zmin, double zmax,
							 char *err, size_t errlen);

#endif							/* TDC_TIN_CUT_H */
