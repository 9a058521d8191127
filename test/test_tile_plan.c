/*
 * test_tile_plan.c
 *		The tile plan's unit parts (tile_plan.c, tile_plan.h): the cell of a
 *		coordinate, the hull cells and outer cell sides, the cells a rerun
 *		adds, the hull cells' limit, the cells a disk's request names
 *		(tile_cells.c), and the square labels.  Each checks a rule the plan's callers
 *		rely on against a case small enough to know the answer by hand.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "tdc.h"
#include "tiles/tile_cells.h"
#include "tiles/tile_plan.h"
#include "splitmix.h"

/*
 * tdc_tp_cell_of is the last c with cut[c] <= v (0 when none), reading
 * neither cut[0] nor cut[TDC_TP_GRID]: against a linear search on cuts with
 * runs of equal values (empty cells), on every cut, beside it, below and
 * above all cuts, and for NaN (cell 0, as no comparison holds).  The
 * branch-free search must put every point where the branching one did, or
 * the bins would disagree with the counts.
 */
static void
test_cell_of(void)
{
	double	   *cut = malloc(sizeof(double) * (TDC_TP_GRID + 1));
	uint64_t	s = 7;
	long		wrong = 0,
				tried = 0;

	for (int round = 0; round < 4; round++)
	{
		double		c = -100;

		for (int i = 0; i <= TDC_TP_GRID; i++)
		{
			/* steps of 0 (equal cuts), tiny and large */
			uint64_t	r = tdc_splitmix64(&s) % 4;

			c += r == 0 ? 0 : r == 1 ? 1e-9 : (double) (tdc_splitmix64(&s) % 1000) / 7;
			cut[i] = c;
		}
		if (round == 3)
			cut[0] = cut[TDC_TP_GRID] = NAN;	/* must not be read */
		for (int i = 0; i <= TDC_TP_GRID + 1; i++)
		{
			double		base = i <= TDC_TP_GRID && !isnan(cut[i]) ? cut[i] : 1e9,
						vs[4] = {base, nextafter(base, -INFINITY), nextafter(base, INFINITY), -1e9};

			for (int k = 0; k < 4; k++)
			{
				int			want = 0;

				for (int j = 1; j < TDC_TP_GRID; j++)
					if (cut[j] <= vs[k])
						want = j;
				wrong += tdc_tp_cell_of(vs[k], 0, 0, cut) != want;
				tried++;
			}
		}
	}
	CHECK(wrong == 0, "tdc_tp_cell_of: %ld of %ld values in the wrong cell", wrong, tried);
	CHECK(tdc_tp_cell_of(NAN, 0, 0, cut) == 0, "NaN's cell is not 0");
	free(cut);
}

/*
 * The policy's hull cells and outer cell sides (tile_plan.c): on a uniform
 * grid of 512 x 512 unit cells, one point each, a corner tile of 64 x 64
 * cells takes the cells along the bottom and left hull edges outside it,
 * an edge at a time within the limit; the outer sides move to the true box
 * without moving a point.
 */
static void
test_hull_cells(void)
{
	tdc_tp_grid *g = malloc(sizeof(tdc_tp_grid));
	uint32_t   *counts = malloc(sizeof(uint32_t) * TDC_TP_GRID * TDC_TP_GRID),
			   *cells = malloc(sizeof(uint32_t) * TDC_TP_HULL_CELLS);
	double		box[4] = {0, 0, 512, 512},
				bb[4] = {0.25, 0.5, 511.5, 511.75},
				hull[8] = {0, 0, 512, 0, 512, 512, 0, 512};
	uint8_t		mark[4] = {1, 0, 0, 1};
	tdc_tp_tile ti = {0, 64, 0, 64, 4096, {0}};
	size_t		n;
	bool		ok = true;

	for (size_t c = 0; c < (size_t) TDC_TP_GRID * TDC_TP_GRID; c++)
		counts[c] = 1;
	tdc_tp_grid_set(g, box);
	n = tdc_tp_hull_cells(g, counts, &ti, hull, 4, mark, 100000, cells);
	for (size_t k = 0; k < n; k++)
		ok &= (cells[k] < TDC_TP_GRID && cells[k] >= 64) ||
			(cells[k] % TDC_TP_GRID == 0 && cells[k] / TDC_TP_GRID >= 64);
	CHECK(n == 2 * (TDC_TP_GRID - 64) && ok,
		  "hull cells of a corner tile: %zu, want the %d of the bottom row and left column outside it",
		  n, 2 * (TDC_TP_GRID - 64));
	n = tdc_tp_hull_cells(g, counts, &ti, hull, 4, mark, 500, cells);
	CHECK(n == TDC_TP_GRID - 64, "hull cells within 500 points: %zu, want one edge's %d", n,
		  TDC_TP_GRID - 64);
	mark[0] = mark[3] = 0;
	CHECK(tdc_tp_hull_cells(g, counts, &ti, hull, 4, mark, 100000, cells) == 0,
		  "no marked edge, yet hull cells");

	tdc_tp_grid_reach(g, bb);
	CHECK(g->xcut[0] == 0.25 && g->ycut[0] == 0.5 && g->xcut[TDC_TP_GRID] == 511.5 &&
		  g->ycut[TDC_TP_GRID] == 511.75 && g->xcut[1] == 1 && g->ycut[TDC_TP_GRID - 1] == 511,
		  "outer cell sides %g %g %g %g, want the true box", g->xcut[0], g->ycut[0],
		  g->xcut[TDC_TP_GRID], g->ycut[TDC_TP_GRID]);
	CHECK(tdc_tp_cell(g, 0.25, 0.5) == 0 && tdc_tp_cell(g, 511.5, 511.75) == TDC_TP_GRID * TDC_TP_GRID - 1,
		  "the true box's corners changed cell");
	free(g);
	free(counts);
	free(cells);
}

/*
 * The cells a rerun adds (tdc_tp_cells_fit): on the uniform grid of unit
 * cells, 100 points each, a tile of cells [0, 8) x [0, 8) asks for cells at
 * distances 30, 1, 10 and 5 (a cell already added among them): all when
 * they fit, else the nearest first as far as they fit, none when not even
 * the nearest does; and the requests' reach (tdc_tp_rings) doubles to its cap.
 */
static void
test_cells_fit(void)
{
	tdc_tp_grid *g = malloc(sizeof(tdc_tp_grid));
	uint32_t   *counts = malloc(sizeof(uint32_t) * TDC_TP_GRID * TDC_TP_GRID);
	uint8_t    *added = calloc((size_t) TDC_TP_GRID * TDC_TP_GRID, 1);
	double		box[4] = {0, 0, 512, 512};
	tdc_tp_tile ti = {0, 8, 0, 8, 6400, {0}};
	uint32_t	ask[4] = {38, 9, 18, 13},	/* row 0: gaps 30, 1, 10, 5 from column 8 */
				cells[4];
	size_t		k;

	for (size_t c = 0; c < (size_t) TDC_TP_GRID * TDC_TP_GRID; c++)
		counts[c] = 100;
	tdc_tp_grid_set(g, box);
	memcpy(cells, ask, sizeof(cells));
	k = tdc_tp_cells_fit(g, counts, added, &ti, cells, 4, 6400, 6800);
	CHECK(k == 4 && memcmp(cells, ask, sizeof(cells)) == 0, "all fit: %zu cells, want the 4 as asked", k);
	k = tdc_tp_cells_fit(g, counts, added, &ti, cells, 4, 6400, 6650);
	CHECK(k == 2 && cells[0] == 9 && cells[1] == 13 && cells[2] == 18 && cells[3] == 38,
		  "room for 2 cells: %zu, order %u %u %u %u, want 2 of 9 13 18 38", k, cells[0], cells[1],
		  cells[2], cells[3]);
	added[13] = 1;
	memcpy(cells, ask, sizeof(cells));
	k = tdc_tp_cells_fit(g, counts, added, &ti, cells, 4, 6400, 6650);
	CHECK(k == 3, "an added cell costs nothing: %zu cells, want 3", k);
	memcpy(cells, ask, sizeof(cells));
	CHECK(tdc_tp_cells_fit(g, counts, added, &ti, cells, 4, 6400, 6450) == 0,
		  "not even the nearest fits, yet cells");
	CHECK(tdc_tp_rings(0) == TDC_TP_FIRST_RINGS && tdc_tp_rings(1) == 2 * TDC_TP_FIRST_RINGS &&
		  tdc_tp_rings(100) == TDC_TP_RINGS_MAX, "rings %g %g %g", tdc_tp_rings(0), tdc_tp_rings(1),
		  tdc_tp_rings(100));
	free(g);
	free(counts);
	free(added);
}

/*
 * The hull cells' limit (tdc_tp_hull_limit): half the tile's own points at
 * least (1,000 at least), up to all of them while its K and they stay
 * within twice tile_max.  hull_edge_walk (test/cli.sh) is the case: a row
 * of cells along a side held more than half a border tile.
 */
static void
test_hull_limit(void)
{
	CHECK(tdc_tp_hull_limit(100000, 200000, 150000) == 100000, "room for all: %zu",
		  tdc_tp_hull_limit(100000, 200000, 150000));
	CHECK(tdc_tp_hull_limit(100000, 200000, 330000) == 70000, "room for 70,000: %zu",
		  tdc_tp_hull_limit(100000, 200000, 330000));
	CHECK(tdc_tp_hull_limit(100000, 200000, 390000) == 50000, "half at least: %zu",
		  tdc_tp_hull_limit(100000, 200000, 390000));
	CHECK(tdc_tp_hull_limit(100000, 200000, 500000) == 50000, "K past twice tile_max: %zu",
		  tdc_tp_hull_limit(100000, 200000, 500000));
	CHECK(tdc_tp_hull_limit(10, 200000, 0) == 1000, "a tiny tile: %zu", tdc_tp_hull_limit(10, 200000, 0));
}

static bool
covered_none(const void *arg, const double box[4])
{
	(void) arg;
	(void) box;
	return false;
}

/*
 * The cells a disk's request names (tdc_cells_disk), on 64 x 64 unit cells,
 * all OTHER but the tile's [0, 8) x [0, 8): a disk around (30, 30) of
 * radius 25 names the cells within the rings of the nearest to its own
 * vertex at (8.5, 30), not the far side of the disk; the disk of a sliver
 * along the side x = 64 (radius 1e6, centre far to the right), whose part
 * inside the clip is a strip 0.001 wide from y = 0 to 64, names every cell
 * of the column x in [63, 64), however far from its own vertex at
 * (63.9995, 4).  Without the strip rule it named the 9 nearest (4 rings),
 * and a tile along a side of 1e8 uniform points ran 5 times, a few cells
 * further along each time.
 */
static void
test_cells_disk(void)
{
	double		cut[65];
	uint8_t    *st = malloc(64 * 64);
	tdc_tile_grid g = {64, 64, cut, cut, st, 4};
	tdc_cells	c;
	tdc_cell_list out = {0};
	double		disk[3] = {30, 30, 25},
				clip[4] = {-INFINITY, -INFINITY, INFINITY, INFINITY},
				near[2] = {8.5, 30};
	bool		far = false,
				all = true;

	for (int i = 0; i <= 64; i++)
		cut[i] = i;
	for (int j = 0; j < 64; j++)
		for (int i = 0; i < 64; i++)
			st[j * 64 + i] = i < 8 && j < 8 ? TDC_TILE_CELL_KNOWN : TDC_TILE_CELL_OTHER;
	CHECK(tdc_cells_init(&c, &g), "cells: out of memory");
	CHECK(!tdc_cells_disk(&c, disk, clip, near, 1, covered_none, NULL, &out), "the disk meets OTHER cells");
	for (size_t k = 0; k < out.n; k++)
		far |= out.v[k] % 64 > 20;
	CHECK(out.n > 0 && !far, "a round disk: %zu cells named, some past column 20: %d", out.n, far);
	free(out.v);
	memset(&out, 0, sizeof(out));

	disk[0] = 63.9995 + 1e6;
	disk[1] = 32;
	disk[2] = 1e6;
	clip[0] = 63.999;
	clip[2] = 64;
	clip[1] = 0;
	clip[3] = 64;
	near[0] = 63.9995;
	near[1] = 4;
	CHECK(!tdc_cells_disk(&c, disk, clip, near, 1, covered_none, NULL, &out), "the strip meets OTHER cells");
	for (int j = 0; j < 64; j++)
	{
		bool		in = false;

		for (size_t k = 0; k < out.n; k++)
			in |= out.v[k] == (uint32_t) (j * 64 + 63);
		all &= in;
	}
	CHECK(all && out.n == 64, "a strip along x = 64: %zu cells named, every cell of the column: %d",
		  out.n, all);
	free(out.v);
	tdc_cells_free(&c);
	free(st);
}

/*
 * Square labels count from the origin, so that points far from (0, 0) in
 * tiny squares get small labels, and squares too small to number are
 * refused rather than wrapped.
 */
static void
test_square_labels(void)
{
	double		origin[2] = {5e6, 5e6};
	int64_t		l,
				prev = -1;
	bool		ok = true;

	/* 5e6 + [0, 1e-3) in squares of 6e-4: columns and rows 0 and 1 */
	CHECK(tdc_tp_square_label(5e6, 5e6, origin, 6e-4, &l) && l == 0, "origin's label %lld", (long long) l);
	CHECK(tdc_tp_square_label(5e6 + 9.9e-4, 5e6 + 7e-4, origin, 6e-4, &l) && l == 4294967297LL,
		  "far corner's label %lld, want column 1 row 1", (long long) l);
	/* monotone along x at 1e-9 squares */
	for (int i = 0; i < 1000 && ok; i++)
	{
		ok = tdc_tp_square_label(5e6 + i * 1e-7, 5e6, origin, 1e-9, &l) && l >= prev;
		prev = l;
	}
	CHECK(ok, "labels at 1e-9 squares are not monotone in x");
	CHECK(!tdc_tp_square_label(5e6 + 10, 5e6, origin, 1e-9, &l),
		  "a column past 2^31 must be refused");
	CHECK(!tdc_tp_square_label(5e6 - 1, 5e6, origin, 1, &l), "a point below the origin must be refused");
}

void
test_tile_plan(void)
{
	test_cell_of();
	test_hull_cells();
	test_cells_fit();
	test_hull_limit();
	test_cells_disk();
	test_square_labels();
}
