/*
 * tiled_stage.h
 *		The vertices of a tiled procedure's source, in memory while one pass
 *		fits tdc_delaunay.max_memory, else staged to files for the core's
 *		bounded run (tiled_stage.c), and the files' lifetime.  Shared by
 *		tdc_delaunay_tiled (fn_tiled_bounded.c), tdc_interpolate_tiled
 *		(fn_interpolate_tiled.c) and tdc_contours_tiled (fn_contours_tiled.c).
 */
#ifndef TDC_TILED_STAGE_H
#define TDC_TILED_STAGE_H

#include <stdio.h>

#include "tdc_pg.h"

/* Vertices collected before they are appended to the files: 1.5 MB of xy. */
#define STAGE_CHUNK			65536

/* Everything a run holds outside PostgreSQL's memory, freed by the callback. */
typedef struct BoundedRun
{
	char		dir[MAXPGPATH];	/* "" until made */
	char		xypath[MAXPGPATH],
				zpath[MAXPGPATH],
				lpath[MAXPGPATH],	/* the vertices' ranks, for the run */
				lrawpath[MAXPGPATH],	/* their value numbers, as read */
				tripath[MAXPGPATH];
	FILE	   *fxy,
			   *fz,
			   *fl,
			   *fin,			/* a staged file read back */
			   *ftri;
	uint64		n;				/* vertices staged */
	bool		hasz;
	bool		hasl;			/* labels: a tile column */
	int			dim;
	tdc_bounded_job *job;
	int			write_errno;	/* emit: the errno of a failed write (run's thread) */
	MemoryContextCallback cb;
} BoundedRun;

/*
 * What the staging row callback needs: where the vertices go, and whether
 * they still fit one pass.
 */
typedef struct StageArg
{
	BoundedRun *br;
	TdcPointBuf *buf;
	TdcTableWriter *tw;
	MemoryContext cxt;			/* the call's */
	bool		tagged;			/* the query has a tile column */
	double		size;			/* tile_size, 0 without: not with a tile column */
	TdcTileValues *tv;			/* its values, from the first row with a vertex */
	const char *tile_name;
	int64	   *lab;			/* each vertex of buf: its value's number, later its rank */
	uint64		lab_cap;
	const tdc_options *opt;
	uint64		limit;			/* bytes; 0: none */
	bool		to_files;		/* past one pass: every chunk goes to the files */
	uint64		next_check;		/* vertex count at which the fit is checked again */
	double		lo[2],			/* the vertices' box so far */
				hi[2];
	uint64		beside;			/* bytes the caller will hold beside one pass */
	bool		tin;			/* one pass builds a TIN too (tdc_tin_memory) */
	const char *fname;
} StageArg;

/*
 * A run whose final triangles go to a consumer of the core (the raster of
 * tdc_interpolate_tiled, the contour pieces of tdc_contours_tiled): the
 * run's emit hands each final tile's triangles to tile, and on any end of
 * the call the run is stopped before free_obj frees the consumer, then the
 * files go.  The callers' structs begin with it, so that the run's begin,
 * given the StageConsumer, reaches the rest.
 */
typedef int (*StageTileFn) (void *obj, const double *q, const double *qz, const size_t *tri,
							size_t ntri, char *err, size_t errlen);

typedef struct StageConsumer
{
	BoundedRun *br;
	void	   *obj;			/* the consumer, made by the run's begin */
	StageTileFn tile;
	void		(*free_obj) (void *obj);
	char		err[1024];		/* a callback's failure, said in full */
	MemoryContextCallback cb;
} StageConsumer;

extern void tdc_stage_consumer_init(StageConsumer *sc, MemoryContext cxt, StageTileFn tile,
									void (*free_obj) (void *obj));
extern int	tdc_stage_consumer_emit(void *arg, int tile, const double *q, const double *qz,
									const int64_t *ql, const size_t *tri, size_t ntri);
extern void tdc_stage_consumer_release(void *arg);

extern void tdc_stage_close(FILE **f);
extern void tdc_stage_release(void *arg);
extern void tdc_stage_make_dir(BoundedRun *br, const char *fname);
extern FILE *tdc_stage_open(const char *path, const char *mode, const char *fname);
extern void tdc_stage_write(FILE *f, const void *p, size_t size, size_t count, const char *path,
							const char *fname);
extern void tdc_stage_finish(FILE **f, const char *path, const char *fname);
extern uint64 tdc_stage_labels_bytes(uint64 n);
extern uint64 tdc_stage_values_bytes(const StageArg *sa);
extern bool tdc_stage_fits(const StageArg *sa, uint64 n);
extern void tdc_stage_flush(StageArg *sa);
extern void tdc_stage_to_files(StageArg *sa);
extern void tdc_stage_row(void *arg, uint64 first);
extern void tdc_stage_init(StageArg *sa, BoundedRun *br, TdcPointBuf *buf, MemoryContext cxt,
						   const tdc_options *opt, uint64 limit_mb, const char *fname);
extern uint64 tdc_stage_done(StageArg *sa);
extern void tdc_stage_stop(BoundedRun *br);
extern void tdc_stage_write_error(BoundedRun *br, const char *fname);
extern TdcPcColumn *tdc_stage_pc_column(FunctionCallInfo fcinfo, int geometry_nargs, MemoryContext cxt);
extern void tdc_stage_run(BoundedRun *br, tdc_bounded_params *p, const tdc_options *opt,
						  uint64 limit_mb, const char *setting, uint64 outside, const char *what,
						  const char *cb_err, tdc_bounded_stats *st, const char *fname);

#endif							/* TDC_TILED_STAGE_H */
