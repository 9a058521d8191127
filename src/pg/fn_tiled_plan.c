/*
 * fn_tiled_plan.c
 *		The tiling policy of tdc_delaunay_tiled (src/sql/tiled.sql), from
 *		the core (src/core/tile_plan.c) through small C helpers: the labels
 *		of squares, the first known region of a tile and its growth on a
 *		rerun, and the adaptive plan of automatic tiles.
 *
 * The procedure used to repeat the policy in PL/pgSQL (a halo of 8
 * spacings, hull bands of 16, K "grown by a tenth", a uniform grid of
 * squares labelled floor(x / size) * 2^32 + floor(y / size), which
 * overflowed bigint far from the origin) and had drifted from ./tdc's.  Now
 * every number comes from tile_plan.c, the file ./tdc --max-memory calls.
 *
 * A tile's known region travels as one float8[]: {h, K (4 values), the
 * extra known boxes (4 values each)}, h being the tile's halo, which the
 * growth on a rerun is measured in.
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

#define TILED_FNAME		"tdc_delaunay_tiled"
#define PLAN_MAGIC		0x50434454	/* "TDCP" */
#define PLAN_GRID_MAGIC 0x47434454	/* "TDCG" */
/* ./tdc's TILE_FLOOR: the plan makes tiles smaller down to this many points */
#define PLAN_FLOOR		1000
/* ./tdc samples inputs of at least this many points (bounded_scan.c) */
#define PLAN_SAMPLE_MIN ((uint64) 1 << 18)
#define PLAN_RUNS		256
#define PLAN_RUN_LEN	256

/*
 * The bytes of a tile's backend beside the engine for each point it holds,
 * as _tdc_tile (fn_tiled.c) counts them against tdc_delaunay.max_memory:
 * coordinates (16, Z 8), owner label and source position (24), in arrays
 * that grow by doubling (so twice that), and the triangles of the result
 * value (2 a point, 3 vertices of 2 or 3 doubles).
 */
#define PLAN_POINT_BYTES(hasz)	((size_t) (2 * (16 + ((hasz) ? 8 : 0) + 24) + 2 * 3 * ((hasz) ? 3 : 2) * 8))

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

/*
 * A float8[] argument as doubles, copied (aligned); n its length.  NULLs,
 * more dimensions or too few values are errors.
 */
static double *
float8_array(ArrayType *a, int *n, int want_min, int multiple, const char *what)
{
	double	   *out;
	int			count;

	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != FLOAT8OID || ARR_HASNULL(a))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s must be a one-dimensional float8 array without NULLs",
						TILED_FNAME, what)));
	count = ARR_NDIM(a) == 0 ? 0 : ARR_DIMS(a)[0];
	if (count < want_min || count % multiple != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s has %d values, want a multiple of %d, at least %d",
						TILED_FNAME, what, count, multiple, want_min)));
	out = palloc(sizeof(double) * (count + 1));
	if (count > 0)
		memcpy(out, ARR_DATA_PTR(a), sizeof(double) * count);
	*n = count;
	return out;
}

static ArrayType *
float8_result(const double *v, int n)
{
	Datum	   *d = palloc(sizeof(Datum) * (n + 1));

	for (int i = 0; i < n; i++)
		d[i] = Float8GetDatum(v[i]);
	return construct_array(d, n, FLOAT8OID, 8, FLOAT8PASSBYVAL, TYPALIGN_DOUBLE);
}

/* A box argument {xmin, ymin, xmax, ymax}. */
static void
box_arg(ArrayType *a, double box[4], const char *what)
{
	int			n;
	double	   *v = float8_array(a, &n, 4, 4, what);

	if (n != 4)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s must be {xmin, ymin, xmax, ymax}", TILED_FNAME, what)));
	memcpy(box, v, 4 * sizeof(double));
}

PG_FUNCTION_INFO_V1(_tdc_square_label);

/*
 * _tdc_square_label(x, y, origin_x, origin_y, size) RETURNS int8
 * The label of the square of side size that holds (x, y), counted from the
 * origin (tdc_tp_square_label): column * 2^32 + row.  An ERROR when the
 * point lies below the origin, or its column or row passes 2^31 - 1.
 */
Datum
_tdc_square_label(PG_FUNCTION_ARGS)
{
	double		x = PG_GETARG_FLOAT8(0),
				y = PG_GETARG_FLOAT8(1),
				origin[2] = {PG_GETARG_FLOAT8(2), PG_GETARG_FLOAT8(3)},
				size = PG_GETARG_FLOAT8(4);
	int64_t		label;

	if (!tdc_tp_square_label(x, y, origin, size, &label))
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: the point (%.17g %.17g) has no square of tile_size %.17g counted from (%.17g %.17g)",
						TILED_FNAME, x, y, size, origin[0], origin[1]),
				 errdetail("A square's column and row count from the data's lower left corner and must stay below 2^31."),
				 errhint("Use a larger tile_size.")));
	PG_RETURN_INT64((int64) label);
}

/*
 * The region {h, K, bands...} of a tile whose first K and halo h are given:
 * the hull bands (tdc_tp_hull_bands over the data's mean spacing) that
 * tdc_tp_first_bands takes for it, unless counts (ps, g) drop those that
 * would hold clusters (tdc_tp_fit_bands), as ./tdc does.
 */
static ArrayType *
region_result(const double K[4], double h, size_t count, const double *hull, int nhull,
			  double spacing, const size_t *ps, const tdc_tp_grid *g)
{
	double	   *bands = palloc(sizeof(double) * 4 * (nhull + 1)),
			   *out = palloc(sizeof(double) * (5 + 4 * (nhull + 1)));
	uint8	   *mark = palloc0(nhull + 1);
	int			n = 5;

	out[0] = h;
	memcpy(out + 1, K, 4 * sizeof(double));
	tdc_tp_hull_bands(hull, (size_t) nhull, spacing, bands);
	tdc_tp_first_bands(K, count, bands, (size_t) nhull, mark);
	if (ps != NULL)
		tdc_tp_fit_bands(ps, g, bands, (size_t) nhull, count / 8 > 1000 ? count / 8 : 1000, mark);
	for (int i = 0; nhull > 1 && i < nhull; i++)
		if (mark[i])
		{
			memcpy(out + n, bands + 4 * i, 4 * sizeof(double));
			n += 4;
		}
	return float8_result(out, n);
}

PG_FUNCTION_INFO_V1(_tdc_tile_region);

/*
 * _tdc_tile_region(box float8[], n int8, extent float8[], npts int8,
 *					hull float8[]) RETURNS float8[]
 * The first known region {h, K, bands...} of a tile of n points whose box
 * is box, in data of npts points with box extent and convex hull hull
 * {x,y,...}: K is the box plus a halo of 8 of the tile's mean spacings,
 * the bands those of the hull edges near K (tdc_tp_first_known,
 * tdc_tp_first_bands).  For tiles of a column or of squares; the
 * automatic plan's come from _tdc_plan_regions.
 */
Datum
_tdc_tile_region(PG_FUNCTION_ARGS)
{
	double		box[4],
				extent[4],
				K[4],
				h,
			   *hull;
	int64		n = PG_GETARG_INT64(1),
				npts = PG_GETARG_INT64(3);
	int			nhull;

	box_arg(PG_GETARG_ARRAYTYPE_P(0), box, "the tile's box");
	box_arg(PG_GETARG_ARRAYTYPE_P(2), extent, "the extent");
	hull = float8_array(PG_GETARG_ARRAYTYPE_P(4), &nhull, 0, 2, "the hull");
	if (n < 0 || npts < 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: negative point counts", TILED_FNAME)));
	tdc_tp_first_known(box, (size_t) n, tdc_tp_spacing(extent, (size_t) npts), K, &h);
	PG_RETURN_ARRAYTYPE_P(region_result(K, h, (size_t) n, hull, nhull / 2,
										tdc_tp_spacing(extent, (size_t) npts), NULL, NULL));
}

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
 * _tdc_tile_need_cells(need geometry, plan bytea) RETURNS int4[]
 * The cells of the plan that a tile's run that was not final named, from
 * its row (the rings after the first, see _tdc_tile_triangles): the next
 * run adds their points, as ./tdc's does (add_cells).  Empty when it named
 * none: its known box must grow (_tdc_tile_regrow).
 */
Datum
_tdc_tile_need_cells(PG_FUNCTION_ARGS)
{
	TdcPointBuf rings;
	TiledPlanGrid pg;
	Datum	   *d;
	uint64		ncells;

	tdc_pointbuf_init(&rings, CurrentMemoryContext);
	(void) tdc_read_geometry(&rings, PG_GETARG_DATUM(0), TILED_FNAME);
	if (rings.n == 0 || rings.n % 5 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the box needed must be rings of 5 vertices", TILED_FNAME)));
	tdc_tiled_plan_grid(PG_GETARG_BYTEA_P(1), &pg);
	ncells = rings.n / 5 - 1;
	d = palloc(sizeof(Datum) * (ncells + 1));
	for (uint64 k = 0; k < ncells; k++)
		d[k] = Int32GetDatum(ring_cell(&pg, rings.xy + 10 * (k + 1)));
	PG_RETURN_ARRAYTYPE_P(construct_array(d, (int) ncells, INT4OID, 4, true, TYPALIGN_INT));
}

PG_FUNCTION_INFO_V1(_tdc_tile_regrow);

/*
 * _tdc_tile_regrow(region float8[], need geometry, extent float8[],
 *					npts int8, hull float8[], plan bytea) RETURNS float8[]
 * The region of a tile's next run, after a run that was not final: need is
 * the row _tdc_tile_triangles gave for it, a POLYGON whose first ring is
 * the box it needs (the other rings are the cells it needs, which the
 * procedure adds with _tdc_tile_need_cells).  As ./tdc grows a tile
 * that named no cell: without
 * a plan's cells (plan NULL) the bands of the hull edges that meet the
 * box and that it lacks, if there are such (tdc_tp_grow_bands); else K
 * grown to the box and half the halo beyond (tdc_tp_grow_known).
 */
Datum
_tdc_tile_regrow(PG_FUNCTION_ARGS)
{
	double	   *region,
				need[4],
				extent[4],
			   *hull,
			   *bands,
			   *extra,
				K[4],
				Kmin[4];
	uint8	   *inband;
	int			nregion,
				nhull;
	size_t		nextra;
	int64		npts;
	bool		cells = !PG_ARGISNULL(5);
	TdcPointBuf rings;

	if (PG_ARGISNULL(0) || PG_ARGISNULL(1) || PG_ARGISNULL(2) || PG_ARGISNULL(3) || PG_ARGISNULL(4))
		PG_RETURN_NULL();
	npts = PG_GETARG_INT64(3);

	region = float8_array(PG_GETARG_ARRAYTYPE_P(0), &nregion, 5, 1, "the region");
	if ((nregion - 5) % 4 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: a region is {h, xmin, ymin, xmax, ymax, boxes...}", TILED_FNAME)));
	tdc_pointbuf_init(&rings, CurrentMemoryContext);
	(void) tdc_read_geometry(&rings, PG_GETARG_DATUM(1), TILED_FNAME);
	if (rings.n == 0 || rings.n % 5 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the box needed must be rings of 5 vertices", TILED_FNAME)));
	/* ring k's box: corners 0 and 2 */
	need[0] = rings.xy[0];
	need[1] = rings.xy[1];
	need[2] = rings.xy[4];
	need[3] = rings.xy[5];
	box_arg(PG_GETARG_ARRAYTYPE_P(2), extent, "the extent");
	hull = float8_array(PG_GETARG_ARRAYTYPE_P(4), &nhull, 0, 2, "the hull");
	nhull /= 2;
	nextra = (nregion - 5) / 4;
	extra = palloc(sizeof(double) * (5 + 4 * (nextra + nhull + 1)));
	memcpy(extra, region, sizeof(double) * nregion);
	if (!cells)
	{
		bands = palloc(sizeof(double) * 4 * (nhull + 1));
		inband = palloc0(nhull + 1);
		tdc_tp_hull_bands(hull, (size_t) nhull, tdc_tp_spacing(extent, (size_t) Max(npts, 0)), bands);
		/* the bands the tile has: the same doubles, made by the same call */
		for (int i = 0; nhull > 1 && i < nhull; i++)
			for (size_t e = 0; e < nextra; e++)
				if (memcmp(bands + 4 * i, region + 5 + 4 * e, 4 * sizeof(double)) == 0)
					inband[i] = 1;
		if (tdc_tp_grow_bands(bands, (size_t) nhull, need, inband, extra + 5, &nextra) > 0)
			PG_RETURN_ARRAYTYPE_P(float8_result(extra, 5 + 4 * (int) nextra));
	}
	memcpy(K, region + 1, sizeof(K));
	tdc_tp_grow_known(K, Kmin, need, region[0]);
	memcpy(extra + 1, K, sizeof(K));
	PG_RETURN_ARRAYTYPE_P(float8_result(extra, nregion));
}

/* ---- the automatic plan ---- */

/* Options of a tile's run, as run.c sets them, for tdc_estimate_memory. */
static void
plan_options(tdc_options *opt)
{
	tdc_options_init(opt);
	opt->threads = tdc_effective_threads();
	opt->grid_size = tdc_guc_grid_size;
	opt->levels = tdc_guc_levels;
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
	plan_options(&opt);
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
	plan_options(&opt);
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
static PlanHdr *
plan_of(bytea *b, MemoryContext cxt, tdc_tp_grid *g)
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
		p = plan_of(b, CurrentMemoryContext, &c->g);
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
	p = plan_of(PG_GETARG_BYTEA_P(0), CurrentMemoryContext, g);
	hull = float8_array(PG_GETARG_ARRAYTYPE_P(1), &nhull, 0, 2, "the hull");
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
		values[2] = PointerGetDatum(region_result(K, h, tiles[t].count, hull, nhull, spacing, ps, g));
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
	PlanHdr    *p = plan_of(PG_GETARG_BYTEA_P(0), CurrentMemoryContext, NULL);
	double		v[6] = {p->bb[0], p->bb[1], p->bb[2], p->bb[3], (double) p->n, (double) p->nt};

	PG_RETURN_ARRAYTYPE_P(float8_result(v, 6));
}

/* ---- the plan's cells in a tile's run (fn_tiled.c) ---- */

void
tdc_tiled_plan_grid(const bytea *plan, TiledPlanGrid *pg)
{
	PlanHdr    *p = plan_of((bytea *) plan, CurrentMemoryContext, NULL);

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
					  const int32 *added, int nadded, uint8 *cell, tdc_tile_grid *g)
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
