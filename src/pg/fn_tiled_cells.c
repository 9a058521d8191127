/*
 * fn_tiled_cells.c
 *		The cells of an automatic plan (fn_tiled_plan.c) in a tile's run of
 *		tdc_delaunay_tiled: their states for the finality check, the cells
 *		a tile that was not final named, and which of them its rerun adds.
 *
 * As ./tdc's tiles do, a tile of an automatic plan runs with the plan's
 * grid (tdc_tile_grid): the finality check knows where the data has no
 * point (a cell the plan counted empty) and, when not final, names the
 * cells its next run needs rather than a box, which on clustered data
 * takes whole clusters the circles only graze.  The rerun adds those cells'
 * points, all of them when they fit tdc_delaunay.max_memory, else the
 * nearest to the tile first as far as they fit, the request reaching
 * farther on each rerun: the same core functions as ./tdc's
 * (tdc_tp_cells_fit, tdc_tp_run_max, tdc_tp_rings), so the policy has one
 * copy.  The cells travel from the finality check to the procedure as the
 * rings of the tile's "need" row (fn_tiled.c), and back as their indices
 * (row * 512 + column).
 */
#include "postgres.h"

#include "fmgr.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "catalog/pg_type.h"
#include "utils/array.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include <math.h>

#include "tdc_pg.h"
#include "tile_plan.h"
#include "tiled_plan.h"


/* The first i with cut[i] == v (the side of a cell), or -1. */
static int
side_index(const double *cut, int n, double v)
{
	int			l = 0,
				h = n;

	while (l < h)
	{
		int			m = (l + h) / 2;

		if (cut[m] >= v)
			h = m;
		else
			l = m + 1;
	}
	return cut[l] == v ? l : -1;
}

/* The index of the cell of the plan's grid whose closed box is ring r's (5 vertices). */
static int32
ring_cell(const TiledPlanGrid *pg, const double *r)
{
	int			n = pg->n,
				i = side_index(pg->xcut, n, r[0]),
				j = side_index(pg->ycut, n, r[1]);

	/* equal cuts make empty cells: the cell is the last of them */
	while (i >= 0 && i < n - 1 && pg->xcut[i + 1] != r[4])
		i++;
	while (j >= 0 && j < n - 1 && pg->ycut[j + 1] != r[5])
		j++;
	if (i < 0 || j < 0 || i >= n || j >= n || pg->xcut[i + 1] != r[4] || pg->ycut[j + 1] != r[5])
		ereport(ERROR,
				(errcode(ERRCODE_INTERNAL_ERROR),
				 errmsg("%s: a cell needed is not a cell of the plan", TILED_FNAME)));
	return (int32) j * n + i;
}

PG_FUNCTION_INFO_V1(_tdc_tile_need_cells);

/*
 * _tdc_tile_need_cells(need geometry, plan bytea, tile int8, m int8,
 *						added int4[]) RETURNS int4[]
 * The cells of the plan that tile's next run adds, after a run of m points
 * that was not final and named cells (the rings of its row after the
 * first, see _tdc_tile_triangles), added holding the cells it has already:
 * as ./tdc adds them (add_cells_fit in src/cli/bounded_tile.c), all of
 * them when they fit tdc_delaunay.max_memory, else the nearest to the
 * tile first as far as they fit (tdc_tp_cells_fit), and the next run asks
 * again.  An ERROR when not even the nearest fits.  Empty when it named
 * none: its known box must grow (_tdc_tile_regrow).
 */
Datum
_tdc_tile_need_cells(PG_FUNCTION_ARGS)
{
	TdcPointBuf rings;
	PlanHdr    *p;
	tdc_tp_grid *g = palloc(sizeof(tdc_tp_grid));
	TiledPlanGrid pg;
	Datum	   *d;
	uint32	   *cells;
	uint8	   *added;
	uint64		ncells,
				k;
	int64		tile = PG_GETARG_INT64(2),
				m = PG_GETARG_INT64(3);
	ArrayType  *a = PG_GETARG_ARRAYTYPE_P(4);
	uint64		budget = tdc_max_memory_bytes();

	tdc_pointbuf_init(&rings, CurrentMemoryContext);
	(void) tdc_read_geometry(&rings, PG_GETARG_DATUM(0), TILED_FNAME);
	if (rings.n == 0 || rings.n % 5 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the box needed must be rings of 5 vertices", TILED_FNAME)));
	p = tdc_tiled_plan_of(PG_GETARG_BYTEA_P(1), CurrentMemoryContext, g);
	if (tile < 0 || tile >= p->nt || m < 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tile " INT64_FORMAT " is not a tile of the plan", TILED_FNAME, tile)));
	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != INT4OID || ARR_HASNULL(a))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the added cells must be a one-dimensional int4 array without NULLs",
						TILED_FNAME)));
	pg.n = TDC_TP_GRID;
	pg.xcut = p->xcut;
	pg.ycut = p->ycut;
	pg.counts = PLAN_COUNTS(p);
	added = palloc0((Size) TDC_TP_GRID * TDC_TP_GRID);
	for (int i = 0; ARR_NDIM(a) == 1 && i < ARR_DIMS(a)[0]; i++)
	{
		int32		c = ((const int32 *) ARR_DATA_PTR(a))[i];

		if (c >= 0 && c < TDC_TP_GRID * TDC_TP_GRID)
			added[c] = 1;
	}
	ncells = rings.n / 5 - 1;
	cells = palloc(sizeof(uint32) * (ncells + 1));
	for (k = 0; k < ncells; k++)
		cells[k] = (uint32) ring_cell(&pg, rings.xy + 10 * (k + 1));
	k = ncells;
	if (ncells > 0 && budget > 0)
	{
		tdc_options opt;

		tdc_tiled_plan_options(&opt);
		k = tdc_tp_cells_fit(g, pg.counts, added, &PLAN_TILES(p)[tile], cells, ncells, (size_t) m,
							 tdc_tp_run_max((size_t) p->n, &opt, PLAN_POINT_BYTES(p->hasz),
											(size_t) budget));
		if (k == 0)
			ereport(ERROR,
					(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
					 errmsg("%s: tile " INT64_FORMAT " of %d (%llu own points) holds " INT64_FORMAT
							" points and needs more, beyond tdc_delaunay.max_memory = %llu MB: "
							"the data is too clustered around this tile for the limit",
							TILED_FNAME, tile, p->nt, (unsigned long long) PLAN_TILES(p)[tile].count,
							m, (unsigned long long) (budget >> 20)),
					 errhint("Raise tdc_delaunay.max_memory, or give tiles (tile_column).")));
	}
	d = palloc(sizeof(Datum) * (k + 1));
	for (uint64 i = 0; i < k; i++)
		d[i] = Int32GetDatum((int32) cells[i]);
	PG_RETURN_ARRAYTYPE_P(construct_array(d, (int) k, INT4OID, 4, true, TYPALIGN_INT));
}

/* ---- the plan's cells in a tile's run (fn_tiled.c) ---- */

void
tdc_tiled_plan_grid(const bytea *plan, TiledPlanGrid *pg)
{
	PlanHdr    *p = tdc_tiled_plan_of((bytea *) plan, CurrentMemoryContext, NULL);

	pg->n = TDC_TP_GRID;
	pg->xcut = p->xcut;
	pg->ycut = p->ycut;
	pg->counts = PLAN_COUNTS(p);
}

/* The cells [*lo, *hi) whose sides lie in [a, b]: cut[*lo] >= a, cut[*hi] <= b. */
static void
cells_within(const double *cut, int n, double a, double b, int *lo, int *hi)
{
	int			l = 0,
				h = n;

	/* the first side >= a */
	while (l < h)
	{
		int			m = (l + h) / 2;

		if (cut[m] >= a)
			h = m;
		else
			l = m + 1;
	}
	*lo = l;
	/* the last side <= b */
	l = 0;
	h = n;
	while (l < h)
	{
		int			m = (l + h + 1) / 2;

		if (cut[m] <= b)
			l = m;
		else
			h = m - 1;
	}
	*hi = cut[l] <= b ? l : 0;
}

void
tdc_tiled_cell_states(const TiledPlanGrid *pg, const double K[4], const double *extra, int nextra,
					  const int32 *added, int nadded, int reruns, uint8 *cell, tdc_tile_grid *g)
{
	int			n = pg->n;

	for (size_t c = 0; c < (size_t) n * n; c++)
		cell[c] = pg->counts[c] == 0 ? TDC_TILE_CELL_EMPTY : TDC_TILE_CELL_OTHER;
	for (int e = -1; e < nextra; e++)
	{
		const double *b = e < 0 ? K : extra + 4 * e;
		int			c0,
					c1,
					r0,
					r1;

		cells_within(pg->xcut, n, b[0], b[2], &c0, &c1);
		cells_within(pg->ycut, n, b[1], b[3], &r0, &r1);
		for (int r = r0; r < r1; r++)
			for (int c = c0; c < c1; c++)
				if (cell[(size_t) r * n + c] == TDC_TILE_CELL_OTHER)
					cell[(size_t) r * n + c] = TDC_TILE_CELL_KNOWN;
	}
	for (int k = 0; k < nadded; k++)
		if (added[k] >= 0 && added[k] < n * n && cell[added[k]] == TDC_TILE_CELL_OTHER)
			cell[added[k]] = TDC_TILE_CELL_KNOWN;
	g->nx = g->ny = n;
	g->xcut = pg->xcut;
	g->ycut = pg->ycut;
	g->cell = cell;
	g->rings = tdc_tp_rings(reruns);
}

void
tdc_tiled_cell_box(const TiledPlanGrid *pg, uint32 c, double box[4])
{
	int			i = (int) (c % (uint32) pg->n),
				j = (int) (c / (uint32) pg->n);

	box[0] = pg->xcut[i];
	box[1] = pg->ycut[j];
	box[2] = pg->xcut[i + 1];
	box[3] = pg->ycut[j + 1];
}

PG_FUNCTION_INFO_V1(_tdc_in_boxes);

/*
 * _tdc_in_boxes(x, y, boxes float8[]) RETURNS boolean
 * Whether a closed box of {xmin, ymin, xmax, ymax, ...} holds the point:
 * a point of a cell a rerun adds is passed once, not again when K or a
 * band already holds it.
 */
Datum
_tdc_in_boxes(PG_FUNCTION_ARGS)
{
	double		x = PG_GETARG_FLOAT8(0),
				y = PG_GETARG_FLOAT8(1);
	ArrayType  *a = PG_GETARG_ARRAYTYPE_P(2);
	int			n;
	const double *b;

	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != FLOAT8OID || ARR_HASNULL(a))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the boxes must be a one-dimensional float8 array without NULLs", TILED_FNAME)));
	n = ARR_NDIM(a) == 0 ? 0 : ARR_DIMS(a)[0] / 4;
	b = (const double *) ARR_DATA_PTR(a);
	for (int i = 0; i < n; i++)
		if (b[4 * i] <= x && x <= b[4 * i + 2] && b[4 * i + 1] <= y && y <= b[4 * i + 3])
			PG_RETURN_BOOL(true);
	PG_RETURN_BOOL(false);
}
