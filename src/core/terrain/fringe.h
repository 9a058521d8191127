/*
 * fringe.h
 *		The points' convex hull as a bounded grid sees it (fringe.c): which
 *		pixel centres lie outside it, and the site nearest to one that does,
 *		from the few sites whose triangles reach past the hull.  Private to
 *		terrain/.
 */
#ifndef TDC_TERRAIN_FRINGE_H
#define TDC_TERRAIN_FRINGE_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define FR_CELLS	256			/* cells a side, over the hull's box */

typedef struct fringe
{
	double	   *hull;			/* nhull >= 3 x,y pairs, counter-clockwise (a copy) */
	size_t		nhull;
	double		box[4];			/* the hull's box */
	double		cw,
				ch,				/* an inner cell's width and height */
				icw,
				ich,			/* 1 / cw, 1 / ch (a cell off by one in rounding is still deep's) */
				delta;			/* beside a circumcentre's error bound: the coordinates' rounding */
	uint8_t		deep[FR_CELLS * FR_CELLS];	/* 1: the cell and its 8 neighbours lie inside the hull */

	/* the candidate sites: appended while tiles come, loaded for the nearest */
	char		path[4200];
	FILE	   *f;
	double		buf[3 * 1024];
	size_t		nbuf,			/* doubles in buf */
				written;		/* sites written (copies included) */
	double	   *site;			/* loaded: nsite x,y,z triples, distinct, as a k-d tree */
	size_t		nsite;
	bool		loaded;
} fringe;

/* bytes a fringe holds while tiles come (its write buffer and the hull) */
#define FR_HOLD(nhull)	(sizeof(fringe) + 16 * (nhull))

extern int	fr_init(fringe *f, const double *hull, size_t nhull, const char *dir,
					char *err, size_t errlen);
extern bool fr_inside(const fringe *f, const double *q);
extern bool fr_on_hull(const fringe *f, const double *q);
extern bool fr_inside_fast(const fringe *f, const double *q);
extern bool fr_centre_box(const fringe *f, const double *a, const double *b, const double *c,
						  double o[2], double *e);
extern bool fr_centre_outside(const fringe *f, const double *a, const double *b, const double *c);
extern bool fr_better(const double *q, const double *s, const double *best);
extern int	fr_add(fringe *f, const double *p, double z, char *err, size_t errlen);
extern int	fr_load(fringe *f, size_t max_bytes, char *err, size_t errlen);
extern const double *fr_nearest(const fringe *f, const double *q);
extern void fr_free(fringe *f);

#endif							/* TDC_TERRAIN_FRINGE_H */
