/*
 * tiled_plan.h
 *		What the tile aggregate (fn_tiled.c) takes from the plan of
 *		automatic tiles (fn_tiled_plan.c): the cells of the plan's grid,
 *		with which a tile's finality check knows where the data has no
 *		point and names the cells a rerun needs (tdc_tile_grid).
 */
#ifndef TDC_TILED_PLAN_H
#define TDC_TILED_PLAN_H

#include "postgres.h"

#include "tdc.h"

/* A plan's grid for a tile run: the cell sides, and the counts to tell empty cells. */
typedef struct TiledPlanGrid
{
	double	   *xcut;
	double	   *ycut;
	uint32	   *counts;
	int			n;				/* cells per side */
} TiledPlanGrid;

/* The grid of a plan value (copied into the current memory context). */
extern void tdc_tiled_plan_grid(const bytea *plan, TiledPlanGrid *pg);

/*
 * The cells' states of a tile run whose known region is K and the extra
 * boxes (nextra of 4 values): EMPTY where the plan counted no point, KNOWN
 * where the cell's closed box lies in K or in one extra box, or the cell
 * is one of the nadded cells a rerun added (their points are passed), else OTHER;
 * into cell (n * n bytes), and g set to describe them.
 */
extern void tdc_tiled_cell_states(const TiledPlanGrid *pg, const double K[4], const double *extra,
								  int nextra, const int32 *added, int nadded, uint8 *cell,
								  tdc_tile_grid *g);

/* The closed box of cell c of the plan's grid. */
extern void tdc_tiled_cell_box(const TiledPlanGrid *pg, uint32 c, double box[4]);

#endif							/* TDC_TILED_PLAN_H */
