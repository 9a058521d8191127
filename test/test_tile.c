/*
 * test_tile.c
 *		Tiled triangulation (tile_final.c): the union of the tiles' triangles must be
 *		the one-shot triangle set, triangle for triangle.
 *
 * The driver below is the caller's loop of tdc.h: every tile starts from the
 * bounding box of its own points plus a margin, gathers every point inside
 * its box K, and grows K to what tdc_tile_triangulate asks for until its
 * stars are final.  Tiles are any labelling of the points (a grid, random
 * labels, a line of points given its own label), because ownership must not
 * depend on the tiles being boxes.  Triangle sets are compared as sorted
 * lists of coordinate triples, each rotated so its smallest vertex comes
 * first (orientation is part of the check).
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "tdc.h"
#include "tiles/tile_plan.h"

typedef struct tset
{
	size_t		ntri;
	double	   *t;				/* 6 per triangle */
} tset;

typedef struct tile_stats
{
	size_t		rounds;			/* tile runs, retries included */
	size_t		retries;
	size_t		tiles;
	size_t		deep;			/* triangles final by a deep vertex, final rounds */
	int			rc;
} tile_stats;

static uint64_t rs;

/*
 * > 0: tiled() also passes, as extra boxes, the bounding box of every edge
 * of the convex hull grown by this fraction of the data's size, with their
 * points: the bands the command line adds so that border tiles need not
 * widen K along long hull edges.
 */
static double band;

/*
 * > 0: tiled() also passes a grid of cells_grid x cells_grid cells over the
 * data's box (tdc_tile_grid): empty cells, cells inside K and the cells a
 * run asked for are known, and a run that names cells gets their points
 * added with K unchanged, as ./tdc --max-memory does.  cells_stats counts
 * the runs that named cells and the most points a run held.
 */
static int	cells_grid;
static struct
{
	size_t		cell_reruns;
	size_t		max_points;
} cells_stats;

static int
cmp_dbl(const void *a, const void *b)
{
	double		u = *(const double *) a,
				v = *(const double *) b;

	return u < v ? -1 : u > v;
}

/* The cell of v along one axis of n cells: the last c with cut[c] <= v, 0 when none. */
static int
cell_index(const double *cut, int n, double v)
{
	int			c = 0;

	while (c + 1 < n && cut[c + 1] <= v)
		c++;
	return c;
}

static uint64_t
rng(void)
{
	uint64_t	z = (rs += 0x9E3779B97F4A7C15ull);

	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
	return z ^ (z >> 31);
}

static double
urand(void)
{
	return (rng() >> 11) * 0x1p-53;
}

static int
cmp_tri(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	for (int i = 0; i < 6; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

/* Append triangle (a, b, c), rotated so its lexicographically smallest vertex is first. */
static void
tset_add(tset *s, size_t *cap, const double *a, const double *b, const double *c)
{
	const double *v[3] = {a, b, c};
	int			lo = 0;

	if (s->ntri == *cap)
	{
		*cap = *cap ? 2 * *cap : 1024;
		s->t = realloc(s->t, 48 * *cap);
	}
	for (int k = 1; k < 3; k++)
		if (v[k][0] < v[lo][0] || (v[k][0] == v[lo][0] && v[k][1] < v[lo][1]))
			lo = k;
	for (int k = 0; k < 3; k++)
	{
		s->t[6 * s->ntri + 2 * k] = v[(lo + k) % 3][0];
		s->t[6 * s->ntri + 2 * k + 1] = v[(lo + k) % 3][1];
	}
	s->ntri++;
}

static bool
oneshot(const double *xy, size_t n, tset *s)
{
	tdc_job    *job;
	char		err[256];
	size_t		cap = 0;
	tdc_iter	it = {0};
	uint32_t	v[3];

	s->ntri = 0;
	s->t = NULL;
	if (tdc_triangulate(xy, n, NULL, &job, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "one-shot failed: %s", err);
		tdc_job_free(job);
		return false;
	}
	while (tdc_next_triangle(job, &it, v))
		tset_add(s, &cap, tdc_site_xy(job, v[0]), tdc_site_xy(job, v[1]), tdc_site_xy(job, v[2]));
	tdc_job_free(job);
	if (s->ntri > 0)
		qsort(s->t, s->ntri, 48, cmp_tri);
	return true;
}

/*
 * The points a tile is run with: those in its known box K or in one of the
 * nextra extra boxes (closed), or whose cell (pcell) is marked in added,
 * with their owners' labels, into q and ql.  Returns how many.
 */
static size_t
gather_known(const double *xy, const int64_t *lab, size_t n, const double *K,
			 const double *extra, size_t nextra, const int *pcell, const uint8_t *added,
			 double *q, int64_t *ql)
{
	size_t		m = 0;

	for (size_t i = 0; i < n; i++)
	{
		bool		in = xy[2 * i] >= K[0] && xy[2 * i] <= K[2] &&
			xy[2 * i + 1] >= K[1] && xy[2 * i + 1] <= K[3];

		for (size_t e = 0; e < nextra && !in; e++)
			in = xy[2 * i] >= extra[4 * e] && xy[2 * i] <= extra[4 * e + 2] &&
				xy[2 * i + 1] >= extra[4 * e + 1] && xy[2 * i + 1] <= extra[4 * e + 3];
		if (!in && added)
			in = added[pcell[i]];
		if (in)
		{
			q[2 * m] = xy[2 * i];
			q[2 * m + 1] = xy[2 * i + 1];
			ql[m++] = lab[i];
		}
	}
	return m;
}

/*
 * The caller's loop for every label 0 .. ntiles - 1.  halo: the first K is
 * the own points' box grown by halo times its larger side (0: no halo, the
 * grow-and-retry path does all the work).  box_extent: give the 4 corners of
 * the bounding box as C instead of the convex hull.
 */
static void
tiled(const double *xy, size_t n, const int64_t *lab, int64_t ntiles, double halo,
	  bool box_extent, int weaken, tset *s, tile_stats *st)
{
	double	   *hull = NULL,
				bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
	size_t		nhull = 0,
				cap = 0;
	double	   *q = malloc(16 * n + 16);
	int64_t    *ql = malloc(8 * n + 8);
	/* the cells (cells_grid > 0): cuts, each point's cell, counts, states, added marks */
	int			G = cells_grid;
	double	   *xcut = NULL,
			   *ycut = NULL;
	int		   *pcell = NULL;
	uint32_t   *ccount = NULL;
	uint8_t    *cst = NULL,
			   *added = NULL;
	tdc_tile_grid tg = {0};

	memset(st, 0, sizeof(*st));
	s->ntri = 0;
	s->t = NULL;
	for (size_t i = 0; i < n; i++)
	{
		bb[0] = fmin(bb[0], xy[2 * i]);
		bb[1] = fmin(bb[1], xy[2 * i + 1]);
		bb[2] = fmax(bb[2], xy[2 * i]);
		bb[3] = fmax(bb[3], xy[2 * i + 1]);
	}
	if (G > 0)
	{
		xcut = malloc(sizeof(double) * (G + 1));
		ycut = malloc(sizeof(double) * (G + 1));
		pcell = malloc(sizeof(int) * (n + 1));
		ccount = calloc((size_t) G * G, sizeof(uint32_t));
		cst = malloc((size_t) G * G);
		added = calloc((size_t) G * G, 1);
		/* the cell sides at the quantiles of the points, as ./tdc takes them from a sample */
		{
			double	   *sx = malloc(8 * n + 8),
					   *sy = malloc(8 * n + 8);

			for (size_t i = 0; i < n; i++)
			{
				sx[i] = xy[2 * i];
				sy[i] = xy[2 * i + 1];
			}
			qsort(sx, n, 8, cmp_dbl);
			qsort(sy, n, 8, cmp_dbl);
			for (int c = 0; c <= G; c++)
			{
				xcut[c] = c == 0 ? bb[0] : c == G ? bb[2] : sx[(size_t) c * n / G];
				ycut[c] = c == 0 ? bb[1] : c == G ? bb[3] : sy[(size_t) c * n / G];
			}
			free(sx);
			free(sy);
		}
		for (size_t i = 0; i < n; i++)
		{
			pcell[i] = cell_index(ycut, G, xy[2 * i + 1]) * G + cell_index(xcut, G, xy[2 * i]);
			ccount[pcell[i]]++;
		}
		tg.nx = tg.ny = G;
		tg.xcut = xcut;
		tg.ycut = ycut;
		tg.cell = cst;
	}
	if (box_extent)
	{
		hull = malloc(64);
		memcpy(hull, (double[8]) {bb[0], bb[1], bb[2], bb[1], bb[2], bb[3], bb[0], bb[3]}, 64);
		nhull = 4;
	}
	else
		tdc_convex_hull(xy, n, &hull, &nhull);

	double	   *extra = NULL;
	size_t		nextra = 0;

	if (band > 0 && nhull >= 2)
	{
		double		w = band * fmax(bb[2] - bb[0], bb[3] - bb[1]);

		extra = malloc(32 * nhull);
		for (size_t i = 0; i < nhull; i++)
		{
			const double *a = hull + 2 * i,
					   *b = hull + 2 * ((i + 1) % nhull);

			extra[4 * i] = fmin(a[0], b[0]) - w;
			extra[4 * i + 1] = fmin(a[1], b[1]) - w;
			extra[4 * i + 2] = fmax(a[0], b[0]) + w;
			extra[4 * i + 3] = fmax(a[1], b[1]) + w;
		}
		nextra = nhull;
	}
	for (int64_t t = 0; t < ntiles; t++)
	{
		tdc_tile_spec sp = {0};
		double		own[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
		double		w;

		for (size_t i = 0; i < n; i++)
			if (lab[i] == t)
			{
				own[0] = fmin(own[0], xy[2 * i]);
				own[1] = fmin(own[1], xy[2 * i + 1]);
				own[2] = fmax(own[2], xy[2 * i]);
				own[3] = fmax(own[3], xy[2 * i + 1]);
			}
		if (own[0] > own[2])
		{
			/* an empty tile: any box will do, it owns nothing */
			own[0] = own[2] = n ? xy[0] : 0;
			own[1] = own[3] = n ? xy[1] : 0;
		}
		w = fmax(own[2] - own[0], own[3] - own[1]) * halo;
		sp.known[0] = own[0] - w;
		sp.known[1] = own[1] - w;
		sp.known[2] = own[2] + w;
		sp.known[3] = own[3] + w;
		sp.hull = hull;
		sp.nhull = nhull;
		sp.self = t;
		sp.test_weaken = weaken;
		sp.extra = extra;
		sp.nextra = nextra;
		sp.grid = G > 0 ? &tg : NULL;
		if (added)
			memset(added, 0, (size_t) G * G);
		st->tiles++;
		for (;;)
		{
			tdc_tile_result res;
			char		err[256];
			const double *K = sp.known;
			size_t		m = gather_known(xy, lab, n, K, extra, nextra, pcell, added, q, ql);

			for (int j = 0; j < G; j++)
				for (int i = 0; i < G; i++)
					cst[j * G + i] = ccount[j * G + i] == 0 ? TDC_TILE_CELL_EMPTY :
						added[j * G + i] || (xcut[i] >= K[0] && xcut[i + 1] <= K[2] &&
											 ycut[j] >= K[1] && ycut[j + 1] <= K[3]) ?
						TDC_TILE_CELL_KNOWN : TDC_TILE_CELL_OTHER;
			if (m > cells_stats.max_points)
				cells_stats.max_points = m;
			sp.tile = ql;
			st->rounds++;
			st->rc = tdc_tile_triangulate(q, m, &sp, NULL, &res, err, sizeof(err));
			if (st->rc != TDC_OK)
			{
				CHECK(0, "tile %lld failed: %s", (long long) t, err);
				tdc_tile_result_free(&res);
				goto out;
			}
			if (res.final)
			{
				st->deep += res.deep;
				for (size_t k = 0; k < res.ntri; k++)
					tset_add(s, &cap, q + 2 * res.tri[3 * k], q + 2 * res.tri[3 * k + 1],
							 q + 2 * res.tri[3 * k + 2]);
				tdc_tile_result_free(&res);
				break;
			}
			if (res.nneed_cells > 0)
			{
				bool		fresh = true;

				/* only cells not known yet, or the loop would not end */
				for (size_t k = 0; k < res.nneed_cells; k++)
				{
					fresh &= res.need_cells[k] < (uint32_t) (G * G) && cst[res.need_cells[k]] == TDC_TILE_CELL_OTHER;
					added[res.need_cells[k] % ((uint32_t) G * G)] = 1;
				}
				CHECK(G > 0 && fresh, "tile %lld: named cells that are not OTHER", (long long) t);
				if (getenv("TDC_TILE_VERBOSE") && getenv("TDC_TILE_VERBOSE")[0] == '2')
					printf("    tile %lld: %zu points, %zu items not final, %zu cells named\n",
						   (long long) t, m, res.unfinal, res.nneed_cells);
				cells_stats.cell_reruns++;
				st->retries++;
				tdc_tile_result_free(&res);
				if (!fresh)
					goto out;
				continue;
			}
			/* the box must grow, or the loop would not end */
			if (!(res.need[0] <= K[0] && res.need[1] <= K[1] && res.need[2] >= K[2] &&
				  res.need[3] >= K[3] &&
				  (res.need[0] < K[0] || res.need[1] < K[1] || res.need[2] > K[2] ||
				   res.need[3] > K[3])))
			{
				CHECK(0, "tile %lld: the needed box does not grow", (long long) t);
				tdc_tile_result_free(&res);
				goto out;
			}
			if (getenv("TDC_TILE_VERBOSE") && getenv("TDC_TILE_VERBOSE")[0] == '2')
				printf("    tile %lld: %zu items not final (%zu own sites); K %g %g %g %g -> %g %g %g %g\n",
					   (long long) t, res.unfinal, res.own_sites, K[0], K[1], K[2], K[3],
					   res.need[0], res.need[1], res.need[2], res.need[3]);
			memcpy(sp.known, res.need, sizeof(sp.known));
			st->retries++;
			tdc_tile_result_free(&res);
		}
	}
out:
	if (s->ntri > 0)
		qsort(s->t, s->ntri, 48, cmp_tri);
	free(xcut);
	free(ycut);
	free(pcell);
	free(ccount);
	free(cst);
	free(added);
	free(extra);
	free(hull);
	free(q);
	free(ql);
}

static bool
tset_equal(const tset *a, const tset *b)
{
	return a->ntri == b->ntri && (a->ntri == 0 || memcmp(a->t, b->t, 48 * a->ntri) == 0);
}

/* Labels of a gx x gy grid over the bounding box (borders go to the upper tile). */
static int64_t *
grid_labels(const double *xy, size_t n, int gx, int gy)
{
	int64_t    *lab = malloc(8 * n + 8);
	double		bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	for (size_t i = 0; i < n; i++)
	{
		bb[0] = fmin(bb[0], xy[2 * i]);
		bb[1] = fmin(bb[1], xy[2 * i + 1]);
		bb[2] = fmax(bb[2], xy[2 * i]);
		bb[3] = fmax(bb[3], xy[2 * i + 1]);
	}
	for (size_t i = 0; i < n; i++)
	{
		double		fx = bb[2] > bb[0] ? (xy[2 * i] - bb[0]) / (bb[2] - bb[0]) * gx : 0,
					fy = bb[3] > bb[1] ? (xy[2 * i + 1] - bb[1]) / (bb[3] - bb[1]) * gy : 0;
		int			ix = (int) fx,
					iy = (int) fy;

		ix = ix < 0 ? 0 : ix >= gx ? gx - 1 : ix;
		iy = iy < 0 ? 0 : iy >= gy ? gy - 1 : iy;
		lab[i] = (int64_t) iy * gx + ix;
	}
	return lab;
}

/* One-shot vs tiled on several grids; returns retries seen. */
static size_t
check_grids(const char *name, const double *xy, size_t n, double halo)
{
	static const int grids[][2] = {{1, 1}, {2, 2}, {3, 5}, {7, 4}};
	tset		one,
				til;
	size_t		retries = 0;

	if (!oneshot(xy, n, &one))
		return 0;
	for (size_t g = 0; g < sizeof(grids) / sizeof(grids[0]); g++)
	{
		int64_t    *lab = grid_labels(xy, n, grids[g][0], grids[g][1]);
		tile_stats st;

		tiled(xy, n, lab, (int64_t) grids[g][0] * grids[g][1], halo, false, 0, &til, &st);
		CHECK(st.rc == TDC_OK && tset_equal(&one, &til),
			  "%s, grid %dx%d: tiled %zu triangles, one-shot %zu, %s", name, grids[g][0],
			  grids[g][1], til.ntri, one.ntri,
			  tset_equal(&one, &til) ? "same" : "different sets");
		retries += st.retries;
		if (getenv("TDC_TILE_VERBOSE"))
			printf("  %s %dx%d: %zu triangles, %zu rounds for %zu tiles\n", name, grids[g][0],
				   grids[g][1], til.ntri, st.rounds, st.tiles);
		free(til.t);
		free(lab);
	}
	free(one.t);
	return retries;
}

/* Same, for a given labelling; returns the stats. */
static tile_stats
check_labels(const char *name, const double *xy, size_t n, const int64_t *lab, int64_t ntiles,
			 double halo, bool box_extent)
{
	tset		one,
				til;
	tile_stats	st = {0};

	if (!oneshot(xy, n, &one))
		return st;
	tiled(xy, n, lab, ntiles, halo, box_extent, 0, &til, &st);
	CHECK(st.rc == TDC_OK && tset_equal(&one, &til),
		  "%s: tiled %zu triangles, one-shot %zu, %s", name, til.ntri, one.ntri,
		  tset_equal(&one, &til) ? "same" : "different sets");
	free(til.t);
	free(one.t);
	return st;
}

static double *
gen_uniform(size_t n, double scale, double ox, double oy)
{
	double	   *xy = malloc(16 * n + 16);

	for (size_t i = 0; i < n; i++)
	{
		xy[2 * i] = ox + urand() * scale;
		xy[2 * i + 1] = oy + urand() * scale;
	}
	return xy;
}

static double *
gen_clustered(size_t n)
{
	double	   *xy = malloc(16 * n + 16);
	double		cx = 0,
				cy = 0;

	for (size_t i = 0; i < n; i++)
	{
		if (i % 500 == 0)
		{
			cx = urand() * 1000;
			cy = urand() * 1000;
		}
		xy[2 * i] = cx + (urand() + urand() + urand() - 1.5) * 6;
		xy[2 * i + 1] = cy + (urand() + urand() + urand() - 1.5) * 6;
	}
	return xy;
}

static double *
gen_lattice(size_t side, double step, double ox, double oy)
{
	double	   *xy = malloc(16 * side * side + 16);

	for (size_t i = 0; i < side; i++)
		for (size_t j = 0; j < side; j++)
		{
			xy[2 * (i * side + j)] = ox + i * step;
			xy[2 * (i * side + j) + 1] = oy + j * step;
		}
	return xy;
}

/* Lattice points on circles with many representations (cocircular sets). */
static double *
gen_circles(size_t *n)
{
	static const long radii[] = {5, 25, 65, 325, 1105};
	size_t		k = 0;
	double	   *xy = malloc(16 * 65536);

	for (size_t r = 0; r < sizeof(radii) / sizeof(radii[0]); r++)
	{
		long		R = radii[r];

		for (long x = -R; x <= R; x++)
		{
			long		y2 = R * R - x * x;
			long		y = (long) llround(sqrt((double) y2));

			if (y * y != y2)
				continue;
			xy[2 * k] = x;
			xy[2 * k + 1] = y;
			k++;
			if (y != 0)
			{
				xy[2 * k] = x;
				xy[2 * k + 1] = -y;
				k++;
			}
		}
	}
	*n = k;
	return xy;
}

/*
 * The numbers of a file, in order, as x, y pairs: a JSON array of [x, y]
 * pairs, or WKT lines of 2-D geometries (a word such as LINESTRING is no
 * number: a token counts only when strtod reads it whole).
 */
static double *
read_number_pairs(const char *path, size_t *n)
{
	FILE	   *f = fopen(path, "r");
	size_t		cap = 1024,
				k = 0;
	double	   *v;
	int			c;
	char		buf[64];
	size_t		len = 0;

	*n = 0;
	if (f == NULL)
		return NULL;
	v = malloc(8 * cap);
	while ((c = fgetc(f)) != EOF || len)
	{
		if (c != EOF && (strchr("0123456789.-+eE", c) != NULL) && len < sizeof(buf) - 1)
		{
			buf[len++] = (char) c;
			continue;
		}
		if (len)
		{
			char	   *end;
			double		x;

			buf[len] = '\0';
			x = strtod(buf, &end);
			if (end == buf + len)
			{
				if (k == cap)
					v = realloc(v, 8 * (cap *= 2));
				v[k++] = x;
			}
			len = 0;
		}
		if (c == EOF)
			break;
	}
	fclose(f);
	*n = k / 2;
	return v;
}

static void
test_distributions(void)
{
	size_t		big = tdc_test_quick ? 5000 : 30000,
				n,
				retries = 0;
	double	   *xy;
	int64_t    *lab;
	tile_stats	st;

	rs = 7;
	xy = gen_uniform(big, 1000, 0, 0);
	retries += check_grids("uniform", xy, big, 0.05);
	/* no halo at all: only the grow-and-retry path makes it right */
	lab = grid_labels(xy, big, 4, 4);
	st = check_labels("uniform, 4x4, no halo (grow and retry)", xy, big, lab, 16, 0, false);
	CHECK(st.retries >= 16, "no halo: %zu retries for 16 tiles, expected every tile to retry",
		  st.retries);
	/* bands along the hull edges as extra boxes: fewer retries, same set */
	{
		tile_stats plain;

		st = check_labels("uniform, 4x4, 5 % halo", xy, big, lab, 16, 0.05, false);
		plain = st;
		band = 0.01;
		st = check_labels("uniform, 4x4, 5 % halo, hull bands", xy, big, lab, 16, 0.05, false);
		CHECK(st.retries < plain.retries, "hull bands: %zu retries, without %zu", st.retries,
			  plain.retries);
		retries += check_grids("uniform, hull bands", xy, big, 0.05);
		band = 0;
	}
	/* the bounding box instead of the hull as the extent: slower, same set */
	st = check_labels("uniform, 4x4, box extent", xy, big, lab, 16, 0.05, true);
	free(lab);
	free(xy);

	xy = gen_clustered(big);
	retries += check_grids("clustered", xy, big, 0.05);
	free(xy);

	/* lattices: cocircular squares, and rows of points exactly on the tile borders */
	xy = gen_lattice(61, 1, 0, 0);
	retries += check_grids("integer lattice 61x61", xy, 61 * 61, 0.05);
	lab = grid_labels(xy, 61 * 61, 3, 4);	/* borders at x = 20, 40 and y = 15, 30, 45 */
	check_labels("lattice, 3x4 tiles on lattice lines", xy, 61 * 61, lab, 12, 0, false);
	free(lab);
	free(xy);
	xy = gen_lattice(40, 0.125, 5e6, 6e6);
	retries += check_grids("lattice at 5e6 offsets", xy, 1600, 0.05);
	free(xy);
	xy = gen_circles(&n);
	retries += check_grids("cocircular lattice points", xy, n, 0.05);
	free(xy);

	xy = gen_uniform(5000, 0.001, 5e6, 4.2e6);
	retries += check_grids("5e6 + sub-millimetre", xy, 5000, 0.05);
	free(xy);
	xy = gen_uniform(3000, 1e55, 0, 0);
	retries += check_grids("huge scale 1e55", xy, 3000, 0.05);
	free(xy);
	xy = gen_uniform(3000, 1e-50, 1e-45, 1e-45);
	retries += check_grids("tiny scale 1e-50", xy, 3000, 0.05);
	free(xy);

	/* sites one ulp apart: slivers whose circles the error bound must handle */
	xy = malloc(16 * 3000);
	for (size_t i = 0; i < 1000; i++)
	{
		double		x = 1 + urand(),
					y = 1 + urand();

		xy[6 * i] = x;
		xy[6 * i + 1] = y;
		xy[6 * i + 2] = nextafter(x, 3);
		xy[6 * i + 3] = y;
		xy[6 * i + 4] = x;
		xy[6 * i + 5] = nextafter(y, 0);
	}
	retries += check_grids("one ulp apart", xy, 3000, 0.05);
	free(xy);

	/* collinear sites along the hull, random interior */
	xy = malloc(16 * 2000);
	for (size_t i = 0; i < 1000; i++)
	{
		double		f = (double) (i % 250);
		double		p[4][2] = {{f, 0}, {250, f}, {250 - f, 250}, {0, 250 - f}};

		xy[2 * i] = p[i / 250][0];
		xy[2 * i + 1] = p[i / 250][1];
	}
	for (size_t i = 1000; i < 2000; i++)
	{
		xy[2 * i] = 1 + urand() * 248;
		xy[2 * i + 1] = 1 + urand() * 248;
	}
	retries += check_grids("collinear hull sites", xy, 2000, 0.05);
	free(xy);

	/* the fixtures: a coastline (Ukraine's border) and delaunator's robustness cases */
	{
		static const char *files[] = {"ukraine", "robustness1", "robustness2",
		"robustness3", "robustness4", "issue13", "issue44"};

		for (size_t f = 0; f < sizeof(files) / sizeof(files[0]); f++)
		{
			char		path[512];

			snprintf(path, sizeof(path), "%s/test/fixtures/delaunator/%s.json",
					 TDC_SOURCE_DIR, files[f]);
			xy = read_number_pairs(path, &n);
			CHECK(xy != NULL && n > 10, "cannot read %s", path);
			if (xy)
				retries += check_grids(files[f], xy, n, 0.05);
			free(xy);
		}
	}
	/*
	 * The GSHHG shoreline of the Stockholm archipelago: real, clustered
	 * coastline vertices, every ring's first vertex twice.
	 */
	{
		char		path[512];

		snprintf(path, sizeof(path), "%s/test/fixtures/gshhg-stockholm.wkt", TDC_SOURCE_DIR);
		xy = read_number_pairs(path, &n);
		CHECK(xy != NULL && n == 17548, "%s: %zu vertices, want 17548", path, n);
		if (xy && n == 17548)
			retries += check_grids("gshhg-stockholm", xy, n, 0.05);
		free(xy);
	}
	/* at 5 % halo some tiles of these sets must have grown */
	CHECK(retries > 0, "no tile ever retried over all distributions");
}

static void
test_small_tiles_and_duplicates(void)
{
	size_t		n = 300;
	double	   *xy;
	int64_t    *lab;
	tile_stats	st;

	rs = 11;
	/* tiles of 1-3 points and many empty tiles: a 12 x 12 grid over 300 points */
	xy = gen_uniform(n, 100, 0, 0);
	lab = grid_labels(xy, n, 12, 12);
	st = check_labels("300 points in 144 tiles", xy, n, lab, 144, 0.5, false);
	{
		size_t		cnt[144] = {0},
					empty = 0,
					small = 0;

		for (size_t i = 0; i < n; i++)
			cnt[lab[i]]++;
		for (int t = 0; t < 144; t++)
			empty += cnt[t] == 0, small += cnt[t] >= 1 && cnt[t] <= 3;
		CHECK(empty > 0 && small > 20, "grid should have empty and 1-3 point tiles: %zu, %zu",
			  empty, small);
	}
	free(lab);
	/* random labels: tiles are scattered sets, not boxes */
	lab = malloc(8 * n);
	for (size_t i = 0; i < n; i++)
		lab[i] = (int64_t) (rng() % 40);
	check_labels("random labels, 40 scattered tiles", xy, n, lab, 40, 0.1, false);
	/* one point per tile */
	for (size_t i = 0; i < n; i++)
		lab[i] = (int64_t) i;
	check_labels("one point per tile", xy, n, lab, (int64_t) n, 0, false);

	/* duplicates split across tiles: the copy with the smallest label owns the site */
	for (size_t i = 150; i < n; i++)
	{
		size_t		j = rng() % 150;

		xy[2 * i] = xy[2 * j];
		xy[2 * i + 1] = xy[2 * j + 1];
	}
	for (size_t i = 0; i < n; i++)
		lab[i] = (int64_t) (rng() % 9);
	check_labels("duplicates with random labels", xy, n, lab, 9, 0.2, false);
	for (size_t i = 0; i < n; i++)
		lab[i] = i < 150 ? 5 : 2;	/* every later copy in another, smaller-labelled tile */
	check_labels("duplicates, copies in another tile", xy, n, lab, 9, 0.2, false);
	free(lab);
	free(xy);

	/* a tile whose points are all collinear, inside random points */
	n = 2000;
	xy = gen_uniform(n, 100, 0, 0);
	lab = grid_labels(xy, n, 3, 3);
	for (size_t i = 0; i < 40; i++)
	{
		xy[2 * i] = 20 + i * 1.5;
		xy[2 * i + 1] = 30 + i * 0.75;
		lab[i] = 9;
	}
	check_labels("a collinear tile", xy, n, lab, 10, 0.1, false);
	check_labels("a collinear tile, box extent", xy, n, lab, 10, 0.1, true);
	free(lab);
	free(xy);

	/* degenerate inputs: everything collinear, one point, two, three, none */
	xy = malloc(16 * 500);
	lab = malloc(8 * 500);
	for (size_t i = 0; i < 500; i++)
	{
		xy[2 * i] = (double) (rng() % 300);
		xy[2 * i + 1] = 3 * xy[2 * i] - 7;
		lab[i] = (int64_t) (i % 5);
	}
	check_labels("all collinear", xy, 500, lab, 5, 0, false);
	free(lab);
	/* segments of the line as tiles; the box as extent cannot certify the line */
	lab = grid_labels(xy, 500, 5, 1);
	st = check_labels("all collinear, 5 segments, box extent", xy, 500, lab, 5, 0, true);
	CHECK(st.retries > 0, "all collinear, box extent: no tile had to grow (%zu rounds)", st.rounds);
	for (size_t k = 0; k <= 3; k++)
	{
		char		name[64];
		double		p[6] = {1, 1, 5, 2, 3, 7};
		int64_t		l[3] = {0, 1, 1};

		snprintf(name, sizeof(name), "%zu points in 2 tiles", k);
		check_labels(name, p, k, l, 2, 0, false);
	}
	free(lab);
	free(xy);
}

/*
 * The disk test is what makes the result exact: with every triangle taken as
 * final, tiles with a thin halo emit triangles that are not global ones.
 * First on random points, then on a built case: the flat triangle
 * (0,0) (10,0) (5,1) of tile 0 has its circle centred at (5,-12), radius 13;
 * the point (5,-3) of tile 1 lies inside it but outside K.  Three halo
 * points far away make the own sites interior to the local hull, so no hull
 * edge test can notice: only the disk test does.
 */
static void
test_weakened_check_is_caught(void)
{
	size_t		n = tdc_test_quick ? 3000 : 10000;
	double	   *xy;
	int64_t    *lab;
	tset		one,
				weak,
				good;
	tile_stats	st;
	double		adv[] = {0, 0, 10, 0, 5, 1, -40, -0.4, 50, -0.4, 5, 50, 5, -3, -40, -40, 50, -40};
	int64_t		advl[] = {0, 0, 0, 1, 1, 1, 1, 1, 1};
	double	   *hull;
	size_t		nhull;
	tdc_tile_spec sp = {.tile = advl, .self = 0, .known = {-45, -0.5, 55, 55}};
	tdc_tile_result res;
	char		err[256];
	bool		bogus = false;

	rs = 3;
	xy = gen_uniform(n, 1000, 0, 0);
	lab = grid_labels(xy, n, 4, 4);
	oneshot(xy, n, &one);
	tiled(xy, n, lab, 16, 0.02, false, TDC_TILE_WEAKEN_DISKS, &weak, &st);
	CHECK(!tset_equal(&one, &weak),
		  "weakened finality check: tiled set equals one-shot (%zu vs %zu), the test shows nothing",
		  weak.ntri, one.ntri);
	tiled(xy, n, lab, 16, 0.02, false, 0, &good, &st);
	CHECK(tset_equal(&one, &good), "real check: %zu vs %zu triangles", good.ntri, one.ntri);
	free(one.t);
	free(weak.t);
	free(good.t);
	free(lab);
	free(xy);

	/* the built case: Q is the first 6 points, inside K */
	oneshot(adv, 9, &one);
	tdc_convex_hull(adv, 9, &hull, &nhull);
	sp.hull = hull;
	sp.nhull = nhull;
	sp.test_weaken = TDC_TILE_WEAKEN_DISKS;
	CHECK(tdc_tile_triangulate(adv, 6, &sp, NULL, &res, err, sizeof(err)) == TDC_OK && res.final,
		  "weakened: %s final %d", err, res.final);
	for (size_t k = 0; k < res.ntri; k++)
	{
		tset		t = {0};
		size_t		cap = 0;

		tset_add(&t, &cap, adv + 2 * res.tri[3 * k], adv + 2 * res.tri[3 * k + 1],
				 adv + 2 * res.tri[3 * k + 2]);
		if (bsearch(t.t, one.t, one.ntri, 48, cmp_tri) == NULL)
			bogus = true;
		free(t.t);
	}
	CHECK(bogus, "weakened check emitted no wrong triangle on the built case");
	tdc_tile_result_free(&res);
	sp.test_weaken = 0;
	CHECK(tdc_tile_triangulate(adv, 6, &sp, NULL, &res, err, sizeof(err)) == TDC_OK &&
		  !res.final && res.need[1] <= -3,
		  "real check: final %d, need ymin %g (must reach the point at y = -3)", res.final,
		  res.need[1]);
	tdc_tile_result_free(&res);
	tiled(adv, 9, advl, 2, 0.1, false, 0, &good, &st);
	CHECK(tset_equal(&one, &good), "built case tiled: %zu vs %zu", good.ntri, one.ntri);
	free(good.t);
	free(one.t);
	free(hull);
}

/*
 * Deep sites (tile_final.c, mark_deep): a site whose neighbourhood of blocks has
 * no empty block has every circumdisk inside K, unless it is near K's side.
 * Uniform points with a round hole of radius 60 centred on x = 500; tile 0
 * owns the points left of x = 450 and is run with K reaching x = 520, so
 * that all its own sites near the hole are far enough from K's side to be
 * deep if the hole's empty blocks were not counted.  The hole's local
 * triangles have circles of about its radius, which reach past K to the
 * rim points of tile 1 at x = 560: not global triangles.  Taking every
 * block as non-empty (TDC_TILE_WEAKEN_BLOCKS) certifies them and the tiled
 * set differs from the one-shot set; counting the empty blocks sends them
 * through the disk test, tile 0 grows, and the sets agree.  On the same
 * points without the hole, most triangles are certified from the counts
 * alone (res.deep), with the same set.
 */
static void
test_deep_sites(void)
{
	size_t		n = tdc_test_quick ? 20000 : 60000,
				m = 0;
	double	   *xy,
			   *holed = malloc(16 * n);
	int64_t    *lab = malloc(8 * n);
	tset		one,
				weak,
				good;
	tile_stats	st;

	rs = 5;
	xy = gen_uniform(n, 1000, 0, 0);
	for (size_t i = 0; i < n; i++)
	{
		double		dx = xy[2 * i] - 500,
					dy = xy[2 * i + 1] - 500;

		if (dx * dx + dy * dy > 60 * 60)
		{
			holed[2 * m] = xy[2 * i];
			holed[2 * m + 1] = xy[2 * i + 1];
			m++;
		}
	}

	/* bands along the hull, as the CLI gives: tile 0 is final at once on its other sides */
	band = 0.01;
	for (size_t i = 0; i < n; i++)
		lab[i] = xy[2 * i] < 450 ? 0 : 1;
	CHECK(oneshot(xy, n, &one), "one-shot failed");
	tiled(xy, n, lab, 2, 0.07, false, 0, &good, &st);
	CHECK(tset_equal(&one, &good), "uniform, 2 tiles: %zu vs %zu triangles", good.ntri, one.ntri);
	CHECK(st.deep > one.ntri / 4,
		  "uniform, 2 tiles: only %zu of %zu triangles certified by deep sites", st.deep, one.ntri);
	free(one.t);
	free(good.t);

	for (size_t i = 0; i < m; i++)
		lab[i] = holed[2 * i] < 450 ? 0 : 1;
	CHECK(oneshot(holed, m, &one), "one-shot failed");
	tiled(holed, m, lab, 2, 0.07, false, TDC_TILE_WEAKEN_BLOCKS, &weak, &st);
	CHECK(!tset_equal(&one, &weak),
		  "every block taken as non-empty: tiled set equals one-shot (%zu vs %zu), the test shows nothing",
		  weak.ntri, one.ntri);
	tiled(holed, m, lab, 2, 0.07, false, 0, &good, &st);
	CHECK(tset_equal(&one, &good), "hole across K's side: %zu vs %zu triangles", good.ntri,
		  one.ntri);
	CHECK(st.retries > 0, "hole across K's side: no tile had to grow");
	band = 0;
	free(one.t);
	free(weak.t);
	free(good.t);
	free(lab);
	free(holed);
	free(xy);
}

static void
test_tile_errors(void)
{
	double		p[6] = {0, 0, 1, 0, 0, 1};
	int64_t		l[3] = {0, 0, 0};
	double		hull[6] = {0, 0, 1, 0, 0, 1};
	tdc_tile_spec sp = {.tile = l, .self = 0, .known = {0, 0, 0.5, 1}, .hull = hull, .nhull = 3};
	tdc_tile_result res;
	tdc_options opt;
	char		err[256];
	double	   *h;
	size_t		nh;
	double		sq[] = {0, 0, 2, 0, 1, 0, 2, 2, 0, 2, 1, 1, 2, 1, 0, 0};

	CHECK(tdc_tile_triangulate(p, 3, &sp, NULL, &res, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "outside the known box"), "point outside K accepted: %s", err);
	tdc_tile_result_free(&res);
	sp.known[2] = 1;
	tdc_options_init(&opt);
	opt.tolerance = 0.1;
	CHECK(tdc_tile_triangulate(p, 3, &sp, &opt, &res, err, sizeof(err)) == TDC_EINVAL,
		  "tolerance accepted");
	tdc_tile_result_free(&res);
	CHECK(tdc_tile_triangulate(p, 3, &sp, NULL, &res, err, sizeof(err)) == TDC_OK &&
		  res.final && res.ntri == 1, "whole set in one tile: final %d, %zu triangles",
		  res.final, res.ntri);
	tdc_tile_result_free(&res);

	/* the hull drops collinear and duplicate points and runs counter-clockwise */
	CHECK(tdc_convex_hull(sq, 8, &h, &nh) == TDC_OK && nh == 4 &&
		  h[0] == 0 && h[1] == 0 && h[2] == 2 && h[3] == 0 && h[4] == 2 && h[5] == 2,
		  "hull of a square with edge midpoints: %zu vertices", nh);
	free(h);
}

/*
 * A sliver along a long hull edge: a point 2^-30 under the top side of the
 * square makes a triangle over a hull edge 700 long with a circle of radius
 * about 6e13.  A bound on its part inside C through the computed centre
 * (clip_box) carries rounding far larger than the segment's height and
 * does not shrink the disk's box, so the corner tile asked for the whole
 * side (the same happened with slivers 1e-4 under a side in the CLI's 10M
 * point runs, where two corner tiles ran eleven times each).  The segment
 * over the edge, bounded from the angle at the third vertex, stays in the
 * band: the corner tile, given as the CLI does the bands of the hull edges
 * that meet its K, is final at once; and the tiled set is the one-shot set.
 */
static void
test_hull_sliver(void)
{
	size_t		body = tdc_test_quick ? 20000 : 60000,
				n = body + 3,
				nhull,
				m = 0,
				nextra = 0;
	double	   *xy = malloc(16 * n),
			   *q = malloc(16 * n),
			   *hull,
			   *extra;
	int64_t    *lab = malloc(8 * n),
			   *ql = malloc(8 * n);
	double		K[4] = {-30, 670, 330, 1030},
				w = 10;
	tdc_tile_spec sp = {0};
	tdc_tile_result res;
	char		err[256];

	rs = 11;
	for (size_t i = 0; i < body; i++)
	{
		xy[2 * i] = urand() * 1000;
		xy[2 * i + 1] = urand() * 1000;
	}
	/* the hull's top side, and a point just under it */
	memcpy(xy + 2 * body, (double[6]) {50, 1000, 750, 1000, 600, 1000 - 0x1p-30}, 48);
	/* the corner tile [0, 300] x [700, 1000] against the rest */
	for (size_t i = 0; i < n; i++)
		lab[i] = xy[2 * i] <= 300 && xy[2 * i + 1] >= 700 ? 0 : 1;

	tdc_convex_hull(xy, n, &hull, &nhull);
	extra = malloc(32 * nhull);
	for (size_t i = 0; i < nhull; i++)
	{
		const double *a = hull + 2 * i,
				   *b = hull + 2 * ((i + 1) % nhull);
		double	   *e = extra + 4 * nextra;

		e[0] = fmin(a[0], b[0]) - w;
		e[1] = fmin(a[1], b[1]) - w;
		e[2] = fmax(a[0], b[0]) + w;
		e[3] = fmax(a[1], b[1]) + w;
		if (e[0] <= K[2] && K[0] <= e[2] && e[1] <= K[3] && K[1] <= e[3])
			nextra++;
	}
	m = gather_known(xy, lab, n, K, extra, nextra, NULL, NULL, q, ql);
	memcpy(sp.known, K, sizeof(K));
	sp.hull = hull;
	sp.nhull = nhull;
	sp.extra = extra;
	sp.nextra = nextra;
	sp.tile = ql;
	sp.self = 0;
	CHECK(tdc_tile_triangulate(q, m, &sp, NULL, &res, err, sizeof(err)) == TDC_OK && res.final,
		  "hull sliver: the corner tile with %zu hull bands is not final at once (asks for %g %g %g %g) %s",
		  nextra, res.need[0], res.need[1], res.need[2], res.need[3], err);
	tdc_tile_result_free(&res);

	band = 0.01;
	check_labels("hull sliver, corner tile and the rest, hull bands", xy, n, lab, 2, 0.1, false);
	band = 0;
	free(xy);
	free(q);
	free(lab);
	free(ql);
	free(hull);
	free(extra);
}

/* k-d labels: alternate x and y cuts at the median until a tile holds at most cap points. */
static const double *kd_xy;
static int	kd_axis;

static int
cmp_kd(const void *a, const void *b)
{
	double		u = kd_xy[2 * *(const size_t *) a + kd_axis],
				v = kd_xy[2 * *(const size_t *) b + kd_axis];

	return u < v ? -1 : u > v;
}

static void
kd_split(const double *xy, size_t *idx, size_t n, size_t cap, int axis, int64_t *lab, int64_t *nt)
{
	if (n <= cap)
	{
		for (size_t i = 0; i < n; i++)
			lab[idx[i]] = *nt;
		(*nt)++;
		return;
	}
	kd_xy = xy;
	kd_axis = axis;
	qsort(idx, n, sizeof(size_t), cmp_kd);
	kd_split(xy, idx, n / 2, cap, 1 - axis, lab, nt);
	kd_split(xy, idx + n / 2, n - n / 2, cap, 1 - axis, lab, nt);
}

static int64_t *
kd_labels(const double *xy, size_t n, size_t cap, int64_t *nt)
{
	int64_t    *lab = malloc(8 * n + 8);
	size_t	   *idx = malloc(sizeof(size_t) * (n + 1));

	for (size_t i = 0; i < n; i++)
		idx[i] = i;
	*nt = 0;
	kd_split(xy, idx, n, cap, 0, lab, nt);
	free(idx);
	return lab;
}

/*
 * Tiles with cells (tdc_tile_grid) on clustered data: the tiled set is the
 * one-shot set.  No halo: the first run knows the tile's own points only,
 * and the cells the check names bring in what the stars need, around the
 * tile rather than a box.  (The most points a run held is printed with
 * TDC_TILE_VERBOSE; the memory bound itself is checked through ./tdc
 * --max-memory in test/cli.sh, on the same kinds of data.)
 */
static void
check_cells(const char *name, const double *xy, size_t n, size_t cap)
{
	int64_t		nt;
	int64_t    *lab = kd_labels(xy, n, cap, &nt);
	tile_stats	st;

	cells_grid = 64;
	memset(&cells_stats, 0, sizeof(cells_stats));
	st = check_labels(name, xy, n, lab, nt, 0, false);
	if (getenv("TDC_TILE_VERBOSE"))
		printf("  %s (cells): %lld tiles, %zu rounds, %zu named cells, at most %zu points of %zu\n",
			   name, (long long) nt, st.rounds, cells_stats.cell_reruns, cells_stats.max_points, n);
	cells_grid = 0;
	free(lab);
}

static void
test_cells(void)
{
	size_t		n,
				total = 0;
	double	   *xy;
	char		path[512];

	rs = 28;
	/* the Stockholm archipelago's shoreline: islands in water */
	snprintf(path, sizeof(path), "%s/test/fixtures/gshhg-stockholm.wkt", TDC_SOURCE_DIR);
	xy = read_number_pairs(path, &n);
	CHECK(xy != NULL && n == 17548, "%s: %zu vertices, want 17548", path, n);
	if (xy && n == 17548)
	{
		check_cells("gshhg-stockholm", xy, n, n / 8);
		total += cells_stats.cell_reruns;
	}
	free(xy);

	/* 9 tight clusters (sigma 0.3) in a 1000 square */
	n = 9000;
	xy = malloc(16 * n);
	for (size_t c = 0; c < 9; c++)
	{
		double		cx = 50 + urand() * 900,
					cy = 50 + urand() * 900;

		for (size_t i = c * 1000; i < (c + 1) * 1000; i++)
		{
			xy[2 * i] = cx + (urand() + urand() + urand() - 1.5) * 0.6;
			xy[2 * i + 1] = cy + (urand() + urand() + urand() - 1.5) * 0.6;
		}
	}
	check_cells("9 tight clusters", xy, n, n / 12);
	total += cells_stats.cell_reruns;
	free(xy);

	/* a dense town (6000 points in a 10 square) in sparse country (2000 in 1000) */
	n = 8000;
	xy = malloc(16 * n);
	for (size_t i = 0; i < n; i++)
	{
		xy[2 * i] = i < 2000 ? urand() * 1000 : 400 + urand() * 10;
		xy[2 * i + 1] = i < 2000 ? urand() * 1000 : 600 + urand() * 10;
	}
	check_cells("dense town in sparse country", xy, n, n / 10);
	total += cells_stats.cell_reruns;
	free(xy);

	/* a strip 1000 x 20 with gaps of 100 and 250 (LiDAR with missing passes) */
	n = 8000;
	xy = malloc(16 * n);
	for (size_t i = 0; i < n; i++)
	{
		double		x = urand() * 650;

		xy[2 * i] = x < 200 ? x : x < 350 ? x + 100 : x + 350;
		xy[2 * i + 1] = urand() * 20;
	}
	check_cells("strip with gaps", xy, n, n / 10);
	total += cells_stats.cell_reruns;
	free(xy);
	CHECK(total > 0, "no run named cells on any clustered set");
}

void
test_tile(void)
{
	test_cells();
	test_tile_plan();
	test_tile_errors();
	test_hull_sliver();
	test_distributions();
	test_small_tiles_and_duplicates();
	test_weakened_check_is_caught();
	test_deep_sites();
}
