/*
 * tiles.c
 *		./tdc --max-memory when the one-shot run does not fit: the core's
 *		bounded run (tdc_bounded_run, src/core/tiles/bounded*.c) on the staged
 *		.bin input, its triangles written as text.
 *
 * The core runs the phases and the tiles; what belongs to the process
 * stays here: the temporary directory (tmpdir.c), the resident size at the
 * start, the heap's policy and the peak (bounded_mem.c), handed over as
 * `outside` and the settle and peak callbacks, and the output.  Each final
 * tile's triangles are written by emit as the core hands them over, one
 * per line, counter-clockwise, each vertex "x y" (and z with z input),
 * %.17g: the same lines in the same order as when these files were the
 * CLI's.  An error of the run is fatal here (die, with the core's message).
 */
#include <stdio.h>
#include <stdlib.h>

#include <sys/resource.h>

#include "cli.h"

/* What the callbacks share. */
typedef struct tiles_out
{
	FILE	   *out;			/* NULL: no -o */
} tiles_out;

static int
emit_text(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
		  const size_t *tri, size_t ntri)
{
	FILE	   *out = ((tiles_out *) arg)->out;
	g17_line	l;

	(void) tile;
	(void) ql;

	for (size_t j = 0; out && j < ntri; j++)
	{
		const size_t *v = tri + 3 * j;

		g17_line_start(&l, out);
		for (int k = 0; k < 3; k++)
		{
			const double *c = q + 2 * v[k];

			g17_line_num(&l, c[0]);
			g17_line_num(&l, c[1]);
			if (qz)
				g17_line_num(&l, qz[v[k]]);
		}
		g17_line_end(&l);
	}
	return 0;
}

/* TDC_TILE_DEBUG=1: each tile run's region on stderr */
static void
trace(void *arg, const char *line)
{
	(void) arg;
	fprintf(stderr, "%s\n", line);
}

/*
 * The first --stats line of a grid or contours in tiles: the run's counts
 * and phases, total its wall seconds, and the process's peak so far.
 */
void
tiles_stats_line(const tdc_bounded_stats *st, double total)
{
	struct rusage ru;

	getrusage(RUSAGE_SELF, &ru);
	fprintf(stderr, "n=%zu unique=%zu triangles=%zu tiles=%d halo_points=%zu tile_runs=%zu "
			"scan=%.6f bin=%.6f gather=%.6f engine=%.6f finish=%.6f write=%.6f workers=%d wait=%.6f "
			"tiles_wall=%.6f total=%.6f peak_rss_mb=%.1f bin_threads=%d\n", st->n, st->unique, st->ntri,
			st->tiles, st->halo, st->runs, st->scan, st->bin, st->gather, st->engine, st->finish,
			st->write, st->workers, st->wait, st->tiles_wall, total, ru.ru_maxrss / 1024.0,
			st->bin_threads);
}

/*
 * The run in tiles.  xypath/zpath: the .bin source (z beside it for text
 * input with z), in tmp_dir or not.  limit: bytes.  Writes the triangles
 * to out (when not NULL) and the counts and times to st; dies on errors.
 */
void
run_bounded(const char *xypath, const char *zpath, size_t n, const tdc_options *opt,
			size_t limit, FILE *out, tdc_bounded_stats *st)
{
	tiles_out	to = {out};
	tdc_bounded_params p = {
		.xypath = xypath, .zpath = zpath, .n = n, .opt = opt, .limit = limit,
		.tmpdir = tmp_dir, .limit_name = "--max-memory",
		.emit = emit_text, .settle = heap_settle, .peak = heap_peak, .arg = &to,
		.cancel = &cli_cancel
	};
	char		err[1024];

	/* TDC_TILE_CHECK=1 (test/cli.sh): each first run's files checked against its region */
	p.check_files = getenv("TDC_TILE_CHECK") != NULL;
	p.trace = getenv("TDC_TILE_DEBUG") ? trace : NULL;
	/* without -o the order of the tiles shows nowhere: two at a time */
	p.any_order = out == NULL;
	/* a staged copy of the input: its disk goes to the tiles once binned */
	p.drop_input = tmp_owns(xypath);
	/* the heap kept between tiles; what the process holds beside them off the limit */
	p.outside = heap_start(limit);
	if (tdc_bounded_run(&p, st, err, sizeof(err)) != TDC_OK)
		die(1, "%s", err);
}
