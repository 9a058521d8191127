/*
 * job.c
 *		The lifecycle of a job: start, wait, cancel, free.
 *
 * tdc_job_start() checks the options and the memory bound, then either runs
 * a small job on the caller's thread (TDC_INLINE_MAX) or starts a driver
 * thread with every signal blocked, and returns.  The driver runs one phase
 * (job->phase: the triangulation, then on request the handing-over of
 * emit.c) and publishes its status under the job's lock.  The caller's
 * thread only waits (tdc_job_wait) and may cancel; a cancel is a flag that
 * every task polls.  The thread, the lock, the wait and the join are the
 * runner that constraints and Voronoi diagrams share (runner.c).
 *
 * Invariant: the job's finished flag and status change only under its lock
 * (job->run.lock), or for a small job on the caller's thread before
 * tdc_job_start returns it (runner.c), and the pool is gone before finished
 * turns true, so a waiter that sees a finished job sees no thread of it but
 * the (idle) driver.  Freeing joins the driver first; then nothing but
 * memory is left, which may be returned on a detached thread
 * (tdc_job_free_background).
 */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"

/*
 * The status of the phase that just ended, its message in job->err: a
 * task's error wins, then a cancel.  The pool goes first.
 */
static int
settle_phase(tdc_job *job, int rc)
{
	tdc_pool_destroy(job->pool);
	job->pool = NULL;

	if (atomic_load(&job->failed))
	{
		snprintf(job->err, sizeof(job->err), "%s", job->task_err);
		return atomic_load(&job->failed);
	}
	if (rc == TDC_ECANCELED || (rc == TDC_OK && atomic_load(&job->cancel)))
	{
		snprintf(job->err, sizeof(job->err), "triangulation cancelled");
		return TDC_ECANCELED;
	}
	return rc;
}

/*
 * A phase, on the driver thread or inline on the caller's (tdc_work_fn); the
 * runner publishes the status.
 */
static int
phase_work(void *arg)
{
	tdc_job    *job = arg;

	return settle_phase(job, job->phase(job));
}

/*
 * The arena.  A call on a handful of points used to spend a third of its
 * time in malloc and free: some twenty arrays, each a few dozen bytes, and
 * glibc consolidating its free lists whenever a chunk next to the top of
 * the heap came back.  So a job on at most ARENA_MAX_POINTS points gets its
 * arrays from one zeroed block allocated together with the job, a bump
 * allocator with nothing to free.  An array that does not fit (the sizing
 * below is generous, not exact) falls back to tdc_big_alloc, so the arena
 * is a speed-up only, never a limit.  The block stays within a few tens of
 * kB, below glibc's mapping threshold, and it is counted by
 * tdc_estimate_memory's per-point and fixed terms like the arrays it
 * replaces.  Only the thread that runs the phases allocates from it; the
 * input map, built on demand by any reader, never does.  The block is
 * zeroed an array at a time as it is handed out, not as a whole: the sizing
 * is generous, and clearing the unused rest cost more than the arrays.
 */
#define ARENA_MAX_POINTS	256
#define ARENA_ALIGN			16		/* one thread: no false sharing to avoid */
#define ARENA_FIXED			1024	/* tree nodes, grid counts, rounding */
#define ARENA_PER_POINT		(6 * sizeof(tdc_he) + 48)	/* mesh, xy, idx, site_of, cell */

static size_t
arena_bytes(size_t n)
{
	return n <= ARENA_MAX_POINTS ? ARENA_FIXED + n * ARENA_PER_POINT : 0;
}

/*
 * 16-aligned memory for one of the job's arrays, zeroed unless the caller
 * fills it before reading it; NULL if out of memory.
 */
static void *
job_alloc(tdc_job *job, size_t size, bool zero)
{
	size_t		rounded = (size + ARENA_ALIGN - 1) & ~(size_t) (ARENA_ALIGN - 1);

	if (job->arena != NULL && rounded >= size &&
		rounded <= job->arena_size - job->arena_used)
	{
		void	   *p = job->arena + job->arena_used;

		job->arena_used += rounded;
		return zero ? memset(p, 0, size) : p;
	}
	job->off_arena = true;
	return zero ? tdc_big_alloc(job->opt.cache, size) :
		tdc_big_alloc_uninit(job->opt.cache, size);
}

void *
tdc_job_alloc(tdc_job *job, size_t size)
{
	return job_alloc(job, size, true);
}

void *
tdc_job_alloc_uninit(tdc_job *job, size_t size)
{
	return job_alloc(job, size, false);
}

void
tdc_job_release(tdc_job *job, void *ptr)
{
	char	   *p = ptr;

	if (p != NULL && job->arena != NULL && p >= job->arena && p < job->arena + job->arena_size)
		return;
	tdc_big_free(job->opt.cache, ptr);
}

static void
free_arrays(tdc_job *job)
{
	/* the input map never comes from the arena (see above) */
	if (job->arena != NULL && !job->off_arena)
	{
		tdc_big_free(job->opt.cache, job->map);
		return;
	}
	tdc_job_release(job, job->xy);
	tdc_job_release(job, job->idx);
	tdc_job_release(job, job->site_of);
	tdc_job_release(job, job->map);
	tdc_job_release(job, job->outer);
	tdc_job_release(job, job->tol_to);
	tdc_job_release(job, job->he);
	tdc_job_release(job, job->prefix);
	tdc_job_release(job, job->node_rect);
	tdc_job_release(job, job->node_axis);
	tdc_job_release(job, job->node_lo);
	tdc_job_release(job, job->node_hi);
	tdc_job_release(job, job->subs);
}

static void *
reaper_main(void *arg)
{
	tdc_job    *job = arg;

	free_arrays(job);
	free(job);
	return NULL;
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

int
tdc_job_start(const double *xy, size_t n, const tdc_options *opt, tdc_job **out,
			  char *err, size_t errlen)
{
	tdc_job    *job;
	tdc_options o;
	size_t		arena;
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

	arena = tdc_plan_inline(n) ? arena_bytes(n) : 0;
	job = malloc(sizeof(tdc_job) + (arena > 0 ? arena + ARENA_ALIGN : 0));
	if (job == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	/* all but the two message buffers, which only need to be empty */
	memset(job, 0, offsetof(tdc_job, task_err));
	job->task_err[0] = job->err[0] = '\0';
	if (arena > 0)
	{
		job->arena = (char *) (((uintptr_t) (job + 1) + ARENA_ALIGN - 1) &
							   ~(uintptr_t) (ARENA_ALIGN - 1));
		job->arena_size = arena;
	}
	job->opt = o;
	job->n = n;
	job->input = xy;
	job->inline_run = tdc_plan_inline(n);
	job->threads = tdc_plan_threads(n, &o);
	atomic_init(&job->failed, 0);
	if (job->inline_run)
		tdc_runner_init_inline(&job->run, &job->cancel);
	else
		tdc_runner_init(&job->run, &job->cancel);

	job->phase = tdc_run_phase;
	rc = tdc_runner_start(&job->run, job->inline_run, phase_work, job, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&job->run);
		free(job);
		return rc;
	}
	*out = job;
	return TDC_OK;
#undef FAIL
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
	if (tdc_runner_wait(&job->run, 0) != TDC_OK)
	{
		if (err && errlen)
			snprintf(err, errlen, "the job has not finished successfully");
		return TDC_EINVAL;
	}
	/* the driver that ran the triangulation is done: reap it */
	tdc_runner_rearm(&job->run);
	job->emit = emit;
	job->emit_arg = arg;
	job->phase = job->inline_run ? tdc_emit_inline : tdc_emit_phase;
	rc = tdc_runner_start(&job->run, job->inline_run, phase_work, job, err, errlen);
	if (rc != TDC_OK)
	{
		/* the triangulation stays valid; only the handing-over failed */
		tdc_runner_finish(&job->run, TDC_OK);
		return rc;
	}
	return TDC_OK;
}

int
tdc_job_wait(tdc_job *job, int timeout_ms)
{
	return tdc_runner_wait(&job->run, timeout_ms);
}

void
tdc_job_cancel(tdc_job *job)
{
	if (job)
		tdc_runner_cancel(&job->run);
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
	tdc_runner_destroy(&job->run);
	free_arrays(job);
	free(job);
}


/*
 * Returning a big job's pages to the kernel takes time in proportion to its
 * size, more on a loaded machine, and a host that frees while unwinding from
 * a cancel makes its user wait for it.  The
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
	tdc_runner_destroy(&job->run);
	/* the host's cache is not ours to touch from another thread */
	job->opt.cache = NULL;

	if (pthread_attr_init(&attr) != 0)
		rc = -1;
	else
	{
		pthread_attr_setdetachstate(&attr, PTHREAD_CREATE_DETACHED);
		pthread_attr_setstacksize(&attr, 64 * 1024);
		rc = tdc_thread_create_masked(&reaper, &attr, reaper_main, job);
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
