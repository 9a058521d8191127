/*
 * core_cancel.c
 *		How fast the core stops and frees a job that is cancelled in each of
 *		its phases, without PostgreSQL (built and run by core_cancel.sh).
 *
 *	core_cancel N THREADS RUNS MAX_STOP_MS MAX_FREE_MS
 *
 * One complete run of N pseudo-random points gives the phase durations;
 * then RUNS jobs are cancelled at evenly spread moments of that run.  For
 * each: "stop" is the time from tdc_job_cancel() until tdc_job_wait()
 * returns, "free" the time tdc_job_free() takes.  The backend can only raise
 * its ERROR after both, so their sum bounds the core's share of the cancel
 * latency seen in SQL.  Prints one line per run, a summary per phase and
 * "N passed, N failed" (a run passes when stop <= MAX_STOP_MS and free <=
 * MAX_FREE_MS and the job reported TDC_ECANCELED or finished).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "tdc.h"

static double
now_ms(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

typedef struct PhaseStat
{
	const char *name;
	int			n;
	double		max_stop;
	double		max_free;
	double		sum_stop;
	double		sum_free;
} PhaseStat;

int
main(int argc, char **argv)
{
	size_t		n = argc > 1 ? strtoul(argv[1], NULL, 10) : 2000000;
	int			threads = argc > 2 ? atoi(argv[2]) : 2;
	int			runs = argc > 3 ? atoi(argv[3]) : 30;
	double		max_stop = argc > 4 ? atof(argv[4]) : 100;
	double		max_free = argc > 5 ? atof(argv[5]) : 150;
	double	   *xy = malloc(16 * n + 16);
	uint64_t	s = 88172645463325252ull;
	tdc_options opt;
	tdc_job    *job;
	tdc_times	t;
	char		err[256];
	double		b[4];
	PhaseStat	ph[4] = {{"sort"}, {"subdivide"}, {"leaves"}, {"merge"}};
	int			passed = 0,
				failed = 0;

	for (size_t i = 0; i < 2 * n; i++)
	{
		s ^= s << 13;
		s ^= s >> 7;
		s ^= s << 17;
		xy[i] = (double) (s % 100000000) / 100.0;
	}
	tdc_options_init(&opt);
	opt.threads = threads;
	opt.times = 1;
	if (tdc_triangulate(xy, n, &opt, &job, err, sizeof(err)) != TDC_OK)
	{
		fprintf(stderr, "reference run failed: %s\n", err);
		return 2;
	}
	tdc_job_times(job, &t);
	tdc_job_free(job);
	b[0] = t.sort * 1e3;
	b[1] = b[0] + t.subdivide * 1e3;
	b[2] = b[1] + t.leaves * 1e3;
	b[3] = b[2] + t.merge * 1e3;
	printf("%zu points, %d threads: sort %.0f, subdivide %.0f, leaves %.0f, merge %.0f ms (total %.0f)\n",
		   n, threads, t.sort * 1e3, t.subdivide * 1e3, t.leaves * 1e3,
		   t.merge * 1e3, t.total * 1e3);

	for (int r = 0; r < runs; r++)
	{
		double		at = (r + 0.5) * t.total * 1e3 / runs;
		double		t1,
					t2,
					t3;
		int			rc,
					p = at < b[0] ? 0 : at < b[1] ? 1 : at < b[2] ? 2 : 3;

		if (tdc_job_start(xy, n, &opt, &job, err, sizeof(err)) != TDC_OK)
		{
			printf("start failed: %s\n", err);
			failed++;
			continue;
		}
		rc = tdc_job_wait(job, (int) at);
		t1 = now_ms();
		t2 = t1;
		if (rc == TDC_RUNNING)
		{
			tdc_job_cancel(job);
			rc = tdc_job_wait(job, -1);
			t2 = now_ms();
		}
		tdc_job_free(job);
		t3 = now_ms();
		printf("  at %6.0f ms (%-9s) status %2d  stop %6.1f ms  free %6.1f ms\n",
			   at, ph[p].name, rc, t2 - t1, t3 - t2);
		ph[p].n++;
		ph[p].sum_stop += t2 - t1;
		ph[p].sum_free += t3 - t2;
		if (t2 - t1 > ph[p].max_stop)
			ph[p].max_stop = t2 - t1;
		if (t3 - t2 > ph[p].max_free)
			ph[p].max_free = t3 - t2;
		if ((rc == TDC_ECANCELED || rc == TDC_OK) && t2 - t1 <= max_stop && t3 - t2 <= max_free)
			passed++;
		else
			failed++;
	}
	for (int p = 0; p < 4; p++)
		if (ph[p].n > 0)
			printf("%-9s %2d runs: stop mean %6.1f max %6.1f ms, free mean %6.1f max %6.1f ms\n",
				   ph[p].name, ph[p].n, ph[p].sum_stop / ph[p].n, ph[p].max_stop,
				   ph[p].sum_free / ph[p].n, ph[p].max_free);
	free(xy);
	printf("%d passed, %d failed\n", passed, failed);
	return failed > 0;
}
