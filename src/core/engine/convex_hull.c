/*
 * convex_hull.c
 *		The convex hull of a point set (Andrew's monotone chain), with
 *		exact orientations: the polygon C that the tiled triangulations
 *		(tile_final.c, its callers in the command line and the server)
 *		hand to every tile.
 */
#include <stdlib.h>
#include <string.h>

#include "engine_int.h"

/* Lexicographic order of points, for the monotone chain. */
static int
cmp_pt(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	if (p[0] != q[0])
		return p[0] < q[0] ? -1 : 1;
	if (p[1] != q[1])
		return p[1] < q[1] ? -1 : 1;
	return 0;
}

int
tdc_convex_hull(const double *xy, size_t n, double **hull, size_t *nhull)
{
	double	   *p,
			   *h;
	size_t		k = 0,
				m = 0;

	*hull = NULL;
	*nhull = 0;
	if (n == 0)
		return TDC_OK;
	p = malloc(16 * n);
	h = malloc(16 * (2 * n + 1));
	if (p == NULL || h == NULL)
	{
		free(p);
		free(h);
		return TDC_ENOMEM;
	}
	/*
	 * Akl-Toussaint: a point strictly inside the polygon of the extreme
	 * points in eight directions is no hull vertex; only the rest is sorted.
	 */
	{
		size_t		ext[8] = {0};
		double		oct[16];

		for (size_t i = 1; i < n; i++)
		{
			const double *q = xy + 2 * i;
			double		key[8] = {q[0], q[0] + q[1], q[1], q[1] - q[0],
			-q[0], -q[0] - q[1], -q[1], q[0] - q[1]};

			for (int k = 0; k < 8; k++)
			{
				const double *e = xy + 2 * ext[k];
				double		ek[8] = {e[0], e[0] + e[1], e[1], e[1] - e[0],
				-e[0], -e[0] - e[1], -e[1], e[0] - e[1]};

				if (key[k] < ek[k])
					ext[k] = i;
			}
		}
		/* left, lower left, bottom, lower right, ...: counter-clockwise */
		for (int k = 0; k < 8; k++)
		{
			oct[2 * k] = xy[2 * ext[k]];
			oct[2 * k + 1] = xy[2 * ext[k] + 1];
		}
		for (size_t i = 0; i < n; i++)
		{
			const double *q = xy + 2 * i;
			bool		inside = true;

			for (int k = 0; k < 8 && inside; k++)
				inside = tdc_orient2d(oct + 2 * k, oct + 2 * ((k + 1) % 8), q) > 0;
			if (!inside)
			{
				p[2 * m] = q[0];
				p[2 * m + 1] = q[1];
				m++;
			}
		}
		n = m;
		m = 0;
	}
	qsort(p, n, 16, cmp_pt);
	/* drop exact duplicates */
	for (size_t i = 0; i < n; i++)
		if (m == 0 || cmp_pt(p + 2 * (m - 1), p + 2 * i) != 0)
		{
			p[2 * m] = p[2 * i];
			p[2 * m + 1] = p[2 * i + 1];
			m++;
		}
	if (m < 3)
	{
		memcpy(h, p, 16 * m);
		k = m;
	}
	else
	{
		/* Andrew's monotone chain, exact turns, collinear vertices dropped */
		for (size_t i = 0; i < m; i++)
		{
			while (k >= 2 && tdc_orient2d(h + 2 * (k - 2), h + 2 * (k - 1), p + 2 * i) <= 0)
				k--;
			h[2 * k] = p[2 * i];
			h[2 * k + 1] = p[2 * i + 1];
			k++;
		}
		for (size_t i = m - 1, t = k + 1; i-- > 0;)
		{
			while (k >= t && tdc_orient2d(h + 2 * (k - 2), h + 2 * (k - 1), p + 2 * i) <= 0)
				k--;
			h[2 * k] = p[2 * i];
			h[2 * k + 1] = p[2 * i + 1];
			k++;
		}
		k--;					/* the first point closes the chain */
	}
	free(p);
	*hull = h;
	*nhull = k;
	return TDC_OK;
}
