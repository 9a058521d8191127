/*
 * runner.c
 *		The lifecycle that every long operation of the core shares: a
 *		triangulation (and its handing-over, emit.c), a constraint insertion
 *		(cdt.c) and a Voronoi diagram (voronoi.c).
 *
 * The host's thread must stay free to notice its own interrupts and to
 * cancel, so the work runs on a thread of its own, started with every signal
 * blocked (the host's handlers must never run on our threads, and the pool
 * threads that work starts inherit the full mask in turn).  The host waits
 * with a timeout, polling its interrupt flag in between, and cancels by
 * raising a flag that the work polls; it never interrupts a thread.  Small
 * work skips the thread and runs on the caller's thread before the start
 * returns, and waiting on it reads no clock.  An owner that knows at the
 * start that all its work runs inline (a small triangulation) initializes
 * the runner with tdc_runner_init_inline: then there is no condition
 * variable, and publishing and waiting take no lock, since the status is
 * written by the thread that then hands the owner out, before it does.  On
 * a call of a few points those pthread calls were several percent of the
 * core's time.  The lock itself still exists, for owners that guard other
 * state with it (a job's input map, result.c).
 *
 * Invariant: finished and status change only under lock (inline_only: on
 * the one thread that runs the work), and finished turns true after the
 * work has let go of everything but the owner's memory (its pool is gone),
 * so a waiter that sees it finished sees no thread of it but the idle one
 * that published it.  The work writes its results and error
 * message before the runner takes the lock to publish, so a waiter that saw
 * finished sees them too.  Freeing cancels and joins first; then nothing but
 * memory is left.  The runner holds no global state: it lives inside its
 * owner, and the cancel flag it raises is the owner's, which the owner's
 * tasks poll.
 */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "engine_int.h"

/*
 * Ready a runner for its owner's first work.  The cancel flag is the owner's,
 * polled by its tasks: the runner clears it here and raises it on cancel.
 */
void
tdc_runner_init(tdc_runner *r, atomic_int *cancel)
{
	pthread_condattr_t ca;

	r->cancel = cancel;
	atomic_init(r->cancel, 0);
	r->started = false;
	r->inline_only = false;
	r->finished = false;
	r->status = TDC_RUNNING;
	pthread_mutex_init(&r->lock, NULL);
	pthread_condattr_init(&ca);
	pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
	pthread_cond_init(&r->done, &ca);
	pthread_condattr_destroy(&ca);
}

/* A runner whose work only ever runs inline (tdc_runner_start's inline_run). */
void
tdc_runner_init_inline(tdc_runner *r, atomic_int *cancel)
{
	r->cancel = cancel;
	atomic_init(r->cancel, 0);
	r->started = false;
	r->inline_only = true;
	r->finished = false;
	r->status = TDC_RUNNING;
	pthread_mutex_init(&r->lock, NULL);
}

/*
 * Our threads must never take the host's signals: block them all around
 * creation, so the new thread inherits the full mask.
 */
int
tdc_thread_create_masked(pthread_t *thread, const pthread_attr_t *attr,
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

static void *
runner_main(void *arg)
{
	tdc_runner *r = arg;

	tdc_runner_finish(r, r->work(r->arg));
	return NULL;
}

/*
 * Run work(arg), which returns the status to publish: on the caller's
 * thread when inline_run (it has finished on return), otherwise on a new
 * thread.  On failure (TDC_ETHREAD, with a message in err) nothing was
 * started and the runner is as before.
 */
int
tdc_runner_start(tdc_runner *r, bool inline_run, tdc_work_fn work, void *arg,
				 char *err, size_t errlen)
{
	int			rc;

	if (inline_run || r->inline_only)
	{
		tdc_runner_finish(r, work(arg));
		return TDC_OK;
	}
	r->work = work;
	r->arg = arg;
	rc = tdc_thread_create_masked(&r->thread, NULL, runner_main, r);
	if (rc != 0)
	{
		if (err && errlen)
			snprintf(err, errlen, "could not create a thread: %s", strerror(rc));
		return TDC_ETHREAD;
	}
	r->started = true;
	return TDC_OK;
}

/*
 * Publish the status of the work, which has let go of its threads (or
 * settle a runner whose next work could not start).
 */
void
tdc_runner_finish(tdc_runner *r, int status)
{
	if (r->inline_only)
	{
		r->status = status;
		r->finished = true;
		return;
	}
	pthread_mutex_lock(&r->lock);
	r->status = status;
	r->finished = true;
	pthread_cond_broadcast(&r->done);
	pthread_mutex_unlock(&r->lock);
}

/*
 * The status, or TDC_RUNNING if the work has not finished within timeout_ms
 * (< 0: wait for it; 0: only look).
 */
int
tdc_runner_wait(tdc_runner *r, int timeout_ms)
{
	int			status;

	if (r->inline_only)
		return r->finished ? r->status : TDC_RUNNING;
	pthread_mutex_lock(&r->lock);
	if (r->finished)
		;						/* inline work: no clock to read */
	else if (timeout_ms < 0)
	{
		while (!r->finished)
			pthread_cond_wait(&r->done, &r->lock);
	}
	else
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
		while (!r->finished)
			if (pthread_cond_timedwait(&r->done, &r->lock, &ts) == ETIMEDOUT)
				break;
	}
	status = r->finished ? r->status : TDC_RUNNING;
	pthread_mutex_unlock(&r->lock);
	return status;
}

void
tdc_runner_cancel(tdc_runner *r)
{
	atomic_store(r->cancel, 1);
}

/*
 * Ready a finished runner for its owner's next piece of work: reap the
 * thread that ran the last one (it has published, so it is about to exit).
 */
void
tdc_runner_rearm(tdc_runner *r)
{
	if (r->started)
	{
		pthread_join(r->thread, NULL);
		r->started = false;
	}
	if (r->inline_only)
	{
		r->finished = false;
		r->status = TDC_RUNNING;
		return;
	}
	pthread_mutex_lock(&r->lock);
	r->finished = false;
	r->status = TDC_RUNNING;
	pthread_mutex_unlock(&r->lock);
}

/* Stop and join the thread, if any; then nothing but memory is left. */
void
tdc_runner_destroy(tdc_runner *r)
{
	if (r->started)
	{
		tdc_runner_cancel(r);
		pthread_join(r->thread, NULL);
		r->started = false;
	}
	pthread_mutex_destroy(&r->lock);
	if (!r->inline_only)
		pthread_cond_destroy(&r->done);
}
