/*
 * fn_tiled_plan.c
 *		The automatic tiles of tdc_delaunay_tiled (src/sql/tiled.sql): the
 *		adaptive plan of the core (src/core/tile_plan.c), made as ./tdc
 *		--max-memory makes it, each tile's first region from it, and the
 *		tile of a point.  (Regions of other tiles and their growth:
 *		fn_tiled_region.c; the plan's cells in a tile's run:
 *		fn_tiled_cells.c.)
 *
 * The automatic plan is made as ./tdc makes it, in two passes over the
 * vertices in the source's order:
 *	_tdc_plan_grid	the exact box, and a sample taken at the vertex indices
 *					./tdc samples its file at (256 runs of 256 points spread
 *					over the input, from 2^18 points on): the counting grid,
 *					its cell sides at the sample's quantiles, or uniform over
 *					the box when the input is small or the sample far off;
 *	_tdc_plan		the counts of the grid's cells, then the plan
 *					(tdc_tp_plan_fit) under tdc_delaunay.max_memory, or a
 *					refusal with the floor in MB before any tile is staged.
 * For a table of points in the order of ./tdc's input file, the grid, the
 * counts and so the tiles are ./tdc's, but for the bytes a point costs in
 * a backend (PLAN_POINT_BYTES), which size the tiles.
 *
 * The plan is a bytea (PlanHdr, the cell sides, the tiles, the counts),
 * internal to one call of the procedure.  _tdc_plan_label gives a point's
 * tile from it; it keeps a cell-to-tile table, built from the plan once per
 * query (fn_extra), keyed by the plan's id.
 */
#include "postgres.h"

#include "fmgr.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "catalog/pg_type.h"
#include "common/hashfn.h"
#include "utils/array.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include <math.h>

#include "tdc_pg.h"
#include "tile_plan.h"
#include "tiled_plan.h"


#define PLAN_GRID_MAGIC 0x47434454	/* "TDCG" */
/* ./tdc's TILE_FLOOR: the plan makes tiles smaller down to this many points */
#define PLAN_FLOOR		1000
/* ./tdc samples inputs of at least this many points (bounded_scan.c) */
#define PLAN_SAMPLE_MIN ((uint64) 1 << 18)
#define PLAN_RUNS		256
#define PLAN_RUN_LEN	256

/* The counting grid that _tdc_plan_grid makes and _tdc_plan counts on. */
typedef struct PlanGrid
{
	int32		vl_len_;
	int32		magic;
	uint64		n;				/* vertices */
	double		bb[4];			/* their exact box */
	double		box[4];			/* the grid's box */
	double		xcut[TDC_TP_GRID + 1],
				ycut[TDC_TP_GRID + 1];
} PlanGrid;


/* ---- the automatic plan ---- */

/* Options of a tile's run, as run.c sets them, for tdc_estimate_memory. */
void
tdc_tiled_plan_options(tdc_options *opt)
{
	tdc_session_options(opt);
}

PG_FUNCTION_INFO_V1(_tdc_plan_tile_max);

/*
 * _tdc_plan_tile_max(npts int8, hasz bool) RETURNS int8
 * The most points an automatic tile may own under tdc_delaunay.max_memory
 * (tdc_tp_tile_max): npts when all of them fit as one tile with the growth
 * allowance, and the procedure then runs them in one pass.
 */
Datum
_tdc_plan_tile_max(PG_FUNCTION_ARGS)
{
	int64		npts = PG_GETARG_INT64(0);
	bool		hasz = PG_GETARG_BOOL(1);
	uint64		budget = tdc_max_memory_bytes();
	tdc_options opt;

	if (npts <= 0 || budget == 0)
		PG_RETURN_INT64(Max(npts, 0));
	tdc_tiled_plan_options(&opt);
	PG_RETURN_INT64((int64) tdc_tp_tile_max((size_t) npts, &opt, PLAN_POINT_BYTES(hasz), (size_t) budget));
}

/* The state of _tdc_plan_grid and _tdc_plan: a reusable buffer for a row's vertices. */
typedef struct TilePlanState
{
	TdcPointBuf row;
	uint64		n;				/* vertices seen */
	uint64		npts;			/* _tdc_plan_grid: the vertices expected */
	double		bb[4];
	double	   *xs,
			   *ys;				/* _tdc_plan_grid: the sample */
	uint64		ns;
	PlanGrid   *grid;			/* _tdc_plan: the grid counted on (a copy) */
	tdc_tp_grid g;
	uint32	   *counts;
	bool		hasz;
} TilePlanState;

static TilePlanState *
plan_state(FunctionCallInfo fcinfo, const char *fn)
{
	MemoryContext aggcxt;
	TilePlanState  *st = PG_ARGISNULL(0) ? NULL : (TilePlanState *) PG_GETARG_POINTER(0);

	if (!AggCheckCallContext(fcinfo, &aggcxt))
		elog(ERROR, "%s called in non-aggregate context", fn);
	if (st == NULL)
	{
		st = MemoryContextAllocZero(aggcxt, sizeof(TilePlanState));
		tdc_pointbuf_init(&st->row, aggcxt);
		st->row.curves = TDC_CURVES_STROKE;
		st->bb[0] = st->bb[1] = INFINITY;
		st->bb[2] = st->bb[3] = -INFINITY;
	}
	return st;
}

/* The vertices of the row's geometry into st->row (n of them). */
static uint64
plan_read_row(TilePlanState *st, Datum geom)
{
	st->row.n = 0;
	(void) tdc_read_geometry(&st->row, geom, TILED_FNAME);
	st->hasz = st->row.hasz;
	return st->row.n;
}

/* Whether vertex i of npts is in ./tdc's sample (sample_grid in bounded_scan.c). */
static inline bool
in_sample(uint64 i, uint64 npts)
{
	uint64		step = (npts - PLAN_RUN_LEN) / (PLAN_RUNS - 1);
	uint64		j;

	if (step == 0)
		return true;
	j = i / step;
	/* runs start at step * j, j < 256; a run may reach into the next step */
	if (j < PLAN_RUNS && i - step * j < PLAN_RUN_LEN)
		return true;
	return j >= 1 && j - 1 < PLAN_RUNS && i - step * (j - 1) < PLAN_RUN_LEN;
}

PG_FUNCTION_INFO_V1(_tdc_plan_grid_transfn);

/* _tdc_plan_grid(geom geometry, npts int8): the vertices' box and ./tdc's sample. */
Datum
_tdc_plan_grid_transfn(PG_FUNCTION_ARGS)
{
	TilePlanState  *st = plan_state(fcinfo, "_tdc_plan_grid_transfn");
	uint64		k;

	tdc_signal_guard();
	if (PG_ARGISNULL(1))
		PG_RETURN_POINTER(st);
	if (st->xs == NULL)
	{
		MemoryContext aggcxt;

		(void) AggCheckCallContext(fcinfo, &aggcxt);
		st->npts = PG_ARGISNULL(2) ? 0 : (uint64) Max(PG_GETARG_INT64(2), 0);
		st->xs = MemoryContextAlloc(aggcxt, sizeof(double) * PLAN_RUNS * PLAN_RUN_LEN);
		st->ys = MemoryContextAlloc(aggcxt, sizeof(double) * PLAN_RUNS * PLAN_RUN_LEN);
	}
	k = plan_read_row(st, PG_GETARG_DATUM(1));
	for (uint64 i = 0; i < k; i++)
	{
		double		x = st->row.xy[2 * i],
					y = st->row.xy[2 * i + 1];

		tdc_tp_box_add(st->bb, x, y);
		if (st->npts >= PLAN_SAMPLE_MIN && st->ns < PLAN_RUNS * PLAN_RUN_LEN &&
			in_sample(st->n + i, st->npts) && isfinite(x) && isfinite(y))
		{
			st->xs[st->ns] = x;
			st->ys[st->ns++] = y;
		}
	}
	st->n += k;
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(_tdc_plan_grid_finalfn);

/*
 * The counting grid, as ./tdc's plan ends up with it: over the sample's
 * box grown by two cells with its sides at the sample's quantiles, the
 * outer cells reaching the true box; uniform over the true box when the
 * input is small, the sample flat, or far off the true box.
 */
Datum
_tdc_plan_grid_finalfn(PG_FUNCTION_ARGS)
{
	TilePlanState  *st;
	PlanGrid   *out;
	tdc_tp_grid *g;
	double		sb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
	bool		quantiles = false;

	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (TilePlanState *) PG_GETARG_POINTER(0);
	if (st->n == 0)
		PG_RETURN_NULL();
	g = palloc(sizeof(tdc_tp_grid));
	for (uint64 i = 0; i < st->ns; i++)
		tdc_tp_box_add(sb, st->xs[i], st->ys[i]);
	if (st->npts >= PLAN_SAMPLE_MIN && tdc_tp_grid_from_sample(sb))
	{
		tdc_tp_grid_quantiles(g, sb, st->xs, st->ys, st->ns);
		quantiles = true;
		/* ./tdc counts again on a uniform grid when the sample was far off */
		if (!tdc_tp_grid_near(g, st->bb) &&
			!(st->bb[2] - st->bb[0] <= 2 * (g->box[2] - g->box[0]) &&
			  st->bb[3] - st->bb[1] <= 2 * (g->box[3] - g->box[1])))
			quantiles = false;
	}
	if (!quantiles)
		tdc_tp_grid_set(g, st->bb);
	tdc_tp_grid_reach(g, st->bb);
	out = palloc0(sizeof(PlanGrid));
	SET_VARSIZE(out, sizeof(PlanGrid));
	out->magic = PLAN_GRID_MAGIC;
	out->n = st->n;
	memcpy(out->bb, st->bb, sizeof(out->bb));
	memcpy(out->box, g->box, sizeof(out->box));
	memcpy(out->xcut, g->xcut, sizeof(out->xcut));
	memcpy(out->ycut, g->ycut, sizeof(out->ycut));
	PG_RETURN_BYTEA_P(out);
}

/* The grid of a PlanGrid value (copied: a bytea's data is only 4-aligned). */
static void
grid_of(bytea *b, PlanGrid *pg, tdc_tp_grid *g)
{
	if (VARSIZE(b) != sizeof(PlanGrid))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: not a tiling grid", TILED_FNAME)));
	memcpy(pg, b, sizeof(PlanGrid));
	if (pg->magic != PLAN_GRID_MAGIC)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: not a tiling grid", TILED_FNAME)));
	memcpy(g->box, pg->box, sizeof(g->box));
	g->sx = g->box[2] > g->box[0] ? TDC_TP_GRID / (g->box[2] - g->box[0]) : 0;
	g->sy = g->box[3] > g->box[1] ? TDC_TP_GRID / (g->box[3] - g->box[1]) : 0;
	g->cw = (g->box[2] - g->box[0]) / TDC_TP_GRID;
	g->ch = (g->box[3] - g->box[1]) / TDC_TP_GRID;
	memcpy(g->xcut, pg->xcut, sizeof(g->xcut));
	memcpy(g->ycut, pg->ycut, sizeof(g->ycut));
}

PG_FUNCTION_INFO_V1(_tdc_plan_transfn);

/* _tdc_plan(geom geometry, grid bytea): the counts of the grid's cells. */
Datum
_tdc_plan_transfn(PG_FUNCTION_ARGS)
{
	TilePlanState  *st = plan_state(fcinfo, "_tdc_plan_transfn");
	uint64		k;

	tdc_signal_guard();
	if (PG_ARGISNULL(1) || PG_ARGISNULL(2))
		PG_RETURN_POINTER(st);
	if (st->counts == NULL)
	{
		MemoryContext aggcxt;

		(void) AggCheckCallContext(fcinfo, &aggcxt);
		st->grid = MemoryContextAlloc(aggcxt, sizeof(PlanGrid));
		grid_of(PG_GETARG_BYTEA_P(2), st->grid, &st->g);
		st->counts = MemoryContextAllocZero(aggcxt, sizeof(uint32) * TDC_TP_GRID * TDC_TP_GRID);
	}
	k = plan_read_row(st, PG_GETARG_DATUM(1));
	for (uint64 i = 0; i < k; i++)
	{
		double		x = st->row.xy[2 * i],
					y = st->row.xy[2 * i + 1];

		tdc_tp_box_add(st->bb, x, y);
		st->counts[tdc_tp_cell(&st->g, x, y)]++;
	}
	st->n += k;
	PG_RETURN_POINTER(st);
}

/*
 * The refusal of a plan, before any tile is staged, as ./tdc words it: the
 * limit is below this input's floor, the least limit whose tiles hold the
 * densest cell of the grid with the growth allowance.
 */
static void
refuse_plan(TilePlanState *st, const tdc_options *opt, size_t tile_max, tdc_tp_plan_status rc)
{
	uint64		limit_mb = tdc_max_memory_bytes() >> 20;
	size_t		dmax = 0,
				per = PLAN_POINT_BYTES(st->hasz),
				floor_bytes,
				fl;
	int			dcell = 0;

	if (rc == TDC_TP_PLAN_TOO_MANY_TILES)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: tdc_delaunay.max_memory %llu MB is too small for this input: tiles of at most %zu points "
						"(the most that fit with their halos) would be more than %d; with %llu points allow about %zu MB",
						TILED_FNAME, (unsigned long long) limit_mb, tile_max, TDC_TP_MAX_TILES,
						(unsigned long long) st->n,
						(tdc_tp_tile_bytes(TDC_TP_ALLOW((size_t) st->n / (TDC_TP_MAX_TILES / 2)), opt, per) >> 20) + 1),
				 errhint("%s", tdc_memory_limit_hint())));
	for (int c = 0; c < TDC_TP_GRID * TDC_TP_GRID; c++)
		if (st->counts[c] > dmax)
		{
			dmax = st->counts[c];
			dcell = c;
		}
	/*
	 * The floor: the least limit for which tdc_tp_tile_max, stepping down
	 * from n by tenths, stops at a tile size that holds the densest cell
	 * (the step's size, not dmax: a limit between the two still refuses).
	 */
	fl = st->n;
	while (fl > PLAN_FLOOR && fl * 9 / 10 >= (dmax > PLAN_FLOOR ? dmax : PLAN_FLOOR))
		fl = fl * 9 / 10;
	floor_bytes = tdc_tp_tile_bytes(TDC_TP_ALLOW(fl), opt, per);
	ereport(ERROR,
			(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
			 errmsg("%s: tdc_delaunay.max_memory %llu MB is below this input's floor of %zu MB: the densest cell of "
					"the tiling grid, %.6g x %.6g at (%.17g %.17g), holds %zu points (a tile may hold %zu within the "
					"limit), and a tile of them with its halo needs about %zu MB",
					TILED_FNAME, (unsigned long long) limit_mb, (floor_bytes >> 20) + 1,
					st->g.xcut[dcell % TDC_TP_GRID + 1] - st->g.xcut[dcell % TDC_TP_GRID],
					st->g.ycut[dcell / TDC_TP_GRID + 1] - st->g.ycut[dcell / TDC_TP_GRID],
					st->g.xcut[dcell % TDC_TP_GRID], st->g.ycut[dcell / TDC_TP_GRID],
					dmax, tile_max, (floor_bytes >> 20) + 1),
			 errhint("%s", tdc_memory_limit_hint())));
}

/* Prefix sums of a plan's counts (palloc'd). */
static size_t *
plan_prefix_sums(const uint32 *counts)
{
	size_t	   *ps = palloc0(sizeof(size_t) * (TDC_TP_GRID + 1) * (TDC_TP_GRID + 1));

	tdc_tp_prefix_sums(counts, ps);
	return ps;
}

PG_FUNCTION_INFO_V1(_tdc_plan_finalfn);

/*
 * The plan: tiles of at most tile_max points under tdc_delaunay.max_memory
 * (tdc_tp_tile_max), made smaller while a first region does not fit
 * (tdc_tp_plan_fit), or a refusal.
 */
Datum
_tdc_plan_finalfn(PG_FUNCTION_ARGS)
{
	TilePlanState  *st;
	PlanHdr    *out;
	size_t	   *ps,
				tile_max,
				fit_max,
				per,
				dmax = 0;
	tdc_tp_tile *tiles;
	tdc_options opt;
	tdc_tp_plan_status rc;
	int			nt = 0;
	uint64		budget = tdc_max_memory_bytes();

	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	st = (TilePlanState *) PG_GETARG_POINTER(0);
	if (st->n == 0 || st->counts == NULL)
		PG_RETURN_NULL();
	if (st->n != st->grid->n || memcmp(st->bb, st->grid->bb, sizeof(st->bb)) != 0)
		ereport(ERROR,
				(errcode(ERRCODE_OBJECT_NOT_IN_PREREQUISITE_STATE),
				 errmsg("%s: the source changed while it was planned (%llu vertices, then %llu)",
						TILED_FNAME, (unsigned long long) st->grid->n, (unsigned long long) st->n)));
	tdc_tiled_plan_options(&opt);
	per = PLAN_POINT_BYTES(st->hasz);
	ps = plan_prefix_sums(st->counts);
	tiles = palloc0(sizeof(tdc_tp_tile) * TDC_TP_MAX_TILES);
	tile_max = budget > 0 ? tdc_tp_tile_max((size_t) st->n, &opt, per, (size_t) budget) : (size_t) st->n;
	if (budget > 0 && tdc_tp_tile_bytes(TDC_TP_ALLOW(tile_max), &opt, per) > budget)
		refuse_plan(st, &opt, 0, TDC_TP_PLAN_DENSE_CELL);
	/*
	 * The plan is made smaller while a first region does not fit, but not
	 * below the densest cell: ./tdc passes its floor of 1000 points, and
	 * where a cell holds more, tdc_tp_plan_fit's last step refused a plan
	 * whose tiles fitted (9 clusters of 4,000 points at 16 MB).
	 */
	for (int c = 0; c < TDC_TP_GRID * TDC_TP_GRID; c++)
		dmax = Max(dmax, (size_t) st->counts[c]);
	rc = tdc_tp_plan_fit(ps, &st->g, tile_max, Max(PLAN_FLOOR, dmax), tdc_tp_spacing(st->bb, (size_t) st->n),
						 tiles, &nt, &fit_max);
	if (rc != TDC_TP_PLAN_OK)
		refuse_plan(st, &opt, fit_max, rc);

	out = palloc0(PLAN_SIZE(nt));
	SET_VARSIZE(out, PLAN_SIZE(nt));
	out->magic = PLAN_MAGIC;
	out->nt = nt;
	out->hasz = st->hasz;
	out->n = st->n;
	out->tile_max = fit_max;
	memcpy(out->bb, st->bb, sizeof(out->bb));
	memcpy(out->xcut, st->g.xcut, sizeof(out->xcut));
	memcpy(out->ycut, st->g.ycut, sizeof(out->ycut));
	memcpy(PLAN_TILES(out), tiles, sizeof(tdc_tp_tile) * nt);
	memcpy(PLAN_COUNTS(out), st->counts, sizeof(uint32) * TDC_TP_GRID * TDC_TP_GRID);
	out->id = hash_bytes_extended((const unsigned char *) out->xcut,
								  (int) (2 * sizeof(out->xcut) + sizeof(tdc_tp_tile) * nt), (uint64) nt);
	PG_RETURN_BYTEA_P(out);
}

/*
 * A plan argument, checked and copied into aligned memory of cxt, with its
 * grid in g (when not NULL).
 */
PlanHdr *
tdc_tiled_plan_of(bytea *b, MemoryContext cxt, tdc_tp_grid *g)
{
	PlanHdr		h;
	PlanHdr    *p;
	Size		size = VARSIZE(b);

	if (size < sizeof(PlanHdr))
		goto bad;
	memcpy(&h, b, sizeof(PlanHdr));
	if (h.magic != PLAN_MAGIC || h.nt < 0 || h.nt > TDC_TP_MAX_TILES || size != PLAN_SIZE(h.nt))
		goto bad;
	p = MemoryContextAlloc(cxt, size);
	memcpy(p, b, size);
	if (g != NULL)
	{
		double		box[4] = {p->xcut[0], p->ycut[0], p->xcut[TDC_TP_GRID], p->ycut[TDC_TP_GRID]};

		tdc_tp_grid_set(g, box);
		memcpy(g->xcut, p->xcut, sizeof(g->xcut));
		memcpy(g->ycut, p->ycut, sizeof(g->ycut));
	}
	return p;
bad:
	ereport(ERROR,
			(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
			 errmsg("%s: not a tiling plan", TILED_FNAME)));
	return NULL;				/* keep the compiler quiet */
}

/* _tdc_plan_label's cache: the cells' tiles of the plan last seen. */
typedef struct LabelCache
{
	uint64		id;
	int32		nt;
	tdc_tp_grid g;
	int16	   *cell_tile;
} LabelCache;

/* The cache of _tdc_plan_label and _tdc_plan_cell for plan b. */
static LabelCache *
label_cache(FunctionCallInfo fcinfo, bytea *b)
{
	LabelCache *c = (LabelCache *) fcinfo->flinfo->fn_extra;
	PlanHdr		h;

	if (VARSIZE(b) < sizeof(PlanHdr))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: not a tiling plan", TILED_FNAME)));
	/* the header, to compare the plan's id with the cache's */
	memcpy(&h, b, offsetof(PlanHdr, n));
	if (c == NULL || c->id != h.id || c->nt != h.nt)
	{
		MemoryContext cxt = fcinfo->flinfo->fn_mcxt;
		PlanHdr    *p;
		tdc_tp_tile *tiles;

		if (c == NULL)
		{
			c = MemoryContextAllocZero(cxt, sizeof(LabelCache));
			c->cell_tile = MemoryContextAlloc(cxt, sizeof(int16) * TDC_TP_GRID * TDC_TP_GRID);
			fcinfo->flinfo->fn_extra = c;
		}
		p = tdc_tiled_plan_of(b, CurrentMemoryContext, &c->g);
		tiles = PLAN_TILES(p);
		memset(c->cell_tile, 0xff, sizeof(int16) * TDC_TP_GRID * TDC_TP_GRID);
		tdc_tp_label_cells(tiles, p->nt, c->cell_tile);
		c->id = p->id;
		c->nt = p->nt;
		pfree(p);
	}
	return c;
}

PG_FUNCTION_INFO_V1(_tdc_plan_label);

/*
 * _tdc_plan_label(x, y, plan bytea) RETURNS int8
 * The tile (from 0) that owns the point (x, y) in the plan: the tile of its
 * cell, the cell decided exactly against the doubles of the cell sides
 * (tdc_tp_cell), as ./tdc bins it.  A point in a cell that the plan counted
 * no point in has no tile: an ERROR (the source changed).
 */
Datum
_tdc_plan_label(PG_FUNCTION_ARGS)
{
	double		x = PG_GETARG_FLOAT8(0),
				y = PG_GETARG_FLOAT8(1);
	LabelCache *c = label_cache(fcinfo, PG_GETARG_BYTEA_P(2));
	int			t;

	t = c->cell_tile[tdc_tp_cell(&c->g, x, y)];
	if (t < 0)
		ereport(ERROR,
				(errcode(ERRCODE_OBJECT_NOT_IN_PREREQUISITE_STATE),
				 errmsg("%s: the point (%.17g %.17g) lies in a cell the plan counted empty: the source changed while it was tiled",
						TILED_FNAME, x, y)));
	PG_RETURN_INT64(t);
}

PG_FUNCTION_INFO_V1(_tdc_plan_regions);

/*
 * _tdc_plan_regions(plan bytea, hull float8[])
 *		RETURNS TABLE(tile int8, n int8, region float8[])
 * Every tile of the plan with its count and first known region, as ./tdc
 * makes it (first_region in src/cli/bounded.h): its cell box plus a halo
 * halved while K would hold more than twice its points by the counts
 * (tdc_tp_fit_known), and the hull bands near K but those that would hold
 * clusters (tdc_tp_first_bands, tdc_tp_fit_bands).
 */
Datum
_tdc_plan_regions(PG_FUNCTION_ARGS)
{
	ReturnSetInfo *rsinfo = (ReturnSetInfo *) fcinfo->resultinfo;
	PlanHdr    *p;
	tdc_tp_grid *g = palloc(sizeof(tdc_tp_grid));
	tdc_tp_tile *tiles;
	size_t	   *ps;
	double	   *hull;
	int			nhull;
	double		spacing;

	InitMaterializedSRF(fcinfo, 0);
	p = tdc_tiled_plan_of(PG_GETARG_BYTEA_P(0), CurrentMemoryContext, g);
	hull = tdc_tiled_float8_array(PG_GETARG_ARRAYTYPE_P(1), &nhull, 0, 2, "the hull");
	nhull /= 2;
	tiles = PLAN_TILES(p);
	ps = plan_prefix_sums(PLAN_COUNTS(p));
	spacing = tdc_tp_spacing(p->bb, (size_t) p->n);
	for (int t = 0; t < p->nt; t++)
	{
		double		box[4],
					K[4],
					h;
		Datum		values[3];
		bool		nulls[3] = {false, false, false};

		CHECK_FOR_INTERRUPTS();
		if (tiles[t].count == 0)
			continue;
		tdc_tp_least_known(&tiles[t], g, box);
		tdc_tp_fit_known(ps, g, box, tiles[t].count, spacing,
						 tdc_tp_known_limit(tiles[t].count, (size_t) p->tile_max), K, &h);
		values[0] = Int64GetDatum(t);
		values[1] = Int64GetDatum((int64) tiles[t].count);
		values[2] = PointerGetDatum(tdc_tiled_region_result(K, h, tiles[t].count, hull, nhull, spacing, ps, g));
		tuplestore_putvalues(rsinfo->setResult, rsinfo->setDesc, values, nulls);
	}
	return (Datum) 0;
}

PG_FUNCTION_INFO_V1(_tdc_plan_box);

/*
 * _tdc_plan_box(plan bytea) RETURNS float8[]
 * The exact box of the planned vertices {xmin, ymin, xmax, ymax} and their
 * number, {.., n}: the extent the procedure then sizes everything by.
 */
Datum
_tdc_plan_box(PG_FUNCTION_ARGS)
{
	PlanHdr    *p = tdc_tiled_plan_of(PG_GETARG_BYTEA_P(0), CurrentMemoryContext, NULL);
	double		v[6] = {p->bb[0], p->bb[1], p->bb[2], p->bb[3], (double) p->n, (double) p->nt};

	PG_RETURN_ARRAYTYPE_P(tdc_tiled_float8_result(v, 6));
}

PG_FUNCTION_INFO_V1(_tdc_plan_cell);

/*
 * _tdc_plan_cell(x, y, plan bytea) RETURNS int4
 * The cell of the plan's grid (row * 512 + column) that holds the point,
 * decided exactly as ./tdc decides it (tdc_tp_cell): a tile's rerun takes
 * the points of the cells it named.
 */
Datum
_tdc_plan_cell(PG_FUNCTION_ARGS)
{
	LabelCache *c = label_cache(fcinfo, PG_GETARG_BYTEA_P(2));

	PG_RETURN_INT32(tdc_tp_cell(&c->g, PG_GETARG_FLOAT8(0), PG_GETARG_FLOAT8(1)));
}
