/*
 * driver.c
 *		The job: options, memory, threads, the three phases of Wu et al.
 *		2014, and access to the result.
 *
 * tdc_job_start() checks the options and the memory bound, then starts a
 * driver thread with every signal blocked, and returns.  The driver creates
 * the pool and runs the phases, each a parallel loop on the pool:
 *
 *	check		validate the input, bounding box (reported as sort time)
 *	tolerance	optional sequential filter (sites.c, also sort time)
 *	step 1		grid counts, the tree of 2^d subsets level by level, and one
 *				counting sort of the points into tree order (subdivide.c)
 *	step 2		Guibas-Stolfi in each subset, down to its grid cells,
 *				removing duplicates on the way (leaf.c)
 *	step 3		merge up the tree, level by level (merge.c)
 *
 * The caller's thread only waits (tdc_job_wait) and may cancel: every task
 * polls the flag and the driver stops between phases, so a cancel is
 * answered within milliseconds.  Errors inside tasks are recorded once and
 * turn into the job's status; nothing exits or aborts.
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
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "job.h"

#define LEAF_TARGET		65536	/* largest subset the auto depth allows */
#define CELL_TARGET		4.0		/* points per grid cell the auto grid aims at */
#define MAX_AUTO_GRID	8192
#define MIN_PARALLEL	TDC_INLINE_MAX	/* below this one subset is fastest */
#define CHECK_CHUNK		65536
#define EMIT_INLINE_BATCH	256	/* triangles per callback of a small job */
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

void
tdc_job_fail(tdc_job *job, int code, const char *fmt,...)
{
	int			expected = 0;

	if (atomic_compare_exchange_strong(&job->failed, &expected, code))
	{
		va_list		ap;

		va_start(ap, fmt);
		vsnprintf(job->task_err, sizeof(job->task_err), fmt, ap);
		va_end(ap);
	}
	atomic_store(&job->cancel, 1);
}

void
tdc_options_init(tdc_options *opt)
{
	memset(opt, 0, sizeof(*opt));
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

/* Below TDC_INLINE_MAX points a job runs on the caller's thread. */
static bool
plan_inline(size_t n)
{
	return n < TDC_INLINE_MAX;
}

static int
plan_threads(size_t n, const tdc_options *o)
{
	if (plan_inline(n))
		return 1;
	return o->threads > 0 ? o->threads : online_cpus();
}

/*
 * s of the s x s grid.  A grid with more cells than about two per point
 * separates nothing more and only costs memory (a user's grid_size of 65536
 * would be 16 GB of counters), so a requested size is capped by n.
 */
static int
plan_grid(size_t n, const tdc_options *o)
{
	int			cap = (int) ceil(sqrt(2.0 * (double) n));
	int			s;

	if (o->grid_size > 0)
		s = o->grid_size < cap ? o->grid_size : cap;
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

/*
 * Every allocation of a job of n points, at the peak of each phase; the
 * largest is the estimate.  The phases and what is alive in each:
 *
 *	all		xy 16, idx 4, site_of 4 bytes per point; tol_to 4 with a
 *			tolerance; the tree (2^(d+1) nodes, d <= log2 n); the prefix sums
 *			((s+1)^2 counters) from step 1 on
 *	tolerance	its sort records and hash table (sites.c)
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
	threads = plan_threads(n, &o);
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

	ca.job = job;
	ca.bounds = malloc(nchunks * 4 * sizeof(double) + 1);
	ca.bad = malloc(nchunks * sizeof(size_t) + 1);
	if (!ca.bounds || !ca.bad)
	{
		free(ca.bounds);
		free(ca.bad);
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
	free(ca.bounds);
	free(ca.bad);
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
	job->outer = tdc_big_alloc(((job->nin * 6 + 63) / 64 + 1) * sizeof(uint64_t));
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

static int
run(tdc_job *job)
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
	job->xy = tdc_big_alloc(job->n * 2 * sizeof(double) + 16);
	job->idx = tdc_big_alloc(job->n * sizeof(uint32_t) + 4);
	job->site_of = tdc_big_alloc(job->n * sizeof(uint32_t) + 4);
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
		job->tol_to = tdc_big_alloc(job->n * sizeof(uint32_t));
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
	job->node_rect = malloc(nnodes * sizeof(tdc_rect));
	job->node_axis = calloc(nnodes, 1);
	job->node_lo = malloc(nnodes * sizeof(uint32_t));
	job->node_hi = malloc(nnodes * sizeof(uint32_t));
	job->subs = malloc(nnodes * sizeof(tdc_sub));
	if (!job->node_rect || !job->node_axis || !job->node_lo || !job->node_hi || !job->subs)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory for the subdivision tree");
		return TDC_ENOMEM;
	}
	tdc_subdivide(job);
	job->times.subdivide = job_clock(job) - t;
	if (atomic_load(&job->cancel))
		return TDC_ECANCELED;

	job->he = tdc_big_alloc(job->nin * 6 * sizeof(tdc_he) + sizeof(tdc_he));
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

/* Publish the status of the phase that just ended; the pool goes first. */
static void
finish_phase(tdc_job *job, int rc)
{
	tdc_pool_destroy(job->pool);
	job->pool = NULL;

	pthread_mutex_lock(&job->lock);
	if (atomic_load(&job->failed))
	{
		job->status = atomic_load(&job->failed);
		snprintf(job->err, sizeof(job->err), "%s", job->task_err);
	}
	else if (rc == TDC_ECANCELED || (rc == TDC_OK && atomic_load(&job->cancel)))
	{
		job->status = TDC_ECANCELED;
		snprintf(job->err, sizeof(job->err), "triangulation cancelled");
	}
	else
		job->status = rc;
	job->finished = true;
	pthread_cond_broadcast(&job->done);
	pthread_mutex_unlock(&job->lock);
}

static void *
driver_main(void *arg)
{
	tdc_job    *job = arg;

	finish_phase(job, job->phase(job));
	return NULL;
}

static void
free_arrays(tdc_job *job)
{
	tdc_big_free(job->xy);
	tdc_big_free(job->idx);
	tdc_big_free(job->site_of);
	tdc_big_free(job->map);
	tdc_big_free(job->outer);
	tdc_big_free(job->tol_to);
	tdc_big_free(job->he);
	tdc_big_free(job->prefix);
	free(job->node_rect);
	free(job->node_axis);
	free(job->node_lo);
	free(job->node_hi);
	free(job->subs);
}

/*
 * Our threads must never take the host's signals: block them all around
 * creation, so the new thread inherits the full mask (and the pool threads
 * the driver starts inherit it in turn).
 */
static int
create_masked_thread(pthread_t *thread, const pthread_attr_t *attr,
					 void *(*fn) (void *), void *arg)
{
	sigset_t	all,
				old;
	int			rc;

	sigfillset(&all);
	pthread_sigmask(SIG_SETMASK, &all, &old);
	rc = pthread_create(thread, attr, fn, arg);
	pthread_sigmask(SIG_SETMASK, &old, NULL);
	return rc;
}

static int
start_driver(tdc_job *job)
{
	int			rc = create_masked_thread(&job->driver, NULL, driver_main, job);

	job->driver_started = rc == 0;
	return rc;
}

/* Stop and join the driver, if any; then nothing but memory is left. */
static void
stop_driver(tdc_job *job)
{
	if (job->driver_started)
	{
		tdc_job_cancel(job);
		pthread_join(job->driver, NULL);
		job->driver_started = false;
	}
	pthread_mutex_destroy(&job->lock);
	pthread_cond_destroy(&job->done);
}

int
tdc_job_start(const double *xy, size_t n, const tdc_options *opt, tdc_job **out,
			  char *err, size_t errlen)
{
	tdc_job    *job;
	tdc_options o;
	pthread_condattr_t ca;
	int			rc;

	*out = NULL;
	if (opt)
		o = *opt;
	else
		tdc_options_init(&o);
	if (err && errlen)
		err[0] = '\0';

#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (n > TDC_MAX_POINTS)
		FAIL(TDC_ETOOBIG, "%zu points exceed the limit of %zu points per triangulation (32-bit mesh indices)",
			 n, TDC_MAX_POINTS);
	if (o.threads < 0 || o.threads > 1024)
		FAIL(TDC_EINVAL, "threads must be between 0 and 1024, not %d", o.threads);
	if (o.grid_size < 0 || o.grid_size > 65536)
		FAIL(TDC_EINVAL, "grid size must be between 0 and 65536, not %d", o.grid_size);
	if (o.levels < -1 || o.levels > TDC_MAX_LEVELS)
		FAIL(TDC_EINVAL, "levels must be between -1 and %d, not %d", TDC_MAX_LEVELS, o.levels);
	if (!(o.tolerance >= 0) || isinf(o.tolerance))
		FAIL(TDC_EINVAL, "tolerance must be a finite number >= 0, not %g", o.tolerance);
	if (n > 0 && xy == NULL)
		FAIL(TDC_EINVAL, "no coordinates given for %zu points", n);
	if (o.max_memory > 0 && tdc_estimate_memory(n, &o) > o.max_memory)
		FAIL(TDC_EMEMLIMIT, "triangulating %zu points needs about %zu MB, more than the limit of %zu MB",
			 n, tdc_estimate_memory(n, &o) >> 20, o.max_memory >> 20);

	job = calloc(1, sizeof(tdc_job));
	if (job == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	job->opt = o;
	job->n = n;
	job->input = xy;
	job->inline_run = plan_inline(n);
	job->threads = plan_threads(n, &o);
	atomic_init(&job->cancel, 0);
	atomic_init(&job->failed, 0);
	pthread_mutex_init(&job->lock, NULL);
	pthread_condattr_init(&ca);
	pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
	pthread_cond_init(&job->done, &ca);
	pthread_condattr_destroy(&ca);

	job->phase = run;
	if (job->inline_run)
	{
		finish_phase(job, run(job));
		*out = job;
		return TDC_OK;
	}
	rc = start_driver(job);
	if (rc != 0)
	{
		pthread_mutex_destroy(&job->lock);
		pthread_cond_destroy(&job->done);
		free(job);
		FAIL(TDC_ETHREAD, "could not create a thread: %s", strerror(rc));
	}
	*out = job;
	return TDC_OK;
#undef FAIL
}

/*
 * A small job's triangles, handed over on the caller's thread in batches in
 * the order of tdc_next_triangle, with none of emit.c's planning.
 */
static int
emit_inline(tdc_job *job)
{
	uint32_t	v[3 * EMIT_INLINE_BATCH];
	tdc_iter	it = {0};
	size_t		first = 0,
				k = 0;

	while (tdc_next_triangle(job, &it, v + 3 * k))
	{
		if (++k == EMIT_INLINE_BATCH)
		{
			job->emit(job->emit_arg, first, k, v);
			first += k;
			k = 0;
		}
	}
	if (k > 0)
		job->emit(job->emit_arg, first, k, v);
	return first + k == job->ntri ? TDC_OK : TDC_EINVAL;
}

/*
 * The second phase a finished job can run: its triangles handed to the
 * host's callback on the pool (emit.c).  Same lifecycle as the first: the
 * host waits with tdc_job_wait and may cancel.
 */
int
tdc_job_emit_start(tdc_job *job, tdc_emit_fn emit, void *arg, char *err,
				   size_t errlen)
{
	int			rc;

	if (err && errlen)
		err[0] = '\0';
	pthread_mutex_lock(&job->lock);
	rc = job->finished ? job->status : TDC_RUNNING;
	pthread_mutex_unlock(&job->lock);
	if (rc != TDC_OK)
	{
		if (err && errlen)
			snprintf(err, errlen, "the job has not finished successfully");
		return TDC_EINVAL;
	}
	/* the driver that ran the triangulation is done: reap it */
	if (job->driver_started)
	{
		pthread_join(job->driver, NULL);
		job->driver_started = false;
	}
	job->emit = emit;
	job->emit_arg = arg;
	job->phase = tdc_emit_phase;
	job->finished = false;
	job->status = TDC_RUNNING;
	if (job->inline_run)
	{
		finish_phase(job, emit_inline(job));
		return TDC_OK;
	}
	rc = start_driver(job);
	if (rc != 0)
	{
		/* the triangulation stays valid; only the handing-over failed */
		job->finished = true;
		job->status = TDC_OK;
		if (err && errlen)
			snprintf(err, errlen, "could not create a thread: %s", strerror(rc));
		return TDC_ETHREAD;
	}
	return TDC_OK;
}

int
tdc_job_wait(tdc_job *job, int timeout_ms)
{
	int			status;

	pthread_mutex_lock(&job->lock);
	if (job->finished)
		;						/* an inline job: no clock to read */
	else if (timeout_ms < 0)
	{
		while (!job->finished)
			pthread_cond_wait(&job->done, &job->lock);
	}
	else if (!job->finished)
	{
		struct timespec ts;

		clock_gettime(CLOCK_MONOTONIC, &ts);
		ts.tv_sec += timeout_ms / 1000;
		ts.tv_nsec += (long) (timeout_ms % 1000) * 1000000L;
		if (ts.tv_nsec >= 1000000000L)
		{
			ts.tv_sec++;
			ts.tv_nsec -= 1000000000L;
		}
		while (!job->finished)
			if (pthread_cond_timedwait(&job->done, &job->lock, &ts) == ETIMEDOUT)
				break;
	}
	status = job->finished ? job->status : TDC_RUNNING;
	pthread_mutex_unlock(&job->lock);
	return status;
}

void
tdc_job_cancel(tdc_job *job)
{
	if (job)
		atomic_store(&job->cancel, 1);
}

const char *
tdc_job_error(const tdc_job *job)
{
	return job->err;
}

void
tdc_job_free(tdc_job *job)
{
	if (job == NULL)
		return;
	stop_driver(job);
	free_arrays(job);
	free(job);
}

static void *
reaper_main(void *arg)
{
	tdc_job    *job = arg;

	free_arrays(job);
	free(job);
	return NULL;
}

/*
 * Returning a big job's pages to the kernel takes a while (about 10 ms per
 * million points, several times that on a loaded machine), and a host that
 * frees while unwinding from a cancel makes its user wait for it.  The
 * workers are stopped and joined here, so the detached thread only unmaps
 * memory no one else can reach; if it cannot start, the caller frees.
 */
void
tdc_job_free_background(tdc_job *job)
{
	pthread_attr_t attr;
	pthread_t	reaper;
	int			rc;

	if (job == NULL)
		return;
	stop_driver(job);

	if (pthread_attr_init(&attr) != 0)
		rc = -1;
	else
	{
		pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
		pthread_attr_setstacksize(&attr, 64 * 1024);
		rc = create_masked_thread(&reaper, &attr, reaper_main, job);
		pthread_attr_destroy(&attr);
	}
	if (rc != 0)
		(void) reaper_main(job);
}

int
tdc_triangulate(const double *xy, size_t n, const tdc_options *opt, tdc_job **job,
				char *err, size_t errlen)
{
	int			rc = tdc_job_start(xy, n, opt, job, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_job_wait(*job, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", tdc_job_error(*job));
	return rc;
}

/* --- results --- */

size_t
tdc_num_input(const tdc_job *job)
{
	return job->n;
}

size_t
tdc_num_sites(const tdc_job *job)
{
	return job->nsites;
}

size_t
tdc_num_triangles(const tdc_job *job)
{
	return job->ntri;
}

size_t
tdc_num_edges(const tdc_job *job)
{
	return job->nedges;
}

int
tdc_threads_used(const tdc_job *job)
{
	return job->threads;
}

int
tdc_levels_used(const tdc_job *job)
{
	return job->d;
}

int
tdc_grid_used(const tdc_job *job)
{
	return job->s;
}

void
tdc_job_times(const tdc_job *job, tdc_times *t)
{
	*t = job->times;
}

uint32_t
tdc_site_id_limit(const tdc_job *job)
{
	return (uint32_t) job->nin;
}

const double *
tdc_site_xy(const tdc_job *job, uint32_t site)
{
	return job->xy + 2 * (size_t) site;
}

void
tdc_site_extent(const tdc_job *job, double lo[2], double hi[2])
{
	/*
	 * check_input's box covers every input point, and without a tolerance
	 * each input point is a site or an exact duplicate of one.  The
	 * tolerance pass may drop extreme points, so then the survivors (the
	 * first nin entries of xy, in whatever order the sorts left them) are
	 * scanned instead.
	 */
	if (!(job->opt.tolerance > 0))
	{
		lo[0] = job->bmin[0], lo[1] = job->bmin[1];
		hi[0] = job->bmax[0], hi[1] = job->bmax[1];
		return;
	}
	lo[0] = lo[1] = INFINITY;
	hi[0] = hi[1] = -INFINITY;
	for (size_t p = 0; p < job->nin; p++)
	{
		lo[0] = fmin(lo[0], job->xy[2 * p]);
		hi[0] = fmax(hi[0], job->xy[2 * p]);
		lo[1] = fmin(lo[1], job->xy[2 * p + 1]);
		hi[1] = fmax(hi[1], job->xy[2 * p + 1]);
	}
}

size_t
tdc_site_input(const tdc_job *job, uint32_t site)
{
	return job->idx[site];
}

/*
 * Invert idx[] (position -> input) through site_of[], then send the points a
 * tolerance dropped to the site of the point that absorbed them.  Built once,
 * under the job's lock; the job is otherwise read-only after it finished.
 * Returns the map, or NULL when it cannot be allocated.
 *
 * Invariant: job->map is NULL or the complete map.  It is only stored under
 * the lock, with release order after the map's contents, so a thread that
 * loads it with acquire order outside the lock sees the whole map; threads
 * that race to build it queue on the lock and the later ones find it built.
 */
static uint32_t *
build_input_map(tdc_job *job)
{
	uint32_t   *map;

	pthread_mutex_lock(&job->lock);
	map = atomic_load_explicit(&job->map, memory_order_relaxed);
	if (map == NULL)
	{
		map = tdc_big_alloc(job->n * sizeof(uint32_t) + 4);
		if (map != NULL)
		{
			for (size_t p = 0; p < job->nin; p++)
				map[job->idx[p]] = job->site_of[p];
			if (job->tol_to)
				for (size_t i = 0; i < job->n; i++)
					if (job->tol_to[i] != i)
						map[i] = map[job->tol_to[i]];
			atomic_store_explicit(&job->map, map, memory_order_release);
		}
	}
	pthread_mutex_unlock(&job->lock);
	return map;
}

uint32_t
tdc_input_site(const tdc_job *job, size_t i)
{
	tdc_job    *j = (tdc_job *) job;
	uint32_t   *map = atomic_load_explicit(&j->map, memory_order_acquire);

	if (map == NULL && (map = build_input_map(j)) == NULL)
		return UINT32_MAX;
	return map[i];
}

/*
 * Every face but the outer one is a triangle, reported from its smallest
 * half-edge.  Lnext(h) lies in h's own cache line, so most half-edges are
 * rejected without touching another part of the mesh; the outer face's
 * half-edges are marked in job->outer.
 */
int
tdc_next_triangle(const tdc_job *job, tdc_iter *it, uint32_t v[3])
{
	size_t		nhe = job->nin * 6;

	if (job->ntri == 0)
		return 0;
	for (size_t h = it->pos; h < nhe; h++)
	{
		if (tdc_tri_at(job, h, v))
		{
			it->pos = h + 1;
			return 1;
		}
	}
	it->pos = nhe;
	return 0;
}

int
tdc_next_edge(const tdc_job *job, tdc_iter *it, uint32_t v[2])
{
	size_t		nhe = job->nin * 6;

	for (size_t h = it->pos; h < nhe; h += 2)
	{
		uint32_t	a = job->he[h].org,
					b = job->he[h + 1].org;

		if (a == TDC_NIL)
			continue;
		if (tdc_key_less(job->xy + 2 * (size_t) b, job->xy + 2 * (size_t) a, 0))
			v[0] = b, v[1] = a;
		else
			v[0] = a, v[1] = b;
		it->pos = h + 2;
		return 1;
	}
	it->pos = nhe;
	return 0;
}
