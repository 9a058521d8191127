/*
 * xy_oracle.h
 *		Point-set facts computed without the engine, shared by the core suite
 *		(test_engine.c) and the core fuzz target (fuzz/fuzz_core.c): each
 *		checks the engine's site count against count_unique().
 */
#ifndef TDC_XY_ORACLE_H
#define TDC_XY_ORACLE_H

#include <stdlib.h>
#include <string.h>

/* Lexicographic x, y on 2-double points; -0 equals 0, as for the engine. */
static int
cmp_xy(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	if (p[0] != q[0])
		return p[0] < q[0] ? -1 : 1;
	if (p[1] != q[1])
		return p[1] < q[1] ? -1 : 1;
	return 0;
}

/* Number of distinct points of xy (n points), by sorting a copy. */
static size_t
count_unique(const double *xy, size_t n)
{
	double	   *c = malloc(16 * n + 16);
	size_t		u = 0;

	if (c == NULL)
		abort();
	memcpy(c, xy, 16 * n);
	qsort(c, n, 16, cmp_xy);
	for (size_t i = 0; i < n; i++)
		if (i == 0 || cmp_xy(c + 2 * i, c + 2 * (i - 1)) != 0)
			u++;
	free(c);
	return u;
}

#endif
