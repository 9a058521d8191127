/*
 * bounded_scan.c
 *		Pass 1 of a bounded run over the .bin source: the points' exact
 *		box, their convex hull, and the counts of the cells of the fine
 *		grid that the plan cuts into tiles.
 *
 * The grid's box comes from a sample of the file, so that the pass can
 * count as it finds the box and hull; when the sample was far off, or the
 * input too small to sample, the plan has the cells counted again in a
 * pass of their own (scan_count).
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "bounded_int.h"

/*
 * A sample of the .bin source (256 runs of 256 points spread over the
 * file): its box in g, made a grid's box by tdc_tp_grid_from_sample, and
 * the grid r->grid over it with its cell sides at the sample's quantiles
 * (tdc_tp_grid_quantiles).  False when n is small, the file unreadable or
 * the sample flat.
 */
static bool
sample_grid(bounded_run *r)
{
	FILE	   *f;
	double		buf[2 * 256],
				g[4],
			   *xs,
			   *ys;
	size_t		ns = 0;

	if (r->n < ((size_t) 1 << 18) || (f = fopen(r->xypath, "rb")) == NULL)
		return false;
	xs = malloc(sizeof(double) * 256 * 256);
	ys = malloc(sizeof(double) * 256 * 256);
	if (xs == NULL || ys == NULL)
	{
		fclose(f);
		free(xs);
		free(ys);
		tdc_bd_nomem(&r->e);
		return false;
	}
	g[0] = g[1] = INFINITY;
	g[2] = g[3] = -INFINITY;
	for (size_t j = 0; j < 256; j++)
	{
		size_t		got;

		if (fseeko(f, (off_t) ((r->n - 256) / 255 * j) * 16, SEEK_SET) != 0)
			break;
		got = fread(buf, 16, 256, f);
		for (size_t i = 0; i < got; i++)
			if (isfinite(buf[2 * i]) && isfinite(buf[2 * i + 1]))
			{
				tdc_tp_box_add(g, buf[2 * i], buf[2 * i + 1]);
				xs[ns] = buf[2 * i];
				ys[ns++] = buf[2 * i + 1];
			}
	}
	fclose(f);
	if (tdc_tp_grid_from_sample(g))
	{
		tdc_tp_grid_quantiles(&r->grid, g, xs, ys, ns);
		free(xs);
		free(ys);
		return true;
	}
	free(xs);
	free(ys);
	return false;
}

/*
 * Pass 1 over the input points [from, from + count): their box, convex
 * hull and, when the grid is known (grid not NULL), the counts of its
 * cells.  The hull of a union is the hull of the parts' hulls; a point
 * strictly inside a rectangle inside the hull so far (inner) cannot be a
 * vertex of it, and for most data that rectangle holds almost every point:
 * only the others go to the chunk's hull.  Runs as two parts on two
 * threads when the grid is known.
 */
typedef struct scan_work
{
	const char *xypath;
	size_t		from,
				count;
	const tdc_tp_grid *grid;
	uint32_t   *counts;
	const volatile int *cancel;
	/* results */
	double		bb[4];
	double	   *hull;
	size_t		nhull;
	bool		bad;			/* a coordinate not finite or out of range */
	bd_err		e;				/* this part's first error */
} scan_work;

/*
 * The largest rectangle, of the hull's box shrunk towards its centre, whose
 * open inside is inside the hull (nhull >= 3 vertices): into inner, left
 * as it is when none is found.
 */
static int
inner_rectangle(const double *hull, size_t nhull, double inner[4], bd_err *e)
{
	double		hb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
				cx,
				cy;

	for (size_t i = 0; i < nhull; i++)
		tdc_tp_box_add(hb, hull[2 * i], hull[2 * i + 1]);
	cx = 0.5 * (hb[0] + hb[2]);
	cy = 0.5 * (hb[1] + hb[3]);
	for (double f = 0.98; f > 0.2; f -= 0.16)
	{
		double		r[4] = {cx - f * (cx - hb[0]), cy - f * (cy - hb[1]),
		cx + f * (hb[2] - cx), cy + f * (hb[3] - cy)};
		bool		in = r[0] < r[2] && r[1] < r[3];
		double	   *hb2 = malloc(16 * (nhull + 4)),
				   *h3 = NULL;
		size_t		n3 = 0;

		/*
		 * The closed rectangle is inside the closed hull when adding its
		 * corners leaves the hull as it is; its open inside is then inside
		 * the hull's, whose points are no vertices.
		 */
		if (hb2 == NULL)
			return tdc_bd_nomem(e);
		memcpy(hb2, hull, 16 * nhull);
		memcpy(hb2 + 2 * nhull, (double[8]) {r[0], r[1], r[2], r[1], r[2], r[3], r[0], r[3]}, 64);
		if (in && tdc_convex_hull(hb2, nhull + 4, &h3, &n3) != TDC_OK)
		{
			free(hb2);
			return tdc_bd_nomem(e);
		}
		in = in && n3 == nhull && memcmp(h3, hull, 16 * nhull) == 0;
		free(hb2);
		free(h3);
		if (in)
		{
			memcpy(inner, r, sizeof(r));
			return TDC_OK;
		}
	}
	return TDC_OK;
}

static void *
scan_range(void *arg)
{
	scan_work  *sw = arg;
	source		src;
	size_t		k,
				nhull = 0;
	double	   *hull = NULL,
				inner[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
			   *bb = sw->bb;
	bool		counted = sw->grid != NULL;
	const double *grid = counted ? sw->grid->box : NULL,
			   *xcut = counted ? sw->grid->xcut : NULL,
			   *ycut = counted ? sw->grid->ycut : NULL;
	double		sx = counted ? sw->grid->sx : 0,
				sy = counted ? sw->grid->sy : 0;
	uint32_t   *counts = sw->counts;

	bb[0] = bb[1] = INFINITY;
	bb[2] = bb[3] = -INFINITY;
	sw->bad = false;
	sw->hull = NULL;
	sw->nhull = 0;
	if (tdc_bd_source_open(&src, sw->xypath, NULL, NULL, &sw->e, sw->cancel) != TDC_OK)
		return NULL;
	tdc_bd_source_range(&src, sw->from, sw->count);
	while ((k = tdc_bd_source_read(&src)) > 0)
	{
		double	   *buf,
				   *h2;
		size_t		n2,
					m = 0;

		buf = malloc(16 * (k + nhull));
		if (buf == NULL)
		{
			tdc_bd_nomem(&sw->e);
			break;
		}
		for (size_t i = 0; i < k; i++)
		{
			double		x = src.xy[2 * i],
						y = src.xy[2 * i + 1];

			if (!isfinite(x) || !isfinite(y) ||
				(x != 0 && (fabs(x) < TDC_COORD_MIN || fabs(x) > TDC_COORD_MAX)) ||
				(y != 0 && (fabs(y) < TDC_COORD_MIN || fabs(y) > TDC_COORD_MAX)))
			{
				sw->bad = true;
				continue;
			}
			if (x < bb[0])
				bb[0] = x;
			if (x > bb[2])
				bb[2] = x;
			if (y < bb[1])
				bb[1] = y;
			if (y > bb[3])
				bb[3] = y;
			if (counted)
				counts[tdc_tp_cell_of(y, grid[1], sy, ycut) * TDC_TP_GRID + tdc_tp_cell_of(x, grid[0], sx, xcut)]++;
			if (x > inner[0] && x < inner[2] && y > inner[1] && y < inner[3])
				continue;
			buf[2 * m] = x;
			buf[2 * m + 1] = y;
			m++;
		}
		if (nhull)
			memcpy(buf + 2 * m, hull, 16 * nhull);
		if (tdc_convex_hull(buf, m + nhull, &h2, &n2) != TDC_OK)
		{
			free(buf);
			tdc_bd_nomem(&sw->e);
			break;
		}
		free(buf);
		free(hull);
		hull = h2;
		nhull = n2;
		if (nhull >= 3 && inner_rectangle(hull, nhull, inner, &sw->e) != TDC_OK)
			break;
	}
	tdc_bd_source_close(&src);
	sw->hull = hull;
	sw->nhull = nhull;
	return NULL;
}

/*
 * Pass 1: r->bb the exact box of the points, r->hull their convex hull,
 * and, when a sample of the file gave a grid (r->counted), r->grid that
 * grid and r->counts its cells' counts.  Fails on a coordinate that is not
 * finite or out of the supported range.
 */
int
tdc_bd_scan_input(bounded_run *r)
{
	/* the two halves of the input on two threads when the grid is known */
	int			np;
	scan_work	sw[2];
	pthread_t	th;
	bool		started = false;

	memset(sw, 0, sizeof(sw));
	r->counts = calloc((size_t) TDC_TP_GRID * TDC_TP_GRID, sizeof(uint32_t));
	if (r->counts == NULL)
		return tdc_bd_nomem(&r->e);
	r->counted = sample_grid(r);
	if (r->e.code != TDC_OK)
		return r->e.code;
	np = r->counted ? 2 : 1;
	for (int p = 0; p < np; p++)
	{
		sw[p].xypath = r->xypath;
		sw[p].from = r->n / np * p;
		sw[p].count = p == np - 1 ? r->n - sw[p].from : r->n / np;
		sw[p].grid = r->counted ? &r->grid : NULL;
		sw[p].cancel = r->p->cancel;
		sw[p].counts = p == 0 ? r->counts : calloc((size_t) TDC_TP_GRID * TDC_TP_GRID, sizeof(uint32_t));
		if (sw[p].counts == NULL)
			return tdc_bd_nomem(&r->e);
	}
	if (np == 2)
		started = pthread_create(&th, NULL, scan_range, &sw[1]) == 0;
	scan_range(&sw[0]);
	if (started)
		pthread_join(th, NULL);
	else if (np == 2)
		scan_range(&sw[1]);
	r->hull = sw[0].hull;
	r->nhull = sw[0].nhull;
	for (int p = 0; p < np; p++)
		if (sw[p].e.code != TDC_OK)
			tdc_bd_fail(&r->e, sw[p].e.code, "%s", sw[p].e.msg);
	for (int p = 0; p < np && r->e.code == TDC_OK; p++)
		if (sw[p].bad)
			tdc_bd_fail(&r->e, TDC_EINVAL, "a point has a non-finite coordinate or one outside the "
						"supported magnitude range");
	memcpy(r->bb, sw[0].bb, sizeof(r->bb));
	if (np == 2)
	{
		double	   *buf = r->e.code == TDC_OK ? malloc(16 * (r->nhull + sw[1].nhull + 1)) : NULL;

		if (buf != NULL)
		{
			tdc_tp_box_union(r->bb, sw[1].bb);
			memcpy(buf, r->hull, 16 * r->nhull);
			memcpy(buf + 2 * r->nhull, sw[1].hull, 16 * sw[1].nhull);
			free(r->hull);
			r->hull = NULL;
			if (tdc_convex_hull(buf, r->nhull + sw[1].nhull, &r->hull, &r->nhull) != TDC_OK)
				tdc_bd_nomem(&r->e);
			free(buf);
			for (size_t c = 0; c < (size_t) TDC_TP_GRID * TDC_TP_GRID; c++)
				r->counts[c] += sw[1].counts[c];
		}
		else
			tdc_bd_nomem(&r->e);
		free(sw[1].hull);
		free(sw[1].counts);
	}
	return r->e.code;
}

/* r->counts: the cells' counts on r->grid, in a pass of their own. */
int
tdc_bd_scan_count(bounded_run *r)
{
	source		src;
	size_t		k;

	if (tdc_bd_source_open(&src, r->xypath, NULL, NULL, &r->e, r->p->cancel) != TDC_OK)
		return r->e.code;
	while ((k = tdc_bd_source_read(&src)) > 0)
		for (size_t i = 0; i < k; i++)
			r->counts[tdc_tp_cell(&r->grid, src.xy[2 * i], src.xy[2 * i + 1])]++;
	tdc_bd_source_close(&src);
	return r->e.code;
}

static int
cmp_xy(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	return p[0] < q[0] ? -1 : p[0] > q[0] ? 1 : p[1] < q[1] ? -1 : p[1] > q[1];
}

/*
 * For the refusal of a cell too dense to be a tile (bounded.c): the point
 * with the most exact copies among the first limit points of cell (a
 * sample), in spot, and its copies in the whole input, counted exactly in
 * a second pass.  A read of the input, only on the way to an error.
 */
int
tdc_bd_dense_spot(bounded_run *r, int cell, size_t limit, double spot[2], size_t *copies)
{
	source		src;
	size_t		k,
				m = 0,
				best = 0;
	double	   *pts = malloc(16 * (limit + 1));

	spot[0] = spot[1] = NAN;
	*copies = 0;
	if (pts == NULL)
		return tdc_bd_nomem(&r->e);
	if (tdc_bd_source_open(&src, r->xypath, NULL, NULL, &r->e, r->p->cancel) != TDC_OK)
	{
		free(pts);
		return r->e.code;
	}
	while (m < limit && (k = tdc_bd_source_read(&src)) > 0)
		for (size_t i = 0; i < k && m < limit; i++)
			if (tdc_tp_cell(&r->grid, src.xy[2 * i], src.xy[2 * i + 1]) == cell)
			{
				pts[2 * m] = src.xy[2 * i];
				pts[2 * m + 1] = src.xy[2 * i + 1];
				m++;
			}
	tdc_bd_source_close(&src);
	qsort(pts, m, 16, cmp_xy);
	for (size_t i = 0, j; i < m; i = j)
	{
		for (j = i + 1; j < m && cmp_xy(pts + 2 * i, pts + 2 * j) == 0; j++)
			;
		if (j - i > best)
		{
			best = j - i;
			spot[0] = pts[2 * i];
			spot[1] = pts[2 * i + 1];
		}
	}
	free(pts);
	if (best < 2 || r->e.code != TDC_OK)
		return r->e.code;
	if (tdc_bd_source_open(&src, r->xypath, NULL, NULL, &r->e, r->p->cancel) != TDC_OK)
		return r->e.code;
	while ((k = tdc_bd_source_read(&src)) > 0)
		for (size_t i = 0; i < k; i++)
			*copies += src.xy[2 * i] == spot[0] && src.xy[2 * i + 1] == spot[1];
	tdc_bd_source_close(&src);
	return r->e.code;
}
