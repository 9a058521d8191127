/*
 * cdt.c
 *		Constrained Delaunay triangulation: constraint segments inserted into
 *		a finished Delaunay triangulation, in place, with exact predicates.
 *		This file shares the segments out (the parallel pass, then the
 *		serial one) and runs them; the insertion of one segment, with its
 *		method, ties and rules, is cdt_insert.c's.
 *
 * Parallel pass.  With at least PART_MIN_SEG segments, the sites are cut
 * into NPART vertical stripes of equal width (a function of the sites alone,
 * never of the thread count).  A segment with both ends in stripe k goes to
 * stripe k's inserter, which takes its segments in input order and may only
 * change triangles whose three corners lie in stripe k: the moment a piece
 * would touch another triangle (a corner, a split site or a crossed triangle
 * outside the stripe, or more crossed edges than its fixed lists hold), it
 * leaves the segment, before changing anything of that piece, to the serial
 * pass.  Such triangles are never flipped by anyone in this pass (a flip
 * stays inside the union of the triangles a segment crosses), and an
 * inserter reads only edges with an end in its stripe, so inserters of
 * different stripes share nothing they write: the stripes run on a pool of
 * the job's thread count, in any order, and leave the same mesh, half-edge
 * for half-edge, as one thread running them one after the other.  Then the
 * serial pass inserts, in input order, every segment not done (ends in two
 * stripes, or left over), finding the pieces already in place as edges.
 * An error is the one of the lowest stripe that failed, else the serial
 * pass's, so it does not depend on the thread count either.  A counting
 * sort in the preparation lists each stripe's segments (and those with ends
 * in two stripes) in input order, so no inserter reads the others'.
 *
 * Speed.  Contour lines are mostly Delaunay edges already, so the insertion
 * of a million of them is mostly find_edge: turning around a segment's first
 * end to meet the other, a cache miss a step, each step depending on the
 * last.  find_edge turns both ways at once, and a stripe's inserter fetches
 * the first steps of its next segments ahead (part_task), so that several
 * misses are in flight at a time.
 *
 * Memory: 4 bytes per edge slot for the constraint numbers (12 per point),
 * 4 per site for vedge, the job's input map (4 per input point), and the
 * serial lists of crossed and new edges, which start small and double up to
 * one entry per edge slot (12 bytes per point each, counted in full); the
 * parallel pass adds 6 bytes per segment (its stripe, whether it is done,
 * and its place in the stripes' order), 1 per point and NPART fixed lists.
 * Cancel is polled before every segment and every 4096 steps inside one.  The
 * insertion runs like a triangulation, on the caller's thread when it is
 * small, otherwise on a thread with every signal blocked that the host
 * waits for and cancels (the runner of runner.c), whose pool threads
 * inherit that mask.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cdt_int.h"

/*
 * The preparation of the parallel pass, as tasks: task 0 sets vedge[],
 * task k > 0 sorts chunk k - 1 of the segments by stripe: both ends in
 * stripe i gives i, ends in two stripes SEG_SERIAL, one site SEG_NONE, and
 * counts the chunk's segments of each stripe.  A chunk stops at its first
 * bad segment and notes it in bad[k - 1].  Then order_task lists each
 * stripe's segments in order[], so that a stripe's inserter reads its own
 * segments only, not every segment's stripe (16 passes over them cost more
 * instructions than the insertion of contour lines).
 */
#define PREP_CHUNK	65536

/* order[]'s range of a seg_part[] value other than SEG_NONE: its stripe, or NPART */
static inline int
bucket(uint8_t part)
{
	return part < NPART ? part : NPART;
}

typedef struct cdt_prep
{
	tdc_cdt    *c;
	size_t	   *bad;
	size_t	   *pos;			/* per chunk and stripe: its count, then where it goes in order[] */
} cdt_prep;

/* Task k: the stripes of sites [k * PREP_CHUNK, (k + 1) * PREP_CHUNK). */
static void
spart_task(void *arg, size_t k, int worker)
{
	tdc_cdt    *c = arg;
	size_t		lo = k * PREP_CHUNK,
				hi = lo + PREP_CHUNK < c->mesh.nin ? lo + PREP_CHUNK : c->mesh.nin;

	for (size_t p = lo; p < hi; p++)
		c->spart[p] = x_part(c, c->mesh.xy[2 * p]);
}

static void
prep_task(void *arg, size_t k, int worker)
{
	cdt_prep   *pp = arg;
	tdc_cdt    *c = pp->c;
	const tdc_mesh_view *mesh = &c->mesh;
	size_t		lo,
				hi;
	const uint32_t *map;

	if (k == 0)
	{
		for (size_t h = 0; h < 6 * mesh->nin; h++)
		{
			if (mesh->he[h].org != TDC_NIL)
				c->vedge[mesh->he[h].org] = (uint32_t) h;
			if ((h & ((1 << 20) - 1)) == 0 &&
				atomic_load_explicit(&c->cancel, memory_order_relaxed))
				return;
		}
		return;
	}
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return;
	lo = (k - 1) * PREP_CHUNK;
	hi = lo + PREP_CHUNK < c->nseg ? lo + PREP_CHUNK : c->nseg;
	/* the first call builds the map, under the job's lock */
	map = tdc_job_input_map(c->job);
	if (map == NULL)
	{
		pp->bad[k - 1] = lo;
		return;
	}
	for (size_t s = lo; s < hi; s++)
	{
		uint32_t	i = c->seg[2 * s],
					j = c->seg[2 * s + 1],
					a,
					b;
		int			pa;

		if (i >= mesh->n || j >= mesh->n)
		{
			pp->bad[k - 1] = s;
			return;
		}
		a = map[i];
		b = map[j];
		pa = site_part(c, a);
		c->seg_part[s] = a == b ? SEG_NONE : pa == site_part(c, b) ? (uint8_t) pa : SEG_SERIAL;
		if (c->seg_part[s] != SEG_NONE)
			pp->pos[(k - 1) * (NPART + 1) + bucket(c->seg_part[s])]++;
	}
}

/*
 * Task k: chunk k's segments into order[], each to its stripe's range (or
 * the range of those with ends in two stripes) at the place prepare()
 * computed for this chunk, so that every range holds its segments in input
 * order.
 */
static void
order_task(void *arg, size_t k, int worker)
{
	cdt_prep   *pp = arg;
	tdc_cdt    *c = pp->c;
	size_t		lo = k * PREP_CHUNK,
				hi = lo + PREP_CHUNK < c->nseg ? lo + PREP_CHUNK : c->nseg,
			   *pos = pp->pos + k * (NPART + 1);

	for (size_t s = lo; s < hi; s++)
		if (c->seg_part[s] != SEG_NONE)
			c->order[pos[bucket(c->seg_part[s])]++] = (uint32_t) s;
}

/* Set vedge[] and sort the segments by stripe (prep_task), on the pool. */
static int
prepare(tdc_cdt *c, tdc_pool *pool, cdt_ctx *ser)
{
	const tdc_mesh_view *mesh = &c->mesh;
	size_t		nchunks = (c->nseg + PREP_CHUNK - 1) / PREP_CHUNK;
	cdt_prep	pp = {c, malloc(nchunks * sizeof(size_t)), calloc(nchunks * (NPART + 1), sizeof(size_t))};
	double		lo = INFINITY,
				hi = -INFINITY;
	size_t		at = 0;

	if (pp.bad == NULL || pp.pos == NULL)
	{
		free(pp.bad);
		free(pp.pos);
		return tdc_cdt_ctx_fail(ser, TDC_ENOMEM, "out of memory for the constraints");
	}
	for (size_t p = 0; p < mesh->nin; p++)
	{
		double		v = mesh->xy[2 * p];

		lo = v < lo ? v : lo;
		hi = v > hi ? v : hi;
	}
	c->part_x0 = lo;
	c->part_scale = hi > lo ? NPART / (hi - lo) : 0;
	tdc_pool_for(pool, (mesh->nin + PREP_CHUNK - 1) / PREP_CHUNK, spart_task, c);
	for (size_t k = 0; k < nchunks; k++)
		pp.bad[k] = SIZE_MAX;
	tdc_pool_for(pool, nchunks + 1, prep_task, &pp);
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
	{
		free(pp.bad);
		free(pp.pos);
		return TDC_ECANCELED;
	}
	for (size_t k = 0; k < nchunks; k++)
		if (pp.bad[k] != SIZE_MAX)
		{
			uint32_t	a,
						b;
			int			rc = tdc_cdt_seg_sites(ser, pp.bad[k], &a, &b);

			free(pp.bad);
			free(pp.pos);
			return rc != TDC_OK ? rc : tdc_cdt_internal_error(ser, pp.bad[k], "a segment was misread");
		}
	/* range by range, chunk by chunk: where each chunk's part of a range goes */
	for (int p = 0; p <= NPART; p++)
	{
		c->part_off[p] = at;
		for (size_t k = 0; k < nchunks; k++)
		{
			size_t		n = pp.pos[k * (NPART + 1) + p];

			pp.pos[k * (NPART + 1) + p] = at;
			at += n;
		}
	}
	c->part_off[NPART + 1] = at;
	tdc_pool_for(pool, nchunks, order_task, &pp);
	free(pp.bad);
	free(pp.pos);
	return TDC_OK;
}

/* How far ahead part_task fetches (see there). */
#define PF_DIST		8

/* The pool's task k: stripe k's segments, in input order. */
static void
part_task(void *arg, size_t k, int worker)
{
	tdc_cdt    *c = arg;
	cdt_ctx    *x = &c->parts[k];
	/* prepare() checked the ends and built the input map */
	const uint32_t *map = tdc_job_input_map(c->job);
	const tdc_he *he = c->m.he;
	size_t		end = c->part_off[k + 1];

	for (size_t i = c->part_off[k]; i < end; i++)
	{
		size_t		s = c->order[i];
		uint32_t	a,
					b;
		int			rc;

		if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		{
			x->rc = TDC_ECANCELED;
			return;
		}

		/*
		 * Fetch ahead what tdc_cdt_insert_segment will need for the segments to
		 * come: they are mostly edges already (contour lines), found by
		 * turning around their first end (find_edge), each step a cache miss
		 * that the next depends on.  vedge[] of the segment 2 * PF_DIST ahead,
		 * that half-edge's line PF_DIST ahead, and PF_DIST / 2 ahead the
		 * lines of its two neighbours around the site (find_edge turns both
		 * ways) and the three constraint slots: these misses are then in
		 * flight while earlier segments are inserted.  Edges around the
		 * stripe's own sites only, which no other inserter changes.  (1M
		 * contour segments, one thread: the insertion's CPU time -25%.)  In
		 * line, not in a function: GCC deletes a call whose body only
		 * prefetches.
		 */
		if (i + PF_DIST < end)
			__builtin_prefetch(&he[c->vedge[map[c->seg[2 * (size_t) c->order[i + PF_DIST]]]]]);
		if (i + PF_DIST / 2 < end)
		{
			uint32_t	v = c->vedge[map[c->seg[2 * (size_t) c->order[i + PF_DIST / 2]]]],
						n = he[v].next,
						p = he[v].prev;

			__builtin_prefetch(&he[n]);
			__builtin_prefetch(&he[p]);
			__builtin_prefetch(&c->cons[v >> 1]);
			__builtin_prefetch(&c->cons[n >> 1]);
			__builtin_prefetch(&c->cons[p >> 1]);
		}
		if (i + 2 * PF_DIST < end)
			__builtin_prefetch(&c->vedge[map[c->seg[2 * (size_t) c->order[i + 2 * PF_DIST]]]]);
		a = map[c->seg[2 * s]];
		b = map[c->seg[2 * s + 1]];
		rc = tdc_cdt_insert_segment(x, s, a, b);
		if (rc == TDC_OK)
		{
			c->seg_done[s] = 1;
			x->ndone++;
		}
		else if (rc == TDC_DEFER)
			c->order[c->part_off[k] + x->ndeferred++] = (uint32_t) s;	/* behind i */
		else
		{
			x->rc = rc;
			return;
		}
	}
}

/*
 * The parallel pass.  Stripe k's inserter only changes triangles whose three
 * corners lie in stripe k, and only reads edges with an end in stripe k or
 * triangles no inserter changes (those with corners in two stripes), so the
 * stripes' inserters touch disjoint parts of the mesh: run in any order or
 * at once, they leave the same mesh, and the first stripe with an error
 * names the same error.  With one thread they run one after the other, and
 * stop at the first error, as the threads' result is read.
 */
static int
run_parts(tdc_cdt *c, tdc_pool *pool)
{
	for (int k = 0; k < NPART; k++)
	{
		cdt_ctx    *x = &c->parts[k];

		x->c = c;
		x->part = k;
		x->list = c->part_lists + (size_t) 2 * k * PART_CAP;
		x->fresh = x->list + PART_CAP;
		x->cap = PART_CAP;
		x->cross[0] = x->cross[1] = SIZE_MAX;
	}
	if (pool != NULL)
		tdc_pool_for(pool, NPART, part_task, c);
	else
	{
		for (int k = 0; k < NPART; k++)
		{
			part_task(c, (size_t) k, 0);
			if (c->parts[k].rc != TDC_OK)
				break;
		}
	}
	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return TDC_ECANCELED;
	for (int k = 0; k < NPART; k++)
	{
		c->nconstraint += c->parts[k].nconstraint;
		c->npar_done += c->parts[k].ndone;
		c->npar_deferred += c->parts[k].ndeferred;
		if (c->parts[k].rc != TDC_OK)
			return tdc_cdt_take_error(c, &c->parts[k], c->parts[k].rc);
	}
	return TDC_OK;
}

/* The serial inserter on segment s; an error is taken into c. */
static int
serial_insert(tdc_cdt *c, cdt_ctx *ser, size_t s)
{
	uint32_t	a,
				b;
	int			rc;

	if (atomic_load_explicit(&c->cancel, memory_order_relaxed))
		return TDC_ECANCELED;
	rc = tdc_cdt_seg_sites(ser, s, &a, &b);
	if (rc == TDC_OK && a != b)
		rc = tdc_cdt_insert_segment(ser, s, a, b);
	return rc == TDC_OK ? TDC_OK : tdc_cdt_take_error(c, ser, rc);
}

/*
 * Many segments: the parallel pass then the serial one for what it left;
 * few: the serial one alone.  The pool is the job's thread count (none for
 * one thread: tdc_pool_for then runs the tasks itself).
 */
static int
cdt_run(tdc_cdt *c)
{
	const tdc_mesh_view *mesh = &c->mesh;
	size_t		nslots = mesh->nin * 3;
	cdt_ctx    *ser = &c->serial;
	int			rc,
				threads = mesh->threads;

	/* the one consumer that writes the mesh (mesh_view.h): its flips */
	c->m.xy = mesh->xy;
	c->m.he = tdc_job_edit_mesh(c->job);
	c->m.cancel = &c->cancel;
	c->nslots = nslots;
	ser->c = c;
	ser->part = -1;
	ser->cross[0] = ser->cross[1] = SIZE_MAX;
	c->cons = tdc_big_alloc(c->cache, nslots * sizeof(uint32_t) + 4);
	c->vedge = tdc_big_alloc(c->cache, mesh->nin * sizeof(uint32_t) + 4);
	ser->cap = nslots < LIST_MIN ? nslots : LIST_MIN;
	c->list = malloc(ser->cap * sizeof(uint32_t) + 4);
	c->fresh = malloc(ser->cap * sizeof(uint32_t) + 4);
	if (c->nseg >= PART_MIN_SEG)
	{
		c->seg_part = tdc_big_alloc(c->cache, 2 * c->nseg + mesh->nin);
		c->order = tdc_big_alloc(c->cache, c->nseg * sizeof(uint32_t));
		c->parts = calloc(NPART, sizeof(cdt_ctx));
		c->part_lists = malloc((size_t) 2 * NPART * PART_CAP * sizeof(uint32_t));
	}
	if (!c->cons || !c->vedge || !c->list || !c->fresh ||
		(c->nseg >= PART_MIN_SEG && (!c->seg_part || !c->order || !c->parts || !c->part_lists)))
		return tdc_cdt_take_error(c, ser, tdc_cdt_ctx_fail(ser, TDC_ENOMEM, "out of memory for the constraints of %zu points", mesh->nin));
	ser->list = c->list;
	ser->fresh = c->fresh;

	/* tdc_big_alloc's memory is zeroed: every cons[] is NO_SEG */
	if (c->seg_part != NULL)
	{
		tdc_pool   *pool = NULL;

		c->seg_done = c->seg_part + c->nseg;
		c->spart = c->seg_done + c->nseg;
		if (threads > 1 &&
			(rc = tdc_pool_create(&pool, threads < NPART ? threads : NPART)) != TDC_OK)
			return tdc_cdt_take_error(c, ser, tdc_cdt_ctx_fail(ser, rc, "could not create the insertion's threads"));
		rc = prepare(c, pool, ser);
		if (rc == TDC_OK)
			rc = run_parts(c, pool);
		else
			rc = tdc_cdt_take_error(c, ser, rc);
		tdc_pool_destroy(pool);
		if (rc != TDC_OK)
			return rc;
	}
	else
		for (size_t h = 0; h < 2 * nslots; h++)
			if (mesh->he[h].org != TDC_NIL)
				c->vedge[mesh->he[h].org] = (uint32_t) h;

	/*
	 * The serial pass, in input order.  After the parallel pass with no
	 * segment left over (contour lines: the common case), the ones with ends
	 * in two stripes are all there is, already listed in input order.
	 */
	if (c->seg_done != NULL)
		c->npar_serial = c->part_off[NPART + 1] - c->part_off[NPART];
	if (c->seg_done != NULL && c->npar_deferred == 0)
	{
		for (size_t i = c->part_off[NPART]; i < c->part_off[NPART + 1]; i++)
		{
			if ((rc = serial_insert(c, ser, c->order[i])) != TDC_OK)
				return rc;
		}
		return TDC_OK;
	}
	for (size_t s = 0; s < c->nseg; s++)
	{
		if (c->seg_done != NULL && (c->seg_done[s] || c->seg_part[s] == SEG_NONE))
			continue;
		if ((rc = serial_insert(c, ser, s)) != TDC_OK)
			return rc;
	}
	return TDC_OK;
}

/* The work, on the runner's thread or the caller's; returns the status. */
static int
cdt_work(void *arg)
{
	tdc_cdt    *c = arg;
	int			rc = cdt_run(c);

	c->nconstraint += c->serial.nconstraint;
	/* the lists are only needed while inserting */
	free(c->list);
	free(c->fresh);
	tdc_big_free(c->cache, c->vedge);
	tdc_big_free(c->cache, c->seg_part);
	tdc_big_free(c->cache, c->order);
	free(c->parts);
	free(c->part_lists);
	c->list = c->fresh = c->vedge = c->part_lists = c->order = NULL;
	c->seg_part = c->seg_done = c->spart = NULL;
	c->parts = NULL;
	if (rc == TDC_ECANCELED)
		snprintf(c->err, sizeof(c->err), "constraint insertion cancelled");
	else if (rc == TDC_OK)
		c->err[0] = '\0';
	return rc;
}

size_t
tdc_cdt_memory(size_t n)
{
	/* cons, vedge, list, fresh, and the job's input map */
	return n * (3 * 4 + 4 + 3 * 4 + 3 * 4 + 4) + 64;
}

/* The parallel pass's own arrays, for nseg segments and n points. */
static size_t
cdt_seg_memory(size_t nseg, size_t n)
{
	return nseg >= PART_MIN_SEG ?
		(2 + sizeof(uint32_t)) * nseg + n + NPART * (sizeof(cdt_ctx) + 2 * PART_CAP * sizeof(uint32_t)) +
		((nseg + PREP_CHUNK - 1) / PREP_CHUNK) * (NPART + 2) * sizeof(size_t) : 0;
}

int
tdc_cdt_start(tdc_job *job, const uint32_t *seg, size_t nseg, tdc_cdt **out,
			  char *err, size_t errlen)
{
	tdc_mesh_view mesh;
	tdc_cdt    *c;
	int			rc;

#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	*out = NULL;
	if (err && errlen)
		err[0] = '\0';
	if (tdc_job_wait(job, 0) != TDC_OK)
		FAIL(TDC_EINVAL, "the triangulation has not finished successfully");
	tdc_job_view(job, &mesh);
	if (nseg > MAX_SEG)
		FAIL(TDC_ETOOBIG, "%zu constraint segments exceed the limit of %zu", nseg, MAX_SEG);
	if (nseg > 0 && seg == NULL)
		FAIL(TDC_EINVAL, "no end points given for %zu segments", nseg);
	if (mesh.opt->max_memory > 0 &&
		tdc_estimate_memory(mesh.n, mesh.opt) + tdc_cdt_memory(mesh.n) +
		cdt_seg_memory(nseg, mesh.n) > mesh.opt->max_memory)
		FAIL(TDC_EMEMLIMIT, "constraining %zu points needs about %zu MB, more than the limit of %zu MB",
			 mesh.n, (tdc_estimate_memory(mesh.n, mesh.opt) + tdc_cdt_memory(mesh.n) +
					  cdt_seg_memory(nseg, mesh.n)) >> 20,
			 mesh.opt->max_memory >> 20);
	c = calloc(1, sizeof(tdc_cdt));
	if (c == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	c->job = job;
	c->mesh = mesh;
	c->cache = mesh.opt->cache;
	c->seg = seg;
	c->nseg = nseg;
	c->cross[0] = c->cross[1] = SIZE_MAX;
	tdc_runner_init(&c->run, &c->cancel);

	/* like the triangulation: small work runs on the caller's thread */
	c->inline_run = mesh.n < TDC_INLINE_MAX && nseg < TDC_INLINE_MAX;
	rc = tdc_runner_start(&c->run, c->inline_run, cdt_work, c, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&c->run);
		free(c);
		return rc;
	}
	*out = c;
	return TDC_OK;
#undef FAIL
}

int
tdc_cdt_wait(tdc_cdt *c, int timeout_ms)
{
	return tdc_runner_wait(&c->run, timeout_ms);
}

void
tdc_cdt_cancel(tdc_cdt *c)
{
	if (c)
		tdc_runner_cancel(&c->run);
}

const char *
tdc_cdt_error(const tdc_cdt *c)
{
	return c->err;
}

int
tdc_cdt_crossing(const tdc_cdt *c, size_t *s1, size_t *s2)
{
	if (c->run.status != TDC_ECROSS)
		return 0;
	*s1 = c->cross[0];
	*s2 = c->cross[1];
	return 1;
}

size_t
tdc_cdt_num_constraint_edges(const tdc_cdt *c)
{
	return c->nconstraint;
}

void
tdc_cdt_pass_counts(const tdc_cdt *c, size_t *parallel, size_t *deferred, size_t *serial)
{
	*parallel = c->npar_done;
	*deferred = c->npar_deferred;
	*serial = c->npar_serial;
}

void
tdc_cdt_free(tdc_cdt *c)
{
	if (c == NULL)
		return;
	tdc_runner_destroy(&c->run);
	tdc_big_free(c->cache, c->cons);
	free(c->list);
	free(c->fresh);
	tdc_big_free(c->cache, c->vedge);
	tdc_big_free(c->cache, c->seg_part);
	tdc_big_free(c->cache, c->order);
	free(c->parts);
	free(c->part_lists);
	free(c);
}

int
tdc_cdt_run(tdc_job *job, const uint32_t *seg, size_t nseg, tdc_cdt **out,
			char *err, size_t errlen)
{
	int			rc = tdc_cdt_start(job, seg, nseg, out, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_cdt_wait(*out, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", tdc_cdt_error(*out));
	return rc;
}

int
tdc_next_constraint_edge(const tdc_cdt *c, tdc_iter *it, uint32_t v[2])
{
	const tdc_mesh_view *mesh = &c->mesh;
	size_t		nslots = mesh->nin * 3;

	if (c->cons == NULL || c->run.status != TDC_OK)
		return 0;
	for (size_t e = it->pos; e < nslots; e++)
	{
		uint32_t	a,
					b;

		if (c->cons[e] == NO_SEG || c->cons[e] >= CAVQ)
			continue;
		a = mesh->he[2 * e].org;
		b = mesh->he[2 * e + 1].org;
		if (tdc_key_less(mesh->xy + 2 * (size_t) b, mesh->xy + 2 * (size_t) a, 0))
			v[0] = b, v[1] = a;
		else
			v[0] = a, v[1] = b;
		it->pos = e + 1;
		return 1;
	}
	it->pos = nslots;
	return 0;
}

/*
 * Validate a finished constrained job: its sites, triangles and the input
 * segments, renumbered densely, through tdc_validate_cdt().
 */
int
tdc_cdt_validate(const tdc_cdt *c, char *err, size_t errlen)
{
	const tdc_job *job = c->job;
	size_t		n = tdc_num_input(job),
				m = 0,
				t = 0,
				ns = 0;
	uint32_t	lim = tdc_site_id_limit(job),
			   *dense = malloc(sizeof(uint32_t) * ((size_t) lim + 1)),
			   *tri = malloc(12 * (tdc_num_triangles(job) + 1)),
			   *seg = malloc(8 * (c->nseg + 1)),
				v[3];
	double	   *sites = malloc(16 * (tdc_num_sites(job) + 1));
	tdc_iter	it = {0};
	int			rc = -1;

	if (!dense || !tri || !sites || !seg)
	{
		snprintf(err, errlen, "out of memory for validation");
		goto done;
	}
	for (uint32_t s = 0; s < lim; s++)
		dense[s] = UINT32_MAX;
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);

		if (s >= lim || (dense[s] == UINT32_MAX && m == tdc_num_sites(job)))
		{
			snprintf(err, errlen, "input %zu maps to a bad site %u", i, s);
			goto done;
		}
		if (dense[s] == UINT32_MAX)
		{
			dense[s] = (uint32_t) m;
			memcpy(sites + 2 * m++, tdc_site_xy(job, s), 16);
		}
	}
	while (tdc_next_triangle(job, &it, v))
	{
		if (t == tdc_num_triangles(job))
		{
			snprintf(err, errlen, "more triangles than the %zu reported", tdc_num_triangles(job));
			goto done;
		}
		for (int k = 0; k < 3; k++)
		{
			if (v[k] >= lim || dense[v[k]] == UINT32_MAX)
			{
				snprintf(err, errlen, "a triangle uses site %u, which no input reaches", v[k]);
				goto done;
			}
			tri[3 * t + k] = dense[v[k]];
		}
		t++;
	}
	for (size_t s = 0; s < c->nseg; s++)
	{
		uint32_t	a = dense[tdc_input_site(job, c->seg[2 * s])],
					b = dense[tdc_input_site(job, c->seg[2 * s + 1])];

		if (a != b)
		{
			seg[2 * ns] = a;
			seg[2 * ns++ + 1] = b;
		}
	}
	if (t != tdc_num_triangles(job))
		snprintf(err, errlen, "%zu triangles iterated, %zu reported", t, tdc_num_triangles(job));
	else
		rc = tdc_validate_cdt(sites, m, tri, t, seg, ns, err, errlen);
done:
	free(dense);
	free(tri);
	free(sites);
	free(seg);
	return rc;
}
