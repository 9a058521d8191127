/*
 * cli.h
 *		What the files of ./tdc share.  Not installed.
 *
 *	tdc.c		the front end: arguments, which run, the --max-memory sizing
 *	input.c		reading INPUT and the segment file
 *	las.c		INPUT as a LAS file: its header, CRS and points
 *	oneshot.c	the run with the whole input in memory, and its output
 *	tiles.c		the run of --max-memory that does not fit: the core's
 *				tdc_bounded_run (src/core/tiles/bounded*.c), its triangles as text
 *	bounded_mem.c	the process's memory around that run
 *	tmpdir.c	the temporary directory of --max-memory
 *	tin_out.c	--contours and --grid: the TIN of x y z input, written as text
 *				or (geotiff.c) as a GeoTIFF
 *	grid_tiles.c	--grid in tiles: the run's triangles rasterised (terrain/raster.c)
 *	contours_tiles.c	--contours in tiles: the run's triangles cut into lines
 *				(terrain/contour_tiles.c), joined after it
 *	geotiff.c	the GeoTIFF writer, through GDAL
 *	die.c		how ./tdc fails
 *	fmt_g17.c	numbers as the text of "%.17g", without printf
 * Layered without loops: die.c and fmt_g17.c at the bottom, then tmpdir.c,
 * bounded_mem.c and geotiff.c and las.c, then input.c and tiles.c, then
 * oneshot.c and tin_out.c, then grid_tiles.c and contours_tiles.c, then
 * tdc.c.
 */
#ifndef TDC_CLI_H
#define TDC_CLI_H

#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <stddef.h>
#include <stdint.h>

#include "tdc.h"

/* The command line, as parsed by tdc.c */
typedef struct cli_args
{
	tdc_options opt;
	const char *input,
			   *outpath,		/* -o */
			   *segpath,		/* --segments */
			   *tmpdir;			/* --tmpdir */
	int			stats,
				validate,
				voronoi;
	long		max_mb;			/* --max-memory, 0 without it */
	int			contours;		/* --contours INTERVAL [--base B] */
	double		contour_interval,
				contour_base;
	int			grid;			/* --grid CELLSIZE [--extent ...] [--method M] */
	double		grid_cell;
	int			has_extent;
	double		extent[4];		/* xmin, ymin, xmax, ymax */
	const char *method;			/* --method, GDAL's syntax; NULL: linear */
	const char *srs;			/* --srs, for a GeoTIFF -o; NULL: the input's */
	int			float32;		/* --type Float32 (GeoTIFF); else Float64 */
	int			has_class;		/* --class LIST (LAS input): the values kept */
	unsigned char class_keep[256];
} cli_args;

/* The input points in memory */
typedef struct cli_input
{
	size_t		n;
	double	   *xy,
			   *z;				/* NULL without z */
	char	   *srs;			/* the input's CRS: a LAS file's WKT or "EPSG:N"
								 * (las.c says which); NULL when none;
								 * malloc'd, freed by oneshot_free */
} cli_input;

/* die.c: "tdc: " and fmt with arg on stderr, then exit(code) */
extern void die(int code, const char *fmt, const char *arg) __attribute__((noreturn));
/* die.c: msg into first under mu, unless first holds a message already */
extern void keep_first_error(pthread_mutex_t *mu, char *first, size_t firstlen, const char *msg);

/*
 * fmt_g17.c: v as snprintf(buf, 32, "%.17g", v) writes it, NUL included;
 * returns the characters before the NUL.  buf: 32 bytes.
 */
extern size_t fmt_g17(char *buf, double v);

/* A line of such numbers, one space apart, to f through a buffer */
typedef struct g17_line
{
	FILE	   *f;
	size_t		len;
	bool		first;
	char		buf[4096];
} g17_line;

extern void g17_line_start(g17_line *l, FILE *f);
extern void g17_line_num(g17_line *l, double v);
extern void g17_line_end(g17_line *l);	/* "\n", and what is left to f */

/* las.c: an open LAS file (las_open), read in batches of whole records (las_next) */
typedef struct las_file
{
	const char *path;
	FILE	   *f;
	uint64_t	size,			/* the file's bytes */
				point_offset,
				n,				/* records */
				done,			/* records read */
				kept;			/* of them, points --class kept */
	int			major,
				minor,
				format;
	unsigned	reclen,
				global_encoding;
	double		scale[3],
				offset[3];
	char	   *srs;			/* malloc'd; NULL when none */
	unsigned char *buf;			/* bufrecs records */
	size_t		bufrecs;
} las_file;

extern bool is_las_path(const char *path);
extern void las_parse_classes(const char *list, unsigned char keep[256]);
extern void las_open(const char *path, las_file *lf);
extern bool las_next(las_file *lf, const unsigned char *keep, double *xy, double *z, size_t max, size_t *k);
extern void las_report(const las_file *lf);
extern void las_close(las_file *lf);

/* input.c */
extern bool is_bin_path(const char *path);
extern bool is_xyz_bin_path(const char *path);
extern int	parse_line(char *line, size_t lineno, double v[3], int *dims);
extern void read_input(const cli_args *a, cli_input *in);
extern double *read_bin(const char *path, size_t *n);
extern uint32_t *read_segments(const char *path, size_t n, size_t *k);
extern size_t text_to_bin(const char *path, int *has_z);
extern size_t las_to_bin(const cli_args *a, char **srs);
extern size_t xyz_bin_to_bin(const char *path);

/* oneshot.c: the run over the whole input, in memory */
typedef struct oneshot
{
	tdc_job    *job;
	tdc_cdt    *cdt;			/* with --segments */
	uint32_t   *seg;
	size_t		nseg;
	double		constrain_s;
	tdc_voronoi *vor;			/* with --voronoi */
	char	   *cells;			/* the cells written without -o */
	double		vor_seconds;
} oneshot;

extern void oneshot_run(const cli_args *a, const cli_input *in, oneshot *r);
extern void oneshot_write(const cli_args *a, const cli_input *in, const oneshot *r);
extern void oneshot_report(const cli_args *a, const oneshot *r);
extern void oneshot_free(oneshot *r, cli_input *in);

/* geotiff.c: a grid to a GeoTIFF through GDAL (errors: -1 and err) */
typedef struct gtiff_out gtiff_out;
extern bool gtiff_path(const char *path);	/* ends in .tif or .tiff, any case */
extern int	gtiff_check_srs(const char *srs, char *err, size_t errlen);
/* bytes of GDAL's block cache while a GeoTIFF is written (geotiff.c caps it) */
#define GTIFF_CACHE_BYTES	((size_t) 16 << 20)
/* threads that compress a GeoTIFF's blocks, for -t threads (0: the online CPUs) */
#define GTIFF_THREADS		4
extern int	gtiff_threads(int threads);
/* bytes GDAL holds while it writes one: the cache, and each thread's block and one more */
#define GTIFF_HOLD(threads)	(GTIFF_CACHE_BYTES + ((size_t) gtiff_threads(threads) + 1) * 2 * \
							 ((size_t) 8 << 16))
/* the temporary file beside path, now; removed at exit unless closed */
extern gtiff_out *gtiff_reserve(const char *path, char *err, size_t errlen);
/* threads: -t's (gtiff_threads of it compress the blocks) */
extern int	gtiff_open(gtiff_out *g, size_t width, size_t height, const double gt[6],
					   const char *srs, double nodata, bool float32, int threads, char *err,
					   size_t errlen);
/* rows y0 .. y0 + nrows - 1, top down, in order: width values a row */
extern int	gtiff_write_rows(gtiff_out *g, size_t y0, size_t nrows, const double *values,
							 char *err, size_t errlen);
/* closed, renamed to path; frees g */
extern int	gtiff_close(gtiff_out *g, char *err, size_t errlen);
/* the file given up and removed; frees g */
extern void gtiff_discard(gtiff_out *g);

/* tin_out.c: --contours or --grid on the one-shot triangulation */
extern gtiff_out *tin_output_prepare(const cli_args *a, const cli_input *in);
extern void tin_output(const cli_args *a, const cli_input *in, const oneshot *r, gtiff_out *tif);
extern int	grid_geometry(const cli_args *a, const double data_box[4], tdc_grid_spec *g,
						  double box[4], char *err, size_t errlen);
extern void asc_header(FILE *f, const tdc_grid_spec *g, const double box[4], double nodata);
extern void asc_rows(FILE *f, const double *v, size_t width, size_t nrows);
extern void contour_line(FILE *f, double level, const double *xy, size_t n);

/* grid_tiles.c: --grid in tiles */
extern void grid_in_tiles(const cli_args *a, const char *xypath, const char *zpath, size_t n,
						  const char *srs, gtiff_out *tif);

/* contours_tiles.c: --contours in tiles */
extern void contours_in_tiles(const cli_args *a, const char *xypath, const char *zpath, size_t n);

/* tmpdir.c: the temporary directory of --max-memory, removed at exit */
extern char tmp_dir[4096];
extern volatile int cli_cancel;	/* a signal came: the run in tiles stops */
extern void tmp_create(const char *base);
extern void tmp_cleanup(void);
extern FILE *tmp_open(const char *name, const char *mode);
extern bool tmp_owns(const char *path);

/* bounded_mem.c: the process's memory around a run in tiles */
extern size_t heap_start(size_t limit);
extern size_t heap_resident(void);	/* resident bytes now, 0 where unknown */
/* the settle and peak callbacks of tdc_bounded_params (arg unused) */
extern void heap_settle(void *arg, bool always);
extern size_t heap_peak(void *arg);

/* tiles.c: --stats' line of a run in tiles that writes a product (grid, contours) */
extern void tiles_stats_line(const tdc_bounded_stats *st, double total);

/* tiles.c: the run in tiles (tdc_bounded_run), its triangles to out (when not NULL) */
extern void run_bounded(const char *xypath, const char *zpath, size_t n, const tdc_options *opt,
						size_t limit, FILE *out, tdc_bounded_stats *st);

#endif							/* TDC_CLI_H */
