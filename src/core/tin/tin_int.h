/*
 * tin_int.h
 *		The state of a TIN (a finished triangulation with a height per
 *		site), shared by the files that build and use it: tin.c (building,
 *		lifecycle, the operations' runner), tin_locate.c (point location and
 *		nearest sites), tin_natural.c (Sibson's natural neighbour
 *		coordinates), tin_interp.c (the methods, points and grids),
 *		tin_contour.c (contour lines) and tin_drape.c (lines split at the
 *		triangle edges).  Not installed.
 *
 * The layers, bottom up, with no call loop between the files
 * (test/layering.sh): tin.c and tin_locate.c know only the job; tin_natural.c
 * uses tin_locate.c; tin_interp.c uses both and tin.c's runner; tin_contour.c
 * and tin_drape.c use tin_interp.c and tin.c.  tin.c runs an operation
 * through a function pointer the operation's file hands it, so it never
 * names them.
 */
#ifndef TDC_TIN_INT_H
#define TDC_TIN_INT_H

#include <math.h>
#include <stdlib.h>

#include "engine/exact.h"
#include "engine/mesh_view.h"

#define TIN_KD_LEAF		8		/* k-d ranges of at most this many sites are scanned */

/* A located point (tin_locate.c). */
typedef enum tin_loc_kind
{
	LOC_NONE = 0,				/* no site at all */
	LOC_FACE,					/* strictly inside triangle left of h */
	LOC_EDGE,					/* strictly inside edge a-b (h: a->b, or NIL) */
	LOC_VERTEX,					/* at site a (h: a half-edge out of a, or NIL) */
	LOC_OUTSIDE					/* strictly outside the hull: right of hull half-edge h
								 * (its left face a triangle), or off the line of
								 * collinear sites (h NIL) */
} tin_loc_kind;

typedef struct tin_loc
{
	tin_loc_kind kind;
	uint32_t	h;				/* a half-edge as above, TDC_NIL without a mesh */
	uint32_t	a,
				b;				/* LOC_EDGE: its ends; LOC_VERTEX: a */
} tin_loc;

/* What an operation (contours, a grid, points, a drape) runs on the pool. */
typedef int (*tin_op_fn) (tdc_tin *tin);

struct tdc_tin
{
	const tdc_job *job;		/* the opaque handle, for tdc.h calls */
	tdc_mesh_view mesh;		/* what the TIN reads of it (mesh_view.h) */
	tdc_cache  *cache;			/* the job's: its arrays go back there */
	int			threads;
	size_t		max_memory;		/* for the TIN and its operations; 0: none */
	const double *zin;			/* the caller's heights per input point, until built */

	/* the mesh, numbered */
	size_t		nsite_ids;		/* site id limit (mesh.nin) */
	size_t		nsites;			/* distinct sites */
	size_t		nhe;			/* half-edge slots */
	size_t		ntri;
	double	   *sz;				/* site -> its height (from its first input point) */
	uint32_t   *tri_he;			/* triangle -> its smallest half-edge */
	uint32_t   *he_tri;			/* half-edge -> triangle left of it, or TDC_NIL */
	_Atomic(uint32_t) *site_he; /* site -> its smallest outgoing half-edge */
	double		zmin,
				zmax;			/* of the sites' heights */
	double		lo[2],
				hi[2];			/* the sites' bounding box */

	/* the locate grid: cell -> a site in it (or a neighbouring cell's) */
	uint32_t	gw,
				gh;
	double		gscale[2];
	_Atomic(uint32_t) *cell_site;

	/* collinear sites (no triangle): sorted by (x, y) */
	uint32_t   *line;
	size_t		nline;

	/*
	 * A constrained mesh (mesh.constrained): its sites as an implicit k-d
	 * tree for the nearest site (tin.c builds it, tin_locate.c reads it).
	 * The range [lo, hi) of more than TIN_KD_LEAF sites has its median at
	 * lo + (hi - lo) / 2 in the order of its axis, the ones before it, the
	 * ones after; the axis is x at even depths, y at odd ones, and a site's
	 * key along x is (x, y), along y (y, x), so that distinct sites never
	 * tie.  NULL otherwise.
	 */
	uint32_t   *kd;
	size_t		nkd;

	/* the current operation and its results (see each op's file) */
	tin_op_fn	op;
	void	   *op_state;
	void		(*op_free) (tdc_tin *tin);
	bool		built;
	bool		inline_now;		/* the current work runs on the host's thread */

	tdc_pool   *pool;
	atomic_int	cancel;
	atomic_int	failed;
	atomic_size_t used;			/* bytes the operations hold, against max_memory */
	char		task_err[256];
	tdc_runner	run;
	char		err[256];
};

/* ----------------------------------------------------------------
 *		helpers
 * ----------------------------------------------------------------
 */
static inline bool
tin_cancelled(const tdc_tin *tin)
{
	return atomic_load_explicit(&tin->cancel, memory_order_relaxed) != 0;
}

/* Record the first task error and stop the others. */
static inline void
tin_fail(tdc_tin *tin, int code, const char *msg)
{
	int			expected = 0;

	if (atomic_compare_exchange_strong(&tin->failed, &expected, code))
		snprintf(tin->task_err, sizeof(tin->task_err), "%s", msg);
	atomic_store(&tin->cancel, 1);
}

static inline const double *
tin_pt(const tdc_tin *tin, uint32_t s)
{
	return tin->mesh.xy + 2 * (size_t) s;
}

static inline uint32_t
tin_org(const tdc_tin *tin, uint32_t h)
{
	return tin->mesh.he[h].org;
}

static inline uint32_t
tin_dest(const tdc_tin *tin, uint32_t h)
{
	return tin->mesh.he[h ^ 1u].org;
}

static inline uint32_t
tin_onext(const tdc_tin *tin, uint32_t h)
{
	return tin->mesh.he[h].next;
}

static inline uint32_t
tin_lnext(const tdc_tin *tin, uint32_t h)
{
	return tin->mesh.he[h ^ 1u].prev;
}

/* Is the face left of h the outer face (h a hull edge seen from outside)? */
static inline bool
tin_outer(const tdc_tin *tin, uint32_t h)
{
	return (tin->mesh.outer[h >> 6] >> (h & 63)) & 1;
}

/*
 * Count "bytes" more against the operations' share of max_memory; false
 * (and the TIN failed with TDC_EMEMLIMIT) when that would pass it.  Safe
 * from any task.
 */
extern bool tin_charge(tdc_tin *tin, size_t bytes, const char *what);
extern void tin_uncharge(tdc_tin *tin, size_t bytes);

/* tin.c: run op on the pool of the TIN's thread count, like a job's phase */
extern int	tin_op_start(tdc_tin *tin, tin_op_fn op, void *state,
						 void (*op_free) (tdc_tin *), bool inline_run,
						 char *err, size_t errlen);
/* the pool of the running operation */
static inline tdc_pool *
tin_pool(const tdc_tin *tin)
{
	return tin->pool;
}

/* tin_locate.c */
extern void tin_locate(const tdc_tin *tin, const double *q, uint32_t hint,
					   tin_loc *loc);
extern uint32_t tin_nearest(const tdc_tin *tin, const double *q, const tin_loc *loc);
extern uint32_t tin_start_he(const tdc_tin *tin, const double *q);
extern double tin_lerp_edge(const tdc_tin *tin, uint32_t a, uint32_t b,
							const double *q);
extern double tin_linear_face(const tdc_tin *tin, uint32_t h, const double *q);

/*
 * Per-thread scratch of the natural neighbour coordinates (tin_natural.c):
 * the cavity of one query, grown as needed.
 */
typedef struct tin_scratch
{
	uint32_t   *tri;			/* cavity triangles (their smallest half-edge) */
	size_t		ntri,
				cap;
	dd		   *cc;				/* their circumcenters relative to q, 2 per triangle */
	size_t		cccap;
	uint32_t   *hash;			/* open addressing: index into tri + 1, 0 empty */
	size_t		hcap;
	uint32_t   *bnd;			/* boundary half-edges, cavity on their left, then in order */
	size_t		nbnd,
				bcap;
	double	   *w;				/* per boundary vertex: its piece's area */
	dd		   *g;				/* per boundary edge: V(q)'s vertex, relative to q */
	size_t		wcap;
	dd		   *px,
			   *py;				/* one piece's polygon */
	size_t		pcap;
	size_t		bytes;			/* all of the above, allocated */
	size_t		charged;		/* of them charged against max_memory (tin_scratch_charge) */
} tin_scratch;

extern void tin_scratch_free(tin_scratch *sc);
/*
 * Charge what a task's scratch grew by against max_memory (false: over it,
 * the TIN failed); tin_scratch_release gives it back and frees it.
 */
extern bool tin_scratch_charge(tdc_tin *tin, tin_scratch *sc);
extern void tin_scratch_release(tdc_tin *tin, tin_scratch *sc);
/*
 * The natural neighbour (Sibson) value at q, located at loc (LOC_FACE or
 * LOC_EDGE strictly inside the hull).  Returns TDC_OK, or TDC_ENOMEM.
 */
extern int	tin_natural(const tdc_tin *tin, tin_scratch *sc, const double *q,
						const tin_loc *loc, double *z);

/*
 * tin_interp.c: the value of a method at q (1 with *z, 0 without, or an
 * error); *hint the walk's start and end; *where (or NULL) where q lies.
 */
extern int	tin_value_at(const tdc_tin *tin, const tdc_interp_spec *spec,
						 tin_scratch *sc, const double *q, uint32_t *hint,
						 double *z, tin_loc *where);
/*
 * tin_interp.c, max_edge (> 0): is edge a-b longer, exactly?  Does it keep
 * the triangle left of h?  Does it keep a triangle whose closure holds the
 * point located at lp (LOC_FACE or LOC_EDGE)?
 */
extern bool tin_edge_long(const tdc_tin *tin, uint32_t a, uint32_t b, double max_edge);
extern bool tin_face_kept(const tdc_tin *tin, uint32_t h, double max_edge);
extern bool tin_loc_kept(const tdc_tin *tin, const tin_loc *lp, double max_edge);
/* tin_interp.c: can spec run on tin (false with err)? */
extern bool tin_spec_ok(const tdc_tin *tin, const tdc_interp_spec *spec, char *err,
						size_t errlen);
/* tin_interp.c: fail the operation for a value's error, naming the point */
extern void tin_point_fail(tdc_tin *tin, int rc, const double *q);

#endif							/* TDC_TIN_INT_H */
