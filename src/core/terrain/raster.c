/*
 * raster.c
 *		A grid of linear heights from the final triangles of a bounded run
 *		(tdc_raster_*, tdc.h): the whole TIN's grid, to the bit, in the
 *		memory of one tile.
 *
 * Linear interpolation is local.  The value at a pixel centre q is fixed
 * by what holds q in the Delaunay triangulation: a site (its height), the
 * inside of an edge (linear along it, from its end first in (x, y) order)
 * or the inside of a triangle (barycentric, from its first corner in (x, y)
 * order), with max_edge's mask on the triangles; outside the hull, the
 * nearest site's height within the radius.  tin_interp.c finds that by a
 * walk and computes it with the two formulas of tin_lerp.c.  Here each
 * final triangle, as its tile hands it over, finds the pixel centres it
 * holds, by the same exact orientation tests (predicates.h) and computes
 * them with the same two formulas: a triangle of the bounded run is a
 * triangle of the whole one (tile_final.c proves each before it is
 * emitted), so every value is the whole run's double, whatever the tiles.
 * A centre on an edge or at a site is found by every triangle around it,
 * and each writes the same value; one max_edge drops writes nothing but
 * its sites, so the rule "a value when some triangle holding it is kept"
 * holds across tiles as it does in one TIN.
 *
 * The pixels wait in a file of the grid's size, 8 bytes a pixel, each
 * stored as its bits XOR a NaN pattern no height can have (SENT): the file
 * is made sparse, its unwritten zeros read back as "no triangle held this
 * centre", and a grid over a sparse survey takes disk only where it has
 * values.  A tile's pixels are made in a window of rows in memory (its
 * cap is the grid's hold, WIN_MIN or 16 rows), as many windows as its
 * triangles span, each written back as runs of the pixels it set.
 *
 * Rows come out after the run (tdc_raster_rows).  A pixel no triangle held
 * is nodata inside the hull (max_edge dropped it) and outside it takes
 * the nearest site within the radius, found among the sites on the hull
 * and those of the triangles whose circumcentre lies outside it (fringe.c),
 * which each tile's triangles add to as they pass.
 *
 * Natural neighbour takes the same pixels, sites and hull edges included;
 * the others are marked (RS_NN_MARK) and raster_natural.c fills them from
 * the tile's whole triangulation before the window is written.
 */
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/predicates.h"
#include "raster_int.h"
#include "tin/tin_lerp.h"

#define SENT		RS_SENT		/* a signalling NaN's bits */
#define WIN_MIN		((size_t) 2 << 20)	/* bytes of a tile's window, at least */



static bool
coord_ok(double c)
{
	double		a = fabs(c);

	return c == 0 || (a >= TDC_COORD_MIN && a <= TDC_COORD_MAX);
}


int
tdc_raster_begin(const tdc_interp_spec *spec, const tdc_grid_spec *g, const double *hull,
				 size_t nhull, const char *tmpdir, tdc_raster **out, size_t *hold,
				 char *err, size_t errlen)
{
	tdc_raster *r;
	double		q[2];
	int			rc;

	*out = NULL;
	*hold = 0;
	if (spec->breaklines)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "a grid in tiles cannot take breaklines: "
					"they need the whole constrained triangulation");
	if (!(g->gt[1] > 0 && g->gt[5] < 0 && g->gt[2] == 0 && g->gt[4] == 0) ||
		g->width == 0 || g->height == 0 || g->width > SIZE_MAX / 32 / g->height ||
		g->height > UINT32_MAX || g->width > UINT32_MAX)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "a grid in tiles must be north-up, with pixels");
	for (int k = 0; k < 4; k++)
	{
		rs_centre(g->gt, k & 1 ? g->width - 1 : 0, k & 2 ? g->height - 1 : 0, q);
		if (!coord_ok(q[0]) || !coord_ok(q[1]))
		{
			char		c[80];

			snprintf(c, sizeof(c), "(%.17g %.17g)", q[0], q[1]);
			return tdc_rs_fail(err, errlen, TDC_EINVAL, "the pixel centre %s is out of the exact "
						"range of coordinates", c);
		}
	}
	if (nhull < 3)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "the points are one site or on one line: "
					"they have no triangle to grid in tiles");
	if ((r = calloc(1, sizeof(*r))) == NULL)
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory");
	r->fd = -1;
	r->spec = *spec;
	r->g = *g;
	r->inv[0] = 1 / g->gt[1];
	r->inv[1] = 1 / g->gt[5];
	r->slack = 1e-6 + 8 * DBL_EPSILON * ((fabs(g->gt[0]) + fabs(g->gt[3])) / g->gt[1] +
										 (double) g->width + (double) g->height);
	/* linear's and natural neighbour's window (nearest has its own, raster_nearest.c) */
	r->wincap = spec->method == TDC_INTERP_NEAREST ? 0 :
		WIN_MIN / 8 > 16 * g->width ? WIN_MIN / 8 : 16 * g->width;
	r->win = r->wincap > 0 ? malloc(8 * r->wincap) : NULL;
	if (r->wincap > 0 && r->win == NULL)
	{
		free(r);
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the grid's window");
	}
	if ((rc = fr_init(&r->fr, hull, nhull, tmpdir, err, errlen)) != TDC_OK ||
		(spec->method == TDC_INTERP_NEAREST && (rc = tdc_rn_begin(r, err, errlen)) != TDC_OK))
	{
		tdc_raster_free(r);
		return rc;
	}
	snprintf(r->path, sizeof(r->path), "%s/raster", tmpdir);
	r->fd = open(r->path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
	if (r->fd < 0)
	{
		r->path[0] = '\0';
		rc = tdc_rs_fail(err, errlen, TDC_EIO, "cannot create %s/raster", tmpdir);
		tdc_raster_free(r);
		return rc;
	}
	if (ftruncate(r->fd, (off_t) (RS_REC(r) * g->width * g->height)) != 0)
	{
		rc = tdc_rs_fail(err, errlen, TDC_EIO, "cannot size the grid's temporary file %s", r->path);
		tdc_raster_free(r);
		return rc;
	}
	*out = r;
	*hold = sizeof(*r) + 8 * r->wincap + FR_HOLD(nhull) + tdc_rn_hold(r) +
		(spec->method == TDC_INTERP_NATURAL ? RS_NN_HOLD : 0);
	return TDC_OK;
}


static inline void
put(uint64_t *w, double v)
{
	memcpy(w, &v, 8);
}

/*
 * The pixels of one triangle (p counter-clockwise) in the window's rows
 * [w0, w1) (columns [c0, c0 + wcols)): each centre it holds, closed, gets
 * its value when max_edge keeps it (none of its edges is long), else only
 * a centre at one of its sites gets a value, the site's.  The columns and
 * rows are those whose centres lie in its box, found in floating point and
 * widened by slack, far more than the rounding of that (a millionth of a
 * pixel, more where the coordinates dwarf the pixels: the tile's, from its
 * largest coordinates); the exact tests decide.  A triangle of dense
 * samples holds no centre at all most often: its range of columns or rows
 * is then empty (the first column is the ceiling of the box's left side in
 * centres, not its floor), and it costs four products and no orientation
 * test.
 */
static void
tri_pixels(const tdc_raster *r, const double *const p[3], const double z[3], double slack,
		   size_t w0, size_t w1, size_t c0, size_t wcols, uint64_t *win)
{
	bool		kept = true;
	const double *gt = r->g.gt;
	double		xmin = fmin(fmin(p[0][0], p[1][0]), p[2][0]),
				xmax = fmax(fmax(p[0][0], p[1][0]), p[2][0]),
				ymin = fmin(fmin(p[0][1], p[1][1]), p[2][1]),
				ymax = fmax(fmax(p[0][1], p[1][1]), p[2][1]);
	double		fc0 = ceil((xmin - gt[0]) * r->inv[0] - 0.5 - slack),
				fc1 = floor((xmax - gt[0]) * r->inv[0] - 0.5 + slack),
				fr0 = ceil((ymax - gt[3]) * r->inv[1] - 0.5 - slack),
				fr1 = floor((ymin - gt[3]) * r->inv[1] - 0.5 + slack);
	size_t		ca,
				cb,
				ra,
				rb;

	if (fc0 > fc1 || fr0 > fr1 ||
		fc1 < (double) c0 || fc0 >= (double) (c0 + wcols) || fr1 < (double) w0 || fr0 >= (double) w1)
		return;
	/* max_edge, only for a triangle that may hold a centre */
	for (int k = 0; r->spec.max_edge > 0 && k < 3 && kept; k++)
		kept = !tdc_rs_edge_long(p[k], p[(k + 1) % 3], r->spec.max_edge);
	ca = fc0 > (double) c0 ? (size_t) fc0 : c0;
	cb = fc1 < (double) (c0 + wcols - 1) ? (size_t) fc1 : c0 + wcols - 1;
	ra = fr0 > (double) w0 ? (size_t) fr0 : w0;
	rb = fr1 < (double) (w1 - 1) ? (size_t) fr1 : w1 - 1;
	for (size_t row = ra; row <= rb; row++)
		for (size_t col = ca; col <= cb; col++)
		{
			double		q[2],
						o[3];
			int			zeros = 0,
						zk = -1;
			uint64_t   *w = win + (row - w0) * wcols + (col - c0);

			rs_centre(gt, col, row, q);
			for (int k = 0; k < 3; k++)
			{
				o[k] = tdc_orient2d(p[k], p[(k + 1) % 3], q);
				if (o[k] == 0)
				{
					zeros++;
					zk = zk < 0 ? k : zk;
				}
			}
			if (o[0] < 0 || o[1] < 0 || o[2] < 0)
				continue;
			if (zeros == 2)
			{
				/* at a corner: edge zk and the other zero's edge meet at it */
				int			v = (o[(zk + 1) % 3] == 0) ? (zk + 1) % 3 : zk;

				put(w, z[v]);
			}
			else if (!kept)
				continue;		/* a long edge: the triangle's other pixels are not its */
			else if (r->spec.method == TDC_INTERP_NATURAL && (zeros == 0 || !fr_on_hull(&r->fr, q)))
				*w = RS_NN_MARK;	/* the cavity's value, raster_natural.c */
			else if (zeros == 1)
				put(w, tin_lerp_xy(p[zk], z[zk], p[(zk + 1) % 3], z[(zk + 1) % 3], q));
			else
				put(w, tin_face_xy(p, z, q));
		}
}

/* The window's set pixels, rows [w0, w1), to the file as runs. */
static int
win_flush(tdc_raster *r, size_t w0, size_t w1, size_t c0, size_t wcols, char *err, size_t errlen)
{
	for (size_t row = w0; row < w1; row++)
	{
		uint64_t   *w = r->win + (row - w0) * wcols;

		for (size_t a = 0; a < wcols;)
		{
			size_t		b;

			if (w[a] == SENT)
			{
				a++;
				continue;
			}
			for (b = a; b < wcols && w[b] != SENT; b++)
				w[b] ^= SENT;
			if (pwrite(r->fd, w + a, 8 * (b - a), (off_t) (8 * (row * r->g.width + c0 + a))) !=
				(ssize_t) (8 * (b - a)))
				return tdc_rs_fail(err, errlen, TDC_EIO, "cannot write the grid's temporary file %s",
							r->path);
			a = b;
		}
	}
	return TDC_OK;
}

int
tdc_raster_tile(tdc_raster *r, const double *q, const double *qz, const size_t *tri, size_t ntri,
				char *err, size_t errlen)
{
	if (r->spec.method == TDC_INTERP_NATURAL)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "a natural neighbour grid takes each tile's "
					"whole triangulation (tdc_raster_nn_tile), not only its final triangles");
	return tdc_rs_tile(r, q, qz, tri, ntri, NULL, NULL, err, errlen);
}

/*
 * The pixels of a tile's final triangles, window by window; fill (natural
 * neighbour: NULL otherwise) replaces each RS_NN_MARK of a window before
 * it is written.
 */
int
tdc_rs_tile(tdc_raster *r, const double *q, const double *qz, const size_t *tri, size_t ntri,
			rs_fill_fn fill, void *arg, char *err, size_t errlen)
{
	const double *gt = r->g.gt;
	double		xmin = INFINITY,
				xmax = -INFINITY,
				ymin = INFINITY,
				ymax = -INFINITY,
				slack,
				tslack,
				f;
	size_t		c0,
				c1,
				r0,
				r1,
				wcols,
				wrows;
	int			rc;

	if (ntri == 0)
		return TDC_OK;
	if (r->spec.method == TDC_INTERP_NEAREST)
		return tdc_rn_tile(r, q, qz, tri, ntri, err, errlen);
	/* the fringe's sites, and the tile's box */
	for (size_t t = 0; t < ntri; t++)
	{
		const size_t *v = tri + 3 * t;

		for (int k = 0; k < 3; k++)
		{
			xmin = fmin(xmin, q[2 * v[k]]);
			xmax = fmax(xmax, q[2 * v[k]]);
			ymin = fmin(ymin, q[2 * v[k] + 1]);
			ymax = fmax(ymax, q[2 * v[k] + 1]);
		}
		if (r->spec.radius != 0)
		{
			/* the corners of a triangle whose circumcentre leaves the hull, and sites on it */
			bool		all = fr_centre_outside(&r->fr, q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]);

			for (int k = 0; k < 3; k++)
				if ((all || fr_on_hull(&r->fr, q + 2 * v[k])) &&
					(rc = fr_add(&r->fr, q + 2 * v[k], qz[v[k]], err, errlen)) != TDC_OK)
					return rc;
		}
	}
	/* the tile's columns and rows, more each way than its box needs (tri_pixels' slack and one) */
	tslack = r->slack + 8 * DBL_EPSILON * (fmax(fabs(xmin), fabs(xmax)) + fmax(fabs(ymin), fabs(ymax))) / gt[1];
	slack = 3 + 8 * DBL_EPSILON * (fabs(gt[0]) + fabs(gt[3]) + fmax(fabs(xmin), fabs(xmax)) +
								   fmax(fabs(ymin), fabs(ymax))) / gt[1];
	f = floor((xmin - gt[0]) / gt[1] - slack);
	c0 = f > 0 ? (f < (double) r->g.width ? (size_t) f : r->g.width) : 0;
	f = ceil((xmax - gt[0]) / gt[1] + slack);
	c1 = f > 0 ? (f < (double) r->g.width ? (size_t) f : r->g.width) : 0;
	f = floor((ymax - gt[3]) / gt[5] - slack);
	r0 = f > 0 ? (f < (double) r->g.height ? (size_t) f : r->g.height) : 0;
	f = ceil((ymin - gt[3]) / gt[5] + slack);
	r1 = f > 0 ? (f < (double) r->g.height ? (size_t) f : r->g.height) : 0;
	if (c1 <= c0 || r1 <= r0)
		return TDC_OK;
	wcols = c1 - c0;
	wrows = r->wincap / wcols;	/* at least 16: the window holds 16 rows of the grid */
	for (size_t w0 = r0; w0 < r1; w0 += wrows)
	{
		size_t		w1 = w0 + wrows < r1 ? w0 + wrows : r1;

		for (size_t i = 0; i < (w1 - w0) * wcols; i++)
			r->win[i] = SENT;
		for (size_t t = 0; t < ntri; t++)
		{
			const size_t *v = tri + 3 * t;
			const double *p[3] = {q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]};
			double		z[3] = {qz[v[0]], qz[v[1]], qz[v[2]]};

			tri_pixels(r, p, z, tslack, w0, w1, c0, wcols, r->win);
		}
		if (fill && (rc = fill(arg, w0, w1, c0, wcols, r->win, err, errlen)) != TDC_OK)
			return rc;
		if ((rc = win_flush(r, w0, w1, c0, wcols, err, errlen)) != TDC_OK)
			return rc;
	}
	return TDC_OK;
}

int
tdc_raster_rows(tdc_raster *r, size_t y0, size_t nrows, double *v, size_t *valid, size_t max_bytes,
				char *err, size_t errlen)
{
	size_t		w = r->g.width,
				n = w * nrows;
	int			rc;

	if (RS_FRINGE(r) && (rc = fr_load(&r->fr, max_bytes, err, errlen)) != TDC_OK)
		return rc;
	if (y0 + nrows > r->g.height)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "rows beyond the grid");
	if (r->spec.method == TDC_INTERP_NEAREST)
		return tdc_rn_rows(r, y0, nrows, v, valid, err, errlen);
	for (size_t got = 0; got < 8 * n;)
	{
		ssize_t		k = pread(r->fd, (char *) v + got, 8 * n - got, (off_t) (8 * y0 * w + got));

		if (k <= 0)
			return tdc_rs_fail(err, errlen, TDC_EIO, "cannot read the grid's temporary file %s", r->path);
		got += (size_t) k;
	}
	for (size_t i = 0; i < n; i++)
	{
		uint64_t	b;
		double		q[2];
		const double *s;

		memcpy(&b, v + i, 8);
		if (b != 0)
		{
			b ^= SENT;
			memcpy(v + i, &b, 8);
			(*valid)++;
			continue;
		}
		/* no triangle held this centre: nodata inside the hull, the nearest site outside */
		v[i] = r->spec.nodata;
		rs_centre(r->g.gt, i % w, y0 + i / w, q);
		if (r->spec.radius == 0 || fr_inside(&r->fr, q))
			continue;
		if ((s = fr_nearest(&r->fr, q)) == NULL)
			continue;
		if (r->spec.radius > 0)
		{
			double		rr[2] = {r->spec.radius, 0},
						o[2] = {0, 0};

			if (tdc_sqdist_cmp(q, s, rr, o) > 0)
				continue;
		}
		v[i] = s[2];
		(*valid)++;
	}
	return TDC_OK;
}

void
tdc_raster_free(tdc_raster *r)
{
	if (r == NULL)
		return;
	if (r->fd >= 0)
		close(r->fd);
	if (r->path[0])
		unlink(r->path);
	fr_free(&r->fr);
	free(r->win);
	tdc_rn_free(r);
	free(r);
}
