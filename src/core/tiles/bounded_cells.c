/*
 * bounded_cells.c
 *		A tile's file in the order of its cells, for the reruns that need
 *		only some of them.
 *
 * Binning appends each point to its tile's file in input order.  A rerun
 * of a tile needs, from each neighbour, only the points in its grown
 * region: a strip along the shared edge, or the cells the finality check
 * named.  Read in input order, that meant reading every neighbour's whole
 * file, twice (counted, then copied); on a billion points, where the first
 * runs of most tiles are not final, that was several times the input read
 * again per round of reruns.
 *
 * So the first time a rerun needs a tile's file, the file is rewritten in
 * the order of the grid's cells (row-major within the tile's rectangle of
 * cells), stably: a cell's points keep their input order, so exact copies
 * of a point reach the engine in the same order as before and the one kept
 * is the same.  A cell's records then start at the sum of the counts of the
 * cells before it (pass 1's counts, which the rewrite checks against the
 * points), and a region reads only the runs of consecutive cells whose
 * closed boxes meet it: every point lies in its cell's closed box
 * (tdc_tp_cell decides it against the doubles of the sides, and the
 * rewrite checks that too), so a cell whose box misses the region holds
 * none of its points.  Tiles that no rerun needs are never rewritten.
 */
#include <stdlib.h>

#include "bounded_int.h"

/*
 * Tile s's file rewritten in cell order as its single part, the other parts
 * removed.  Each record goes straight to its place among the tile's points,
 * which the cells' counts give, so the rewrite holds the tile's points once
 * and two numbers per cell of its rectangle: less than the tile's own run.
 */
static int
sort_tile(bounded_run *r, int s)
{
	const tdc_tp_tile *ti = &r->tiles[s];
	const tdc_tp_grid *g = &r->grid;
	int			w = r->w,
				cw = ti->c1 - ti->c0;
	size_t		n = ti->count,
				ncell = (size_t) cw * (size_t) (ti->r1 - ti->r0),
				at = 0,
				got;
	double	   *out = NULL,
				rec[4 * 1024];
	uint32_t   *next = NULL,
			   *end = NULL;
	mreader		m;
	FILE	   *f;
	bool		short_write;

	out = malloc(8 * (size_t) w * n + 8);
	next = malloc(4 * ncell + 4);
	end = malloc(4 * ncell + 4);
	if (!out || !next || !end)
	{
		tdc_bd_nomem(&r->e);
		goto done;
	}
	for (size_t c = 0; c < ncell; c++)
	{
		next[c] = (uint32_t) at;
		at += r->counts[(size_t) (ti->r0 + c / cw) * TDC_TP_GRID + ti->c0 + c % cw];
		end[c] = (uint32_t) at;
	}
	if (at != n)
	{
		tdc_bd_fail(&r->e, TDC_EINVAL, "internal error: a tile file in %s does not match the counts "
					"of its cells", r->dir);
		goto done;
	}
	if (tdc_bd_mr_open(&m, r->dir, &r->e, "tile", s, r->nparts) != TDC_OK)
		goto done;
	while ((got = tdc_bd_mr_read(&m, rec, 8 * (size_t) w, 4096 / w)) > 0 && r->e.code == TDC_OK)
		for (size_t k = 0; k < got; k++)
		{
			const double *q = rec + w * k;
			int			c = tdc_tp_cell(g, q[0], q[1]),
						i = c % TDC_TP_GRID,
						j = c / TDC_TP_GRID;
			size_t		lc;

			/* the cell's closed box holds the point: cell_meets relies on it */
			if (i < ti->c0 || i >= ti->c1 || j < ti->r0 || j >= ti->r1 ||
				q[0] < g->xcut[i] || q[0] > g->xcut[i + 1] || q[1] < g->ycut[j] || q[1] > g->ycut[j + 1])
			{
				tdc_bd_fail(&r->e, TDC_EINVAL, "internal error: a point of a tile file in %s lies "
							"outside its cells", r->dir);
				break;
			}
			lc = (size_t) (j - ti->r0) * cw + (i - ti->c0);
			if (next[lc] >= end[lc])
			{
				tdc_bd_fail(&r->e, TDC_EINVAL, "internal error: a tile file in %s does not match the "
							"counts of its cells", r->dir);
				break;
			}
			for (int e = 0; e < w; e++)
				out[(size_t) w * next[lc] + e] = q[e];
			next[lc]++;
		}
	tdc_bd_mr_close(&m);
	for (size_t c = 0; c < ncell && r->e.code == TDC_OK; c++)
		if (next[c] != end[c])
			tdc_bd_fail(&r->e, TDC_EINVAL, "internal error: a tile file in %s does not match the "
						"counts of its cells", r->dir);
	if (r->e.code != TDC_OK)
		goto done;
	free(next);
	free(end);
	next = end = NULL;
	f = tdc_bd_part_file(r->dir, &r->e, "cell", s, 0, "wb");
	if (f == NULL)
		goto done;
	short_write = n > 0 && fwrite(out, 8 * (size_t) w, n, f) != n;
	if (fclose(f) != 0 || short_write)
	{
		tdc_bd_fail(&r->e, TDC_EIO, "cannot write temporary files in %s (disk full?)", r->dir);
		goto done;
	}
	free(out);
	out = NULL;
	for (int p = 0; p < r->nparts; p++)
		if (tdc_bd_remove(r->dir, &r->e, "tile", s, p) != TDC_OK)
			goto done;
	r->sorted[s] = 1;
done:
	free(out);
	free(next);
	free(end);
	return r->e.code;
}

/* The bytes sort_tile holds for tile s. */
static size_t
sort_bytes(const bounded_run *r, int s)
{
	const tdc_tp_tile *ti = &r->tiles[s];

	return 8 * (size_t) r->w * ti->count + 8 * (size_t) (ti->c1 - ti->c0) * (ti->r1 - ti->r0) + 16;
}

/*
 * Tile s's file in cell order, rewritten now if no worker did it before.
 * Its bytes are reserved first, before its file lock: this worker holds
 * nothing here (a rerun's count), and a worker waiting for memory must
 * not hold a lock the other one, holding memory, may wait for.
 */
static int
sort_once(bounded_run *r, int s)
{
	bool		sorted;

	tdc_bd_file_lock(r, s, false);
	sorted = r->sorted[s];
	tdc_bd_file_unlock(r, s);
	if (sorted)
		return TDC_OK;
	if (tdc_bd_reserve(r, sort_bytes(r, s)) != TDC_OK)
		return r->e.code;
	tdc_bd_file_lock(r, s, true);
	if (!r->sorted[s])
		sort_tile(r, s);
	tdc_bd_file_unlock(r, s);
	tdc_bd_release(r);
	return r->e.code;
}

/*
 * Does cell c (of tile s's rectangle) hold a point the region may take:
 * does its closed box meet K or one of the nx boxes of r->xs, or was it
 * added to the region?
 */
static bool
cell_meets(const bounded_run *r, int c, const double *K, size_t nx)
{
	int			i = c % TDC_TP_GRID,
				j = c / TDC_TP_GRID;
	double		box[4] = {r->grid.xcut[i], r->grid.ycut[j], r->grid.xcut[i + 1], r->grid.ycut[j + 1]};

	if (r->counts[c] == 0)
		return false;
	if (r->nadded > 0 && r->added[c])
		return true;
	if (tdc_tp_box_meets(box, K))
		return true;
	for (size_t e = 0; e < nx; e++)
		if (tdc_tp_box_meets(box, r->xs[e]))
			return true;
	return false;
}

/*
 * The records of tile s that a region (K, the nx boxes of r->xs, the added
 * cells) may take, in file order, handed to take(arg, records, count) in
 * pieces of at most cap records of buf: with whole (a tile's own file), or
 * on a grid of cells of no size, the whole file; else, once the file is in
 * cell order (sorted the first time), the runs of cells that meet the
 * region.  take still tests every point.
 */
int
tdc_bd_region_records(bounded_run *r, int s, bool whole, const double *K, size_t nx, double *buf,
					  size_t cap, void (*take) (void *arg, const double *rec, size_t got), void *arg)
{
	const tdc_tp_tile *ti = &r->tiles[s];
	int			w = r->w;
	size_t		got,
				at = 0;
	mreader		f;

	if (whole || !r->use_cells)
	{
		tdc_bd_file_lock(r, s, false);
		if (tile_open(r, &f, s) == TDC_OK)
		{
			while ((got = tdc_bd_mr_read(&f, buf, 8 * (size_t) w, cap)) > 0)
			{
				take(arg, buf, got);
				if (!whole)
					r->st->reread += got;
			}
			tdc_bd_mr_close(&f);
		}
		tdc_bd_file_unlock(r, s);
		return r->e.code;
	}
	/* rewritten once, by whichever worker needs it first; never undone, so read unlocked */
	if (sort_once(r, s) != TDC_OK || tdc_bd_mr_open(&f, r->dir, &r->e, "cell", s, 1) != TDC_OK)
		return r->e.code;
	for (int j = ti->r0; j < ti->r1; j++)
	{
		int			i = ti->c0;

		while (i < ti->c1)
		{
			int			c = j * TDC_TP_GRID + i;
			size_t		from = at,
						len = 0;

			/* a run of cells that meet the region, or of cells that do not */
			if (cell_meets(r, c, K, nx))
				for (; i < ti->c1 && cell_meets(r, j * TDC_TP_GRID + i, K, nx); i++)
					len += r->counts[j * TDC_TP_GRID + i];
			else
				for (; i < ti->c1 && !cell_meets(r, j * TDC_TP_GRID + i, K, nx); i++)
					at += r->counts[j * TDC_TP_GRID + i];
			if (len == 0)
				continue;
			at += len;
			if (fseeko(f.f, (off_t) from * 8 * w, SEEK_SET) != 0)
			{
				tdc_bd_mr_close(&f);
				return tdc_bd_fail(&r->e, TDC_EIO, "cannot seek in a temporary file in %s", r->dir);
			}
			while (len > 0)
			{
				got = fread(buf, 8 * (size_t) w, len < cap ? len : cap, f.f);
				if (got == 0)
				{
					tdc_bd_mr_close(&f);
					return tdc_bd_fail(&r->e, TDC_EIO, "short read on a temporary file in %s", r->dir);
				}
				take(arg, buf, got);
				r->st->reread += got;
				len -= got;
			}
		}
	}
	tdc_bd_mr_close(&f);
	return r->e.code;
}
