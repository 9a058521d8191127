/*
 * triangulate.c
 *		The plan of a job and its first phase: the three steps of Wu et al.
 *		2014 on the pool.
 *
 * A job's plan (threads, grid, levels) is a pure function of n and the
 * options, so that tdc_estimate_memory() sizes before the start exactly
 * what the run will allocate; both live here, next to each other, so that a
 * change to one is seen beside the other.
 *
 * tdc_run_phase() is what the driver thread (job.c) runs first.  It creates
 * the pool and runs the phases, each a parallel loop on the pool:
 *
 *	check		validate the input, bounding box (reported as sort time)
 *	tolerance	optional sequential filter (tolerance.c, also sort time)
 *	step 1		grid counts, the tree of 2^d subsets level by level, and one
 *				counting sort of the points into tree order (subdivide.c)
 *	step 2		Guibas-Stolfi in each subset, down to its grid cells,
 *				removing duplicates on the way (leaf.c)
 *	step 3		merge up the tree, level by level (merge.c)
 *
 * Every task polls the cancel flag and the phase stops between steps, so a
 * cancel is answered within milliseconds.  Errors inside tasks are recorded
 * once (tdc_job_fail) and turn into the job's status; nothing exits or
 * aborts.
 *
 * Memory, beyond the caller's coordinates, per input point: 16 bytes of
 * coordinates, 4 of input index, 4 of position->site and 72 of mesh (six
 * 12-byte half-edges), 96 in all, plus the grid (about 3 bytes per point)
 * and a bit per half-edge marking the outer face.
 * The input->site map costs 4 more, and only if asked for.  Handing the
 * triangles over in parallel (emit.c) lists them first: 12 bytes per
 * triangle, about 24 per point, while the rest is still alive.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "job_int.h"

#define LEAF_TARGET		65536	/* largest subset the auto depth allows */
#define CELL_TARGET		4.0		/* points per grid cell the auto grid aims at */
#define MAX_AUTO_GRID	8192
#define MIN_PARALLEL	TDC_INLINE_MAX	/* below this one subset is fastest */
#define CHECK_CHUNK		65536
#define NO_GRID_MAX		128	/* below this the auto grid is one cell */

static double
now_sec(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Phase times cost a clock read each: only when asked for (options.times). */
static double
job_clock(const tdc_job *job)
{
	return job->opt.times ? now_sec() : 0;
}

static int
online_cpus(void)
{
	long		c = sysconf(_SC_NPROCESSORS_ONLN);

	return c < 1 ? 1 : (c > 256 ? 256 : (int) c);
}

/*
 * The plan of a job (threads, grid, levels) is a function of n and the
 * options alone, so that tdc_estimate_memory() can size exactly what a job
 * will allocate before it starts.  The driver plans with the number of
 * points that reach the subdivision (fewer after a tolerance pass), and each
 * figure is non-decreasing in n, so the estimate for n bounds it.
 */

/*
 * s of the s x s grid.  A grid with more cells than about two per point
 * separates nothing more and only costs memory (a user's grid_size of 65536
 * would be 16 GB of counters), so a requested size is capped by n.
 */
static int
plan_grid(size_t n, const tdc_options *o)
{
	int			s;

	if (o->grid_size > 0)
	{
		int			cap = (int) ceil(sqrt(2.0 * (double) n));

		s = o->grid_size < cap ? o->grid_size : cap;
	}
	else if (n < NO_GRID_MAX)
		s = 1;					/* a few points: sorting them beats binning */
	else
	{
		s = (int) ceil(sqrt((double) n / CELL_TARGET));
		s = s > MAX_AUTO_GRID ? MAX_AUTO_GRID : s;
	}
	return s < 1 ? 1 : s;
}

static int
plan_levels(size_t n, const tdc_options *o, int threads)
{
	int			d = 0;

	if (o->levels > 0)
		d = o->levels;
	else if (o->levels == 0 && n >= MIN_PARALLEL)
	{
		/* enough subsets to balance the threads, none larger than the target */
		size_t		leaves = (size_t) threads * 8;

		while (leaves * LEAF_TARGET < n)
			leaves *= 2;
		while (((size_t) 1 << d) < leaves)
			d++;
	}
	if (d > TDC_MAX_LEVELS)
		d = TDC_MAX_LEVELS;
	/* no more levels than halvings of the input */
	while (d > 0 && ((size_t) 1 << d) > n)
		d--;
	return d;
}

/* --- copy and validation --- */

typedef struct copy_arg
{
	tdc_job    *job;
	double	   *bounds;			/* 4 per chunk: minx, miny, maxx, maxy */
	size_t	   *bad;			/* first bad point per chunk, or SIZE_MAX */
} copy_arg;

static inline bool
coord_ok(double v)
{
	double		a = fabs(v);

	return v == 0 || (a >= TDC_COORD_MIN && a <= TDC_COORD_MAX);
}

/* Validate a chunk of the input and take its bounding box. */
static void
check_task(void *arg, size_t c, int worker)
{
	copy_arg   *ca = arg;
	tdc_job    *job = ca->job;
	size_t		lo = c * CHECK_CHUNK,
				hi = lo + CHECK_CHUNK < job->n ? lo + CHECK_CHUNK : job->n;
	double		mnx = INFINITY,
				mny = INFINITY,
				mxx = -INFINITY,
				mxy = -INFINITY;

	ca->bad[c] = SIZE_MAX;
	for (size_t i = lo; i < hi; i++)
	{
		double		x = job->input[2 * i],
					y = job->input[2 * i + 1];

		if (!coord_ok(x) || !coord_ok(y))
		{
			ca->bad[c] = i;
			return;
		}
		mnx = x < mnx ? x : mnx;
		mxx = x > mxx ? x : mxx;
		mny = y < mny ? y : mny;
		mxy = y > mxy ? y : mxy;
	}
	ca->bounds[4 * c] = mnx;
	ca->bounds[4 * c + 1] = mny;
	ca->bounds[4 * c + 2] = mxx;
	ca->bounds[4 * c + 3] = mxy;
}

static int
check_input(tdc_job *job)
{
	size_t		nchunks = (job->n + CHECK_CHUNK - 1) / CHECK_CHUNK;
	copy_arg	ca;
	double		bounds1[4];		/* one chunk: no allocation */
	size_t		bad1;

	ca.job = job;
	if (nchunks == 1)
	{
		ca.bounds = bounds1;
		ca.bad = &bad1;
	}
	else
	{
		ca.bounds = tdc_job_alloc(job, nchunks * 4 * sizeof(double));
		ca.bad = tdc_job_alloc(job, nchunks * sizeof(size_t));
	}
	if (!ca.bounds || !ca.bad)
	{
		tdc_job_release(job, ca.bounds);
		tdc_job_release(job, ca.bad);
		tdc_job_fail(job, TDC_ENOMEM, "out of memory");
		return TDC_ENOMEM;
	}
	tdc_pool_for(job->pool, nchunks, check_task, &ca);
	job->bmin[0] = job->bmin[1] = INFINITY;
	job->bmax[0] = job->bmax[1] = -INFINITY;
	for (size_t c = 0; c < nchunks; c++)
	{
		if (ca.bad[c] != SIZE_MAX)
		{
			size_t		i = ca.bad[c];
			double		x = job->input[2 * i],
						y = job->input[2 * i + 1];

			if (!isfinite(x) || !isfinite(y))
				tdc_job_fail(job, TDC_EINVAL,
							 "point %zu has a non-finite coordinate (%g %g): NaN and Infinity are not allowed",
							 i, x, y);
			else
				tdc_job_fail(job, TDC_EINVAL,
							 "point %zu (%.17g %.17g) has a coordinate outside the supported magnitude range [%g, %g] (zero is allowed)",
							 i, x, y, TDC_COORD_MIN, TDC_COORD_MAX);
			break;
		}
		job->bmin[0] = fmin(job->bmin[0], ca.bounds[4 * c]);
		job->bmin[1] = fmin(job->bmin[1], ca.bounds[4 * c + 1]);
		job->bmax[0] = fmax(job->bmax[0], ca.bounds[4 * c + 2]);
		job->bmax[1] = fmax(job->bmax[1], ca.bounds[4 * c + 3]);
	}
	if (nchunks > 1)
	{
		tdc_job_release(job, ca.bounds);
		tdc_job_release(job, ca.bad);
	}
	return atomic_load(&job->failed);
}

/* --- steps 2 and 3 --- */

static void
leaf_task(void *arg, size_t i, int worker)
{
	tdc_job    *job = arg;
	size_t		k = ((size_t) 1 << job->d) + i;

	if (atomic_load_explicit(&job->cancel, memory_order_relaxed))
		return;
	tdc_triangulate_leaf(job, k, &job->subs[k]);
}

typedef struct merge_arg
{
	tdc_job    *job;
	int			level;
} merge_arg;

static void
merge_task(void *arg, size_t i, int worker)
{
	merge_arg  *ma = arg;
	tdc_job    *job = ma->job;
	size_t		k = ((size_t) 1 << ma->level) + i;
	tdc_mesh	m = {job->xy, job->he, &job->cancel};
	tdc_sub    *L = &job->subs[2 * k],
			   *R = &job->subs[2 * k + 1],
			   *out = &job->subs[k];

	if (atomic_load_explicit(&job->cancel, memory_order_relaxed))
		return;
	out->fl = L->fl;
	tdc_freelist_concat(&m, &out->fl, &R->fl);
	tdc_merge(&m, &out->fl, L, R, job->node_axis[k], out);
}

/*
 * Walk the convex hull once: it sizes the result without scanning the mesh,
 * and marks the half-edges of the outer face (the reverse of every hull
 * edge), so the triangle iterator needs no face walk to tell it apart.
 */
static int
count_result(tdc_job *job)
{
	tdc_mesh	m = {job->xy, job->he, &job->cancel};
	const tdc_sub *root = &job->subs[1];
	size_t		u = root->nsites,
				h = 0;

	job->nsites = u;
	if (u < 2)
	{
		job->ntri = job->nedges = 0;
		return TDC_OK;
	}
	for (uint32_t e = root->ext[0];;)
	{
		h++;
		e = tdc_rprev(&m, e);
		if (e == root->ext[0])
			break;
	}
	if (h == 2 * (u - 1))
	{
		/* a chain: every site collinear */
		job->ntri = 0;
		job->nedges = u - 1;
		return TDC_OK;
	}
	job->ntri = 2 * u - 2 - h;
	job->nedges = 3 * u - 3 - h;
	job->outer = tdc_job_alloc(job, ((job->nin * 6 + 63) / 64 + 1) * sizeof(uint64_t));
	if (job->outer == NULL)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory marking the convex hull");
		return TDC_ENOMEM;
	}
	for (uint32_t e = root->ext[0];;)
	{
		uint32_t	o = SYM(e);

		job->outer[o >> 6] |= (uint64_t) 1 << (o & 63);
		e = tdc_rprev(&m, e);
		if (e == root->ext[0])
			break;
	}
	return TDC_OK;
}

void
tdc_options_init(tdc_options *opt)
{
	memset(opt, 0, sizeof(*opt));
}

/* Below TDC_INLINE_MAX points a job runs on the caller's thread. */
bool
tdc_plan_inline(size_t n)
{
	return n < TDC_INLINE_MAX;
}

int
tdc_plan_threads(size_t n, const tdc_options *o)
{
	if (tdc_plan_inline(n))
		return 1;
	return o->threads > 0 ? o->threads : online_cpus();
}

/*
 * Every allocation of a job of n points, at the peak of each phase; the
 * largest is the estimate.  The phases and what is alive in each:
 *
 *	all		xy 16, idx 4, site_of 4 bytes per point; tol_to 4 with a
 *			tolerance; the tree (2^(d+1) nodes, d <= log2 n); the prefix sums
 *			((s+1)^2 counters) from step 1 on
 *	tolerance	its sort records and hash table (tolerance.c)
 *	step 1	the survivors' copy (20 per point, with a tolerance), the cell of
 *			each point (4), one histogram of s^2 counters per slice (at most
 *			TDC_GRID_SLICES, whatever the thread count) and the cell starts
 *	steps 2-3	the mesh (72 per point) and the outer-face bitmap
 *	results	the input map (4 per point, built on request) and emit.c's
 *			triangle list (12 per triangle plus a chunk per range)
 *
 * Threads add their stacks' touched pages and malloc arenas; a generous
 * 256 KB each is counted.
 */
size_t
tdc_estimate_memory(size_t n, const tdc_options *opt)
{
	tdc_options o;
	int			threads,
				s,
				d;
	size_t		cells,
				prefix,
				tree,
				common,
				tol,
				step1,
				mesh,
				results,
				peak;

	if (opt)
		o = *opt;
	else
		tdc_options_init(&o);
	threads = tdc_plan_threads(n, &o);
	s = plan_grid(n, &o);
	d = plan_levels(n, &o, threads);
	cells = (size_t) s * s;
	prefix = ((size_t) s + 1) * ((size_t) s + 1) * sizeof(uint32_t);
	tree = ((size_t) 2 << d) * (sizeof(tdc_rect) + 1 + 2 * sizeof(uint32_t) + sizeof(tdc_sub));
	common = n * (16 + 4 + 4) + tree + (o.tolerance > 0 ? n * 4 : 0);

	tol = o.tolerance > 0 ? tdc_tolerance_memory(n) : 0;
	step1 = (o.tolerance > 0 ? n * 20 : 0) + n * 4 +
		((size_t) (threads < TDC_GRID_SLICES ? threads : TDC_GRID_SLICES) + 1) * cells * sizeof(uint32_t) +
		prefix;
	mesh = prefix + n * 6 * sizeof(tdc_he) + (n * 6 / 64 + 2) * sizeof(uint64_t);
	results = n * 4 + tdc_emit_memory(n, threads);

	peak = tol > step1 ? tol : step1;
	peak = peak > mesh + results ? peak : mesh + results;
	return common + peak + (size_t) threads * (256 << 10) + ((size_t) 1 << 20);
}

/*
 * The first phase of a job: validate, filter, subdivide, triangulate the
 * leaves, merge.  Returns a status; the first task error is in job->failed.
 */
int
tdc_run_phase(tdc_job *job)
{
	double		t0 = job_clock(job),
				t;
	size_t		nnodes;
	int			rc;

	rc = tdc_pool_create(&job->pool, job->threads);
	if (rc != 0)
	{
		/* on TDC_ETHREAD the pool left pthread_create's error in errno */
		tdc_job_fail(job, rc, rc == TDC_ETHREAD ? "could not create worker threads: %s" : "out of memory%s",
					 rc == TDC_ETHREAD ? strerror(errno) : "");
		return rc;
	}

	/* validate; tolerance */
	t = job_clock(job);
	job->xy = tdc_job_alloc(job, job->n * 2 * sizeof(double) + 16);
	job->idx = tdc_job_alloc(job, job->n * sizeof(uint32_t) + 4);
	job->site_of = tdc_job_alloc(job, job->n * sizeof(uint32_t) + 4);
	if (!job->xy || !job->idx || !job->site_of)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory for %zu points", job->n);
		return TDC_ENOMEM;
	}
	job->nin = job->n;
	if (job->n > 0 && check_input(job) != 0)
		return atomic_load(&job->failed);
	if (job->opt.tolerance > 0 && job->n > 0)
	{
		job->tol_to = tdc_job_alloc(job, job->n * sizeof(uint32_t));
		if (job->tol_to == NULL)
		{
			tdc_job_fail(job, TDC_ENOMEM, "out of memory for the tolerance pass");
			return TDC_ENOMEM;
		}
		memcpy(job->xy, job->input, job->n * 2 * sizeof(double));
		for (size_t i = 0; i < job->n; i++)
			job->idx[i] = (uint32_t) i;
		if (tdc_tolerance_filter(job) != 0)
		{
			tdc_job_fail(job, TDC_ENOMEM, "out of memory for the tolerance pass");
			return TDC_ENOMEM;
		}
	}
	job->times.sort = job_clock(job) - t;
	if (atomic_load(&job->cancel))
		return TDC_ECANCELED;

	/* step 1 */
	t = job_clock(job);
	job->d = plan_levels(job->nin, &job->opt, job->threads);
	job->s = plan_grid(job->nin, &job->opt);
	for (int a = 0; a < 2; a++)
	{
		double		extent = job->bmax[a] - job->bmin[a];

		job->gscale[a] = extent > 0 ? job->s / extent : 0;
		if (!isfinite(job->gscale[a]))
			job->gscale[a] = 0;	/* extent below the smallest normal: one cell */
	}
	nnodes = (size_t) 2 << job->d;
	job->node_rect = tdc_job_alloc(job, nnodes * sizeof(tdc_rect));
	job->node_axis = tdc_job_alloc(job, nnodes);
	job->node_lo = tdc_job_alloc(job, nnodes * sizeof(uint32_t));
	job->node_hi = tdc_job_alloc(job, nnodes * sizeof(uint32_t));
	job->subs = tdc_job_alloc(job, nnodes * sizeof(tdc_sub));
	if (!job->node_rect || !job->node_axis || !job->node_lo || !job->node_hi || !job->subs)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory for the subdivision tree");
		return TDC_ENOMEM;
	}
	tdc_subdivide(job);
	job->times.subdivide = job_clock(job) - t;
	if (atomic_load(&job->cancel))
		return TDC_ECANCELED;

	/* every subset writes each of its slots (tdc_triangulate_leaf) */
	job->he = tdc_job_alloc_uninit(job, job->nin * 6 * sizeof(tdc_he) + sizeof(tdc_he));
	if (job->he == NULL)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory for the mesh of %zu points (%zu bytes)",
					 job->nin, job->nin * 6 * sizeof(tdc_he));
		return TDC_ENOMEM;
	}

	/* step 2, removing duplicates on the way */
	t = job_clock(job);
	tdc_pool_for(job->pool, (size_t) 1 << job->d, leaf_task, job);
	job->times.leaves = job_clock(job) - t;
	if (atomic_load(&job->cancel))
		return TDC_ECANCELED;

	/* step 3 */
	t = job_clock(job);
	for (int level = job->d - 1; level >= 0; level--)
	{
		merge_arg	ma = {job, level};

		tdc_pool_for(job->pool, (size_t) 1 << level, merge_task, &ma);
		if (atomic_load(&job->cancel))
			return TDC_ECANCELED;
	}
	job->times.merge = job_clock(job) - t;

	if (count_result(job) != TDC_OK)
		return TDC_ENOMEM;
	job->times.total = job_clock(job) - t0;
	return TDC_OK;
}
