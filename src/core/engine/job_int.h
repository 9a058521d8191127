/*
 * job_int.h
 *		The state of one triangulation, shared by the core's sources (the
 *		plan and first phase in triangulate.c, the lifecycle in job.c on the
 *		runner of runner.c, the results in result.c).  Not installed.
 *		The consumers of a finished job (Voronoi, constrained, tiles) do
 *		not include it: they read the view of mesh_view.h.
 */
#ifndef TDC_JOB_INT_H
#define TDC_JOB_INT_H

#include "engine_int.h"
#include "mesh_view.h"

/* A rectangle of grid cells: rows [r0, r1), columns [c0, c1). */
typedef struct tdc_rect
{
	uint32_t	r0,
				r1,
				c0,
				c1;
} tdc_rect;

struct tdc_job
{
	tdc_options opt;
	size_t		n;				/* input points */
	const double *input;		/* caller's coordinates, valid until the job ends */

	/*
	 * Points entering the subdivision: coordinates and input index, permuted
	 * in place by the subdivision and the subset sorts.  After the subset
	 * sorts, position p of a subset's unique prefix is site p.
	 */
	size_t		nin;
	double	   *xy;
	uint32_t   *idx;
	uint32_t   *site_of;		/* position -> site (its own position if a site) */
	_Atomic(uint32_t *) map;	/* input index -> site, built on first request */
	uint32_t   *tol_to;			/* tolerance: dropped input -> absorbing input */

	tdc_he	   *he;				/* 6 half-edges per entering point */
	bool		constrained;	/* tdc_job_edit_mesh was called: maybe no longer Delaunay */
	int			d;				/* levels: 2^d subsets */
	int			s;				/* grid size */
	int			threads;
	double		bmin[2],
				bmax[2];		/* bounding box of the input */
	double		gscale[2];		/* grid cells per unit along x and y */
	uint32_t   *prefix;			/* (s+1)^2 2-D prefix sums of the cell counts */

	/* the tree, heap-numbered from root 1, 2^(d+1) nodes */
	tdc_rect   *node_rect;
	uint8_t    *node_axis;		/* axis of the node's split (and merge) */
	uint32_t   *node_lo;		/* point range */
	uint32_t   *node_hi;
	tdc_sub    *subs;

	tdc_pool   *pool;

	/*
	 * A small job's arrays: carved from a block allocated with the job
	 * (tdc_job_alloc), so that a call on a few points costs one malloc and
	 * one free.  Empty for big jobs.
	 */
	char	   *arena;
	size_t		arena_size;
	size_t		arena_used;
	bool		off_arena;		/* some array did not fit: tdc_job_free_arrays looks */

	atomic_int	cancel;
	atomic_int	failed;			/* first task error wins */

	/* results */
	size_t		nsites;
	size_t		ntri;
	size_t		nedges;
	uint64_t   *outer;			/* bitmap: half-edges of the outer face */
	tdc_times	times;

	/* tdc_job_emit_start */
	tdc_emit_fn emit;
	void	   *emit_arg;

	/* lifecycle (runner.c); run.lock also guards the input map's building */
	bool		inline_run;		/* phases run on the caller's thread (TDC_INLINE_MAX) */
	int			(*phase) (struct tdc_job *job);	/* what the driver (or caller) runs */
	tdc_runner	run;

	/* messages last: a new job clears everything before them (job.c) */
	char		task_err[256];
	char		err[256];
};

/* result.c, emit.c: does half-edge h start a triangle (its smallest half-edge)? */
static inline bool
tdc_tri_at(const tdc_job *job, size_t h, uint32_t v[3])
{
	return tdc_face_tri_at(job->he, job->outer, h, v);
}

/* emit.c: the driver phase of tdc_job_emit_start. */
extern int	tdc_emit_phase(tdc_job *job);

/* emit.c: the same for a small job, on the caller's thread. */
extern int	tdc_emit_inline(tdc_job *job);

/* triangulate.c: the plan of a job of n points (see tdc_estimate_memory). */
extern bool tdc_plan_inline(size_t n);
extern int	tdc_plan_threads(size_t n, const tdc_options *o);

/* triangulate.c: the first phase, the triangulation itself. */
extern int	tdc_run_phase(tdc_job *job);

/* job_arena.c: record the first error of a task and stop the others. */
extern void tdc_job_fail(tdc_job *job, int code, const char *fmt,...)
			__attribute__((format(printf, 3, 4)));

/* subdivide.c: step 1, the grid, the tree and the points in tree order. */
extern void tdc_subdivide(tdc_job *job);
extern uint32_t tdc_rect_count(const tdc_job *job, const tdc_rect *r);
extern int	tdc_rect_split(const tdc_job *job, const tdc_rect *r, int axis,
						   bool by_count, tdc_rect *a, tdc_rect *b);
extern int	tdc_rect_split_inner(const tdc_job *job, const tdc_rect *r, int axis,
								 tdc_rect *a, tdc_rect *b);

/* tolerance.c */
extern int	tdc_tolerance_filter(tdc_job *job);
extern size_t tdc_tolerance_memory(size_t n);

/* emit.c: bytes tdc_emit_phase allocates for up to 2n triangles. */
extern size_t tdc_emit_memory(size_t n, int threads);

/*
 * subdivide.c counts the cells in at most this many slices, each with its
 * own s x s histogram: enough to keep the counting parallel, and a bound
 * on the grid's memory that does not grow with the thread count.
 */
#define TDC_GRID_SLICES		8

/*
 * leaf.c: triangulate subset k (a leaf of the tree) down to its cells;
 * removes duplicates and fills site_of[] for its points.
 */
extern void tdc_triangulate_leaf(tdc_job *job, size_t k, tdc_sub *out);

/*
 * The arena.  A call on a handful of points used to spend a third of its
 * time in malloc and free: some twenty arrays, each a few dozen bytes, and
 * glibc consolidating its free lists whenever a chunk next to the top of
 * the heap came back.  So a job on at most TDC_ARENA_MAX_POINTS points gets its
 * arrays from one zeroed block allocated together with the job, a bump
 * allocator with nothing to free.  An array that does not fit (the sizing
 * below is generous, not exact) falls back to tdc_big_alloc, so the arena
 * is a speed-up only, never a limit.  The block stays within a few tens of
 * kB, below glibc's mapping threshold, and it is counted by
 * tdc_estimate_memory's per-point and fixed terms like the arrays it
 * replaces.  Only the thread that runs the phases allocates from it; the
 * input map, built on demand by any reader, never does.  The block is
 * zeroed an array at a time as it is handed out, not as a whole: the sizing
 * is generous, and clearing the unused rest cost more than the arrays.
 */
#define TDC_ARENA_MAX_POINTS	256
#define TDC_ARENA_ALIGN			16		/* one thread: no false sharing to avoid */
#define TDC_ARENA_FIXED			1024	/* tree nodes, grid counts, rounding */
#define TDC_ARENA_PER_POINT		(6 * sizeof(tdc_he) + 48)	/* mesh, xy, idx, site_of, cell */

static inline size_t
tdc_arena_bytes(size_t n)
{
	return n <= TDC_ARENA_MAX_POINTS ? TDC_ARENA_FIXED + n * TDC_ARENA_PER_POINT : 0;
}

/*
 * job_arena.c: a job's arrays, from its arena when they fit (driver thread
 * only): 16-aligned, zeroed (tdc_job_alloc) or for the caller to fill
 * (tdc_job_alloc_uninit); NULL if out of memory.  tdc_job_release gives
 * one back (nothing for an arena array); tdc_job_free_arrays all of them.
 */
extern void *tdc_job_alloc(tdc_job *job, size_t size);
extern void *tdc_job_alloc_uninit(tdc_job *job, size_t size);
extern void tdc_job_release(tdc_job *job, void *ptr);
extern void tdc_job_free_arrays(tdc_job *job);

#endif							/* TDC_JOB_INT_H */
