/*
 * tdc_bounded.h
 *		Public API of the core, continued: the bounded run (an input that
 *		does not fit, tile by tile through files) and the terrain products
 *		made from its final triangles, a grid and contour lines.
 *
 * Part of tdc.h, which includes it at its end: include either.  It is a
 * file of its own only to keep each header under 1,000 lines; the
 * conventions of tdc.h (status codes, messages, no global state) hold.
 */
#ifndef TDC_BOUNDED_H
#define TDC_BOUNDED_H

#include "tdc.h"

/* --- Bounded runs: an input that does not fit, tile by tile through files --- */

/*
 * tdc_bounded_run (bounded*.c) triangulates n points that need not fit in
 * memory: they are read from a file, cut into tiles on disk with the tiling
 * policy of tile_plan.c, and each tile is run until final (tile_final.c), so
 * the triangles are exactly those of one tdc_triangulate over all points
 * (each once, in tile order, not the one-shot run's order).  The caller's
 * process stays under limit bytes at its peak as far as the tiles' model
 * (tdc_tp_tile_bytes) and the callbacks' view of the heap go; a plan or a
 * tile that would not fit is an error, never a silent overrun.
 *
 * Runs on the caller's thread (with one more thread for each of the two
 * passes over the input) and calls every callback from it, unless the
 * caller takes the tiles in any order (any_order below): then up to two
 * tiles run at once, on threads of the run, which call emit, settle and
 * trace one call at a time.  Never exits: an error returns its code with
 * a message, after freeing what the run allocated and removing the files
 * it created.
 */
typedef struct tdc_bounded_stats
{
	size_t		n,				/* input points */
				unique,			/* distinct sites, each counted by its owning tile */
				ntri,			/* triangles emitted */
				halo,			/* points of other tiles in the final runs */
				runs,			/* tile runs, reruns included */
				reread;			/* records reruns read from other tiles' files */
	int			tiles,			/* tiles of the plan */
				threads,		/* worker threads of the engine's last run */
				workers,		/* tiles that could run at once (1, or 2 with any_order) */
				bin_threads;	/* threads that binned the input (1, or 2 with files enough) */
	tdc_times	t;				/* the engine's phases, summed over the runs */
	double		scan,			/* wall seconds: box, hull and counts */
				bin,			/* the points to the tile files */
				tiles_wall,		/* every tile, from the first run to the last emit */
				/* seconds summed over the tile workers (each a wall time): */
				gather,			/* each tile's points read back */
				engine,			/* tdc_triangulate */
				finish,			/* tdc_tile_finish */
				write,			/* emit, and the frees after a run */
				wait;			/* a worker waiting for the other's memory */
} tdc_bounded_stats;

typedef struct tdc_bounded_params
{
	const char *xypath;			/* n x,y pairs of doubles, in this machine's byte order */
	const char *zpath;			/* NULL, or n z doubles beside them (passed to emit) */
	const char *lpath;			/* NULL, or n int64 labels beside them (passed to emit,
								 * each site's least: tdc_least_labels) */
	size_t		n;
	const tdc_options *opt;		/* the engine's options; tolerance must be 0 */
	size_t		limit;			/* bytes the caller's process may hold at its peak */
	size_t		outside;		/* bytes the process holds beside the run: off the limit */
	const char *tmpdir;			/* an existing directory: the run creates its files
								 * there (named tile*, halo* and cell*) and removes them */
	const char *limit_name;		/* how messages name the limit; NULL: "--max-memory" */

	/*
	 * The triangles of final tile number tile (from 0, in the plan's
	 * order, each tile at most once): ntri triangles, 3 indices each,
	 * counter-clockwise, into q (x,y pairs), qz (z, or NULL without
	 * zpath) and ql (NULL without lpath: for a vertex, the least label of
	 * the input points at its coordinates), valid during the call.
	 * Nonzero stops the run: a negative TDC_ code is returned as it is,
	 * anything else as TDC_EINVAL.  NULL: not emitted.
	 */
	int			(*emit) (void *arg, int tile, const double *q, const double *qz,
						 const int64_t *ql, const size_t *tri, size_t ntri);
	/*
	 * Optional, for an output that needs more than the final triangles
	 * (the natural neighbour grid, terrain/raster_natural.c): called for
	 * each final tile run before emit, one call at a time as emit is, with
	 * the run's finished job (the tile's whole triangulation T(Q); its
	 * input is q, m points, with qz as emit's), the tile's final triangles
	 * (as emit's) and what the tile knows (spec: K, the extra boxes, the
	 * cells, each point's tile; tdc_tile_finish's).  Returns 0 (emit
	 * follows), 1 with more's need (a box containing K) and need_cells set
	 * as a tile that is not final sets them (the tile runs again with what
	 * they ask, and emit waits for that run), or a nonzero code that stops
	 * the run as emit's does.  final_per_point: the bytes per point of q it
	 * holds at most while it runs, counted in the tiles' memory.
	 */
	int			(*final_run) (void *arg, const tdc_job *job, const double *q, const double *qz,
							  size_t m, const size_t *tri, size_t ntri,
							  const tdc_tile_spec *spec, tdc_tile_result *more);
	size_t		final_per_point;
	/*
	 * Optional, with final_run: what its requests for more are for, said
	 * in the refusal when the limit cannot hold one (" (the ... reach that
	 * far: ...)"); NULL says nothing more than the tile's numbers.
	 */
	const char *final_run_why;
	/*
	 * Optional, before emit: called once after the first pass, before the
	 * plan, with the points' exact box (xmin, ymin, xmax, ymax) and their
	 * convex hull (nhull x,y pairs, counter-clockwise, collinear vertices
	 * dropped), both valid during the call.  *hold (0 on entry): the bytes
	 * the caller will hold beside the tiles from then on (an output's
	 * buffers, say), taken off the tiles' budget before the plan.  Nonzero
	 * stops the run, as emit's does.
	 */
	int			(*begin) (void *arg, const double box[4], const double *hull, size_t nhull,
						  size_t *hold);
	/*
	 * Optional memory hooks.  settle: hand the free heap back (always, or
	 * only when the process nears the limit: the caller's policy), called
	 * after binning with always and after every tile run without.  peak:
	 * the process's peak resident bytes so far (0: unknown), checked
	 * against limit before the first tile.
	 */
	void		(*settle) (void *arg, bool always);
	size_t		(*peak) (void *arg);
	/*
	 * Optional, for tests and diagnosis.  trace: one line per tile run
	 * (tile, K, points).  check_files: verify that each first run's files
	 * hold exactly its first region, counted again from every tile file
	 * (slow); a mismatch is an error.
	 */
	void		(*trace) (void *arg, const char *line);
	bool		check_files;

	/*
	 * The caller takes the final tiles in any order: two may run at once
	 * (bounded_share.c), emit called as each finishes, one call at a time;
	 * the tiles and triangles are the same.  false: the plan's order, one
	 * tile at a time.
	 */
	bool		any_order;
	/*
	 * With any_order: emit may be called by both workers at once (the
	 * caller's emit guards its own state; a raster's tdc_raster_tile
	 * does), beside settle and trace too, which stay one call at a time
	 * among themselves.  A tile's output then no longer waits for the
	 * other's.  false: emit is one call at a time with them all.
	 */
	bool		emit_concurrent;
	bool		drop_input;		/* the input files are the caller's temporaries: unlinked once binned */
	void	   *arg;			/* passed to the callbacks */
	/*
	 * NULL, or a flag another thread may set to nonzero: polled between
	 * chunks of input, tile runs and tiles, and every few ms while a
	 * tile's engine runs; the run then returns TDC_ECANCELED.
	 */
	const volatile int *cancel;
} tdc_bounded_params;

/*
 * Run it: TDC_OK with *st filled, or an error code with a message in err
 * (the plan's refusals, with this input's floor, are TDC_EMEMLIMIT; file
 * errors TDC_EIO; a bad coordinate TDC_EINVAL).
 */
extern int	tdc_bounded_run(const tdc_bounded_params *p, tdc_bounded_stats *st,
							char *err, size_t errlen);

/*
 * The same run on a thread of its own (bounded_job.c), for a host whose
 * thread must stay free to notice interrupts: start, wait with a timeout
 * (TDC_RUNNING until it ends, then tdc_bounded_run's status), cancel
 * (the run then returns TDC_ECANCELED within a few ms, a tile's engine run
 * included), and free (cancels and joins first).  p->cancel must be NULL:
 * the job has its own.  The callbacks run on the job's thread.  *p and
 * what it points to must stay valid until the job is freed.
 */
typedef struct tdc_bounded_job tdc_bounded_job;

extern int	tdc_bounded_start(const tdc_bounded_params *p, tdc_bounded_job **job,
							  char *err, size_t errlen);
extern int	tdc_bounded_wait(tdc_bounded_job *job, int timeout_ms);
extern void tdc_bounded_cancel(tdc_bounded_job *job);
extern const char *tdc_bounded_error(const tdc_bounded_job *job);
/* valid once tdc_bounded_wait returned TDC_OK */
extern const tdc_bounded_stats *tdc_bounded_stats_of(const tdc_bounded_job *job);
extern void tdc_bounded_free(tdc_bounded_job *job);

/* --- A grid from a bounded run's triangles (terrain/raster.c) --- */

/*
 * The grid of tdc_tin_grid_start, computed from the final triangles a
 * bounded run emits tile by tile instead of from a whole TIN, with the
 * same values to the bit: linear (its value at a pixel is decided by the
 * triangle or edge or site that holds the pixel's centre) and nearest (the
 * nearest site is a corner of a triangle whose region with its
 * circumcentre holds the centre: terrain/raster_nearest.c) and natural
 * neighbour (through tdc_raster_nn_tile below).  The values
 * wait in a temporary file of the grid's size (8 bytes a pixel, 32 for
 * nearest; sparse: never written pixels take no disk) and come out by
 * rows; the tiles may come in any order.
 *
 * begin: from the bounded run's begin callback (the hull is copied).  g
 * may be any grid whose pixels have an area: north-up, flipped, skewed or
 * rotated (its pixel matrix gt[1], gt[2]; gt[4], gt[5] is inverted, and a
 * singular one, or one whose determinant is below 1e-12 of |gt[1] gt[5]| +
 * |gt[2] gt[4]|, is TDC_EINVAL naming the geotransform).  *hold: the
 * bytes the grid holds from then on (the buffers; add them to the run's).
 * tile: a final tile's triangles, from the run's emit (q, qz, tri as
 * there); at_once (1 or 2) of them may be called at once, on threads of
 * the run that sets emit_concurrent (each tile takes its own window of
 * rows: linear holds 2 MB or 16 rows more for the second).  rows: after the run, rows y0 .. y0 + nrows - 1 (top down) into
 * v (nrows * width doubles), *valid += the pixels with a value; the first
 * call loads the sites the pixels outside the hull may take (those on the
 * hull, and the corners of the triangles whose circumcentre lies outside
 * it: some per hull edge), which must fit in
 * max_bytes (TDC_EMEMLIMIT otherwise).  free: the file removed.
 */
typedef struct tdc_raster tdc_raster;

extern int	tdc_raster_begin(const tdc_interp_spec *spec, const tdc_grid_spec *g,
							 const double *hull, size_t nhull, const char *tmpdir, int at_once,
							 tdc_raster **r, size_t *hold, char *err, size_t errlen);
extern int	tdc_raster_tile(tdc_raster *r, const double *q, const double *qz,
							const size_t *tri, size_t ntri, char *err, size_t errlen);
extern int	tdc_raster_rows(tdc_raster *r, size_t y0, size_t nrows, double *v, size_t *valid,
							size_t max_bytes, char *err, size_t errlen);
extern void tdc_raster_free(tdc_raster *r);

/*
 * A natural neighbour grid (terrain/raster_natural.c) takes each final
 * tile's whole triangulation instead of tile: call it from the bounded
 * run's final_run with its arguments and return what it returns: TDC_OK,
 * 1 when a pixel's cavity is not proven global from what the tile knows
 * (more: what it must know besides; the pixels proven are written), or an
 * error.  The values are those of the whole TIN to the bit.  Set the
 * run's final_per_point to TDC_RASTER_NN_PER_POINT: the TIN it builds on
 * the tile's job (tdc_tin_memory), a label and a flag per point and a byte
 * per triangle.
 */
#define TDC_RASTER_NN_PER_POINT		72
/* and its final_run_why */
#define TDC_RASTER_NN_WHY	" (the natural neighbour cavities of its pixels reach that far: a larger " \
	"limit, or linear or nearest)"

extern int	tdc_raster_nn_tile(tdc_raster *r, const tdc_job *job, const double *q, const double *qz,
							   size_t m, const size_t *tri, size_t ntri, const tdc_tile_spec *spec,
							   tdc_tile_result *more, char *err, size_t errlen);

/* --- Contour lines from a bounded run's triangles (terrain/contour_tiles.c) --- */

/*
 * The lines of tdc_tin_contours_start_spec, made from the final triangles
 * a bounded run emits tile by tile instead of from a whole TIN: the same
 * lines, the same points bit for bit, in the same order (levels
 * increasing, a level's lines by their points).  Each tile's pieces of
 * lines wait in two temporary files (removed from the directory at once,
 * gone when freed); after the run they are joined.
 *
 * begin: interval, base and spec (NULL, or linear with max_edge only) as
 * for tdc_tin_contours_start_spec; *hold: the bytes held from then on
 * beside the tiles (add them to the run's).  tile: a final tile's
 * triangles, from the run's emit; at_once (1 or 2) calls may run at
 * once, on threads of a run that sets emit_concurrent.  lines: after the run, calls fn for
 * each line in order (xy: n x,y pairs, valid during the call; a ring's
 * last point repeats its first); nonzero from fn stops it (returned as a
 * TDC_ code as emit's is).  The join and one level's lines must fit in
 * max_bytes: TDC_EMEMLIMIT with the numbers otherwise.  cancel (NULL or a
 * flag) is polled between levels.
 */
typedef struct tdc_contour_tiles tdc_contour_tiles;
typedef int (*tdc_contour_line_fn) (void *arg, double level, const double *xy, size_t n,
									bool closed);

extern int	tdc_contour_tiles_begin(double interval, double base, const tdc_interp_spec *spec,
									const char *tmpdir, int at_once, tdc_contour_tiles **c,
									size_t *hold, char *err, size_t errlen);
extern int	tdc_contour_tiles_tile(tdc_contour_tiles *c, const double *q, const double *qz,
								   const size_t *tri, size_t ntri, char *err, size_t errlen);
extern int	tdc_contour_tiles_lines(tdc_contour_tiles *c, size_t max_bytes, tdc_contour_line_fn fn,
									void *arg, const volatile int *cancel, size_t *nlines,
									size_t *npoints, char *err, size_t errlen);
extern void tdc_contour_tiles_free(tdc_contour_tiles *c);

#endif							/* TDC_BOUNDED_H */
