/*
 * tiled_plan.h
 *		What the C helpers of tdc_delaunay_tiled share: the plan value of
 *		automatic tiles (fn_tiled_plan.c), the argument helpers and first
 *		regions (fn_tiled_region.c), and what the tile aggregate (fn_tiled.c)
 *		takes from the plan (fn_tiled_cells.c): the cells of the plan's
 *		grid, with which a tile's finality check knows where the data has no
 *		point and names the cells a rerun needs (tdc_tile_grid).
 */
#ifndef TDC_TILED_PLAN_H
#define TDC_TILED_PLAN_H

#include "postgres.h"

#include "utils/array.h"

#include "tdc.h"
#include "tile_plan.h"

#define TILED_FNAME		"tdc_delaunay_tiled"
#define PLAN_MAGIC		0x50434454	/* "TDCP" */
/*
 * The bytes of a tile's backend beside the engine for each point it holds,
 * as _tdc_tile (fn_tiled.c) counts them against tdc_delaunay.max_memory:
 * coordinates (16, Z 8), owner label and source position (24), in arrays
 * that grow by doubling (so twice that), and the triangles of the result
 * value (2 a point, 3 vertices of 2 or 3 doubles).
 */
#define PLAN_POINT_BYTES(hasz)	((size_t) (2 * (16 + ((hasz) ? 8 : 0) + 24) + 2 * 3 * ((hasz) ? 3 : 2) * 8))

/* The plan: this header, nt tdc_tp_tile, TDC_TP_GRID^2 uint32 counts. */
typedef struct PlanHdr
{
	int32		vl_len_;
	int32		magic;
	int32		nt;
	int32		hasz;
	uint64		id;				/* hash of the tiles and cuts: the label cache's key */
	uint64		n;
	uint64		tile_max;		/* the tile size the plan fitted */
	double		bb[4];
	double		xcut[TDC_TP_GRID + 1],
				ycut[TDC_TP_GRID + 1];
} PlanHdr;

#define PLAN_TILES(p)	((tdc_tp_tile *) ((char *) (p) + sizeof(PlanHdr)))
#define PLAN_COUNTS(p)	((uint32 *) (PLAN_TILES(p) + (p)->nt))
#define PLAN_SIZE(nt)	(sizeof(PlanHdr) + (Size) (nt) * sizeof(tdc_tp_tile) + \
						 (Size) TDC_TP_GRID * TDC_TP_GRID * sizeof(uint32))


/* fn_tiled_region.c: float8[] arguments and results, and a first region */
extern double *tdc_tiled_float8_array(ArrayType *a, int *n, int want_min, int multiple,
									  const char *what);
extern ArrayType *tdc_tiled_float8_result(const double *v, int n);
extern void tdc_tiled_box_arg(ArrayType *a, double box[4], const char *what);
extern int64 tdc_tiled_square_label(double x, double y, const double origin[2], double size);
extern ArrayType *tdc_tiled_region_result(const double K[4], double h, size_t count,
										  const double *hull, int nhull, double spacing,
										  const size_t *ps, const tdc_tp_grid *g);

/* fn_tiled_plan.c: a plan value checked and copied, and the options of a tile's run */
extern PlanHdr *tdc_tiled_plan_of(bytea *b, MemoryContext cxt, tdc_tp_grid *g);
extern void tdc_tiled_plan_options(tdc_options *opt);

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
 * into cell (n * n bytes), and g set to describe them, its requests reaching
 * as far as after reruns runs that added cells (tdc_tp_rings).
 */
extern void tdc_tiled_cell_states(const TiledPlanGrid *pg, const double K[4], const double *extra,
								  int nextra, const int32 *added, int nadded, int reruns, uint8 *cell,
								  tdc_tile_grid *g);

/* The closed box of cell c of the plan's grid. */
extern void tdc_tiled_cell_box(const TiledPlanGrid *pg, uint32 c, double box[4]);

#endif							/* TDC_TILED_PLAN_H */
