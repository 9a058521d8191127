/*
 * test_cache.c
 *		The host's cache of big arrays (mem.c): what a job leaves in it, what
 *		the next job takes back, and that nothing of a run's old contents
 *		reaches the next one.
 *
 * A kept mapping holds the last run's mesh, orders and cells; an array that
 * takes it back must read as zeroes like a fresh mapping, or the engine's
 * results would depend on what ran before.  So every run here with a cache
 * is compared, triangle by triangle and cell by cell, with the same run
 * without one, after runs on other inputs have filled the cache.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "splitmix.h"
#include "engine/engine_int.h"

/* FNV-1a over the coordinates of every triangle, in the order they come. */
static uint64_t
triangles_hash(const tdc_job *job, size_t *ntri)
{
	uint64_t	h = 1469598103934665603ULL;
	tdc_iter	it = {0};
	uint32_t	v[3];

	*ntri = 0;
	while (tdc_next_triangle(job, &it, v))
	{
		for (int k = 0; k < 3; k++)
		{
			const unsigned char *b = (const unsigned char *) tdc_site_xy(job, v[k]);

			for (size_t i = 0; i < 2 * sizeof(double); i++)
				h = (h ^ b[i]) * 1099511628211ULL;
		}
		(*ntri)++;
	}
	return h;
}

/* The same over every Voronoi cell's vertices, site by site. */
static uint64_t
cells_hash(const tdc_job *job, const tdc_voronoi *v)
{
	uint64_t	h = 1469598103934665603ULL;

	for (uint32_t s = 0; s < tdc_site_id_limit(job); s++)
	{
		const double *xy;
		size_t		m = tdc_voronoi_cell(v, s, &xy);
		const unsigned char *b = (const unsigned char *) xy;

		h = (h ^ m) * 1099511628211ULL;
		for (size_t i = 0; i < 2 * m * sizeof(double); i++)
			h = (h ^ b[i]) * 1099511628211ULL;
	}
	return h;
}

static double *
points(size_t n, uint64_t seed, bool lattice)
{
	double	   *xy = malloc(2 * n * sizeof(double));
	uint64_t	rng = seed;

	for (size_t i = 0; i < n && xy != NULL; i++)
	{
		if (lattice)
		{
			/* cocircular everywhere, and duplicates: every tie-break runs */
			xy[2 * i] = (double) tdc_splitmix_below(&rng, 300);
			xy[2 * i + 1] = (double) tdc_splitmix_below(&rng, 300);
		}
		else
		{
			xy[2 * i] = tdc_splitmix_unit(&rng);
			xy[2 * i + 1] = tdc_splitmix_unit(&rng);
		}
	}
	return xy;
}

typedef struct run_result
{
	int			rc;
	size_t		ntri;
	uint64_t	tri_hash;
	uint64_t	cell_hash;
} run_result;

/* Triangulate (with tolerance, to use the tolerance.c arrays too) and build the cells. */
static run_result
run(const double *xy, size_t n, double tolerance, tdc_cache *cache)
{
	tdc_options opt;
	tdc_job    *job = NULL;
	tdc_voronoi *v = NULL;
	double		env[4] = {-1, -1, 400, 400};
	char		err[256];
	run_result	r = {0};

	tdc_options_init(&opt);
	opt.threads = 2;
	opt.tolerance = tolerance;
	opt.cache = cache;
	r.rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	if (r.rc == TDC_OK)
	{
		r.tri_hash = triangles_hash(job, &r.ntri);
		/* the input map is built on demand, from the cache too */
		(void) tdc_input_site(job, 0);
		r.rc = tdc_voronoi_build(job, env, 2, &v, err, sizeof(err));
		if (r.rc == TDC_OK)
			r.cell_hash = cells_hash(job, v);
		tdc_voronoi_free(v);
	}
	tdc_job_free(job);
	return r;
}

static bool
same(run_result a, run_result b)
{
	return a.rc == TDC_OK && b.rc == TDC_OK && a.ntri == b.ntri &&
		a.tri_hash == b.tri_hash && a.cell_hash == b.cell_hash;
}

/* Arrays taken back from the cache read as zeroes, and are cut to size. */
static void
test_cache_contract(void)
{
	tdc_cache  *c = tdc_cache_create((size_t) 64 << 20);
	size_t		big = (size_t) 8 << 20;
	unsigned char *p,
			   *q;
	bool		zero = true;

	CHECK(c != NULL, "tdc_cache_create failed");
	if (c == NULL)
		return;
	p = tdc_big_alloc(c, big);
	CHECK(p != NULL, "tdc_big_alloc from an empty cache failed");
	if (p == NULL)
		return;
	memset(p, 0xab, big);
	tdc_big_free(c, p);
	CHECK(tdc_cache_kept(c) >= big, "a freed 8 MB array is kept (%zu bytes kept)",
		  tdc_cache_kept(c));

	/* a little smaller: the same mapping, cut down, every byte cleared */
	q = tdc_big_alloc(c, big - (1 << 20));
	CHECK(q == p, "the kept mapping is taken back for a slightly smaller array");
	CHECK(tdc_cache_kept(c) == 0, "taken back, it is no longer kept");
	for (size_t i = 0; q != NULL && i < big - (1 << 20); i++)
		zero &= q[i] == 0;
	CHECK(zero, "an array taken back from the cache reads as zeroes");
	tdc_big_free(c, q);
	CHECK(tdc_cache_kept(c) < big, "the mapping was cut to the smaller size");

	/* far smaller arrays do not eat a big kept mapping */
	p = tdc_big_alloc(c, big / 4);
	CHECK(p != NULL && tdc_cache_kept(c) > 0, "a quarter-size array maps afresh");
	tdc_big_free(c, p);

	/* the limit holds: what does not fit is unmapped */
	tdc_cache_set_limit(c, (size_t) 4 << 20);
	CHECK(tdc_cache_kept(c) <= ((size_t) 4 << 20), "set_limit trims to the new limit");
	p = tdc_big_alloc(c, big);
	tdc_big_free(c, p);
	CHECK(tdc_cache_kept(c) <= ((size_t) 4 << 20),
		  "an array over the limit is not kept (%zu kept)", tdc_cache_kept(c));
	CHECK(tdc_cache_trim(c, 0) && tdc_cache_kept(c) == 0, "trim(0) empties the cache");
	tdc_cache_destroy(c);

	/*
	 * A fresh array big enough for the huge-page probe (which maps its first
	 * 2 MB page in, and may turn the rest back to 4 kB pages) still reads
	 * as zeroes and takes writes everywhere, up to its last byte.
	 */
	p = tdc_big_alloc(NULL, (size_t) 24 << 20);
	CHECK(p != NULL, "a 24 MB array");
	if (p != NULL)
	{
		size_t		n = (size_t) 24 << 20;

		zero = true;
		for (size_t i = 0; i < n; i += 4096)
			zero &= p[i] == 0;
		zero &= p[n - 1] == 0;
		memset(p, 0x5a, n);
		CHECK(zero && p[0] == 0x5a && p[n - 1] == 0x5a,
			  "an array after the huge-page probe reads as zeroes and takes writes");
		tdc_big_free(NULL, p);
	}
}

/*
 * Runs with a cache give what runs without one give, whatever ran before
 * them in the same cache: the same input again, a different size, a
 * lattice with duplicates and a tolerance.
 */
static void
test_cache_runs(void)
{
	size_t		n1 = tdc_test_quick ? 20000 : 200000,
				n2 = n1 - n1 / 10;
	double	   *u1 = points(n1, 11, false),
			   *u2 = points(n2, 12, false),
			   *l1 = points(n1, 13, true);
	tdc_cache  *c = tdc_cache_create((size_t) 512 << 20);
	run_result	ref_u1,
				ref_u2,
				ref_l1,
				r;

	CHECK(u1 && u2 && l1 && c, "out of memory setting up");
	if (!(u1 && u2 && l1 && c))
		goto done;
	ref_u1 = run(u1, n1, 0, NULL);
	ref_u2 = run(u2, n2, 0, NULL);
	ref_l1 = run(l1, n1, 0.5, NULL);
	CHECK(ref_u1.rc == TDC_OK && ref_u2.rc == TDC_OK && ref_l1.rc == TDC_OK,
		  "the runs without a cache succeed");

	r = run(u1, n1, 0, c);
	CHECK(same(r, ref_u1), "first run with an empty cache: the same triangles and cells");
	CHECK(tdc_cache_kept(c) > 0, "the run left arrays in the cache");
	r = run(u1, n1, 0, c);
	CHECK(same(r, ref_u1), "the same input again from kept arrays: the same result");
	r = run(l1, n1, 0.5, c);
	CHECK(same(r, ref_l1), "a lattice with duplicates and a tolerance after it: the same");
	r = run(u2, n2, 0, c);
	CHECK(same(r, ref_u2), "a smaller input in arrays cut from kept ones: the same");
	r = run(u1, n1, 0, c);
	CHECK(same(r, ref_u1), "the first input once more: the same");
	CHECK(tdc_cache_kept(c) <= ((size_t) 512 << 20), "the cache stays within its limit");

	/* a cache too small to keep anything changes nothing either */
	tdc_cache_set_limit(c, 4096);
	r = run(u1, n1, 0, c);
	CHECK(same(r, ref_u1) && tdc_cache_kept(c) == 0,
		  "a cache with no room keeps nothing and changes nothing");
done:
	tdc_cache_destroy(c);
	free(u1);
	free(u2);
	free(l1);
}

void
test_cache(void)
{
	test_cache_contract();
	test_cache_runs();
}
