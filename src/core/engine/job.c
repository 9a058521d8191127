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

#include "job_int.h"

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

static void *
reaper_main(void *arg)
{
	tdc_job    *job = arg;

	tdc_job_free_arrays(job);
	free(job);
	return NULL;
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

	arena = tdc_plan_inline(n) ? tdc_arena_bytes(n) : 0;
	job = malloc(sizeof(tdc_job) + (arena > 0 ? arena + TDC_ARENA_ALIGN : 0));
	if (job == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	/* all but the two message buffers, which only need to be empty */
	memset(job, 0, offsetof(tdc_job, task_err));
	job->task_err[0] = job->err[0] = '\0';
	if (arena > 0)
	{
		job->arena = (char *) (((uintptr_t) (job + 1) + TDC_ARENA_ALIGN - 1) &
							   ~(uintptr_t) (TDC_ARENA_ALIGN - 1));
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
	tdc_job_free_arrays(job);
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
