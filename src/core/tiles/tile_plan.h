/*
 * tile_plan.h
 *		The tiling policy of the bounded-memory runs (tdc_bounded_run,
 *		which ./tdc --max-memory calls, and tdc_delaunay_tiled): which
 *		tiles, which points each tile's first run must know, how a tile's
 *		known region grows when its run is not final, and the labels of
 *		the tiles.
 *
 * One policy for both callers, next to the finality check
 * (src/core/tiles/tile_final.c) that it serves: the bounded run
 * (src/core/tiles/bounded*.c) calls it directly, the SQL procedure through small
 * C helpers (src/pg/fn/fn_tiled.c).  Pure functions of their arguments: no
 * I/O, no state, no PostgreSQL.
 *
 * The plan is made on a fine grid of TDC_TP_GRID x TDC_TP_GRID cells over the
 * points' box: a point's cell, hence its tile, is decided exactly against
 * the doubles of the cell sides (tdc_tp_cell), so a tile's points lie in its
 * cells' box and its first known region is fixed before the points are
 * placed.  A point's label, the tile that owns it, is the tile of its cell.
 */
#ifndef TDC_TILE_PLAN_H
#define TDC_TILE_PLAN_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tdc.h"

#define TDC_TP_GRID			512		/* cells per side of the counting grid */
_Static_assert((TDC_TP_GRID & (TDC_TP_GRID - 1)) == 0, "tdc_tp_cell_of needs a power of two");
#define TDC_TP_MAX_TILES	900		/* the most tiles a plan may have */
/*
 * The points a tile of m own points may come to hold, its halo and the
 * cells its reruns add included: the plan's growth allowance.  It was 1.5
 * for uniform data; on clustered data a tile's reruns add the cells along
 * its rim, and 10M points in 64 clusters needed 1.8 times a tile's own.
 */
#define TDC_TP_ALLOW(m)		((m) * 5 / 2)
/*
 * The most cells tdc_tp_hull_cells names (an edge takes at most
 * TDC_TP_EDGE_CELLS, a row's columns and the rows)
 */
#define TDC_TP_EDGE_CELLS	(3 * TDC_TP_GRID)
#define TDC_TP_HULL_CELLS	(8 * TDC_TP_EDGE_CELLS)
/* The most points a tile's first K may hold (tdc_tp_known_limit) */
#define TDC_TP_KNOWN_MAX(tile_max)	((tile_max) * 3 / 2)
/*
 * How far a tile's first request for cells reaches past the nearest cell it
 * needs, in that cell's sides (tdc_tile_grid.rings), doubled on every rerun
 * up to TDC_TP_RINGS_MAX.  At 0.5 of the one-shot's peak on ~300,000
 * clustered points, 1 ring took 104 to 250 runs a set, 4 took 62 to 216, 8
 * took 55 to 200 with the peak within 1 % of the limit on 9 tight clusters.
 */
#define TDC_TP_FIRST_RINGS	4
#define TDC_TP_RINGS_MAX	4096
#define TDC_TP_FINISH_BYTES	61		/* tile_final.c's bytes a point, triangles included */
/*
 * The cells' bytes in a tile run: the caller's counts, states and added
 * marks (4 + 1 + 1 a cell), tile_final.c's prefix sums of the OTHER cells
 * and its merge marks (tile_cells.c)
 */
#define TDC_TP_CELLS_BYTES	((size_t) 7 * TDC_TP_GRID * TDC_TP_GRID + \
							 (size_t) 4 * (TDC_TP_GRID + 1) * (TDC_TP_GRID + 1))

/* The fine grid: its box, scales, cell sizes and the doubles of its cell sides. */
typedef struct tdc_tp_grid
{
	double		box[4];
	double		sx,
				sy,				/* cells per unit, 0 on a flat side */
				cw,
				ch;				/* a cell's width and height */
	double		xcut[TDC_TP_GRID + 1],
				ycut[TDC_TP_GRID + 1];	/* non-decreasing */
} tdc_tp_grid;

/* One tile of the plan. */
typedef struct tdc_tp_tile
{
	int			c0,
				c1,
				r0,
				r1;				/* cells [c0, c1) x [r0, r1) */
	size_t		count;
	double		bb[4];			/* exact box of its points, once they are placed */
} tdc_tp_tile;

/* What tdc_tp_plan can refuse. */
typedef enum tdc_tp_plan_status
{
	TDC_TP_PLAN_OK = 0,
	TDC_TP_PLAN_DENSE_CELL,			/* one cell holds more than a tile's share */
	TDC_TP_PLAN_TOO_MANY_TILES		/* more than TDC_TP_MAX_TILES tiles needed */
} tdc_tp_plan_status;

/*
 * The grid's cell of v along one axis: the last c with cut[c] <= v (0 when
 * none), so cut[c] <= v < cut[c + 1] but in the last cell, which is closed
 * (and in the first, for v below cut[0]); cut[] the doubles of the cell
 * sides, non-decreasing (equal cuts make empty cells).  Exact: a tile's
 * cell box holds every point binned to it, so its K and its halo are known
 * before the points are binned.  Neither cut[0] nor cut[TDC_TP_GRID] is
 * read, so widening the outer cells moves no point.  (lo and scale are
 * unused: the cuts are quantiles, not a uniform grid.)
 */
static inline int
tdc_tp_cell_of(double v, double lo, double scale, const double *cut)
{
	int			a = 0;

	(void) lo;
	(void) scale;

	/*
	 * A binary search without branches (TDC_TP_GRID is a power of two): the
	 * invariant is cut[a] <= v or a = 0, and the last c with cut[c] <= v is
	 * below a + 2 * half.  Every point of the scan and of the bins passes
	 * here twice, and the branching search mispredicted half its steps.
	 */
	for (int half = TDC_TP_GRID / 2; half > 0; half /= 2)
		a += cut[a + half] <= v ? half : 0;
	return a;
}

/* The index of (x, y)'s cell in a row-major TDC_TP_GRID x TDC_TP_GRID array. */
static inline int
tdc_tp_cell(const tdc_tp_grid *g, double x, double y)
{
	return tdc_tp_cell_of(y, g->box[1], g->sy, g->ycut) * TDC_TP_GRID +
		tdc_tp_cell_of(x, g->box[0], g->sx, g->xcut);
}

static inline bool
tdc_tp_box_meets(const double *a, const double *b)
{
	return a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3];
}

static inline void
tdc_tp_box_add(double *b, double x, double y)
{
	b[0] = fmin(b[0], x);
	b[1] = fmin(b[1], y);
	b[2] = fmax(b[2], x);
	b[3] = fmax(b[3], y);
}

static inline void
tdc_tp_box_union(double *b, const double *a)
{
	b[0] = fmin(b[0], a[0]);
	b[1] = fmin(b[1], a[1]);
	b[2] = fmax(b[2], a[2]);
	b[3] = fmax(b[3], a[3]);
}

/* The grid */
extern bool tdc_tp_grid_from_sample(double g[4]);
extern void tdc_tp_grid_set(tdc_tp_grid *g, const double box[4]);
extern void tdc_tp_grid_quantiles(tdc_tp_grid *g, const double box[4], double *xs, double *ys,
								  size_t ns);
extern bool tdc_tp_grid_near(const tdc_tp_grid *g, const double bb[4]);
extern void tdc_tp_grid_reach(tdc_tp_grid *g, const double bb[4]);

/* The plan */
extern size_t tdc_tp_tile_bytes(size_t m, const tdc_options *opt, size_t per_point);
extern size_t tdc_tp_tile_max(size_t n, const tdc_options *opt, size_t per_point, size_t budget);
extern void tdc_tp_prefix_sums(const uint32_t *counts, size_t *ps);
extern tdc_tp_plan_status tdc_tp_plan(const size_t *ps, const tdc_tp_grid *g, size_t tile_max,
							  tdc_tp_tile *tiles, int *nt);
extern void tdc_tp_fit_known(const size_t *ps, const tdc_tp_grid *g, const double box[4],
							 size_t count, double spacing, size_t limit, double K[4], double *h);
extern void tdc_tp_fit_bands(const size_t *ps, const tdc_tp_grid *g, const double *bands,
							 size_t nhull, size_t limit, uint8_t *mark);
extern size_t tdc_tp_known_limit(size_t count, size_t tile_max);
extern size_t tdc_tp_box_count(const size_t *ps, const tdc_tp_grid *g, const double box[4]);
extern size_t tdc_tp_hull_limit(size_t count, size_t tile_max, size_t known);
extern tdc_tp_plan_status tdc_tp_plan_fit(const size_t *ps, const tdc_tp_grid *g, size_t tile_max,
										  size_t floor, double spacing, tdc_tp_tile *tiles,
										  int *nt, size_t *fit_max);
extern void tdc_tp_label_cells(const tdc_tp_tile *tiles, int nt, int16_t *cell_tile);

/* The labels of squares of a given size, counted from the grid's origin */
extern bool tdc_tp_square_label(double x, double y, const double origin[2], double size,
								int64_t *label);
extern int	tdc_tp_owner_vertex(const double *a, const double *b, const double *c);

/* The first known region */
extern double tdc_tp_spacing(const double bb[4], size_t n);
extern void tdc_tp_hull_bands(const double *hull, size_t nhull, double spacing, double *bands);
extern void tdc_tp_first_known(const double box[4], size_t count, double spacing,
							   double K[4], double *h);
extern void tdc_tp_first_bands(const double K[4], size_t count, const double *bands,
							   size_t nhull, uint8_t *mark);
extern size_t tdc_tp_hull_cells(const tdc_tp_grid *g, const uint32_t *counts, const tdc_tp_tile *ti,
								const double *hull, size_t nhull, const uint8_t *mark,
								size_t limit, uint32_t *cells);

/* Its growth and shrinking from run to run */
extern void tdc_tp_least_known(const tdc_tp_tile *ti, const tdc_tp_grid *g, double Kmin[4]);
extern void tdc_tp_shrink_known(double K[4], const double Kmin[4], int shrinks);
extern size_t tdc_tp_grow_bands(const double *bands, size_t nhull, const double need[4],
							uint8_t *inband, double *extra, size_t *nextra);
extern void tdc_tp_grow_known(double K[4], double Kmin[4], const double need[4], double h);
extern double tdc_tp_rings(int reruns);
extern size_t tdc_tp_run_max(size_t n, const tdc_options *opt, size_t per_point, size_t budget);
extern size_t tdc_tp_cells_fit(const tdc_tp_grid *g, const uint32_t *counts, const uint8_t *added,
							   const tdc_tp_tile *ti, uint32_t *cells, size_t ncells, size_t m,
							   size_t fit);

#endif							/* TDC_TILE_PLAN_H */
