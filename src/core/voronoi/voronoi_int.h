/*
 * voronoi_int.h
 *		The state of a Voronoi diagram, shared by the files that build it:
 *		voronoi_geom.c (circumcenters), voronoi_number.c (triangle numbers
 *		and cocircular classes), voronoi_cell.c (cells and clipping),
 *		voronoi_write.c (the cells written into the host's value) and
 *		voronoi.c (the run and the lifecycle).  Not installed.
 */
#ifndef TDC_VORONOI_INT_H
#define TDC_VORONOI_INT_H

#include <math.h>
#include <stdlib.h>

#include "engine/exact.h"
#include "engine/mesh_view.h"

#define SITES_PER_TASK	4096	/* cells built per task, and per cancel poll */
#define ITEMS_PER_TASK	65536	/* half-edges or triangles per task */
#define CELL_RANGE_MIN	262144	/* half-edges per cell task, at least */
#define FLATTEN_CHUNKS	64		/* triangle chunks per flatten task (voronoi_number.c) */
#define TRI_CHUNK		1024	/* triangle numbers claimed at a time */

struct tdc_voronoi
{
	const tdc_job *job;			/* opaque (tdc.h): its accessors, the input map */
	tdc_mesh_view mesh;			/* what the diagram reads of it */
	tdc_cache  *cache;			/* the job's, kept: the job may be freed first */
	double		env[4];			/* E: xmin, ymin, xmax, ymax */
	double		box[4];			/* B, strictly around E, sites and vertices */
	int			threads;

	/* triangle structure */
	size_t		nhe;
	size_t		ntri;
	uint32_t   *tri_id;			/* half-edge -> triangle left of it, or NIL */
	_Atomic(uint32_t) *parent;	/* union-find over triangles, root = class min;
								 * NULL when no two triangles are cocircular */
	atomic_int	need_join;		/* two cocircular triangles' vertices differ */
	double	   *cc;				/* circumcenter of each class root, 2 per tri */
	_Atomic(uint32_t) *site_he; /* site -> smallest outgoing half-edge */
	size_t	   *range_ntri;		/* half-edge range -> triangles numbered */
	size_t		nchunks;		/* triangle numbers come in chunks (number_task) */
	size_t		ntri_cap;		/* nchunks * TRI_CHUNK: triangle numbers below */
	uint32_t   *chunk_fill;		/* chunk -> numbers used */
	atomic_size_t chunks_claimed;
	uint32_t   *tri_he;			/* joining: triangle -> its smallest half-edge */
	double	   *range_box;		/* 4 per range: bounding box of its vertices */

	/* collinear input */
	uint32_t   *line;			/* the sites sorted by (x, y) */
	uint32_t   *line_pos;		/* site -> its place in line[] */
	size_t		nline;

	/* cells */
	size_t		nsites;			/* site id limit */
	double	  **cell_xy;		/* site -> its ring, or NULL */
	uint32_t   *cell_n;			/* site -> vertices in its ring */
	size_t		nranges;
	size_t		cell_range;		/* half-edges per cell range (mesh input) */
	bool		big_bufs;		/* range_buf from tdc_big_alloc, not malloc */
	double	  **range_buf;		/* ring storage of each site range */
	size_t		total_vertices;

	/* tdc_voronoi_start_emit: sizes, then the cells straight to the writer */
	bool		emit;
	bool		writing;		/* the second phase (tdc_voronoi_emit) */
	tdc_cell_writer writer;
	uint64_t	emit_bytes;
	size_t		emit_cells;
	uint64_t   *range_bytes;	/* per cell range: bytes of its cells */
	size_t	   *range_cells;
	char	   *dst;
	size_t		ninput;
	uint32_t   *first_in;		/* site -> first input (tolerance only) */
	uint64_t   *inpos;			/* input -> its cell's size, then offset */
	uint64_t   *site_off;		/* site -> its cell's offset */
	bool		offsets_in_tri_id;	/* inpos and site_off live in tri_id's pages */
	uint32_t  **range_rec;		/* cell range -> its record (mesh_size_task) */
	size_t	   *range_rec_len;
	uint64_t   *block_start;	/* input block -> offset of its first cell */

	tdc_pool   *pool;
	atomic_int	cancel;
	atomic_int	failed;
	char		task_err[256];

	tdc_runner	run;			/* the driver and its status (runner.c) */
	char		err[256];
};

/* ----------------------------------------------------------------
 *		helpers
 * ----------------------------------------------------------------
 */
static inline bool
vor_cancelled(const tdc_voronoi *v)
{
	return atomic_load_explicit(&v->cancel, memory_order_relaxed) != 0;
}

static inline void
vor_fail(tdc_voronoi *v, int code, const char *msg)
{
	int			expected = 0;

	if (atomic_compare_exchange_strong(&v->failed, &expected, code))
		snprintf(v->task_err, sizeof(v->task_err), "%s", msg);
	atomic_store(&v->cancel, 1);
}

static inline const double *
site_pt(const tdc_voronoi *v, uint32_t s)
{
	return v->mesh.xy + 2 * (size_t) s;
}

static inline bool
is_outer(const tdc_mesh_view *mesh, size_t h)
{
	return tdc_he_outer(mesh->outer, h);
}

static inline void
grow_box(double *box, const double *p)
{
	box[0] = fmin(box[0], p[0]);
	box[1] = fmin(box[1], p[1]);
	box[2] = fmax(box[2], p[0]);
	box[3] = fmax(box[3], p[1]);
}

/*
 * The walks over the half-edges look at the next half-edge around each face
 * (tdc_tri_at), a random load in a mesh far bigger than the caches: ask for
 * it PREFETCH half-edges early, as emit.c does.  A free slot's link may be
 * anything: only prefetch inside the mesh.
 */
#define PREFETCH	16

static inline void
prefetch_face(const tdc_voronoi *v, size_t h, size_t hi)
{
	if (h + PREFETCH < hi)
	{
		uint32_t	ahead = v->mesh.he[SYM(h + PREFETCH)].prev;

		if (ahead < v->nhe)
			__builtin_prefetch(&v->mesh.he[SYM(ahead)]);
	}
}

static inline size_t
nranges_for(size_t n, size_t per)
{
	return n == 0 ? 0 : (n + per - 1) / per;
}

/* The class of the triangle left of h: its root, whose vertex is the class's. */
static inline uint32_t
class_of(const tdc_voronoi *v, uint32_t h)
{
	uint32_t	t = v->tri_id[h];

	return v->parent ? atomic_load_explicit(&v->parent[t], memory_order_relaxed) : t;
}

static inline const double *
vertex_of(const tdc_voronoi *v, uint32_t h)
{
	return v->cc + 2 * (size_t) class_of(v, h);
}

/* Are the two triangles beside edge h, h + 1 (h even) cocircular? */
static inline bool
edge_cocircular(const tdc_voronoi *v, size_t h)
{
	const tdc_mesh_view *mesh = &v->mesh;
	uint32_t	a = mesh->he[h].org,
				b = mesh->he[h + 1].org,
				c,
				d;

	if (a == TDC_NIL || b == TDC_NIL || is_outer(mesh, h) || is_outer(mesh, h + 1))
		return false;
	c = mesh->he[mesh->he[h + 1].prev ^ 1].org;	/* apex left of h */
	d = mesh->he[mesh->he[h].prev ^ 1].org;	/* apex left of h + 1 */
	return tdc_incircle(site_pt(v, a), site_pt(v, b), site_pt(v, c), site_pt(v, d)) == 0;
}

/*
 * Consecutive triangles ta and tb around a site, beside edge h: if their
 * vertices are close enough that the two triangles may be cocircular
 * (within the documented bound of each, 1/2 ulp + 2^-55 of the coordinate,
 * with room to spare), and they are, the classes are joined (vor_run).
 * Two cocircular triangles whose vertices came out as the same doubles
 * would need no join (the rings drop the repeat, as they must), but they
 * are joined all the same: it is what makes exactly cocircular input
 * (lattices) take, and so test, the path that the rare cocircular pair
 * with different roundings needs, and it costs nothing on input with no
 * four sites on a circle.  Once joined, every class has one vertex.
 */
static inline bool
close_coordinate(double a, double b)
{
	return fabs(a - b) <= 0x1p-48 * fmax(fabs(a), fabs(b));
}

static inline void
note_pair(const tdc_voronoi *v, uint32_t ta, uint32_t tb, uint32_t h)
{
	const double *a = v->cc + 2 * (size_t) ta,
			   *b = v->cc + 2 * (size_t) tb;

	if (v->parent)
		return;
	if (close_coordinate(a[0], b[0]) && close_coordinate(a[1], b[1]) &&
		edge_cocircular(v, h & ~(uint32_t) 1))
		atomic_store_explicit((atomic_int *) &v->need_join, 1, memory_order_relaxed);
}

/*
 * A ring being built.  A tagged ring also records, for each vertex, the
 * site across the edge that starts there (the neighbour whose bisector the
 * edge lies on), or TDC_NIL for an edge along B or E: clipping computes a
 * crossing from that bisector, not from the edge's end points, which may be
 * far away and rounded at their own, much larger, scale.
 */
typedef struct ring
{
	double	   *p;				/* 2 per vertex */
	uint32_t   *tag;			/* tagged rings: 1 per vertex */
	size_t		n;
	size_t		cap;
	bool		tagged;
	tdc_cache  *cache;			/* untagged: where p comes from (tdc_big_alloc) */
} ring;

static inline bool
ring_reserve(ring *r, size_t extra)
{
	if (r->n + extra > r->cap)
	{
		size_t		cap = (r->n + extra) + (r->n + extra) / 2 + 16;
		double	   *p = realloc(r->p, cap * 2 * sizeof(double));

		if (p == NULL)
			return false;
		r->p = p;
		if (r->tagged)
		{
			uint32_t   *t = realloc(r->tag, cap * sizeof(uint32_t));

			if (t == NULL)
				return false;
			r->tag = t;
		}
		r->cap = cap;
	}
	return true;
}

/*
 * Append a vertex whose outgoing edge has the given tag, dropping a repeat
 * of the previous vertex (which then takes the tag: the edge that starts
 * there is now this one); room was reserved.
 */
static inline void
ring_push(ring *r, double x, double y, uint32_t tag)
{
	if (r->n > 0 && r->p[2 * r->n - 2] == x && r->p[2 * r->n - 1] == y)
	{
		if (r->tagged)
			r->tag[r->n - 1] = tag;
		return;
	}
	r->p[2 * r->n] = x;
	r->p[2 * r->n + 1] = y;
	if (r->tagged)
		r->tag[r->n] = tag;
	r->n++;
}

/* Drop a closing repeat of the first vertex. */
static inline void
ring_close(ring *r)
{
	while (r->n > 1 && r->p[0] == r->p[2 * r->n - 2] && r->p[1] == r->p[2 * r->n - 1])
		r->n--;
}

/* voronoi_number.c: the numbering and cocircular tasks (tdc_pool_for) */
extern void tdc_vor_number_task(void *arg, size_t r, int worker);
extern void tdc_vor_parent_task(void *arg, size_t r, int worker);
extern void tdc_vor_tri_he_task(void *arg, size_t r, int worker);
extern void tdc_vor_cocircular_task(void *arg, size_t r, int worker);
extern void tdc_vor_flatten_task(void *arg, size_t r, int worker);

/* voronoi_cell.c: cells, clipping, and the cell tasks */
extern bool tdc_vor_clip_to_env(const tdc_voronoi *v, uint32_t site, ring *a, ring *b);
extern size_t tdc_vor_site_degree(const tdc_voronoi *v, uint32_t s, uint32_t *ho);
extern void tdc_vor_cell_of_mesh(const tdc_voronoi *v, uint32_t s, size_t deg, uint32_t ho, ring *r);
extern void tdc_vor_cell_task(void *arg, size_t rg, int worker);
extern void tdc_vor_mesh_cell_task(void *arg, size_t rg, int worker);

/* voronoi_write.c: sizing and writing the cells */
extern void tdc_vor_mesh_size_task(void *arg, size_t rg, int worker);
extern int tdc_vor_emit_run(tdc_voronoi *v);

#define FAIL_OOM(msg) do { vor_fail(v, TDC_ENOMEM, msg); return TDC_ENOMEM; } while (0)

#endif							/* TDC_VORONOI_INT_H */
