/*
 * test_raster_tiles.c
 *		A grid in tiles (tdc_raster_*, src/core/terrain/raster*.c): the
 *		bounded run's final triangles rasterised tile by tile give the whole
 *		TIN's grid (tdc_tin_grid_start), every pixel's double bit for bit.
 *
 *	- uniform samples on a smooth surface, the grid's extent beyond their
 *	  box on every side: pixels inside (faces), and outside the hull the
 *	  nearest site at any distance (linear's default), within a radius,
 *	  or none (radius=0); nodata=-9999; max_edge; and a "window" of them,
 *	  narrower than their box, whose rows cross the hull beside the grid;
 *	- "lattice on the pixels": samples on a unit lattice with pixels of
 *	  0.5 whose centres fall on sites, on the edges of the lattice (its
 *	  sides and, half of them, its diagonals) and inside triangles, with a
 *	  lake of no samples and max_edge: the vertex, edge and face rules and
 *	  the mask, where a walk and a scan of one triangle must agree;
 *	- "projected offset": samples around (500000, 4000000), where the
 *	  formulas' roundings are largest;
 *	- "diamond": a hull of slanted sides inside the grid's box, whose
 *	  corners' pixels take the nearest of the samples along the hull
 *	  (fringe.c: a test of the triangles' circumdisks against the hull's
 *	  box alone would miss the samples those pixels take);
 *	- "clusters": dense spots in a sparse field, so tiles differ in size;
 *	- nearest (raster_nearest.c) on each: the site each triangle offers
 *	  around it, with its radius and max_edge's mask; on the lattice,
 *	  centres equidistant from several sites take the first in (x, y);
 *	- natural neighbour (raster_natural.c) on each: every pixel's cavity
 *	  proven global in its tile's own triangulation, or the tile run
 *	  again; on the lattice the pixel centres at the squares' centres have
 *	  cavities of cocircular triangles, which a tile must see as the whole
 *	  triangulation does; max_edge, radius=0, near the hull (the diamond);
 *	- the same grid with 1 and 2 threads (two tiles at once); many tiles
 *	  (the stats say);
 *	- the refusals: breaklines, a collinear input, each with its message;
 *	  no file left in the directory.
 * A check that compared a few values, or that the grid merely has the
 * right size, would pass with a wrong edge rule; every pixel is compared.
 */
#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"
#include "tiles_test.h"

typedef struct rt_case
{
	const char *name;
	double	   *xy,
			   *z;
	size_t		n;
	double		extent[4];
	double		cell;
	size_t		limit_mb;
	int			workers;		/* 2: two tile workers expected with 2 threads (0: one or two) */
	const tdc_grid_spec *grid;	/* NULL: north-up over extent, pixels of cell */
} rt_case;

typedef struct rt_state
{
	tdc_interp_spec spec;
	tdc_grid_spec g;
	const char *dir;
	tdc_raster *ras;
	pthread_mutex_t mu;			/* err: both workers emit at once */
	char		err[512];
	int			begins;
	int			reruns;			/* natural neighbour: tiles that asked for a larger K */
} rt_state;

double
tiles_u01(uint64_t *s)
{
	return tdc_splitmix64(s) / 18446744073709551616.0;
}

static int
rt_begin(void *arg, const double box[4], const double *hull, size_t nhull, size_t *hold)
{
	rt_state   *s = arg;

	(void) box;
	s->begins++;
	return tdc_raster_begin(&s->spec, &s->g, hull, nhull, s->dir, 2, &s->ras, hold, s->err,
							sizeof(s->err));
}

static int
rt_emit(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
		const size_t *tri, size_t ntri)
{
	rt_state   *s = arg;
	char		err[512];
	int			rc;

	(void) tile;
	(void) ql;
	if (s->spec.method == TDC_INTERP_NATURAL)
		return 0;				/* rt_final_run took the tile */
	if ((rc = tdc_raster_tile(s->ras, q, qz, tri, ntri, err, sizeof(err))) != TDC_OK)
	{
		pthread_mutex_lock(&s->mu);
		if (s->err[0] == '\0')
			snprintf(s->err, sizeof(s->err), "%s", err);
		pthread_mutex_unlock(&s->mu);
	}
	return rc;
}

/* natural neighbour: the tile's whole triangulation, or what it needs more (1) */
static int
rt_final_run(void *arg, const tdc_job *job, const double *q, const double *qz, size_t m,
			 const size_t *tri, size_t ntri, const tdc_tile_spec *spec, tdc_tile_result *more)
{
	rt_state   *s = arg;
	int			rc = tdc_raster_nn_tile(s->ras, job, q, qz, m, tri, ntri, spec, more, s->err,
										sizeof(s->err));

	s->reruns += rc == 1;
	return rc;
}

int
tiles_files_in(const char *dir)
{
	DIR		   *d = opendir(dir);
	struct dirent *e;
	int			k = 0;

	if (d == NULL)
		return -1;
	while ((e = readdir(d)) != NULL)
		if (e->d_name[0] != '.' && strncmp(e->d_name, "input", 5) != 0)
			k++;
	closedir(d);
	return k;
}

static int
write_file(const char *path, const double *v, size_t count)
{
	FILE	   *f = fopen(path, "wb");

	if (f == NULL)
		return -1;
	if (fwrite(v, sizeof(double), count, f) != count)
	{
		fclose(f);
		return -1;
	}
	return fclose(f);
}

/* The grid of c under method by the whole TIN: values (nodata where none). */
static double *
whole_grid(const rt_case *c, const tdc_interp_spec *spec, const tdc_grid_spec *g, int threads,
		   size_t *valid)
{
	tdc_options opt;
	tdc_job    *job = NULL;
	tdc_tin    *tin = NULL;
	char		err[512];
	double	   *v = malloc(8 * g->width * g->height);
	uint8_t    *ok = malloc(g->width * g->height);
	int			rc;

	tdc_options_init(&opt);
	opt.threads = threads;
	*valid = 0;
	rc = tdc_triangulate(c->xy, c->n, &opt, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "raster %s: one-shot: %s", c->name, err);
	if (rc == TDC_OK)
		rc = tdc_tin_build(job, c->z, threads, 0, &tin, err, sizeof(err));
	CHECK(rc == TDC_OK, "raster %s: TIN: %s", c->name, err);
	if (rc == TDC_OK)
	{
		rc = tdc_tin_grid_start(tin, spec, g, v, ok, err, sizeof(err));
		if (rc == TDC_OK)
			rc = tdc_tin_wait(tin, -1);
		CHECK(rc == TDC_OK, "raster %s: the whole grid: %d %s", c->name, rc, err);
	}
	for (size_t i = 0; i < g->width * g->height; i++)
		*valid += ok[i];
	if (tin)
		tdc_tin_free(tin);
	if (job)
		tdc_job_free(job);
	free(ok);
	return v;
}

/* The grid of c under method in tiles, or NULL with s->err / err. */
static double *
tiled_grid(const rt_case *c, rt_state *s, const char *dir, int threads, size_t *valid,
		   int *tiles, int *rc_out, char *err, size_t errlen)
{
	char		xyp[4200],
				zp[4200];
	tdc_options opt;
	tdc_bounded_params p;
	tdc_bounded_stats st;
	double	   *v = NULL;
	int			rc;

	snprintf(xyp, sizeof(xyp), "%s/input.xy", dir);
	snprintf(zp, sizeof(zp), "%s/input.z", dir);
	tdc_options_init(&opt);
	opt.threads = threads;
	memset(&p, 0, sizeof(p));
	p.xypath = xyp;
	p.zpath = zp;
	p.n = c->n;
	p.opt = &opt;
	/* nearest's window of offers (4 MB of 32-byte records) beside linear's 2 MB */
	p.limit = (c->limit_mb + (s->spec.method == TDC_INTERP_NEAREST ? 4 : 0)) << 20;
	p.tmpdir = dir;
	p.begin = rt_begin;
	p.emit = rt_emit;
	if (s->spec.method == TDC_INTERP_NATURAL)
	{
		p.final_run = rt_final_run;
		p.final_per_point = TDC_RASTER_NN_PER_POINT;
	}
	p.arg = s;
	/*
	 * as ./tdc: the output does not depend on the tiles' order, so two run
	 * at once, and hand their tiles over at once (the raster's windows)
	 */
	p.any_order = true;
	p.emit_concurrent = true;
	pthread_mutex_init(&s->mu, NULL);
	s->dir = dir;
	s->ras = NULL;
	s->err[0] = '\0';
	*valid = 0;
	err[0] = '\0';
	rc = tdc_bounded_run(&p, &st, err, errlen);
	*tiles = st.tiles;
	/* one worker with one thread; two where the case makes room for them (else one or two) */
	CHECK(rc != TDC_OK || (threads < 2 ? st.workers == 1 : c->workers == 2 ? st.workers == 2 :
						   st.workers >= 1 && st.workers <= 2),
		  "raster %s in tiles: %d workers with %d threads", c->name, st.workers, threads);
	if (rc == TDC_OK)
	{
		v = malloc(8 * s->g.width * s->g.height);
		for (size_t y = 0; rc == TDC_OK && y < s->g.height; y += 37)
		{
			size_t		k = s->g.height - y < 37 ? s->g.height - y : 37;

			rc = tdc_raster_rows(s->ras, y, k, v + y * s->g.width, valid, (size_t) 64 << 20,
								 err, errlen);
		}
	}
	if (rc != TDC_OK && s->err[0])
		snprintf(err, errlen, "%s", s->err);
	tdc_raster_free(s->ras);
	s->ras = NULL;
	*rc_out = rc;
	if (rc != TDC_OK)
	{
		free(v);
		return NULL;
	}
	return v;
}

static void
grid_of(const rt_case *c, tdc_grid_spec *g)
{
	double		w = ceil((c->extent[2] - c->extent[0]) / c->cell),
				h = ceil((c->extent[3] - c->extent[1]) / c->cell);

	if (c->grid)
	{
		*g = *c->grid;
		return;
	}
	g->width = (size_t) w;
	g->height = (size_t) h;
	g->gt[0] = c->extent[0];
	g->gt[1] = c->cell;
	g->gt[2] = 0;
	g->gt[3] = c->extent[1] + h * c->cell;
	g->gt[4] = 0;
	g->gt[5] = -c->cell;
}

/* One case under one method: every pixel the same bits, the same count of values. */
static void
compare(const rt_case *c, const char *method, const char *dir, int threads)
{
	rt_state	s = {0};
	char		err[1024];
	double	   *v1,
			   *v2;
	size_t		valid1,
				valid2,
				differ = 0,
				first = 0;
	int			tiles = 0,
				rc;

	CHECK(tdc_interp_parse(method, &s.spec, err, sizeof(err)) == TDC_OK, "raster: parse %s", method);
	grid_of(c, &s.g);
	v1 = whole_grid(c, &s.spec, &s.g, threads, &valid1);
	v2 = tiled_grid(c, &s, dir, threads, &valid2, &tiles, &rc, err, sizeof(err));
	CHECK(rc == TDC_OK && v2 != NULL, "raster %s %s: the tiled grid failed: %d %s", c->name, method, rc, err);
	if (v2)
	{
		for (size_t i = 0; i < s.g.width * s.g.height; i++)
			if (memcmp(v1 + i, v2 + i, 8) != 0)
			{
				if (differ++ == 0)
					first = i;
			}
		CHECK(differ == 0, "raster %s %s (%d threads): %zu of %zu pixels differ, the first "
			  "(col %zu, row %zu) %.17g in tiles against %.17g", c->name, method, threads, differ,
			  s.g.width * s.g.height, first % s.g.width, first / s.g.width, v2[first], v1[first]);
		CHECK(valid1 == valid2, "raster %s %s: %zu pixels with a value in tiles, %zu whole",
			  c->name, method, valid2, valid1);
		/* the sanitizers' --quick inputs are a third the size: fewer tiles */
		CHECK(tiles >= (tdc_test_quick || c->workers > 1 ? 3 : c->grid ? 10 : 8),
			  "raster %s %s: %d tiles, at least %d expected", c->name, method, tiles,
			  tdc_test_quick || c->workers > 1 ? 3 : c->grid ? 10 : 8);
		CHECK(valid1 > 0 && valid1 < s.g.width * s.g.height * 2, "raster %s %s: %zu valid",
			  c->name, method, valid1);
		if (getenv("TDC_TEST_VERBOSE"))
			fprintf(stderr, "raster %s %s: %d tiles, %d reruns for natural neighbour\n", c->name,
					method, tiles, s.reruns);
	}
	CHECK(tiles_files_in(dir) == 0, "raster %s %s: files left in %s", c->name, method, dir);
	free(v1);
	free(v2);
}

bool
tiles_stage(const char *dir, const double *xy, const double *z, size_t n)
{
	char		p[4200];

	snprintf(p, sizeof(p), "%s/input.xy", dir);
	if (write_file(p, xy, 2 * n) != 0)
		return false;
	snprintf(p, sizeof(p), "%s/input.z", dir);
	return write_file(p, z, n) == 0;
}

/* The refusals, each with its message and nothing left behind. */
static void
refusals(rt_case *c, const char *dir)
{
	rt_state	s = {0};
	char		err[1024];
	size_t		valid;
	int			tiles,
				rc;
	double	   *v;

	grid_of(c, &s.g);
	tdc_interp_parse("linear:breaklines=true", &s.spec, err, sizeof(err));
	v = tiled_grid(c, &s, dir, 2, &valid, &tiles, &rc, err, sizeof(err));
	CHECK(v == NULL && rc == TDC_EINVAL && strstr(err, "cannot take breaklines") != NULL,
		  "raster: breaklines in tiles: %d %s", rc, err);
	CHECK(tiles_files_in(dir) == 0, "raster: refusals: files left in %s", dir);
}

/*
 * A grid of w x h pixels centred on (cx, cy), pixel matrix (a b; d e)
 * (gt[1], gt[2]; gt[4], gt[5]).
 */
static tdc_grid_spec
grid_at(double cx, double cy, size_t w, size_t h, double a, double b, double d, double e)
{
	tdc_grid_spec g;

	g.width = w;
	g.height = h;
	g.gt[1] = a;
	g.gt[2] = b;
	g.gt[4] = d;
	g.gt[5] = e;
	g.gt[0] = cx - ((double) w / 2 * a + (double) h / 2 * b);
	g.gt[3] = cy - ((double) w / 2 * d + (double) h / 2 * e);
	return g;
}

/*
 * Skewed, rotated and flipped grids over case c (samples in the 1000 x
 * 1000 square from (ox, oy)), each reaching past the samples' hull on
 * every side: the pixel ranges of triangles, tiles, hull spans and
 * nearest's pieces go through the inverse of the pixel matrix (raster.c's
 * pixel_matrix); a grid its bounds were too narrow for would lose pixels,
 * a count that differs.
 */
static void
skewed(rt_case *c, const char *dir, double ox, double oy, bool all)
{
	double		th = 0.5235987755982988;	/* 30 degrees */
	tdc_grid_spec skew = grid_at(ox + 500, oy + 500, 470, 430, 2.2, 0.8, -0.5, -2.4),
				rot = grid_at(ox + 500.3, oy + 499.1, 440, 450, 2.6 * cos(th), 2.6 * sin(th),
							  2.6 * sin(th), -2.6 * cos(th)),
				flip = grid_at(ox + 500, oy + 500, 430, 440, -2.5, 0, 0, 2.5),
				mirror = grid_at(ox + 501, oy + 498, 450, 460, 2.3, 0.4, 0.3, 2.1);
	const char *name = c->name;
	static const char *const methods[] = {
		"linear", "linear:max_edge=6", "linear:radius=30:nodata=-9999", "nearest",
		"nearest:max_edge=6", "nearest:radius1=3:radius2=3:nodata=-9999"
	};

	c->grid = &skew;
	c->name = "skewed";
	for (size_t m = 0; m < (all ? sizeof(methods) / sizeof(methods[0]) : 1); m++)
		compare(c, methods[m], dir, 2);
	c->grid = &rot;
	c->name = "rotated";
	compare(c, "linear:max_edge=6:radius=20", dir, 2);
	compare(c, "nearest", dir, 2);
	compare(c, "natural_neighbor", dir, 2);
	if (all)
	{
		compare(c, "linear", dir, 1);
		compare(c, "nearest:max_edge=6", dir, 2);
		c->grid = &flip;
		c->name = "flipped";
		compare(c, "linear", dir, 2);
		compare(c, "nearest:max_edge=6", dir, 2);
		compare(c, "natural_neighbor:max_edge=6", dir, 2);
		c->grid = &mirror;
		c->name = "mirrored and skewed";
		compare(c, "linear:max_edge=6", dir, 2);
		compare(c, "nearest", dir, 2);
	}
	c->grid = NULL;
	c->name = name;
}

/* A singular grid is refused before the run, naming it; nothing left behind. */
static void
singular(rt_case *c, const char *dir)
{
	tdc_grid_spec g = grid_at(500, 500, 100, 100, 2, 1, 4, 2);
	rt_state	s = {0};
	char		err[1024];
	size_t		valid;
	int			tiles,
				rc;

	c->grid = &g;
	grid_of(c, &s.g);
	tdc_interp_parse("linear", &s.spec, err, sizeof(err));
	CHECK(tiled_grid(c, &s, dir, 2, &valid, &tiles, &rc, err, sizeof(err)) == NULL && rc == TDC_EINVAL &&
		  strstr(err, "geotransform (scale 2 x 2, skew 1 x 4) is singular") != NULL,
		  "raster: a singular grid: %d %s", rc, err);
	CHECK(tiles_files_in(dir) == 0, "raster: singular: files left in %s", dir);
	c->grid = NULL;
}

void
test_raster_tiles(void)
{
	size_t		n = tdc_test_quick ? 60000 : 160000;
	uint64_t	seed = 39;
	const char *base = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	char		dir[4096];
	rt_case		c;
	static const char *const methods[] = {
		"linear", "linear:radius=0", "linear:radius=30:nodata=-9999", "linear:max_edge=6",
		"linear:max_edge=4:radius=12", "nearest", "nearest:radius1=3:radius2=3:nodata=-9999",
		"nearest:max_edge=6", "natural_neighbor", "natural_neighbor:radius=0",
		"natural_neighbor:max_edge=6:radius=30:nodata=-9999"
	};

	snprintf(dir, sizeof(dir), "%s/tdc_test_raster.XXXXXX", base);
	CHECK(mkdtemp(dir) != NULL, "raster: cannot make a directory in %s", base);

	/* uniform samples, a smooth surface, the extent beyond the box */
	memset(&c, 0, sizeof(c));
	c.workers = 0;				/* a tight limit may leave no room for a second worker */
	c.name = "uniform";
	c.n = n;
	c.xy = malloc(16 * n);
	c.z = malloc(8 * n);
	for (size_t i = 0; i < n; i++)
	{
		c.xy[2 * i] = 1000 * tiles_u01(&seed);
		c.xy[2 * i + 1] = 1000 * tiles_u01(&seed);
		c.z[i] = 50 * sin(c.xy[2 * i] / 90) * cos(c.xy[2 * i + 1] / 70) + tiles_u01(&seed);
	}
	c.extent[0] = -40.3;
	c.extent[1] = -35.1;
	c.extent[2] = 1044.7;
	c.extent[3] = 1031.9;
	c.cell = 2.5;
	c.limit_mb = 14;
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
	for (size_t m = 0; m < sizeof(methods) / sizeof(methods[0]); m++)
		compare(&c, methods[m], dir, 2);
	compare(&c, "linear", dir, 1);
	compare(&c, "nearest", dir, 1);
	compare(&c, "natural_neighbor", dir, 1);
	/* a window inside the samples' box: every row's hull crossings lie beside the grid */
	c.name = "window";
	c.extent[0] = 300.3;
	c.extent[2] = 700.9;
	compare(&c, "linear", dir, 2);
	compare(&c, "nearest", dir, 2);
	compare(&c, "nearest:max_edge=6", dir, 2);
	compare(&c, "natural_neighbor", dir, 2);
	c.name = "uniform";
	c.extent[0] = -40.3;
	c.extent[2] = 1044.7;
	refusals(&c, dir);
	singular(&c, dir);
	skewed(&c, dir, 0, 0, true);
	/* room for a second worker's scratch: two tiles at once (bounded_share.c) */
	c.limit_mb = tdc_test_quick ? 24 : 40;
	c.workers = 2;
	compare(&c, "linear", dir, 2);
	compare(&c, "nearest:max_edge=6", dir, 2);
	compare(&c, "natural_neighbor", dir, 2);
	c.limit_mb = 14;
	c.workers = 0;

	/* the projected offset */
	c.name = "projected offset";
	for (size_t i = 0; i < n; i++)
	{
		c.xy[2 * i] += 500000;
		c.xy[2 * i + 1] += 4000000;
	}
	c.extent[0] = 500000 - 7.25;
	c.extent[1] = 4000000 + 3.5;
	c.extent[2] = 501000 + 9;
	c.extent[3] = 4001000 - 2;
	c.cell = 1.75;
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
	compare(&c, "linear", dir, 2);
	compare(&c, "linear:max_edge=5:radius=20", dir, 2);
	compare(&c, "nearest", dir, 2);
	compare(&c, "natural_neighbor", dir, 2);
	skewed(&c, dir, 500000, 4000000, false);

	/* a diamond: the hull's sides are slanted, so the corners' pixels lie far outside it */
	c.name = "diamond";
	for (size_t i = 0; i < n; i++)
	{
		double		u = 1000 * tiles_u01(&seed),
					v = 1000 * tiles_u01(&seed);

		c.xy[2 * i] = 500000 + (u + v) / 2;
		c.xy[2 * i + 1] = 4000000 + (u - v) / 2;
		c.z[i] = 30 * sin(u / 60) + v / 50;
	}
	c.extent[0] = 500000 - 11;
	c.extent[1] = 4000000 - 512;
	c.extent[2] = 501000 + 13;
	c.extent[3] = 4000000 + 515;
	c.cell = 2.25;
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
	compare(&c, "linear", dir, 2);
	compare(&c, "linear:radius=40:max_edge=7", dir, 2);
	compare(&c, "nearest:max_edge=7", dir, 2);
	compare(&c, "natural_neighbor", dir, 2);
	compare(&c, "natural_neighbor:radius=40:max_edge=7", dir, 2);

	/* clusters in a sparse field */
	c.name = "clusters";
	for (size_t i = 0; i < n; i++)
	{
		double		cx = 100 + 200 * (double) (i % 5),
					cy = 150 + 170 * (double) (i % 7 % 5);

		if (i % 10 < 7)
		{
			c.xy[2 * i] = cx + 20 * (tiles_u01(&seed) - 0.5) * (tiles_u01(&seed) + 0.1);
			c.xy[2 * i + 1] = cy + 20 * (tiles_u01(&seed) - 0.5) * (tiles_u01(&seed) + 0.1);
		}
		else
		{
			c.xy[2 * i] = 1000 * tiles_u01(&seed);
			c.xy[2 * i + 1] = 1000 * tiles_u01(&seed);
		}
		c.z[i] = c.xy[2 * i] * 0.01 + c.xy[2 * i + 1] * 0.02 + tiles_u01(&seed);
	}
	c.extent[0] = 0;
	c.extent[1] = 0;
	c.extent[2] = 1000;
	c.extent[3] = 1000;
	c.cell = 1.5;
	c.limit_mb = 20;			/* reruns of tiles among the clusters need more than 14 */
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
	compare(&c, "linear", dir, 2);
	compare(&c, "linear:max_edge=8", dir, 2);
	compare(&c, "nearest", dir, 2);
	compare(&c, "natural_neighbor", dir, 2);
	compare(&c, "natural_neighbor:max_edge=8", dir, 2);

	/* the lattice on the pixels, with a lake */
	{
		size_t		side = tdc_test_quick ? 240 : 400,
					k = 0;

		c.name = "lattice on the pixels";
		for (size_t j = 0; j < side; j++)
			for (size_t i = 0; i < side; i++)
			{
				double		dx = (double) i - side / 2.0,
							dy = (double) j - side / 3.0;

				if (dx * dx + dy * dy < 30 * 30 && !(i == side / 2 && j == side / 3))
					continue;	/* the lake, with one sample in it */
				c.xy[2 * k] = (double) i;
				c.xy[2 * k + 1] = (double) j;
				c.z[k] = (double) ((i * 7 + j * 13) % 17) + 0.125 * (double) (i % 3);
				k++;
			}
		c.n = k;
		/* centres at 0, 0.5, 1, ...: on sites, on sides and diagonals, inside */
		c.extent[0] = -0.25 - 2;
		c.extent[1] = -0.25 - 2;
		c.extent[2] = (double) side - 1 + 0.25 + 2;
		c.extent[3] = (double) side - 1 + 0.25 + 2;
		c.cell = 0.5;
		c.limit_mb = 14;
		CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
		compare(&c, "linear", dir, 2);
		compare(&c, "linear:max_edge=1.5", dir, 2);
		compare(&c, "linear:max_edge=1.5:radius=0", dir, 2);
		compare(&c, "nearest", dir, 2);
		compare(&c, "nearest:max_edge=1.5", dir, 2);
		compare(&c, "natural_neighbor", dir, 2);
		compare(&c, "natural_neighbor:max_edge=1.5", dir, 2);
		compare(&c, "natural_neighbor:max_edge=1.5:radius=0", dir, 2);
		{
			/*
			 * Skewed grids whose centres fall on the lattice's sites,
			 * sides and diagonals: transposed (the rows run up the
			 * columns), and turned by 45 degrees.
			 */
			double		mid = (double) (side - 1) / 2 + 0.25;
			tdc_grid_spec tr = grid_at(mid, mid, 2 * side + 8, 2 * side + 8, 0, 0.5, 0.5, 0),
						dia = grid_at((double) (side / 2), (double) (side / 2), 2 * side + 16,
									  2 * side + 16, 0.5, 0.5, 0.5, -0.5);

			c.grid = &tr;
			c.name = "lattice, transposed";
			compare(&c, "linear:max_edge=1.5", dir, 2);
			compare(&c, "nearest:max_edge=1.5", dir, 2);
			c.grid = &dia;
			c.name = "lattice, turned 45 degrees";
			compare(&c, "linear:max_edge=1.5:radius=0", dir, 2);
			compare(&c, "nearest", dir, 2);
			compare(&c, "natural_neighbor:max_edge=1.5", dir, 2);
			c.grid = NULL;
		}
	}

	/* a collinear input: refused, with its reason */
	{
		rt_state	s = {0};
		char		err[1024];
		size_t		valid;
		int			tiles,
					rc;

		c.name = "collinear";
		c.n = 1000;
		for (size_t i = 0; i < c.n; i++)
		{
			c.xy[2 * i] = (double) i;
			c.xy[2 * i + 1] = 2 * (double) i;
			c.z[i] = 1;
		}
		c.extent[0] = 0;
		c.extent[1] = 0;
		c.extent[2] = 999;
		c.extent[3] = 1998;
		c.cell = 10;
		c.limit_mb = 64;
		CHECK(tiles_stage(dir, c.xy, c.z, c.n), "raster: cannot stage %s", c.name);
		grid_of(&c, &s.g);
		tdc_interp_parse("linear", &s.spec, err, sizeof(err));
		CHECK(tiled_grid(&c, &s, dir, 2, &valid, &tiles, &rc, err, sizeof(err)) == NULL &&
			  rc == TDC_EINVAL && strstr(err, "on one line") != NULL,
			  "raster: collinear: %d %s", rc, err);
		CHECK(tiles_files_in(dir) == 0, "raster: collinear: files left in %s", dir);
	}

	{
		char		p[4200];

		snprintf(p, sizeof(p), "%s/input.xy", dir);
		unlink(p);
		snprintf(p, sizeof(p), "%s/input.z", dir);
		unlink(p);
		rmdir(dir);
	}
	free(c.xy);
	free(c.z);
}
