/*
 * test_contour_tiles.c
 *		Contour lines in tiles (tdc_contour_tiles_*,
 *		src/core/terrain/contour_tiles.c and contour_join.c): the lines
 *		joined from a bounded run's final triangles are the whole TIN's
 *		(tdc_tin_contours_start_spec): the same count, and line by line the
 *		same level, the same closing, the same points bit for bit, in the
 *		same order.
 *
 *	- uniform samples on a smooth surface: several intervals and bases,
 *	  max_edge, 1 and 2 threads;
 *	- "lattice on the levels": integer heights on a unit lattice with an
 *	  interval of 1, so that crossings fall on sites and whole edges lie
 *	  on levels (the repeats, the ridges along a level), with a lake of no
 *	  samples cut open by max_edge;
 *	- "projected offset": around (500000, 4000000), where the crossings'
 *	  roundings are largest;
 *	- "clusters": dense spots in a sparse field, tiles of unequal sizes;
 *	- every case in at least 8 tiles (the run's stats say), nothing left in
 *	  the directory; an interval too small for the heights refused with
 *	  the one-shot's message; a join, or a level's lines, that would not
 *	  fit in what the limit leaves refused with the numbers.
 * Comparing counts alone would pass with a wrong ring start or a wrong
 * join; every point of every line is compared.
 */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"
#include "tiles_test.h"

typedef struct ctt_case
{
	const char *name;
	double	   *xy,
			   *z;
	size_t		n;
	size_t		limit_mb;
	int			workers;		/* 2: two tile workers expected with 2 threads (0: one or two) */
} ctt_case;

/* The lines, as either side gives them: levels, lengths, closings, all points. */
typedef struct ctt_lines
{
	double	   *level;
	size_t	   *n;
	bool	   *closed;
	size_t		nlines,
				lcap;
	double	   *xy;
	size_t		npts,
				pcap;
} ctt_lines;

typedef struct ctt_state
{
	double		interval,
				base;
	tdc_interp_spec spec;
	const char *dir;
	tdc_contour_tiles *ct;
	char		err[512];
} ctt_state;

static int
add_line(void *arg, double level, const double *xy, size_t n, bool closed)
{
	ctt_lines  *l = arg;

	if (l->nlines == l->lcap)
	{
		l->lcap = l->lcap ? 2 * l->lcap : 64;
		l->level = realloc(l->level, l->lcap * sizeof(double));
		l->n = realloc(l->n, l->lcap * sizeof(size_t));
		l->closed = realloc(l->closed, l->lcap * sizeof(bool));
	}
	while (l->npts + n > l->pcap)
	{
		l->pcap = l->pcap ? 2 * l->pcap : 1024;
		l->xy = realloc(l->xy, l->pcap * 16);
	}
	l->level[l->nlines] = level;
	l->n[l->nlines] = n;
	l->closed[l->nlines] = closed;
	l->nlines++;
	memcpy(l->xy + 2 * l->npts, xy, n * 16);
	l->npts += n;
	return 0;
}

static void
lines_free(ctt_lines *l)
{
	free(l->level);
	free(l->n);
	free(l->closed);
	free(l->xy);
	memset(l, 0, sizeof(*l));
}

static int
ctt_begin(void *arg, const double box[4], const double *hull, size_t nhull, size_t *hold)
{
	ctt_state  *s = arg;

	(void) box;
	(void) hull;
	(void) nhull;
	return tdc_contour_tiles_begin(s->interval, s->base, &s->spec, s->dir, 2, &s->ct, hold,
								   s->err, sizeof(s->err));
}

static int
ctt_emit(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
		 const size_t *tri, size_t ntri)
{
	ctt_state  *s = arg;

	(void) tile;
	(void) ql;
	return tdc_contour_tiles_tile(s->ct, q, qz, tri, ntri, s->err, sizeof(s->err));
}

/* The whole TIN's lines; the return code, the message in err. */
static int
whole_lines(const ctt_case *c, const ctt_state *s, int threads, ctt_lines *out, char *err,
			size_t errlen)
{
	tdc_options opt;
	tdc_job    *job = NULL;
	tdc_tin    *tin = NULL;
	int			rc;

	tdc_options_init(&opt);
	opt.threads = threads;
	err[0] = '\0';
	rc = tdc_triangulate(c->xy, c->n, &opt, &job, err, errlen);
	if (rc == TDC_OK)
		rc = tdc_tin_build(job, c->z, threads, 0, &tin, err, errlen);
	if (rc == TDC_OK)
		rc = tdc_tin_contours_start_spec(tin, s->interval, s->base, &s->spec, err, errlen);
	if (rc == TDC_OK)
		rc = tdc_tin_wait(tin, -1);
	if (rc == TDC_OK)
	{
		size_t		nl = tdc_tin_contour_count(tin, NULL);

		for (size_t i = 0; i < nl; i++)
		{
			double		level;
			size_t		n;
			bool		closed;
			const double *xy = tdc_tin_contour_line(tin, i, &level, &n, &closed);

			add_line(out, level, xy, n, closed);
		}
	}
	if (tin)
		tdc_tin_free(tin);
	if (job)
		tdc_job_free(job);
	return rc;
}

/* The lines in tiles; the return code, the message in err, the tiles in *tiles. */
static int
tiled_lines(const ctt_case *c, ctt_state *s, const char *dir, int threads, size_t max_bytes,
			ctt_lines *out, int *tiles, char *err, size_t errlen)
{
	char		xyp[4200],
				zp[4200];
	tdc_options opt;
	tdc_bounded_params p;
	tdc_bounded_stats st;
	size_t		nl,
				np;
	int			rc;

	snprintf(xyp, sizeof(xyp), "%s/input.xy", dir);
	snprintf(zp, sizeof(zp), "%s/input.z", dir);
	tdc_options_init(&opt);
	opt.threads = threads;
	memset(&p, 0, sizeof(p));
	memset(&st, 0, sizeof(st));
	p.xypath = xyp;
	p.zpath = zp;
	p.n = c->n;
	p.opt = &opt;
	p.limit = c->limit_mb << 20;
	p.tmpdir = dir;
	p.begin = ctt_begin;
	p.emit = ctt_emit;
	p.arg = s;
	/*
	 * as ./tdc: the output does not depend on the tiles' order, so two run
	 * at once and hand their tiles over at once (a failure's message is
	 * the only thing two emits could both write, in s->err)
	 */
	p.any_order = true;
	p.emit_concurrent = true;
	s->dir = dir;
	s->ct = NULL;
	s->err[0] = '\0';
	err[0] = '\0';
	rc = tdc_bounded_run(&p, &st, err, errlen);
	*tiles = st.tiles;
	/* one worker with one thread; two where the case makes room for them (else one or two) */
	CHECK(rc != TDC_OK || (threads < 2 ? st.workers == 1 : c->workers == 2 ? st.workers == 2 :
						   st.workers >= 1 && st.workers <= 2),
		  "contours %s in tiles: %d workers with %d threads", c->name, st.workers, threads);
	if (rc == TDC_OK)
		rc = tdc_contour_tiles_lines(s->ct, max_bytes, add_line, out, NULL, &nl, &np,
									 err, errlen);
	if (rc == TDC_OK)
		CHECK(nl == out->nlines && np == out->npts, "contours in tiles %s: counted %zu lines "
			  "%zu points, handed %zu %zu", c->name, nl, np, out->nlines, out->npts);
	else if (s->err[0])
		snprintf(err, errlen, "%s", s->err);
	tdc_contour_tiles_free(s->ct);
	s->ct = NULL;
	return rc;
}

/* One case, one interval, base and method: every line the same. */
static void
compare(const ctt_case *c, double interval, double base, const char *method, const char *dir,
		int threads)
{
	ctt_state	s = {.interval = interval, .base = base};
	ctt_lines	a = {0},
				b = {0};
	char		err[1024];
	int			tiles = 0,
				rc;

	CHECK(tdc_interp_parse(method, &s.spec, err, sizeof(err)) == TDC_OK, "contours: parse %s", method);
	rc = whole_lines(c, &s, threads, &a, err, sizeof(err));
	CHECK(rc == TDC_OK, "contours %s: the whole TIN's: %d %s", c->name, rc, err);
	rc = tiled_lines(c, &s, dir, threads, (size_t) 64 << 20, &b, &tiles, err, sizeof(err));
	CHECK(rc == TDC_OK, "contours %s: in tiles: %d %s", c->name, rc, err);
	/* the sanitizers' --quick inputs are smaller: fewer tiles */
	CHECK(tiles >= (tdc_test_quick || c->workers > 1 ? 3 : 8), "contours %s %s: %d tiles, at least %d expected",
		  c->name, method, tiles, tdc_test_quick || c->workers > 1 ? 3 : 8);
	CHECK(a.nlines > 10, "contours %s %s every %g: only %zu lines", c->name, method, interval,
		  a.nlines);
	CHECK(a.nlines == b.nlines && a.npts == b.npts, "contours %s %s every %g from %g (%d threads): "
		  "%zu lines of %zu points in tiles, %zu of %zu whole", c->name, method, interval, base,
		  threads, b.nlines, b.npts, a.nlines, a.npts);
	if (a.nlines == b.nlines && a.npts == b.npts)
	{
		size_t		bad = 0,
					first = 0;

		for (size_t i = 0, at = 0; i < a.nlines; at += a.n[i], i++)
			if (a.level[i] != b.level[i] || a.n[i] != b.n[i] || a.closed[i] != b.closed[i] ||
				memcmp(a.xy + 2 * at, b.xy + 2 * at, a.n[i] * 16) != 0)
			{
				if (bad++ == 0)
					first = i;
			}
		CHECK(bad == 0, "contours %s %s every %g from %g (%d threads): %zu of %zu lines differ, the "
			  "first #%zu (level %.17g, %zu points%s in tiles, level %.17g, %zu points%s whole)",
			  c->name, method, interval, base, threads, bad, a.nlines, first,
			  bad ? b.level[first] : 0, bad ? b.n[first] : 0, bad && b.closed[first] ? ", a ring" : "",
			  bad ? a.level[first] : 0, bad ? a.n[first] : 0, bad && a.closed[first] ? ", a ring" : "");
	}
	CHECK(tiles_files_in(dir) == 0, "contours %s %s: files left in %s", c->name, method, dir);
	lines_free(&a);
	lines_free(&b);
}

void
test_contour_tiles(void)
{
	size_t		n = tdc_test_quick ? 60000 : 160000;
	uint64_t	seed = 41;
	const char *tbase = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	char		dir[4096];
	ctt_case	c;

	snprintf(dir, sizeof(dir), "%s/tdc_test_contours.XXXXXX", tbase);
	CHECK(mkdtemp(dir) != NULL, "contours: cannot make a directory in %s", tbase);
	memset(&c, 0, sizeof(c));
	c.xy = malloc(16 * n);
	c.z = malloc(8 * n);

	/* uniform samples on a smooth surface */
	c.name = "uniform";
	c.n = n;
	for (size_t i = 0; i < n; i++)
	{
		c.xy[2 * i] = 1000 * tiles_u01(&seed);
		c.xy[2 * i + 1] = 1000 * tiles_u01(&seed);
		c.z[i] = 50 * sin(c.xy[2 * i] / 90) * cos(c.xy[2 * i + 1] / 70) + tiles_u01(&seed);
	}
	c.limit_mb = 14;
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "contours: cannot stage %s", c.name);
	compare(&c, 5, 0, "linear", dir, 2);
	compare(&c, 1.25, 0.3, "linear", dir, 2);
	compare(&c, 2, 0, "linear:max_edge=6", dir, 2);
	compare(&c, 5, 0, "linear", dir, 1);
	/* room for a second worker's scratch: two tiles at once (bounded_share.c) */
	c.limit_mb = tdc_test_quick ? 24 : 40;
	c.workers = 2;
	compare(&c, 2, 0, "linear", dir, 2);
	c.limit_mb = 14;
	c.workers = 0;

	/* an interval too small for the heights: the one-shot's refusal */
	{
		ctt_state	s = {.interval = 1e-15, .base = 0};
		ctt_lines	a = {0},
					b = {0};
		char		e1[1024],
					e2[1024];
		int			tiles,
					r1,
					r2;

		tdc_interp_parse("linear", &s.spec, e1, sizeof(e1));
		r1 = whole_lines(&c, &s, 2, &a, e1, sizeof(e1));
		r2 = tiled_lines(&c, &s, dir, 2, (size_t) 64 << 20, &b, &tiles, e2, sizeof(e2));
		CHECK(r1 == TDC_EINVAL && r2 == TDC_EINVAL && strcmp(e1, e2) == 0 && b.nlines == 0,
			  "contours: a tiny interval: %d '%s' in tiles, %d '%s' whole", r2, e2, r1, e1);
		CHECK(tiles_files_in(dir) == 0, "contours: a tiny interval: files left in %s", dir);
		lines_free(&a);
		lines_free(&b);
	}

	/*
	 * Too little memory left for the join (4 kB), then for a level's lines:
	 * one level (0.5 between heights of -50 to 51), half its points' bytes
	 * (a chain holds far more than 12 points, so the join itself fits).
	 */
	for (int k = 0; k < 2; k++)
	{
		ctt_state	s = {.interval = k == 0 ? 5 : 100, .base = k == 0 ? 0 : 0.5};
		ctt_lines	a = {0},
					b = {0};
		char		e[1024];
		int			tiles,
					rc;
		size_t		budget = 4096;

		tdc_interp_parse("linear", &s.spec, e, sizeof(e));
		if (k == 1)
		{
			rc = tiled_lines(&c, &s, dir, 2, (size_t) 64 << 20, &a, &tiles, e, sizeof(e));
			CHECK(rc == TDC_OK && a.nlines > 0, "contours: one level: %d %s", rc, e);
			budget = a.npts * 8;
		}
		rc = tiled_lines(&c, &s, dir, 2, budget, &b, &tiles, e, sizeof(e));
		CHECK(rc == TDC_EMEMLIMIT && strstr(e, k == 0 ? "contour chains needs" : "for one level's") &&
			  strstr(e, "raise it") != NULL, "contours: a join in %zu bytes: %d '%s'", budget, rc, e);
		CHECK(tiles_files_in(dir) == 0, "contours: a join short of memory: files left in %s", dir);
		lines_free(&a);
		lines_free(&b);
	}

	/* the projected offset */
	c.name = "projected offset";
	for (size_t i = 0; i < n; i++)
	{
		c.xy[2 * i] += 500000;
		c.xy[2 * i + 1] += 4000000;
	}
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "contours: cannot stage %s", c.name);
	compare(&c, 2.5, 0, "linear", dir, 2);
	compare(&c, 2.5, 0, "linear:max_edge=5", dir, 2);

	/* clusters in a sparse field */
	c.name = "clusters";
	for (size_t i = 0; i < n; i++)
	{
		double		cx = 100 + 200 * (double) (i % 5),
					cy = 150 + 170 * (double) (i % 7 % 5);

		if (i % 10 < 7)
		{
			c.xy[2 * i] = cx + 20 * (tiles_u01(&seed) - 0.5) * (tiles_u01(&seed) + 0.1);
			c.xy[2 * i + 1] = cy + 20 * (tiles_u01(&seed) - 0.5) * (tiles_u01(&seed) + 0.1);
		}
		else
		{
			c.xy[2 * i] = 1000 * tiles_u01(&seed);
			c.xy[2 * i + 1] = 1000 * tiles_u01(&seed);
		}
		c.z[i] = 20 * sin(c.xy[2 * i] / 40) + c.xy[2 * i + 1] * 0.02 + tiles_u01(&seed);
	}
	c.limit_mb = 20;			/* reruns of tiles among the clusters need more than 14 */
	CHECK(tiles_stage(dir, c.xy, c.z, c.n), "contours: cannot stage %s", c.name);
	compare(&c, 1, 0, "linear", dir, 2);
	compare(&c, 1, 0, "linear:max_edge=8", dir, 2);

	/* the lattice on the levels, with a lake */
	{
		size_t		side = tdc_test_quick ? 240 : 400,
					k = 0;

		c.name = "lattice on the levels";
		for (size_t j = 0; j < side; j++)
			for (size_t i = 0; i < side; i++)
			{
				double		dx = (double) i - side / 2.0,
							dy = (double) j - side / 3.0;

				if (dx * dx + dy * dy < 30 * 30 && !(i == side / 2 && j == side / 3))
					continue;	/* the lake, with one sample in it */
				c.xy[2 * k] = (double) i;
				c.xy[2 * k + 1] = (double) j;
				/* integers: sites on levels, runs of equal heights along rows */
				c.z[k] = (double) ((i / 3 + j / 5) % 7) + (double) ((i * j) % 11 == 0);
				k++;
			}
		c.n = k;
		c.limit_mb = 14;
		CHECK(tiles_stage(dir, c.xy, c.z, c.n), "contours: cannot stage %s", c.name);
		compare(&c, 1, 0, "linear", dir, 2);
		compare(&c, 2, 1, "linear", dir, 2);
		compare(&c, 1, 0, "linear:max_edge=1.5", dir, 2);
	}

	{
		char		p[4200];

		snprintf(p, sizeof(p), "%s/input.xy", dir);
		unlink(p);
		snprintf(p, sizeof(p), "%s/input.z", dir);
		unlink(p);
		rmdir(dir);
	}
	free(c.xy);
	free(c.z);
}
