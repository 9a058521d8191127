/*
 * engine_int.h
 *		Structures shared by the engine's files (and the features that
 *		run on its pool and runner).  Not installed.
 *
 * The mesh is Guibas & Stolfi's quad-edge structure reduced to its primal
 * half: undirected edge e owns half-edges 2e and 2e+1 (so Sym is h ^ 1), and
 * every half-edge stores its origin and its neighbours in the ring of
 * half-edges around that origin, counter-clockwise (next = Onext) and
 * clockwise (prev = Oprev).  Keeping Oprev explicitly makes Splice four
 * stores and every GS navigation primitive one load:
 *		Lnext(h) = Oprev(Sym(h)),  Rprev(h) = Onext(Sym(h)).
 * The arrays are flat and indexed by uint32_t: 12 bytes per half-edge, and at
 * most 3 edges per input point are ever alive (a planar straight-line graph on
 * m vertices has at most 3m - 6 edges), so capacity 3n never runs out.
 *
 * Every subset of the subdivision owns the edge slots [3 lo, 3 hi) of its
 * point range [lo, hi).  Deleted or never used slots of a subset are kept on
 * the subset's free list, so merging two adjacent subsets needs no locking:
 * their slot ranges and free lists are disjoint.
 */
#ifndef TDC_ENGINE_INT_H
#define TDC_ENGINE_INT_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "tdc.h"
#include "predicates.h"

#define TDC_NIL		UINT32_MAX

typedef struct tdc_he
{
	uint32_t	org;			/* origin site; TDC_NIL when the edge is free */
	uint32_t	next;			/* Onext; for a free edge's first half: next free edge */
	uint32_t	prev;			/* Oprev */
} tdc_he;

/*
 * A triangulated subset, as the merge needs it.  Directions: 0 = minimum of
 * the key (x, y), 1 = maximum of (x, y), 2 = minimum of (y, -x), 3 = maximum
 * of (y, -x).  ext[k] is the convex hull half-edge leaving the extreme site
 * in direction k with the hull traversed counter-clockwise (outer face on its
 * right).  A subset of one site has no edges: ext[] = NIL and vert is the
 * site.  An empty subset has vert = NIL and no edges.
 */
typedef struct tdc_freelist
{
	uint32_t	head;			/* free edge slots (edge numbers), singly linked */
	uint32_t	tail;
	uint32_t	bump;			/* never used slots [bump, limit), taken after the list */
	uint32_t	limit;
} tdc_freelist;

typedef struct tdc_sub
{
	uint32_t	ext[4];
	uint32_t	vert;
	uint32_t	nsites;
	tdc_freelist fl;			/* slots this subset may still use */
} tdc_sub;

/* What a triangulation step needs: sites, mesh, cancel flag. */
typedef struct tdc_mesh
{
	const double *xy;			/* site coordinates, 2 per site */
	tdc_he	   *he;
	const atomic_int *cancel;
} tdc_mesh;

/*
 * Arrays that grow with the input (mem.c): big ones are mapped (or taken
 * from the host's cache, which may be NULL) and unmapped (or kept in it),
 * small ones come from malloc.  The memory comes zeroed and 64-aligned.
 * NULL on failure; tdc_big_free(cache, NULL) does nothing.  An array must be
 * freed with the cache it was allocated with, or NULL.
 */
extern void *tdc_big_alloc(tdc_cache *cache, size_t size);
/* The same, for an array its user fills before reading: contents undefined. */
extern void *tdc_big_alloc_uninit(tdc_cache *cache, size_t size);
extern void tdc_big_free(tdc_cache *cache, void *p);

/* Thread pool (pool.c): a parallel-for on which the calling thread helps. */
typedef struct tdc_pool tdc_pool;
typedef void (*tdc_task_fn) (void *arg, size_t i, int worker);

extern int	tdc_pool_create(tdc_pool **pool, int nthreads);
extern void tdc_pool_for(tdc_pool *pool, size_t ntasks, tdc_task_fn fn, void *arg);
extern void tdc_pool_destroy(tdc_pool *pool);

/*
 * The lifecycle of a job, a constraint insertion and a Voronoi diagram
 * (runner.c): work on a thread with every signal blocked, or inline on the
 * caller's; a status the host waits for with a timeout; a cancel flag (the
 * owner's) the work polls; cancel and join on free.
 */
typedef int (*tdc_work_fn) (void *arg);

typedef struct tdc_runner
{
	atomic_int *cancel;			/* the owner's flag, polled by its work */
	tdc_work_fn work;			/* what the thread runs, and on what */
	void	   *arg;
	pthread_t	thread;
	bool		started;		/* a thread was started and not joined yet */
	bool		inline_only;	/* tdc_runner_init_inline: no thread, no condvar */
	pthread_mutex_t lock;
	pthread_cond_t done;
	bool		finished;		/* under lock */
	int			status;			/* under lock */
} tdc_runner;

extern void tdc_runner_init(tdc_runner *r, atomic_int *cancel);
extern void tdc_runner_init_inline(tdc_runner *r, atomic_int *cancel);
extern int	tdc_runner_start(tdc_runner *r, bool inline_run, tdc_work_fn work,
							 void *arg, char *err, size_t errlen);
extern void tdc_runner_finish(tdc_runner *r, int status);
extern int	tdc_runner_wait(tdc_runner *r, int timeout_ms);
extern void tdc_runner_cancel(tdc_runner *r);
extern void tdc_runner_rearm(tdc_runner *r);
extern void tdc_runner_destroy(tdc_runner *r);
extern int	tdc_thread_create_masked(pthread_t *thread, const pthread_attr_t *attr,
									 void *(*fn) (void *), void *arg);

/* merge.c: Guibas-Stolfi merge of two separated subsets along an axis. */
extern void tdc_merge(tdc_mesh *m, tdc_freelist *fl, const tdc_sub *L,
					  const tdc_sub *R, int axis, tdc_sub *out);

/* merge.c: the extremes of a subset of 2 or 3 sorted sites, once its edges exist. */
extern void tdc_sub_from_sites(tdc_mesh *m, const uint32_t *v, const uint32_t *ccw,
							   int n, tdc_sub *out);


static inline bool
tdc_cancelled(const tdc_mesh *m)
{
	return atomic_load_explicit(m->cancel, memory_order_relaxed) != 0;
}

/* Lexicographic keys: axis 0 is (x, y), axis 1 is (y, -x). */
static inline bool
tdc_key_less(const double *p, const double *q, int axis)
{
	if (axis == 0)
		return tdc_lex_less(p, q);
	return p[1] < q[1] || (p[1] == q[1] && p[0] > q[0]);
}

/* --- mesh primitives (Guibas & Stolfi 1985, section 4) --- */

#define SYM(h)		((h) ^ 1u)

static inline uint32_t
tdc_org(const tdc_mesh *m, uint32_t h)
{
	return m->he[h].org;
}

static inline uint32_t
tdc_dest(const tdc_mesh *m, uint32_t h)
{
	return m->he[SYM(h)].org;
}

static inline uint32_t
tdc_onext(const tdc_mesh *m, uint32_t h)
{
	return m->he[h].next;
}

static inline uint32_t
tdc_oprev(const tdc_mesh *m, uint32_t h)
{
	return m->he[h].prev;
}

static inline uint32_t
tdc_lnext(const tdc_mesh *m, uint32_t h)
{
	return m->he[SYM(h)].prev;
}

static inline uint32_t
tdc_rprev(const tdc_mesh *m, uint32_t h)
{
	return m->he[SYM(h)].next;
}

/* Exchange the rings after a and after b: joins two rings or splits one. */
static inline void
tdc_splice(tdc_mesh *m, uint32_t a, uint32_t b)
{
	tdc_he	   *he = m->he;
	uint32_t	an = he[a].next;
	uint32_t	bn = he[b].next;

	he[a].next = bn;
	he[b].next = an;
	he[bn].prev = a;
	he[an].prev = b;
}

/* Take an edge slot from the subset's free list; the list never runs dry. */
static inline uint32_t
tdc_make_edge(tdc_mesh *m, tdc_freelist *fl, uint32_t org, uint32_t dest)
{
	uint32_t	e,
				h;
	tdc_he	   *he = m->he;

	if (fl->head != TDC_NIL)
	{
		e = fl->head;
		fl->head = he[2 * e].next;
		if (fl->head == TDC_NIL)
			fl->tail = TDC_NIL;
	}
	else
		e = fl->bump++;
	h = 2 * e;
	he[h].org = org;
	he[h].next = he[h].prev = h;
	he[h + 1].org = dest;
	he[h + 1].next = he[h + 1].prev = h + 1;
	return h;
}

static inline void
tdc_free_edge(tdc_mesh *m, tdc_freelist *fl, uint32_t h)
{
	uint32_t	e = h >> 1;

	h = 2 * e;
	m->he[h].org = m->he[h + 1].org = TDC_NIL;
	m->he[h].next = fl->head;
	if (fl->head == TDC_NIL)
		fl->tail = e;
	fl->head = e;
}

/* Append list b to list a. */
static inline void
tdc_freelist_concat(tdc_mesh *m, tdc_freelist *a, const tdc_freelist *b)
{
	if (b->head == TDC_NIL)
		return;
	if (a->head == TDC_NIL)
		*a = *b;
	else
	{
		m->he[2 * (size_t) a->tail].next = b->head;
		a->tail = b->tail;
	}
}

static inline void
tdc_delete_edge(tdc_mesh *m, tdc_freelist *fl, uint32_t h)
{
	tdc_splice(m, h, tdc_oprev(m, h));
	tdc_splice(m, SYM(h), tdc_oprev(m, SYM(h)));
	tdc_free_edge(m, fl, h);
}

/* New edge from Dest(a) to Org(b), left faces of a and b joined (GS Connect). */
static inline uint32_t
tdc_connect(tdc_mesh *m, tdc_freelist *fl, uint32_t a, uint32_t b)
{
	uint32_t	e = tdc_make_edge(m, fl, tdc_dest(m, a), tdc_org(m, b));

	tdc_splice(m, e, tdc_lnext(m, a));
	tdc_splice(m, SYM(e), b);
	return e;
}

static inline const double *
tdc_pt(const tdc_mesh *m, uint32_t v)
{
	return m->xy + 2 * (size_t) v;
}

#endif							/* TDC_ENGINE_INT_H */
