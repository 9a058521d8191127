/*
 * test_concurrency.c
 *		The core's promise of no global mutable state, checked with threads
 *		that use it at the same moment; and the message of a failed
 *		pthread_create, in the pool and in every start.
 *
 * Races rarely change a result on two cores, so the real check of the
 * first two tests is `make check-core-tsan`: ThreadSanitizer reports any
 * unsynchronised access between the threads, whatever they computed.
 */
#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"

#define NTHREADS	4

static double *
random_points(size_t n, uint64_t seed)
{
	double	   *xy = malloc(2 * n * sizeof(double));

	for (size_t i = 0; i < 2 * n; i++)
		xy[i] = tdc_splitmix_unit(&seed) * 1000;
	return xy;
}

/*
 * A finished job's triangulation as plain arrays for tdc_validate: the
 * sites renumbered densely.  Returns false when anything is missing.
 */
typedef struct plain
{
	double	   *sites;
	size_t		m;
	uint32_t   *tri;
	size_t		ntri;
} plain;

static bool
to_plain(const tdc_job *job, plain *p)
{
	uint32_t	lim = tdc_site_id_limit(job),
			   *dense = malloc(sizeof(uint32_t) * ((size_t) lim + 1)),
				v[3];
	tdc_iter	it = {0};

	p->sites = malloc(16 * (tdc_num_sites(job) + 1));
	p->tri = malloc(12 * (tdc_num_triangles(job) + 1));
	p->m = p->ntri = 0;
	if (!dense || !p->sites || !p->tri)
	{
		free(dense);
		return false;
	}
	for (uint32_t s = 0; s < lim; s++)
		dense[s] = UINT32_MAX;
	while (tdc_next_triangle(job, &it, v))
	{
		for (int k = 0; k < 3; k++)
		{
			if (dense[v[k]] == UINT32_MAX)
			{
				dense[v[k]] = (uint32_t) p->m;
				memcpy(p->sites + 2 * p->m++, tdc_site_xy(job, v[k]), 16);
			}
			p->tri[3 * p->ntri + k] = dense[v[k]];
		}
		p->ntri++;
	}
	free(dense);
	return p->m == tdc_num_sites(job);
}

typedef struct validate_arg
{
	pthread_barrier_t *start;
	const plain *p;
	int			rc;
	char		err[256];
} validate_arg;

static void *
validate_main(void *a)
{
	validate_arg *va = a;

	pthread_barrier_wait(va->start);
	va->rc = tdc_validate(va->p->sites, va->p->m, va->p->tri, va->p->ntri,
						  va->err, sizeof(va->err));
	return NULL;
}

/*
 * tdc_validate on different triangulations in several threads at once.  Its
 * hull sorts the sites: a comparator reaching them through a shared static
 * would sort one thread's sites by another's coordinates.
 */
static void
test_concurrent_validate(void)
{
	size_t		n = tdc_test_quick ? 20000 : 100000;
	plain		p[NTHREADS];
	validate_arg va[NTHREADS];
	pthread_t	th[NTHREADS];
	pthread_barrier_t start;
	bool		ready = true;

	for (int k = 0; k < NTHREADS; k++)
	{
		/* different sizes, so a wrong site array is also out of bounds */
		size_t		nk = n + (size_t) k * (n / 4);
		double	   *xy = random_points(nk, 1000 + (uint64_t) k);
		tdc_options opt;
		tdc_job    *job;
		char		err[256];

		tdc_options_init(&opt);
		opt.threads = 1;
		CHECK(tdc_triangulate(xy, nk, &opt, &job, err, sizeof(err)) == TDC_OK,
			  "concurrent validate: triangulation %d: %s", k, err);
		if (!to_plain(job, &p[k]))
			ready = false;
		tdc_job_free(job);
		free(xy);
	}
	CHECK(ready, "concurrent validate: could not list the triangles");
	pthread_barrier_init(&start, NULL, NTHREADS);
	for (int round = 0; ready && round < 3; round++)
	{
		for (int k = 0; k < NTHREADS; k++)
		{
			va[k].start = &start;
			va[k].p = &p[k];
			va[k].rc = -2;
			va[k].err[0] = '\0';
			pthread_create(&th[k], NULL, validate_main, &va[k]);
		}
		for (int k = 0; k < NTHREADS; k++)
		{
			pthread_join(th[k], NULL);
			CHECK(va[k].rc == 0, "concurrent validate: round %d, thread %d: %s",
				  round, k, va[k].err);
		}
	}
	pthread_barrier_destroy(&start);
	for (int k = 0; k < NTHREADS; k++)
	{
		free(p[k].sites);
		free(p[k].tri);
	}
}

typedef struct map_arg
{
	pthread_barrier_t *start;
	const tdc_job *job;
	uint32_t   *site;			/* what tdc_input_site said, per input */
	int			rc;
	char		err[256];
} map_arg;

static void *
map_main(void *a)
{
	map_arg    *ma = a;
	size_t		n = tdc_num_input(ma->job);

	pthread_barrier_wait(ma->start);
	for (size_t i = 0; i < n; i++)
		ma->site[i] = tdc_input_site(ma->job, i);
	/* and the validator, which reaches the sites through the same map */
	ma->rc = tdc_validate_job(ma->job, ma->err, sizeof(ma->err));
	return NULL;
}

/*
 * The first calls of tdc_input_site build the input->site map lazily: from
 * several threads at once on a fresh job, all must get the same complete
 * map (one build, safely published).  Duplicates and a tolerance make the
 * map more than a permutation.  Small jobs too: they ran inline, where the
 * runner publishes its status without locking, but the map is still built
 * under the job's lock.
 */
static void
input_site_rounds(size_t n, int rounds)
{
	double	   *xy = random_points(n, 77);
	uint32_t   *site[NTHREADS];
	map_arg		ma[NTHREADS];
	pthread_t	th[NTHREADS];
	pthread_barrier_t start;

	for (size_t i = 0; i < n / 10; i++)
		memcpy(xy + 2 * (n - 1 - i), xy + 2 * i, 16);	/* duplicates */
	for (int k = 0; k < NTHREADS; k++)
		site[k] = malloc(n * sizeof(uint32_t));
	pthread_barrier_init(&start, NULL, NTHREADS);
	for (int round = 0; round < rounds; round++)
	{
		tdc_options opt;
		tdc_job    *job;
		char		err[256];

		tdc_options_init(&opt);
		opt.threads = 2;
		opt.tolerance = round % 2 ? 0.01 : 0;
		CHECK(tdc_triangulate(xy, n, &opt, &job, err, sizeof(err)) == TDC_OK,
			  "concurrent input_site: %zu points: triangulation: %s", n, err);
		if (job == NULL)
			continue;
		for (int k = 0; k < NTHREADS; k++)
		{
			ma[k].start = &start;
			ma[k].job = job;
			ma[k].site = site[k];
			ma[k].rc = -2;
			ma[k].err[0] = '\0';
			pthread_create(&th[k], NULL, map_main, &ma[k]);
		}
		for (int k = 0; k < NTHREADS; k++)
			pthread_join(th[k], NULL);
		for (int k = 0; k < NTHREADS; k++)
		{
			size_t		bad = 0;

			CHECK(ma[k].rc == 0, "concurrent input_site: %zu points, round %d, thread %d validates: %s",
				  n, round, k, ma[k].err);
			for (size_t i = 0; i < n; i++)
				if (site[k][i] != site[0][i] || site[k][i] >= tdc_site_id_limit(job))
					bad++;
			CHECK(bad == 0, "concurrent input_site: %zu points, round %d, thread %d: %zu inputs mapped differently or not at all",
				  n, round, k, bad);
		}
		/* without a tolerance, duplicates follow their first occurrence */
		CHECK(opt.tolerance > 0 || tdc_input_site(job, n - 1) == tdc_input_site(job, 0),
			  "concurrent input_site: %zu points, round %d: a duplicate maps elsewhere", n, round);
		tdc_job_free(job);
	}
	pthread_barrier_destroy(&start);
	for (int k = 0; k < NTHREADS; k++)
		free(site[k]);
	free(xy);
}

static void
test_concurrent_input_site(void)
{
	input_site_rounds(tdc_test_quick ? 20000 : 100000, 6);
	/* inline, then inline within the arena of a small job */
	input_site_rounds(TDC_INLINE_MAX - 1, 2);
	input_site_rounds(60, 4);
}

/* Virtual memory of this process in bytes (first field of /proc/self/statm). */
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
 * Run child(xy, n, fd) on n random points in a forked process, which reports
 * on fd and exits; msg gets what it wrote.  Checks that it exited 0; returns
 * whether it did.  A child keeps a changed process-wide state (thread
 * attributes, limits) away from the rest of the suite.
 */
static bool
child_passes(const char *what, void (*child) (const double *xy, size_t n, int fd),
			 size_t n, uint64_t seed, char *msg, size_t msglen)
{
	double	   *xy = random_points(n, seed);
	int			fd[2];
	pid_t		pid = -1;
	int			status = -1;
	ssize_t		got;

	msg[0] = '\0';
	if (pipe(fd) == 0)
	{
		fflush(NULL);
		pid = fork();
		if (pid == 0)
		{
			close(fd[0]);
			child(xy, n, fd[1]);
			_exit(127);
		}
		close(fd[1]);
		if (pid > 0)
		{
			got = read(fd[0], msg, msglen - 1);
			msg[got > 0 ? got : 0] = '\0';
			waitpid(pid, &status, 0);
		}
		close(fd[0]);
	}
	free(xy);
	CHECK(pid > 0, "%s: no child process: %s", what, strerror(errno));
	if (pid <= 0)
		return false;
	CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0,
		  "%s: the child ended with %s %d, message \"%s\"", what,
		  WIFEXITED(status) ? "exit" : "signal",
		  WIFEXITED(status) ? WEXITSTATUS(status) : WTERMSIG(status), msg);
	return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

static void
thread_error_child(const double *xy, size_t n, int fd)
{
	pthread_attr_t attr;
	struct rlimit rl;
	tdc_options opt;
	tdc_job    *job = NULL;
	char		err[256] = "";
	int			rc;

	pthread_attr_init(&attr);
	pthread_attr_setstacksize(&attr, (size_t) 64 << 20);
	if (pthread_setattr_default_np(&attr) != 0)
		_exit(10);
	rl.rlim_cur = rl.rlim_max = vm_size() + ((size_t) 512 << 20);
	if (setrlimit(RLIMIT_AS, &rl) != 0)
		_exit(11);
	tdc_options_init(&opt);
	opt.threads = 1024;
	rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	if (job != NULL)
		snprintf(err, sizeof(err), "%s", tdc_job_error(job));
	if (write(fd, err, strlen(err)) < 0)
		_exit(12);
	_exit(rc == TDC_ETHREAD ? 0 : rc == TDC_OK ? 13 : 14);
}

/*
 * When the pool cannot start its threads, the job's message must give
 * pthread_create's own error, which it returns and does not leave in errno.
 * The job is just big enough to run on a driver thread with a pool.
 * A child process makes every thread stack 64 MB and caps its address space
 * 512 MB above what it uses: the driver thread fits, a pool of 1024 threads
 * does not, and glibc answers a stack it cannot map with EAGAIN.  Skipped
 * under sanitizers (--quick), whose shadow memory and thread bookkeeping
 * do not survive a capped address space.
 */
static void
test_thread_error_message(void)
{
	char		msg[256];

	/* smaller jobs than TDC_INLINE_MAX run inline, without a pool */
	if (tdc_test_quick ||
		!child_passes("thread error (exit 0 = TDC_ETHREAD)", thread_error_child,
					  TDC_INLINE_MAX, 5, msg, sizeof(msg)))
		return;
	CHECK(strstr(msg, strerror(EAGAIN)) != NULL && strstr(msg, strerror(0)) == NULL,
		  "thread error: message \"%s\" does not give pthread_create's error (%s)",
		  msg, strerror(EAGAIN));
	printf("thread error: \"%s\"\n", msg);
}

static void
count_emitted(void *arg, size_t first, size_t count, const uint32_t *v)
{
	atomic_fetch_add((_Atomic size_t *) arg, count);
}

static void
start_error_child(const double *xy, size_t n, int fd)
{
	pthread_attr_t attr;
	tdc_job    *job = NULL,
			   *job2 = NULL;
	tdc_cdt    *cdt = NULL;
	tdc_voronoi *vor = NULL;
	uint32_t	seg[2] = {0, 1};
	double		env[4];
	_Atomic size_t emitted = 0;
	char		err[4][256],
				msg[1024];
	int			rc[4];
	const char *what[4] = {"emit", "cdt", "voronoi", "job"};
	size_t		len = 0;

	if (tdc_triangulate(xy, n, NULL, &job, err[0], sizeof(err[0])) != TDC_OK)
		_exit(2);
	tdc_voronoi_default_env(job, env);
	pthread_attr_init(&attr);
	pthread_attr_setstacksize(&attr, (size_t) 1 << 46);
	if (pthread_setattr_default_np(&attr) != 0)
		_exit(3);
	rc[0] = tdc_job_emit_start(job, count_emitted, &emitted, err[0], sizeof(err[0]));
	rc[1] = tdc_cdt_start(job, seg, 1, &cdt, err[1], sizeof(err[1]));
	rc[2] = tdc_voronoi_start(job, env, 0, &vor, err[2], sizeof(err[2]));
	rc[3] = tdc_job_start(xy, n, NULL, &job2, err[3], sizeof(err[3]));
	for (int i = 0; i < 4; i++)
		if (rc[i] != TDC_ETHREAD || strstr(err[i], strerror(EAGAIN)) == NULL)
			len += snprintf(msg + len, sizeof(msg) - len, "%s: %d \"%s\"; ",
							what[i], rc[i], err[i]);
	if (cdt != NULL || vor != NULL || job2 != NULL)
		len += snprintf(msg + len, sizeof(msg) - len, "an object came back; ");
	if (tdc_job_wait(job, 0) != TDC_OK)
		len += snprintf(msg + len, sizeof(msg) - len, "the job lost its status; ");
	pthread_attr_setstacksize(&attr, (size_t) 1 << 20);
	pthread_setattr_default_np(&attr);
	if (tdc_job_emit_start(job, count_emitted, &emitted, err[0], sizeof(err[0])) != TDC_OK ||
		tdc_job_wait(job, -1) != TDC_OK || emitted != tdc_num_triangles(job))
		len += snprintf(msg + len, sizeof(msg) - len, "no handing-over after: %zu of %zu triangles",
						(size_t) emitted, tdc_num_triangles(job));
	if (len > 0 && write(fd, msg, strlen(msg)) < 0)
		_exit(4);
	_exit(len > 0);
}

/*
 * The other starts (runner.c): when the thread of a handing-over, a
 * constraint insertion, a Voronoi diagram or a new job cannot be created,
 * each returns TDC_ETHREAD with pthread_create's error and no object, and
 * the finished job stays usable.  A child process makes every new thread's
 * stack 64 TB, which glibc cannot map (EAGAIN), after the job has finished;
 * it writes what went wrong, if anything, and exits 1.  Skipped under
 * sanitizers (--quick), like the test above.
 */
static void
test_start_thread_error(void)
{
	char		msg[1024];

	/* TDC_INLINE_MAX + 1 points: every start takes a thread */
	if (!tdc_test_quick)
		child_passes("start thread error", start_error_child, TDC_INLINE_MAX + 1, 7,
					 msg, sizeof(msg));
}

void
test_concurrency(void)
{
	test_concurrent_validate();
	test_concurrent_input_site();
	test_thread_error_message();
	test_start_thread_error();
}
