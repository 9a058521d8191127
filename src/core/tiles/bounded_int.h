/*
 * bounded_int.h
 *		The bounded run (tdc_bounded_run in tdc.h: an input that does not
 *		fit, tile by tile through files): what its files share (bounded.c
 *		explains the run).  Private to the core.
 *
 *	bounded.c			the phases in order, the plan, tdc_bounded_run
 *	tile_plan.c			the tiling policy, pure (tile_plan.h)
 *	bounded_files.c		errors, the source in chunks, the tile and halo files
 *	bounded_scan.c		pass 1: box, hull and cell counts
 *	bounded_bin.c		pass 2: every point to its tile's file and halos
 *	bounded_cells.c		a tile's file in cell order, for the reruns
 *	bounded_tile.c		a tile's runs until final, and its triangles out
 *	bounded_share.c		what the tile workers share: memory, files, output
 * Layered without loops: bounded_files.c and bounded_share.c at the
 * bottom, then the phases, then bounded.c (which runs the tile workers).
 *
 * Errors: every function that can fail returns TDC_OK or an error code and
 * leaves the first error's code and message in a bd_err, which unwinds to
 * tdc_bounded_run; it frees the run's arrays and removes its files.  The
 * threads of the two passes have a bd_err each, merged after the join.
 */
#ifndef TDC_BOUNDED_INT_H
#define TDC_BOUNDED_INT_H

#include <stdio.h>
#include <string.h>
#include <time.h>

#include "tdc.h"
#include "tile_plan.h"

/* The first error of a run or of one of its threads: code and message. */
typedef struct bd_err
{
	int			code;			/* TDC_OK until the first error */
	char		msg[640];
} bd_err;

/*
 * Bytes a point costs a tile run beside the engine and the finality check
 * (tdc_tp_tile_bytes): its coordinates, its tile, its z, the caller's
 * label, and what the caller's final_run holds per point while it runs.
 */
#define POINT_BYTES(r)	((size_t) (16 + 8 + ((r)->has_z ? 8 : 0) + ((r)->has_l ? 8 : 0) + \
								   ((r)->p->final_run ? (r)->p->final_per_point : 0)))

/*
 * A point's record in the run's files: x, y, then z with a z file, then the
 * caller's label with a label file (its int64 bits in a double's slot,
 * copied, never converted); a halo record adds its tile's number.
 */
#define REC_L(r)		(2 + (r)->has_z)

static inline void
rec_set_label(double *rec, int at, int64_t l)
{
	memcpy(rec + at, &l, sizeof(l));
}

static inline int64_t
rec_label(const double *rec, int at)
{
	int64_t		l;

	memcpy(&l, rec + at, sizeof(l));
	return l;
}

#define CHUNK		(1 << 16)	/* points per read of the source */

/* Reads the .bin source (and z, and the labels) in chunks: the caller's loop. */
typedef struct source
{
	FILE	   *fxy,
			   *fz,
			   *fl;
	double	   *xy,
			   *z;
	int64_t    *l;
	size_t		left;			/* points still to read */
	bd_err	   *e;				/* a read error or the cancel flag: 0 points, e set */
	const volatile int *cancel;
} source;

/* Buffered appends of fixed-size records to one temporary file. */
typedef struct recfile
{
	FILE	   *f;
	double	   *buf;
	size_t		len,			/* doubles in buf */
				cap;
	size_t		count;			/* records written */
	const char *dir;
	bd_err	   *e;				/* a write error: later records dropped, e set */
} recfile;

/* Reads a tile's file of a kind across its parts, in order. */
typedef struct mreader
{
	const char *kind;
	int			t,
				part,
				nparts;
	FILE	   *f;				/* NULL after an error: reads give 0 */
	const char *dir;
	bd_err	   *e;
} mreader;

struct bd_share;					/* bounded_share.c: what the tile workers share */

/*
 * The state of one run, filled phase by phase (bounded.c says which phase
 * fills what).  Each tile worker has a copy (bounded.c): the shared
 * arrays read-only, its own scratch for a tile's region, its own error
 * and counts.
 */
typedef struct bounded_run
{
	/* the call's */
	const tdc_bounded_params *p;
	const char *xypath,
			   *zpath,			/* the .bin source, and z beside it or NULL */
			   *lpath;			/* and the caller's labels beside it or NULL */
	const char *dir;			/* the caller's temporary directory */
	const char *lname;			/* the limit's name in messages */
	size_t		n;
	const tdc_options *opt;
	size_t		limit;			/* bytes */
	size_t		outside;		/* what the process holds beyond the tiles' model */
	size_t		budget;			/* the tiles' share: limit - outside */
	tdc_bounded_stats *st;
	bd_err		e;				/* the run's first error */
	int			has_z,
				has_l,
				w;				/* doubles per point record: 2, 3 with z or labels, 4 with both */

	/* pass 1 */
	double		bb[4];			/* the points' exact box */
	double	   *hull;			/* their convex hull */
	size_t		nhull;
	uint32_t   *counts;			/* per cell of grid (EMPTY cells for the finality check) */
	bool		counted;		/* pass 1 counted the cells too */

	/* the plan */
	tdc_tp_grid		grid;
	size_t	   *ps;				/* prefix sums of counts, for the first regions */
	size_t		tile_max;		/* the plan's tile size */
	tdc_tp_tile    *tiles;
	int			nt;
	int16_t    *cell_tile;		/* the tile of each cell, freed by binning */

	/* the first known regions */
	double	   *bands;			/* every hull edge's band */
	double	   *extra;			/* nhull + 1 boxes: a tile run's extra known boxes */
	uint8_t    *inband;			/* nhull + 1: is it among this tile's extra boxes */
	uint32_t   *hcells;			/* the hull cells of the tile's first region */
	size_t		nhcells;
	const double **xs;			/* nhull + 1: the bands a point is tested against */
	bool		use_halo;		/* binning writes halo files */
	double	   *kfirst;			/* each tile's first K */
	size_t	   *band_off,		/* each tile's first bands: band_idx[band_off[t] ..] */
			   *band_idx;
	uint32_t   *cell_off;		/* per cell, its halo tiles: cell_halo[cell_off[c] ..] */
	int16_t    *cell_halo;

	/* the cells a tile run knows whole (tdc_tile_grid, bounded_tile.c) */
	bool		use_cells;		/* the grid has cells of non-zero size */
	uint8_t    *cellst;			/* per cell: TDC_TILE_CELL_EMPTY, _KNOWN or _OTHER */
	uint8_t    *added;			/* per cell: added to this tile's region by a rerun */
	uint32_t   *added_list;		/* those cells */
	size_t		nadded,
				added_cap;

	/* pass 2 */
	int			nparts;			/* binning parts: files per tile and kind */
	size_t	   *halo_count;		/* each tile's halo file's points */

	/* the tiles */
	uint8_t    *sorted;			/* per tile: its file is in cell order (bounded_cells.c);
								 * read and set under the tile's file lock */
	bool		two;			/* a second tile worker's scratch is held */
	struct bd_share *sh;		/* the workers' memory, file locks and output (NULL
								 * before the tiles) */
	size_t		held;			/* bytes this worker reserved (tdc_bd_reserve) */
	tdc_options wopt;			/* a worker's engine options (opt points here) */
} bounded_run;

/* bounded_share.c */
extern int	tdc_bd_workers(const bounded_run *r);
extern size_t tdc_bd_worker_bytes(const bounded_run *r);
extern struct bd_share *tdc_bd_share_new(const bounded_run *r, int nworkers);
extern void tdc_bd_share_free(struct bd_share *sh);
extern const bd_err *tdc_bd_share_error(const struct bd_share *sh);
extern int	tdc_bd_claim(bounded_run *r);
extern void tdc_bd_leave(bounded_run *r);
extern void tdc_bd_stop(bounded_run *r);
extern bool tdc_bd_stopped(const bounded_run *r);
extern int	tdc_bd_reserve(bounded_run *r, size_t bytes);
extern void tdc_bd_release(bounded_run *r);
extern void tdc_bd_run_threads(bounded_run *r);
extern void tdc_bd_file_lock(const bounded_run *r, int s, bool write);
extern void tdc_bd_file_unlock(const bounded_run *r, int s);
extern void tdc_bd_out_lock(const bounded_run *r);
extern void tdc_bd_out_unlock(const bounded_run *r);

/*
 * Tile t's first known region, as the policy makes it from its cell box:
 * K and the halo h, in r->inband (cleared here) its hull bands, and in
 * r->hcells the cells along the hull edges near it, whole (as many as
 * tdc_tp_hull_limit allows, tdc_tp_hull_cells).
 */
static inline void
first_region(struct bounded_run *r, int t, double K[4], double *h)
{
	double		box[4];

	tdc_tp_least_known(&r->tiles[t], &r->grid, box);
	tdc_tp_fit_known(r->ps, &r->grid, box, r->tiles[t].count, tdc_tp_spacing(r->bb, r->n),
					 tdc_tp_known_limit(r->tiles[t].count, r->tile_max), K, h);
	memset(r->inband, 0, r->nhull + 1);
	tdc_tp_first_bands(K, r->tiles[t].count, r->bands, r->nhull, r->inband);
	r->nhcells = r->use_cells ?
		tdc_tp_hull_cells(&r->grid, r->counts, &r->tiles[t], r->hull, r->nhull, r->inband,
						  tdc_tp_hull_limit(r->tiles[t].count, r->tile_max,
											tdc_tp_box_count(r->ps, &r->grid, K)), r->hcells) : 0;
	tdc_tp_fit_bands(r->ps, &r->grid, r->bands, r->nhull,
					 r->tiles[t].count / 8 > 1000 ? r->tiles[t].count / 8 : 1000, r->inband);
}

static inline double
now_s(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

/* bounded_files.c */
extern int	tdc_bd_fail(bd_err *e, int code, const char *fmt,...)
			__attribute__((format(printf, 3, 4)));
extern int	tdc_bd_nomem(bd_err *e);
extern bool tdc_bd_canceled(const volatile int *cancel);
extern int	tdc_bd_source_open(source *s, const char *xypath, const char *zpath, const char *lpath,
							   bd_err *e, const volatile int *cancel);
extern int	tdc_bd_source_range(source *s, size_t from, size_t count);
extern size_t tdc_bd_source_read(source *s);
extern void tdc_bd_source_close(source *s);
extern int	tdc_bd_rec_open(recfile *r, const char *dir, bd_err *e, const char *kind, int t,
							int part, size_t cap);
extern void tdc_bd_rec_flush(recfile *r);
extern int	tdc_bd_rec_close(recfile *r);
extern FILE *tdc_bd_part_file(const char *dir, bd_err *e, const char *kind, int t, int part,
							  const char *mode);
extern int	tdc_bd_remove(const char *dir, bd_err *e, const char *kind, int t, int part);
extern void tdc_bd_remove_all(const char *dir, int nt);
extern int	tdc_bd_mr_open(mreader *m, const char *dir, bd_err *e, const char *kind, int t,
						   int nparts);
extern size_t tdc_bd_mr_read(mreader *m, void *buf, size_t size, size_t count);
extern void tdc_bd_mr_close(mreader *m);
extern int	tdc_bd_read_all(const char *dir, bd_err *e, const char *kind, int t, int nparts,
							double *buf, size_t k, int w);

/* One record appended; after a write error (r->e set) records are dropped. */
static inline void
rec_put(recfile *r, const double *v, int w)
{
	if (r->len + w > r->cap)
		tdc_bd_rec_flush(r);
	for (int k = 0; k < w; k++)
		r->buf[r->len + k] = v[k];
	r->len += w;
	r->count++;
}

/* Tile s's own points, read whole: from binning's parts, or in cell order once sorted. */
static inline int
tile_open(bounded_run *r, mreader *m, int s)
{
	if (r->sorted[s])
		return tdc_bd_mr_open(m, r->dir, &r->e, "cell", s, 1);
	return tdc_bd_mr_open(m, r->dir, &r->e, "tile", s, r->nparts);
}

/* bounded_scan.c */
extern int	tdc_bd_scan_input(bounded_run *r);
extern int	tdc_bd_scan_count(bounded_run *r);
extern int	tdc_bd_dense_spot(bounded_run *r, int cell, size_t limit, double spot[2], size_t *copies);

/* The process's bytes for a run of m points: the tiles' model and what it holds beside them. */
static inline size_t
run_need(const bounded_run *r, size_t m)
{
	return tdc_tp_tile_bytes(m, r->opt, POINT_BYTES(r)) + r->outside;
}

/* The caller's heap policy (tdc_bounded_params.settle), when it has one. */
static inline void
heap_settle(const bounded_run *r, bool always)
{
	if (r->p->settle)
	{
		tdc_bd_out_lock(r);
		r->p->settle(r->p->arg, always);
		tdc_bd_out_unlock(r);
	}
}

/* bounded_bin.c */
extern int	tdc_bd_halo_index(bounded_run *r);
extern int	tdc_bd_bin_points(bounded_run *r);

/* bounded_cells.c */
extern int	tdc_bd_region_records(bounded_run *r, int s, bool whole, const double *K, size_t nx,
								  double *buf, size_t cap,
								  void (*take) (void *arg, const double *rec, size_t got), void *arg);

/* bounded_tile.c */
extern int	tdc_bd_tile_run(bounded_run *r, int t);


#endif							/* TDC_BOUNDED_INT_H */
