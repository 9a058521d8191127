/*
 * fringe.c
 *		A bounded grid's pixels outside the points' convex hull: which they
 *		are, and the site nearest to each, without the whole TIN.
 *
 * Linear interpolation gives a pixel outside the hull the height of its
 * nearest site (within the method's radius; tin_interp.c).  The whole TIN
 * finds that site by a walk; a bounded run has only its tiles, one at a
 * time.  But few sites can be nearest to a point q outside the hull: q lies
 * in the Voronoi cell of its nearest site s, so that cell reaches outside
 * the hull.  A site on the hull's boundary has an unbounded cell; any
 * other site's cell is the convex polygon of the circumcentres of its
 * triangles, and a convex polygon leaves a convex region only if one of
 * its corners does.  So every outside pixel's nearest site is on the
 * hull's boundary or a corner of a triangle whose circumcentre lies
 * outside the hull: the triangles along the hull with an obtuse angle
 * facing in, some thousands where a tile holds millions.  A superset
 * serves as well, so both tests are conservative: a circumcentre is
 * computed in floating point with a bound on its error far above the
 * true one, and taken as outside unless that whole box is inside (a
 * sliver, whose centre is ill-conditioned, is taken); a site is on the
 * boundary by exact orientations (fr_on_hull).  The sites found go to a
 * file as the tiles come (fr_add), and are read back once, made distinct
 * and put in a k-d tree (fr_load).  The nearest of them is the nearest of
 * all sites, compared exactly (tdc_sqdist_cmp), ties to the site first in
 * (x, y) order: the whole TIN's rule (tin_nearest), hence its site.
 *
 * Inside is exact: the hull is convex and counter-clockwise, and q is
 * inside or on it when it is left of or on every edge, found in O(log n)
 * orientation tests by a binary search of the fan from the hull's first
 * vertex.  Most points need none: a grid of FR_CELLS^2 cells over the
 * hull's box marks the cells whose four corners are inside (so the whole
 * closed cell is: the hull is convex), and a point whose cell and eight
 * neighbours are marked is strictly inside, whatever the rounding of its
 * cell's index (at most one cell off).  Only the points along the hull
 * take the exact tests.
 */
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/predicates.h"
#include "fringe.h"
#include "tdc.h"

static int
fr_fail(char *err, size_t errlen, int code, const char *msg, const char *path)
{
	if (err && errlen)
		snprintf(err, errlen, "%s%s%s", msg, path ? " " : "", path ? path : "");
	return code;
}

int
fr_init(fringe *f, const double *hull, size_t nhull, const char *dir, char *err, size_t errlen)
{
	double		maxabs = 0,
				diam;
	uint8_t    *corner,
				inner[FR_CELLS * FR_CELLS];
	int			fd;

	memset(f, 0, sizeof(*f));
	f->hull = malloc(16 * nhull);
	if (f->hull == NULL)
		return fr_fail(err, errlen, TDC_ENOMEM, "out of memory for the hull", NULL);
	memcpy(f->hull, hull, 16 * nhull);
	f->nhull = nhull;
	f->box[0] = f->box[2] = hull[0];
	f->box[1] = f->box[3] = hull[1];
	for (size_t i = 0; i < nhull; i++)
	{
		f->box[0] = fmin(f->box[0], hull[2 * i]);
		f->box[2] = fmax(f->box[2], hull[2 * i]);
		f->box[1] = fmin(f->box[1], hull[2 * i + 1]);
		f->box[3] = fmax(f->box[3], hull[2 * i + 1]);
	}
	for (int k = 0; k < 4; k++)
		maxabs = fmax(maxabs, fabs(f->box[k]));
	diam = fmax(f->box[2] - f->box[0], f->box[3] - f->box[1]);
	/* far above the rounding of a circumcentre, relative to the hull and to the coordinates' size */
	f->delta = 1e-9 * diam + 64 * DBL_EPSILON * maxabs;
	f->cw = (f->box[2] - f->box[0]) / FR_CELLS;
	f->ch = (f->box[3] - f->box[1]) / FR_CELLS;
	f->icw = 1 / f->cw;
	f->ich = 1 / f->ch;
	/* a corner of the grid inside the hull, exactly; a cell, when its four are */
	corner = malloc((FR_CELLS + 1) * (FR_CELLS + 1));
	if (corner == NULL)
	{
		fr_free(f);
		return fr_fail(err, errlen, TDC_ENOMEM, "out of memory for the hull's cells", NULL);
	}
	for (int j = 0; j <= FR_CELLS; j++)
		for (int i = 0; i <= FR_CELLS; i++)
		{
			double		c[2] = {f->box[0] + i * f->cw, f->box[1] + j * f->ch};

			corner[j * (FR_CELLS + 1) + i] = fr_inside(f, c);
		}
	for (int j = 0; j < FR_CELLS; j++)
		for (int i = 0; i < FR_CELLS; i++)
			inner[j * FR_CELLS + i] = corner[j * (FR_CELLS + 1) + i] && corner[j * (FR_CELLS + 1) + i + 1] &&
				corner[(j + 1) * (FR_CELLS + 1) + i] && corner[(j + 1) * (FR_CELLS + 1) + i + 1];
	free(corner);
	/* a cell whose neighbours are inner too: a point there is strictly inside */
	for (int j = 0; j < FR_CELLS; j++)
		for (int i = 0; i < FR_CELLS; i++)
		{
			bool		all = true;

			for (int dj = -1; dj <= 1 && all; dj++)
				for (int di = -1; di <= 1 && all; di++)
				{
					int			ii = i + di,
								jj = j + dj;

					all = ii >= 0 && jj >= 0 && ii < FR_CELLS && jj < FR_CELLS && inner[jj * FR_CELLS + ii];
				}
			f->deep[j * FR_CELLS + i] = all;
		}
	snprintf(f->path, sizeof(f->path), "%s/fringe", dir);
	fd = open(f->path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
	if (fd < 0 || (f->f = fdopen(fd, "w+b")) == NULL)
	{
		int			rc = fr_fail(err, errlen, TDC_EIO, "cannot create", f->path);

		if (fd >= 0)
		{
			close(fd);
			unlink(f->path);
		}
		f->path[0] = '\0';
		return rc;
	}
	return TDC_OK;
}

bool
fr_inside(const fringe *f, const double *q)
{
	const double *h = f->hull;
	size_t		lo = 1,
				hi = f->nhull - 1;

	/* within the fan of h[0]: left of or on h0-h1, right of or on h0-h[n-1] */
	if (tdc_orient2d(h, h + 2, q) < 0 || tdc_orient2d(h, h + 2 * hi, q) > 0)
		return false;
	/* the wedge h0, h[lo], h[lo + 1] that holds q */
	while (hi - lo > 1)
	{
		size_t		mid = (lo + hi) / 2;

		if (tdc_orient2d(h, h + 2 * mid, q) >= 0)
			lo = mid;
		else
			hi = mid;
	}
	return tdc_orient2d(h + 2 * lo, h + 2 * hi, q) >= 0;
}

/*
 * Is q strictly inside the hull by its cell (false: the exact tests must
 * say)?  A deep cell's neighbours are inside the hull, so a q that rounding
 * puts in the cell beside its own is still strictly inside.
 */
static inline bool
fr_deep(const fringe *f, const double *q)
{
	double		fi = floor((q[0] - f->box[0]) * f->icw),
				fj = floor((q[1] - f->box[1]) * f->ich);

	return fi >= 0 && fj >= 0 && fi < FR_CELLS && fj < FR_CELLS &&
		f->deep[(size_t) fj * FR_CELLS + (size_t) fi];
}

bool
fr_on_hull(const fringe *f, const double *q)
{
	const double *h = f->hull;
	size_t		lo = 1,
				hi = f->nhull - 1;

	if (fr_deep(f, q))
		return false;
	if (!fr_inside(f, q))
		return false;
	/* inside or on: on the boundary when on the edge of its wedge, or on a side of the fan */
	if (tdc_orient2d(h, h + 2, q) == 0 || tdc_orient2d(h, h + 2 * hi, q) == 0)
		return true;
	while (hi - lo > 1)
	{
		size_t		mid = (lo + hi) / 2;

		if (tdc_orient2d(h, h + 2 * mid, q) >= 0)
			lo = mid;
		else
			hi = mid;
	}
	return tdc_orient2d(h + 2 * lo, h + 2 * hi, q) == 0;
}

/* Is q inside the hull or on it (exact; the cells first)? */
bool
fr_inside_fast(const fringe *f, const double *q)
{
	return fr_deep(f, q) || fr_inside(f, q);
}

/*
 * The circumcentre of triangle a, b, c in floating point, o, and a bound e
 * on its error in each coordinate, far above the rounding; false for a
 * sliver, whose centre is ill-conditioned (o and e not set).
 */
bool
fr_centre_box(const fringe *f, const double *a, const double *b, const double *c, double o[2],
			  double *e)
{
	double		bx = b[0] - a[0],
				by = b[1] - a[1],
				cx = c[0] - a[0],
				cy = c[1] - a[1],
				b2 = bx * bx + by * by,
				c2 = cx * cx + cy * cy,
				l2 = fmax(fmax(b2, c2), (cx - bx) * (cx - bx) + (cy - by) * (cy - by)),
				d = 2 * (bx * cy - by * cx),
				ux,
				uy;

	/* a sliver's centre is ill-conditioned */
	if (!(fabs(d) > 1e-6 * l2))
		return false;
	ux = (cy * b2 - by * c2) / d;
	uy = (bx * c2 - cx * b2) / d;
	/* the error box: far above the rounding of u (relative 1e-9 at this conditioning) */
	*e = 1e-6 * (sqrt(ux * ux + uy * uy) + sqrt(l2)) + f->delta;
	o[0] = a[0] + ux;
	o[1] = a[1] + uy;
	return true;
}

/*
 * Does the circumcentre of triangle a, b, c lie outside the hull, or may
 * it (its error box is not inside, or it is ill-conditioned)?
 */
bool
fr_centre_outside(const fringe *f, const double *a, const double *b, const double *c)
{
	double		o[2],
				e;

	/* a sliver's centre is ill-conditioned: take it */
	if (!fr_centre_box(f, a, b, c, o, &e))
		return true;
	if (e < 0.5 * fmin(f->cw, f->ch) && fr_deep(f, o))
		return false;			/* the box lies in the cell's block, inside */
	for (int k = 0; k < 4; k++)
	{
		double		q[2] = {o[0] + (k & 1 ? e : -e), o[1] + (k & 2 ? e : -e)};

		if (!fr_inside(f, q))
			return true;
	}
	return false;				/* the box's corners are inside: so is the box */
}

static int
fr_flush(fringe *f, char *err, size_t errlen)
{
	if (f->nbuf > 0 && fwrite(f->buf, sizeof(double), f->nbuf, f->f) != f->nbuf)
		return fr_fail(err, errlen, TDC_EIO, "cannot write", f->path);
	f->nbuf = 0;
	return TDC_OK;
}

int
fr_add(fringe *f, const double *p, double z, char *err, size_t errlen)
{
	if (f->nbuf + 3 > sizeof(f->buf) / sizeof(f->buf[0]) && fr_flush(f, err, errlen) != TDC_OK)
		return TDC_EIO;
	f->buf[f->nbuf++] = p[0];
	f->buf[f->nbuf++] = p[1];
	f->buf[f->nbuf++] = z;
	f->written++;
	return TDC_OK;
}

static int
lex_cmp(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	return tdc_lex_less(p, q) ? -1 : tdc_lex_less(q, p) ? 1 : 0;
}

static void
swap3(double *a, double *b)
{
	double		t[3];

	memcpy(t, a, sizeof(t));
	memcpy(a, b, sizeof(t));
	memcpy(b, t, sizeof(t));
}

/*
 * The k-d tree, implicit: in s[lo, hi) the middle triple splits the rest by
 * coordinate `axis` (the part before it <= it, the part after >=), and each
 * part is a tree on the other axis.  Quickselect with a three-way
 * partition, so that many sites on one line (a hull side along x) cost no
 * more than any others.
 */
static void
kd_build(double *s, size_t lo, size_t hi, int axis)
{
	size_t		mid = lo + (hi - lo) / 2,
				l = lo,
				r = hi;			/* the median lies in [l, r) */

	if (hi - lo < 2)
		return;
	while (r - l > 1)
	{
		double		pv = s[3 * (l + (r - l) / 2) + axis];
		size_t		lt = l,		/* [l, lt) < pv, [lt, i) == pv, [gt, r) > pv */
					i = l,
					gt = r;

		while (i < gt)
		{
			double		v = s[3 * i + axis];

			if (v < pv)
				swap3(s + 3 * lt++, s + 3 * i++);
			else if (v > pv)
				swap3(s + 3 * i, s + 3 * --gt);
			else
				i++;
		}
		if (mid < lt)
			r = lt;
		else if (mid >= gt)
			l = gt;
		else
			break;				/* s[mid] == pv: in place */
	}
	kd_build(s, lo, mid, !axis);
	kd_build(s, mid + 1, hi, !axis);
}

int
fr_load(fringe *f, size_t max_bytes, char *err, size_t errlen)
{
	size_t		n = f->written,
				k = 0;

	if (f->loaded)
		return TDC_OK;
	if (fr_flush(f, err, errlen) != TDC_OK)
		return TDC_EIO;
	/* the triples, and as much again for the sort */
	if (n > max_bytes / 48)
	{
		if (err && errlen)
			snprintf(err, errlen, "the %zu sites along the hull that pixels outside it may take "
					 "need %zu MB, beyond the limit's %zu MB left for them", n,
					 (n * 48 >> 20) + 1, max_bytes >> 20);
		return TDC_EMEMLIMIT;
	}
	f->site = malloc(24 * n + 24);
	if (f->site == NULL)
		return fr_fail(err, errlen, TDC_ENOMEM, "out of memory for the hull's sites", NULL);
	if (fflush(f->f) != 0 || fseek(f->f, 0, SEEK_SET) != 0 ||
		fread(f->site, 24, n, f->f) != n)
		return fr_fail(err, errlen, TDC_EIO, "cannot read back", f->path);
	qsort(f->site, n, 24, lex_cmp);
	for (size_t i = 0; i < n; i++)
		if (k == 0 || lex_cmp(f->site + 3 * i, f->site + 3 * (k - 1)) != 0)
			memmove(f->site + 3 * k++, f->site + 3 * i, 24);
	f->nsite = k;
	kd_build(f->site, 0, k, 0);
	f->loaded = true;
	return TDC_OK;
}

/* Is s nearer to q than best, or as near and first in (x, y) order (exactly)? */
bool
fr_better(const double *q, const double *s, const double *best)
{
	int			c;

	if (best == NULL)
		return true;
	c = tdc_sqdist_cmp(q, s, q, best);
	return c < 0 || (c == 0 && tdc_lex_less(s, best));
}

static double
fdist2(const double *q, const double *s)
{
	double		dx = q[0] - s[0],
				dy = q[1] - s[1];

	return dx * dx + dy * dy;
}

/*
 * The search: a part is skipped only when its side of the split is
 * farther than the best by more than the float error, so that no site as
 * near as the best (a tie) is ever skipped.
 */
static void
kd_near(const double *s, size_t lo, size_t hi, int axis, const double *q, const double **best,
		double *bd)
{
	size_t		mid;
	double		dx;

	if (hi <= lo)
		return;
	mid = lo + (hi - lo) / 2;
	if (fr_better(q, s + 3 * mid, *best))
	{
		*best = s + 3 * mid;
		*bd = fdist2(q, *best);
	}
	dx = q[axis] - s[3 * mid + axis];
	if (dx < 0)
	{
		kd_near(s, lo, mid, !axis, q, best, bd);
		if (dx * dx <= *bd * (1 + 1e-9))
			kd_near(s, mid + 1, hi, !axis, q, best, bd);
	}
	else
	{
		kd_near(s, mid + 1, hi, !axis, q, best, bd);
		if (dx * dx <= *bd * (1 + 1e-9))
			kd_near(s, lo, mid, !axis, q, best, bd);
	}
}

const double *
fr_nearest(const fringe *f, const double *q)
{
	const double *best = NULL;
	double		bd = INFINITY;

	kd_near(f->site, 0, f->nsite, 0, q, &best, &bd);
	return best;
}

void
fr_free(fringe *f)
{
	if (f->f)
		fclose(f->f);
	if (f->path[0])
		unlink(f->path);
	free(f->hull);
	free(f->site);
	memset(f, 0, sizeof(*f));
}
