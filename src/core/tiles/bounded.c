/*
 * bounded.c
 *		tdc_bounded_run (tdc.h): the triangulation of an input that does not
 *		fit, tile by tile through files; ./tdc --max-memory MB is its first
 *		caller.
 *
 * When the one-shot run (the input, the engine, the result) would not fit
 * in the limit, the input is cut into tiles on disk and triangulated tile
 * by tile with the core's exact tiling (tile_final.c), and the triangles
 * are handed to the caller (emit) as each tile finishes.  Two sequential
 * reads of the input (a .bin file the caller staged: ./tdc converts text
 * input to one first), in phases:
 *	scan	bounding box, convex hull (in chunks: the hull of a union is the
 *			hull of the parts' hulls, and a point inside a rectangle inside
 *			the hull so far is skipped) and counts on a fine grid, whose box
 *			comes from a sample of the file (counted again in a pass of its
 *			own when the sample was far off) (bounded_scan.c);
 *	plan	the grid (its sides at the quantiles of a sample) cut into
 *			tiles of at most tile_max points by median splits along the
 *			longer side (kd-tree of cells), so that clustered data gets
 *			small tiles where it is dense, made smaller while a first
 *			region does not fit; refused before any work, with the floor
 *			in MB, when the densest cell does not fit (tile_plan.c);
 *	bands	the bands along the hull edges, extra known boxes of the tiles
 *			near them (tile_plan.c);
 *	bin		each point appended to its tile's file, and to the halo file of
 *			every other tile whose first known region holds it; the two
 *			halves of the input on two threads, each with its own files,
 *			read back one after the other (bounded_bin.c);
 *	tiles	each tile run until final, its triangles emitted
 *			(bounded_tile.c): in the plan's order one at a time, or, when
 *			the caller takes them in any order, two at a time on two
 *			workers that share the budget by reservations (bounded_share.c
 *			says how, and why that cannot deadlock).
 * A point's cell is decided exactly against the doubles of the cell sides,
 * so a tile's points lie in its cells' box, and its first known region is
 * fixed before binning: K = that box plus a halo of 8 mean point spacings
 * (halved while K would hold more than twice the tile), as extra known
 * boxes the bands along the hull edges near it (those that hold few
 * points), and whole the cells those hull edges pass through (the hull
 * cells, up to the tile's own points while the region stays within twice
 * the largest tile, tdc_tp_hull_limit).
 *
 * Memory: the largest tile with its halo is bounded by tile_max times a
 * growth allowance; a tile whose K would exceed the budget is an error,
 * never a silent overrun.  A rerun adds the cells of the grid that the
 * finality check names (tdc_tile_grid), not a box around them: on a
 * coastline or between clusters a box would take whole stretches of
 * dense data that the disks only graze.  The named cells reach a few
 * rings of cells past the nearest one needed, twice as far on every
 * rerun, and are added as far as the budget holds them, nearest first
 * (bounded_tile.c).
 *
 * Beside the coordinates, every file carries a point's z and the caller's
 * label when the caller gives them (zpath, lpath; REC_L in bounded.h): a
 * final tile's emit gets each vertex's z from its first copy in the input
 * and its label as the least of its copies' (tdc_least_labels), which is
 * how tdc_delaunay_tiled labels triangles by the tiles of a tile column.
 *
 * The process around the run is the caller's: what it holds beside the
 * tiles comes in as `outside`, its heap policy and its peak through the
 * settle and peak callbacks (./tdc: src/cli/bounded_mem.c).  Nothing here
 * exits: an error unwinds to tdc_bounded_run with its message (bd_err,
 * bounded_int.h), which frees the run's arrays and removes its files.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bounded_int.h"

/*
 * The refusal of a plan: the limit is below this input's floor, the least
 * budget whose tiles hold its densest cell (the plan's smallest tile) with
 * the growth allowance, and at least TILE_FLOOR points; the message gives
 * the numbers, and the exact copies of one spot when they are what makes
 * the cell dense.  Before any tile is binned or run.
 */
#define TILE_FLOOR	1000

static int
refuse_plan(bounded_run *r, size_t tile_max, tdc_tp_plan_status rc)
{
	size_t		dmax = 0,
				floor_bytes,
				copies = 0;
	int			dcell = 0;
	double		spot[2];
	char		msg[640],
				dup[200] = "";

	for (int c = 0; c < TDC_TP_GRID * TDC_TP_GRID; c++)
		if (r->counts[c] > dmax)
		{
			dmax = r->counts[c];
			dcell = c;
		}
	floor_bytes = run_need(r, TDC_TP_ALLOW(dmax > TILE_FLOOR ? dmax : TILE_FLOOR));
	if (rc == TDC_TP_PLAN_TOO_MANY_TILES)
	{
		snprintf(msg, sizeof(msg), "%s %zu is too small for this input: tiles of at most %zu points "
				 "(the most that fit with their halos) would be more than %d; with %zu points allow about %zu MB",
				 r->lname, r->limit >> 20, tile_max, TDC_TP_MAX_TILES, r->n,
				 (run_need(r, TDC_TP_ALLOW(r->n / (TDC_TP_MAX_TILES / 2))) >> 20) + 1);
		return tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "%s", msg);
	}
	if (dmax > tile_max && dmax >= 2)
	{
		if (tdc_bd_dense_spot(r, dcell, tile_max, spot, &copies) != TDC_OK)
			return r->e.code;
		if (copies * 2 >= dmax)
			snprintf(dup, sizeof(dup), "; %zu of them are exact copies of (%.17g %.17g)",
					 copies, spot[0], spot[1]);
	}
	snprintf(msg, sizeof(msg), "%s %zu is below this input's floor of %zu MB: the densest cell of the "
			 "tiling grid, %.6g x %.6g at (%.17g %.17g), holds %zu points (a tile may hold %zu within the limit), "
			 "and a tile of them with its halo needs about %zu MB%s",
			 r->lname, r->limit >> 20, (floor_bytes >> 20) + 1,
			 r->grid.xcut[dcell % TDC_TP_GRID + 1] - r->grid.xcut[dcell % TDC_TP_GRID],
			 r->grid.ycut[dcell / TDC_TP_GRID + 1] - r->grid.ycut[dcell / TDC_TP_GRID],
			 r->grid.xcut[dcell % TDC_TP_GRID], r->grid.ycut[dcell / TDC_TP_GRID],
			 dmax, tile_max, (floor_bytes >> 20) + 1, dup);
	return tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "%s", msg);
}

/*
 * The plan: after it, r->grid is the grid every point is placed on (its
 * outer cells reaching the true box), r->tiles[0 .. r->nt) the tiles, each
 * with its cells, its count and an empty box, and r->cell_tile each cell's
 * tile.  Fails when the policy refuses the plan.
 */
static int
plan(bounded_run *r)
{
	size_t	   *ps,
				tile_max,
				fit_max;
	tdc_tp_plan_status rc;

	/*
	 * Fine counts (unless pass 1 made them on a grid near the box) and the
	 * tiles.  The outer cells reach the true box: a point's cell still
	 * holds it.
	 */
	/*
	 * Counts made on the sample's grid stay exact whatever the true box:
	 * a point beyond the grid is counted in an outer cell, which
	 * tdc_tp_grid_reach moves the outer sides to.  Only when the sample missed
	 * much of the data are the cells counted again, on a uniform grid
	 * over the true box: the sample's quantiles then say little.
	 */
	if (r->counted && !tdc_tp_grid_near(&r->grid, r->bb) &&
		!(r->bb[2] - r->bb[0] <= 2 * (r->grid.box[2] - r->grid.box[0]) &&
		  r->bb[3] - r->bb[1] <= 2 * (r->grid.box[3] - r->grid.box[1])))
	{
		r->counted = false;
		memset(r->counts, 0, sizeof(uint32_t) * TDC_TP_GRID * TDC_TP_GRID);
	}
	if (!r->counted)
		tdc_tp_grid_set(&r->grid, r->bb);
	tdc_tp_grid_reach(&r->grid, r->bb);
	r->ps = ps = calloc((size_t) (TDC_TP_GRID + 1) * (TDC_TP_GRID + 1), sizeof(size_t));
	r->tiles = calloc(TDC_TP_MAX_TILES, sizeof(tdc_tp_tile));
	r->cell_tile = malloc((size_t) TDC_TP_GRID * TDC_TP_GRID * sizeof(int16_t));
	if (!ps || !r->tiles || !r->cell_tile)
		return tdc_bd_nomem(&r->e);
	if (!r->counted && tdc_bd_scan_count(r) != TDC_OK)
		return r->e.code;
	tdc_tp_prefix_sums(r->counts, ps);

	tile_max = tdc_tp_tile_max(r->n, r->opt, POINT_BYTES(r), r->budget);
	if (tdc_tp_tile_bytes(TDC_TP_ALLOW(tile_max), r->opt, POINT_BYTES(r)) > r->budget)
		return refuse_plan(r, 0, TDC_TP_PLAN_DENSE_CELL);
	rc = tdc_tp_plan_fit(ps, &r->grid, tile_max, TILE_FLOOR, tdc_tp_spacing(r->bb, r->n),
						 r->tiles, &r->nt, &fit_max);
	if (rc != TDC_TP_PLAN_OK)
	{
		r->nt = 0;				/* no tile has a file yet */
		return refuse_plan(r, fit_max, rc);
	}
	r->tile_max = fit_max;
	for (int t = 0; t < r->nt; t++)
	{
		r->tiles[t].bb[0] = r->tiles[t].bb[1] = INFINITY;
		r->tiles[t].bb[2] = r->tiles[t].bb[3] = -INFINITY;
	}
	tdc_tp_label_cells(r->tiles, r->nt, r->cell_tile);
	r->st->tiles = r->nt;
	return TDC_OK;
}

/*
 * The hull bands, r->bands, and the scratch arrays of a tile's extra known
 * boxes, sized by the hull.
 */
static int
bands(bounded_run *r)
{
	r->extra = malloc(32 * (r->nhull + 1));
	r->bands = malloc(32 * (r->nhull + 1));
	r->inband = calloc(r->nhull + 1, 1);
	r->xs = malloc(sizeof(double *) * (r->nhull + 1));
	if (r->extra == NULL || r->bands == NULL || r->inband == NULL || r->xs == NULL)
		return tdc_bd_nomem(&r->e);
	/* the cells, when they have a size (a flat input has no use for them) */
	r->use_cells = r->grid.xcut[TDC_TP_GRID] > r->grid.xcut[0] && r->grid.ycut[TDC_TP_GRID] > r->grid.ycut[0];
	r->cellst = malloc((size_t) TDC_TP_GRID * TDC_TP_GRID);
	r->added = calloc((size_t) TDC_TP_GRID * TDC_TP_GRID, 1);
	r->hcells = malloc(sizeof(uint32_t) * TDC_TP_HULL_CELLS);
	if (r->cellst == NULL || r->added == NULL || r->hcells == NULL)
		return tdc_bd_nomem(&r->e);
	tdc_tp_hull_bands(r->hull, r->nhull, tdc_tp_spacing(r->bb, r->n), r->bands);
	return TDC_OK;
}

/*
 * The peak so far (the caller's peak callback) against the limit, before
 * any tile: what the run held by then (read buffers, the counting grids,
 * the halo index) is beyond the tiles' model, and a limit below it is an
 * error, not a silent overrun.
 */
static int
before_tiles(bounded_run *r)
{
	size_t		peak = r->p->peak ? r->p->peak(r->p->arg) : 0;

	if (peak <= r->limit)
		return TDC_OK;
	return tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "%s %zu is below the %zu MB this run held before its "
					   "first tile (read buffers, the counting grid and the halo index); raise it",
					   r->lname, r->limit >> 20, (peak >> 20) + 1);
}

/*
 * Does the file at path hold fewer than r->n records of size bytes?  (A
 * source shorter than n would end the passes early and be found out only
 * as a mismatch of counts.)  Sets r->e.
 */
static bool
too_short(bounded_run *r, const char *path, size_t size)
{
	struct stat sb;

	if (stat(path, &sb) != 0)
		return tdc_bd_fail(&r->e, TDC_EIO, "cannot open %s", path) != TDC_OK;
	if ((size_t) sb.st_size / size < r->n)
		return tdc_bd_fail(&r->e, TDC_EINVAL, "%s holds %zu points, fewer than the %zu expected",
						   path, (size_t) sb.st_size / size, r->n) != TDC_OK;
	return false;
}

/*
 * Bytes the process holds beside the tiles from now on (the output's
 * buffers, a second tile worker's scratch), off the tiles' budget; a limit
 * they leave nothing of is an error.
 */
static int
hold_outside(bounded_run *r, size_t bytes)
{
	r->outside += bytes;
	if (r->outside >= r->limit)
		return tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "%s %zu is below the %zu MB the process and "
						   "the output's buffers hold beside the tiles; raise it",
						   r->lname, r->limit >> 20, (r->outside >> 20) + 1);
	r->budget = r->limit - r->outside;
	return TDC_OK;
}

/*
 * The caller's begin, with the box and the hull of the first pass: what it
 * will hold beside the tiles comes off their budget before the plan, and
 * a limit it leaves nothing of is an error.
 */
static int
begin_output(bounded_run *r)
{
	size_t		hold = 0;
	int			rc = r->p->begin(r->p->arg, r->bb, r->hull, r->nhull, &hold);

	if (rc != 0)
		return tdc_bd_fail(&r->e, rc < 0 ? rc : TDC_EINVAL, "the output could not begin "
						   "(the caller's begin returned %d)", rc);
	return hold_outside(r, hold);
}

/* A worker: tiles claimed in the plan's order, each run until final. */
static void *
tile_worker(void *arg)
{
	bounded_run *w = arg;
	int			t;

	while ((t = tdc_bd_claim(w)) >= 0)
	{
		int			rc = tdc_bd_tile_run(w, t);

		tdc_bd_release(w);
		if (rc != TDC_OK)
			break;
	}
	if (w->e.code != TDC_OK)
		tdc_bd_stop(w);
	tdc_bd_leave(w);
	return NULL;
}

/* A worker's own scratch for a tile's region (the first worker's is r's). */
static bool
worker_scratch(bounded_run *w)
{
	size_t		cells = (size_t) TDC_TP_GRID * TDC_TP_GRID;

	w->cellst = malloc(cells);
	w->added = calloc(cells, 1);
	w->added_list = NULL;
	w->nadded = w->added_cap = 0;
	w->hcells = malloc(sizeof(uint32_t) * TDC_TP_HULL_CELLS);
	w->extra = malloc(32 * (w->nhull + 1));
	w->inband = calloc(w->nhull + 1, 1);
	w->xs = malloc(sizeof(double *) * (w->nhull + 1));
	return w->cellst && w->added && w->hcells && w->extra && w->inband && w->xs;
}

static void
worker_scratch_free(bounded_run *w)
{
	free(w->cellst);
	free(w->added);
	free(w->added_list);
	free(w->hcells);
	free(w->extra);
	free(w->inband);
	free(w->xs);
}

/* One worker's counts added to the run's. */
static void
add_stats(tdc_bounded_stats *st, const tdc_bounded_stats *w)
{
	st->unique += w->unique;
	st->ntri += w->ntri;
	st->halo += w->halo;
	st->runs += w->runs;
	st->reread += w->reread;
	st->threads = w->threads > st->threads ? w->threads : st->threads;
	st->t.sort += w->t.sort;
	st->t.subdivide += w->t.subdivide;
	st->t.leaves += w->t.leaves;
	st->t.merge += w->t.merge;
	st->gather += w->gather;
	st->engine += w->engine;
	st->finish += w->finish;
	st->write += w->write;
	st->wait += w->wait;
}

/*
 * The tiles, on tdc_bd_workers(r) workers (bounded_share.c): the first on
 * this thread, a second on a thread of its own.  Each works on a copy of
 * r with its own scratch, error and counts; r->e gets the first error.
 * A second worker that cannot start leaves the tiles to the first.
 */
static void
run_tiles(bounded_run *r)
{
	int			nw = tdc_bd_workers(r);
	bounded_run w[2];
	tdc_bounded_stats wst[2];
	pthread_t	th;
	bool		started = false;

	r->sh = tdc_bd_share_new(r, nw);
	if (r->sh == NULL)
	{
		tdc_bd_nomem(&r->e);
		return;
	}
	memset(wst, 0, sizeof(wst));
	for (int i = 0; i < nw; i++)
	{
		w[i] = *r;
		w[i].st = &wst[i];
		memset(&w[i].e, 0, sizeof(w[i].e));
		w[i].wopt = *r->p->opt;
		w[i].opt = &w[i].wopt;
		w[i].held = 0;
	}
	if (nw > 1)
	{
		if (!worker_scratch(&w[1]))
			nw = 1;				/* the first worker takes every tile */
		else
			started = pthread_create(&th, NULL, tile_worker, &w[1]) == 0;
		if (!started)
		{
			tdc_bd_leave(&w[1]);
			nw = 1;
		}
	}
	r->st->workers = nw;
	tile_worker(&w[0]);
	if (started)
		pthread_join(th, NULL);
	if (tdc_bd_share_error(r->sh)->code != TDC_OK)
		r->e = *tdc_bd_share_error(r->sh);
	for (int i = 0; i < (started ? 2 : 1); i++)
		add_stats(r->st, &wst[i]);
	/* the first worker's list may have moved when it grew */
	r->added_list = w[0].added_list;
	if (tdc_bd_workers(r) > 1)
		worker_scratch_free(&w[1]);
	tdc_bd_share_free(r->sh);
	r->sh = NULL;
}

/* The phases in order; the first error stops them. */
static int
run_phases(bounded_run *r)
{
	tdc_bounded_stats *st = r->st;
	double		t0;

	t0 = now_s();
	/* the points' box and hull; the cells counted when the grid is known */
	if (tdc_bd_scan_input(r) != TDC_OK)
		return r->e.code;
	/* the caller's output, sized by the box, holds its buffers from here on */
	if (r->p->begin && begin_output(r) != TDC_OK)
		return r->e.code;
	/*
	 * A second tile worker's scratch, whenever the caller takes any order
	 * and the budget dwarfs it (so the plan is the same for any thread
	 * count; under a tight limit the tiles run one at a time).
	 */
	if (r->p->any_order && tdc_bd_worker_bytes(r) * 8 <= r->budget)
	{
		if (hold_outside(r, tdc_bd_worker_bytes(r)) != TDC_OK)
			return r->e.code;
		r->two = true;
	}
	/* every cell in one tile, every tile at most tile_max points */
	if (plan(r) != TDC_OK)
		return r->e.code;
	/* every tile's first known region fixed: K and its bands */
	if (bands(r) != TDC_OK || tdc_bd_halo_index(r) != TDC_OK)
		return r->e.code;
	st->scan = now_s() - t0;

	/* every point in its tile's file, and in the halo files of the others' first regions */
	t0 = now_s();
	if (tdc_bd_bin_points(r) != TDC_OK)
		return r->e.code;
	st->bin = now_s() - t0;
	/*
	 * Nothing reads the input after the bins (the tiles' files hold every
	 * point, its z and label): a caller's temporary copy of it frees its
	 * disk for the reruns' rewrites and the caller's output (the peak, at
	 * the end of the bins, holds both).
	 */
	if (r->p->drop_input)
	{
		unlink(r->p->xypath);
		if (r->p->zpath)
			unlink(r->p->zpath);
		if (r->p->lpath)
			unlink(r->p->lpath);
	}
	/* the scan's and the bins' buffers, freed, are not the tiles' to reuse */
	heap_settle(r, true);
	if (before_tiles(r) != TDC_OK)
		return r->e.code;
	r->sorted = calloc((size_t) (r->nt > 0 ? r->nt : 1), 1);
	if (r->sorted == NULL)
		return tdc_bd_nomem(&r->e);

	/* every global triangle emitted once, by the tile that owns it */
	t0 = now_s();
	run_tiles(r);
	st->tiles_wall = now_s() - t0;
	return r->e.code;
}

/*
 * The bounded run (tdc.h).  The limit less what the process holds beside
 * the tiles (the caller's outside, and the plan's prefix sums, kept for
 * the first regions) is the tiles' budget.  Whatever the outcome, the
 * run's arrays are freed and its files removed before it returns.
 */
int
tdc_bounded_run(const tdc_bounded_params *p, tdc_bounded_stats *st, char *err, size_t errlen)
{
	bounded_run r = {
		.p = p, .xypath = p->xypath, .zpath = p->zpath, .lpath = p->lpath, .dir = p->tmpdir,
		.lname = p->limit_name ? p->limit_name : "--max-memory",
		.n = p->n, .opt = p->opt, .limit = p->limit, .st = st,
		.has_z = p->zpath != NULL, .has_l = p->lpath != NULL,
		.w = 2 + (p->zpath != NULL) + (p->lpath != NULL)
	};

	memset(st, 0, sizeof(*st));
	st->n = p->n;
	if (err && errlen)
		err[0] = '\0';
	r.outside = p->outside + sizeof(size_t) * (TDC_TP_GRID + 1) * (TDC_TP_GRID + 1);
	r.budget = r.limit > r.outside ? r.limit - r.outside : 0;
	if (p->xypath == NULL || p->tmpdir == NULL || p->opt == NULL)
		tdc_bd_fail(&r.e, TDC_EINVAL, "tdc_bounded_run: xypath, tmpdir and opt are required");
	else if (too_short(&r, p->xypath, 16) || (p->zpath && too_short(&r, p->zpath, 8)) ||
			 (p->lpath && too_short(&r, p->lpath, 8)))
		;						/* r.e says which */
	else if (p->opt->tolerance > 0)
		tdc_bd_fail(&r.e, TDC_EINVAL, "a tolerance cannot be used when the input is tiled "
					"(which points are merged depends on all of them)");
	else
		run_phases(&r);

	tdc_bd_remove_all(r.dir, r.nt);
	free(r.counts);
	free(r.ps);
	free(r.tiles);
	free(r.cell_tile);
	free(r.cell_off);
	free(r.cell_halo);
	free(r.cellst);
	free(r.added);
	free(r.added_list);
	free(r.hcells);
	free(r.extra);
	free(r.bands);
	free(r.inband);
	free(r.xs);
	free(r.hull);
	free(r.kfirst);
	free(r.band_off);
	free(r.band_idx);
	free(r.halo_count);
	free(r.sorted);
	if (r.e.code != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", r.e.msg);
	return r.e.code;
}
