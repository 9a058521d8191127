/*
 * bounded_job.c
 *		A bounded run (tdc_bounded_run) on a thread of its own, for a host
 *		that must keep its own thread free: tdc_bounded_start, _wait,
 *		_cancel, _error, _free (tdc.h).
 *
 * A PostgreSQL backend stages a table to a file and runs the bounded
 * pipeline on it, which takes seconds to hours; its main thread must keep
 * looking at its interrupts meanwhile (a query cancel, statement_timeout,
 * a terminate) and must never be the thread the pipeline's callbacks run
 * on.  So the run gets the lifecycle every long operation of the core has
 * (runner.c): a thread started with every signal blocked, a status the
 * host waits for with a timeout, and a cancel flag.  The flag is the run's
 * own cancel (tdc_bounded_params.cancel), which it polls between chunks of
 * input and between tiles, and which reaches into a tile's engine run
 * (bounded_tile.c), so a cancel is noticed within a few ms however big the
 * tile.
 *
 * Invariant: the callbacks of the params (emit, settle, peak, trace) run
 * on the run's thread only, never on the host's, and never after
 * tdc_bounded_wait has returned a final status.  Freeing cancels and joins
 * first.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/engine_int.h"

struct tdc_bounded_job
{
	tdc_bounded_params p;		/* the caller's, with cancel pointing at flag */
	tdc_bounded_stats st;
	tdc_runner	run;
	atomic_int	cancel;			/* the runner's flag */
	volatile int flag;			/* the run's: set with cancel */
	char		err[640];
};

static int
bounded_work(void *arg)
{
	tdc_bounded_job *job = arg;

	return tdc_bounded_run(&job->p, &job->st, job->err, sizeof(job->err));
}

int
tdc_bounded_start(const tdc_bounded_params *p, tdc_bounded_job **jobp, char *err, size_t errlen)
{
	tdc_bounded_job *job;
	int			rc;

	*jobp = NULL;
	if (err && errlen)
		err[0] = '\0';
	if (p->cancel != NULL)
	{
		if (err && errlen)
			snprintf(err, errlen, "tdc_bounded_start: the job has its own cancel (tdc_bounded_cancel)");
		return TDC_EINVAL;
	}
	job = calloc(1, sizeof(*job));
	if (job == NULL)
	{
		if (err && errlen)
			snprintf(err, errlen, "out of memory for a bounded run");
		return TDC_ENOMEM;
	}
	job->p = *p;
	job->flag = 0;
	job->p.cancel = &job->flag;
	tdc_runner_init(&job->run, &job->cancel);
	rc = tdc_runner_start(&job->run, false, bounded_work, job, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&job->run);
		free(job);
		return rc;
	}
	*jobp = job;
	return TDC_OK;
}

int
tdc_bounded_wait(tdc_bounded_job *job, int timeout_ms)
{
	return tdc_runner_wait(&job->run, timeout_ms);
}

void
tdc_bounded_cancel(tdc_bounded_job *job)
{
	__atomic_store_n(&job->flag, 1, __ATOMIC_RELAXED);
	tdc_runner_cancel(&job->run);
}

const char *
tdc_bounded_error(const tdc_bounded_job *job)
{
	return job->err;
}

const tdc_bounded_stats *
tdc_bounded_stats_of(const tdc_bounded_job *job)
{
	return &job->st;
}

void
tdc_bounded_free(tdc_bounded_job *job)
{
	if (job == NULL)
		return;
	__atomic_store_n(&job->flag, 1, __ATOMIC_RELAXED);
	tdc_runner_destroy(&job->run);
	free(job);
}
