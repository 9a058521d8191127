/*
 * bounded_policy.h
 *		The tiling policy of a bounded-memory run: which tiles, which
 *		points each tile's first run must know, and how a tile's known
 *		region grows when its run is not final.
 *
 * Pure functions of their arguments: no I/O, no exit, no state of the
 * command line.  They depend on the core's public header only, so that the
 * SQL procedure can share them once they sit in src/core next to the
 * finality check (src/core/tile_final.c) that they serve.
 *
 * The plan is made on a fine grid of BP_GRID x BP_GRID cells over the
 * points' box: a point's cell, hence its tile, is decided exactly against
 * the doubles of the cell sides (bp_cell), so a tile's points lie in its
 * cells' box and its first known region is fixed before the points are
 * placed.  A point's label, the tile that owns it, is the tile of its cell.
 */
#ifndef TDC_BOUNDED_POLICY_H
#define TDC_BOUNDED_POLICY_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tdc.h"

#define BP_GRID			512		/* cells per side of the counting grid */
#define BP_MAX_TILES	900		/* the most tiles a plan may have */

/* The fine grid: its box, scales, cell sizes and the doubles of its cell sides. */
typedef struct bp_grid
{
	double		box[4];
	double		sx,
				sy,				/* cells per unit, 0 on a flat side */
				cw,
				ch;				/* a cell's width and height */
	double		xcut[BP_GRID + 1],
				ycut[BP_GRID + 1];	/* non-decreasing */
} bp_grid;

/* One tile of the plan. */
typedef struct bp_tile
{
	int			c0,
				c1,
				r0,
				r1;				/* cells [c0, c1) x [r0, r1) */
	size_t		count;
	double		bb[4];			/* exact box of its points, once they are placed */
} bp_tile;

/* What bp_plan can refuse. */
typedef enum bp_plan_status
{
	BP_PLAN_OK = 0,
	BP_PLAN_DENSE_CELL,			/* one cell holds more than a tile's share */
	BP_PLAN_TOO_MANY_TILES		/* more than BP_MAX_TILES tiles needed */
} bp_plan_status;

static inline int
bp_fine_cell(double v, double lo, double scale)
{
	int			c = (int) ((v - lo) * scale);

	return c < 0 ? 0 : c >= BP_GRID ? BP_GRID - 1 : c;
}

/*
 * The fine grid's cell of v along one axis: the c with cut[c] <= v <
 * cut[c + 1] (the last cell closed), cut[] the doubles of the cell sides,
 * non-decreasing.  Exact: a tile's cell box holds every point binned to
 * it, so its K and its halo are known before the points are binned.
 */
static inline int
bp_cell_of(double v, double lo, double scale, const double *cut)
{
	int			c = bp_fine_cell(v, lo, scale);

	while (c > 0 && v < cut[c])
		c--;
	while (c < BP_GRID - 1 && v >= cut[c + 1])
		c++;
	return c;
}

/* The index of (x, y)'s cell in a row-major BP_GRID x BP_GRID array. */
static inline int
bp_cell(const bp_grid *g, double x, double y)
{
	return bp_cell_of(y, g->box[1], g->sy, g->ycut) * BP_GRID +
		bp_cell_of(x, g->box[0], g->sx, g->xcut);
}

static inline bool
bp_box_meets(const double *a, const double *b)
{
	return a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3];
}

static inline void
bp_box_add(double *b, double x, double y)
{
	b[0] = fmin(b[0], x);
	b[1] = fmin(b[1], y);
	b[2] = fmax(b[2], x);
	b[3] = fmax(b[3], y);
}

static inline void
bp_box_union(double *b, const double *a)
{
	b[0] = fmin(b[0], a[0]);
	b[1] = fmin(b[1], a[1]);
	b[2] = fmax(b[2], a[2]);
	b[3] = fmax(b[3], a[3]);
}

/* The grid */
extern bool bp_grid_from_sample(double g[4]);
extern void bp_grid_set(bp_grid *g, const double box[4]);
extern bool bp_grid_near(const bp_grid *g, const double bb[4]);
extern void bp_grid_reach(bp_grid *g, const double bb[4]);

/* The plan */
extern size_t bp_tile_bytes(size_t m, const tdc_options *opt, int has_z);
extern size_t bp_tile_max(size_t n, const tdc_options *opt, int has_z, size_t budget);
extern void bp_prefix_sums(const uint32_t *counts, size_t *ps);
extern bp_plan_status bp_plan(const size_t *ps, const bp_grid *g, size_t tile_max,
							  bp_tile *tiles, int *nt);
extern void bp_label_cells(const bp_tile *tiles, int nt, int16_t *cell_tile);

/* The first known region */
extern void bp_hull_bands(const double *hull, size_t nhull, const double bb[4], size_t n,
						  double *bands);
extern void bp_first_known(const bp_tile *ti, const bp_grid *g, const double *bands,
						   size_t nhull, double K[4], double *h, uint8_t *mark);

/* Its growth and shrinking from run to run */
extern void bp_least_known(const bp_tile *ti, const bp_grid *g, double Kmin[4]);
extern void bp_shrink_known(double K[4], const double Kmin[4], int shrinks);
extern size_t bp_grow_bands(const double *bands, size_t nhull, const double need[4],
							uint8_t *inband, double *extra, size_t *nextra);
extern void bp_grow_known(double K[4], double Kmin[4], const double need[4], double h);

#endif							/* TDC_BOUNDED_POLICY_H */
