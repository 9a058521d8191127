/*
 * tile_cells.c
 *		Which OTHER cells of a tile's grid a circumdisk or the outer side of
 *		a hull edge meets (see tile_cells.h and tdc_tile_grid in tdc.h).
 *
 * Both answers are conservative in the one direction that matters: a cell
 * that may hold a point of the disk (of the open half-plane) is reported,
 * so "none reported" proves that every point of P there is in Q.  A cell's
 * closed box holds its points; a disk meets a row of cells over the x-range
 * of its widest slice in the row, taken with a relative slack of 1e-9 and
 * a few ulps of the magnitudes (the disk's radius already bounds the true
 * circle, tile_final.c's disk_box); a cell has a point strictly beyond a
 * line only if a corner of its box is, decided by the exact orientation.
 * Reporting a cell too many only makes the tile read its points.
 *
 * The cost: a prefix sum of the OTHER cells answers "none in this
 * rectangle" at once, which is the common case; a disk is then walked row
 * by row, a hull edge's side in boxes that double around the edge until
 * one holds an OTHER cell beyond it or the grid's box is covered.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "tile_cells.h"

#define EPS		0x1p-53

bool
tdc_cells_init(tdc_cells *c, const tdc_tile_grid *g)
{
	size_t		w;

	c->g = g;
	c->ps = NULL;
	if (g->nx < 1 || g->ny < 1 || g->xcut == NULL || g->ycut == NULL || g->cell == NULL)
		return false;
	w = (size_t) g->nx + 1;
	c->ps = calloc(w * ((size_t) g->ny + 1), sizeof(uint32_t));
	if (c->ps == NULL)
		return false;
	for (int j = 0; j < g->ny; j++)
		for (int i = 0; i < g->nx; i++)
			c->ps[(j + 1) * w + i + 1] = (g->cell[(size_t) j * g->nx + i] == TDC_TILE_CELL_OTHER) +
				c->ps[j * w + i + 1] + c->ps[(j + 1) * w + i] - c->ps[j * w + i];
	return true;
}

void
tdc_cells_free(tdc_cells *c)
{
	free(c->ps);
	c->ps = NULL;
}

/* OTHER cells in [i0, i1) x [j0, j1). */
static uint32_t
other_count(const tdc_cells *c, int i0, int i1, int j0, int j1)
{
	size_t		w = (size_t) c->g->nx + 1;

	if (i0 >= i1 || j0 >= j1)
		return 0;
	return c->ps[j1 * w + i1] - c->ps[j0 * w + i1] - c->ps[j1 * w + i0] + c->ps[j0 * w + i0];
}

/* The first cell i of n whose closed box reaches v or beyond: cut[i + 1] >= v (n if none). */
static int
first_reaching(const double *cut, int n, double v)
{
	int			lo = 0,
				hi = n;

	while (lo < hi)
	{
		int			mid = (lo + hi) / 2;

		if (cut[mid + 1] >= v)
			hi = mid;
		else
			lo = mid + 1;
	}
	return lo;
}

/* The number of cells i of n whose closed box starts at or before v: cut[i] <= v. */
static int
count_starting(const double *cut, int n, double v)
{
	int			lo = 0,
				hi = n;

	while (lo < hi)
	{
		int			mid = (lo + hi) / 2;

		if (cut[mid] <= v)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo;
}

static void
list_add(tdc_cell_list *l, uint32_t v)
{
	if (l->failed)
		return;
	if (l->n == l->cap)
	{
		size_t		nc = l->cap ? 2 * l->cap : 64;
		uint32_t   *t = realloc(l->v, nc * sizeof(uint32_t));

		if (t == NULL)
		{
			l->failed = true;
			return;
		}
		l->v = t;
		l->cap = nc;
	}
	l->v[l->n++] = v;
}

static void
cell_box(const tdc_tile_grid *g, int i, int j, double box[4])
{
	box[0] = g->xcut[i];
	box[1] = g->ycut[j];
	box[2] = g->xcut[i + 1];
	box[3] = g->ycut[j + 1];
}

/* The Chebyshev distance between closed boxes a and b (0 when they meet). */
static double
box_gap(const double *a, const double *b)
{
	return fmax(fmax(fmax(a[0] - b[2], b[0] - a[2]), fmax(a[1] - b[3], b[1] - a[3])), 0);
}

/*
 * Keeps in *dmin the least distance of a cell box to ref, and in *side the
 * larger side of that nearest cell: a request takes the cells within
 * the least distance plus that side, a ring of about one cell where
 * the cells are (small cells inside a cluster, large ones in sparse land).
 */
static void
nearest(const double *box, const double *ref, double *dmin, double *side)
{
	double		d = box_gap(box, ref);

	if (d < *dmin)
	{
		*dmin = d;
		*side = fmax(box[2] - box[0], box[3] - box[1]);
	}
}

/* The cell of v along one axis of n cells: the last c with cut[c] <= v, 0 when none. */
static int
cell_of(const double *cut, int n, double v)
{
	int			k = count_starting(cut, n, v);

	return k > 0 ? k - 1 : 0;
}

/* Is point p in a KNOWN cell (its points all passed)? */
bool
tdc_cells_point_known(const tdc_cells *c, const double *p)
{
	const tdc_tile_grid *g = c->g;

	return g->cell[(size_t) cell_of(g->ycut, g->ny, p[1]) * g->nx +
				   cell_of(g->xcut, g->nx, p[0])] == TDC_TILE_CELL_KNOWN;
}

/*
 * Does the closed disk (centre disk[0..1], radius disk[2]) meet no OTHER
 * cell that covered() does not vouch for?  Of the cells it does meet, the
 * nearest to the box near (the triangle's) are appended to out: those
 * within the least distance plus the nearest cell's side.  A disk of a triangle
 * at the edge of what the tile knows can reach far into the unknown (a
 * triangle on a coast whose disk spans a sea, with the far coast not yet
 * read); the points nearest to it, once known, usually cut it into small
 * triangles, so the far cells are asked for only if the disk survives.
 */
bool
tdc_cells_disk(const tdc_cells *c, const double disk[3], const double near[4],
			   tdc_cells_covered_fn covered, const void *arg, tdc_cell_list *out)
{
	const tdc_tile_grid *g = c->g;
	double		cx = disk[0],
				cy = disk[1],
				es = 8 * EPS * (fabs(cx) + fabs(cy) + disk[2]) + 0x1p-1000,
				R = disk[2] * (1 + 1e-9) + es;
	int			j0,
				j1,
				i0,
				i1;
	bool		none = true;
	double		dmin = INFINITY,
				margin = 0;

	if (!isfinite(R) || !isfinite(cx) || !isfinite(cy))
		return false;
	j0 = first_reaching(g->ycut, g->ny, cy - R);
	j1 = count_starting(g->ycut, g->ny, cy + R);
	i0 = first_reaching(g->xcut, g->nx, cx - R);
	i1 = count_starting(g->xcut, g->nx, cx + R);
	if (other_count(c, i0, i1, j0, j1) == 0)
		return true;
	/* pass 0 finds the least distance, pass 1 appends the cells near it */
	for (int pass = 0; pass < 2; pass++)
	for (int j = j0; j < j1; j++)
	{
		double		yb = fmin(fmax(cy, g->ycut[j]), g->ycut[j + 1]),
					dy = fabs(yb - cy),
					w;

		if (dy > R)
			continue;
		/* the half-width of the disk's widest slice in this row */
		w = sqrt(fmax(0, R * R - dy * dy) + 8 * EPS * R * R) * (1 + 1e-9) + es;
		i0 = first_reaching(g->xcut, g->nx, cx - w);
		i1 = count_starting(g->xcut, g->nx, cx + w);
		if (other_count(c, i0, i1, j, j + 1) == 0)
			continue;
		for (int i = i0; i < i1; i++)
		{
			double		box[4];

			if (g->cell[(size_t) j * g->nx + i] != TDC_TILE_CELL_OTHER)
				continue;
			cell_box(g, i, j, box);
			if (covered && covered(arg, box))
				continue;
			none = false;
			if (pass == 0)
				nearest(box, near, &dmin, &margin);
			else if (box_gap(box, near) <= dmin + margin)
				list_add(out, (uint32_t) j * (uint32_t) g->nx + (uint32_t) i);
		}
	}
	return none;
}

/*
 * Is every cell with a point strictly right of the line a -> b (the outer
 * side of a hull edge of Q, interior on the left) EMPTY, KNOWN or vouched
 * for by covered()?  Then no point of P lies beyond the edge that Q lacks,
 * and Q has none: the edge is a hull edge of P (Lemma 2).  Otherwise the
 * OTHER cells beyond it nearest to the edge (in the smallest of boxes
 * doubling around it that holds any, within the least distance
 * plus the nearest cell's side) are appended to out.
 */
bool
tdc_cells_beyond(const tdc_cells *c, const double *a, const double *b,
				 tdc_cells_covered_fn covered, const void *arg, tdc_cell_list *out)
{
	const tdc_tile_grid *g = c->g;
	double		gx0 = g->xcut[0],
				gy0 = g->ycut[0],
				gx1 = g->xcut[g->nx],
				gy1 = g->ycut[g->ny],
				len = fmax(fabs(b[0] - a[0]), fabs(b[1] - a[1])),
				grow = fmax(len, fmax(gx1 - gx0, gy1 - gy0) * 1e-4);
	uint32_t	seen = 0;
	double		eb[4] = {fmin(a[0], b[0]), fmin(a[1], b[1]), fmax(a[0], b[0]), fmax(a[1], b[1])},
				dmin = INFINITY,
				margin = 0;

	if (!(grow > 0) || !isfinite(grow))
		grow = 0x1p-1000;
	for (int step = 0; step < 200; step++, grow *= 2)
	{
		double		box[4] = {fmin(a[0], b[0]) - grow, fmin(a[1], b[1]) - grow,
		fmax(a[0], b[0]) + grow, fmax(a[1], b[1]) + grow};
		bool		all = box[0] <= gx0 && box[1] <= gy0 && box[2] >= gx1 && box[3] >= gy1;
		int			i0 = first_reaching(g->xcut, g->nx, box[0]),
					i1 = count_starting(g->xcut, g->nx, box[2]),
					j0 = first_reaching(g->ycut, g->ny, box[1]),
					j1 = count_starting(g->ycut, g->ny, box[3]);
		uint32_t	k = other_count(c, i0, i1, j0, j1);
		bool		found = false;

		/* pass 0 finds the least distance to the edge, pass 1 appends the cells near it */
		for (int pass = 0; pass < 2 && k > seen; pass++)
		{
			for (int j = j0; j < j1; j++)
			{
				if (other_count(c, i0, i1, j, j + 1) == 0)
					continue;
				for (int i = i0; i < i1; i++)
				{
					double		cb[4];
					bool		beyond = false;

					if (g->cell[(size_t) j * g->nx + i] != TDC_TILE_CELL_OTHER)
						continue;
					cell_box(g, i, j, cb);
					for (int q = 0; q < 4 && !beyond; q++)
					{
						double		p[2] = {cb[(q & 1) ? 2 : 0], cb[(q & 2) ? 3 : 1]};

						beyond = tdc_orient2d(a, b, p) < 0;
					}
					if (!beyond || (covered && covered(arg, cb)))
						continue;
					if (pass == 0)
						nearest(cb, eb, &dmin, &margin);
					else if (box_gap(cb, eb) <= dmin + margin)
						list_add(out, (uint32_t) j * (uint32_t) g->nx + (uint32_t) i);
					found = true;
				}
			}
		}
		seen = k;
		if (found)
			return false;
		if (all)
			return true;
	}
	return false;
}

/*
 * The cells of nlists lists, each once, in increasing order, into *cells
 * (malloc'd; NULL when none); the lists are freed.  False when out of
 * memory, here or in a list.
 */
bool
tdc_cells_merge(const tdc_cells *c, tdc_cell_list *lists, int nlists, uint32_t **cells,
				size_t *ncells)
{
	size_t		ncell = (size_t) c->g->nx * c->g->ny,
				n = 0;
	uint8_t    *mark = calloc(ncell, 1);
	bool		ok = mark != NULL;

	*cells = NULL;
	*ncells = 0;
	for (int l = 0; l < nlists; l++)
	{
		ok &= !lists[l].failed;
		for (size_t k = 0; mark && k < lists[l].n; k++)
			if (!mark[lists[l].v[k]])
			{
				mark[lists[l].v[k]] = 1;
				n++;
			}
		free(lists[l].v);
		memset(&lists[l], 0, sizeof(lists[l]));
	}
	if (ok && n > 0)
	{
		*cells = malloc(n * sizeof(uint32_t));
		if (*cells == NULL)
			ok = false;
		for (size_t k = 0; *cells && k < ncell; k++)
			if (mark[k])
				(*cells)[(*ncells)++] = (uint32_t) k;
	}
	free(mark);
	return ok;
}
