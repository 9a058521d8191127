/*
 * test_bounded.c
 *		The bounded run (tdc_bounded_run, src/core/tiles/bounded*.c) through its
 *		API, without the CLI: the same triangle set as one tdc_triangulate,
 *		on the caller's thread and on a job's (tdc_bounded_start), and
 *		every way it stops (the caller's cancel flag before the run, between
 *		tiles and inside a tile's engine run, a job canceled or freed while
 *		it runs, emit refusing a tile, a directory that does not
 *		exist, a limit below the input's floor or below the peak before the
 *		first tile, a source shorter than n, a NaN, a tolerance) an error
 *		code with its message and nothing left in the caller's directory
 *		but the caller's own file.
 *
 * Triangle sets are compared by count and by an order-free hash: each
 * triangle turned to start at its least vertex (keeping it counter-
 * clockwise), its six coordinates hashed, the hashes summed.
 * ./tdc --max-memory (test/cli.sh) covers the inputs that need reruns,
 * z, text input and the peak under the limit.
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"

#define TILES_KEPT	512

/* What emit gathers, and how it misbehaves when asked to. */
typedef struct tri_sum
{
	size_t		ntri,
				calls;
	uint64_t	hash;
	int			refuse_at;		/* > 0: return 7 on that call */
	volatile int *cancel_at_first;	/* set after the first call */
	volatile int cancel;
	volatile int *cancel_at_trace;	/* set at the first trace line */
	size_t		traced_points;	/* the first trace line's points */
	uint64_t	tile_hash[TILES_KEPT];	/* per tile (the first TILES_KEPT) */
	size_t		tile_ntri[TILES_KEPT];
} tri_sum;

static uint64_t
tri_hash(const double *a, const double *b, const double *c)
{
	const double *v[3] = {a, b, c};
	int			k = 0;
	uint64_t	h = 0x1234;

	for (int i = 1; i < 3; i++)
		if (v[i][0] < v[k][0] || (v[i][0] == v[k][0] && v[i][1] < v[k][1]))
			k = i;
	for (int i = 0; i < 3; i++)
		for (int d = 0; d < 2; d++)
		{
			uint64_t	bits;

			memcpy(&bits, &v[(k + i) % 3][d], 8);
			h ^= bits;
			h = tdc_splitmix64(&h);
		}
	return h;
}

static int
emit_sum(void *arg, int tile, const double *q, const double *qz, const int64_t *ql, const size_t *tri,
		 size_t ntri)
{
	tri_sum    *s = arg;

	s->calls++;
	if (s->refuse_at > 0 && (int) s->calls == s->refuse_at)
		return 7;
	for (size_t j = 0; j < ntri; j++)
	{
		uint64_t	h = tri_hash(q + 2 * tri[3 * j], q + 2 * tri[3 * j + 1], q + 2 * tri[3 * j + 2]);

		s->hash += h;
		if (tile >= 0 && tile < TILES_KEPT)
			s->tile_hash[tile] += h;
	}
	if (tile >= 0 && tile < TILES_KEPT)
		s->tile_ntri[tile] += ntri;
	s->ntri += ntri;
	/* A worker sets it while the run's threads read it: atomically. */
	if (s->cancel_at_first)
		__atomic_store_n(s->cancel_at_first, 1, __ATOMIC_RELAXED);
	return 0;
}

static void
trace_cancel(void *arg, const char *line)
{
	tri_sum    *s = arg;

	const char *c = strrchr(line, ':');

	if (s->cancel_at_trace && !__atomic_load_n(s->cancel_at_trace, __ATOMIC_RELAXED))
	{
		__atomic_store_n(s->cancel_at_trace, 1, __ATOMIC_RELAXED);
		s->traced_points = c ? strtoul(c + 1, NULL, 10) : 0;
	}
}

static size_t
huge_peak(void *arg)
{
	(void) arg;
	return (size_t) 1 << 40;
}

/* Files in dir other than keep */
static int
others_in(const char *dir, const char *keep)
{
	DIR		   *d = opendir(dir);
	struct dirent *e;
	int			k = 0;

	if (d == NULL)
		return -1;
	while ((e = readdir(d)) != NULL)
		if (e->d_name[0] != '.' && strcmp(e->d_name, keep) != 0)
			k++;
	closedir(d);
	return k;
}

static int
write_bin(const char *path, const double *xy, size_t n)
{
	FILE	   *f = fopen(path, "wb");

	if (f == NULL)
		return -1;
	if (fwrite(xy, 16, n, f) != n)
	{
		fclose(f);
		return -1;
	}
	return fclose(f);
}

/* One run with these changes to the good params; its status, err and stats. */
static int
run(const tdc_bounded_params *p, tri_sum *s, tdc_bounded_stats *st, char *err, size_t errlen)
{
	tdc_bounded_params q = *p;

	q.arg = s;
	return tdc_bounded_run(&q, st, err, errlen);
}

void
test_bounded(void)
{
	size_t		n = tdc_test_quick ? 120000 : 300000;
	double	   *xy = malloc(16 * n);
	uint64_t	seed = 28;
	char		dir[4096],
				bin[4200],
				err[1024];
	const char *base = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	tdc_options opt;
	tdc_job    *job = NULL;
	tdc_bounded_params p;
	tdc_bounded_stats st;
	tri_sum		one = {0},
				s;
	tdc_iter	it = {0};
	uint32_t	v[3];
	size_t		sites = 0;
	int			rc;

	CHECK(xy != NULL, "bounded: out of memory");
	if (xy == NULL)
		return;
	snprintf(dir, sizeof(dir), "%s/tdc_test_bounded.XXXXXX", base);
	CHECK(mkdtemp(dir) != NULL, "bounded: cannot make a directory in %s", base);
	snprintf(bin, sizeof(bin), "%s/input.bin", dir);
	/* uniform points, with a dense spot and exact copies */
	for (size_t i = 0; i < n; i++)
	{
		xy[2 * i] = tdc_splitmix64(&seed) / 18446744073709551616.0 * 1000;
		xy[2 * i + 1] = tdc_splitmix64(&seed) / 18446744073709551616.0 * 1000;
		if (i % 10 == 3)
		{
			xy[2 * i] = 100 + xy[2 * i] / 1000;
			xy[2 * i + 1] = 200 + xy[2 * i + 1] / 1000;
		}
		if (i % 997 == 5)
		{
			xy[2 * i] = 10;
			xy[2 * i + 1] = 20;
		}
	}
	CHECK(write_bin(bin, xy, n) == 0, "bounded: cannot write %s", bin);

	/* the one-shot triangle set */
	tdc_options_init(&opt);
	rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "bounded: one-shot run: %s", err);
	if (rc != TDC_OK)
		goto out;
	while (tdc_next_triangle(job, &it, v))
	{
		one.hash += tri_hash(tdc_site_xy(job, v[0]), tdc_site_xy(job, v[1]), tdc_site_xy(job, v[2]));
		one.ntri++;
	}
	sites = tdc_num_sites(job);
	tdc_job_free(job);

	memset(&p, 0, sizeof(p));
	p.xypath = bin;
	p.n = n;
	p.opt = &opt;
	p.limit = (size_t) (tdc_test_quick ? 16 : 14) << 20;
	p.tmpdir = dir;
	p.emit = emit_sum;
	p.check_files = true;

	/* tiled: the same set, each triangle once; nothing of the run left (and
	 * each first run's files hold exactly its first region: check_files) */
	memset(&s, 0, sizeof(s));
	rc = run(&p, &s, &st, err, sizeof(err));
	CHECK(rc == TDC_OK, "bounded: run: %d %s", rc, err);
	CHECK(st.tiles > 1, "bounded: %d tiles, more than 1 expected", st.tiles);
	CHECK(s.ntri == one.ntri && st.ntri == one.ntri, "bounded: %zu (stats %zu) triangles, one-shot %zu",
		  s.ntri, st.ntri, one.ntri);
	CHECK(s.hash == one.hash, "bounded: the triangle set differs from the one-shot run's");
	CHECK(st.n == n && st.unique == sites, "bounded: stats n %zu unique %zu, one-shot %zu sites",
		  st.n, st.unique, sites);
	CHECK(others_in(dir, "input.bin") == 0, "bounded: files left in %s", dir);
	CHECK(st.workers == 1, "bounded: %d tile workers in the plan's order, 1 expected", st.workers);

	/*
	 * drop_input: a caller's staged copy of the input is gone once binned
	 * (the tiles' files hold what the runs read), with the same triangles;
	 * without it the input stays (above: input.bin is still there).
	 */
	{
		tdc_bounded_params q = p;
		char		copy[4200];

		snprintf(copy, sizeof(copy), "%s/staged.bin", dir);
		CHECK(write_bin(copy, xy, n) == 0, "bounded: cannot write %s", copy);
		q.xypath = copy;
		q.drop_input = true;
		q.check_files = false;
		memset(&s, 0, sizeof(s));
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_OK && s.hash == one.hash && s.ntri == one.ntri,
			  "bounded: drop_input: %d %s, or another triangle set", rc, err);
		CHECK(access(copy, F_OK) != 0 && access(bin, F_OK) == 0,
			  "bounded: drop_input left the staged copy, or took the other input");
		unlink(copy);
	}

	/*
	 * In any order: two tiles at a time on two threads (each reserving its
	 * share of the limit, the other waiting while it does not fit), and
	 * every tile the same triangles as in the plan's order; with one
	 * engine thread, one worker.  A limit tight enough that two tiles'
	 * models do not always fit at once, so the reservations wait.
	 */
	{
		tdc_bounded_params q = p;
		tdc_options two = opt;
		tri_sum		ordered,	/* one thread: one worker, in the plan's order */
					any;
		tdc_bounded_stats st1;
		bool		same = true;

		two.threads = 1;
		q.opt = &two;
		q.any_order = true;
		/* a limit with room for a second worker's scratch, still several tiles */
		q.limit = (size_t) 40 << 20;
		memset(&ordered, 0, sizeof(ordered));
		rc = run(&q, &ordered, &st1, err, sizeof(err));
		CHECK(rc == TDC_OK && st1.workers == 1 && ordered.hash == one.hash,
			  "bounded: any order, 1 thread: %d, %d workers, same set %d %s", rc, st1.workers,
			  ordered.hash == one.hash, err);
		two.threads = 2;
		memset(&any, 0, sizeof(any));
		rc = run(&q, &any, &st, err, sizeof(err));
		CHECK(rc == TDC_OK, "bounded: any order: %d %s", rc, err);
		CHECK(st.workers == 2, "bounded: any order: %d tile workers, 2 expected", st.workers);
		CHECK(any.ntri == one.ntri && any.hash == one.hash && st.unique == sites,
			  "bounded: any order: %zu triangles (one-shot %zu), same set %d", any.ntri, one.ntri,
			  any.hash == one.hash);
		CHECK(st.tiles_wall > 0 && st.tiles_wall <= st.gather + st.engine + st.finish + st.write + st.wait + 1,
			  "bounded: any order: tiles' wall %g s beside the workers' %g s", st.tiles_wall,
			  st.gather + st.engine + st.finish + st.write + st.wait);
		for (int t = 0; t < st.tiles && t < TILES_KEPT; t++)
			same = same && any.tile_hash[t] == ordered.tile_hash[t] &&
				any.tile_ntri[t] == ordered.tile_ntri[t];
		CHECK(st.tiles == st1.tiles && st.tiles >= 3 && same, "bounded: any order: %d tiles (1 thread %d), "
			  "each the same triangles %d", st.tiles, st1.tiles, same);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: any order: files left in %s", dir);

		/* a cancel in the first emit: nothing emitted after it, by either worker */
		memset(&any, 0, sizeof(any));
		any.cancel_at_first = &any.cancel;
		q.cancel = &any.cancel;
		q.check_files = false;
		rc = run(&q, &any, &st, err, sizeof(err));
		CHECK(rc == TDC_ECANCELED && any.calls == 1 && strcmp(err, "canceled") == 0,
			  "bounded: any order, cancel after a tile: %d (%zu calls) %s", rc, any.calls, err);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: any order, cancel: files left");
		q.cancel = NULL;

		/* emit refusing a tile: the run's error, whichever worker met it */
		memset(&any, 0, sizeof(any));
		any.refuse_at = 3;
		rc = run(&q, &any, &st, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && strstr(err, "emit returned 7") != NULL && any.calls == 3,
			  "bounded: any order, emit refuses: %d (%zu calls) %s", rc, any.calls, err);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: any order, emit refuses: files left");

	}
	p.check_files = false;

	/*
	 * The bin on two threads needs two sets of tile files open at once:
	 * with a soft limit of 1,024 open files a plan of over 200 tiles bins
	 * on one, with room for them on two (bounded_bin.c, files_room), and
	 * the triangles are the same.  A million uniform points under a limit
	 * that makes small tiles (not in --quick).
	 */
	if (n >= ((size_t) 1 << 18))
	{
		tdc_bounded_params q = p;
		struct rlimit old,
					lim;
		int			threads[2] = {0, 0},
					tiles = 0;
		bool		same = true;
		size_t		un = 1000000;
		double	   *u = malloc(16 * un);
		char		ubin[4200];
		tri_sum		uone = {0};

		CHECK(u != NULL, "bounded: out of memory");
		if (u == NULL)
			goto out;
		for (size_t i = 0; i < 2 * un; i++)
			u[i] = tdc_splitmix64(&seed) / 18446744073709551616.0 * 1000;
		snprintf(ubin, sizeof(ubin), "%s/uniform.bin", dir);
		CHECK(write_bin(ubin, u, un) == 0, "bounded: cannot write %s", ubin);
		rc = tdc_triangulate(u, un, &opt, &job, err, sizeof(err));
		CHECK(rc == TDC_OK, "bounded: one-shot run of uniform points: %s", err);
		memset(&it, 0, sizeof(it));
		while (rc == TDC_OK && tdc_next_triangle(job, &it, v))
		{
			uone.hash += tri_hash(tdc_site_xy(job, v[0]), tdc_site_xy(job, v[1]), tdc_site_xy(job, v[2]));
			uone.ntri++;
		}
		tdc_job_free(job);
		job = NULL;
		free(u);
		q.xypath = ubin;
		q.n = un;
		q.limit = (size_t) 10 << 20;
		CHECK(getrlimit(RLIMIT_NOFILE, &old) == 0, "bounded: getrlimit");
		for (int k = 0; k < 2; k++)
		{
			lim = old;
			lim.rlim_cur = k == 0 ? 1024 :
				(old.rlim_max == RLIM_INFINITY || old.rlim_max > 8192 ? 8192 : old.rlim_max);
			if (setrlimit(RLIMIT_NOFILE, &lim) != 0)
				continue;
			memset(&s, 0, sizeof(s));
			rc = run(&q, &s, &st, err, sizeof(err));
			CHECK(rc == TDC_OK, "bounded: bin threads, soft limit %llu: %d %s",
				  (unsigned long long) lim.rlim_cur, rc, err);
			same = same && s.hash == uone.hash && s.ntri == uone.ntri;
			threads[k] = st.bin_threads;
			tiles = st.tiles;
		}
		setrlimit(RLIMIT_NOFILE, &old);
		printf("bounded: %d tiles binned on %d thread(s) under a soft limit of 1024 open files, "
			   "on %d with %llu\n", tiles, threads[0], threads[1], (unsigned long long) lim.rlim_cur);
		CHECK(tiles > 200 && tiles <= 400, "bounded: bin threads: %d tiles, 201 to 400 wanted", tiles);
		CHECK(threads[0] == 1, "bounded: %d bin threads under 1024 open files, 1 expected", threads[0]);
		CHECK(threads[1] == 2 || lim.rlim_cur < 2 * 2 * (rlim_t) tiles + 1224,
			  "bounded: %d bin threads with room for the files, 2 expected", threads[1]);
		CHECK(same, "bounded: bin threads: another triangle set than the one-shot run's");
		unlink(ubin);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: bin threads: files left in %s", dir);
	}

	/* canceled before it starts */
	memset(&s, 0, sizeof(s));
	s.cancel = 1;
	p.cancel = &s.cancel;
	rc = run(&p, &s, &st, err, sizeof(err));
	CHECK(rc == TDC_ECANCELED && s.calls == 0, "bounded: preset cancel: %d %s", rc, err);
	CHECK(others_in(dir, "input.bin") == 0, "bounded: preset cancel: files left");

	/* canceled after the first tile's triangles */
	memset(&s, 0, sizeof(s));
	s.cancel_at_first = &s.cancel;
	rc = run(&p, &s, &st, err, sizeof(err));
	CHECK(rc == TDC_ECANCELED && s.calls == 1, "bounded: cancel after a tile: %d (%zu calls) %s",
		  rc, s.calls, err);
	CHECK(others_in(dir, "input.bin") == 0, "bounded: cancel after a tile: files left");

	/*
	 * canceled while the first tile is gathered (trace comes between the
	 * gathering and the engine): the engine's run is stopped, not
	 * finished, so no engine time is counted and nothing is emitted.
	 * (Tiles big enough for the engine's threads: below TDC_INLINE_MAX
	 * points it runs inline, to the end.)
	 */
	{
		tdc_bounded_params q = p;

		q.limit = (size_t) 40 << 20;
		memset(&s, 0, sizeof(s));
		s.cancel_at_trace = &s.cancel;
		q.trace = trace_cancel;
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(s.traced_points > TDC_INLINE_MAX, "bounded: the first tile has %zu points, too few to test",
			  s.traced_points);
		CHECK(rc == TDC_ECANCELED && s.calls == 0 && st.runs == 1 && st.engine == 0,
			  "bounded: cancel in a tile's engine run: %d (%zu calls, %zu runs, engine %g s) %s",
			  rc, s.calls, st.runs, st.engine, err);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: cancel in the engine: files left");
	}
	p.cancel = NULL;

	/* on a thread of its own (tdc_bounded_start): the same set; a cancel; its own flag */
	{
		tdc_bounded_job *bj = NULL;
		tdc_bounded_params q = p;

		memset(&s, 0, sizeof(s));
		q.arg = &s;
		rc = tdc_bounded_start(&q, &bj, err, sizeof(err));
		CHECK(rc == TDC_OK, "bounded job: start: %d %s", rc, err);
		if (rc == TDC_OK)
		{
			rc = tdc_bounded_wait(bj, -1);
			CHECK(rc == TDC_OK && s.ntri == one.ntri && s.hash == one.hash &&
				  tdc_bounded_stats_of(bj)->ntri == one.ntri,
				  "bounded job: %d, %zu triangles, one-shot %zu, same set %d: %s", rc, s.ntri, one.ntri,
				  s.hash == one.hash, tdc_bounded_error(bj));
			tdc_bounded_free(bj);
		}
		memset(&s, 0, sizeof(s));
		rc = tdc_bounded_start(&q, &bj, err, sizeof(err));
		if (rc == TDC_OK)
		{
			tdc_bounded_cancel(bj);
			rc = tdc_bounded_wait(bj, -1);
			CHECK(rc == TDC_ECANCELED && strcmp(tdc_bounded_error(bj), "canceled") == 0,
				  "bounded job: canceled: %d %s", rc, tdc_bounded_error(bj));
			tdc_bounded_free(bj);
		}
		CHECK(others_in(dir, "input.bin") == 0, "bounded job: files left");
		/* freed while it runs: canceled and joined, its files removed */
		rc = tdc_bounded_start(&q, &bj, err, sizeof(err));
		if (rc == TDC_OK)
			tdc_bounded_free(bj);
		CHECK(others_in(dir, "input.bin") == 0, "bounded job: freed while running: files left");
		q.cancel = &s.cancel;
		rc = tdc_bounded_start(&q, &bj, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && bj == NULL, "bounded job: a cancel of the caller's: %d %s", rc, err);
	}

	/* emit refuses the second tile */
	memset(&s, 0, sizeof(s));
	s.refuse_at = 2;
	rc = run(&p, &s, &st, err, sizeof(err));
	CHECK(rc == TDC_EINVAL && strstr(err, "emit returned 7") != NULL, "bounded: emit refuses: %d %s",
		  rc, err);
	CHECK(others_in(dir, "input.bin") == 0, "bounded: emit refuses: files left");

	/* a directory that is not there */
	{
		tdc_bounded_params q = p;
		char		gone[4300];

		snprintf(gone, sizeof(gone), "%s/not-there", dir);
		q.tmpdir = gone;
		memset(&s, 0, sizeof(s));
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_EIO && strstr(err, "cannot open temporary file") != NULL,
			  "bounded: no directory: %d %s", rc, err);
	}

	/* below the floor: refused before any file, the limit named as asked */
	{
		tdc_bounded_params q = p;

		q.limit = (size_t) 3 << 20;
		q.limit_name = "tdc.test_limit";
		memset(&s, 0, sizeof(s));
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_EMEMLIMIT && strncmp(err, "tdc.test_limit 3 is below this input's floor of ", 48) == 0,
			  "bounded: below the floor: %d %s", rc, err);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: below the floor: files left");
	}

	/* a peak above the limit before the first tile */
	{
		tdc_bounded_params q = p;

		q.peak = huge_peak;
		memset(&s, 0, sizeof(s));
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_EMEMLIMIT && strstr(err, "this run held before its first tile") != NULL &&
			  s.calls == 0, "bounded: peak: %d %s", rc, err);
		CHECK(others_in(dir, "input.bin") == 0, "bounded: peak: files left");
	}

	/* a source shorter than n */
	{
		tdc_bounded_params q = p;

		q.n = n + 1;
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && strstr(err, "fewer than the") != NULL, "bounded: short source: %d %s",
			  rc, err);
	}

	/* a tolerance, and a NaN */
	{
		tdc_bounded_params q = p;
		tdc_options tol = opt;

		tol.tolerance = 0.5;
		q.opt = &tol;
		rc = run(&q, &s, &st, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && strstr(err, "tolerance") != NULL, "bounded: tolerance: %d %s", rc, err);
	}
	xy[2 * (n - 7) + 1] = NAN;
	CHECK(write_bin(bin, xy, n) == 0, "bounded: cannot write %s", bin);
	memset(&s, 0, sizeof(s));
	rc = run(&p, &s, &st, err, sizeof(err));
	CHECK(rc == TDC_EINVAL && strstr(err, "non-finite") != NULL && s.calls == 0,
		  "bounded: NaN: %d %s", rc, err);
	CHECK(others_in(dir, "input.bin") == 0, "bounded: NaN: files left");

out:
	unlink(bin);
	rmdir(dir);
	free(xy);
}
