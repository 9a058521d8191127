/*
 * test_engine.c
 *		Property tests of the engine through its public API.
 *
 * Every result goes through the exact validator (tdc_validate), and results
 * that must be equal are compared as canonical triangle sets: each triangle
 * as its three vertex coordinates, rotated so the lexicographically smallest
 * comes first (orientation is part of the check), the list sorted.  The
 * symbolic tie-break makes the set unique even for cocircular sites, so it
 * must not depend on threads, grid size, levels or input order.
 */
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"
#include "xy_oracle.h"

typedef struct canon
{
	size_t		ntri;
	double	   *t;				/* 6 doubles per triangle */
} canon;

static uint64_t rng_state;

static uint64_t
rng(void)
{
	return tdc_splitmix64(&rng_state);
}

static double
urand(void)
{
	return (rng() >> 11) * 0x1p-53;
}

static double
nrand(void)
{
	double		u = urand() + 1e-300,
				v = urand();

	return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
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

static bool
pt_less(const double *p, const double *q)
{
	return p[0] < q[0] || (p[0] == q[0] && p[1] < q[1]);
}

/*
 * Triangulate, validate and canonicalise.  Returns false (after counting a
 * failure) when the engine or the validator fails.
 */
static bool
run_checked(const char *name, const double *xy, size_t n, const tdc_options *opt,
			canon *out)
{
	tdc_job    *job;
	char		err[512];
	int			rc = tdc_triangulate(xy, n, opt, &job, err, sizeof(err));
	uint32_t	lim,
			   *compact,
			   *tri,
				v[3];
	double	   *sites;
	size_t		m = 0,
				t = 0,
				uniq;
	tdc_iter	it = {0};
	bool		ok;

	out->ntri = 0;
	out->t = NULL;
	if (rc != TDC_OK)
	{
		CHECK(0, "%s: engine failed: %s", name, err);
		tdc_job_free(job);
		return false;
	}
	uniq = count_unique(xy, n);
	CHECK(tdc_num_sites(job) == uniq || opt->tolerance > 0,
		  "%s: %zu unique sites reported, %zu expected", name, tdc_num_sites(job), uniq);

	/* the used sites, compacted, via the input map (covers collinear input) */
	lim = tdc_site_id_limit(job);
	compact = malloc(sizeof(uint32_t) * (lim + 1));
	sites = malloc(16 * (size_t) (tdc_num_sites(job) + 1));
	tri = malloc(12 * (tdc_num_triangles(job) + 1));
	for (uint32_t s = 0; s < lim; s++)
		compact[s] = UINT32_MAX;
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);

		if (s >= lim)
		{
			CHECK(0, "%s: input %zu maps to site %u beyond %u", name, i, s, lim);
			goto fail;
		}
		if (compact[s] == UINT32_MAX)
		{
			compact[s] = (uint32_t) m;
			memcpy(sites + 2 * m, tdc_site_xy(job, s), 16);
			m++;
		}
	}
	CHECK(m == tdc_num_sites(job), "%s: map reaches %zu sites, engine reports %zu",
		  name, m, tdc_num_sites(job));
	while (tdc_next_triangle(job, &it, v))
	{
		if (t >= tdc_num_triangles(job))
		{
			CHECK(0, "%s: more triangles iterated than the %zu reported", name,
				  tdc_num_triangles(job));
			goto fail;
		}
		for (int k = 0; k < 3; k++)
		{
			if (compact[v[k]] == UINT32_MAX)
			{
				CHECK(0, "%s: triangle uses a site no input maps to", name);
				goto fail;
			}
			tri[3 * t + k] = compact[v[k]];
		}
		t++;
	}
	CHECK(t == tdc_num_triangles(job), "%s: iterated %zu triangles, reported %zu", name,
		  t, tdc_num_triangles(job));
	ok = tdc_validate(sites, m, tri, t, err, sizeof(err)) == 0;
	CHECK(ok, "%s: validator: %s", name, err);
	if (!ok)
		goto fail;

	out->ntri = t;
	out->t = malloc(48 * (t + 1));
	for (size_t i = 0; i < t; i++)
	{
		int			lo = 0;

		for (int k = 1; k < 3; k++)
			if (pt_less(sites + 2 * tri[3 * i + k], sites + 2 * tri[3 * i + lo]))
				lo = k;
		for (int k = 0; k < 3; k++)
			memcpy(out->t + 6 * i + 2 * k, sites + 2 * tri[3 * i + (lo + k) % 3], 16);
	}
	qsort(out->t, t, 48, cmp_tri);
	free(compact);
	free(sites);
	free(tri);
	tdc_job_free(job);
	return true;

fail:
	free(compact);
	free(sites);
	free(tri);
	tdc_job_free(job);
	return false;
}

static bool
canon_equal(const canon *a, const canon *b)
{
	return a->ntri == b->ntri &&
		(a->ntri == 0 || memcmp(a->t, b->t, 48 * a->ntri) == 0);
}

/*
 * FNV-1a over the triangles' vertex coordinates in tdc_next_triangle's
 * order: two runs hash alike only if they emit the same triangles in the
 * same order with the same first vertex, that is the same output bytes.
 */
static uint64_t
output_hash(const double *xy, size_t n, const tdc_options *opt)
{
	tdc_job    *job;
	char		err[512];
	tdc_iter	it = {0};
	uint32_t	v[3];
	uint64_t	h = 1469598103934665603ULL;

	if (tdc_triangulate(xy, n, opt, &job, err, sizeof(err)) != TDC_OK)
	{
		tdc_job_free(job);
		return 0;
	}
	while (tdc_next_triangle(job, &it, v))
		for (int k = 0; k < 3; k++)
		{
			const unsigned char *b = (const unsigned char *) tdc_site_xy(job, v[k]);

			for (int i = 0; i < 16; i++)
				h = (h ^ b[i]) * 1099511628211ULL;
		}
	tdc_job_free(job);
	return h;
}

/*
 * Validate one input under many settings and require the same triangle set
 * from all of them, and from the input shuffled: with the same options, even
 * the same output in the same order (the recursion depends on the point set
 * only, never on positions).
 */
static void
check_settings(const char *name, double *xy, size_t n, size_t expect_tri)
{
	static const struct
	{
		int			threads,
					grid,
					levels;
	}			settings[] = {
		{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}, {8, 0, 0},
		{1, 0, -1}, {2, 0, 1}, {2, 16, 3}, {4, 1000, 5}, {8, 7, 8}, {5, 0, 2},
	};
	canon		ref,
				c;
	tdc_options opt;
	char		label[256];
	double	   *shuffled;

	tdc_options_init(&opt);
	if (!run_checked(name, xy, n, &opt, &ref))
		return;
	if (expect_tri != SIZE_MAX)
		CHECK(ref.ntri == expect_tri, "%s: %zu triangles, expected %zu", name, ref.ntri, expect_tri);
	for (size_t s = 0; s < sizeof(settings) / sizeof(settings[0]); s++)
	{
		if (tdc_test_quick && settings[s].threads > 4)
			continue;
		opt.threads = settings[s].threads;
		opt.grid_size = settings[s].grid;
		opt.levels = settings[s].levels;
		snprintf(label, sizeof(label), "%s [t=%d g=%d l=%d]", name, opt.threads,
				 opt.grid_size, opt.levels);
		if (run_checked(label, xy, n, &opt, &c))
		{
			CHECK(canon_equal(&ref, &c), "%s: triangle set differs from the default run", label);
			free(c.t);
		}
	}
	/* input order */
	shuffled = malloc(16 * n + 16);
	memcpy(shuffled, xy, 16 * n);
	for (size_t i = n; i > 1; i--)
	{
		size_t		j = rng() % i;
		double		tx = shuffled[2 * (i - 1)],
					ty = shuffled[2 * (i - 1) + 1];

		shuffled[2 * (i - 1)] = shuffled[2 * j];
		shuffled[2 * (i - 1) + 1] = shuffled[2 * j + 1];
		shuffled[2 * j] = tx;
		shuffled[2 * j + 1] = ty;
	}
	tdc_options_init(&opt);
	opt.threads = 2;
	snprintf(label, sizeof(label), "%s [shuffled]", name);
	if (run_checked(label, shuffled, n, &opt, &c))
	{
		CHECK(canon_equal(&ref, &c), "%s: triangle set depends on input order", label);
		free(c.t);
	}
	CHECK(output_hash(xy, n, &opt) == output_hash(shuffled, n, &opt),
		  "%s: output order depends on input order", label);
	free(shuffled);
	free(ref.t);
}

/* --- generators --- */

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
		xy[2 * i] = cx + nrand() * 3;
		xy[2 * i + 1] = cy + nrand() * 3;
	}
	return xy;
}

static double *
gen_grid(size_t side, double step, double ox, double oy)
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

/* All lattice points on circles x^2 + y^2 = r^2 with many representations. */
static double *
gen_circles(size_t *n)
{
	static const long radii[] = {5, 25, 65, 325, 1105, 5525};
	size_t		cap = 1 << 16,
				k = 0;
	double	   *xy = malloc(16 * cap);

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

static size_t
hull_with_collinear_rect(size_t side)
{
	return 4 * (side - 1);
}

static void
test_small_and_degenerate(void)
{
	double		pts[] = {0, 0, 1, 0, 0, 1, 1, 1, 0.5, 0.5};
	double		line[2 * 50];
	double		dup[2 * 40];
	canon		c;
	tdc_options opt;

	tdc_options_init(&opt);
	for (size_t k = 0; k <= 3; k++)
	{
		char		name[32];

		snprintf(name, sizeof(name), "%zu sites", k);
		CHECK(run_checked(name, pts, k, &opt, &c) && c.ntri == (k == 3),
			  "%s: %zu triangles", name, c.ntri);
		free(c.t);
	}
	check_settings("square (cocircular)", pts, 4, 2);
	check_settings("square + centre", pts, 5, 4);

	for (int i = 0; i < 50; i++)
	{
		line[2 * i] = 3 + 0.25 * ((i * 17) % 50);
		line[2 * i + 1] = -2 + 0.5 * ((i * 17) % 50);
	}
	check_settings("collinear (no triangles)", line, 50, 0);
	for (int i = 0; i < 40; i++)
	{
		dup[2 * i] = 7.5;
		dup[2 * i + 1] = -1.25;
	}
	check_settings("all duplicates", dup, 40, 0);
	dup[2] = 8;
	check_settings("duplicates + 1", dup, 40, 0);
	dup[5] = 3;
	check_settings("duplicates + 2", dup, 40, 1);
}

static void
test_random_sets(void)
{
	size_t		big = tdc_test_quick ? 20000 : 200000;
	double	   *xy;
	size_t		n;

	rng_state = 42;
	for (size_t sz = 3; sz <= 40; sz++)
	{
		char		name[64];

		snprintf(name, sizeof(name), "uniform %zu", sz);
		xy = gen_uniform(sz, 1000, 0, 0);
		check_settings(name, xy, sz, SIZE_MAX);
		free(xy);
	}
	xy = gen_uniform(5000, 1000, 0, 0);
	check_settings("uniform 5000", xy, 5000, SIZE_MAX);
	free(xy);
	xy = gen_uniform(big, 1000, 0, 0);
	check_settings("uniform large", xy, big, SIZE_MAX);
	free(xy);
	xy = gen_clustered(big / 4);
	check_settings("clustered", xy, big / 4, SIZE_MAX);
	free(xy);

	/* integer grid: every lattice square is cocircular; hull keeps collinear sites */
	xy = gen_grid(70, 1, 0, 0);
	check_settings("integer grid 70x70", xy, 4900, 2 * 4900 - 2 - hull_with_collinear_rect(70));
	free(xy);
	xy = gen_grid(40, 0.125, 5e6, 6e6);
	check_settings("grid at 5e6 offsets", xy, 1600, 2 * 1600 - 2 - hull_with_collinear_rect(40));
	free(xy);
	xy = gen_circles(&n);
	check_settings("cocircular lattice points", xy, n, SIZE_MAX);
	free(xy);

	/* projected coordinates with sub-millimetre offsets */
	xy = gen_uniform(20000, 0.001, 5e6, 4.2e6);
	check_settings("5e6 + sub-millimetre", xy, 20000, SIZE_MAX);
	free(xy);
	/* lon/lat */
	xy = gen_uniform(20000, 1, 0, 0);
	for (size_t i = 0; i < 20000; i++)
	{
		xy[2 * i] = -180 + 360 * xy[2 * i];
		xy[2 * i + 1] = -90 + 180 * xy[2 * i + 1];
	}
	check_settings("lon/lat", xy, 20000, SIZE_MAX);
	free(xy);
	/* huge and tiny scales */
	xy = gen_uniform(5000, 1e55, 0, 0);
	check_settings("huge scale 1e55", xy, 5000, SIZE_MAX);
	free(xy);
	xy = gen_uniform(5000, 1e-50, 1e-45, 1e-45);
	check_settings("tiny scale 1e-50", xy, 5000, SIZE_MAX);
	free(xy);

	/* sites one ulp apart, and near-duplicates */
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
	check_settings("one ulp apart", xy, 3000, SIZE_MAX);
	free(xy);

	/* many exact duplicates among random points */
	xy = gen_uniform(30000, 100, 0, 0);
	for (size_t i = 10000; i < 30000; i++)
	{
		size_t		j = rng() % 10000;

		xy[2 * i] = xy[2 * j];
		xy[2 * i + 1] = xy[2 * j + 1];
	}
	check_settings("duplicates in random", xy, 30000, SIZE_MAX);
	free(xy);

	/* all collinear along a diagonal, and along the axes */
	xy = malloc(16 * 10000);
	for (size_t i = 0; i < 10000; i++)
	{
		xy[2 * i] = (double) (rng() % 5000);
		xy[2 * i + 1] = 2 * xy[2 * i] + 1;
	}
	check_settings("collinear diagonal 10000", xy, 10000, 0);
	for (size_t i = 0; i < 10000; i++)
		xy[2 * i + 1] = 3;
	check_settings("collinear horizontal", xy, 10000, 0);
	free(xy);

	/* collinear sites along the hull: points on a rectangle's border + interior */
	xy = malloc(16 * 2000);
	for (size_t i = 0; i < 1000; i++)
	{
		double		f = (double) (i % 250);

		switch (i / 250)
		{
			case 0:
				xy[2 * i] = f, xy[2 * i + 1] = 0;
				break;
			case 1:
				xy[2 * i] = 250, xy[2 * i + 1] = f;
				break;
			case 2:
				xy[2 * i] = 250 - f, xy[2 * i + 1] = 250;
				break;
			default:
				xy[2 * i] = 0, xy[2 * i + 1] = 250 - f;
		}
	}
	for (size_t i = 1000; i < 2000; i++)
	{
		xy[2 * i] = 1 + urand() * 248;
		xy[2 * i + 1] = 1 + urand() * 248;
	}
	check_settings("collinear hull sites", xy, 2000, 2 * 2000 - 2 - 1000);
	free(xy);
}

static void
test_map_and_tolerance(void)
{
	double		pts[] = {5, 5, 6, 0, 7, 9, 8, 9, 5, 5, 7, 9};
	tdc_options opt;
	tdc_job    *job;
	char		err[256];
	double		lo[2],
				hi[2];

	tdc_options_init(&opt);
	CHECK(tdc_triangulate(pts, 6, &opt, &job, err, sizeof(err)) == TDC_OK, "map: %s", err);
	CHECK(tdc_num_sites(job) == 4, "map: 4 unique sites");
	CHECK(tdc_input_site(job, 4) == tdc_input_site(job, 0), "map: duplicate follows first");
	CHECK(tdc_input_site(job, 5) == tdc_input_site(job, 2), "map: duplicate follows first");
	CHECK(tdc_site_input(job, tdc_input_site(job, 4)) == 0, "map: first occurrence kept");
	CHECK(tdc_site_input(job, tdc_input_site(job, 5)) == 2, "map: first occurrence kept");
	tdc_site_extent(job, lo, hi);
	CHECK(lo[0] == 5 && lo[1] == 0 && hi[0] == 8 && hi[1] == 9,
		  "extent: (%g %g, %g %g)", lo[0], lo[1], hi[0], hi[1]);
	tdc_job_free(job);

	/* PostGIS case: tolerance 2 drops (8 9), within 1 of (7 9) */
	opt.tolerance = 2;
	CHECK(tdc_triangulate(pts, 4, &opt, &job, err, sizeof(err)) == TDC_OK, "tol: %s", err);
	CHECK(tdc_num_sites(job) == 3 && tdc_num_triangles(job) == 1,
		  "tolerance 2: %zu sites %zu triangles", tdc_num_sites(job), tdc_num_triangles(job));
	CHECK(tdc_input_site(job, 3) == tdc_input_site(job, 2), "tolerance: dropped maps to absorbing site");
	/* the dropped (8 9) was the input's xmax: the extent is the kept sites' */
	tdc_site_extent(job, lo, hi);
	CHECK(lo[0] == 5 && lo[1] == 0 && hi[0] == 7 && hi[1] == 9,
		  "tolerance extent: (%g %g, %g %g)", lo[0], lo[1], hi[0], hi[1]);
	tdc_job_free(job);

	/* tolerance: no two kept sites closer than it, and deterministic */
	{
		double	   *xy = gen_uniform(20000, 100, 0, 0);
		canon		a,
					b;

		opt.tolerance = 0.5;
		opt.threads = 1;
		if (run_checked("tolerance 0.5", xy, 20000, &opt, &a))
		{
			opt.threads = 4;
			opt.levels = 4;
			if (run_checked("tolerance 0.5 t4", xy, 20000, &opt, &b))
			{
				CHECK(canon_equal(&a, &b), "tolerance result independent of threads");
				free(b.t);
			}
			free(a.t);
		}
		free(xy);
	}
}

static void
test_errors(void)
{
	double		bad[] = {0, 0, 1, 1, NAN, 2};
	double		inf[] = {0, 0, INFINITY, 1, 2, 2};
	double		far[] = {0, 0, 1e61, 1, 2, 2};
	double		tiny[] = {0, 0, 1e-61, 1, 2, 2};
	tdc_options opt;
	tdc_job    *job;
	char		err[256];

	tdc_options_init(&opt);
	CHECK(tdc_triangulate(bad, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "non-finite"), "NaN rejected: %s", err);
	tdc_job_free(job);
	CHECK(tdc_triangulate(inf, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "non-finite"), "Infinity rejected: %s", err);
	tdc_job_free(job);
	CHECK(tdc_triangulate(far, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "magnitude"), "1e61 rejected: %s", err);
	tdc_job_free(job);
	CHECK(tdc_triangulate(tiny, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL,
		  "1e-61 rejected: %s", err);
	tdc_job_free(job);
	opt.max_memory = 1000;
	CHECK(tdc_job_start(bad, 3, &opt, &job, err, sizeof(err)) == TDC_EMEMLIMIT && job == NULL,
		  "memory limit: %s", err);
	tdc_options_init(&opt);
	CHECK(tdc_job_start(bad, TDC_MAX_POINTS + 1, &opt, &job, err, sizeof(err)) == TDC_ETOOBIG &&
		  strstr(err, "700000000"), "too many points: %s", err);
	opt.threads = -1;
	CHECK(tdc_job_start(bad, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL, "bad threads");
	tdc_options_init(&opt);
	opt.tolerance = -1;
	CHECK(tdc_job_start(bad, 3, &opt, &job, err, sizeof(err)) == TDC_EINVAL, "negative tolerance");
}

/*
 * Jobs below TDC_INLINE_MAX points run on the caller's thread, the others on
 * the pool.  Padding a point set with exact duplicates of its own points
 * changes no site, so the same sites go through both paths: the triangle
 * sets must be equal.  Covers 0 to 10 sites, collinear sites, a tolerance,
 * and sizes on both sides of the switch.
 */
static void
check_inline_vs_threaded(const char *name, const double *xy, size_t m,
						 double tolerance)
{
	size_t		n = m < TDC_INLINE_MAX ? TDC_INLINE_MAX + 1 : m + 1;
	double	   *pad = malloc(16 * n);
	tdc_options opt;
	tdc_job    *job;
	char		err[256];
	canon		a,
				b;

	memcpy(pad, xy, 16 * m);
	for (size_t i = m; i < n; i++)
		memcpy(pad + 2 * i, xy + 2 * ((i * 7919) % (m ? m : 1)), 16);
	if (m == 0)
		for (size_t i = 0; i < n; i++)
			pad[2 * i] = pad[2 * i + 1] = 1.5;
	tdc_options_init(&opt);
	opt.threads = 2;
	opt.tolerance = tolerance;

	CHECK(tdc_triangulate(xy, m, &opt, &job, err, sizeof(err)) == TDC_OK &&
		  tdc_threads_used(job) == (m < TDC_INLINE_MAX ? 1 : 2),
		  "%s: %zu points ran on %d threads", name, m, job ? tdc_threads_used(job) : -1);
	tdc_job_free(job);
	CHECK(tdc_triangulate(pad, n, &opt, &job, err, sizeof(err)) == TDC_OK &&
		  tdc_threads_used(job) == 2,
		  "%s: %zu points ran on %d threads", name, n, job ? tdc_threads_used(job) : -1);
	tdc_job_free(job);

	if (m > 0 && run_checked(name, xy, m, &opt, &a))
	{
		if (run_checked(name, pad, n, &opt, &b))
		{
			CHECK(canon_equal(&a, &b), "%s: %zu sites inline give %zu triangles, threaded %zu (or other ones)",
				  name, m, a.ntri, b.ntri);
			free(b.t);
		}
		free(a.t);
	}
	free(pad);
}

static void
test_inline_boundary(void)
{
	/* 255..257: the largest jobs whose arrays come from job.c's arena, and the first that do not */
	size_t		sizes[] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 100, 255, 256, 257, 1000,
	TDC_INLINE_MAX - 2, TDC_INLINE_MAX - 1, TDC_INLINE_MAX, TDC_INLINE_MAX + 1};
	double	   *xy = gen_uniform(TDC_INLINE_MAX + 2, 1000, 0, 0);
	double		line[2 * 64];
	char		name[64];

	for (size_t k = 0; k < sizeof(sizes) / sizeof(sizes[0]); k++)
	{
		snprintf(name, sizeof(name), "inline/threaded, %zu points", sizes[k]);
		check_inline_vs_threaded(name, xy, sizes[k], 0);
	}
	check_inline_vs_threaded("inline/threaded, 0 points", xy, 0, 0);
	check_inline_vs_threaded("inline/threaded, tolerance", xy, 5000, 3.0);
	check_inline_vs_threaded("inline/threaded, tolerance, arena", xy, 200, 30.0);
	{
		/* a user's grid and levels outgrow the arena: those arrays fall back */
		tdc_options o;
		canon		c;

		tdc_options_init(&o);
		o.grid_size = 65536;
		o.levels = 24;
		if (run_checked("arena overflow: grid 65536, levels 24, 256 points", xy, 256, &o, &c))
			free(c.t);
	}
	for (int i = 0; i < 64; i++)
	{
		line[2 * i] = 0.125 * ((i * 37) % 64);
		line[2 * i + 1] = 1 - 0.25 * ((i * 37) % 64);
	}
	check_inline_vs_threaded("inline/threaded, collinear", line, 64, 0);
	free(xy);
}

/*
 * Cancel at several moments of a large run.  On a quiet machine the worst
 * moment is answered in about 12 ms (printed, and reported in the README);
 * the check allows 250 ms, a margin no load on a shared machine has broken,
 * while a missing cancel check still shows up as seconds.
 */
#define CANCEL_LIMIT_MS		250
static void
test_cancel_and_concurrency(void)
{
	size_t		n = tdc_test_quick ? 200000 : 2000000;
	double	   *xy = gen_uniform(n, 1000, 0, 0);
	tdc_options opt;
	double		worst = 0;

	tdc_options_init(&opt);
	for (int delay = 0; delay <= 60; delay += 15)
	{
		/*
		 * The best of three tries per moment: on a loaded machine the driver
		 * thread may simply not be scheduled for a while, which says nothing
		 * about how often the workers poll.
		 */
		double		best = 1e9;

		for (int attempt = 0; attempt < 3 && best >= CANCEL_LIMIT_MS * 1e-3 / 5; attempt++)
		{
			tdc_job    *job;
			char		err[256];
			double		t;
			int			rc;

			opt.levels = delay == 60 ? -1 : 0;	/* one subset: cancel inside one recursion */
			CHECK(tdc_job_start(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK, "start: %s", err);
			if (job == NULL)
				continue;
			tdc_job_wait(job, delay);
			t = tdc_test_now();
			tdc_job_cancel(job);
			rc = tdc_job_wait(job, -1);
			t = tdc_test_now() - t;
			best = t < best ? t : best;
			CHECK(rc == TDC_ECANCELED || rc == TDC_OK, "cancel after %d ms: status %d", delay, rc);
			tdc_job_free(job);
		}
		worst = best > worst ? best : worst;
	}
	CHECK(worst < CANCEL_LIMIT_MS * 1e-3, "cancel answered in %.1f ms (limit %d)",
		  worst * 1e3, CANCEL_LIMIT_MS);
	printf("cancel latency, worst of 5 moments (best of up to 3 tries each): %.2f ms\n", worst * 1e3);

	/* two triangulations at once in one process */
	{
		tdc_job    *a,
				   *b;
		char		err[256];

		opt.levels = 0;
		opt.threads = 2;
		CHECK(tdc_job_start(xy, n / 4, &opt, &a, err, sizeof(err)) == TDC_OK, "job a");
		CHECK(tdc_job_start(xy + n / 2, n / 4, &opt, &b, err, sizeof(err)) == TDC_OK, "job b");
		CHECK(tdc_job_wait(a, -1) == TDC_OK && tdc_job_wait(b, -1) == TDC_OK, "both finish");
		CHECK(tdc_num_triangles(a) > n / 4 && tdc_num_triangles(b) > n / 4, "both triangulated");
		tdc_job_free(a);
		tdc_job_free(b);
	}
	free(xy);
}

typedef struct emit_sink
{
	uint32_t   *tri;			/* 3 per triangle, by triangle number */
	size_t		ntri;
	atomic_size_t calls;
	atomic_int	bad;			/* a range outside [0, ntri) */
} emit_sink;

static void
emit_collect(void *arg, size_t first, size_t count, const uint32_t *v)
{
	emit_sink  *s = arg;

	atomic_fetch_add(&s->calls, 1);
	if (first + count > s->ntri || count == 0)
	{
		atomic_store(&s->bad, 1);
		return;
	}
	memcpy(s->tri + 3 * first, v, 3 * count * sizeof(uint32_t));
}

/*
 * tdc_job_emit_start hands over exactly the triangles of tdc_next_triangle,
 * numbered in its order, whatever the thread count; it refuses unfinished
 * jobs, does nothing for collinear ones, and stops on cancel.
 */
static void
test_emit(void)
{
	size_t		sizes[] = {3, 1000, 70000, tdc_test_quick ? 150000 : 600000};
	int			threads[] = {1, 2, 3, 7};

	for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++)
	{
		size_t		n = sizes[si];
		double	   *xy = gen_uniform(n, 1000, 0, 0);

		for (size_t ti = 0; ti < sizeof(threads) / sizeof(threads[0]); ti++)
		{
			tdc_options opt;
			tdc_job    *job;
			char		err[256];
			emit_sink	sink;
			uint32_t	v[3];
			tdc_iter	it = {0};
			size_t		k = 0;
			int			same = 1;

			tdc_options_init(&opt);
			opt.threads = threads[ti];
			CHECK(tdc_triangulate(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK,
				  "emit: triangulate %zu: %s", n, err);
			if (job == NULL)
				continue;
			memset(&sink, 0, sizeof(sink));
			sink.ntri = tdc_num_triangles(job);
			sink.tri = malloc((3 * sink.ntri + 1) * sizeof(uint32_t));
			memset(sink.tri, 0xff, 3 * sink.ntri * sizeof(uint32_t));
			CHECK(tdc_job_emit_start(job, emit_collect, &sink, err, sizeof(err)) == TDC_OK,
				  "emit: start: %s", err);
			CHECK(tdc_job_wait(job, -1) == TDC_OK, "emit: %zu points, %d threads: %s",
				  n, threads[ti], tdc_job_error(job));
			CHECK(!atomic_load(&sink.bad), "emit: a range past the triangle count");
			while (tdc_next_triangle(job, &it, v))
			{
				if (k >= sink.ntri || memcmp(sink.tri + 3 * k, v, sizeof(v)) != 0)
					same = 0;
				k++;
			}
			CHECK(same && k == sink.ntri,
				  "emit: %zu points, %d threads: triangles differ from tdc_next_triangle", n, threads[ti]);
			/* a second round gives the same again */
			CHECK(tdc_job_emit_start(job, emit_collect, &sink, err, sizeof(err)) == TDC_OK &&
				  tdc_job_wait(job, -1) == TDC_OK, "emit: second round");
			free(sink.tri);
			tdc_job_free(job);
		}
		free(xy);
	}

	/* collinear: no triangles, no calls */
	{
		double		line[] = {0, 0, 1, 1, 2, 2, 3, 3};
		tdc_job    *job;
		char		err[256];
		emit_sink	sink;

		memset(&sink, 0, sizeof(sink));
		CHECK(tdc_triangulate(line, 4, NULL, &job, err, sizeof(err)) == TDC_OK, "emit: collinear");
		CHECK(tdc_job_emit_start(job, emit_collect, &sink, err, sizeof(err)) == TDC_OK &&
			  tdc_job_wait(job, -1) == TDC_OK && atomic_load(&sink.calls) == 0,
			  "emit: collinear input emits nothing");
		tdc_job_free(job);
	}

	/* refused while running; cancelled while emitting */
	{
		size_t		n = tdc_test_quick ? 300000 : 2000000;
		double	   *xy = gen_uniform(n, 1000, 0, 0);
		tdc_options opt;
		tdc_job    *job;
		char		err[256];
		emit_sink	sink;
		double		t;
		int			rc;

		tdc_options_init(&opt);
		opt.threads = 2;
		CHECK(tdc_job_start(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK, "emit: start big");
		CHECK(tdc_job_emit_start(job, emit_collect, &sink, err, sizeof(err)) == TDC_EINVAL,
			  "emit: refused while the triangulation runs");
		CHECK(tdc_job_wait(job, -1) == TDC_OK, "emit: big job");
		memset(&sink, 0, sizeof(sink));
		sink.ntri = tdc_num_triangles(job);
		sink.tri = malloc((3 * sink.ntri + 1) * sizeof(uint32_t));
		CHECK(tdc_job_emit_start(job, emit_collect, &sink, err, sizeof(err)) == TDC_OK, "emit: start: %s", err);
		tdc_job_wait(job, 2);
		t = tdc_test_now();
		tdc_job_cancel(job);
		rc = tdc_job_wait(job, -1);
		t = tdc_test_now() - t;
		CHECK(rc == TDC_ECANCELED || rc == TDC_OK, "emit: cancelled: status %d", rc);
		/* quiet machine: about 1 ms; the limit is the load-proof one above */
		CHECK(t < CANCEL_LIMIT_MS * 1e-3, "emit: cancel answered in %.1f ms (limit %d)", t * 1e3,
			  CANCEL_LIMIT_MS);
		printf("emit: cancel during the hand-over answered in %.2f ms (status %d)\n", t * 1e3, rc);
		free(sink.tri);
		tdc_job_free(job);
		free(xy);
	}
}

/* Private resident memory of this process in kB (RssAnon). */
static long
rss_anon_kb(void)
{
	FILE	   *f = fopen("/proc/self/status", "r");
	char		line[256];
	long		kb = -1;

	if (f == NULL)
		return -1;
	while (fgets(line, sizeof(line), f))
		if (sscanf(line, "RssAnon: %ld", &kb) == 1)
			break;
	fclose(f);
	return kb;
}

/*
 * tdc_job_free_background: whatever moment a job is dropped at, the caller
 * gets back at once and the memory still goes back to the system.  A job
 * that was never unmapped would leave ~100 MB per run resident here.
 */
static void
test_free_background(void)
{
	size_t		n = tdc_test_quick ? 200000 : 1000000;
	double	   *xy = gen_uniform(n, 1000, 0, 0);
	tdc_options opt;
	long		base,
				after = -1;
	double		bg_worst = 0,
				sync_total = 0,	/* tdc_job_free of finished jobs */
				bg_total = 0,	/* tdc_job_free_background of as many */
				sync_min = 1e9,
				bg_min = 1e9;	/* the quickest of each: what load cannot inflate */
	int			runs = tdc_test_quick ? 6 : 20;

	tdc_options_init(&opt);
	opt.threads = 2;
	base = rss_anon_kb();
	for (int r = 0; r < runs; r++)
	{
		tdc_job    *job;
		char		err[256];
		double		t;
		int			done;

		CHECK(tdc_job_start(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK, "background free: start: %s", err);
		if (job == NULL)
			continue;
		/* every other run is dropped while it works, the rest once done */
		done = r % 2;
		tdc_job_wait(job, done ? -1 : 10 * (r % 7));
		t = tdc_test_now();
		if (done && r % 4 == 1)
		{
			tdc_job_free(job);
			t = tdc_test_now() - t;
			sync_total += t;
			sync_min = t < sync_min ? t : sync_min;
			continue;
		}
		tdc_job_free_background(job);
		t = tdc_test_now() - t;
		if (done)
		{
			bg_total += t;
			bg_min = t < bg_min ? t : bg_min;
		}
		bg_worst = t > bg_worst ? t : bg_worst;
	}
	/* the reapers run on: give them a moment to unmap */
	for (int i = 0; i < 100; i++)
	{
		after = rss_anon_kb();
		if (after - base < 64 * 1024)
			break;
		usleep(20000);
	}
	printf("background free: worst caller wait %.2f ms; finished jobs: %.2f ms in place vs %.2f ms in the background (%d each); RssAnon %ld kB before, %ld kB after %d jobs\n",
		   bg_worst * 1e3, sync_total * 1e3, bg_total * 1e3, runs / 4, base, after, runs);
	if (!tdc_test_quick)
	{
		CHECK(base > 0 && after - base < 64 * 1024,
			  "background free: RssAnon grew from %ld to %ld kB over %d jobs", base, after, runs);
		/*
		 * The quickest drop against the quickest free in place: a reaper
		 * that does not reap in the background makes them equal, while load
		 * inflates single runs of either, not both minimums.
		 */
		CHECK(bg_min < sync_min / 4,
			  "background free: the quickest drop of a finished job took %.2f ms, not under a quarter of the quickest free in place (%.2f ms)",
			  bg_min * 1e3, sync_min * 1e3);
	}
	free(xy);
}

static pthread_t main_thread;
static volatile sig_atomic_t signals_seen;
static volatile sig_atomic_t signals_on_worker;

static void
on_usr1(int sig)
{
	signals_seen++;
	if (!pthread_equal(pthread_self(), main_thread))
		signals_on_worker++;
}

/*
 * A host process (a PostgreSQL backend) relies on its signals reaching its
 * own thread: process-directed signals sent while a job runs must never be
 * taken by a worker.
 */
static void
test_signals_stay_on_caller(void)
{
	size_t		n = tdc_test_quick ? 200000 : 1000000;
	double	   *xy = gen_uniform(n, 1000, 0, 0);
	struct sigaction sa,
				old;
	tdc_options opt;
	tdc_job    *job;
	char		err[256];
	int			sent = 0;

	main_thread = pthread_self();
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = on_usr1;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGUSR1, &sa, &old);
	tdc_options_init(&opt);
	opt.threads = 4;
	CHECK(tdc_job_start(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK, "signals: start: %s", err);
	if (job)
	{
		sigset_t	usr1;

		/*
		 * Linux hands a process-directed signal to the main thread when it
		 * can take it, so block it here: now only a worker that failed to
		 * block it could, and otherwise it stays pending for us.
		 */
		sigemptyset(&usr1);
		sigaddset(&usr1, SIGUSR1);
		pthread_sigmask(SIG_BLOCK, &usr1, NULL);
		while (tdc_job_wait(job, 1) == TDC_RUNNING && sent < 200)
		{
			kill(getpid(), SIGUSR1);
			sent++;
		}
		CHECK(tdc_job_wait(job, -1) == TDC_OK, "signals: job finishes despite signals");
		tdc_job_free(job);
		CHECK(signals_on_worker == 0 && signals_seen == 0,
			  "signals: %d taken by worker threads while the caller blocked them",
			  (int) signals_on_worker);
		pthread_sigmask(SIG_UNBLOCK, &usr1, NULL);
	}
	sigaction(SIGUSR1, &old, NULL);
	CHECK(sent > 0 && signals_seen > 0 && signals_on_worker == 0,
		  "signals: %d sent, %d reached the caller once unblocked", sent, (int) signals_seen);
	free(xy);
}

/* Virtual memory of this process, in bytes (first field of /proc/self/statm). */
static size_t
vm_size(void)
{
	FILE	   *f = fopen("/proc/self/statm", "r");
	unsigned long pages = 0;

	if (f)
	{
		if (fscanf(f, "%lu", &pages) != 1)
			pages = 0;
		fclose(f);
	}
	return (size_t) pages * (size_t) sysconf(_SC_PAGESIZE);
}

/*
 * Every allocation the engine makes must fail into TDC_ENOMEM (or, for a
 * thread's stack, TDC_ETHREAD), never a crash.  Each run is a child process
 * with its address space capped a little above what it already uses, so
 * that one allocation or another fails; the caps step up until the run
 * succeeds.  Skipped under sanitizers (--quick), whose shadow memory needs
 * an unlimited address space.
 */
static void
test_out_of_memory(void)
{
	static const size_t extra_mb[] = {1, 4, 16, 40, 80, 120, 160, 220, 400, 4000};
	size_t		n = 1000000,
				ref_tri;
	double	   *xy;
	int			enomem = 0,
				ok = 0;
	tdc_options ref_opt;
	tdc_job    *ref;
	char		ref_err[256];

	if (tdc_test_quick)
		return;
	xy = gen_uniform(n, 1000, 0, 0);
	tdc_options_init(&ref_opt);
	CHECK(tdc_triangulate(xy, n, &ref_opt, &ref, ref_err, sizeof(ref_err)) == TDC_OK,
		  "out of memory: reference run: %s", ref_err);
	ref_tri = tdc_num_triangles(ref);
	tdc_job_free(ref);
	for (size_t k = 0; k < sizeof(extra_mb) / sizeof(extra_mb[0]); k++)
	{
		pid_t		pid;
		int			status;

		fflush(NULL);
		pid = fork();
		if (pid == 0)
		{
			struct rlimit rl;
			tdc_options opt;
			tdc_job    *job;
			char		err[256];
			int			rc;

			rl.rlim_cur = rl.rlim_max = vm_size() + (extra_mb[k] << 20);
			setrlimit(RLIMIT_AS, &rl);
			tdc_options_init(&opt);
			opt.threads = 2;
			rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
			if (rc == TDC_OK && tdc_num_triangles(job) != ref_tri)
				rc = 99;		/* an incomplete result is as bad as a crash */
			tdc_job_free(job);
			_exit(rc == TDC_OK ? 0 : rc == TDC_ENOMEM ? 1 : rc == TDC_ETHREAD ? 2 : 3);
		}
		CHECK(pid > 0, "out of memory: fork failed");
		if (pid <= 0)
			break;
		waitpid(pid, &status, 0);
		CHECK(WIFEXITED(status) && WEXITSTATUS(status) <= 2,
			  "out of memory: cap +%zu MB: %s %d", extra_mb[k],
			  WIFEXITED(status) ? "exit" : "killed by signal",
			  WIFEXITED(status) ? WEXITSTATUS(status) : WTERMSIG(status));
		if (WIFEXITED(status) && WEXITSTATUS(status) == 1)
			enomem++;
		if (WIFEXITED(status) && WEXITSTATUS(status) == 0)
			ok++;
	}
	CHECK(enomem >= 3, "out of memory: only %d capped runs failed with TDC_ENOMEM", enomem);
	CHECK(ok >= 1, "out of memory: no capped run succeeded");
	printf("out of memory: %d capped runs ended in TDC_ENOMEM, %d succeeded, none crashed\n",
		   enomem, ok);
	free(xy);
}

void
test_engine(void)
{
	test_small_and_degenerate();
	test_inline_boundary();
	test_map_and_tolerance();
	test_errors();
	test_random_sets();
	test_cancel_and_concurrency();
	test_emit();
	test_free_background();
	test_signals_stay_on_caller();
	test_out_of_memory();
}
