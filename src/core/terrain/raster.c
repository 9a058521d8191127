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
 * triangles span, each written back as runs of the pixels it set.  Two
 * tiles may come at once (the bounded run's workers): each takes a window
 * of its own, and what they share (the fringe's file, nearest's window)
 * is taken under the raster's lock.
 *
 * The grid may be skewed, rotated or flipped: any geotransform whose
 * pixel matrix is invertible.  Its centres are the one-pass expression
 * (rs_centre) and the exact tests decide membership, so only the search
 * for candidates changes: a triangle's corners go to pixel coordinates
 * through the inverse (rs_pixel), and their box, widened by a bound on
 * the rounding (pixel_matrix proves it), holds every centre the triangle
 * holds.  Without skew the old axis-parallel path stays, flips included.
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


/*
 * The grid's pixel matrix A = (gt[1] gt[2]; gt[4] gt[5]) inverted into r
 * (NULL: only checked), and the slack of rs_pixel.  A singular A (exactly:
 * the sign of its determinant is an orientation) has no pixels to map
 * back, and one so nearly singular that its determinant's rounding is not
 * small (k, below, over 1e12) is refused with it; north-up, flipped or any
 * other grid without skew keeps 1 / gt[1] and 1 / gt[5] as they were.
 *
 * The slack.  Let M be the computed inverse, m its largest row sum of
 * magnitudes, a A's largest entry, u = DBL_EPSILON / 2, and
 * k = (|gt[1] gt[5]| + |gt[2] gt[4]|) / |det| (1 without skew).  A centre
 * q = fl(o + A f) (rs_centre, f = (col + 0.5, row + 0.5), o = (gt[0],
 * gt[3])) is off o + A f by at most 3u (|gt[0]| + |gt[3]| + a (W + H)) a
 * coordinate, so M (q - o) is off f by m times that plus |M A - I| |f|,
 * where M's entries are off A's inverse's by (2k + 1)u relatively (the
 * determinant's and the division's rounding): at most 3u (k + 1) m a
 * (W + H) more.  rs_pixel of a corner p is off M (p - o) by at most
 * 3u m (|p| + |o|).  A centre that a triangle holds is a convex
 * combination of its corners, which M keeps: so its f lies within the
 * corners' rs_pixel box widened by the sum, below
 *		8 DBL_EPSILON (m (|gt[0]| + |gt[3]| + |px| + |py|) + (k + 1) m a (W + H))
 * (4u for each 3u, and the rounding of "- 0.5 - slack" itself, for f
 * within the grid, under its W + H), and 1e-6 of a pixel more for the
 * second-order terms.  r->slack is all but the |px| + |py| term, which
 * rs_slack_at adds for the points at hand.
 */
static int
pixel_matrix(const tdc_grid_spec *g, tdc_raster *r, char *err, size_t errlen)
{
	const double *gt = g->gt;
	double		o[2] = {0, 0},
				c1[2] = {gt[1], gt[4]},
				c2[2] = {gt[2], gt[5]},
				det = gt[1] * gt[5] - gt[2] * gt[4],
				k,
				a;
	char		s[160];

	for (int i = 0; i < 6; i++)
		if (!isfinite(gt[i]))
			return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "the grid's geotransform is not finite");
	k = (fabs(gt[1] * gt[5]) + fabs(gt[2] * gt[4])) / fabs(det);
	if (tdc_orient2d(o, c1, c2) == 0 || !(k <= 1e12))
	{
		snprintf(s, sizeof(s), "(scale %.17g x %.17g, skew %.17g x %.17g)", gt[1], gt[5], gt[2], gt[4]);
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "the grid's pixels have no area: its geotransform "
					"%s is singular or nearly so", s);
	}
	if (r == NULL)
		return TDC_OK;
	r->axis = gt[2] == 0 && gt[4] == 0;
	if (r->axis)
	{
		r->inv[0] = 1 / gt[1];
		r->inv[1] = r->inv[2] = 0;
		r->inv[3] = 1 / gt[5];
	}
	else
	{
		r->inv[0] = gt[5] / det;
		r->inv[1] = -gt[2] / det;
		r->inv[2] = -gt[4] / det;
		r->inv[3] = gt[1] / det;
	}
	r->inorm = fmax(fabs(r->inv[0]) + fabs(r->inv[1]), fabs(r->inv[2]) + fabs(r->inv[3]));
	a = fmax(fmax(fabs(gt[1]), fabs(gt[2])), fmax(fabs(gt[4]), fabs(gt[5])));
	r->slack = 1e-6 + 8 * DBL_EPSILON * (r->inorm * (fabs(gt[0]) + fabs(gt[3])) +
										 (k + 1) * r->inorm * a * ((double) g->width + (double) g->height));
	return TDC_OK;
}

int
tdc_raster_begin(const tdc_interp_spec *spec, const tdc_grid_spec *g, const double *hull,
				 size_t nhull, const char *tmpdir, int at_once, tdc_raster **out, size_t *hold,
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
	if (g->width == 0 || g->height == 0 || g->width > SIZE_MAX / 32 / g->height ||
		g->height > UINT32_MAX || g->width > UINT32_MAX)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "a grid in tiles must have pixels");
	if ((rc = pixel_matrix(g, NULL, err, errlen)) != TDC_OK)
		return rc;
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
	pthread_mutex_init(&r->mu, NULL);
	pthread_cond_init(&r->cv, NULL);
	pixel_matrix(g, r, NULL, 0);
	/* linear's and natural neighbour's windows (nearest has its own, raster_nearest.c) */
	r->wincap = spec->method == TDC_INTERP_NEAREST ? 0 :
		WIN_MIN / 8 > 16 * g->width ? WIN_MIN / 8 : 16 * g->width;
	r->nwins = spec->method == TDC_INTERP_NEAREST ? 0 : spec->method == TDC_INTERP_NATURAL ? 1 :
		at_once < 2 ? 1 : RS_WINS;
	for (int i = 0; i < r->nwins; i++)
		if ((r->win[i] = malloc(8 * r->wincap)) == NULL)
		{
			tdc_raster_free(r);
			return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the grid's windows");
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
	*hold = sizeof(*r) + 8 * (size_t) r->nwins * r->wincap + FR_HOLD(nhull) + tdc_rn_hold(r) +
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
 * rows are those whose centres lie in the box of its corners in pixel
 * coordinates (rs_pixel; without skew, the box of its corners mapped),
 * found in floating point and widened by slack, more than the rounding of
 * that (pixel_matrix's bound, with the tile's largest coordinates); the
 * exact tests decide.  A triangle of dense samples holds no centre at all
 * most often: its range of columns or rows is then empty (the first column
 * is the ceiling of the box's left side in centres, not its floor), and
 * without skew it costs four products and no orientation test.
 */
static void
tri_pixels(const tdc_raster *r, const double *const p[3], const double z[3], double slack,
		   size_t w0, size_t w1, size_t c0, size_t wcols, uint64_t *win)
{
	bool		kept = true;
	const double *gt = r->g.gt;
	double		u[2],
				v[2],
				fc0,
				fc1,
				fr0,
				fr1;
	size_t		ca,
				cb,
				ra,
				rb;

	if (r->axis)
	{
		/* a flipped grid's (gt[1] < 0 or gt[5] > 0) first column or row is at the box's other side */
		double		a = (fmin(fmin(p[0][0], p[1][0]), p[2][0]) - gt[0]) * r->inv[0],
					b = (fmax(fmax(p[0][0], p[1][0]), p[2][0]) - gt[0]) * r->inv[0],
					c = (fmax(fmax(p[0][1], p[1][1]), p[2][1]) - gt[3]) * r->inv[3],
					d = (fmin(fmin(p[0][1], p[1][1]), p[2][1]) - gt[3]) * r->inv[3];

		u[0] = fmin(a, b);
		u[1] = fmax(a, b);
		v[0] = fmin(c, d);
		v[1] = fmax(c, d);
	}
	else
	{
		double		t[3][2];

		for (int k = 0; k < 3; k++)
			rs_pixel(r, p[k], t[k]);
		u[0] = fmin(fmin(t[0][0], t[1][0]), t[2][0]);
		u[1] = fmax(fmax(t[0][0], t[1][0]), t[2][0]);
		v[0] = fmin(fmin(t[0][1], t[1][1]), t[2][1]);
		v[1] = fmax(fmax(t[0][1], t[1][1]), t[2][1]);
	}
	fc0 = ceil(u[0] - 0.5 - slack);
	fc1 = floor(u[1] - 0.5 + slack);
	fr0 = ceil(v[0] - 0.5 - slack);
	fr1 = floor(v[1] - 0.5 + slack);
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

/*
 * The window's set pixels, rows [w0, w1), to the file as runs.  Another
 * tile's window may be written at once: the runs are disjoint but for
 * centres on an edge or at a site between the tiles, where both write the
 * same bits (the essay above), so the file does not depend on the order.
 */
static int
win_flush(tdc_raster *r, uint64_t *win, size_t w0, size_t w1, size_t c0, size_t wcols, char *err,
		  size_t errlen)
{
	for (size_t row = w0; row < w1; row++)
	{
		uint64_t   *w = win + (row - w0) * wcols;

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

/* A window no other tile is using: waits while nwins tiles are being rasterised. */
static uint64_t *
win_claim(tdc_raster *r)
{
	int			i;

	pthread_mutex_lock(&r->mu);
	for (;;)
	{
		for (i = 0; i < r->nwins && r->win_busy[i]; i++)
			;
		if (i < r->nwins)
			break;
		pthread_cond_wait(&r->cv, &r->mu);
	}
	r->win_busy[i] = true;
	pthread_mutex_unlock(&r->mu);
	return r->win[i];
}

static void
win_release(tdc_raster *r, const uint64_t *win)
{
	pthread_mutex_lock(&r->mu);
	for (int i = 0; i < r->nwins; i++)
		if (r->win[i] == win)
			r->win_busy[i] = false;
	pthread_cond_signal(&r->cv);
	pthread_mutex_unlock(&r->mu);
}

/* fr_add for tiles handed over at once: the fringe's file is one */
static int
rs_fringe_add(tdc_raster *r, const double *p, double z, char *err, size_t errlen)
{
	int			rc;

	pthread_mutex_lock(&r->mu);
	rc = fr_add(&r->fr, p, z, err, errlen);
	pthread_mutex_unlock(&r->mu);
	return rc;
}

/* f clamped to [0, n] */
static size_t
grid_index(double f, size_t n)
{
	return f > 0 ? (f < (double) n ? (size_t) f : n) : 0;
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
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
				lo[2] = {INFINITY, INFINITY},
				hi[2] = {-INFINITY, -INFINITY},
				slack,
				tslack;
	size_t		c0,
				c1,
				r0,
				r1,
				wcols,
				wrows;
	uint64_t   *win;
	int			rc = TDC_OK;

	if (ntri == 0)
		return TDC_OK;
	if (r->spec.method == TDC_INTERP_NEAREST)
	{
		pthread_mutex_lock(&r->mu);
		rc = tdc_rn_tile(r, q, qz, tri, ntri, err, errlen);
		pthread_mutex_unlock(&r->mu);
		return rc;
	}
	/* the fringe's sites, and the tile's box */
	for (size_t t = 0; t < ntri; t++)
	{
		const size_t *v = tri + 3 * t;

		for (int k = 0; k < 3; k++)
		{
			box[0] = fmin(box[0], q[2 * v[k]]);
			box[2] = fmax(box[2], q[2 * v[k]]);
			box[1] = fmin(box[1], q[2 * v[k] + 1]);
			box[3] = fmax(box[3], q[2 * v[k] + 1]);
		}
		if (r->spec.radius != 0)
		{
			/* the corners of a triangle whose circumcentre leaves the hull, and sites on it */
			bool		all = fr_centre_outside(&r->fr, q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]);

			for (int k = 0; k < 3; k++)
				if ((all || fr_on_hull(&r->fr, q + 2 * v[k])) &&
					(rc = rs_fringe_add(r, q + 2 * v[k], qz[v[k]], err, errlen)) != TDC_OK)
					return rc;
		}
	}
	/*
	 * The tile's columns and rows: its box's corners in pixel coordinates
	 * (which hold its triangles' corners', M being linear), widened by
	 * tri_pixels' slack three times over (theirs, the corners' and
	 * tri_pixels' own) and three pixels more.
	 */
	tslack = rs_slack_at(r, box);
	slack = 3 + 3 * tslack;
	for (int k = 0; k < 4; k++)
	{
		double		corner[2] = {box[k & 1 ? 2 : 0], box[k & 2 ? 3 : 1]},
					uv[2];

		rs_pixel(r, corner, uv);
		for (int i = 0; i < 2; i++)
		{
			lo[i] = fmin(lo[i], uv[i]);
			hi[i] = fmax(hi[i], uv[i]);
		}
	}
	c0 = grid_index(floor(lo[0] - slack), r->g.width);
	c1 = grid_index(ceil(hi[0] + slack), r->g.width);
	r0 = grid_index(floor(lo[1] - slack), r->g.height);
	r1 = grid_index(ceil(hi[1] + slack), r->g.height);
	if (c1 <= c0 || r1 <= r0)
		return TDC_OK;
	wcols = c1 - c0;
	wrows = r->wincap / wcols;	/* at least 16: the window holds 16 rows of the grid */
	win = win_claim(r);
	for (size_t w0 = r0; w0 < r1 && rc == TDC_OK; w0 += wrows)
	{
		size_t		w1 = w0 + wrows < r1 ? w0 + wrows : r1;

		for (size_t i = 0; i < (w1 - w0) * wcols; i++)
			win[i] = SENT;
		for (size_t t = 0; t < ntri; t++)
		{
			const size_t *v = tri + 3 * t;
			const double *p[3] = {q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]};
			double		z[3] = {qz[v[0]], qz[v[1]], qz[v[2]]};

			tri_pixels(r, p, z, tslack, w0, w1, c0, wcols, win);
		}
		if (fill)
			rc = fill(arg, w0, w1, c0, wcols, win, err, errlen);
		if (rc == TDC_OK)
			rc = win_flush(r, win, w0, w1, c0, wcols, err, errlen);
	}
	win_release(r, win);
	return rc;
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
	for (int i = 0; i < RS_WINS; i++)
		free(r->win[i]);
	tdc_rn_free(r);
	pthread_cond_destroy(&r->cv);
	pthread_mutex_destroy(&r->mu);
	free(r);
}
