/*
 * tdc.h
 *		Public API of the tdc_delaunay core: exact, deterministic, threaded
 *		twofold divide-and-conquer Delaunay triangulation of planar points
 *		(Wu, Rui, Su, Cheng, Wang 2014).
 *
 * The core is plain C11 + pthreads.  It never calls PostgreSQL, never exits,
 * and keeps no global mutable state: every triangulation is a tdc_job that
 * owns its threads and memory.  A job runs asynchronously so that the caller's
 * thread stays free to notice interrupts (query cancel) and call
 * tdc_job_cancel(); the workers poll the cancel flag and stop within a few ms.
 *
 * Site ids: the engine copies the input into its own order and removes
 * duplicates.  The surviving sites are identified by "site ids" in
 * [0, tdc_site_id_limit()).
 * Ids are not dense (removed duplicates leave holes) and their order depends
 * on the subdivision, so only compare triangle sets by coordinates.
 */
#ifndef TDC_H
#define TDC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Status codes.  Negative values are errors; the job keeps a message. */
#define TDC_OK				0
#define TDC_RUNNING			1	/* tdc_job_wait timed out */
#define TDC_ENOMEM			(-1)	/* malloc failed */
#define TDC_ECANCELED		(-2)	/* tdc_job_cancel was called */
#define TDC_EINVAL			(-3)	/* bad option or non-finite / out-of-range coordinate */
#define TDC_ETOOBIG			(-4)	/* more points than the 32-bit index width allows */
#define TDC_EMEMLIMIT		(-5)	/* would exceed options.max_memory */
#define TDC_ETHREAD			(-6)	/* pthread_create failed */
#define TDC_ECROSS			(-7)	/* two constraint segments cross (cdt_insert.c) */
#define TDC_EIO				(-8)	/* a file could not be read or written (bounded*.c) */

/*
 * Largest input size: the mesh numbers half-edges with uint32_t and needs
 * 6 per point.
 */
#define TDC_MAX_POINTS		((size_t) 700000000)

/* Deepest subdivision: options.levels is within [-1, TDC_MAX_LEVELS]. */
#define TDC_MAX_LEVELS		24

/*
 * Jobs of fewer points run on the caller's thread inside tdc_job_start(),
 * with no thread and no mapping: they finish in milliseconds, where starting
 * threads would cost more than the triangulation.  They are not cancellable
 * (tdc_job_cancel has nothing left to stop), and give the same triangles as
 * a threaded job would.
 */
#define TDC_INLINE_MAX		20000

/*
 * Coordinates must be 0 or of magnitude within [TDC_COORD_MIN, TDC_COORD_MAX];
 * inside that range every predicate is evaluated exactly.
 */
#define TDC_COORD_MIN		1e-60
#define TDC_COORD_MAX		1e60

/*
 * Freed big arrays a host keeps for its next jobs (mem.c).  The host creates
 * one, passes it in options.cache to the jobs it runs one after another, and
 * decides when to give the memory back; the jobs of one cache must not run
 * at the same time as tdc_cache_trim.  The cache never holds more than its
 * limit, and an array it has no room for is unmapped as without it.
 */
typedef struct tdc_cache tdc_cache;

extern tdc_cache *tdc_cache_create(size_t limit);	/* NULL: out of memory */
extern void tdc_cache_set_limit(tdc_cache *c, size_t limit);	/* trims to it */
/* Unmap until at most keep bytes are kept; false (nothing done) if the cache is in use. */
extern bool tdc_cache_trim(tdc_cache *c, size_t keep);
extern size_t tdc_cache_kept(tdc_cache *c);
extern void tdc_cache_destroy(tdc_cache *c);

typedef struct tdc_options
{
	int			threads;		/* worker threads; 0 = all online CPUs */
	int			grid_size;		/* s of the s x s auxiliary grid; 0 = auto */
	int			levels;			/* d: up to 2^d subsets; 0 = auto, -1 = none */
	double		tolerance;		/* > 0: drop a site closer than this to a kept one */
	size_t		max_memory;		/* bytes the engine may allocate; 0 = no limit */
	int			times;			/* measure phase times for tdc_job_times; 0 = zeros */
	tdc_cache  *cache;			/* where big arrays come from and go; NULL = none */
} tdc_options;

/* Phase timings in seconds, as in Table 1 of the paper. */
typedef struct tdc_times
{
	double		sort;			/* validation and the tolerance pass; no subset is sorted */
	double		subdivide;		/* step 1: grid subdivision into 2^d subsets */
	double		leaves;			/* step 2: Guibas-Stolfi inside every subset */
	double		merge;			/* step 3: merging up the tree */
	double		total;
} tdc_times;

typedef struct tdc_job tdc_job;

typedef struct tdc_iter
{
	size_t		pos;
} tdc_iter;

extern void tdc_options_init(tdc_options *opt);

/*
 * Bytes a job of n input points with these options (NULL: the defaults)
 * allocates at most, counting every array, the grid, the tree, the result
 * hand-over, the input map and the threads: what options.max_memory is
 * checked against.
 */
extern size_t tdc_estimate_memory(size_t n, const tdc_options *opt);

/*
 * Start triangulating n points given as interleaved x,y doubles.  The workers
 * copy them in parallel, so xy must stay valid and unchanged until
 * tdc_job_wait() has returned a final status or tdc_job_free() was called.
 * Signals are blocked in the worker threads.  On failure returns an error
 * code, *job is NULL and err holds a message.
 */
extern int	tdc_job_start(const double *xy, size_t n, const tdc_options *opt,
						  tdc_job **job, char *err, size_t errlen);

/*
 * Wait up to timeout_ms (< 0: forever).  Returns TDC_RUNNING on timeout,
 * otherwise the job's final status.
 */
extern int	tdc_job_wait(tdc_job *job, int timeout_ms);

/* Ask the workers to stop; tdc_job_wait then returns TDC_ECANCELED. */
extern void tdc_job_cancel(tdc_job *job);

/* Message for the final status ("" when TDC_OK). */
extern const char *tdc_job_error(const tdc_job *job);

/* Cancel if running, join threads, free everything.  NULL is allowed. */
extern void tdc_job_free(tdc_job *job);

/*
 * The same, but the memory is returned to the system by a detached thread
 * (signals blocked), so the caller does not wait for it: for error paths
 * where a user waits.  The job must not be used afterwards.
 */
extern void tdc_job_free_background(tdc_job *job);

/*
 * Hand every triangle of a finished job (tdc_job_wait returned TDC_OK) to
 * "emit" on the job's worker threads, for hosts that write big results:
 * emit(arg, first, count, v) receives count triangles, v holding 3 * count
 * site ids, that are triangles first .. first + count - 1 in the order of
 * tdc_next_triangle.  Calls for different ranges run concurrently, on threads
 * with every signal blocked, so emit must be thread-safe and must not call
 * into the host (a PostgreSQL backend: no palloc, no elog).  Runs like the
 * triangulation: tdc_job_wait then returns TDC_OK once every triangle was
 * handed over, or TDC_ECANCELED after tdc_job_cancel, in which case some
 * ranges were never emitted and the job keeps that status (free it).
 * Returns TDC_EINVAL for a job that has not finished successfully,
 * TDC_ETHREAD when no thread could be started (the job stays usable).
 */
typedef void (*tdc_emit_fn) (void *arg, size_t first, size_t count,
							 const uint32_t *v);
extern int	tdc_job_emit_start(tdc_job *job, tdc_emit_fn emit, void *arg,
							   char *err, size_t errlen);

/*
 * Map in the pages of [p, p + len) of freshly allocated memory in one call,
 * for a caller about to write all of it: cheaper than a page fault per page
 * (Linux 5.14's MADV_POPULATE_WRITE).  An emit callback writing a big result
 * may call it for its range.  Only a hint, safe from any thread and on pages
 * shared with other writers (their contents are not touched); without the
 * kernel's support the writes fault the pages in as usual.
 */
extern void tdc_prefault(void *p, size_t len);

/*
 * Transparent huge pages over the 2 MB pages inside [p, p + len) of memory
 * just allocated and not yet touched, mapped in one by one for as long as
 * each comes faster than 4 kB pages would (on a virtual machine whose host
 * has taken back the guest's free memory, a huge page can cost 4 ms); the
 * rest stays in 4 kB pages.  Returns false once a page was slow (or huge
 * pages are not available): a caller going through a big block in slices
 * stops asking then.  No cancel check inside: about 0.1 ms per 2 MB.
 */
extern bool tdc_advise_huge(void *p, size_t len);

/* Convenience: start + wait forever. */
extern int	tdc_triangulate(const double *xy, size_t n, const tdc_options *opt,
							tdc_job **job, char *err, size_t errlen);

/* --- Results, valid once tdc_job_wait returned TDC_OK --- */
extern size_t tdc_num_input(const tdc_job *job);
extern size_t tdc_num_sites(const tdc_job *job);		/* unique kept sites */
extern size_t tdc_num_triangles(const tdc_job *job);
extern size_t tdc_num_edges(const tdc_job *job);
extern int	tdc_threads_used(const tdc_job *job);
extern int	tdc_levels_used(const tdc_job *job);
extern int	tdc_grid_used(const tdc_job *job);
extern void tdc_job_times(const tdc_job *job, tdc_times *t);

/* Exclusive upper bound of site ids. */
extern uint32_t tdc_site_id_limit(const tdc_job *job);

/* Coordinates (x, y) of a site. */
extern const double *tdc_site_xy(const tdc_job *job, uint32_t site);

/*
 * Exact bounding box of the kept sites, which are the vertices of every
 * non-empty result: lo = (xmin, ymin), hi = (xmax, ymax).  O(1) without a
 * tolerance, one pass over the sites with one.
 */
extern void tdc_site_extent(const tdc_job *job, double lo[2], double hi[2]);

/* Input index of the first input point with this site's coordinates. */
extern size_t tdc_site_input(const tdc_job *job, uint32_t site);

/*
 * Site that input point i became (duplicates and tolerance drops included).
 * The first call builds the map: O(n) time and 4 bytes per input point;
 * returns UINT32_MAX if that allocation fails.  Safe from several threads.
 */
extern uint32_t tdc_input_site(const tdc_job *job, size_t i);

/*
 * label[] holds a label per input point (n of them): for every site, the
 * least label among the input points that became that site goes to the
 * slot of its first point, label[tdc_site_input(site)]; the other slots
 * keep their own.  A site's copies may carry different labels (a tiled
 * caller's tiles: the least owns the site).  Without a tolerance (a point
 * a tolerance dropped is not counted); no allocation.
 */
extern void tdc_least_labels(const tdc_job *job, int64_t *label);

/*
 * Iterate triangles: initialise it->pos = 0, then call until it returns 0.
 * v receives three site ids in counter-clockwise order.
 */
extern int	tdc_next_triangle(const tdc_job *job, tdc_iter *it, uint32_t v[3]);

/* Iterate undirected edges the same way (v[0] < v[1] in lexicographic x,y). */
extern int	tdc_next_edge(const tdc_job *job, tdc_iter *it, uint32_t v[2]);

/*
 * Exact validator (validate.c).  sites: m unique points; tri: ntri triangles
 * as indices into sites.  Checks counter-clockwise non-degenerate triangles,
 * manifold edges, boundary equal to the convex hull (collinear hull sites
 * included), every site used (unless all collinear), local Delaunay edges
 * under exact predicates, and ntri == 2m - 2 - h.  Returns 0 or -1 with err.
 */
extern int	tdc_validate(const double *sites, size_t m, const uint32_t *tri,
						 size_t ntri, char *err, size_t errlen);

/*
 * Validate a finished job's result: its unique sites (reached through the
 * input map, so collinear input counts too) and triangles, renumbered
 * densely, through tdc_validate().  Needs about 60 bytes per point.
 */
extern int	tdc_validate_job(const tdc_job *job, char *err, size_t errlen);

/* --- Voronoi diagram of a finished job (voronoi.c) --- */

/*
 * The Voronoi cells of a finished job's sites, clipped to the rectangle
 * env = {xmin, ymin, xmax, ymax}, which must contain every site.  Built on
 * "threads" worker threads (0: the job's count) by a thread of its own, like
 * a job: wait, cancel and free it the same way; tdc_voronoi_build is start
 * plus wait forever.  The job must stay alive and unchanged until the
 * diagram is freed.  A cell is a counter-clockwise ring, not closed (the
 * first vertex is not repeated), with no two consecutive vertices equal;
 * neighbouring cells share their vertices bit for bit.
 */
typedef struct tdc_voronoi tdc_voronoi;

extern int	tdc_voronoi_start(const tdc_job *job, const double env[4], int threads,
							  tdc_voronoi **v, char *err, size_t errlen);
extern int	tdc_voronoi_wait(tdc_voronoi *v, int timeout_ms);
extern void tdc_voronoi_cancel(tdc_voronoi *v);
extern const char *tdc_voronoi_error(const tdc_voronoi *v);
extern void tdc_voronoi_free(tdc_voronoi *v);
extern int	tdc_voronoi_build(const tdc_job *job, const double env[4], int threads,
							  tdc_voronoi **v, char *err, size_t errlen);

/*
 * Writing the cells straight into the host's value, on the worker threads,
 * with no copy of them kept: tdc_voronoi_start_emit builds the vertices
 * and sizes every cell (wait for it as for tdc_voronoi_start);
 * tdc_voronoi_emit_size then gives the bytes of all cells together (and
 * their count), the host allocates them, and tdc_voronoi_emit writes them
 * there (wait, cancel and free as before).  The cells come in the input
 * order of each site's first point, each at the offset where the previous
 * one ended: write(arg, dst, xy, m) must write exactly size(arg, m) bytes
 * for a cell of m vertices (a ring as tdc_voronoi_cell gives it).  Both run
 * on worker threads, at once on disjoint cells, so they must be pure code.
 * The bytes are the same whatever the thread count.  A diagram started this
 * way has no cells for tdc_voronoi_cell.
 */
typedef struct tdc_cell_writer
{
	size_t		(*size) (void *arg, size_t m);
	void		(*write) (void *arg, char *dst, const double *xy, size_t m);
	void	   *arg;
} tdc_cell_writer;

extern int	tdc_voronoi_start_emit(const tdc_job *job, const double env[4], int threads,
								   const tdc_cell_writer *writer, tdc_voronoi **v,
								   char *err, size_t errlen);
extern uint64_t tdc_voronoi_emit_size(const tdc_voronoi *v, size_t *cells);
extern int	tdc_voronoi_emit(tdc_voronoi *v, char *dst, char *err, size_t errlen);

/* Bytes a diagram of a job of n input points allocates at most. */
extern size_t tdc_voronoi_memory(size_t n, int threads);

/* The cell of a site: its vertex count, *xy the 2 * count coordinates; 0 for a non-site. */
extern size_t tdc_voronoi_cell(const tdc_voronoi *v, uint32_t site, const double **xy);

/* The clip envelope the diagram was built with. */
extern void tdc_voronoi_env(const tdc_voronoi *v, double env[4]);

/* Vertices of all cells together. */
extern size_t tdc_voronoi_num_vertices(const tdc_voronoi *v);

/*
 * GEOS's (and so PostGIS's) default clip envelope: the bounding box of the
 * input points (all of them, also those a tolerance dropped) grown on every
 * side by the larger of its width and height.
 */
extern void tdc_voronoi_default_env(const tdc_job *job, double env[4]);

/*
 * Circumcenter of the counter-clockwise triangle a, b, c, computed in
 * double-double and rounded once (error bound in voronoi_geom.c).
 */
extern void tdc_circumcenter(const double *a, const double *b, const double *c,
							 double out[2]);
/* --- Tiled triangulation (tile_final.c) ---
 *
 * The triangles of one tile of the global triangulation of a point set P,
 * computed from the points of a box K around the tile (its own points and a
 * halo), exactly as the one-shot run would give them.  See tile_final.c for the
 * proof.  The caller's loop, per tile:
 *
 *	K = the tile's box, plus a margin
 *	repeat
 *		xy, tile[] = every point of P inside closed K, with its tile's label
 *		tdc_tile_triangulate(xy, n, spec, ...)
 *		if res.final: write res.tri; break
 *		K = res.need (the caller may grow it more)
 *
 * Every global triangle is emitted by exactly one tile: the one that owns
 * its lexicographically smallest vertex, where a site (distinct x,y) belongs
 * to the smallest label among its copies.  The labels are the caller's (a
 * tile number, a rank of a tile column value); the own points of a tile
 * must lie inside its K.  No tolerance (options.tolerance must be 0).
 */
/*
 * Optional: a grid of cells over P that tells the check where P has no
 * point and which cells' points the caller passes whole.  Every point of P
 * lies in the closed box of its cell (cut[i] <= v < cut[i + 1] decides
 * the cell; the outer cuts reach P's box).  A cell is TDC_TILE_CELL_EMPTY
 * when it holds no point of P (known for free: a void between clusters, the
 * sea beside a coast), KNOWN when every point of P in it is passed, OTHER
 * otherwise.  With a grid a disk or a hull edge is also final when the
 * cells it meets are EMPTY or KNOWN, and a tile that is not final names the
 * OTHER cells it needs (need_cells): the next run adds their points, so the
 * known region grows by the cells that matter, not by a box around them.
 * A request names, for each disk or edge, the OTHER cells within the
 * least distance to them (from the own vertices, from the edge) plus
 * rings of the nearest cell's smaller side (0 counts as 1): a caller whose
 * tile keeps asking doubles it from run to run, so that a walk along a
 * rim of cells takes a few runs, not one run a cell.
 */
typedef struct tdc_tile_grid
{
	int			nx,
				ny;
	const double *xcut;			/* nx + 1 cell sides in x, non-decreasing */
	const double *ycut;			/* ny + 1 in y */
	const uint8_t *cell;		/* nx * ny states, row by row (row j: ycut[j] .. ycut[j + 1]) */
	double		rings;			/* how far a request reaches past the nearest cell, in its sides */
} tdc_tile_grid;

#define TDC_TILE_CELL_EMPTY		0
#define TDC_TILE_CELL_KNOWN		1
#define TDC_TILE_CELL_OTHER		2

typedef struct tdc_tile_spec
{
	const int64_t *tile;		/* n labels: the tile owning each point */
	int64_t		self;			/* this tile's label */
	double		known[4];		/* K: xmin, ymin, xmax, ymax; the caller passes every point of P in it */
	const double *extra;		/* nextra more boxes (4 doubles each) whose points are all passed */
	size_t		nextra;			/* too: thin bands along long edges of C, say (may be 0) */
	const double *hull;			/* convex polygon C containing P: nhull x,y vertices */
	size_t		nhull;			/* (the convex hull of P, or the 4 corners of P's bounding box) */
	const tdc_tile_grid *grid;	/* NULL, or the cells above */
	int			test_weaken;	/* tests only: 0, TDC_TILE_WEAKEN_DISKS or _BLOCKS */
} tdc_tile_spec;

/* tests only: take every triangle as final (shows that the disk test matters) */
#define TDC_TILE_WEAKEN_DISKS	1
/* tests only: take every block as non-empty (shows that the deep sites' counts matter) */
#define TDC_TILE_WEAKEN_BLOCKS	2

typedef struct tdc_tile_result
{
	int			final;			/* 1: tri holds the tile's triangles; 0: rerun with K = need */
	double		need[4];		/* when not final: a box containing K that the tile needs */
	size_t		ntri;
	size_t	   *tri;			/* 3 per triangle, counter-clockwise: indices into xy (the
								 * first point with the vertex's coordinates) */
	size_t		sites;			/* distinct sites in K */
	size_t		own_sites;		/* of them owned by this tile */
	size_t		unfinal;		/* triangles and hull edges at own sites found not final */
	size_t		deep;			/* triangles at own sites found final from block counts
								 * alone (a deep vertex, see tile_final.c), without a disk */
	uint32_t   *need_cells;		/* not final, with a grid: the OTHER cells (j * nx + i) */
	size_t		nneed_cells;	/* the next run needs, sorted; 0: grow to need instead */
} tdc_tile_result;

/*
 * Triangulate xy (n points, all inside spec->known) and return the tile's
 * final triangles, or the box it needs.  Returns TDC_OK (look at
 * res->final) or an error code with err; free res with
 * tdc_tile_result_free in both cases.
 */
extern int	tdc_tile_triangulate(const double *xy, size_t n, const tdc_tile_spec *spec,
								 const tdc_options *opt, tdc_tile_result *res,
								 char *err, size_t errlen);

/*
 * The same decision for a job the caller ran (tdc_job_start + tdc_job_wait
 * returned TDC_OK), for hosts that must stay interruptible while it runs.
 */
extern int	tdc_tile_finish(const tdc_job *job, const tdc_tile_spec *spec,
							tdc_tile_result *res, char *err, size_t errlen);

extern void tdc_tile_result_free(tdc_tile_result *res);

/*
 * Convex hull of n points (convex_hull.c), counter-clockwise, exact, collinear vertices
 * dropped (1 or 2 vertices for degenerate input): a malloc'd array of
 * *nhull x,y pairs (free() it), NULL when n = 0.  The hull of a union is
 * the hull of the parts' hulls, so it can be computed in chunks.
 */
extern int	tdc_convex_hull(const double *xy, size_t n, double **hull, size_t *nhull);
/*
 * Exact check of a constrained Delaunay triangulation (validate.c): the
 * checks of tdc_validate(), except that an edge lying on one of the nseg
 * segments (pairs of indices into sites) need not be locally Delaunay, and
 * every segment must be a chain of edges through exactly the sites on it.
 * A triangulation whose other edges are all locally Delaunay is the
 * constrained Delaunay triangulation (the constrained Delaunay lemma).
 */
extern int	tdc_validate_cdt(const double *sites, size_t m, const uint32_t *tri,
							 size_t ntri, const uint32_t *seg, size_t nseg,
							 char *err, size_t errlen);

/*
 * --- Constrained Delaunay triangulation (cdt.c) ---
 *
 * Insert constraint segments into a finished job's triangulation, in place:
 * afterwards the job's triangles (tdc_next_triangle, tdc_job_emit_start) are
 * the constrained Delaunay triangulation of its sites and the segments.
 * seg holds nseg pairs of input indices (into the xy given to
 * tdc_job_start), and must stay valid until tdc_cdt_wait returned a final
 * status.  Segments of zero length (after merging exact duplicates) are
 * ignored, a segment through other sites is split at them, overlaps merge;
 * two segments that cross at a point that is no site of both give
 * TDC_ECROSS, with a message naming both segments' end points.  The job's
 * tdc_job_cancel does not reach the insertion: use tdc_cdt_cancel.  Runs on
 * a thread of its own (signals blocked), on the caller's thread when job and
 * segments are small (fewer than TDC_INLINE_MAX each).  Many segments are
 * inserted on the job's thread count, by stripes, then the rest serially;
 * the result and the error reported do not depend on the thread count.
 * On error the job's mesh is a valid triangulation but not the CDT: free it.
 */
typedef struct tdc_cdt tdc_cdt;

/*
 * Bytes tdc_cdt_start allocates at most, beyond the job, for n input points
 * (at least 8192 segments add 6 bytes each, 1 per point and about 0.5 MB,
 * which tdc_cdt_start counts against options.max_memory as well).
 */
extern size_t tdc_cdt_memory(size_t n);

extern int	tdc_cdt_start(tdc_job *job, const uint32_t *seg, size_t nseg,
						  tdc_cdt **cdt, char *err, size_t errlen);
extern int	tdc_cdt_wait(tdc_cdt *cdt, int timeout_ms);
extern void tdc_cdt_cancel(tdc_cdt *cdt);
extern const char *tdc_cdt_error(const tdc_cdt *cdt);
/* Start + wait forever. */
extern int	tdc_cdt_run(tdc_job *job, const uint32_t *seg, size_t nseg,
						tdc_cdt **cdt, char *err, size_t errlen);
/* After TDC_ECROSS: the numbers of the two segments; returns 1, else 0. */
extern int	tdc_cdt_crossing(const tdc_cdt *cdt, size_t *s1, size_t *s2);
extern size_t tdc_cdt_num_constraint_edges(const tdc_cdt *cdt);
/*
 * The parallel pass (at least 8192 segments; else all three are 0): the
 * segments its stripes inserted, those they left to the serial pass (a piece
 * would have touched a triangle with a corner in another stripe, or crossed
 * more edges than a stripe's lists hold), and those with ends in two
 * stripes, which only the serial pass inserts.  The same for every thread
 * count.
 */
extern void tdc_cdt_pass_counts(const tdc_cdt *cdt, size_t *parallel, size_t *deferred,
								size_t *serial);
/* Iterate the constraint edges like tdc_next_edge. */
extern int	tdc_next_constraint_edge(const tdc_cdt *cdt, tdc_iter *it, uint32_t v[2]);
/* tdc_validate_cdt on the result; the job must still exist. */
extern int	tdc_cdt_validate(const tdc_cdt *cdt, char *err, size_t errlen);
/* Stop (if running) and free; the job stays.  NULL is allowed. */
extern void tdc_cdt_free(tdc_cdt *cdt);

/*
 * --- TIN analysis (tin*.c): heights on a finished triangulation ---
 *
 * A TIN is a finished job (tdc_job_wait returned TDC_OK) with a height per
 * input point.  A site's height is that of its first input point (the
 * lowest input index among the points with its x and y; with a tolerance,
 * the kept point's), so samples with equal x, y and different heights keep
 * the first.  On it, heights are interpolated at points and at the pixel
 * centres of a grid, lines are draped, and contour lines are drawn.
 *
 * Exactness.  Which triangle, edge or vertex a point lies in, which side of
 * an edge a line passes, and which triangles a natural neighbour query
 * conflicts with are decided by the exact predicates; which site is nearest
 * is decided by exact distance comparisons (ties: the site first in (x, y)
 * order).  Heights are computed in double (natural neighbour areas in
 * double-double), in a fixed order of a triangle's vertices (from its first
 * in (x, y) order), so every value is the same for any thread count and
 * any walk that reached it.  Query coordinates follow the input's rule: 0
 * or of magnitude within [TDC_COORD_MIN, TDC_COORD_MAX].
 *
 * Lifecycle.  tdc_tin_start builds the TIN on worker threads, like a job:
 * wait, cancel and free it the same way (tdc_tin_build is start plus wait
 * forever).  Each operation below then starts on the same TIN and is waited
 * for with tdc_tin_wait again; one operation at a time, and its results
 * stay until the next one starts or the TIN is freed.  The job and the
 * heights must stay alive and unchanged until tdc_tin_wait returned the
 * build's final status; the job until the TIN is freed.  Small work runs on
 * the caller's thread before the start returns, as a small job does.
 */
typedef struct tdc_tin tdc_tin;

/* Interpolation methods */
#define TDC_INTERP_LINEAR	1	/* barycentric in the triangle containing the point */
#define TDC_INTERP_NEAREST	2	/* the nearest site's height */
#define TDC_INTERP_NATURAL	3	/* Sibson's natural neighbour interpolation */

/*
 * A method and its options, in GDAL's gdal_grid syntax and with its
 * defaults (tdc_interp_parse).  Outside the convex hull of the sites,
 * linear and natural neighbour take the nearest site's height when it is
 * within radius (< 0: at any distance; 0: never), as GDAL's linear does,
 * and nodata otherwise; a point exactly on the hull's boundary is inside
 * (linear along the hull edge, for both).  Nearest takes the nearest site
 * within radius (radius1 = radius2 in GDAL's terms; 0: any distance).
 *
 * max_edge (> 0; 0: none) drops the triangles with an edge longer than it,
 * for every method: a lake or a building with no sample inside is then
 * nodata instead of long facets across it.  The lengths are in the (x, y)
 * plane and compared exactly (the squared length against max_edge^2), so
 * an edge exactly max_edge long is kept, on every machine alike.  A point
 * has a value when it lies at a site (a sample keeps its height, even in
 * the middle of dropped triangles), or when some triangle containing it,
 * closed, keeps all its edges: a point on an edge between a kept and a
 * dropped triangle has the edge's value, one strictly inside a dropped
 * triangle or on an edge longer than max_edge has none.  Without any
 * triangle (collinear sites) the segment between two neighbouring sites
 * plays the triangle's part.  Outside the hull the radius rule above
 * applies unchanged (radius=0 makes the outside nodata too).  The mask
 * only decides where there is a value; the value is the method's, from
 * all the samples.  options holds a TDC_INTERP_OPT_* bit for each option
 * the text gave, for hosts that take only some of them.
 */
#define TDC_INTERP_OPT_RADIUS		0x01	/* radius, radius1, radius2 or angle */
#define TDC_INTERP_OPT_NODATA		0x02
#define TDC_INTERP_OPT_BREAKLINES	0x04
#define TDC_INTERP_OPT_MAX_EDGE		0x08

typedef struct tdc_interp_spec
{
	int			method;			/* TDC_INTERP_* */
	double		radius;
	double		nodata;			/* the value written where there is none */
	bool		breaklines;		/* linear: the host inserts the samples' lines
								 * as constraints (tdc_cdt_start) before the TIN */
	double		max_edge;		/* > 0: triangles with a longer edge have no value */
	unsigned	options;		/* TDC_INTERP_OPT_*: the options the text gave */
} tdc_interp_spec;

/*
 * Parse "linear[:radius=R][:nodata=V][:breaklines=B][:max_edge=L]",
 * "nearest[:radius1=R][:radius2=R][:angle=A][:nodata=V][:max_edge=L]" or
 * "natural_neighbor[:radius=R][:nodata=V][:max_edge=L]" (GDAL's defaults:
 * linear radius -1, nodata 0; nearest radius 0, nodata 0; max_edge, not
 * GDAL's, none); "natural_neighbour" and "invdist"-style names are not
 * accepted.  L must be a number > 0 (infinity: none); options may come in
 * any order, a repeated one counts its last value.  B is true, false, yes,
 * no, on, off, 1 or 0 (any case; default false); the parser only records
 * it, the host acts on it by building the TIN on a constrained
 * triangulation.
 * breaklines is an option of linear only: natural neighbour coordinates
 * are defined by the Delaunay triangulation (a constrained one has no
 * empty-circle property to take them from), and the nearest sample does
 * not depend on any triangulation, so for those two it is an error rather
 * than silently ignored.  Unknown methods and options, bad numbers and
 * values, and an elliptic nearest search (radius1 != radius2) are
 * TDC_EINVAL with a message.
 */
extern int	tdc_interp_parse(const char *text, tdc_interp_spec *spec, char *err,
							 size_t errlen);

/*
 * Bytes a TIN over a job of n input points allocates at most, beyond the
 * job (a constrained one's nearest-site tree included).
 */
extern size_t tdc_tin_memory(size_t n);

/*
 * A TIN may be built on a job whose constraints were inserted (tdc_cdt_run:
 * "breaklines"): its triangles are then the constrained triangulation's,
 * and linear interpolation, draping and contours follow them, so the
 * surface does not cut across a constraint.  Nearest sites are then found
 * by a tree of the sites (4 bytes a site) instead of a walk on the mesh,
 * which is only right on a Delaunay one; natural neighbour interpolation on
 * such a TIN is TDC_EINVAL.
 *
 * Start building the TIN of a finished job, z holding one height per input
 * point (finite), on "threads" worker threads (0: the job's count).
 * max_memory bounds the TIN and its operations (0: no limit): an operation
 * that would need more stops with TDC_EMEMLIMIT.
 */
extern int	tdc_tin_start(const tdc_job *job, const double *z, int threads,
						  size_t max_memory, tdc_tin **tin, char *err, size_t errlen);
extern int	tdc_tin_wait(tdc_tin *tin, int timeout_ms);
extern void tdc_tin_cancel(tdc_tin *tin);
extern const char *tdc_tin_error(const tdc_tin *tin);
extern void tdc_tin_free(tdc_tin *tin);
extern int	tdc_tin_build(const tdc_job *job, const double *z, int threads,
						  size_t max_memory, tdc_tin **tin, char *err, size_t errlen);

/* The range of the sites' heights (NaN without a site). */
extern void tdc_tin_z_range(const tdc_tin *tin, double *zmin, double *zmax);

/*
 * The value at one point, on the caller's thread (tests, a few points):
 * 1 with *z set, 0 where there is none (*z = spec->nodata), TDC_EINVAL for
 * a coordinate out of range, TDC_ENOMEM.  The built TIN must not be running
 * an operation.
 */
extern int	tdc_tin_value(const tdc_tin *tin, const tdc_interp_spec *spec,
						  const double q[2], double *z);

/*
 * Is q inside the closed convex hull of the sites (1), outside (0)?  With
 * fewer than three non-collinear sites, the hull is the segment or point
 * they span.
 */
extern int	tdc_tin_inside(const tdc_tin *tin, const double q[2]);

/*
 * Values at n points xy (x,y interleaved), on the worker threads: z[i] and
 * valid[i] (1, or 0 with z[i] = spec->nodata).  xy, z and valid must stay
 * valid until tdc_tin_wait returned a final status.  A coordinate out of
 * range stops it with TDC_EINVAL.
 */
extern int	tdc_tin_points_start(tdc_tin *tin, const tdc_interp_spec *spec,
								 const double *xy, size_t n, double *z,
								 uint8_t *valid, char *err, size_t errlen);

/*
 * Values at the pixel centres of a grid, the interface the raster
 * functions (a template raster's extent and resolution) build on.  The
 * grid has width x height pixels and GDAL's affine geotransform gt: pixel
 * (col, row) covers the parallelogram whose corner (col, row) is
 *		x = gt[0] + col * gt[1] + row * gt[2]
 *		y = gt[3] + col * gt[4] + row * gt[5]
 * and its value is taken at its centre (col + 0.5, row + 0.5), as
 * gdal_grid does.  values[row * width + col] receives the value and
 * valid[...] 1, or spec->nodata and 0 where there is none (outside the
 * hull beyond the radius, or no site); valid may be NULL.  The rows are
 * shared out among the worker threads, each row walking from its previous
 * pixel's triangle; cancel with tdc_tin_cancel (polled every row).  values
 * and valid must stay valid until tdc_tin_wait returned a final status.
 * The values are the same for any thread count.  Pixel centres computed
 * from gt must follow the coordinate rule (TDC_EINVAL otherwise).
 */
typedef struct tdc_grid_spec
{
	double		gt[6];
	size_t		width,
				height;
} tdc_grid_spec;

extern int	tdc_tin_grid_start(tdc_tin *tin, const tdc_interp_spec *spec,
							   const tdc_grid_spec *grid, double *values,
							   uint8_t *valid, char *err, size_t errlen);

/*
 * Contour lines at the levels base + k * interval (k any integer; each
 * level computed as that one double expression), merged into maximal
 * lines: a line ends only on the hull's boundary (or max_edge's, below),
 * and is otherwise a closed ring (its first point repeated at its end).
 * Heights equal to a level count as above it (the level lowered by an
 * infinitesimal), so a line through a sample or along an edge at the
 * level's height appears once, with no duplicate and no gap; a peak
 * exactly at a level gives no line.
 * Lines are oriented with the higher ground on their left (rings around
 * hills counter-clockwise; a ring starts at its point first in (x, y)
 * order), come level by level, increasing, and within a level sorted by
 * their points: the same for any thread count.  A crossing lies
 * on its triangle edge, at parameter (level - z0) / (z1 - z0) from the
 * lower end, computed once per edge, so neighbouring triangles share it
 * bit for bit; at a site whose height is the level, it is the site.
 * TDC_EINVAL for an interval that is not finite and > 0, or too small for
 * the heights' resolution (two levels would round to one double), or a
 * base that is not finite.
 */
extern int	tdc_tin_contours_start(tdc_tin *tin, double interval, double base,
								   char *err, size_t errlen);
/*
 * The same, on the triangles spec keeps (NULL: all of them): a line stops
 * where it would enter a triangle with an edge longer than max_edge, so it
 * is open there, as at the hull, and a ring around a hole opens.  spec
 * must be "linear" with no option but max_edge (breaklines=false allowed):
 * tdc_tin_contours_spec_check says so, or TDC_EINVAL with a message, for a
 * host to check its method before building the TIN.
 */
extern int	tdc_tin_contours_start_spec(tdc_tin *tin, double interval, double base,
										const tdc_interp_spec *spec, char *err,
										size_t errlen);
extern int	tdc_tin_contours_spec_check(const tdc_interp_spec *spec, char *err,
										size_t errlen);
/* After the contours: their count and total points. */
extern size_t tdc_tin_contour_count(const tdc_tin *tin, size_t *points);
/* Line i: its level, its *n points (x,y interleaved), whether closed. */
extern const double *tdc_tin_contour_line(const tdc_tin *tin, size_t i, double *level,
										  size_t *n, bool *closed);

/*
 * Drape polylines: nchains chains of vertices, chain c being the vertices
 * [chain_end[c - 1], chain_end[c]) of xy (chain_end[-1] = 0): a point is a
 * chain of one vertex, a ring a chain whose last vertex repeats its first.
 * Every vertex gets the method's value; with TDC_INTERP_LINEAR every
 * segment whose ends are both inside the hull also gets a vertex where it
 * crosses a triangle edge or passes through a site (in order along it),
 * so the draped line follows the TIN exactly: a crossing lies on its edge
 * at a parameter computed from the edge's ends in (x, y) order, and its
 * height is the linear one along that edge, which both triangles' planes
 * share.  The result (tdc_tin_drape_result) lists, for each output vertex,
 * its x, y, z, whether it has a value and whether it lies in the hull, the
 * input vertex its segment starts at and its parameter t along that
 * segment (0 at the input vertex; for interpolating M), chain after chain.  Memory grows with the crossings
 * and is counted against max_memory.  With max_edge every vertex, input or
 * crossing, has a value by the rule above (valid); and with linear, gap
 * marks a vertex whose piece of line to the next output vertex has no
 * value: it runs through a triangle with an edge longer than max_edge, or
 * along an edge none of whose triangles is kept, though both its ends may
 * lie on kept triangles.
 */
typedef struct tdc_drape_vertex
{
	double		x,
				y,
				z;
	double		t;				/* along the segment from input vertex src */
	uint32_t	src;			/* input vertex (index into xy) */
	uint8_t		valid;			/* 1: z is the method's value; 0: z = nodata */
	uint8_t		inside;			/* 1: in the closed convex hull of the sites */
	uint8_t		gap;			/* 1: max_edge drops the way to the next vertex */
	uint8_t		pad;
} tdc_drape_vertex;

extern int	tdc_tin_drape_start(tdc_tin *tin, const tdc_interp_spec *spec,
								const double *xy, const size_t *chain_end,
								size_t nchains, char *err, size_t errlen);
/*
 * After the drape: all output vertices (*v) and chain c's range
 * [(*chain_off)[c], (*chain_off)[c + 1]); returns the vertex count.
 */
extern size_t tdc_tin_drape_result(const tdc_tin *tin, const tdc_drape_vertex **v,
								   const size_t **chain_off);

/* The bounded run and its terrain products: tdc_bounded.h, part of this API. */
#include "tdc_bounded.h"

#endif							/* TDC_H */
