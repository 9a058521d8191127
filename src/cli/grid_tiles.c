/*
 * grid_tiles.c
 *		./tdc --grid under --max-memory when the one-shot run does not fit:
 *		the core's bounded run (tdc_bounded_run) with its final triangles
 *		rasterised as each tile hands them over (tdc_raster_*, the core's
 *		terrain/raster.c), then the grid written by rows as the one-shot
 *		run writes it (tin_out.c): the same ESRI ASCII text, byte for byte,
 *		and a GeoTIFF with the same pixels.
 *
 * The grid's geometry needs the data's box when no --extent is given, and
 * the core's raster the hull: both come from the run's first pass (the
 * begin callback), before the plan.  What the grid holds from then on
 * (its window of rows, the rows on their way out, and GDAL's block cache
 * for a GeoTIFF) is handed back as `hold`, which the run takes off the
 * tiles' budget, so that the peak stays under the limit with the output's
 * buffers counted.  The rows come out after the last tile, when the
 * tiles' memory is free again; the sites that pixels outside the hull may
 * take are loaded then, within what the limit leaves.
 *
 * The two tile workers hand their tiles over at once (emit_concurrent):
 * the raster takes each in a window of its own, and the pixels of two
 * tiles are disjoint but for centres on their shared edges, which both
 * write with the same bits; so neither waits for the other's pixels.
 *
 * Natural neighbour takes each final tile's whole triangulation through
 * the run's final_run (terrain/raster_natural.c proves each pixel's
 * cavity global, or the tile runs again with a larger box).
 * --contours in tiles is contours_tiles.c.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"

#define OUT_ROWS	256			/* rows a write: one GeoTIFF block's height */

typedef struct grid_tiles
{
	const cli_args *a;
	tdc_interp_spec spec;
	tdc_grid_spec g;
	double		box[4];
	tdc_raster *ras;
	bool		tif;
	pthread_mutex_t mu;			/* err, for emits on both workers */
	char		err[1024];		/* a callback's failure, said in full */
} grid_tiles;

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
	grid_tiles *gt = arg;
	size_t		h = 0;
	int			rc;

	if (grid_geometry(gt->a, box, &gt->g, gt->box, gt->err, sizeof(gt->err)) != 0)
		return TDC_EINVAL;
	/* two tiles at once: the run's emit_concurrent */
	if ((rc = tdc_raster_begin(&gt->spec, &gt->g, hull, nhull, tmp_dir, 2, &gt->ras, &h,
							   gt->err, sizeof(gt->err))) != TDC_OK)
		return rc;
	*hold = h + 8 * gt->g.width * (gt->g.height < OUT_ROWS ? gt->g.height : OUT_ROWS) +
		(gt->tif ? GTIFF_HOLD(gt->a->opt.threads) : 0);
	return TDC_OK;
}

static int
emit(void *arg, int tile, const double *q, const double *qz, const int64_t *ql,
	 const size_t *tri, size_t ntri)
{
	grid_tiles *gt = arg;
	char		err[1024];
	int			rc;

	(void) tile;
	(void) ql;
	if (gt->spec.method == TDC_INTERP_NATURAL)
		return 0;				/* final_run took the tile's pixels */
	/* both workers' tiles at once (emit_concurrent): the first failure is said */
	if ((rc = tdc_raster_tile(gt->ras, q, qz, tri, ntri, err, sizeof(err))) != TDC_OK)
		keep_first_error(&gt->mu, gt->err, sizeof(gt->err), err);
	return rc;
}

/* natural neighbour: the tile's pixels from its whole triangulation, or what it needs more */
static int
final_run(void *arg, const tdc_job *job, const double *q, const double *qz, size_t m,
		  const size_t *tri, size_t ntri, const tdc_tile_spec *spec, tdc_tile_result *more)
{
	grid_tiles *gt = arg;

	return tdc_raster_nn_tile(gt->ras, job, q, qz, m, tri, ntri, spec, more, gt->err,
							  sizeof(gt->err));
}

/* The grid's rows, from the raster to the .asc or the GeoTIFF; dies on errors. */
static size_t
write_rows(grid_tiles *gt, const char *srs, gtiff_out *tif, size_t left)
{
	const cli_args *a = gt->a;
	size_t		w = gt->g.width,
				hgt = gt->g.height,
				valid = 0;
	double	   *v = malloc(8 * w * (hgt < OUT_ROWS ? hgt : OUT_ROWS) + 8);
	FILE	   *f = NULL;
	char		err[1024];

	if (v == NULL)
		die(1, "out of memory for the grid's rows%s", "");
	if (tif && gtiff_open(tif, w, hgt, gt->g.gt, srs, gt->spec.nodata, a->float32, a->opt.threads,
						  err, sizeof(err)) != 0)
	{
		gtiff_discard(tif);
		die(1, "%s", err);
	}
	if (!tif && a->outpath)
	{
		f = strcmp(a->outpath, "-") == 0 ? stdout : fopen(a->outpath, "w");
		if (f == NULL)
			die(1, "cannot write %s", a->outpath);
		asc_header(f, &gt->g, gt->box, gt->spec.nodata);
	}
	for (size_t y = 0; y < hgt; y += OUT_ROWS)
	{
		size_t		n = hgt - y < OUT_ROWS ? hgt - y : OUT_ROWS;

		if (cli_cancel)
		{
			if (tif)
				gtiff_discard(tif);
			die(1, "%s", "canceled");
		}
		if (tdc_raster_rows(gt->ras, y, n, v, &valid, left, err, sizeof(err)) != TDC_OK)
		{
			if (tif)
				gtiff_discard(tif);
			die(1, "%s", err);
		}
		if (tif && gtiff_write_rows(tif, y, n, v, err, sizeof(err)) != 0)
		{
			gtiff_discard(tif);
			die(1, "%s", err);
		}
		if (f)
			asc_rows(f, v, w, n);
	}
	if (tif && gtiff_close(tif, err, sizeof(err)) != 0)
		die(1, "%s", err);
	if (f && (f != stdout ? fclose(f) != 0 : fflush(f) != 0))
		die(1, "error writing %s", a->outpath);
	free(v);
	return valid;
}

/*
 * --grid in tiles: the staged input (xypath, zpath: its heights), srs the
 * input's CRS (or NULL), tif tin_output_prepare's.  Writes -o and, with
 * --stats, the run's line and the grid's; dies on errors.
 */
void
grid_in_tiles(const cli_args *a, const char *xypath, const char *zpath, size_t n, const char *srs,
			  gtiff_out *tif)
{
	grid_tiles	gt = {.a = a, .tif = tif != NULL};
	size_t		limit = (size_t) a->max_mb << 20,
				start,
				valid,
				held;
	tdc_bounded_params p = {
		.xypath = xypath, .zpath = zpath, .n = n, .opt = &a->opt, .limit = limit,
		.tmpdir = tmp_dir, .limit_name = "--max-memory",
		.begin = begin, .emit = emit, .settle = heap_settle, .peak = heap_peak, .arg = &gt,
		.cancel = &cli_cancel, .any_order = true, .emit_concurrent = true,
		.drop_input = tmp_owns(xypath)	/* the staged input: its disk goes to the tiles */
	};
	tdc_bounded_stats st;
	char		err[1024];
	double		t0,
				t1,
				t2;

	pthread_mutex_init(&gt.mu, NULL);
	if (zpath == NULL)
		die(1, "--grid needs heights: 'x y z' text, LAS or .xyz.bin input%s", "");
	if (tdc_interp_parse(a->method ? a->method : "linear", &gt.spec, err, sizeof(err)) != TDC_OK)
		die(2, "--method: %s", err);
	if (gt.spec.method == TDC_INTERP_NATURAL)
	{
		p.final_run = final_run;
		p.final_per_point = TDC_RASTER_NN_PER_POINT;
		p.final_run_why = TDC_RASTER_NN_WHY;
	}
	if (n == 0)
		die(1, "--grid needs an --extent when the input has no point%s", "");
	p.outside = start = heap_start(limit);
	t0 = now_s();
	if (tdc_bounded_run(&p, &st, err, sizeof(err)) != TDC_OK)
	{
		tdc_raster_free(gt.ras);
		if (tif)
			gtiff_discard(tif);
		die(1, "%s", gt.err[0] ? gt.err : err);
	}
	t1 = now_s();
	/* the tiles are gone: what the limit leaves beside the grid's buffers is the fringe's */
	held = start + 8 * gt.g.width * (gt.g.height < OUT_ROWS ? gt.g.height : OUT_ROWS) +
		((size_t) 8 << 20) + (tif ? GTIFF_HOLD(a->opt.threads) : 0);
	valid = write_rows(&gt, srs, tif, limit > held ? limit - held : 0);
	t2 = now_s();
	tdc_raster_free(gt.ras);
	if (a->stats)
	{
		tiles_stats_line(&st, t1 - t0);
		fprintf(stderr, "grid=%.6f pixels=%zu valid=%zu\n", t2 - t1, gt.g.width * gt.g.height, valid);
	}
}
