/*
 * bounded_tile.c
 *		One tile of a bounded run, from its first run to its final one, and
 *		its triangles out.
 *
 * The first run of a tile reads its own file and its halo file, and nothing
 * else; it triangulates; tdc_tile_finish either hands over the tile's
 * triangles or asks for a larger known region, and the tile runs again
 * (first with the bands of the hull edges the request meets, then with a
 * larger K), gathering every point inside the new region from the tile
 * files whose boxes meet it, of each only the cells that meet the region
 * (bounded_cells.c).
 *
 * Memory: a tile whose region would exceed the budget is shrunk towards
 * its least region first (a first region too big for the budget is
 * gathered and shrunk as a rerun's is), and is an error when it still
 * does not fit, never a silent overrun.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bounded_int.h"

/* How often a tile's engine run looks at the caller's cancel flag. */
#define ENGINE_POLL_MS		10

/*
 * A tile run's points: coordinates, z (or NULL), each one's tile, and the
 * caller's label of each (or NULL).
 */
typedef struct tile_points
{
	size_t		m;
	double	   *q,
			   *qz;
	int64_t    *ql,
			   *qc;
} tile_points;

static int
points_alloc(bounded_run *r, tile_points *p, size_t m)
{
	p->m = m;
	p->q = malloc(16 * m + 16);
	p->ql = malloc(8 * m + 8);
	p->qz = r->has_z ? malloc(8 * m + 8) : NULL;
	p->qc = r->has_l ? malloc(8 * m + 8) : NULL;
	if (!p->q || !p->ql || (r->has_z && !p->qz) || (r->has_l && !p->qc))
		return tdc_bd_nomem(&r->e);
	return TDC_OK;
}

static void
points_free(tile_points *p)
{
	free(p->q);
	free(p->ql);
	free(p->qz);
	free(p->qc);
	p->q = p->qz = NULL;
	p->ql = p->qc = NULL;
}

/* Point at of p from a record of the run's files (x, y, then z and the label as the run has them). */
static inline void
point_from_rec(const bounded_run *r, tile_points *p, size_t at, const double *rec)
{
	p->q[2 * at] = rec[0];
	p->q[2 * at + 1] = rec[1];
	if (p->qz)
		p->qz[at] = rec[2];
	if (p->qc)
		p->qc[at] = rec_label(rec, REC_L(r));
}

/* The caller's trace of a tile run, when it has one (one worker at a time). */
static void
trace_run(const bounded_run *r, int t, const double *K, size_t nadded, size_t m)
{
	char		line[240];

	if (r->p->trace == NULL)
		return;
	if (nadded == (size_t) -1)
		snprintf(line, sizeof(line), "tile %d/%d: own %zu, K %g %g %g %g: %zu points", t, r->nt,
				 r->tiles[t].count, K[0], K[1], K[2], K[3], m);
	else
		snprintf(line, sizeof(line), "tile %d/%d: own %zu, K %g %g %g %g, %zu cells added: %zu points",
				 t, r->nt, r->tiles[t].count, K[0], K[1], K[2], K[3], nadded, m);
	tdc_bd_out_lock(r);
	r->p->trace(r->p->arg, line);
	tdc_bd_out_unlock(r);
}

/*
 * check_files (tests, TDC_TILE_CHECK=1 for ./tdc): the points inside K, an extra box or an added
 * cell (the hull cells), counted from every tile file, for checking a
 * first run's tile and halo files.
 */
static size_t
count_known(bounded_run *r, const double *K, size_t nextra)
{
	size_t		m = 0,
				got;
	int			w = r->w;
	const double *extra = r->extra;
	double		rec[4 * 1024];

	for (int s = 0; s < r->nt; s++)
	{
		mreader		f;

		if (r->tiles[s].count == 0)
			continue;
		tdc_bd_file_lock(r, s, false);
		if (tile_open(r, &f, s) != TDC_OK)
		{
			tdc_bd_file_unlock(r, s);
			return 0;
		}
		while ((got = tdc_bd_mr_read(&f, rec, 8 * (size_t) w, 1024)) > 0)
			for (size_t i = 0; i < got; i++)
			{
				const double *p = rec + w * i;
				bool		in = p[0] >= K[0] && p[0] <= K[2] && p[1] >= K[1] && p[1] <= K[3];

				for (size_t e = 0; e < nextra && !in; e++)
				{
					const double *x = extra + 4 * e;

					in = p[0] >= x[0] && p[0] <= x[2] && p[1] >= x[1] && p[1] <= x[3];
				}
				if (!in && r->nadded > 0)
					in = r->added[tdc_tp_cell(&r->grid, p[0], p[1])];
				m += in;
			}
		tdc_bd_mr_close(&f);
		tdc_bd_file_unlock(r, s);
	}
	return m;
}

/*
 * The points of tile t's first run: its own file, then its halo file, each
 * in input order; those are exactly the points of its first region (K and
 * the nextra boxes of r->extra), which check_files verifies.
 */
static int
gather_first(bounded_run *r, int t, const double *K, size_t nextra, tile_points *p)
{
	const tdc_tp_tile *ti = &r->tiles[t];
	size_t		nh = r->halo_count[t],
				at = 0,
				got,
				m = ti->count + nh;
	int			w = r->w;
	mreader		f;
	double		rec[4 * 4096];

	trace_run(r, t, K, (size_t) -1, m);
	if (tdc_bd_reserve(r, tdc_tp_tile_bytes(m, r->opt, POINT_BYTES(r))) != TDC_OK ||
		points_alloc(r, p, m) != TDC_OK)
		return r->e.code;
	/* the other worker may rewrite this file in cell order meanwhile */
	tdc_bd_file_lock(r, t, false);
	if (w == 2)
		tdc_bd_read_all(r->dir, &r->e, r->sorted[t] ? "cell" : "tile", t,
						r->sorted[t] ? 1 : r->nparts, p->q, ti->count, 2);
	else if (tile_open(r, &f, t) == TDC_OK)
	{
		while ((got = tdc_bd_mr_read(&f, rec, 8 * (size_t) w, 4096 * 4 / w)) > 0)
			for (size_t i = 0; i < got && at < ti->count; i++, at++)
				point_from_rec(r, p, at, rec + w * i);
		tdc_bd_mr_close(&f);
		if (r->e.code == TDC_OK && at != ti->count)
			tdc_bd_fail(&r->e, TDC_EIO, "short read on a temporary file in %s", r->dir);
	}
	tdc_bd_file_unlock(r, t);
	if (r->e.code != TDC_OK)
		return r->e.code;
	for (size_t i = 0; i < ti->count; i++)
		p->ql[i] = t;
	at = ti->count;
	if (tdc_bd_mr_open(&f, r->dir, &r->e, "halo", t, r->nparts) != TDC_OK)
		return r->e.code;
	while ((got = tdc_bd_mr_read(&f, rec, 8 * (size_t) (w + 1), 4096 * 4 / (w + 1))) > 0)
		for (size_t i = 0; i < got && at < m; i++, at++)
		{
			const double *h = rec + (w + 1) * i;

			point_from_rec(r, p, at, h);
			p->ql[at] = (int64_t) h[w];
		}
	tdc_bd_mr_close(&f);
	if (r->e.code != TDC_OK)
		return r->e.code;
	if (at != m)
		return tdc_bd_fail(&r->e, TDC_EIO, "short read on a temporary file in %s", r->dir);
	if (r->p->check_files)
	{
		size_t		known = count_known(r, K, nextra);

		if (r->e.code == TDC_OK && known != m)
			tdc_bd_fail(&r->e, TDC_EINVAL, "check_files: tile %d: %zu points in its files, "
						"%zu in its first region", t, m, known);
	}
	return r->e.code;
}

/* Does tile s own one of the cells added to this tile's region? */
static bool
owns_added(const bounded_run *r, int s)
{
	const tdc_tp_tile *ti = &r->tiles[s];

	for (size_t k = 0; k < r->nadded; k++)
	{
		int			i = (int) (r->added_list[k] % TDC_TP_GRID),
					j = (int) (r->added_list[k] / TDC_TP_GRID);

		if (i >= ti->c0 && i < ti->c1 && j >= ti->r0 && j < ti->r1)
			return true;
	}
	return false;
}

/* What region_points takes from a tile's records. */
typedef struct region_take
{
	bounded_run *r;
	const double *K;
	size_t		nx;				/* the boxes of r->xs to test */
	tile_points *p;				/* NULL: count only */
	size_t		m;
	int			s;				/* the records' tile */
} region_take;

static void
take_points(void *arg, const double *rec, size_t got)
{
	region_take *a = arg;
	const bounded_run *r = a->r;
	const double *K = a->K;
	int			w = r->w;

	for (size_t i = 0; i < got; i++)
	{
		const double *q = rec + w * i;
		bool		in = q[0] >= K[0] && q[0] <= K[2] && q[1] >= K[1] && q[1] <= K[3];

		for (size_t e = 0; e < a->nx && !in; e++)
		{
			const double *x = r->xs[e];

			in = q[0] >= x[0] && q[0] <= x[2] && q[1] >= x[1] && q[1] <= x[3];
		}
		if (!in && r->nadded > 0)
			in = r->added[tdc_tp_cell(&r->grid, q[0], q[1])];
		if (!in)
			continue;
		if (a->p)
		{
			point_from_rec(r, a->p, a->m, q);
			a->p->ql[a->m] = a->s;
		}
		a->m++;
	}
}

/*
 * The points inside K, one of the nextra boxes of r->extra or one of the
 * cells a rerun added (r->added), from the files of the tiles whose boxes
 * meet them (or that own an added cell), tile t's own first and then
 * the others in order (of each neighbour only its cells that meet the
 * region, bounded_cells.c): counted, or with p, copied into p with their
 * tiles' labels.  Returns their number.
 */
static size_t
region_points(bounded_run *r, int t, const double *Kr, size_t nextra, tile_points *p)
{
	/* the points' number; 0 with r->e set on an error */
	const double *extra = r->extra;
	const double K[4] = {Kr[0], Kr[1], Kr[2], Kr[3]};
	const tdc_tp_tile *tiles = r->tiles;
	region_take a = {r, K, 0, p, 0, 0};
	double		rec[4 * 4096];

	for (int u = -1; u < r->nt; u++)
	{
		int			s = u < 0 ? t : u;
		bool		meets = tdc_tp_box_meets(tiles[s].bb, K);

		for (size_t e = 0; e < nextra && !meets; e++)
			meets = tdc_tp_box_meets(tiles[s].bb, extra + 4 * e);
		if (!meets && r->nadded > 0)
			meets = owns_added(r, s);
		if ((u >= 0 && u == t) || tiles[s].count == 0 || !meets)
			continue;
		/* only the bands that meet this file's box need testing */
		a.nx = 0;
		for (size_t e = 0; e < nextra; e++)
			if (tdc_tp_box_meets(tiles[s].bb, extra + 4 * e))
				r->xs[a.nx++] = extra + 4 * e;
		a.s = s;
		if (tdc_bd_region_records(r, s, s == t, K, a.nx, rec, 4096 * 4 / r->w, take_points, &a) != TDC_OK)
			return 0;
	}
	return a.m;
}

/*
 * The points of a run of tile t that is not a first run from the halo
 * files: those of region_points, counted and then copied, so that the
 * buffers are allocated once, at their size.  While they do not fit in the
 * budget, K is shrunk towards Kmin (at most four times); a region that
 * still does not fit is an error.
 */
static int
gather_region(bounded_run *r, int t, double K[4], const double Kmin[4], size_t nextra,
			  tile_points *p, const char *why)
{
	size_t		m;

	for (int shrinks = 0;; shrinks++)
	{
		m = region_points(r, t, K, nextra, NULL);
		if (r->e.code != TDC_OK)
			return r->e.code;
		trace_run(r, t, K, r->nadded, m);
		if (tdc_tp_tile_bytes(m, r->opt, POINT_BYTES(r)) > r->budget && shrinks < 4 &&
			memcmp(K, Kmin, 4 * sizeof(double)) != 0)
			tdc_tp_shrink_known(K, Kmin, shrinks);
		else
			break;
	}
	if (tdc_tp_tile_bytes(m, r->opt, POINT_BYTES(r)) > r->budget)
		return tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "tile %d of %d (%zu own points) needs %zu points with "
						   "the region it must know, about %zu MB, more than %s %zu: the data is too "
						   "clustered around this tile for the limit%s", t, r->nt, r->tiles[t].count, m,
						   (run_need(r, m) >> 20) + 1, r->lname, r->limit >> 20, why);
	/* every file this copies from was rewritten by the count above, if it needed to be */
	if (tdc_bd_reserve(r, tdc_tp_tile_bytes(m, r->opt, POINT_BYTES(r))) != TDC_OK ||
		points_alloc(r, p, m) != TDC_OK)
		return r->e.code;
	region_points(r, t, K, nextra, p);
	return r->e.code;
}

/*
 * The states of the grid's cells for a run that knows K, the extra boxes
 * and the added cells: EMPTY where the input has no point, KNOWN for the
 * added cells and the cells whose closed box lies inside K (every point
 * there is in K, hence passed), OTHER elsewhere.  The finality check then
 * takes a disk over empty cells as known, and names the OTHER cells it
 * needs (tdc_tile_grid in tdc.h).
 */
static void
cell_states(bounded_run *r, const double K[4])
{
	const double *xc = r->grid.xcut,
			   *yc = r->grid.ycut;

	for (int j = 0; j < TDC_TP_GRID; j++)
	{
		bool		row_in = yc[j] >= K[1] && yc[j + 1] <= K[3];

		for (int i = 0; i < TDC_TP_GRID; i++)
		{
			size_t		c = (size_t) j * TDC_TP_GRID + i;

			r->cellst[c] = r->counts[c] == 0 ? TDC_TILE_CELL_EMPTY :
				r->added[c] || (row_in && xc[i] >= K[0] && xc[i + 1] <= K[2]) ?
				TDC_TILE_CELL_KNOWN : TDC_TILE_CELL_OTHER;
		}
	}
}

/* The cells a run asked for (or the first region's hull cells), added to the tile's region. */
static int
add_cells(bounded_run *r, const uint32_t *cells, size_t ncells)
{
	if (r->nadded + ncells > r->added_cap)
	{
		size_t		cap = (r->nadded + ncells) * 2;
		uint32_t   *a = realloc(r->added_list, cap * sizeof(uint32_t));

		if (a == NULL)
			return tdc_bd_nomem(&r->e);
		r->added_list = a;
		r->added_cap = cap;
	}
	for (size_t k = 0; k < ncells; k++)
		if (!r->added[cells[k]])
		{
			r->added[cells[k]] = 1;
			r->added_list[r->nadded++] = cells[k];
		}
	return TDC_OK;
}

/*
 * The cells a rerun asked for (ncells of them, in cells[], reordered
 * here), added to tile t's region of m points as far as the budget
 * allows, nearest first (tdc_tp_cells_fit).  Returns the number of cells
 * added: 0 when not even the nearest fits.
 */
static size_t
add_cells_fit(bounded_run *r, int t, uint32_t *cells, size_t ncells, size_t m)
{
	size_t		n0 = r->nadded,
				k;

	k = tdc_tp_cells_fit(&r->grid, r->counts, r->added, &r->tiles[t], cells, ncells, m,
						 tdc_tp_run_max(r->n, r->opt, POINT_BYTES(r), r->budget));
	if (add_cells(r, cells, k) != TDC_OK)
		return 0;
	return r->nadded - n0;
}

/*
 * To a rerun's region (nextra extra boxes so far, returned with those
 * added): the bands of the hull edges that meet the box need the check
 * asked for, each when it holds few points (as the first region's,
 * tdc_tp_fit_bands), and all of them only when, with the m points the run
 * holds, they leave a quarter of a run's most (tdc_tp_run_max) for the
 * cells: under a tight limit the cells alone, as before.  A request along
 * the border comes from slivers under a long hull edge, whose circles
 * reach inside C along the neighbouring edges too, as thin lenses: the
 * cells the check names reach only a few rings past the nearest, so
 * without the bands such a tile ran again and again along the side
 * (border tiles of 3e8 uniform points, up to six times).
 */
static bool
band_wanted(const bounded_run *r, size_t i, const double need[4], size_t limit, size_t *k)
{
	return !r->inband[i] && tdc_tp_box_meets(r->bands + 4 * i, need) &&
		(*k = tdc_tp_box_count(r->ps, &r->grid, r->bands + 4 * i)) <= limit;
}

static size_t
add_bands(bounded_run *r, int t, const double need[4], size_t m, size_t nextra)
{
	size_t		limit = r->tiles[t].count / 8 > 1000 ? r->tiles[t].count / 8 : 1000,
				room = tdc_tp_run_max(r->n, r->opt, POINT_BYTES(r), r->budget) / 4 * 3,
				pts = m,
				k;

	for (size_t i = 0; r->nhull > 1 && i < r->nhull; i++)
		if (band_wanted(r, i, need, limit, &k))
			pts += k;
	if (pts > room)
		return nextra;
	for (size_t i = 0; r->nhull > 1 && i < r->nhull; i++)
		if (band_wanted(r, i, need, limit, &k))
		{
			r->inband[i] = 1;
			memcpy(r->extra + 4 * nextra++, r->bands + 4 * i, 32);
		}
	return nextra;
}

/*
 * One run of the engine on a tile's points, then the finality check: res
 * holds the tile's triangles (res->final) or the box it needs.  *job: the
 * job, for tile_account (NULL when the engine failed); free res in any
 * case.
 */
static int
tile_engine(bounded_run *r, const tile_points *p, const tdc_tile_spec *spec, tdc_tile_result *res,
			tdc_job **job)
{
	char		err[512];
	double		t0 = now_s();
	int			rc;

	memset(res, 0, sizeof(*res));
	if ((rc = tdc_job_start(p->q, p->m, r->opt, job, err, sizeof(err))) != TDC_OK)
	{
		*job = NULL;
		return tdc_bd_fail(&r->e, rc, "%s", err);
	}
	/* a big tile's engine runs for seconds: the caller's cancel reaches it */
	for (;;)
	{
		if (tdc_bd_stopped(r))
			tdc_job_cancel(*job);
		if ((rc = tdc_job_wait(*job, ENGINE_POLL_MS)) != TDC_RUNNING)
			break;
	}
	if (rc != TDC_OK)
	{
		rc = tdc_bd_fail(&r->e, rc, "%s", rc == TDC_ECANCELED ? "canceled" : tdc_job_error(*job));
		tdc_job_free(*job);
		*job = NULL;
		return rc;
	}
	r->st->engine += now_s() - t0;
	t0 = now_s();
	if ((rc = tdc_tile_finish(*job, spec, res, err, sizeof(err))) != TDC_OK)
		return tdc_bd_fail(&r->e, rc, "%s", err);
	r->st->finish += now_s() - t0;
	return TDC_OK;
}

/* The job's phase times into the run's, and the job freed. */
static void
tile_account(bounded_run *r, tdc_job *job)
{
	tdc_times	tt;

	tdc_job_times(job, &tt);
	r->st->t.sort += tt.sort;
	r->st->t.subdivide += tt.subdivide;
	r->st->t.leaves += tt.leaves;
	r->st->t.merge += tt.merge;
	r->st->threads = tdc_threads_used(job);
	tdc_job_free(job);
}

/*
 * A run's result and points freed, its reservation given back, and the
 * heap handed back if it nears the limit.
 */
static void
run_done(bounded_run *r, tdc_tile_result *res, tile_points *p)
{
	tdc_tile_result_free(res);
	points_free(p);
	tdc_bd_release(r);
	heap_settle(r, false);
}

/* The output: a final run's triangles to the caller's emit, and its counts. */
static int
tile_write(bounded_run *r, int t, const tile_points *p, const tdc_tile_result *res)
{
	int			rc;

	if (r->p->emit)
	{
		bool		lock = !r->p->emit_concurrent;

		/*
		 * Nothing is emitted once the run stops (the other worker's error,
		 * a cancel), and a refusal stops it before the other emits again
		 * (or, with emit_concurrent, before it starts its next).
		 */
		if (lock)
			tdc_bd_out_lock(r);
		if (tdc_bd_stopped(r))
			tdc_bd_fail(&r->e, TDC_ECANCELED, "canceled");
		else if ((rc = r->p->emit(r->p->arg, t, p->q, p->qz, p->qc, res->tri, res->ntri)) != 0)
		{
			tdc_bd_fail(&r->e, rc < 0 ? rc : TDC_EINVAL, "the triangles of tile %d of %d were "
						"not taken (the caller's emit returned %d)", t, r->nt, rc);
			if (r->sh != NULL)
				tdc_bd_stop(r);
		}
		if (lock)
			tdc_bd_out_unlock(r);
		if (r->e.code != TDC_OK)
			return r->e.code;
	}
	r->st->ntri += res->ntri;
	r->st->unique += res->own_sites;
	r->st->halo += p->m - r->tiles[t].count;
	return TDC_OK;
}

/*
 * The caller's final_run on a final run's job (under the output's lock, as
 * emit): 0, 1 with more (the tile runs again), or the run's error code.
 */
static int
tile_final_run(bounded_run *r, int t, const tdc_job *job, const tile_points *p,
			   const tdc_tile_result *res, const tdc_tile_spec *spec, tdc_tile_result *more)
{
	int			rc;

	tdc_bd_out_lock(r);
	if (tdc_bd_stopped(r))
		rc = tdc_bd_fail(&r->e, TDC_ECANCELED, "canceled");
	else if ((rc = r->p->final_run(r->p->arg, job, p->q, p->qz, p->m, res->tri, res->ntri, spec,
								   more)) != 0 && rc != 1)
	{
		rc = tdc_bd_fail(&r->e, rc < 0 ? rc : TDC_EINVAL, "tile %d of %d was not taken (the "
						 "caller's final_run returned %d)", t, r->nt, rc);
		if (r->sh != NULL)
			tdc_bd_stop(r);
	}
	tdc_bd_out_unlock(r);
	return rc;
}

/*
 * Tile t, run until its run is final, its triangles then emitted: each
 * global triangle it owns once, whatever the runs before.  Its known
 * region starts as the policy's first region (first_region) and only
 * grows (tdc_tp_grow_bands, then tdc_tp_grow_known) between runs, except for the
 * shrinking back of a region that does not fit.  A tile that owns no
 * point has no triangle.  The caller's cancel flag is polled before every
 * run.
 */
int
tdc_bd_tile_run(bounded_run *r, int t)
{
	tdc_tp_tile    *ti = &r->tiles[t];
	double		K[4],
				Kmin[4],		/* the least K this round may shrink back to */
				h;
	size_t		nextra = 0;
	tdc_tile_spec spec = {0};
	bool		first = r->use_halo;	/* the first run reads the tile and halo files */
	const char *why = "";		/* what asked for more: the caller's final_run, said */

	tdc_tile_grid tg = {TDC_TP_GRID, TDC_TP_GRID, r->grid.xcut, r->grid.ycut, r->cellst, TDC_TP_FIRST_RINGS};

	if (ti->count == 0)
		return TDC_OK;			/* owns nothing */
	/* no cells added yet */
	for (size_t k = 0; k < r->nadded; k++)
		r->added[r->added_list[k]] = 0;
	r->nadded = 0;
	first_region(r, t, K, &h);
	if (add_cells(r, r->hcells, r->nhcells) != TDC_OK)
		return r->e.code;
	tdc_tp_least_known(ti, &r->grid, Kmin);
	for (size_t i = 0; r->nhull > 1 && i < r->nhull; i++)
		if (r->inband[i])
			memcpy(r->extra + 4 * nextra++, r->bands + 4 * i, 32);
	spec.extra = r->extra;
	spec.nextra = nextra;
	spec.self = t;
	spec.hull = r->hull;
	spec.nhull = r->nhull;
	spec.grid = r->use_cells ? &tg : NULL;
	for (;;)
	{
		tile_points p = {0};
		tdc_tile_result res;
		tdc_job    *job;
		double		t0 = now_s();

		if (tdc_bd_stopped(r))
			return tdc_bd_fail(&r->e, TDC_ECANCELED, "canceled");
		/* the engine's threads, before its memory is reckoned */
		tdc_bd_run_threads(r);
		if (first && tdc_tp_tile_bytes(ti->count + r->halo_count[t], r->opt, POINT_BYTES(r)) > r->budget)
			first = false;
		if (first)
		{
			gather_first(r, t, K, nextra, &p);
			first = false;
		}
		else
			gather_region(r, t, K, Kmin, nextra, &p, why);
		if (r->e.code != TDC_OK)
		{
			points_free(&p);
			return r->e.code;
		}
		memcpy(spec.known, K, sizeof(K));
		if (r->use_cells)
			cell_states(r, K);
		spec.tile = p.ql;
		r->st->runs++;
		r->st->gather += now_s() - t0;
		if (tile_engine(r, &p, &spec, &res, &job) != TDC_OK)
		{
			if (job)
				tdc_job_free(job);
			tdc_tile_result_free(&res);
			points_free(&p);
			return r->e.code;
		}
		t0 = now_s();
		/* each vertex's label: the least of its copies', while the job still names them */
		if (res.final && p.qc)
			tdc_least_labels(job, p.qc);
		/*
		 * the caller's look at the whole T(Q) first: it may need more, and
		 * the run then goes on as a run that is not final
		 */
		if (res.final && r->p->final_run != NULL)
		{
			tdc_tile_result more = {0};
			int			frc = tile_final_run(r, t, job, &p, &res, &spec, &more);

			if (frc != 0 && frc != 1)
			{
				tdc_tile_result_free(&more);
				tile_account(r, job);
				tdc_tile_result_free(&res);
				points_free(&p);
				return r->e.code;
			}
			if (frc == 1)
			{
				why = r->p->final_run_why ? r->p->final_run_why : "";
				tdc_tile_result_free(&res);
				res.final = 0;
				memcpy(res.need, more.need, sizeof(res.need));
				res.need_cells = more.need_cells;
				res.nneed_cells = more.nneed_cells;
			}
		}
		tile_account(r, job);
		if (res.final)
		{
			if (tile_write(r, t, &p, &res) != TDC_OK)
			{
				tdc_tile_result_free(&res);
				points_free(&p);
				return r->e.code;
			}
		}
		else if (res.nneed_cells > 0)
		{
			/*
			 * the same K with the cells the check named, as many as fit;
			 * the next request reaches twice as far past the nearest cell;
			 * and the bands of the hull edges the request meets
			 */
			tg.rings = fmin(2 * tg.rings, TDC_TP_RINGS_MAX);
			spec.nextra = nextra = add_bands(r, t, res.need, p.m, nextra);
			if (add_cells_fit(r, t, res.need_cells, res.nneed_cells, p.m) == 0)
			{
				if (r->e.code == TDC_OK)
					tdc_bd_fail(&r->e, TDC_EMEMLIMIT, "tile %d of %d (%zu own points) holds %zu points "
								"and needs more, beyond %s %zu: the data is too clustered around this "
								"tile for the limit%s", t, r->nt, ti->count, p.m, r->lname, r->limit >> 20,
								why);
				tdc_tile_result_free(&res);
				points_free(&p);
				return r->e.code;
			}
			run_done(r, &res, &p);
			continue;
		}
		else if (!r->use_cells &&
				 tdc_tp_grow_bands(r->bands, r->nhull, res.need, r->inband, r->extra, &nextra) > 0)
		{
			/* the same K with more bands */
			spec.nextra = nextra;
			run_done(r, &res, &p);
			continue;
		}
		else
			tdc_tp_grow_known(K, Kmin, res.need, h);
		run_done(r, &res, &p);
		r->st->write += now_s() - t0;
		if (spec.known[0] == K[0] && spec.known[1] == K[1] &&
			spec.known[2] == K[2] && spec.known[3] == K[3])
			break;				/* final: K was not changed */
	}
	return TDC_OK;
}
