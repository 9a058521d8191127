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
 * circle, tdc_disk_box in tile_disk.c); a cell has a point strictly beyond a
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

#include "engine/predicates.h"
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

/* The distance from point p to the closed box b (0 inside it); no libm calls, it is hot. */
static double
point_gap(const double *b, const double *p)
{
	double		dx = b[0] - p[0] > 0 ? b[0] - p[0] : p[0] - b[2] > 0 ? p[0] - b[2] : 0,
				dy = b[1] - p[1] > 0 ? b[1] - p[1] : p[1] - b[3] > 0 ? p[1] - b[3] : 0;

	return dx == 0 ? dy : dy == 0 ? dx : sqrt(dx * dx + dy * dy);
}

/* The distance from point p to the segment a-b. */
static double
point_segment(const double *p, const double *a, const double *b)
{
	double		dx = b[0] - a[0],
				dy = b[1] - a[1],
				l2 = dx * dx + dy * dy,
				t = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0,
				ex,
				ey;

	t = t < 0 ? 0 : t > 1 ? 1 : t;
	ex = p[0] - (a[0] + t * dx);
	ey = p[1] - (a[1] + t * dy);
	return sqrt(ex * ex + ey * ey);
}

/*
 * The distance from the closed box b to the segment a-b (seg[0..3]): 0
 * when the segment meets the box (clipped as Liang and Barsky do), else
 * the least of the ends' distances to the box and the corners' to the
 * segment.  Rounded: it only orders the cells a request names.
 */
static double
segment_gap(const double *b, const double *seg)
{
	double		t0 = 0,
				t1 = 1,
				d[2] = {seg[2] - seg[0], seg[3] - seg[1]},
				m;
	bool		meets = true;

	for (int k = 0; k < 2 && meets; k++)
	{
		if (d[k] == 0)
			meets = seg[k] >= b[k] && seg[k] <= b[k + 2];
		else
		{
			double		u = (b[k] - seg[k]) / d[k],
						v = (b[k + 2] - seg[k]) / d[k];

			if (u > v)
			{
				double		w = u;

				u = v;
				v = w;
			}
			t0 = u > t0 ? u : t0;
			t1 = v < t1 ? v : t1;
			meets = t0 <= t1;
		}
	}
	if (meets)
		return 0;
	m = point_gap(b, seg);
	for (int q = 0; q < 5; q++)
	{
		double		c[2] = {b[(q & 1) ? 2 : 0], b[(q & 2) ? 3 : 1]},
					e = q == 4 ? point_gap(b, seg + 2) : point_segment(c, seg, seg + 2);

		m = e < m ? e : m;
	}
	return m;
}

/*
 * The distance that orders a request's cells: from the cell box to the
 * nearest of the nref points ref (a triangle's own vertices), or with
 * nref < 0 to the segment ref[0..3] (a hull edge).  A long diagonal edge
 * or a triangle with far-apart own vertices has a bounding box holding
 * much that is far from both: measured from that box, a hull edge of a
 * tile cut through a dense town named every town cell in the edge's box
 * (337,350 of them in one run).
 */
static double
ref_gap(const double *box, const double *ref, int nref)
{
	double		d = INFINITY;

	if (nref < 0)
		return segment_gap(box, ref);
	for (int k = 0; k < nref; k++)
	{
		double		e = point_gap(box, ref + 2 * k);

		d = e < d ? e : d;
	}
	return d;
}

/*
 * Keeps in *dmin the least distance of a cell box to ref (ref_gap), and
 * in *side the smaller side of that nearest cell (within_reach).  The
 * smaller side: the counting grid's cells are quantiles, so a cell in a
 * dense town's column but a sparse row is 0.02 wide and 56 tall, and its
 * larger side took the whole town into a request from beside it.
 */
static void
nearest(const double *box, const double *ref, int nref, double *dmin, double *side)
{
	double		d = ref_gap(box, ref, nref);

	if (d < *dmin)
	{
		*dmin = d;
		*side = fmin(box[2] - box[0], box[3] - box[1]);
	}
}

/*
 * Whether a request takes the cell box at distance d from ref, dmin and
 * side being those of the nearest cell (nearest()): within the least
 * distance plus the grid's rings (at least 1) of a cell's smaller side,
 * the nearest cell's or its own if smaller.  Its own too: along a hull
 * edge from sparse country to a dense town, the nearest cell is a large
 * one at the sparse end, and its side took the whole town beyond the
 * edge's other end.  Not a multiple of the distance: between tight
 * clusters the least distance is a hundred times a cluster's width, and
 * half again of it took whole clusters where their rims were needed.
 */
static bool
within_reach(const tdc_tile_grid *g, const double *box, double d, double dmin, double side)
{
	double		rings = g->rings > 1 ? g->rings : 1;

	return d <= dmin + rings * fmin(side, fmin(box[2] - box[0], box[3] - box[1]));
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
 * cell inside the box clip that covered() does not vouch for?  clip holds
 * every point of P in the disk (the disk's part inside C, tile_disk.c's
 * clip and segment boxes): the disk of a sliver along the hull has a
 * radius of 1e6 and meets the cells along the hull for hundreds of
 * spacings where its part inside C is a lens a few spacings long; without
 * the clip each tile along the hull of 1M uniform points ran 5 times.  Of the cells it does meet, the
 * nearest to the nnear points near (the triangle's own vertices) are
 * appended to out: those within_reach() of them (the least distance and
 * a ring of cells).  A disk of a triangle
 * at the edge of what the tile knows can reach far into the unknown (a
 * triangle on a coast whose disk spans a sea, with the far coast not yet
 * read); the points nearest to it, once known, usually cut it into small
 * triangles, so the far cells are asked for only if the disk survives.
 * But when its part inside clip is a strip under a quarter of the nearest
 * cell's smaller side thick, every cell it meets is appended: such is the
 * lens of a sliver along a hull edge, thinner than the points' spacing, so
 * the nearest points rarely cut it, and each rerun named the next few
 * cells along the edge while the same sliver survived (a tile on the
 * right side of 1e8 uniform points ran five times for a lens 0.0002 wide
 * and 730 long); the cells it meets are a line of them.
 */
bool
tdc_cells_disk(const tdc_cells *c, const double disk[3], const double clip[4], const double *near,
			   int nnear, tdc_cells_covered_fn covered, const void *arg, tdc_cell_list *out)
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
	bool		none = true,
				strip;
	double		dmin = INFINITY,
				margin = 0,
				thin;

	if (!isfinite(R) || !isfinite(cx) || !isfinite(cy))
		return false;
	/* the narrower side of the part of the disk's box inside clip */
	thin = fmin(fmin(cx + R, clip[2]) - fmax(cx - R, clip[0]),
				fmin(cy + R, clip[3]) - fmax(cy - R, clip[1]));
	j0 = first_reaching(g->ycut, g->ny, fmax(cy - R, clip[1]));
	j1 = count_starting(g->ycut, g->ny, fmin(cy + R, clip[3]));
	i0 = first_reaching(g->xcut, g->nx, fmax(cx - R, clip[0]));
	i1 = count_starting(g->xcut, g->nx, fmin(cx + R, clip[2]));
	if (other_count(c, i0, i1, j0, j1) == 0)
		return true;
	/*
	 * pass 0 finds the least distance, pass 1 appends the cells near it,
	 * or every cell it met when the disk's part inside clip is a strip
	 * under a quarter of the nearest cell's smaller side thick
	 */
	for (int pass = 0; pass < 2; pass++)
	{
		strip = pass == 1 && thin * 4 <= margin;
		for (int j = j0; j < j1; j++)
		{
			double		yb = fmin(fmax(cy, g->ycut[j]), g->ycut[j + 1]),
						dy = fabs(yb - cy),
						w;

			if (dy > R)
				continue;
			/* the half-width of the disk's widest slice in this row */
			w = sqrt(fmax(0, R * R - dy * dy) + 8 * EPS * R * R) * (1 + 1e-9) + es;
			i0 = first_reaching(g->xcut, g->nx, fmax(cx - w, clip[0]));
			i1 = count_starting(g->xcut, g->nx, fmin(cx + w, clip[2]));
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
					nearest(box, near, nnear, &dmin, &margin);
				else if (strip || within_reach(g, box, ref_gap(box, near, nnear), dmin, margin))
					list_add(out, (uint32_t) j * (uint32_t) g->nx + (uint32_t) i);
			}
		}
	}
	return none;
}

/*
 * Is every cell with a point strictly right of the line a -> b (the outer
 * side of a hull edge of Q, interior on the left) EMPTY, KNOWN or vouched
 * for by covered()?  Then no point of P lies beyond the edge that Q lacks,
 * and Q has none: the edge is a hull edge of P (Lemma 2).  Otherwise the
 * OTHER cells beyond it nearest to the segment a-b (in the smallest of
 * boxes doubling around it that holds any, within_reach() of the segment)
 * are appended to out.
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
	double		seg[4] = {a[0], a[1], b[0], b[1]},
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
						nearest(cb, seg, -1, &dmin, &margin);
					else if (within_reach(g, cb, ref_gap(cb, seg, -1), dmin, margin))
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
