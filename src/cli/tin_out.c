/*
 * tin_out.c
 *		./tdc --contours and --grid: the TIN of the input (x y z lines) and
 *		what it is for, written as text GIS tools read, or as a GeoTIFF.
 *
 * The triangulation is the one-shot run's (oneshot.c); the heights are the
 * input's z, a site taking its first input point's (tdc.h).  Then:
 *
 *	--contours INTERVAL [--base B] [--method linear:max_edge=L]	the
 *		contour lines at B + k INTERVAL (tdc_tin_contours_start_spec), one
 *		per line of -o: its level, then its points "x y", %.17g, a closed
 *		ring ending with its first point; with max_edge a line stops where
 *		a triangle with a longer edge begins.
 *	--grid CELLSIZE [--extent XMIN,YMIN,XMAX,YMAX] [--method M]	values at
 *		the pixel centres of a grid of square cells (tdc_tin_grid_start,
 *		GDAL's method syntax: linear, nearest, natural_neighbor and their
 *		options).  The extent defaults to the input's bounding box; the grid
 *		covers it from its lower left corner with ceil(width / CELLSIZE)
 *		columns and ceil(height / CELLSIZE) rows, so its upper left corner is
 *		(XMIN, YMIN + rows CELLSIZE).  An -o ending in .tif or .tiff gets a
 *		GeoTIFF (geotiff.c, which says its layout) with that corner as its
 *		origin, CELLSIZE as its pixel size, the method's nodata, and the CRS
 *		of --srs, else the input's (cli_input.srs), else none (a warning
 *		says so); any other -o an ESRI ASCII grid (.asc), which GDAL reads
 *		(AAIGrid): ncols, nrows, the lower left corner, cellsize and
 *		NODATA_value (the method's nodata), then the rows from the top,
 *		%.17g.  Both hold the same values (Float64; --type Float32 rounds
 *		them to float in the GeoTIFF).
 *
 * A GeoTIFF's temporary file is made before the triangulation
 * (tin_output_prepare), so that an -o that cannot be written, or an
 * input CRS GDAL does not read, fails before the work.
 *
 * Both run on the engine's threads (-t), like the triangulation.  --stats
 * adds one line: "tin= contours= contour_points=" or "tin= grid= pixels=
 * valid=" (seconds and counts).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"

static double
now_s(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

static FILE *
open_out(const char *path)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdout : fopen(path, "w");

	if (f == NULL)
		die(1, "cannot write %s", path);
	return f;
}

static void
close_out(FILE *f, const char *path)
{
	if (f != stdout ? fclose(f) != 0 : fflush(f) != 0)
		die(1, "error writing %s", path);
}

/* Wait for the operation just started (rc), or die with its message. */
static void
wait_op(tdc_tin *tin, int rc, const char *err)
{
	if (rc != TDC_OK)
		die(1, "%s", err);
	if (tdc_tin_wait(tin, -1) != TDC_OK)
		die(1, "%s", tdc_tin_error(tin));
}

/* One line of -o: the level, then the n points "x y", %.17g (fmt_g17.c) */
void
contour_line(FILE *f, double level, const double *xy, size_t n)
{
	g17_line	l;

	g17_line_start(&l, f);
	g17_line_num(&l, level);
	for (size_t k = 0; k < 2 * n; k++)
		g17_line_num(&l, xy[k]);
	g17_line_end(&l);
}

static void
contours(const cli_args *a, tdc_tin *tin, double tin_s)
{
	tdc_interp_spec spec;
	char		err[512];
	double		t0 = now_s(),
				t1;
	size_t		npoints,
				nlines;

	if (tdc_interp_parse(a->method ? a->method : "linear", &spec, err, sizeof(err)) != TDC_OK)
		die(2, "--method: %s", err);
	err[0] = '\0';
	wait_op(tin, tdc_tin_contours_start_spec(tin, a->contour_interval, a->contour_base, &spec,
											 err, sizeof(err)), err);
	t1 = now_s();
	nlines = tdc_tin_contour_count(tin, &npoints);
	if (a->outpath)
	{
		FILE	   *f = open_out(a->outpath);

		for (size_t i = 0; i < nlines; i++)
		{
			double		level;
			size_t		n;
			bool		closed;
			const double *xy = tdc_tin_contour_line(tin, i, &level, &n, &closed);

			contour_line(f, level, xy, n);
		}
		close_out(f, a->outpath);
	}
	if (a->stats)
		fprintf(stderr, "tin=%.6f contours=%.6f lines=%zu contour_points=%zu\n", tin_s, t1 - t0,
				nlines, npoints);
}

/* The grid g of values v to the GeoTIFF reserved as tif; dies on failure. */
static void
write_tif(const cli_args *a, const tdc_grid_spec *g, const double *v, double nodata,
		  const char *srs, gtiff_out *tif)
{
	char		err[1024];

	if (gtiff_open(tif, g->width, g->height, g->gt, srs, nodata, a->float32, a->opt.threads,
				   err, sizeof(err)) != 0 ||
		gtiff_write_rows(tif, 0, g->height, v, err, sizeof(err)) != 0)
	{
		gtiff_discard(tif);
		die(1, "%s", err);
	}
	if (gtiff_close(tif, err, sizeof(err)) != 0)
		die(1, "%s", err);
}

/*
 * The grid's geometry (the header's paragraph above) from the extent, or
 * the box of the input's points; -1 with err when it has too many pixels.
 */
int
grid_geometry(const cli_args *a, const double data_box[4], tdc_grid_spec *g, double box[4],
			  char *err, size_t errlen)
{
	double		cs = a->grid_cell,
				w,
				h;

	memcpy(box, a->has_extent ? a->extent : data_box, 4 * sizeof(double));
	w = ceil((box[2] - box[0]) / cs);
	h = ceil((box[3] - box[1]) / cs);
	if (!(w >= 1))
		w = 1;
	if (!(h >= 1))
		h = 1;
	if (w * h > 4e9)
	{
		snprintf(err, errlen, "--grid: %s pixels are too many", w * h > 1e18 ? "more than 1e18" : "over 4e9");
		return -1;
	}
	g->width = (size_t) w;
	g->height = (size_t) h;
	g->gt[0] = box[0];
	g->gt[1] = cs;
	g->gt[2] = 0;
	g->gt[3] = box[1] + h * cs;
	g->gt[4] = 0;
	g->gt[5] = -cs;
	return 0;
}

/* An ESRI ASCII grid's header: g's size, box's lower left corner, the cell size, nodata. */
void
asc_header(FILE *f, const tdc_grid_spec *g, const double box[4], double nodata)
{
	fprintf(f, "ncols        %zu\nnrows        %zu\nxllcorner    %.17g\nyllcorner    %.17g\n"
			"cellsize     %.17g\nNODATA_value %.17g\n", g->width, g->height, box[0], box[1], g->gt[1],
			nodata);
}

/* nrows rows of width values, top down, %.17g (fmt_g17.c). */
void
asc_rows(FILE *f, const double *v, size_t width, size_t nrows)
{
	g17_line	l;

	for (size_t r = 0; r < nrows; r++)
	{
		g17_line_start(&l, f);
		for (size_t c = 0; c < width; c++)
			g17_line_num(&l, v[r * width + c]);
		g17_line_end(&l);
	}
}

static void
grid(const cli_args *a, const tdc_job *job, tdc_tin *tin, double tin_s, const char *srs,
	 gtiff_out *tif)
{
	tdc_interp_spec spec;
	tdc_grid_spec g;
	char		err[512];
	double		box[4],
				data_box[4] = {0, 0, 0, 0},
				t0,
				t1;
	double	   *v;
	uint8_t    *ok;
	size_t		valid = 0;

	if (tdc_interp_parse(a->method ? a->method : "linear", &spec, err, sizeof(err)) != TDC_OK)
		die(2, "--method: %s", err);
	if (!a->has_extent && tdc_num_sites(job) > 0)
	{
		double		lo[2],
					hi[2];

		tdc_site_extent(job, lo, hi);
		data_box[0] = lo[0];
		data_box[1] = lo[1];
		data_box[2] = hi[0];
		data_box[3] = hi[1];
	}
	else if (!a->has_extent)
		die(1, "--grid needs an --extent when the input has no point%s", "");
	if (grid_geometry(a, data_box, &g, box, err, sizeof(err)) != 0)
		die(1, "%s", err);
	v = malloc(g.width * g.height * sizeof(double) + 8);
	ok = malloc(g.width * g.height + 1);
	if (v == NULL || ok == NULL)
		die(1, "out of memory for a grid of %s", "that size");
	t0 = now_s();
	err[0] = '\0';
	wait_op(tin, tdc_tin_grid_start(tin, &spec, &g, v, ok, err, sizeof(err)), err);
	t1 = now_s();
	for (size_t i = 0; i < g.width * g.height; i++)
		valid += ok[i];
	if (tif)
		write_tif(a, &g, v, spec.nodata, srs, tif);
	else if (a->outpath)
	{
		FILE	   *f = open_out(a->outpath);

		asc_header(f, &g, box, spec.nodata);
		asc_rows(f, v, g.width, g.height);
		close_out(f, a->outpath);
	}
	if (a->stats)
		fprintf(stderr, "tin=%.6f grid=%.6f pixels=%zu valid=%zu\n", tin_s, t1 - t0,
				g.width * g.height, valid);
	free(v);
	free(ok);
}

/*
 * Before the run: for --grid with a GeoTIFF -o, the input's CRS checked
 * (when --srs does not replace it) and the file's temporary name taken;
 * NULL for any other output.
 */
gtiff_out *
tin_output_prepare(const cli_args *a, const cli_input *in)
{
	gtiff_out  *tif;
	char		err[1024];

	if (!a->grid || !gtiff_path(a->outpath))
		return NULL;
	/* (GDAL loaded, or the error that says it is missing) */
	if ((tif = gtiff_reserve(a->outpath, err, sizeof(err))) == NULL)
		die(1, "%s", err);
	if (a->srs == NULL && in->srs != NULL && gtiff_check_srs(in->srs, err, sizeof(err)) != 0)
	{
		char		msg[1400];

		snprintf(msg, sizeof(msg), "%s: its CRS is not one GDAL reads (%s); give one with --srs",
				 a->input, err);
		gtiff_discard(tif);
		die(1, "%s", msg);
	}
	if (a->srs == NULL && in->srs == NULL)
		fprintf(stderr, "tdc: warning: %s gets no CRS: the input has none and no --srs was given\n",
				a->outpath);
	return tif;
}

/*
 * --contours or --grid on the one-shot run's triangulation of in; tif is
 * tin_output_prepare's.
 */
void
tin_output(const cli_args *a, const cli_input *in, const oneshot *r, gtiff_out *tif)
{
	tdc_tin    *tin;
	char		err[512];
	double		t0,
				t1;

	if (in->z == NULL && in->n > 0)
		die(1, "--contours and --grid need heights: text input of 'x y z' lines%s", "");
	t0 = now_s();
	if (tdc_tin_build(r->job, in->z, a->opt.threads, 0, &tin, err, sizeof(err)) != TDC_OK)
		die(1, "%s", err);
	t1 = now_s();
	if (a->contours)
		contours(a, tin, t1 - t0);
	else
		grid(a, r->job, tin, t1 - t0, a->srs ? a->srs : in->srs, tif);
	tdc_tin_free(tin);
}
