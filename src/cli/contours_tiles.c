/*
 * contours_tiles.c
 *		./tdc --contours under --max-memory when the one-shot run does not
 *		fit: the core's bounded run (tdc_bounded_run) with each tile's final
 *		triangles cut into pieces of contour lines as it hands them over
 *		(tdc_contour_tiles_*, the core's terrain/contour_tiles.c), then the
 *		pieces joined and the lines written as the one-shot run writes them
 *		(tin_out.c): the same text, byte for byte.
 *
 * The contours' buffers are made in the begin callback and handed back as
 * `hold`, which the run takes off the tiles' budget.  The lines come out
 * after the last tile, when the tiles' memory is free again: the join and
 * one level's lines at a time get what the limit leaves beside what the
 * process holds, and say so when that is too little.  The output file is
 * opened only then, and removed again if the join fails, so a failed run
 * leaves no half file (the one-shot run writes nothing either).  The two
 * tile workers hand their tiles over at once (emit_concurrent): the
 * pieces of each are made on its worker, and only their writing waits.
 */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

typedef struct contours_tiles
{
	const cli_args *a;
	tdc_interp_spec spec;
	tdc_contour_tiles *ct;
	FILE	   *f;
	pthread_mutex_t mu;			/* err, for emits on both workers */
	char		err[1024];		/* a callback's failure, said in full */
} contours_tiles;

static double
now_s(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

static int
begin(void *arg, const double box[4], const double *hull, size_t nhull, size_t *hold)
{
	contours_tiles *ct = arg;

	(void) box;
	(void) hull;
	(void) nhull;
	/* two tiles at once: the run's emit_concurrent */
	return tdc_contour_tiles_begin(ct->a->contour_interval, ct->a->contour_base, &ct->spec,
								   tmp_dir, 2, &ct->ct, hold, ct->err, sizeof(ct->err));
}

static int
emit(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
	 const size_t *tri, size_t ntri)
{
	contours_tiles *ct = arg;
	char		err[1024];
	int			rc;

	(void) tile;
	(void) ql;
	/* both workers' tiles at once (emit_concurrent): the first failure is said */
	if ((rc = tdc_contour_tiles_tile(ct->ct, q, qz, tri, ntri, err, sizeof(err))) != TDC_OK)
		keep_first_error(&ct->mu, ct->err, sizeof(ct->err), err);
	return rc;
}

/* One line, as tin_out.c writes it: the level, then its points, %.17g. */
static int
line_out(void *arg, double level, const double *xy, size_t n, bool closed)
{
	FILE	   *f = arg;

	(void) closed;
	contour_line(f, level, xy, n);
	return ferror(f) ? TDC_EIO : 0;
}

/* Counts only: no -o. */
static int
line_count(void *arg, double level, const double *xy, size_t n, bool closed)
{
	(void) arg;
	(void) level;
	(void) xy;
	(void) n;
	(void) closed;
	return 0;
}

/*
 * --contours in tiles: the staged input (xypath, zpath: its heights).
 * Writes -o and, with --stats, the run's line and the contours'; dies on
 * errors.
 */
void
contours_in_tiles(const cli_args *a, const char *xypath, const char *zpath, size_t n)
{
	contours_tiles ct = {.a = a};
	size_t		limit = (size_t) a->max_mb << 20,
				start,
				held,
				nlines = 0,
				npoints = 0;
	tdc_bounded_params p = {
		.xypath = xypath, .zpath = zpath, .n = n, .opt = &a->opt, .limit = limit,
		.tmpdir = tmp_dir, .limit_name = "--max-memory",
		.begin = begin, .emit = emit, .settle = heap_settle, .peak = heap_peak, .arg = &ct,
		.cancel = &cli_cancel, .any_order = true, .emit_concurrent = true,
		.drop_input = tmp_owns(xypath)	/* the staged input: its disk goes to the tiles */
	};
	tdc_bounded_stats st;
	char		err[1024];
	double		t0,
				t1,
				t2;
	int			rc;
	bool		to_file = a->outpath && strcmp(a->outpath, "-") != 0;

	pthread_mutex_init(&ct.mu, NULL);
	if (zpath == NULL)
		die(1, "--contours needs heights: 'x y z' text, LAS or .xyz.bin input%s", "");
	if (tdc_interp_parse(a->method ? a->method : "linear", &ct.spec, err, sizeof(err)) != TDC_OK)
		die(2, "--method: %s", err);
	p.outside = start = heap_start(limit);
	t0 = now_s();
	if (tdc_bounded_run(&p, &st, err, sizeof(err)) != TDC_OK)
	{
		tdc_contour_tiles_free(ct.ct);
		die(1, "%s", ct.err[0] ? ct.err : err);
	}
	t1 = now_s();
	/* the tiles are gone: the join gets what the limit leaves beside the process and a margin */
	held = start + ((size_t) 8 << 20);
	if (a->outpath)
	{
		ct.f = to_file ? fopen(a->outpath, "w") : stdout;
		if (ct.f == NULL)
		{
			tdc_contour_tiles_free(ct.ct);
			die(1, "cannot write %s", a->outpath);
		}
	}
	err[0] = '\0';
	rc = ct.ct == NULL ? TDC_OK :
		tdc_contour_tiles_lines(ct.ct, limit > held ? limit - held : 0,
								ct.f ? line_out : line_count, ct.f, &cli_cancel,
								&nlines, &npoints, err, sizeof(err));
	tdc_contour_tiles_free(ct.ct);
	if (ct.f && (ct.f != stdout ? fclose(ct.f) != 0 : fflush(ct.f) != 0) && rc == TDC_OK)
	{
		if (to_file)
			unlink(a->outpath);
		die(1, "error writing %s", a->outpath);
	}
	if (rc != TDC_OK)
	{
		if (to_file)
			unlink(a->outpath);
		die(1, "%s", rc == TDC_EIO && ct.f && !err[0] ? "error writing the contour lines" : err);
	}
	t2 = now_s();
	if (a->stats)
	{
		tiles_stats_line(&st, t1 - t0);
		fprintf(stderr, "contours=%.6f lines=%zu contour_points=%zu\n", t2 - t1, nlines, npoints);
	}
}
