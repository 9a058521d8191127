/*
 * raster_nearest.c
 *		The nearest site's height on a grid from the final triangles of a
 *		bounded run (tdc_raster_*, method nearest): the whole TIN's grid, to
 *		the bit, in the memory of one tile.
 *
 * The site nearest to a pixel centre q is not always a corner of the
 * triangle that holds q, and the whole TIN finds it by a walk
 * (tin_nearest).  A bounded run has only its tiles.  But it is a corner of
 * a triangle near q, in this sense: q lies in the Voronoi cell of its
 * nearest site s, and (for q inside the hull) in the region
 *		R_T = conv(T and its circumcentre c_T)
 * of some Delaunay triangle T around s.  Proof: the circumcentres of the
 * triangles around s cut its cell into kites s c c' of consecutive
 * triangles T, T' (sharing the edge s u, whose midpoint is m; c and c' lie
 * on the bisector of s u).  Such a kite lies in s c m and s m c' together,
 * or in the larger of the two when m is not between c and c'.  And s c m
 * lies in R_T: when c is inside T, s, c and m are in T; when it is beyond
 * an edge (the longest, opposite T's obtuse angle), R_T is the convex
 * quadrilateral of T and c, which holds s, c and m.  Where s is on the
 * hull, the unbounded rest of its cell meets the hull only in s c m of the
 * hull edge's triangle.  So when every triangle offers the pixels of R_T
 * the nearest of its three corners, and each pixel keeps the nearest offer
 * (exact distance comparisons, ties to the site first in (x, y) order:
 * tin_nearest's rule), every pixel inside the hull ends with its nearest
 * site, whatever the tiles and their order.  Outside the hull the fringe
 * gives it (fringe.c), as for linear.
 *
 * A superset of R_T serves as well (an offer that is not nearest loses),
 * so R_T is covered in floating point with room to spare: T and the box
 * of c_T's error (fr_centre_box), row by row, widened by a column each
 * way and clipped to the hull's span of each row (widened too); on a
 * skewed grid a row is a band in pixel coordinates (rs_pixel), wide
 * enough for the rounding of the mapping ("The geometry of rows" below).
 * A sliver, whose centre is ill-conditioned, offers T and, beyond each
 * edge whose opposite angle may be obtuse (a dot product's sign, with its
 * rounding), a strip as wide as the edge, reaching past the hull's box:
 * c_T lies on the edge's bisector, so R_T's part beyond the edge is in
 * that strip.
 *
 * max_edge masks as it does linear: a pixel has a value when it is at a
 * site or some closed triangle holding it keeps its edges (the same exact
 * orientations as raster.c's), and the value is the nearest site's.
 *
 * The offers wait in a file of 32 bytes a pixel (the site's x, y and
 * height, and flags: an offer came, the mask holds it), sparse like
 * linear's; a tile reads the rows its triangles reach into a window, in
 * pieces when they do not fit, updates them and writes back the rows it
 * changed.  Rows come out after the run (tdc_rn_rows).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/predicates.h"
#include "raster_int.h"

#define NWIN_MIN	((size_t) 4 << 20)	/* bytes of a tile's window of records, at least */
#define F_OFFER		1				/* a record's flags: a site was offered */
#define F_MASK		2				/* a kept triangle (or a site) holds the centre */
#define PIECE_MAX	7				/* points of a piece of R_T's cover */

/* A convex piece of the region a triangle offers its corners to. */
typedef struct piece
{
	double		v[PIECE_MAX][2];
	int			n;
	double		box[4];			/* xmin, ymin, xmax, ymax */
	double		pv[PIECE_MAX][2];	/* a skewed grid's: v in pixel coordinates (rs_pixel) */
	double		pbox[4];		/* and their box */
	double		sl;				/* the rounding of rs_pixel for its points (rs_slack_at) */
} piece;

static int
rn_io(char *err, size_t errlen, const char *what, const struct tdc_raster *r)
{
	return tdc_rs_fail(err, errlen, TDC_EIO, what, r->path);
}

/*
 * The geometry of rows and columns.  Without skew it is the world's: a
 * row's centres lie exactly on the line y = gt[3] + (row + 0.5) gt[5], as
 * rs_centre computes them, and a column's x maps to pixels by one
 * division.  A skewed grid's row is not a line of the world's doubles:
 * there the points go to pixel coordinates (rs_pixel, off by at most sl,
 * the centre's own rounding included: rs_slack_at, raster.c's
 * pixel_matrix), and a row is the band of half-width sl around row + 0.5,
 * which holds the mapped point of each of its centres that a convex
 * region of those points holds.  Either way the columns and rows found
 * are widened by sl and one more: supersets, the exact tests deciding.
 * sl is r->nslack for the hull and what lies within deep of its box, a
 * piece's own beyond (a circumcentre may lie farther).
 */

/* Cells [*a, *b] of 0 .. n - 1 whose centres (index + 0.5) may lie in [lo, hi] (slack sl); false: none. */
static bool
cells(double lo, double hi, double sl, size_t n, size_t *a, size_t *b)
{
	double		f0 = floor(lo - 0.5 - (sl + 1)),
				f1 = ceil(hi - 0.5 + (sl + 1));

	if (f1 < 0 || f0 > (double) (n - 1))
		return false;
	*a = f0 > 0 ? (size_t) f0 : 0;
	*b = f1 < (double) (n - 1) ? (size_t) f1 : n - 1;
	return true;
}

/*
 * The x range [*xl, *xr] (widened from what they hold) of the convex hull
 * of n points within the band lo <= y <= hi: every pair's segment's part
 * in it.
 */
static void
band_extent(const double (*pt)[2], int n, double lo, double hi, double *xl, double *xr)
{
	for (int i = 0; i < n; i++)
		for (int j = i; j < n; j++)
		{
			const double *a = pt[i],
					   *b = pt[j];

			if (hi < fmin(a[1], b[1]) || lo > fmax(a[1], b[1]))
				continue;
			if (a[1] == b[1])
			{
				*xl = fmin(*xl, fmin(a[0], b[0]));
				*xr = fmax(*xr, fmax(a[0], b[0]));
				continue;
			}
			for (int e = 0; e < (hi > lo ? 2 : 1); e++)
			{
				double		x = a[0] + fmin(fmax(((e ? hi : lo) - a[1]) / (b[1] - a[1]), 0), 1) * (b[0] - a[0]);

				*xl = fmin(*xl, x);
				*xr = fmax(*xr, x);
			}
		}
}

/* n points (world: pt) to pixel coordinates pv, and their box */
static void
pixel_box(const struct tdc_raster *r, const double (*pt)[2], int n, double (*pv)[2], double *pbox)
{
	pbox[0] = pbox[1] = INFINITY;
	pbox[2] = pbox[3] = -INFINITY;
	for (int k = 0; k < n; k++)
	{
		rs_pixel(r, pt[k], pv[k]);
		pbox[0] = fmin(pbox[0], pv[k][0]);
		pbox[1] = fmin(pbox[1], pv[k][1]);
		pbox[2] = fmax(pbox[2], pv[k][0]);
		pbox[3] = fmax(pbox[3], pv[k][1]);
	}
}

/* A grid without skew: world x (y) in [l, h] to columns (rows) */
static bool
axis_cells(const struct tdc_raster *r, int y, double l, double h, size_t *a, size_t *b)
{
	double		fl = (l - r->g.gt[3 * y]) / r->g.gt[1 + 4 * y],
				fh = (h - r->g.gt[3 * y]) / r->g.gt[1 + 4 * y];

	return cells(fmin(fl, fh), fmax(fl, fh), r->nslack, y ? r->g.height : r->g.width, a, b);
}

/*
 * The rows a box (world; pbox: its points' in pixel coordinates with
 * slack sl, for a skewed grid) may reach
 */
static bool
box_rows(const struct tdc_raster *r, const double *box, const double *pbox, double sl, size_t *ra,
		 size_t *rb)
{
	return r->axis ? axis_cells(r, 1, box[1], box[3], ra, rb) :
		cells(pbox[1], pbox[3], sl, r->g.height, ra, rb);
}

/*
 * The pixel columns' range [*ul, *ur] in row row of the convex hull of n
 * points (pt: world, pv: pixel coordinates with slack sl, for a skewed
 * grid); false: it misses the row.
 */
static bool
row_extent(const struct tdc_raster *r, const double (*pt)[2], const double (*pv)[2], int n, size_t row,
		   double sl, double *ul, double *ur)
{
	const double *gt = r->g.gt;
	double		xl = INFINITY,
				xr = -INFINITY;

	if (r->axis)
	{
		double		y = gt[3] + ((double) row + 0.5) * gt[5],
					a,
					b;

		band_extent(pt, n, y, y, &xl, &xr);
		if (!(xl <= xr))
			return false;
		a = (xl - gt[0]) / gt[1];
		b = (xr - gt[0]) / gt[1];
		*ul = fmin(a, b);
		*ur = fmax(a, b);
		return true;
	}
	band_extent(pv, n, (double) row + 0.5 - sl, (double) row + 0.5 + sl, &xl, &xr);
	*ul = xl;
	*ur = xr;
	return xl <= xr;
}

int
tdc_rn_begin(struct tdc_raster *r, char *err, size_t errlen)
{
	const double *h = r->fr.hull;
	size_t		width = r->g.width,
				height = r->g.height,
				nh = r->fr.nhull;
	double		far[4];

	r->nwincap = NWIN_MIN / 32 > 16 * width ? NWIN_MIN / 32 : 16 * width;
	r->nwin = malloc(32 * r->nwincap);
	r->span = malloc(2 * sizeof(uint32_t) * height);
	if (r->nwin == NULL || r->span == NULL)
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the grid's window");
	/* past the hull's box from anywhere in it */
	r->deep = 2 * (r->fr.box[2] - r->fr.box[0] + r->fr.box[3] - r->fr.box[1]) + 1;
	/* the rounding of rs_pixel for any point of a piece (pieces_of: within deep of the hull's box) */
	for (int k = 0; k < 4; k++)
		far[k] = r->fr.box[k] + (k < 2 ? -r->deep : r->deep);
	r->nslack = rs_slack_at(r, far);
	for (size_t row = 0; row < height; row++)
	{
		r->span[2 * row] = UINT32_MAX;
		r->span[2 * row + 1] = 0;
	}

	/*
	 * Each row's span of the hull, from each edge's part in the row's line
	 * (or band), widened by the slack and a column: a superset.
	 */
	for (size_t i = 0; i < nh; i++)
	{
		double		e[2][2] = {{h[2 * i], h[2 * i + 1]},
							   {h[2 * ((i + 1) % nh)], h[2 * ((i + 1) % nh) + 1]}},
					pe[2][2],
					box[4] = {fmin(e[0][0], e[1][0]), fmin(e[0][1], e[1][1]),
							  fmax(e[0][0], e[1][0]), fmax(e[0][1], e[1][1])},
					pbox[4];
		size_t		ra,
					rb;

		if (!r->axis)
			pixel_box(r, (const double (*)[2]) e, 2, pe, pbox);
		if (!box_rows(r, box, pbox, r->nslack, &ra, &rb))
			continue;
		for (size_t row = ra; row <= rb; row++)
		{
			double		ul,
						ur,
						c0,
						c1;
			uint32_t	lo,
						hi;

			if (!row_extent(r, (const double (*)[2]) e, (const double (*)[2]) pe, 2, row, r->nslack,
							&ul, &ur))
				continue;
			c0 = floor(ul - 0.5 - (r->nslack + 1));
			c1 = ceil(ur - 0.5 + (r->nslack + 1));

			/*
			 * A part beside the grid stretches the row's span to the
			 * grid's side (clamped, not skipped: a hull wider than the
			 * grid spans the whole row between its sides).
			 */
			lo = c0 <= 0 ? 0 : c0 >= (double) (width - 1) ? (uint32_t) (width - 1) : (uint32_t) c0;
			hi = c1 <= 0 ? 0 : c1 >= (double) (width - 1) ? (uint32_t) (width - 1) : (uint32_t) c1;
			r->span[2 * row] = lo < r->span[2 * row] ? lo : r->span[2 * row];
			r->span[2 * row + 1] = hi > r->span[2 * row + 1] ? hi : r->span[2 * row + 1];
		}
	}
	return TDC_OK;
}

size_t
tdc_rn_hold(const struct tdc_raster *r)
{
	if (r->spec.method != TDC_INTERP_NEAREST)
		return 0;
	return 32 * r->nwincap + 2 * sizeof(uint32_t) * r->g.height;
}

void
tdc_rn_free(struct tdc_raster *r)
{
	free(r->nwin);
	free(r->span);
	r->nwin = NULL;
	r->span = NULL;
}

static void
piece_box(const struct tdc_raster *r, piece *pc)
{
	pc->box[0] = pc->box[2] = pc->v[0][0];
	pc->box[1] = pc->box[3] = pc->v[0][1];
	for (int k = 1; k < pc->n; k++)
	{
		pc->box[0] = fmin(pc->box[0], pc->v[k][0]);
		pc->box[2] = fmax(pc->box[2], pc->v[k][0]);
		pc->box[1] = fmin(pc->box[1], pc->v[k][1]);
		pc->box[3] = fmax(pc->box[3], pc->v[k][1]);
	}
	pc->sl = r->nslack;
	if (!r->axis)
	{
		pixel_box(r, (const double (*)[2]) pc->v, pc->n, pc->pv, pc->pbox);
		pc->sl = fmax(pc->sl, rs_slack_at(r, pc->box));
	}
}

/*
 * The pieces that cover R_T for triangle p (counter-clockwise): one, T
 * with the box of its circumcentre's error, or for a sliver T and a strip
 * beyond each edge whose opposite angle may be obtuse.  Returns their
 * number (at most 4).
 */
static int
pieces_of(const struct tdc_raster *r, const double *const p[3], piece pc[4])
{
	double		o[2],
				e;
	int			np = 1;

	for (int k = 0; k < 3; k++)
	{
		pc[0].v[k][0] = p[k][0];
		pc[0].v[k][1] = p[k][1];
	}
	pc[0].n = 3;
	if (fr_centre_box(&r->fr, p[0], p[1], p[2], o, &e))
	{
		for (int k = 0; k < 4; k++)
		{
			pc[0].v[3 + k][0] = o[0] + (k & 1 ? e : -e);
			pc[0].v[3 + k][1] = o[1] + (k & 2 ? e : -e);
		}
		pc[0].n = 7;
		piece_box(r, &pc[0]);
		return 1;
	}
	piece_box(r, &pc[0]);
	for (int k = 0; k < 3; k++)
	{
		const double *a = p[k],
				   *b = p[(k + 1) % 3],
				   *c = p[(k + 2) % 3];
		double		ux = a[0] - c[0],
					uy = a[1] - c[1],
					vx = b[0] - c[0],
					vy = b[1] - c[1],
					dot = ux * vx + uy * vy,
					bound = 16 * DBL_EPSILON * (fabs(ux) + fabs(uy)) * (fabs(vx) + fabs(vy)),
					ex = b[0] - a[0],
					ey = b[1] - a[1],
					len = sqrt(ex * ex + ey * ey),
					nx,
					ny;

		/* the angle at c is surely acute: the centre is on c's side of a b */
		if (dot > bound || !(len > 0))
			continue;
		/* the right of a -> b is away from c (counter-clockwise) */
		nx = ey / len * r->deep;
		ny = -ex / len * r->deep;
		pc[np].v[0][0] = a[0];
		pc[np].v[0][1] = a[1];
		pc[np].v[1][0] = b[0];
		pc[np].v[1][1] = b[1];
		pc[np].v[2][0] = b[0] + nx;
		pc[np].v[2][1] = b[1] + ny;
		pc[np].v[3][0] = a[0] + nx;
		pc[np].v[3][1] = a[1] + ny;
		pc[np].n = 4;
		piece_box(r, &pc[np]);
		np++;
	}
	return np;
}

/* The columns of row row that a piece may cover; false: none. */
static bool
piece_cols(const struct tdc_raster *r, const piece *pc, size_t row, size_t *ca, size_t *cb)
{
	double		ul,
				ur;

	return row_extent(r, (const double (*)[2]) pc->v, (const double (*)[2]) pc->pv, pc->n, row, pc->sl,
					  &ul, &ur) &&
		cells(ul, ur, pc->sl, r->g.width, ca, cb);
}

/*
 * The nearest of a triangle's corners offered to the pixels of a piece in
 * the window's rows [w0, w1) and columns [c0, c0 + wcols), within the
 * hull's spans; dirty marks the rows changed.
 */
static void
offer_piece(struct tdc_raster *r, const piece *pc, const double *const p[3], const double z[3],
			size_t w0, size_t w1, size_t c0, size_t wcols, uint8_t *dirty)
{
	size_t		ra,
				rb;

	if (!box_rows(r, pc->box, pc->pbox, pc->sl, &ra, &rb) || rb < w0 || ra >= w1)
		return;
	ra = ra > w0 ? ra : w0;
	rb = rb < w1 - 1 ? rb : w1 - 1;
	for (size_t row = ra; row <= rb; row++)
	{
		size_t		ca,
					cb,
					hlo = r->span[2 * row],
					hhi = r->span[2 * row + 1];

		if (hlo > hhi || !piece_cols(r, pc, row, &ca, &cb))
			continue;
		ca = ca > hlo ? ca : hlo;
		cb = cb < hhi ? cb : hhi;
		ca = ca > c0 ? ca : c0;
		cb = cb < c0 + wcols - 1 ? cb : c0 + wcols - 1;
		for (size_t col = ca; col <= cb; col++)
		{
			double		q[2],
					   *rec = r->nwin + 4 * ((row - w0) * wcols + (col - c0));
			int			best = 0;

			rs_centre(r->g.gt, col, row, q);
			for (int k = 1; k < 3; k++)
				if (fr_better(q, p[k], p[best]))
					best = k;
			if (((int) rec[3] & F_OFFER) && !fr_better(q, p[best], rec))
				continue;
			rec[0] = p[best][0];
			rec[1] = p[best][1];
			rec[2] = z[best];
			rec[3] = (double) ((int) rec[3] | F_OFFER);
			dirty[row - w0] = 1;
		}
	}
}

/*
 * max_edge's mask: the centres triangle p holds, closed, as raster.c's
 * tri_pixels finds them; kept (no long edge) marks them all, else only
 * those at its corners.
 */
static void
mask_tri(struct tdc_raster *r, const double *const p[3], bool kept, size_t w0, size_t w1,
		 size_t c0, size_t wcols, uint8_t *dirty)
{
	piece		t = {.n = 3};
	size_t		ra,
				rb;

	for (int k = 0; k < 3; k++)
	{
		t.v[k][0] = p[k][0];
		t.v[k][1] = p[k][1];
	}
	piece_box(r, &t);
	if (!box_rows(r, t.box, t.pbox, t.sl, &ra, &rb) || rb < w0 || ra >= w1)
		return;
	ra = ra > w0 ? ra : w0;
	rb = rb < w1 - 1 ? rb : w1 - 1;
	for (size_t row = ra; row <= rb; row++)
	{
		size_t		ca,
					cb;

		if (!piece_cols(r, &t, row, &ca, &cb))
			continue;
		ca = ca > c0 ? ca : c0;
		cb = cb < c0 + wcols - 1 ? cb : c0 + wcols - 1;
		for (size_t col = ca; col <= cb; col++)
		{
			double		q[2],
					   *rec = r->nwin + 4 * ((row - w0) * wcols + (col - c0));
			int			zeros = 0;
			bool		out = false;

			rs_centre(r->g.gt, col, row, q);
			for (int k = 0; k < 3 && !out; k++)
			{
				double		o = tdc_orient2d(p[k], p[(k + 1) % 3], q);

				out = o < 0;
				zeros += o == 0;
			}
			if (out || (!kept && zeros < 2))
				continue;
			if (!((int) rec[3] & F_MASK))
			{
				rec[3] = (double) ((int) rec[3] | F_MASK);
				dirty[row - w0] = 1;
			}
		}
	}
}

/* Rows [w0, w1), columns [c0, c0 + wcols) of the file into the window. */
static int
win_read(struct tdc_raster *r, size_t w0, size_t w1, size_t c0, size_t wcols, char *err, size_t errlen)
{
	for (size_t row = w0; row < w1; row++)
	{
		char	   *dst = (char *) (r->nwin + 4 * (row - w0) * wcols);
		size_t		n = 32 * wcols;
		off_t		at = (off_t) (32 * (row * r->g.width + c0));

		for (size_t got = 0; got < n;)
		{
			ssize_t		k = pread(r->fd, dst + got, n - got, at + (off_t) got);

			if (k <= 0)
				return rn_io(err, errlen, "cannot read the grid's temporary file %s", r);
			got += (size_t) k;
		}
	}
	return TDC_OK;
}

/* The window's changed rows back to the file. */
static int
win_write(struct tdc_raster *r, size_t w0, size_t w1, size_t c0, size_t wcols, const uint8_t *dirty,
		  char *err, size_t errlen)
{
	for (size_t row = w0; row < w1; row++)
	{
		size_t		n = 32 * wcols;

		if (dirty[row - w0] &&
			pwrite(r->fd, r->nwin + 4 * (row - w0) * wcols, n, (off_t) (32 * (row * r->g.width + c0))) !=
			(ssize_t) n)
			return rn_io(err, errlen, "cannot write the grid's temporary file %s", r);
	}
	return TDC_OK;
}

int
tdc_rn_tile(struct tdc_raster *r, const double *q, const double *qz, const size_t *tri, size_t ntri,
			char *err, size_t errlen)
{
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
				pbox[4] = {0, 0, 0, 0};
	size_t		r0,
				r1,
				c0 = SIZE_MAX,
				c1 = 0,
				wcols,
				wrows;
	uint8_t    *dirty;
	int			rc = TDC_OK;

	/* the fringe's sites, and the box of the pieces (within the hull's) */
	for (size_t t = 0; t < ntri; t++)
	{
		const size_t *v = tri + 3 * t;
		const double *p[3] = {q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]};
		bool		all = fr_centre_outside(&r->fr, p[0], p[1], p[2]);
		piece		pc[4];
		int			np = pieces_of(r, p, pc);

		for (int k = 0; k < 3; k++)
			if ((all || fr_on_hull(&r->fr, p[k])) &&
				(rc = fr_add(&r->fr, p[k], qz[v[k]], err, errlen)) != TDC_OK)
				return rc;
		for (int i = 0; i < np; i++)
		{
			box[0] = fmin(box[0], fmax(pc[i].box[0], r->fr.box[0]));
			box[1] = fmin(box[1], fmax(pc[i].box[1], r->fr.box[1]));
			box[2] = fmax(box[2], fmin(pc[i].box[2], r->fr.box[2]));
			box[3] = fmax(box[3], fmin(pc[i].box[3], r->fr.box[3]));
		}
	}
	{
		double		corner[4][2] = {{box[0], box[1]}, {box[2], box[1]}, {box[0], box[3]}, {box[2], box[3]}},
					pc4[4][2];

		if (!r->axis)
			pixel_box(r, (const double (*)[2]) corner, 4, pc4, pbox);
	}
	if (!box_rows(r, box, pbox, r->nslack, &r0, &r1))
		return TDC_OK;
	for (size_t row = r0; row <= r1; row++)
		if (r->span[2 * row] <= r->span[2 * row + 1])
		{
			c0 = r->span[2 * row] < c0 ? r->span[2 * row] : c0;
			c1 = r->span[2 * row + 1] > c1 ? r->span[2 * row + 1] : c1;
		}
	{
		size_t		ba,
					bb;

		/* the hull's columns in those rows, within the box's */
		if (c0 > c1 || !(r->axis ? axis_cells(r, 0, box[0], box[2], &ba, &bb) :
						 cells(pbox[0], pbox[2], r->nslack, r->g.width, &ba, &bb)))
			return TDC_OK;
		c0 = c0 > ba ? c0 : ba;
		c1 = c1 < bb ? c1 : bb;
		if (c0 > c1)
			return TDC_OK;
	}
	wcols = c1 - c0 + 1;
	wrows = r->nwincap / wcols;	/* at least 16: the window holds 16 rows of the grid */
	dirty = malloc(wrows);
	if (dirty == NULL)
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory");
	for (size_t w0 = r0; w0 <= r1 && rc == TDC_OK; w0 += wrows)
	{
		size_t		w1 = w0 + wrows <= r1 + 1 ? w0 + wrows : r1 + 1;

		memset(dirty, 0, wrows);
		if ((rc = win_read(r, w0, w1, c0, wcols, err, errlen)) != TDC_OK)
			break;
		for (size_t t = 0; t < ntri; t++)
		{
			const size_t *v = tri + 3 * t;
			const double *p[3] = {q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]};
			double		z[3] = {qz[v[0]], qz[v[1]], qz[v[2]]};
			piece		pc[4];
			int			np = pieces_of(r, p, pc);

			for (int i = 0; i < np; i++)
				offer_piece(r, &pc[i], p, z, w0, w1, c0, wcols, dirty);
			if (r->spec.max_edge > 0)
			{
				bool		kept = true;

				for (int k = 0; k < 3 && kept; k++)
					kept = !tdc_rs_edge_long(p[k], p[(k + 1) % 3], r->spec.max_edge);
				mask_tri(r, p, kept, w0, w1, c0, wcols, dirty);
			}
		}
		rc = win_write(r, w0, w1, c0, wcols, dirty, err, errlen);
	}
	free(dirty);
	return rc;
}

/* Is site s within the radius of q (tin_interp.c's rule: < 0 any distance; nearest's is never 0)? */
static bool
within(const struct tdc_raster *r, const double *q, const double *s)
{
	double		rr[2] = {r->spec.radius, 0},
				o[2] = {0, 0};

	if (r->spec.radius < 0)
		return true;
	return r->spec.radius > 0 && tdc_sqdist_cmp(q, s, rr, o) <= 0;
}

int
tdc_rn_rows(struct tdc_raster *r, size_t y0, size_t nrows, double *v, size_t *valid, char *err,
			size_t errlen)
{
	size_t		w = r->g.width;
	int			rc;

	for (size_t row = y0; row < y0 + nrows; row++)
	{
		double	   *out = v + (row - y0) * w;

		if ((rc = win_read(r, row, row + 1, 0, w, err, errlen)) != TDC_OK)
			return rc;
		for (size_t col = 0; col < w; col++)
		{
			const double *rec = r->nwin + 4 * col,
					   *s;
			int			flags = (int) rec[3];
			double		q[2];

			out[col] = r->spec.nodata;
			rs_centre(r->g.gt, col, row, q);
			if (fr_inside_fast(&r->fr, q))
			{
				/* inside the hull: the nearest offer, where the mask holds the centre */
				if (r->spec.max_edge > 0 && !(flags & F_MASK))
					continue;
				if (!(flags & F_OFFER))
					return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "internal error: a pixel "
									   "inside the hull was offered no site");
				s = rec;
			}
			else if ((s = fr_nearest(&r->fr, q)) == NULL)
				continue;
			if (!within(r, q, s))
				continue;
			out[col] = s[2];
			(*valid)++;
		}
	}
	return TDC_OK;
}
