/*
 * test_tin.c
 *		TIN analysis (tin*.c): interpolation (linear, nearest, natural
 *		neighbour), grids, draping and contour lines.
 *
 *	- the method parser: GDAL's syntax and defaults, and its errors;
 *	- planes reproduced to rounding by linear and natural neighbour, at
 *	  random points, at pixel centres and near huge offsets (a projected
 *	  CRS);
 *	- every method exact at every sample; duplicates keep the first height;
 *	- the same values, lines and draped vertices for 1, 2 and 3 threads;
 *	- cocircular lattices: natural neighbour values equal on a lattice and
 *	  its mirror image, whose triangulations split the squares the other way
 *	  (the linear values, which do depend on the split, differ there);
 *	- 0, 1, 2, 3 samples, collinear samples, outside the hull (radius);
 *	- natural neighbour against CGAL's natural_neighbor_coordinates_2 and
 *	  linear_interpolation with exact constructions (build/cgal_nn), within
 *	  1e-9 of the value range, at random points and pixel centres;
 *	- draping: a line crossing many triangles is split at exactly the edge
 *	  crossings (counted independently with exact predicates), in order,
 *	  and the height there equals both triangles' planes;
 *	- contours: per level the total length equals an independent
 *	  per-triangle computation; rings around a hill are closed and
 *	  counter-clockwise; levels through sample heights give each piece once
 *	  (a plane z = x on a lattice, levels at the lattice's columns: one
 *	  straight line per level); open lines end on the hull;
 *	- cancel of a long grid, and the memory limit;
 *	- breaklines: the option's parsing; a ridge whose Delaunay diagonal
 *	  crosses it, with exact values on and beside it with and without the
 *	  constraint (points, a grid, a drape); natural neighbour refused on a
 *	  constrained TIN; nearest sites on a constrained TIN (the k-d tree)
 *	  against brute force, inside and outside the hull, 1 and 3 threads.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"
#include "engine/predicates.h"
#include "tin_test.h"

/* ----------------------------------------------------------------
 *		helpers (those in tin_test.h are test_tin_maxedge.c's too)
 * ----------------------------------------------------------------
 */
bool
mk(tin_case *c, const double *xy, const double *z, size_t n, int threads)
{
	tdc_options o;
	char		err[256];

	tdc_options_init(&o);
	o.threads = threads;
	c->job = NULL;
	c->tin = NULL;
	if (tdc_triangulate(xy, n, &o, &c->job, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "triangulate: %s", err);
		return false;
	}
	if (tdc_tin_build(c->job, z, threads, 0, &c->tin, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "tin build: %s", err);
		return false;
	}
	return true;
}

void
rm(tin_case *c)
{
	tdc_tin_free(c->tin);
	tdc_job_free(c->job);
	c->tin = NULL;
	c->job = NULL;
}

tdc_interp_spec
spec_of(const char *text)
{
	tdc_interp_spec s;
	char		err[256];

	if (tdc_interp_parse(text, &s, err, sizeof(err)) != TDC_OK)
		CHECK(0, "parse %s: %s", text, err);
	return s;
}

int
run_wait(tdc_tin *tin, int rc, const char *what)
{
	if (rc != TDC_OK)
	{
		CHECK(0, "%s: start failed (%d)", what, rc);
		return rc;
	}
	rc = tdc_tin_wait(tin, -1);
	if (rc != TDC_OK)
		CHECK(0, "%s: %s", what, tdc_tin_error(tin));
	return rc;
}

static int
grid(tdc_tin *tin, const char *method, const tdc_grid_spec *g, double *v, uint8_t *ok)
{
	tdc_interp_spec s = spec_of(method);
	char		err[256];

	return run_wait(tin, tdc_tin_grid_start(tin, &s, g, v, ok, err, sizeof(err)), err);
}

static int
points(tdc_tin *tin, const char *method, const double *xy, size_t n, double *v, uint8_t *ok)
{
	tdc_interp_spec s = spec_of(method);
	char		err[256];

	return run_wait(tin, tdc_tin_points_start(tin, &s, xy, n, v, ok, err, sizeof(err)), err);
}

double
value(tdc_tin *tin, const char *method, double x, double y, int *valid)
{
	tdc_interp_spec s = spec_of(method);
	double		q[2] = {x, y},
				z;
	int			rc = tdc_tin_value(tin, &s, q, &z);

	if (valid)
		*valid = rc;
	return z;
}

/* n random points in [x0, x0 + w] x [y0, y0 + w] */
static double *
random_points(uint64_t *seed, size_t n, double x0, double y0, double w)
{
	double	   *xy = malloc(n * 2 * sizeof(double));

	for (size_t i = 0; i < n; i++)
	{
		xy[2 * i] = x0 + w * tdc_splitmix_unit(seed);
		xy[2 * i + 1] = y0 + w * tdc_splitmix_unit(seed);
	}
	return xy;
}

/* The site's height as the TIN defines it (its first input point). */
static double
site_z(const tdc_job *job, const double *z, uint32_t s)
{
	return z[tdc_site_input(job, s)];
}

/* ----------------------------------------------------------------
 *		the method parser
 * ----------------------------------------------------------------
 */
static void
test_parse(void)
{
	tdc_interp_spec s;
	char		err[256];

	CHECK(tdc_interp_parse("linear", &s, err, sizeof(err)) == TDC_OK &&
		  s.method == TDC_INTERP_LINEAR && s.radius == -1 && s.nodata == 0,
		  "linear's defaults (GDAL: radius -1, nodata 0)");
	CHECK(tdc_interp_parse("linear:radius=0:nodata=-9999", &s, err, sizeof(err)) == TDC_OK &&
		  s.radius == 0 && s.nodata == -9999, "linear:radius=0:nodata=-9999");
	CHECK(tdc_interp_parse("Natural_Neighbor:nodata=1.5", &s, err, sizeof(err)) == TDC_OK &&
		  s.method == TDC_INTERP_NATURAL && s.nodata == 1.5 && s.radius == -1,
		  "natural_neighbor (case-insensitive), nodata");
	CHECK(tdc_interp_parse("nearest", &s, err, sizeof(err)) == TDC_OK &&
		  s.method == TDC_INTERP_NEAREST && s.radius == -1,
		  "nearest: radius1 0 means the whole set");
	CHECK(tdc_interp_parse("nearest:radius1=5:radius2=5:angle=30", &s, err, sizeof(err)) == TDC_OK &&
		  s.radius == 5, "nearest with a circle");
	CHECK(tdc_interp_parse("nearest:radius1=5:radius2=6", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "circular"), "an ellipse is refused: %s", err);
	CHECK(tdc_interp_parse("invdist", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "unknown interpolation method"), "unknown method: %s", err);
	CHECK(tdc_interp_parse("linear:power=2", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "unknown option"), "unknown option: %s", err);
	CHECK(tdc_interp_parse("linear:radius=abc", &s, err, sizeof(err)) == TDC_EINVAL,
		  "a bad number: %s", err);
	CHECK(tdc_interp_parse("linear:radius", &s, err, sizeof(err)) == TDC_EINVAL,
		  "an option without value: %s", err);
	CHECK(tdc_interp_parse("linear:radius=nan", &s, err, sizeof(err)) == TDC_EINVAL,
		  "NaN radius: %s", err);
	CHECK(tdc_interp_parse("", &s, err, sizeof(err)) == TDC_EINVAL, "empty method");
	CHECK(tdc_interp_parse("nearest:radius=2", &s, err, sizeof(err)) == TDC_OK && s.radius == 2,
		  "nearest:radius= sets both radii");
}

/* ----------------------------------------------------------------
 *		planes, samples, threads
 * ----------------------------------------------------------------
 */
static void
check_plane(double x0, double y0, double w, size_t n, const char *name)
{
	uint64_t	seed = 42;
	double	   *xy = random_points(&seed, n, x0, y0, w),
			   *z = malloc(n * sizeof(double)),
				a = 0.25,
				b = -0.5,
				c0 = 3,
				scale,
				worst[3] = {0, 0, 0};
	const char *methods[3] = {"linear", "natural_neighbor", "linear"};
	tin_case	tc;
	size_t		inside = 0;

	/* the plane about the box's corner: its heights stay moderate */
	for (size_t i = 0; i < n; i++)
		z[i] = c0 + a * (xy[2 * i] - x0) + b * (xy[2 * i + 1] - y0);
	/* what rounding the coordinates and heights allows */
	scale = fabs(c0) + (fabs(a) + fabs(b)) * w + (fabs(a) * fabs(x0) + fabs(b) * fabs(y0)) ;
	if (!mk(&tc, xy, z, n, 2))
		goto out;
	for (int m = 0; m < 2; m++)
		for (int i = 0; i < 3000; i++)
		{
			double		qx = x0 + w * tdc_splitmix_unit(&seed),
						qy = y0 + w * tdc_splitmix_unit(&seed),
						q[2] = {qx, qy},
						want = c0 + a * (qx - x0) + b * (qy - y0),
						got;
			int			ok;

			if (!tdc_tin_inside(tc.tin, q))
				continue;
			inside += m == 0;
			got = value(tc.tin, methods[m], qx, qy, &ok);
			if (ok == 1 && fabs(got - want) > worst[m])
				worst[m] = fabs(got - want);
			CHECK(ok == 1, "%s: %s: no value inside the hull at (%.17g %.17g)", name, methods[m], qx, qy);
		}
	/* a grid's pixel centres, natural neighbour */
	{
		tdc_grid_spec g = {{x0, w / 50, 0, y0 + w, 0, -w / 50}, 50, 50};
		double		v[2500];
		uint8_t		ok[2500];

		if (grid(tc.tin, "natural_neighbor:radius=0", &g, v, ok) == TDC_OK)
			for (int r = 0; r < 50; r++)
				for (int cc = 0; cc < 50; cc++)
				{
					double		qx = x0 + (cc + 0.5) * w / 50,
								qy = y0 + w - (r + 0.5) * w / 50,
								want = c0 + a * (qx - x0) + b * (qy - y0);

					if (ok[r * 50 + cc] && fabs(v[r * 50 + cc] - want) > worst[2])
						worst[2] = fabs(v[r * 50 + cc] - want);
				}
	}
	printf("tin: plane %s: %zu points inside, largest error linear %.3g, natural %.3g, grid %.3g (scale %.3g)\n",
		   name, inside, worst[0], worst[1], worst[2], scale);
	CHECK(inside > 2000, "%s: most random points inside the hull (%zu)", name, inside);
	CHECK(worst[0] <= 1e-12 * scale, "%s: linear reproduces the plane: %.3g", name, worst[0]);
	CHECK(worst[1] <= 1e-12 * scale, "%s: natural neighbour reproduces the plane: %.3g", name, worst[1]);
	CHECK(worst[2] <= 1e-12 * scale, "%s: natural grid reproduces the plane: %.3g", name, worst[2]);
	rm(&tc);
out:
	free(xy);
	free(z);
}

static void
test_planes(void)
{
	check_plane(0, 0, 1000, 2000, "unit box");
	check_plane(500000, 5000000, 1000, 2000, "UTM offsets");
	check_plane(-3e7, 4e7, 2e5, 3000, "huge offsets");
	check_plane(0, 0, 1e-3, 500, "small box");
}

static void
test_exact_samples(void)
{
	uint64_t	seed = 7;
	size_t		n = 3000;
	double	   *xy = random_points(&seed, n + 100, 0, 0, 100),
			   *z = malloc((n + 100) * sizeof(double));
	const char *methods[3] = {"linear", "nearest", "natural_neighbor"};
	tin_case	tc;
	int			bad[3] = {0, 0, 0};

	for (size_t i = 0; i < n; i++)
		z[i] = sin(xy[2 * i] * 0.1) * 50 + xy[2 * i + 1] * xy[2 * i + 1] * 0.01;
	/* 100 duplicates of earlier points with other heights: the first one counts */
	for (size_t i = n; i < n + 100; i++)
	{
		size_t		j = (i - n) * 29;

		xy[2 * i] = xy[2 * j];
		xy[2 * i + 1] = xy[2 * j + 1];
		z[i] = -1e6;
	}
	if (!mk(&tc, xy, z, n + 100, 2))
		goto out;
	for (int m = 0; m < 3; m++)
		for (size_t i = 0; i < n + 100; i++)
		{
			int			ok;
			double		v = value(tc.tin, methods[m], xy[2 * i], xy[2 * i + 1], &ok);
			size_t		first = i < n ? i : (i - n) * 29;

			if (!(ok == 1 && v == z[first]))
				bad[m]++;
		}
	CHECK(bad[0] == 0, "linear is exact at every sample (%d not)", bad[0]);
	CHECK(bad[1] == 0, "nearest is exact at every sample (%d not)", bad[1]);
	CHECK(bad[2] == 0, "natural neighbour is exact at every sample (%d not)", bad[2]);
	/* the points op gives the same */
	{
		double	   *v = malloc((n + 100) * sizeof(double));
		uint8_t    *ok = malloc(n + 100);
		int			wrong = 0;

		if (points(tc.tin, "natural_neighbor", xy, n + 100, v, ok) == TDC_OK)
			for (size_t i = 0; i < n + 100; i++)
				wrong += !(ok[i] && v[i] == z[i < n ? i : (i - n) * 29]);
		CHECK(wrong == 0, "points: natural neighbour exact at the samples (%d not)", wrong);
		free(v);
		free(ok);
	}
	rm(&tc);
out:
	free(xy);
	free(z);
}

/* ----------------------------------------------------------------
 *		thread counts
 * ----------------------------------------------------------------
 */
typedef struct run_result
{
	double	   *grid[3];
	uint8_t    *ok[3];
	double	   *pts;
	size_t		nlines,
				npoints;
	double	   *lines;			/* level, n, closed, then the points */
	size_t		nlines_doubles;
	tdc_drape_vertex *dv;
	size_t		ndv;
} run_result;

static void
collect(tdc_tin *tin, const double *qxy, size_t nq, const double *lxy, const size_t *lend,
		size_t nchain, run_result *r)
{
	const char *methods[3] = {"linear", "nearest", "natural_neighbor"};
	tdc_grid_spec g = {{-5, 1.1, 0, 1005, 0, -1.1}, 920, 920};
	char		err[256];
	size_t		np,
				k = 0;

	for (int m = 0; m < 3; m++)
	{
		r->grid[m] = malloc(g.width * g.height * sizeof(double));
		r->ok[m] = malloc(g.width * g.height);
		grid(tin, methods[m], &g, r->grid[m], r->ok[m]);
	}
	r->pts = malloc(nq * sizeof(double));
	points(tin, "natural_neighbor", qxy, nq, r->pts, NULL);
	if (run_wait(tin, tdc_tin_contours_start(tin, 7.5, 1.25, err, sizeof(err)), err) == TDC_OK)
	{
		r->nlines = tdc_tin_contour_count(tin, &np);
		r->lines = malloc((3 * r->nlines + 2 * np + 1) * sizeof(double));
		for (size_t i = 0; i < r->nlines; i++)
		{
			double		lev;
			size_t		n;
			bool		closed;
			const double *p = tdc_tin_contour_line(tin, i, &lev, &n, &closed);

			r->lines[k++] = lev;
			r->lines[k++] = (double) n;
			r->lines[k++] = closed;
			memcpy(r->lines + k, p, n * 2 * sizeof(double));
			k += 2 * n;
		}
		r->nlines_doubles = k;
	}
	{
		tdc_interp_spec s = spec_of("linear");
		const tdc_drape_vertex *v;
		const size_t *off;

		if (run_wait(tin, tdc_tin_drape_start(tin, &s, lxy, lend, nchain, err, sizeof(err)), err) == TDC_OK)
		{
			r->ndv = tdc_tin_drape_result(tin, &v, &off);
			CHECK(nchain == 5 && off[0] == 0 && off[2] == off[3] && off[5] == r->ndv &&
				  off[1] > off[0] && off[3] < off[4] && off[4] < off[5] &&
				  v[off[4]].src == lend[3] && v[off[4]].t == 0 && v[off[3]].src == lend[2] && v[off[1]].src == lend[0],
				  "drape: each chain starts at its first vertex, an empty one where the next does");
			r->dv = malloc(r->ndv * sizeof(tdc_drape_vertex) + 1);
			memcpy(r->dv, v, r->ndv * sizeof(tdc_drape_vertex));
		}
	}
}

static void
free_result(run_result *r)
{
	for (int m = 0; m < 3; m++)
	{
		free(r->grid[m]);
		free(r->ok[m]);
	}
	free(r->pts);
	free(r->lines);
	free(r->dv);
}

static void
test_threads(void)
{
	uint64_t	seed = 99;
	size_t		n = tdc_test_quick ? 25000 : 60000,
				nq = 20000,
				nl = 400 + 10000;
	double	   *xy = random_points(&seed, n, 0, 0, 1000),
			   *z = malloc(n * sizeof(double)),
			   *qxy = random_points(&seed, nq, -10, -10, 1020),
			   *lxy = random_points(&seed, nl, 1, 1, 998);
	/* chain 2 empty; chain 4 a walk of 10000 short steps, over several tasks */
	size_t		lend[5] = {100, 200, 200, 400, 10400};

	for (size_t i = 401; i < nl; i++)
	{
		double		a = i * 0.37;

		lxy[2 * i] = fmin(999, fmax(1, lxy[2 * i - 2] + 3 * cos(a)));
		lxy[2 * i + 1] = fmin(999, fmax(1, lxy[2 * i - 1] + 3 * sin(a * 1.3)));
	}
	run_result	r[3];
	const char *what[3] = {"linear", "nearest", "natural_neighbor"};

	memset(r, 0, sizeof(r));
	for (size_t i = 0; i < n; i++)
		z[i] = 40 * sin(xy[2 * i] / 90) * cos(xy[2 * i + 1] / 70) + xy[2 * i] * 0.02;
	for (int t = 0; t < 3; t++)
	{
		tin_case	tc;

		if (!mk(&tc, xy, z, n, t + 1))
			break;
		collect(tc.tin, qxy, nq, lxy, lend, 5, &r[t]);
		rm(&tc);
	}
	for (int t = 1; t < 3; t++)
	{
		for (int m = 0; m < 3; m++)
			CHECK(r[t].grid[m] && r[0].grid[m] &&
				  memcmp(r[t].grid[m], r[0].grid[m], 920 * 920 * sizeof(double)) == 0 &&
				  memcmp(r[t].ok[m], r[0].ok[m], 920 * 920) == 0,
				  "%s grid: %d threads give 1 thread's values", what[m], t + 1);
		CHECK(memcmp(r[t].pts, r[0].pts, nq * sizeof(double)) == 0,
			  "points: %d threads give 1 thread's values", t + 1);
		CHECK(r[t].nlines == r[0].nlines && r[t].nlines_doubles == r[0].nlines_doubles &&
			  memcmp(r[t].lines, r[0].lines, r[0].nlines_doubles * sizeof(double)) == 0,
			  "contours: %d threads give 1 thread's %zu lines (%zu)", t + 1, r[0].nlines, r[t].nlines);
		CHECK(r[t].ndv == r[0].ndv && memcmp(r[t].dv, r[0].dv, r[0].ndv * sizeof(tdc_drape_vertex)) == 0,
			  "drape: %d threads give 1 thread's %zu vertices (%zu)", t + 1, r[0].ndv, r[t].ndv);
	}
	printf("tin: threads: %zu contour lines, %zu draped vertices from %zu, the same for 1, 2 and 3 threads\n",
		   r[0].nlines, r[0].ndv, nl);
	for (int t = 0; t < 3; t++)
		free_result(&r[t]);
	free(xy);
	free(z);
	free(qxy);
	free(lxy);
}

/* ----------------------------------------------------------------
 *		cocircular lattices
 * ----------------------------------------------------------------
 */
static double
lattice_z(double x, double y)
{
	return 10 * sin(x * 0.7) + y * y * 0.3 - x * y * 0.2;
}

static void
test_lattice(void)
{
	int			k = 16;
	size_t		n = (size_t) k * k;
	double	   *a = malloc(n * 2 * sizeof(double)),
			   *b = malloc(n * 2 * sizeof(double)),
			   *za = malloc(n * sizeof(double)),
			   *zb = malloc(n * sizeof(double)),
				worst_nn = 0,
				worst_lin = 0,
				zmin = INFINITY,
				zmax = -INFINITY;
	tin_case	ta,
				tb;
	uint64_t	seed = 5;
	int			differ = 0,
				queries = 0;

	/* a square lattice and its mirror image x -> -x, the same heights */
	for (int i = 0; i < k; i++)
		for (int j = 0; j < k; j++)
		{
			size_t		p = (size_t) i * k + j;

			a[2 * p] = i;
			a[2 * p + 1] = j;
			b[2 * p] = -i;
			b[2 * p + 1] = j;
			za[p] = zb[p] = lattice_z(i, j);
			zmin = fmin(zmin, za[p]);
			zmax = fmax(zmax, za[p]);
		}
	if (!mk(&ta, a, za, n, 1) || !mk(&tb, b, zb, n, 1))
		return;
	for (int i = 0; i < 4000; i++)
	{
		double		qx = (k - 1) * tdc_splitmix_unit(&seed),
					qy = (k - 1) * tdc_splitmix_unit(&seed);
		int			o1,
					o2;
		double		v1 = value(ta.tin, "natural_neighbor", qx, qy, &o1),
					v2 = value(tb.tin, "natural_neighbor", -qx, qy, &o2),
					l1 = value(ta.tin, "linear", qx, qy, NULL),
					l2 = value(tb.tin, "linear", -qx, qy, NULL);

		queries++;
		CHECK(o1 == 1 && o2 == 1, "lattice: values inside");
		worst_nn = fmax(worst_nn, fabs(v1 - v2));
		worst_lin = fmax(worst_lin, fabs(l1 - l2));
		differ += fabs(l1 - l2) > 1e-6 * (zmax - zmin);
	}
	printf("tin: lattice %dx%d and its mirror image: natural neighbour differs by at most %.3g, "
		   "linear by up to %.3g (%d of %d points differ: the squares are split the other way)\n",
		   k, k, worst_nn, worst_lin, differ, queries);
	CHECK(differ > queries / 10, "the mirror image's triangulation splits the squares the other way");
	CHECK(worst_nn <= 1e-12 * (zmax - zmin), "natural neighbour does not depend on the split: %.3g",
		  worst_nn);
	rm(&ta);
	rm(&tb);
	free(a);
	free(b);
	free(za);
	free(zb);
}

/* ----------------------------------------------------------------
 *		few samples, collinear samples, outside the hull
 * ----------------------------------------------------------------
 */
static void
test_degenerate(void)
{
	tin_case	tc;
	int			ok;
	double		v;

	/* one sample */
	{
		double		xy[2] = {3, 4},
					z[1] = {7};

		if (mk(&tc, xy, z, 1, 1))
		{
			v = value(tc.tin, "linear", 3, 4, &ok);
			CHECK(ok == 1 && v == 7, "one sample: its height at it");
			v = value(tc.tin, "linear", 30, 40, &ok);
			CHECK(ok == 1 && v == 7, "one sample: linear takes the nearest (radius -1) away from it");
			v = value(tc.tin, "linear:radius=0:nodata=-9", 30, 40, &ok);
			CHECK(ok == 0 && v == -9, "one sample: radius 0 gives nodata away from it");
			v = value(tc.tin, "natural_neighbor:radius=50", 30, 40, &ok);
			CHECK(ok == 1 && v == 7, "one sample: within radius 50 (distance 45)");
			v = value(tc.tin, "natural_neighbor:radius=44", 30, 40, &ok);
			CHECK(ok == 0, "one sample: not within radius 44");
			v = value(tc.tin, "nearest:radius1=45:radius2=45", 30, 40, &ok);
			CHECK(ok == 1 && v == 7, "nearest: a site exactly at the radius counts (<=)");
			rm(&tc);
		}
	}
	/* two samples and three collinear */
	{
		double		xy[6] = {0, 0, 10, 10, 4, 4},
					z[3] = {0, 10, 100};

		if (mk(&tc, xy, z, 2, 1))
		{
			v = value(tc.tin, "linear", 2.5, 2.5, &ok);
			CHECK(ok == 1 && v == 2.5, "two samples: linear along their segment (%g)", v);
			v = value(tc.tin, "natural_neighbor", 2.5, 2.5, &ok);
			CHECK(ok == 1 && v == 2.5, "two samples: natural neighbour along their segment");
			v = value(tc.tin, "linear", 1, 0, &ok);
			CHECK(ok == 1 && v == 0, "two samples: off the segment, the nearest");
			v = value(tc.tin, "linear:radius=0", 1, 0, &ok);
			CHECK(ok == 0, "two samples: off the segment with radius 0: nodata");
			v = value(tc.tin, "nearest", 6, 6, &ok);
			CHECK(ok == 1 && v == 10, "two samples: nearest");
			v = value(tc.tin, "nearest", 5, 5, &ok);
			CHECK(ok == 1 && v == 0, "two samples: a tie goes to the first in (x, y) order");
			rm(&tc);
		}
		if (mk(&tc, xy, z, 3, 1))
		{
			v = value(tc.tin, "linear", 7, 7, &ok);
			CHECK(ok == 1 && fabs(v - 55) < 1e-12, "three collinear: along the line (%g)", v);
			v = value(tc.tin, "linear", 4, 4, &ok);
			CHECK(ok == 1 && v == 100, "three collinear: at the middle sample");
			v = value(tc.tin, "linear:radius=0", 11, 11, &ok);
			CHECK(ok == 0, "three collinear: beyond the end");
			rm(&tc);
		}
	}
	/* three samples: one triangle; outside it; on its edges */
	{
		double		xy[6] = {0, 0, 10, 0, 0, 10},
					z[3] = {1, 2, 3};

		if (mk(&tc, xy, z, 3, 1))
		{
			v = value(tc.tin, "natural_neighbor", 2, 3, &ok);
			CHECK(ok == 1 && fabs(v - (1 + 0.2 + 0.6)) < 1e-14, "one triangle: natural is linear (%g)", v);
			v = value(tc.tin, "natural_neighbor", 5, 0, &ok);
			CHECK(ok == 1 && v == 1.5, "one triangle: on a hull edge, linear along it (%.17g)", v);
			v = value(tc.tin, "natural_neighbor:radius=0", 5, -1e-50, &ok);
			CHECK(ok == 0, "just outside the hull edge: nodata with radius 0");
			v = value(tc.tin, "linear", 6, 6, &ok);
			CHECK(ok == 1 && v == 3, "outside: the nearest, of (10 0) and (0 10) equally near the first in (x, y) order (%g)", v);
			v = value(tc.tin, "nearest", 6, 5, &ok);
			CHECK(ok == 1 && v == 2, "nearest: (10 0) is nearer to (6 5) (%g)", v);
			rm(&tc);
		}
	}
	/* no sample at all */
	{
		double		xy[2] = {0, 0},
					z[1] = {0};

		if (mk(&tc, xy, z, 0, 1))
		{
			v = value(tc.tin, "linear:nodata=5", 1, 1, &ok);
			CHECK(ok == 0 && v == 5, "no sample: nodata");
			v = value(tc.tin, "nearest", 1, 1, &ok);
			CHECK(ok == 0, "no sample: nearest has none");
			rm(&tc);
		}
	}
	/* a query coordinate out of range is an error */
	{
		double		xy[6] = {0, 0, 10, 0, 0, 10},
					z[3] = {1, 2, 3};

		if (mk(&tc, xy, z, 3, 1))
		{
			value(tc.tin, "linear", 1e-70, 1, &ok);
			CHECK(ok == TDC_EINVAL, "a query at 1e-70 is out of the exact range");
			rm(&tc);
		}
	}
	/* non-finite heights */
	{
		double		xy[6] = {0, 0, 10, 0, 0, 10},
					z[3] = {1, NAN, 3};
		tdc_job    *job;
		tdc_tin    *tin;
		char		err[256];

		if (tdc_triangulate(xy, 3, NULL, &job, err, sizeof(err)) == TDC_OK)
		{
			CHECK(tdc_tin_build(job, z, 1, 0, &tin, err, sizeof(err)) == TDC_EINVAL &&
				  strstr(err, "not finite"), "a NaN height is an error: %s", err);
			tdc_tin_free(tin);
			tdc_job_free(job);
		}
	}
}

/* ----------------------------------------------------------------
 *		natural neighbour against CGAL
 * ----------------------------------------------------------------
 */
static const char *
cgal_nn_path(void)
{
	static char path[4096];

	snprintf(path, sizeof(path), "%s/build/cgal_nn", TDC_SOURCE_DIR);
	return access(path, X_OK) == 0 ? path : NULL;
}

/* CGAL's values at the queries (NaN outside); NULL if it failed. */
static double *
cgal_nn(const double *xy, const double *z, size_t n, const double *q, size_t m)
{
	char		inpath[] = "/tmp/tdc_nn_inXXXXXX",
				cmd[8192];
	int			fd = mkstemp(inpath);
	FILE	   *f,
			   *p;
	double	   *out = malloc((m + 1) * sizeof(double));
	size_t		i = 0;

	if (fd < 0)
		return NULL;
	f = fdopen(fd, "w");
	fprintf(f, "%zu %zu\n", n, m);
	for (size_t j = 0; j < n; j++)
		fprintf(f, "%.17g %.17g %.17g\n", xy[2 * j], xy[2 * j + 1], z[j]);
	for (size_t j = 0; j < m; j++)
		fprintf(f, "%.17g %.17g\n", q[2 * j], q[2 * j + 1]);
	fclose(f);
	snprintf(cmd, sizeof(cmd), "%s < %s", cgal_nn_path(), inpath);
	p = popen(cmd, "r");
	while (p && i < m)
	{
		char		buf[64];

		if (fscanf(p, "%63s", buf) != 1)
			break;
		out[i++] = strcmp(buf, "nan") == 0 ? NAN : strtod(buf, NULL);
	}
	if (!p || pclose(p) != 0 || i != m)
	{
		free(out);
		out = NULL;
	}
	unlink(inpath);
	return out;
}

static void
compare_cgal(const char *name, const double *xy, const double *z, size_t n,
			 const double *q, size_t m)
{
	tin_case	tc;
	double	   *ref,
			   *ours = malloc(m * sizeof(double)),
				zmin = INFINITY,
				zmax = -INFINITY,
				worst = 0;
	uint8_t    *ok = malloc(m);
	size_t		inside = 0,
				agree_nodata = 0;

	for (size_t i = 0; i < n; i++)
	{
		zmin = fmin(zmin, z[i]);
		zmax = fmax(zmax, z[i]);
	}
	ref = cgal_nn(xy, z, n, q, m);
	CHECK(ref != NULL, "%s: cgal_nn ran", name);
	if (ref && mk(&tc, xy, z, n, 2))
	{
		if (points(tc.tin, "natural_neighbor:radius=0", q, m, ours, ok) == TDC_OK)
			for (size_t i = 0; i < m; i++)
			{
				if (isnan(ref[i]))
				{
					agree_nodata += !ok[i];
					continue;
				}
				inside++;
				CHECK(ok[i], "%s: CGAL has a value at (%.17g %.17g), we have none", name,
					  q[2 * i], q[2 * i + 1]);
				if (ok[i])
					worst = fmax(worst, fabs(ours[i] - ref[i]));
			}
		rm(&tc);
		CHECK(agree_nodata == m - inside, "%s: nodata where CGAL has none (%zu of %zu)", name,
			  agree_nodata, m - inside);
		CHECK(worst <= 1e-9 * (zmax - zmin), "%s: within 1e-9 of the value range of CGAL: %.3g",
			  name, worst / (zmax - zmin));
		printf("tin: natural neighbour against CGAL, %s: %zu samples, %zu values, %zu outside, "
			   "largest difference %.3g of the value range\n", name, n, inside, m - inside,
			   worst / (zmax - zmin));
	}
	free(ref);
	free(ours);
	free(ok);
}

static void
test_cgal(void)
{
	uint64_t	seed = 1234;
	size_t		n = 400,
				m = 3000;
	double	   *xy = random_points(&seed, n, 0, 0, 100),
			   *z = malloc(n * sizeof(double)),
			   *q = random_points(&seed, m + 2500, -5, -5, 110);

	if (!cgal_nn_path())
	{
		printf("tin: build/cgal_nn not built (no CGAL headers): the CGAL comparison is skipped\n");
		free(xy);
		free(z);
		free(q);
		return;
	}
	for (size_t i = 0; i < n; i++)
		z[i] = 30 * sin(xy[2 * i] / 13) + xy[2 * i + 1] * 0.5 + cos(xy[2 * i + 1] / 7) * 10;
	/* and the pixel centres of a 50 x 50 grid over the box */
	for (int r = 0; r < 50; r++)
		for (int c = 0; c < 50; c++)
		{
			q[2 * (m + r * 50 + c)] = (c + 0.5) * 2;
			q[2 * (m + r * 50 + c) + 1] = 100 - (r + 0.5) * 2;
		}
	compare_cgal("random samples", xy, z, n, q, m + 2500);

	/* a cocircular lattice, and points on its edges and at its sites */
	{
		int			k = 12;
		size_t		nl = (size_t) k * k,
					ml = 2000;
		double	   *lxy = malloc(nl * 2 * sizeof(double)),
				   *lz = malloc(nl * sizeof(double)),
				   *lq = malloc(ml * 2 * sizeof(double));

		for (int i = 0; i < k; i++)
			for (int j = 0; j < k; j++)
			{
				lxy[2 * (i * k + j)] = i * 2.5;
				lxy[2 * (i * k + j) + 1] = j * 2.5;
				lz[i * k + j] = lattice_z(i, j);
			}
		for (size_t i = 0; i < ml; i++)
		{
			double		u = tdc_splitmix_unit(&seed) * (k - 1) * 2.5,
						w = tdc_splitmix_unit(&seed) * (k - 1) * 2.5;

			/* a third on grid lines, a third at cell centres */
			if (i % 3 == 1)
				w = floor(w / 2.5) * 2.5;
			else if (i % 3 == 2)
			{
				u = (floor(u / 2.5) + 0.5) * 2.5;
				w = (floor(w / 2.5) + 0.5) * 2.5;
			}
			lq[2 * i] = u;
			lq[2 * i + 1] = w;
		}
		compare_cgal("cocircular lattice", lxy, lz, nl, lq, ml);
		free(lxy);
		free(lz);
		free(lq);
	}
	/* near the hull: points within 1e-9 of its edges */
	{
		double		sq[8] = {0, 0, 100, 0, 100, 100, 0, 100},
					sz[4] = {0, 10, 30, 5},
					nq[2 * 400];

		for (int i = 0; i < 400; i++)
		{
			double		u = tdc_splitmix_unit(&seed) * 100,
						d = pow(10, -1 - 8 * tdc_splitmix_unit(&seed));

			switch (i % 4)
			{
				case 0:
					nq[2 * i] = u, nq[2 * i + 1] = d;
					break;
				case 1:
					nq[2 * i] = 100 - d, nq[2 * i + 1] = u;
					break;
				case 2:
					nq[2 * i] = u, nq[2 * i + 1] = 100 - d;
					break;
				default:
					nq[2 * i] = d, nq[2 * i + 1] = u;
			}
		}
		compare_cgal("near the hull of a square", sq, sz, 4, nq, 400);
	}
	free(xy);
	free(z);
	free(q);
}

/* ----------------------------------------------------------------
 *		draping
 * ----------------------------------------------------------------
 */

/* Linear height of triangle (a, b, c) at p, in long double. */
static long double
plane_at(const double *a, const double *b, const double *c, double za, double zb, double zc,
		 const double *p)
{
	long double ux = (long double) b[0] - a[0],
				uy = (long double) b[1] - a[1],
				vx = (long double) c[0] - a[0],
				vy = (long double) c[1] - a[1],
				wx = (long double) p[0] - a[0],
				wy = (long double) p[1] - a[1],
				d = ux * vy - uy * vx,
				s = (wx * vy - wy * vx) / d,
				t = (ux * wy - uy * wx) / d;

	return za + s * (zb - (long double) za) + t * (zc - (long double) za);
}

static void
test_drape(void)
{
	uint64_t	seed = 77;
	size_t		n = 1500;
	double	   *xy = random_points(&seed, n, 0, 0, 100),
			   *z = malloc(n * sizeof(double)),
				zmin = INFINITY,
				zmax = -INFINITY,
				line[2 * 8];
	size_t		lend[4];
	tin_case	tc;
	size_t		ntri,
				nseg = 0,
				count_bad = 0,
				plane_bad = 0,
				order_bad = 0,
				crossings = 0;
	uint32_t   *tri;
	tdc_iter	it = {0};
	char		err[256];

	for (size_t i = 0; i < n; i++)
	{
		z[i] = 20 * sin(xy[2 * i] / 9) + xy[2 * i + 1] * 0.3;
		zmin = fmin(zmin, z[i]);
		zmax = fmax(zmax, z[i]);
	}
	if (!mk(&tc, xy, z, n, 2))
		return;
	/* the hull's corners, roughly: keep the lines well inside it */
	line[0] = 5, line[1] = 7;		/* chain 0: a long diagonal polyline */
	line[2] = 95, line[3] = 93;
	line[4] = 10, line[5] = 60;
	lend[0] = 3;
	/* chain 1: from a site to a site (through whatever sites are on it) */
	line[6] = xy[0], line[7] = xy[1];
	line[8] = xy[2], line[9] = xy[3];
	lend[1] = 5;
	/* chain 2: a single point */
	line[10] = 50, line[11] = 50;
	lend[2] = 6;
	/* chain 3: along a line through a site, horizontally */
	line[12] = 8, line[13] = xy[5];
	line[14] = 92, line[15] = xy[5];
	lend[3] = 8;

	/* the triangles, for the independent checks */
	ntri = tdc_num_triangles(tc.job);
	tri = malloc(ntri * 3 * sizeof(uint32_t));
	for (size_t t = 0; tdc_next_triangle(tc.job, &it, tri + 3 * t); t++)
		;

	{
		tdc_interp_spec s = spec_of("linear:radius=0");
		const tdc_drape_vertex *v;
		const size_t *off;
		size_t		nv;

		if (run_wait(tc.tin, tdc_tin_drape_start(tc.tin, &s, line, lend, 4, err, sizeof(err)), err) != TDC_OK)
			goto out;
		nv = tdc_tin_drape_result(tc.tin, &v, &off);
		CHECK(off[0] == 0 && off[4] == nv, "drape: chain offsets cover the output");
		for (int c = 0; c < 4; c++)
		{
			size_t		lo = c == 0 ? 0 : lend[c - 1];

			for (size_t i = lo; i + 1 < lend[c]; i++)
			{
				const double *p = line + 2 * i,
						   *q = p + 2;
				size_t		want = 0,
							got = 0;
				double		last_t = 0;

				nseg++;
				/* independent: edges properly crossed, sites strictly inside p-q */
				{
					tdc_iter	ei = {0};
					uint32_t	e[2];

					while (tdc_next_edge(tc.job, &ei, e))
					{
						const double *a = tdc_site_xy(tc.job, e[0]),
								   *b = tdc_site_xy(tc.job, e[1]);
						double		sa = tdc_orient2d(p, q, a),
									sb = tdc_orient2d(p, q, b),
									sp = tdc_orient2d(a, b, p),
									sq = tdc_orient2d(a, b, q);

						if (sa * sb < 0 && sp * sq < 0)
							want++;
					}
					for (uint32_t s2 = 0; s2 < tdc_site_id_limit(tc.job); s2++)
					{
						const double *a;

						if (tdc_input_site(tc.job, tdc_site_input(tc.job, s2)) != s2)
							continue;
						a = tdc_site_xy(tc.job, s2);
						if (tdc_orient2d(p, q, a) == 0 &&
							((tdc_lex_less(p, a) && tdc_lex_less(a, q)) ||
							 (tdc_lex_less(q, a) && tdc_lex_less(a, p))))
							want++;
					}
				}
				/* ours: the vertices after input vertex i up to the next input vertex */
				for (size_t k = off[c]; k < off[c + 1]; k++)
				{
					if (v[k].src != i || v[k].t == 0)
						continue;
					got++;
					crossings++;
					if (!(v[k].t >= last_t && v[k].t <= 1))
						order_bad++;
					last_t = v[k].t;
					/* the point lies on an edge of two triangles, and z is both planes' */
					{
						int			found = 0;
						double		pt[2] = {v[k].x, v[k].y};

						for (size_t t = 0; t < ntri; t++)
						{
							const double *A = tdc_site_xy(tc.job, tri[3 * t]),
									   *B = tdc_site_xy(tc.job, tri[3 * t + 1]),
									   *C = tdc_site_xy(tc.job, tri[3 * t + 2]);
							double		ext = fmax(fabs(A[0]) + fabs(B[0]) + fabs(C[0]),
												   fabs(A[1]) + fabs(B[1]) + fabs(C[1]));
							long double pz;

							/* the point within rounding of the closed triangle (long double areas) */
							{
								long double o1 = ((long double) B[0] - A[0]) * ((long double) pt[1] - A[1]) -
									((long double) B[1] - A[1]) * ((long double) pt[0] - A[0]),
											o2 = ((long double) C[0] - B[0]) * ((long double) pt[1] - B[1]) -
									((long double) C[1] - B[1]) * ((long double) pt[0] - B[0]),
											o3 = ((long double) A[0] - C[0]) * ((long double) pt[1] - C[1]) -
									((long double) A[1] - C[1]) * ((long double) pt[0] - C[0]),
											tol = -1e-12L * ext * ext;

								if (o1 < tol || o2 < tol || o3 < tol)
									continue;
							}
							found++;
							pz = plane_at(A, B, C, site_z(tc.job, z, tri[3 * t]),
										  site_z(tc.job, z, tri[3 * t + 1]),
										  site_z(tc.job, z, tri[3 * t + 2]), pt);
							if (fabsl(pz - v[k].z) > 1e-12L * (zmax - zmin))
							{
								plane_bad++;
								printf("tin: drape crossing (%.17g %.17g) z %.17g, plane %.17Lg\n",
									   pt[0], pt[1], v[k].z, pz);
							}
						}
						/* on an edge: two triangles (or more at a site) */
						if (found < 2)
						{
							plane_bad++;
							printf("tin: drape crossing (%.17g %.17g) in %d triangles\n", pt[0], pt[1], found);
						}
					}
				}
				if (got != want)
				{
					count_bad++;
					printf("tin: drape segment %zu: %zu crossings, %zu expected\n", i, got, want);
				}
			}
		}
		printf("tin: drape: %zu segments, %zu crossings, output %zu vertices\n", nseg, crossings, nv);
		CHECK(count_bad == 0, "drape: every segment split at exactly its edge crossings and sites (%zu wrong)",
			  count_bad);
		CHECK(plane_bad == 0, "drape: every crossing's z equals both triangles' planes (%zu not)", plane_bad);
		CHECK(order_bad == 0, "drape: crossings in order along the segment (%zu not)", order_bad);
		CHECK(crossings > 100, "drape: the lines cross many triangles (%zu)", crossings);
		CHECK(off[3] - off[2] == 1 && v[off[2]].valid, "drape: a point is one vertex, with its value");
		/* the input vertices keep their linear values, and all are inside */
		for (int c = 0; c < 4; c++)
			for (size_t k = off[c]; k < off[c + 1]; k++)
				if (v[k].t == 0)
				{
					int			ok;
					double		want = value(tc.tin, "linear", v[k].x, v[k].y, &ok);

					CHECK(ok == 1 && v[k].z == want && v[k].valid && v[k].inside,
						  "drape: input vertex %u's value", v[k].src);
				}
	}
	/* outside the hull: the vertex has no value (radius 0), and no crossing */
	{
		double		lx[4] = {50, 50, 500, 500};
		size_t		le[1] = {2};
		tdc_interp_spec s = spec_of("linear:radius=0");
		const tdc_drape_vertex *v;
		const size_t *off;

		if (run_wait(tc.tin, tdc_tin_drape_start(tc.tin, &s, lx, le, 1, err, sizeof(err)), err) == TDC_OK)
		{
			size_t		nv = tdc_tin_drape_result(tc.tin, &v, &off);

			CHECK(nv == 2 && v[0].valid == 1 && v[1].valid == 0 && v[0].inside && !v[1].inside,
				  "drape: a vertex outside the hull has no value, its segment no crossing");
		}
	}
out:
	free(tri);
	rm(&tc);
	free(xy);
	free(z);
}

/* ----------------------------------------------------------------
 *		contours
 * ----------------------------------------------------------------
 */

/* The length of level L in each triangle, summed: the independent count. */
double
level_length(const tdc_job *job, const double *z, double L, double max_edge)
{
	tdc_iter	it = {0};
	uint32_t	v[3];
	long double len = 0;

	while (tdc_next_triangle(job, &it, v))
	{
		long double px[2],
					py[2];
		int			np = 0;
		bool		drop = false;

		for (int k = 0; k < 3 && max_edge > 0; k++)
		{
			const double *a = tdc_site_xy(job, v[k]),
					   *b = tdc_site_xy(job, v[(k + 1) % 3]);

			drop |= (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) > max_edge * max_edge;
		}
		if (drop)
			continue;
		for (int k = 0; k < 3; k++)
		{
			uint32_t	a = v[k],
						b = v[(k + 1) % 3];
			double		za = site_z(job, z, a),
						zb = site_z(job, z, b);
			bool		aa = za >= L,
						ab = zb >= L;

			if (aa == ab || np == 2)
				continue;
			{
				/* from the end below */
				const double *lo = aa ? tdc_site_xy(job, b) : tdc_site_xy(job, a),
						   *hi = aa ? tdc_site_xy(job, a) : tdc_site_xy(job, b);
				double		zl = aa ? zb : za,
							zh = aa ? za : zb;
				long double t = ((long double) L - zl) / ((long double) zh - zl);

				px[np] = lo[0] + t * ((long double) hi[0] - lo[0]);
				py[np] = lo[1] + t * ((long double) hi[1] - lo[1]);
				np++;
			}
		}
		if (np == 2)
			len += sqrtl((px[1] - px[0]) * (px[1] - px[0]) + (py[1] - py[0]) * (py[1] - py[0]));
	}
	return (double) len;
}

typedef struct contour_stats
{
	size_t		lines,
				closed,
				ccw;
	double		len_worst;		/* relative */
	size_t		levels;
} contour_stats;

static double
ring_area(const double *p, size_t n)
{
	double		a = 0;

	for (size_t i = 0; i + 1 < n; i++)
		a += p[2 * i] * p[2 * i + 3] - p[2 * i + 2] * p[2 * i + 1];
	return a / 2;
}

static void
check_contours(tin_case *tc, const double *z, double interval, double base, const char *name,
			   contour_stats *st)
{
	char		err[256];
	size_t		nl,
				np,
				i = 0;
	double		hull_tol;

	memset(st, 0, sizeof(*st));
	if (run_wait(tc->tin, tdc_tin_contours_start(tc->tin, interval, base, err, sizeof(err)), err) != TDC_OK)
		return;
	nl = tdc_tin_contour_count(tc->tin, &np);
	st->lines = nl;
	{
		double		lo[2],
					hi[2];

		tdc_site_extent(tc->job, lo, hi);
		hull_tol = 1e-9 * fmax(hi[0] - lo[0], hi[1] - lo[1]);
	}
	while (i < nl)
	{
		double		lev = 0,
					len = 0,
					want;
		size_t		j = i;

		/* all lines of this level */
		while (j < nl)
		{
			double		l2;
			size_t		n;
			bool		closed;
			const double *p = tdc_tin_contour_line(tc->tin, j, &l2, &n, &closed);

			if (j == i)
				lev = l2;
			if (l2 != lev)
				break;
			for (size_t k = 0; k + 1 < n; k++)
			{
				double		dx = p[2 * k + 2] - p[2 * k],
							dy = p[2 * k + 3] - p[2 * k + 1];

				CHECK(dx != 0 || dy != 0, "%s: a zero-length piece at level %g", name, lev);
				len += sqrt(dx * dx + dy * dy);
			}
			if (closed)
			{
				st->closed++;
				CHECK(p[0] == p[2 * n - 2] && p[1] == p[2 * n - 1], "%s: a closed ring ends where it starts",
					  name);
				st->ccw += ring_area(p, n) > 0;
			}
			else
			{
				/* an open line ends on the hull: outside just beyond its ends */
				for (int e = 0; e < 2; e++)
				{
					const double *q = e == 0 ? p : p + 2 * (n - 1);
					int			on = 0;
					double		probe[8][2] = {{q[0] + hull_tol, q[1]}, {q[0] - hull_tol, q[1]},
						{q[0], q[1] + hull_tol}, {q[0], q[1] - hull_tol},
						{q[0] + hull_tol, q[1] + hull_tol}, {q[0] - hull_tol, q[1] - hull_tol},
						{q[0] - hull_tol, q[1] + hull_tol}, {q[0] + hull_tol, q[1] - hull_tol}};

					for (int k = 0; k < 8; k++)
						on += !tdc_tin_inside(tc->tin, probe[k]);
					CHECK(on > 0, "%s: an open line at level %g ends inside the hull at (%.17g %.17g)",
						  name, lev, q[0], q[1]);
				}
			}
			j++;
		}
		want = level_length(tc->job, z, lev, 0);
		st->len_worst = fmax(st->len_worst, fabs(len - want) / fmax(want, 1e-300));
		st->levels++;
		i = j;
	}
}

static void
test_contours(void)
{
	uint64_t	seed = 2024;
	contour_stats st;
	tin_case	tc;

	/* a hill in the middle of a square: closed, counter-clockwise rings */
	{
		size_t		n = 4000;
		double	   *xy = random_points(&seed, n, -100, -100, 200),
				   *z = malloc(n * sizeof(double));

		for (size_t i = 0; i < n; i++)
			z[i] = 100 * exp(-(xy[2 * i] * xy[2 * i] + xy[2 * i + 1] * xy[2 * i + 1]) / 2000);
		if (mk(&tc, xy, z, n, 2))
		{
			check_contours(&tc, z, 10, 0, "hill", &st);
			printf("tin: contours of a hill: %zu levels, %zu lines, %zu closed, %zu counter-clockwise, "
				   "length off by %.3g\n", st.levels, st.lines, st.closed, st.ccw, st.len_worst);
			CHECK(st.levels >= 9 && st.lines == st.levels && st.closed == st.lines && st.ccw == st.lines,
				  "hill: one closed counter-clockwise ring per level (%zu levels, %zu lines, %zu closed, %zu ccw)",
				  st.levels, st.lines, st.closed, st.ccw);
			CHECK(st.len_worst < 1e-9, "hill: each level's length equals the per-triangle sum (%.3g)",
				  st.len_worst);
			/* a pit: the same heights negated, clockwise rings */
			rm(&tc);
			for (size_t i = 0; i < n; i++)
				z[i] = -z[i];
			if (mk(&tc, xy, z, n, 2))
			{
				check_contours(&tc, z, 10, 0, "pit", &st);
				CHECK(st.closed == st.lines && st.ccw == 0 && st.lines >= 9,
					  "pit: clockwise rings (%zu lines, %zu counter-clockwise)", st.lines, st.ccw);
				rm(&tc);
			}
		}
		free(xy);
		free(z);
	}
	/* random terrain, levels at arbitrary heights: lengths per level */
	{
		size_t		n = 20000;
		double	   *xy = random_points(&seed, n, 0, 0, 1000),
				   *z = malloc(n * sizeof(double));

		for (size_t i = 0; i < n; i++)
			z[i] = 50 * sin(xy[2 * i] / 80) * cos(xy[2 * i + 1] / 120) + 30 * sin(xy[2 * i + 1] / 33);
		if (mk(&tc, xy, z, n, 2))
		{
			check_contours(&tc, z, 3.7, 0.3, "terrain", &st);
			printf("tin: contours of terrain: %zu levels, %zu lines (%zu closed), length off by %.3g\n",
				   st.levels, st.lines, st.closed, st.len_worst);
			CHECK(st.levels > 20 && st.len_worst < 1e-9,
				  "terrain: every level's length equals the per-triangle sum (%.3g)", st.len_worst);
			rm(&tc);
		}
		free(xy);
		free(z);
	}
	/* levels through sample heights: integer heights on a lattice */
	{
		int			k = 40;
		size_t		n = (size_t) k * k;
		double	   *xy = malloc(n * 2 * sizeof(double)),
				   *z = malloc(n * sizeof(double));

		for (int i = 0; i < k; i++)
			for (int j = 0; j < k; j++)
			{
				xy[2 * (i * k + j)] = i;
				xy[2 * (i * k + j) + 1] = j;
				z[i * k + j] = (double) (tdc_splitmix64(&seed) % 5);
			}
		if (mk(&tc, xy, z, n, 2))
		{
			check_contours(&tc, z, 1, 0, "integer heights", &st);
			printf("tin: contours through sample heights: %zu levels, %zu lines, length off by %.3g\n",
				   st.levels, st.lines, st.len_worst);
			CHECK(st.levels == 4 && st.len_worst < 1e-12,
				  "integer heights: levels 1..4, each level's length equals the per-triangle sum (%.3g)",
				  st.len_worst);
			rm(&tc);
		}
		/* z = x: each level at a column of sites is one straight line */
		for (size_t p = 0; p < n; p++)
			z[p] = xy[2 * p];
		if (mk(&tc, xy, z, n, 2))
		{
			size_t		nl,
						np;
			int			bad = 0;
			char		err[256];

			if (run_wait(tc.tin, tdc_tin_contours_start(tc.tin, 1, 0, err, sizeof(err)), err) == TDC_OK)
			{
				nl = tdc_tin_contour_count(tc.tin, &np);
				for (size_t i = 0; i < nl; i++)
				{
					double		lev;
					size_t		m;
					bool		closed;
					const double *p = tdc_tin_contour_line(tc.tin, i, &lev, &m, &closed);

					for (size_t j = 0; j < m; j++)
						bad += p[2 * j] != lev;
					bad += closed || m != (size_t) k || lev != (double) (i + 1);
				}
				CHECK(nl == (size_t) k - 1 && bad == 0,
					  "z = x on a lattice: levels 1..%d each one open line through its %d sites (%zu lines, %d wrong)",
					  k - 1, k, nl, bad);
			}
			rm(&tc);
		}
		free(xy);
		free(z);
	}
	/* errors */
	{
		double		xy[6] = {0, 0, 10, 0, 0, 10},
					z[3] = {1e15, 2e15, 3e15};
		char		err[256];

		if (mk(&tc, xy, z, 3, 1))
		{
			CHECK(tdc_tin_contours_start(tc.tin, 0, 0, err, sizeof(err)) == TDC_EINVAL,
				  "interval 0: %s", err);
			CHECK(tdc_tin_contours_start(tc.tin, NAN, 0, err, sizeof(err)) == TDC_EINVAL,
				  "interval NaN: %s", err);
			CHECK(tdc_tin_contours_start(tc.tin, 1e-3, 0, err, sizeof(err)) == TDC_EINVAL &&
				  strstr(err, "too small"), "an interval below the heights' resolution: %s", err);
			CHECK(tdc_tin_contours_start(tc.tin, 1, INFINITY, err, sizeof(err)) == TDC_EINVAL,
				  "an infinite base: %s", err);
			rm(&tc);
		}
	}
}

/* ----------------------------------------------------------------
 *		cancel and memory
 * ----------------------------------------------------------------
 */
static void
test_cancel_memory(void)
{
	uint64_t	seed = 3;
	size_t		n = 60000;
	double	   *xy = random_points(&seed, n, 0, 0, 1000),
			   *z = malloc(n * sizeof(double));
	tin_case	tc;
	char		err[256];

	for (size_t i = 0; i < n; i++)
		z[i] = sin(xy[2 * i]) * 10;
	if (mk(&tc, xy, z, n, 1))
	{
		tdc_grid_spec g = {{0, 0.25, 0, 1000, 0, -0.25}, 4000, 4000};
		double	   *v = malloc(g.width * g.height * sizeof(double));
		tdc_interp_spec s = spec_of("natural_neighbor");
		double		t0,
					t1;
		int			rc;

		rc = tdc_tin_grid_start(tc.tin, &s, &g, v, NULL, err, sizeof(err));
		CHECK(rc == TDC_OK, "a long grid starts: %s", err);
		if (rc == TDC_OK)
		{
			usleep(30000);
			CHECK(tdc_tin_wait(tc.tin, 0) == TDC_RUNNING, "the grid of 16M natural neighbour pixels is still running");
			t0 = tdc_test_now();
			tdc_tin_cancel(tc.tin);
			rc = tdc_tin_wait(tc.tin, -1);
			t1 = tdc_test_now();
			printf("tin: a natural neighbour grid cancelled in %.1f ms\n", (t1 - t0) * 1000);
			CHECK(rc == TDC_ECANCELED && strstr(tdc_tin_error(tc.tin), "cancelled"),
				  "cancel: TDC_ECANCELED (%d: %s)", rc, tdc_tin_error(tc.tin));
			CHECK(t1 - t0 < 0.25, "cancel within 250 ms (%.1f ms)", (t1 - t0) * 1000);
			/* the TIN is usable after it */
			{
				int			ok;
				double		val = value(tc.tin, "linear", xy[0], xy[1], &ok);

				CHECK(ok == 1 && val == z[0], "after a cancel the TIN answers");
			}
		}
		free(v);
		rm(&tc);
	}
	/* a natural neighbour drape of one long line: cancelled inside the line */
	if (mk(&tc, xy, z, n, 1))
	{
		size_t		nv = 3000000,
					end[1] = {3000000};
		double	   *lv = malloc(nv * 2 * sizeof(double)),
					t0,
					t1;
		tdc_interp_spec s = spec_of("natural_neighbor");
		int			rc;

		for (size_t i = 0; i < nv; i++)
		{
			lv[2 * i] = 1 + (i % 998) + i * 1e-4;
			lv[2 * i + 1] = 1 + (double) ((i / 998) % 998);
		}
		rc = tdc_tin_drape_start(tc.tin, &s, lv, end, 1, err, sizeof(err));
		CHECK(rc == TDC_OK, "a long drape starts: %s", err);
		if (rc == TDC_OK)
		{
			usleep(30000);
			CHECK(tdc_tin_wait(tc.tin, 0) == TDC_RUNNING, "the drape of 3M vertices is still running");
			t0 = tdc_test_now();
			tdc_tin_cancel(tc.tin);
			rc = tdc_tin_wait(tc.tin, -1);
			t1 = tdc_test_now();
			printf("tin: a natural neighbour drape of one 3M-vertex line cancelled in %.1f ms\n",
				   (t1 - t0) * 1000);
			CHECK(rc == TDC_ECANCELED && (t1 - t0) < 0.25,
				  "a long line's drape cancelled within 250 ms (%d, %.1f ms)", rc, (t1 - t0) * 1000);
		}
		free(lv);
		rm(&tc);
	}
	/* memory: the TIN's own limit, and an operation's */
	{
		tdc_options o;
		tdc_job    *job;
		tdc_tin    *tin = NULL;

		tdc_options_init(&o);
		if (tdc_triangulate(xy, n, &o, &job, err, sizeof(err)) == TDC_OK)
		{
			CHECK(tdc_tin_build(job, z, 1, 1 << 20, &tin, err, sizeof(err)) == TDC_EMEMLIMIT,
				  "a TIN over its limit: %s", err);
			tdc_tin_free(tin);
			tin = NULL;
			CHECK(tdc_tin_build(job, z, 1, tdc_tin_memory(n) + (1 << 16), &tin, err, sizeof(err)) == TDC_OK,
				  "a TIN within its limit: %s", err);
			if (tin)
			{
				int			rc = tdc_tin_contours_start(tin, 0.01, 0, err, sizeof(err));

				if (rc == TDC_OK)
					rc = tdc_tin_wait(tin, -1);
				CHECK(rc == TDC_EMEMLIMIT, "contours over the limit: %d %s", rc, tdc_tin_error(tin));
			}
			tdc_tin_free(tin);
			tdc_job_free(job);
		}
	}
	free(xy);
	free(z);
}


/* ----------------------------------------------------------------
 *		breaklines: a TIN on a constrained triangulation
 * ----------------------------------------------------------------
 */

/* A TIN of xy, z with the segments seg (pairs of input indices) inserted. */
static bool
mk_cdt(tin_case *c, const double *xy, const double *z, size_t n, const uint32_t *seg,
	   size_t nseg, int threads)
{
	tdc_options o;
	tdc_cdt    *cdt = NULL;
	char		err[256];

	tdc_options_init(&o);
	o.threads = threads;
	c->job = NULL;
	c->tin = NULL;
	if (tdc_triangulate(xy, n, &o, &c->job, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "triangulate: %s", err);
		return false;
	}
	if (tdc_cdt_run(c->job, seg, nseg, &cdt, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "constraints: %s", err);
		tdc_cdt_free(cdt);
		return false;
	}
	tdc_cdt_free(cdt);
	if (tdc_tin_build(c->job, z, threads, 0, &c->tin, err, sizeof(err)) != TDC_OK)
	{
		CHECK(0, "tin build: %s", err);
		return false;
	}
	return true;
}

/* The nearest of n points to q by brute force: exact, ties to the first in (x, y). */
static size_t
brute_nearest(const double *xy, size_t n, const double *q)
{
	size_t		best = 0;

	for (size_t i = 1; i < n; i++)
	{
		int			c = tdc_sqdist_cmp(q, xy + 2 * i, q, xy + 2 * best);

		if (c < 0 || (c == 0 && tdc_lex_less(xy + 2 * i, xy + 2 * best)))
			best = i;
	}
	return best;
}

/*
 * A ridge L(0,1)-R(4,1) at height 10 between P(2,0) at 0 and Q(2,2) at 4.
 * Q lies inside the circle through L, P and R (centre (2, 2.5), radius
 * 2.5), so the Delaunay triangulation takes the diagonal P-Q across the
 * ridge, and on the ridge the surface sags to z = 10 - 4x (x < 2, plane of
 * L, P, Q: z = 8 - 4x + 2y) and z = 4x - 6 (x > 2: z = -8 + 4x + 2y).
 * With L-R as a breakline the triangles are L, P, R (z = 10y) and L, R, Q
 * (z = 10 - 3y + ... : through (0,1,10), (4,1,10), (2,2,4): z = 16 - 6y),
 * and the ridge stays at 10.
 */
static void
test_breaklines_ridge(void)
{
	static const double xy[] = {0, 1, 4, 1, 2, 0, 2, 2};
	static const double z[] = {10, 10, 0, 4};
	static const uint32_t seg[] = {0, 1};
	tin_case	plain,
				brk;
	tdc_grid_spec g = {{0, 1, 0, 1.5, 0, -1}, 4, 2};
	double		vp[8],
				vb[8],
				zq;
	uint8_t		ok[8];
	int			valid;
	char		err[256];
	tdc_interp_spec nn = spec_of("natural_neighbor");

	if (!mk(&plain, xy, z, 4, 1))
		return;
	if (!mk_cdt(&brk, xy, z, 4, seg, 1, 1))
	{
		rm(&plain);
		return;
	}
	/* on the ridge */
	CHECK(value(plain.tin, "linear", 1, 1, NULL) == 6, "no breakline: (1 1) on plane L,P,Q is 6, got %.17g",
		  value(plain.tin, "linear", 1, 1, NULL));
	CHECK(value(brk.tin, "linear", 1, 1, NULL) == 10, "breakline: (1 1) on the ridge is 10, got %.17g",
		  value(brk.tin, "linear", 1, 1, NULL));
	CHECK(value(plain.tin, "linear", 2, 1, NULL) == 2, "no breakline: (2 1) on P-Q is 2, got %.17g",
		  value(plain.tin, "linear", 2, 1, NULL));
	CHECK(value(brk.tin, "linear", 2, 1, NULL) == 10, "breakline: (2 1) is 10, got %.17g",
		  value(brk.tin, "linear", 2, 1, NULL));
	/* off the ridge: the constrained triangles' planes */
	CHECK(value(brk.tin, "linear", 2, 0.5, NULL) == 5, "breakline: (2 0.5) on z = 10y is 5, got %.17g",
		  value(brk.tin, "linear", 2, 0.5, NULL));
	CHECK(value(plain.tin, "linear", 2, 0.5, NULL) == 1, "no breakline: (2 0.5) on P-Q is 1, got %.17g",
		  value(plain.tin, "linear", 2, 0.5, NULL));
	zq = value(brk.tin, "linear", 3, 1.5, NULL);
	CHECK(fabs(zq - 7) < 1e-12, "breakline: (3 1.5) on z = 16 - 6y is 7, got %.17g", zq);
	/* samples stay exact; nearest is the same with and without */
	CHECK(value(brk.tin, "linear", 2, 2, NULL) == 4 && value(brk.tin, "linear", 4, 1, NULL) == 10,
		  "breakline: exact at the samples");
	CHECK(value(brk.tin, "nearest", 2, 1.4, NULL) == 4 && value(plain.tin, "nearest", 2, 1.4, NULL) == 4,
		  "nearest is Q's with and without the breakline");
	/* outside the hull: the nearest site, found by the k-d tree */
	CHECK(value(brk.tin, "linear", 5, 1.2, &valid) == 10 && valid == 1,
		  "breakline: outside, the nearest site R");
	CHECK(value(brk.tin, "linear", 2, -3, &valid) == 0 && valid == 1,
		  "breakline: outside, the nearest site P");

	/* a grid: row 0 along the ridge (y = 1), row 1 at y = 0 is P's corner... */
	if (grid(plain.tin, "linear:radius=0:nodata=-1", &g, vp, ok) == TDC_OK &&
		grid(brk.tin, "linear:radius=0:nodata=-1", &g, vb, ok) == TDC_OK)
	{
		CHECK(vb[0] == 10 && vb[1] == 10 && vb[2] == 10 && vb[3] == 10,
			  "breakline grid: the ridge row is 10: %g %g %g %g", vb[0], vb[1], vb[2], vb[3]);
		CHECK(fabs(vp[0] - 8) < 1e-12 && fabs(vp[1] - 4) < 1e-12 &&
			  fabs(vp[2] - 4) < 1e-12 && fabs(vp[3] - 8) < 1e-12,
			  "plain grid: the ridge row sags to 8 4 4 8: %g %g %g %g", vp[0], vp[1], vp[2], vp[3]);
		/* row 1 (y = 0): outside but for P's corner region; (1.5 0) is outside */
		CHECK(vb[4] == -1 && vp[4] == -1, "outside with radius 0: nodata");
	}

	/* draping along the ridge: on the constraint no edge is crossed */
	{
		double		line[] = {0.5, 1, 3.5, 1};
		size_t		lend[] = {2};
		tdc_interp_spec s = spec_of("linear:breaklines=true");
		const tdc_drape_vertex *v;
		const size_t *off;
		size_t		nv;
		bool		flat = true,
					mid = false;

		if (run_wait(brk.tin, tdc_tin_drape_start(brk.tin, &s, line, lend, 1, err, sizeof(err)), err) == TDC_OK)
		{
			nv = tdc_tin_drape_result(brk.tin, &v, &off);
			for (size_t i = 0; i < nv; i++)
				flat &= v[i].z == 10 && v[i].valid;
			CHECK(nv >= 2 && flat, "breakline drape: %zu vertices, all at 10", nv);
		}
		s = spec_of("linear");
		if (run_wait(plain.tin, tdc_tin_drape_start(plain.tin, &s, line, lend, 1, err, sizeof(err)), err) == TDC_OK)
		{
			nv = tdc_tin_drape_result(plain.tin, &v, &off);
			for (size_t i = 0; i < nv; i++)
				mid |= v[i].x == 2 && v[i].y == 1 && v[i].z == 2;
			CHECK(nv == 3 && mid, "plain drape: a vertex where P-Q is crossed, at 2 (%zu vertices)", nv);
		}
	}

	/* natural neighbour: refused on the constrained TIN, for every entry */
	{
		double		q[2] = {1, 1},
					zz;

		CHECK(tdc_tin_value(brk.tin, &nn, q, &zz) == TDC_EINVAL, "natural neighbour value refused");
		CHECK(tdc_tin_grid_start(brk.tin, &nn, &g, vb, ok, err, sizeof(err)) == TDC_EINVAL &&
			  strstr(err, "constrained") != NULL, "natural neighbour grid refused: %s", err);
		CHECK(tdc_tin_value(plain.tin, &nn, q, &zz) == 1, "natural neighbour without constraints");
	}
	rm(&plain);
	rm(&brk);
}

/*
 * On a constrained TIN the nearest site comes from the k-d tree: the same
 * as brute force, inside and outside the hull, with a long monotone
 * breakline across random sites and for 1 and 3 threads; and the
 * triangulation is the constrained one (every constraint an edge).
 */
static void
test_breaklines_nearest(void)
{
	uint64_t	seed = 2029;
	size_t		ns = 3000,
				nl = 60,
				n = ns + nl,
				nq = 4000,
				bad = 0,
				badlin = 0;
	double	   *xy = random_points(&seed, n, 0, 0, 100),
			   *z = malloc(n * sizeof(double)),
			   *q = random_points(&seed, nq, -30, -30, 160),
			   *v1 = malloc(nq * sizeof(double)),
			   *v3 = malloc(nq * sizeof(double)),
			   *lin = malloc(nq * sizeof(double));
	uint8_t    *ok = malloc(nq);
	uint32_t   *seg = malloc(2 * (nl - 1) * sizeof(uint32_t));
	tin_case	c1,
				c3;

	/* the line: x increasing, y zigzagging, so it never crosses itself */
	for (size_t i = 0; i < nl; i++)
	{
		xy[2 * (ns + i)] = 1 + 98.0 * (double) i / (double) (nl - 1);
		xy[2 * (ns + i) + 1] = i % 2 ? 70 : 30;
		if (i + 1 < nl)
		{
			seg[2 * i] = (uint32_t) (ns + i);
			seg[2 * i + 1] = (uint32_t) (ns + i + 1);
		}
	}
	for (size_t i = 0; i < n; i++)
		z[i] = (double) i;
	/* some queries exactly at sites and exactly between two */
	for (size_t i = 0; i < 40; i++)
	{
		q[2 * i] = xy[2 * (i * 7)];
		q[2 * i + 1] = xy[2 * (i * 7) + 1];
	}
	if (!mk_cdt(&c1, xy, z, n, seg, nl - 1, 1))
		goto out;
	if (!mk_cdt(&c3, xy, z, n, seg, nl - 1, 3))
	{
		rm(&c1);
		goto out;
	}
	if (points(c1.tin, "nearest", q, nq, v1, ok) == TDC_OK &&
		points(c3.tin, "nearest", q, nq, v3, ok) == TDC_OK &&
		points(c3.tin, "linear", q, nq, lin, ok) == TDC_OK)
	{
		for (size_t i = 0; i < nq; i++)
		{
			size_t		b = brute_nearest(xy, n, q + 2 * i);

			bad += v1[i] != z[b] || v3[i] != z[b];
			if (!tdc_tin_inside(c3.tin, q + 2 * i))
				badlin += lin[i] != z[b];
		}
		CHECK(bad == 0, "constrained nearest = brute force at %zu points (%zu differ)", nq, bad);
		CHECK(badlin == 0, "constrained linear outside the hull = the nearest site (%zu differ)", badlin);
	}
	/* the constraints are edges of the TIN's triangulation */
	{
		tdc_iter	it = {0};
		uint32_t	e[2];
		size_t		found = 0;

		while (tdc_next_edge(c3.job, &it, e))
			for (size_t i = 0; i + 1 < nl; i++)
			{
				const double *a = tdc_site_xy(c3.job, e[0]),
						   *b = tdc_site_xy(c3.job, e[1]),
						   *p = xy + 2 * (ns + i),
						   *r = p + 2;

				if ((a[0] == p[0] && a[1] == p[1] && b[0] == r[0] && b[1] == r[1]) ||
					(a[0] == r[0] && a[1] == r[1] && b[0] == p[0] && b[1] == p[1]))
					found++;
			}
		CHECK(found == nl - 1, "all %zu breakline segments are TIN edges (%zu)", nl - 1, found);
	}
	rm(&c1);
	rm(&c3);
out:
	free(xy);
	free(z);
	free(q);
	free(v1);
	free(v3);
	free(lin);
	free(ok);
	free(seg);
}

static void
test_breaklines_parse(void)
{
	tdc_interp_spec s;
	char		err[256];

	CHECK(tdc_interp_parse("linear", &s, err, sizeof(err)) == TDC_OK && !s.breaklines,
		  "breaklines: false by default");
	CHECK(tdc_interp_parse("linear:breaklines=true:radius=0", &s, err, sizeof(err)) == TDC_OK &&
		  s.breaklines && s.radius == 0, "linear:breaklines=true:radius=0");
	CHECK(tdc_interp_parse("LINEAR:BreakLines=YES", &s, err, sizeof(err)) == TDC_OK && s.breaklines,
		  "breaklines=YES, any case");
	CHECK(tdc_interp_parse("linear:breaklines=off", &s, err, sizeof(err)) == TDC_OK && !s.breaklines,
		  "breaklines=off");
	CHECK(tdc_interp_parse("linear:breaklines=maybe", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "not a boolean"), "breaklines=maybe: %s", err);
	CHECK(tdc_interp_parse("linear:breaklines=", &s, err, sizeof(err)) == TDC_EINVAL,
		  "breaklines without a value: %s", err);
	CHECK(tdc_interp_parse("natural_neighbor:breaklines=true", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "linear only") && strstr(err, "natural"), "natural neighbour: %s", err);
	CHECK(tdc_interp_parse("nearest:breaklines=false", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "linear only"), "nearest: %s", err);
	CHECK(tdc_interp_parse("linear:breaklines", &s, err, sizeof(err)) == TDC_EINVAL,
		  "breaklines with no value: %s", err);
}

void
test_tin(void)
{
	test_parse();
	test_planes();
	test_exact_samples();
	test_degenerate();
	test_lattice();
	test_cgal();
	test_drape();
	test_contours();
	test_threads();
	test_cancel_memory();
	test_breaklines_parse();
	test_breaklines_ridge();
	test_breaklines_nearest();
	test_tin_maxedge();			/* test_tin_maxedge.c */
}
