/*
 * raster_int.h
 *		A grid from a bounded run's final triangles (tdc_raster_*, tdc.h):
 *		what raster.c (linear, and the API) and raster_nearest.c (nearest)
 *		share.  Private to terrain/.
 */
#ifndef TDC_TERRAIN_RASTER_INT_H
#define TDC_TERRAIN_RASTER_INT_H

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>

#include "engine/predicates.h"
#include "fringe.h"
#include "tdc.h"

#define RS_WINS			2		/* the bounded run's workers: tdc_bounded.h */

struct tdc_raster
{
	tdc_interp_spec spec;
	tdc_grid_spec g;
	char		path[4200];
	int			fd;				/* the pixels' file: RS_REC(r) bytes a pixel */
	/*
	 * Linear's and natural neighbour's windows of rows, wincap pixels each:
	 * one per tile rasterised at once (linear's: the begin's at_once, at
	 * most RS_WINS; natural neighbour's tiles come one at a time, through
	 * the run's final_run), nwins of them, claimed under mu.  mu also guards the fringe's adds and
	 * nearest's tiles (one at a time), so two workers may hand over their
	 * tiles at once (tdc_raster_tile is thread-safe).
	 */
	uint64_t   *win[RS_WINS];
	bool		win_busy[RS_WINS];
	int			nwins;
	size_t		wincap;
	pthread_mutex_t mu;
	pthread_cond_t cv;			/* a window released */
	double		slack;			/* in pixels: above the rounding of a centre's column or row
								 * (rs_slack_at adds the points' own) */
	double		inv[4];			/* gt's pixel matrix inverted: rs_pixel */
	double		inorm;			/* its largest row sum of magnitudes */
	bool		axis;			/* no skew (gt[2] = gt[4] = 0): the axis-parallel fast paths */
	fringe		fr;

	/* nearest (raster_nearest.c) */
	double	   *nwin;			/* a window of pixel records, nwincap of them */
	size_t		nwincap;
	uint32_t   *span;			/* per row: the hull's first and last column (2 each), widened */
	double		deep;			/* how far a strip beyond an edge may need to reach */
	double		nslack;			/* rs_slack_at the hull's box widened by deep */
};

/*
 * Natural neighbour: a window's pixel whose value its cavity gives
 * (raster_natural.c fills it before the window is written; a NaN no
 * height can be, and not SENT), and the bytes its scratch may hold beside
 * the tile's TIN.
 */
#define RS_NN_MARK		UINT64_C(0x7ff4a1b2c3d4e5f7)
/* a window's pixel not set (raster.c writes it XOR its bits to the file) */
#define RS_SENT			UINT64_C(0x7ff4a1b2c3d4e5f6)
#define RS_NN_HOLD		((size_t) 1 << 20)

/* Fills a window's RS_NN_MARK pixels: rows [w0, w1), columns [c0, c0 + wcols). */
typedef int (*rs_fill_fn) (void *arg, size_t w0, size_t w1, size_t c0, size_t wcols,
						   uint64_t *win, char *err, size_t errlen);

/* raster.c: a tile's final triangles to the grid, fill as above (NULL: linear) */
extern int	tdc_rs_tile(struct tdc_raster *r, const double *q, const double *qz, const size_t *tri,
						size_t ntri, rs_fill_fn fill, void *arg, char *err, size_t errlen);

/* bytes a pixel's record takes in the file: linear's value, or nearest's offer */
#define RS_REC(r)		((r)->spec.method == TDC_INTERP_NEAREST ? (size_t) 32 : (size_t) 8)
/* do the pixels outside the hull take the fringe's nearest site (nearest's radius is never 0)? */
#define RS_FRINGE(r)	((r)->spec.radius != 0)

/* Pixel (col, row)'s centre, the very expression of the whole TIN's grid (tin_interp.c). */
static inline void
rs_centre(const double *gt, size_t col, size_t row, double *q)
{
	double		fy = (double) row + 0.5,
				fx = (double) col + 0.5;

	q[0] = gt[0] + fx * gt[1] + fy * gt[2];
	q[1] = gt[3] + fx * gt[4] + fy * gt[5];
}

/*
 * Point p in pixel coordinates: (col + 0.5, row + 0.5) at pixel (col, row)'s
 * centre, up to rounding that rs_slack_at bounds.  A skewed grid's
 * candidate pixels are found here (a triangle's are those whose centres
 * its corners' box holds), the exact orientation tests of the centres
 * themselves (rs_centre) deciding.
 */
static inline void
rs_pixel(const struct tdc_raster *r, const double *p, double *uv)
{
	double		dx = p[0] - r->g.gt[0],
				dy = p[1] - r->g.gt[3];

	uv[0] = r->inv[0] * dx + r->inv[1] * dy;
	uv[1] = r->inv[2] * dx + r->inv[3] * dy;
}

/* The slack (in pixels) of rs_pixel for points in box (xmin, ymin, xmax, ymax): raster.c's pixel_matrix. */
static inline double
rs_slack_at(const struct tdc_raster *r, const double *box)
{
	return r->slack + 8 * DBL_EPSILON * r->inorm * (fmax(fabs(box[0]), fabs(box[2])) +
													fmax(fabs(box[1]), fabs(box[3])));
}

/* An error's code, with its message (fmt with one string argument) in err. */
static inline int
tdc_rs_fail(char *err, size_t errlen, int code, const char *fmt, const char *arg)
{
	if (err && errlen)
		snprintf(err, errlen, fmt, arg);
	return code;
}

/* Is a -> b longer than max_edge (exactly, as tin_interp.c decides it)? */
static inline bool
tdc_rs_edge_long(const double *a, const double *b, double max_edge)
{
	double		l[2] = {max_edge, 0},
				o[2] = {0, 0};

	return tdc_sqdist_cmp(a, b, l, o) > 0;
}

/* raster_nearest.c */
extern int	tdc_rn_begin(struct tdc_raster *r, char *err, size_t errlen);
extern size_t tdc_rn_hold(const struct tdc_raster *r);
extern int	tdc_rn_tile(struct tdc_raster *r, const double *q, const double *qz, const size_t *tri,
						size_t ntri, char *err, size_t errlen);
extern int	tdc_rn_rows(struct tdc_raster *r, size_t y0, size_t nrows, double *v, size_t *valid,
						char *err, size_t errlen);
extern void tdc_rn_free(struct tdc_raster *r);

#endif							/* TDC_TERRAIN_RASTER_INT_H */
