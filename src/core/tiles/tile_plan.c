/*
 * tile_plan.c
 *		The tiling policy of a bounded-memory run (see tile_plan.h):
 *		the plan of tiles, the first known region of each tile (its cell
 *		box plus 8 mean spacings, and the bands of 16 mean spacings along
 *		the hull edges near it) and the growth of that region on a rerun.
 *
 * Pure: every function reads its arguments and writes its outputs, nothing
 * else.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/predicates.h"
#include "tile_plan.h"

/*
 * The counting grid's box from the box g of a sample of the points, grown
 * by two cells a side, so that the scan can count as it finds the true box.
 * The cells stay exact whatever the sample (tdc_tp_cell_of clamps, and
 * tdc_tp_grid_reach moves the outer cell sides to the true box); a box far off the
 * true one only makes a poor plan, which tdc_tp_grid_near detects.  False when
 * the sample is flat or not finite: no grid before the true box.
 */
bool
tdc_tp_grid_from_sample(double g[4])
{
	double		mx,
				my;

	if (!(g[2] > g[0]) || !(g[3] > g[1]) || !isfinite(g[2] - g[0]) || !isfinite(g[3] - g[1]))
		return false;
	mx = (g[2] - g[0]) * 2 / TDC_TP_GRID;
	my = (g[3] - g[1]) * 2 / TDC_TP_GRID;
	g[0] -= mx;
	g[1] -= my;
	g[2] += mx;
	g[3] += my;
	return isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]) && isfinite(g[3]);
}

/* The fine grid over box: scales, cell sizes and the cell sides. */
void
tdc_tp_grid_set(tdc_tp_grid *g, const double box[4])
{
	memcpy(g->box, box, sizeof(g->box));
	g->sx = box[2] > box[0] ? TDC_TP_GRID / (box[2] - box[0]) : 0;
	g->sy = box[3] > box[1] ? TDC_TP_GRID / (box[3] - box[1]) : 0;
	g->cw = (box[2] - box[0]) / TDC_TP_GRID;
	g->ch = (box[3] - box[1]) / TDC_TP_GRID;
	for (int c = 0; c <= TDC_TP_GRID; c++)
	{
		g->xcut[c] = box[0] + c * g->cw;
		g->ycut[c] = box[1] + c * g->ch;
	}
	g->xcut[TDC_TP_GRID] = fmax(g->xcut[TDC_TP_GRID], box[2]);
	g->ycut[TDC_TP_GRID] = fmax(g->ycut[TDC_TP_GRID], box[3]);
}

static int
cmp_double(const void *a, const void *b)
{
	double		u = *(const double *) a,
				v = *(const double *) b;

	return u < v ? -1 : u > v;
}

/*
 * The grid over box with its inner cell sides at the quantiles of a sample
 * of ns points (xs, ys: their coordinates, sorted here): each column and
 * each row holds about 1/TDC_TP_GRID of the points whatever their
 * clustering, so a cell inside a tight cluster holds a small share of it,
 * where a uniform grid's cell would hold the whole cluster.  The plan
 * splits by counts on these cells, and the finality check names cells
 * whose points are few where the data is dense (tile_cells.c).  sx, sy,
 * cw and ch are those of a uniform grid over box (mean sizes).  With
 * ns < TDC_TP_GRID the grid is uniform.
 */
void
tdc_tp_grid_quantiles(tdc_tp_grid *g, const double box[4], double *xs, double *ys, size_t ns)
{
	tdc_tp_grid_set(g, box);
	if (ns < TDC_TP_GRID)
		return;
	qsort(xs, ns, sizeof(double), cmp_double);
	qsort(ys, ns, sizeof(double), cmp_double);
	for (int c = 1; c < TDC_TP_GRID; c++)
	{
		size_t		k = (size_t) c * ns / TDC_TP_GRID;

		g->xcut[c] = fmin(fmax(xs[k], box[0]), box[2]);
		g->ycut[c] = fmin(fmax(ys[k], box[1]), box[3]);
	}
}

/*
 * Whether counts made on grid g are good for a plan of points whose true
 * box is bb: it reaches at most one cell past g's box on every side.
 */
bool
tdc_tp_grid_near(const tdc_tp_grid *g, const double bb[4])
{
	return !(bb[0] < g->box[0] - g->cw || bb[2] > g->box[2] + g->cw ||
			 bb[1] < g->box[1] - g->ch || bb[3] > g->box[3] + g->ch);
}

/*
 * The outer cell sides moved to the true box bb (within the next inner
 * side): a point's cell still holds it, and no point changes cell
 * (tdc_tp_cell_of reads neither outer side).  Widened where the sample
 * missed points; narrowed where the sample's box, grown by two cells,
 * passed the points: the outer cells' boxes then end where the points do.
 * The finality check takes a cell's box for where its points may be, and
 * the bottom row of 600,000 uniform points, reaching 4 below them, met
 * the circles of the slivers along the bottom of the hull all along it:
 * each rerun of a tile there named the next few cells along the hull.
 */
void
tdc_tp_grid_reach(tdc_tp_grid *g, const double bb[4])
{
	g->xcut[0] = fmin(bb[0], g->xcut[1]);
	g->ycut[0] = fmin(bb[1], g->ycut[1]);
	g->xcut[TDC_TP_GRID] = fmax(bb[2], g->xcut[TDC_TP_GRID - 1]);
	g->ycut[TDC_TP_GRID] = fmax(bb[3], g->ycut[TDC_TP_GRID - 1]);
}

/*
 * Bytes one tile run of m points may hold at once: the engine
 * (tdc_estimate_memory), tile_final.c's per-site arrays and the triangle
 * indices (TDC_TP_FINISH_BYTES a point: 4 + 8 + 1 bytes of per-site
 * arrays, the 4 once taken by the input map now holding its block grid
 * for the deep sites, and at most 2m triangles of 3 size_t), the cells'
 * arrays (TDC_TP_CELLS_BYTES), a megabyte, and per_point bytes of the caller's own (its copy of the
 * points, labels, source positions, result).
 */
size_t
tdc_tp_tile_bytes(size_t m, const tdc_options *opt, size_t per_point)
{
	return tdc_estimate_memory(m, opt) + m * (TDC_TP_FINISH_BYTES + per_point) + TDC_TP_CELLS_BYTES +
		(1 << 20);
}

/*
 * The most points a tile may own: its points with the halo and the growth
 * allowance TDC_TP_ALLOW (2.5) must fit in the budget.  (It was 2.2 while
 * a sliver along a long hull edge made corner tiles grow, then 1.5 once
 * tile_final.c bounded such a triangle's circle by its segment over the
 * hull edge; the cells a clustered tile's reruns add need 2.5.  A tile
 * that still outgrows the budget is first shrunk back, see
 * tdc_tp_shrink_known.)
 */
size_t
tdc_tp_tile_max(size_t n, const tdc_options *opt, size_t per_point, size_t budget)
{
	size_t		tile_max;

	for (tile_max = n; tile_max > 1000 && tdc_tp_tile_bytes(TDC_TP_ALLOW(tile_max), opt, per_point) > budget;)
		tile_max = tile_max * 9 / 10;
	return tile_max;
}

/* ps: the (TDC_TP_GRID + 1)^2 prefix sums of the TDC_TP_GRID^2 cell counts. */
void
tdc_tp_prefix_sums(const uint32_t *counts, size_t *ps)
{
	const int	w = TDC_TP_GRID + 1;

	for (int r = 0; r < TDC_TP_GRID; r++)
		for (int c = 0; c < TDC_TP_GRID; c++)
			ps[(r + 1) * w + c + 1] = counts[r * TDC_TP_GRID + c] +
				ps[r * w + c + 1] + ps[(r + 1) * w + c] - ps[r * w + c];
}

/* Points in cells [c0, c1) x [r0, r1) from the prefix sums. */
static size_t
cells_count(const size_t *ps, int c0, int c1, int r0, int r1)
{
	const int	w = TDC_TP_GRID + 1;

	return ps[r1 * w + c1] - ps[r0 * w + c1] - ps[r1 * w + c0] + ps[r0 * w + c0];
}

/* kd-split of the cell rectangle until every tile holds at most tile_max points. */
static tdc_tp_plan_status
plan_rect(const size_t *ps, int c0, int c1, int r0, int r1, const tdc_tp_grid *g,
		  size_t tile_max, tdc_tp_tile *tiles, int *nt)
{
	size_t		cnt = cells_count(ps, c0, c1, r0, r1),
				k;
	bool		by_x;
	int			lo,
				hi;
	tdc_tp_plan_status rc;

	if (cnt == 0)
		return TDC_TP_PLAN_OK;
	if (cnt <= tile_max || (c1 - c0 == 1 && r1 - r0 == 1))
	{
		if (cnt > tile_max)
			return TDC_TP_PLAN_DENSE_CELL;
		if (*nt >= TDC_TP_MAX_TILES)
			return TDC_TP_PLAN_TOO_MANY_TILES;
		tiles[*nt].c0 = c0;
		tiles[*nt].c1 = c1;
		tiles[*nt].r0 = r0;
		tiles[*nt].r1 = r1;
		tiles[*nt].count = cnt;
		(*nt)++;
		return TDC_TP_PLAN_OK;
	}
	by_x = (c1 - c0 > 1) &&
		(g->xcut[c1] - g->xcut[c0] >= g->ycut[r1] - g->ycut[r0] || r1 - r0 == 1);

	/*
	 * The rectangle needs k = ceil(cnt / tile_max) tiles: cut it at the
	 * fraction floor(k / 2) / k, so that each side needs a whole number of
	 * tiles.  Halving instead would round the count up to a power of two:
	 * 16 tiles where 9 do, each smaller, with more halo in all.  The cut is
	 * the smallest cell line with at least that fraction below.
	 */
	k = (cnt + tile_max - 1) / tile_max;
	lo = by_x ? c0 + 1 : r0 + 1;
	hi = by_x ? c1 - 1 : r1 - 1;
	while (lo < hi)
	{
		int			mid = (lo + hi) / 2;
		size_t		below = by_x ? cells_count(ps, c0, mid, r0, r1) : cells_count(ps, c0, c1, r0, mid);

		if (below * k >= cnt * (k / 2))
			hi = mid;
		else
			lo = mid + 1;
	}
	if (by_x)
	{
		rc = plan_rect(ps, c0, lo, r0, r1, g, tile_max, tiles, nt);
		return rc != TDC_TP_PLAN_OK ? rc : plan_rect(ps, lo, c1, r0, r1, g, tile_max, tiles, nt);
	}
	rc = plan_rect(ps, c0, c1, r0, lo, g, tile_max, tiles, nt);
	return rc != TDC_TP_PLAN_OK ? rc : plan_rect(ps, c0, c1, lo, r1, g, tile_max, tiles, nt);
}

/*
 * The plan: the grid's cells (counts in prefix sums ps) cut into tiles of
 * at most tile_max points by median splits along the longer side (a
 * kd-tree of cells), so that clustered data gets small tiles where it is
 * dense.  Empty rectangles get no tile.  tiles[] has room for TDC_TP_MAX_TILES;
 * *nt counts them.  On a refusal the tiles found so far stay in tiles[].
 */
tdc_tp_plan_status
tdc_tp_plan(const size_t *ps, const tdc_tp_grid *g, size_t tile_max, tdc_tp_tile *tiles, int *nt)
{
	return plan_rect(ps, 0, TDC_TP_GRID, 0, TDC_TP_GRID, g, tile_max, tiles, nt);
}

/*
 * At most the points inside box: those of the cells whose closed boxes
 * meet it, from the prefix sums ps of the cell counts.
 */
size_t
tdc_tp_box_count(const size_t *ps, const tdc_tp_grid *g, const double box[4])
{
	int			c0,
				c1,
				r0,
				r1;

	if (box[2] < g->xcut[0] || box[0] > g->xcut[TDC_TP_GRID] ||
		box[3] < g->ycut[0] || box[1] > g->ycut[TDC_TP_GRID])
		return 0;
	c0 = tdc_tp_cell_of(box[0], 0, 0, g->xcut);
	c1 = tdc_tp_cell_of(box[2], 0, 0, g->xcut) + 1;
	r0 = tdc_tp_cell_of(box[1], 0, 0, g->ycut);
	r1 = tdc_tp_cell_of(box[3], 0, 0, g->ycut) + 1;
	/* a cell whose side is the box's own side meets it too */
	while (c0 > 0 && g->xcut[c0] >= box[0])
		c0--;
	while (r0 > 0 && g->ycut[r0] >= box[1])
		r0--;
	return cells_count(ps, c0, c1, r0, r1);
}

/*
 * The first K of a tile of count points in its cell box, as
 * tdc_tp_first_known makes it, with its halo h halved until K holds at
 * most limit points by the cell counts (ps), down to no halo: a sparse
 * tile beside a dense cluster would otherwise take much of the cluster as
 * its halo, 8 of its own wide spacings.  The halo only saves reruns; the
 * finality check names the cells a tile still needs.
 */
void
tdc_tp_fit_known(const size_t *ps, const tdc_tp_grid *g, const double box[4], size_t count,
				 double spacing, size_t limit, double K[4], double *h)
{
	tdc_tp_first_known(box, count, spacing, K, h);
	for (int i = 0; i < 24 && *h > 0 && tdc_tp_box_count(ps, g, K) > limit; i++)
	{
		*h = i == 23 ? 0 : *h / 2;
		K[0] = box[0] - *h;
		K[1] = box[1] - *h;
		K[2] = box[2] + *h;
		K[3] = box[3] + *h;
	}
}

/*
 * Of the hull bands marked in mark[], unmark those holding more than limit
 * points by the cell counts: a band of 16 mean spacings is a thin strip on
 * uniform data, but where the hull runs from cluster to cluster it holds
 * the clusters at its ends.  The cells cover what such a band was for (a
 * sliver's disk outside C meets only empty cells).
 */
void
tdc_tp_fit_bands(const size_t *ps, const tdc_tp_grid *g, const double *bands, size_t nhull,
				 size_t limit, uint8_t *mark)
{
	for (size_t i = 0; nhull > 1 && i < nhull; i++)
		if (mark[i] && tdc_tp_box_count(ps, g, bands + 4 * i) > limit)
			mark[i] = 0;
}

/*
 * The most points a tile's first K may hold: twice its own, within
 * TDC_TP_KNOWN_MAX(tile_max), so that the hull cells (half its own, more
 * only while there is room: tdc_tp_hull_limit) and a rerun's cells stay
 * within the allowance.  (Within tile_max,
 * as it was, a full tile of uniform points had no halo at all, and every
 * interior tile of 600,000 uniform points ran three times.)
 */
size_t
tdc_tp_known_limit(size_t count, size_t tile_max)
{
	size_t		l = count * 2 > count + 1000 ? count * 2 : count + 1000;

	return l < TDC_TP_KNOWN_MAX(tile_max) ? l : TDC_TP_KNOWN_MAX(tile_max);
}

/*
 * The plan that fits: tiles of at most tile_max points (tdc_tp_plan) whose
 * first known regions (tdc_tp_first_known over the cell box, spacing the
 * data's mean spacing) hold at most TDC_TP_KNOWN_MAX(tile_max), so that a tile
 * with its halo, and the growth a rerun may add, stays in the budget that
 * tile_max was made for (tdc_tp_tile_max: TDC_TP_ALLOW(tile_max) points).  Where the
 * data is clustered a cut through a cluster puts much of it in the halo:
 * the tiles are then made smaller, a fifth at a time, down to floor points.
 * *fit_max: the tile size used.  Counts are of whole cells (an upper bound).
 */
tdc_tp_plan_status
tdc_tp_plan_fit(const size_t *ps, const tdc_tp_grid *g, size_t tile_max, size_t floor,
				double spacing, tdc_tp_tile *tiles, int *nt, size_t *fit_max)
{
	size_t		tmax = tile_max;

	for (;;)
	{
		tdc_tp_plan_status rc;
		size_t		worst = 0;

		*nt = 0;
		*fit_max = tmax;
		rc = tdc_tp_plan(ps, g, tmax, tiles, nt);
		if (rc != TDC_TP_PLAN_OK)
			return rc;
		for (int t = 0; t < *nt; t++)
		{
			double		box[4],
						K[4],
						h;
			size_t		k;

			tdc_tp_least_known(&tiles[t], g, box);
			tdc_tp_fit_known(ps, g, box, tiles[t].count, spacing,
							 tdc_tp_known_limit(tiles[t].count, tile_max), K, &h);
			k = tdc_tp_box_count(ps, g, K);
			worst = k > worst ? k : worst;
		}
		if (worst <= TDC_TP_KNOWN_MAX(tile_max) || tmax * 4 / 5 < floor)
			return TDC_TP_PLAN_OK;
		tmax = tmax * 4 / 5;
	}
}

/* The label of every cell: the index of the tile that owns it. */
void
tdc_tp_label_cells(const tdc_tp_tile *tiles, int nt, int16_t *cell_tile)
{
	for (int t = 0; t < nt; t++)
		for (int r = tiles[t].r0; r < tiles[t].r1; r++)
			for (int c = tiles[t].c0; c < tiles[t].c1; c++)
				cell_tile[r * TDC_TP_GRID + c] = (int16_t) t;
}

/*
 * The mean spacing of n points whose box is bb: the side of the square
 * that each would have alone, or along a flat box its length over n, or 1
 * when the box is a point.
 */
double
tdc_tp_spacing(const double bb[4], size_t n)
{
	double		w = bb[2] - bb[0],
				h = bb[3] - bb[1],
				k = (double) (n ? n : 1);

	if (w * h > 0 && isfinite(w * h))
		return sqrt(w * h / k);
	if (w + h > 0 && isfinite(w + h))
		return (w + h) / k;
	return 1;
}

/*
 * The band of every edge of the hull (nhull vertices, counter-clockwise;
 * none when nhull < 2) of points of mean spacing spacing: 4 doubles per
 * edge in bands[], the edge's box grown by 16 spacings across it.
 */
void
tdc_tp_hull_bands(const double *hull, size_t nhull, double spacing, double *bands)
{
	double		band = 16 * spacing;

	for (size_t i = 0; nhull > 1 && i < nhull; i++)
	{
		const double *a = hull + 2 * i,
				   *b = hull + 2 * ((i + 1) % nhull);

		/*
		 * Longer than the edge by three bands at each end: a sliver whose
		 * circle passes through the edge's end has the part of its disk
		 * inside C reach past that vertex by the disk's error bound, which
		 * for such a circle (radius 1e8) is a few spacings; with one band
		 * the top left tile of 10M uniform points ran twice for 0.7 of a
		 * spacing.
		 */
		bool		along_x = fabs(b[0] - a[0]) >= fabs(b[1] - a[1]);

		bands[4 * i] = fmin(a[0], b[0]) - (along_x ? 3 : 1) * band;
		bands[4 * i + 1] = fmin(a[1], b[1]) - (along_x ? 1 : 3) * band;
		bands[4 * i + 2] = fmax(a[0], b[0]) + (along_x ? 3 : 1) * band;
		bands[4 * i + 3] = fmax(a[1], b[1]) + (along_x ? 1 : 3) * band;
	}
}

/*
 * The first K of a tile of count points inside box (its cell box, or the
 * box of its points): box plus a halo h of 8 of the tile's mean spacings
 * (spacing, the global one, where the box is flat or a point).
 */
void
tdc_tp_first_known(const double box[4], size_t count, double spacing, double K[4], double *h)
{
	double		w = box[2] - box[0],
				ht = box[3] - box[1];

	*h = 8 * (w * ht > 0 ? sqrt(w * ht / (double) (count ? count : 1)) : spacing);
	K[0] = box[0] - *h;
	K[1] = box[1] - *h;
	K[2] = box[2] + *h;
	K[3] = box[3] + *h;
}

/*
 * In mark[] (nhull bytes, cleared by the caller) the hull bands that a
 * tile of count points with first known box K takes as extra boxes.
 */
void
tdc_tp_first_bands(const double K[4], size_t count, const double *bands, size_t nhull,
				   uint8_t *mark)
{
	double		near[4],
				gr;

	/*
	 * Extra known boxes: the boxes of the hull edges near K, grown by a
	 * band of 16 mean spacings.  A long hull edge has one triangle whose
	 * circle bulges far out of C: only its thin part inside C, along the
	 * edge, must be known, and the band holds it, without widening K along
	 * the whole edge.  The bands also bring in the hull's vertices, so
	 * every own hull edge is certified at once.
	 *
	 * The bands of the hull edges near K, not only those meeting it:
	 * slivers under a long hull edge have their circles' parts inside C
	 * along the neighbouring edges too (border tiles of 100M uniform points
	 * re-ran in 7 cases of 12 without this).  Within K's size of K, the
	 * bands along a side hold about 96 / sqrt(count) of the tile's points
	 * (a band is 32 spacings wide), against a whole tile for a re-run:
	 * taken when that is under 5 %, else only the bands meeting K, and a
	 * re-run adds what is missing.
	 */
	gr = count >= 4000000 ? fmax(K[2] - K[0], K[3] - K[1]) : 0;
	near[0] = K[0] - gr;
	near[1] = K[1] - gr;
	near[2] = K[2] + gr;
	near[3] = K[3] + gr;
	for (size_t i = 0; nhull > 1 && i < nhull; i++)
		mark[i] = tdc_tp_box_meets(bands + 4 * i, near);
}

/*
 * The cells that a segment a-b passes through and that hold points (by
 * counts) outside tile ti's own cells, appended to cells[*n ..]; their
 * points in *pts.  Row by row: the segment's x-range over the row's part
 * of its y-range, and the columns that range meets.  In doubles: a cell
 * missed by a rounding is one the finality check names if it must.
 */
static void
segment_cells(const tdc_tp_grid *g, const uint32_t *counts, const tdc_tp_tile *ti,
			  const double *a, const double *b, uint32_t *cells, size_t *n, size_t *pts)
{
	double		ylo = fmin(a[1], b[1]),
				yhi = fmax(a[1], b[1]),
				dy = b[1] - a[1];
	int			j0 = tdc_tp_cell_of(ylo, 0, 0, g->ycut),
				j1 = tdc_tp_cell_of(yhi, 0, 0, g->ycut);

	for (int j = j0; j <= j1; j++)
	{
		double		y0 = fmax(ylo, g->ycut[j]),
					y1 = fmin(yhi, g->ycut[j + 1]),
					x0,
					x1;
		int			i0,
					i1;

		if (dy == 0)
		{
			x0 = fmin(a[0], b[0]);
			x1 = fmax(a[0], b[0]);
		}
		else
		{
			double		u = a[0] + (b[0] - a[0]) * ((y0 - a[1]) / dy),
						v = a[0] + (b[0] - a[0]) * ((y1 - a[1]) / dy);

			x0 = fmax(fmin(u, v), fmin(a[0], b[0]));
			x1 = fmin(fmax(u, v), fmax(a[0], b[0]));
		}
		i0 = tdc_tp_cell_of(x0, 0, 0, g->xcut);
		i1 = tdc_tp_cell_of(x1, 0, 0, g->xcut);
		for (int i = i0; i <= i1; i++)
		{
			size_t		c = (size_t) j * TDC_TP_GRID + i;

			if (counts[c] == 0 || (i >= ti->c0 && i < ti->c1 && j >= ti->r0 && j < ti->r1))
				continue;
			cells[(*n)++] = (uint32_t) c;
			*pts += counts[c];
		}
	}
}

/*
 * The hull cells of tile ti's first region: the cells that the hull edges
 * marked in mark[] (tdc_tp_first_bands) pass through, outside the tile,
 * into cells[] (room for TDC_TP_HULL_CELLS; a cell may come twice, from
 * two edges); returns their number.  An edge's cells are taken while the
 * points taken stay within limit, by the counts, and there is room.
 *
 * A tile along the hull of P must know the points along the hull beyond
 * its own part of it: a hull edge of the tile's points is one of P only
 * once the hull vertices of P beyond it are known, and the slivers along
 * a long hull edge have circles whose parts inside C are thin lenses along
 * the edge.  The bands of 16 spacings hold both, but on clustered data a
 * band from cluster to cluster holds the clusters at its ends, and
 * without them each rerun named the next few cells along the hull: the
 * corner tile of 600,000 uniform points ran 106 times, walking along the
 * bottom edge.  The cells the edge passes through hold the hull's points
 * and little else (a row of cells on uniform data, the rims of the
 * clusters at an edge's ends).
 */
size_t
tdc_tp_hull_cells(const tdc_tp_grid *g, const uint32_t *counts, const tdc_tp_tile *ti,
				  const double *hull, size_t nhull, const uint8_t *mark, size_t limit,
				  uint32_t *cells)
{
	size_t		n = 0,
				pts = 0;

	for (size_t e = 0; nhull > 1 && e < nhull; e++)
	{
		size_t		n0 = n,
					p0 = pts;

		if (!mark[e] || n + TDC_TP_EDGE_CELLS > TDC_TP_HULL_CELLS)
			continue;
		segment_cells(g, counts, ti, hull + 2 * e, hull + 2 * ((e + 1) % nhull), cells, &n, &pts);
		if (pts > limit)
		{
			n = n0;
			pts = p0;
		}
	}
	return n;
}

/*
 * The most points the hull cells of a tile of count points may hold
 * (tdc_tp_hull_cells), its first K holding known of them (by the counts):
 * half its own, and up to all its own while K and they stay within twice
 * tile_max, what a full tile's K (TDC_TP_KNOWN_MAX) and half its own came
 * to, so that a rerun's cells keep the rest of the allowance.  A long hull
 * edge runs past many tiles; until its far vertex is known each rerun of
 * a tile along it certified the next few cells of its own hull: the tiles
 * along the top of 1e8 uniform points, whose edge's row of cells held
 * 100,000 points against a limit of 83,000, ran up to ten times.
 */
size_t
tdc_tp_hull_limit(size_t count, size_t tile_max, size_t known)
{
	size_t		half = count / 2 > 1000 ? count / 2 : 1000,
				room = 2 * tile_max > known ? 2 * tile_max - known : 0;

	room = room < count ? room : count;
	return room > half ? room : half;
}

/* The least known region of tile ti: its cell box, which holds its points. */
void
tdc_tp_least_known(const tdc_tp_tile *ti, const tdc_tp_grid *g, double Kmin[4])
{
	Kmin[0] = g->xcut[ti->c0];
	Kmin[1] = g->ycut[ti->r0];
	Kmin[2] = g->xcut[ti->c1];
	Kmin[3] = g->ycut[ti->r1];
}

/*
 * The shrinks-th shrinking (0 to 3) of a K whose points do not fit: the
 * halo (or the slack of a grown box) reaches into denser data than the
 * tile's.  K goes three quarters of the way towards Kmin, the fourth time
 * all the way; the finality test will ask for what is really needed.
 */
void
tdc_tp_shrink_known(double K[4], const double Kmin[4], int shrinks)
{
	for (int c = 0; c < 4; c++)
		K[c] = shrinks == 3 ? Kmin[c] : Kmin[c] + (K[c] - Kmin[c]) / 4;
}

/*
 * The first growth after a run that was not final and asked for the box
 * need: the bands of the hull edges that meet need and are not yet among
 * the tile's extra boxes (inband[]) are added to extra[] (*nextra boxes).
 * A request reaching along the border comes from slivers under a long hull
 * edge, whose circles' parts inside C are thin lenses along the hull: the
 * tile runs again with the same K and these bands, rather than widen K
 * along the whole side.  Returns the number of bands added; with none, K
 * must grow (tdc_tp_grow_known).
 */
size_t
tdc_tp_grow_bands(const double *bands, size_t nhull, const double need[4], uint8_t *inband,
			  double *extra, size_t *nextra)
{
	size_t		added = 0;

	for (size_t i = 0; nhull > 1 && i < nhull; i++)
		if (!inband[i] && tdc_tp_box_meets(bands + 4 * i, need))
		{
			inband[i] = 1;
			memcpy(extra + 4 * (*nextra)++, bands + 4 * i, 32);
			added++;
		}
	return added;
}

/*
 * K grown to the box need the run asked for, and by half the tile's halo h
 * beyond it: a little more than asked, since each run costs a whole tile.
 * If need is too big for the budget, K may fall back (tdc_tp_shrink_known) to
 * the new Kmin, a step of an eighth of the way from the old K: the needs
 * of a thin halo overstate what the final stars need, and any growth is
 * progress.
 */
void
tdc_tp_grow_known(double K[4], double Kmin[4], const double need[4], double h)
{
	double		gx = 0.5 * h,
				gy = 0.5 * h;

	for (int c = 0; c < 4; c++)
		Kmin[c] = K[c] + (need[c] - K[c]) / 8;
	K[0] = need[0] - gx;
	K[1] = need[1] - gy;
	K[2] = need[2] + gx;
	K[3] = need[3] + gy;
}

/*
 * The label of the square of side size that holds (x, y), counted from
 * origin: column * 2^32 + row, both from 0 at the origin, so that a label
 * does not depend on how far from (0, 0) the data lies (floor(x / size)
 * passes 2^31 at x = 5e6 with squares of 0.002).  Each step rounds
 * monotonically, so a column (row) holds an interval of x (y).  False when
 * a point lies below the origin, is not finite, or its column or row
 * passes 2^31 - 1: squares that small for data that wide are refused.
 */
bool
tdc_tp_square_label(double x, double y, const double origin[2], double size, int64_t *label)
{
	double		c = floor((x - origin[0]) / size),
				r = floor((y - origin[1]) / size);

	if (!(c >= 0 && c < 2147483648.0 && r >= 0 && r < 2147483648.0))
		return false;
	*label = (int64_t) c * 4294967296 + (int64_t) r;
	return true;
}

/*
 * Which vertex of a triangle (0, 1 or 2) decides the tile that keeps it:
 * the smallest in the lexicographic order (x, then y), as tile_final.c
 * keeps a triangle in the tile that owns that vertex.  A caller that
 * labels a finished triangulation's triangles by tiles of its own (squares)
 * gets the tiles a tiled run of those squares would give.
 */
int
tdc_tp_owner_vertex(const double *a, const double *b, const double *c)
{
	const double *v[3] = {a, b, c};
	int			lo = 0;

	for (int k = 1; k < 3; k++)
		if (tdc_lex_less(v[k], v[lo]))
			lo = k;
	return lo;
}

/*
 * The reach of a tile's request for cells (tdc_tile_grid.rings) after
 * reruns runs that added cells: TDC_TP_FIRST_RINGS, doubled on each.
 */
double
tdc_tp_rings(int reruns)
{
	double		r = TDC_TP_FIRST_RINGS;

	for (int i = 0; i < reruns && r < TDC_TP_RINGS_MAX; i++)
		r *= 2;
	return r < TDC_TP_RINGS_MAX ? r : TDC_TP_RINGS_MAX;
}

/*
 * The most points a tile's run may hold (of n in all) when a rerun adds
 * cells: the last m whose tdc_tp_tile_bytes is within 7/8 of the budget
 * (at the whole budget, 9 tight clusters at 18 MB peaked at 17.8 MB).
 */
size_t
tdc_tp_run_max(size_t n, const tdc_options *opt, size_t per_point, size_t budget)
{
	size_t		lo = 0,
				hi = n + 1;

	while (lo + 1 < hi)
	{
		size_t		mid = lo + (hi - lo) / 2;

		if (tdc_tp_tile_bytes(mid, opt, per_point) <= budget / 8 * 7)
			lo = mid;
		else
			hi = mid;
	}
	return lo;
}

/* The squared distance of cell c's box from the box tb. */
static double
cell_gap(const tdc_tp_grid *g, const double tb[4], uint32_t c)
{
	int			i = (int) (c % TDC_TP_GRID),
				j = (int) (c / TDC_TP_GRID);
	double		dx = fmax(fmax(g->xcut[i] - tb[2], tb[0] - g->xcut[i + 1]), 0),
				dy = fmax(fmax(g->ycut[j] - tb[3], tb[1] - g->ycut[j + 1]), 0);

	return dx * dx + dy * dy;
}

/* Whether cell a comes after cell b: farther from tb, or as far and a later index. */
static bool
cell_after(const tdc_tp_grid *g, const double tb[4], uint32_t a, uint32_t b)
{
	double		u = cell_gap(g, tb, a),
				v = cell_gap(g, tb, b);

	return u > v || (u == v && a > b);
}

/* Cell i of the heap cells[0 .. n) sifted down (the farthest on top). */
static void
sift_down(const tdc_tp_grid *g, const double tb[4], uint32_t *cells, size_t i, size_t n)
{
	for (size_t k; (k = 2 * i + 1) < n; i = k)
	{
		uint32_t	t;

		if (k + 1 < n && cell_after(g, tb, cells[k + 1], cells[k]))
			k++;
		if (!cell_after(g, tb, cells[k], cells[i]))
			break;
		t = cells[i];
		cells[i] = cells[k];
		cells[k] = t;
	}
}

/* Heap sort of cells, nearest to tb first (in place: nothing to allocate). */
static void
sort_by_gap(const tdc_tp_grid *g, const double tb[4], uint32_t *cells, size_t n)
{
	for (size_t s = n / 2; s-- > 0;)
		sift_down(g, tb, cells, s, n);
	for (size_t end = n; end-- > 1;)
	{
		uint32_t	t = cells[0];

		cells[0] = cells[end];
		cells[end] = t;
		sift_down(g, tb, cells, 0, end);
	}
}

/*
 * The cells a rerun asked for (ncells of them, in cells[], reordered
 * here) that tile ti's run of m points may add within fit points
 * (tdc_tp_run_max), by the counts; added[c] (or NULL) marks the cells it
 * has already, which cost nothing.  When all of them would not fit, those
 * nearest to the tile's cell box come first, and the next run asks again
 * for what it still needs: a request reaches about the distance of the
 * nearest unknown points and a little more (tile_cells.c), and between
 * tight clusters a little more is a whole cluster, which only part of the
 * tile's stars need.  Returns k: the first k of cells[] are to be added; 0
 * when not even the nearest fits (the caller's error: the data is too
 * clustered around the tile for the budget).
 */
size_t
tdc_tp_cells_fit(const tdc_tp_grid *g, const uint32_t *counts, const uint8_t *added,
				 const tdc_tp_tile *ti, uint32_t *cells, size_t ncells, size_t m, size_t fit)
{
	size_t		more = 0,
				k;
	double		tb[4];

	for (k = 0; k < ncells; k++)
		more += (added && added[cells[k]]) ? 0 : counts[cells[k]];
	if (m + more <= fit)
		return ncells;
	tdc_tp_least_known(ti, g, tb);
	sort_by_gap(g, tb, cells, ncells);
	for (k = 0, more = 0; k < ncells; k++)
	{
		size_t		c = (added && added[cells[k]]) ? 0 : counts[cells[k]];

		if (m + more + c > fit)
			break;
		more += c;
	}
	return k;
}
