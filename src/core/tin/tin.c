/*
 * tin.c
 *		A TIN: a finished triangulation with a height per site, numbered and
 *		indexed for the operations on it (interpolation, contours, draping),
 *		and the lifecycle those operations share.
 *
 * What a TIN adds to the job.  The job's mesh (mesh_view.h) is a set of half-edges
 * with no numbering of its faces and no way in from a coordinate.  The
 * operations need three things more:
 *
 *	- the height of each site, from its first input point (tdc_site_input:
 *	  the lowest input index with the site's x and y, or the point a
 *	  tolerance kept), so that duplicates keep the first height, as the
 *	  output vertices of a triangulation do;
 *	- a dense numbering of the triangles, in the order of their smallest
 *	  half-edge (the order tdc_next_triangle gives them), and for every
 *	  half-edge the triangle on its left: the contour lines keep a mark per
 *	  triangle and level, and walk from triangle to triangle;
 *	- a way in: a grid of cells over the sites' box, each holding the
 *	  smallest site id inside it (or, for an empty cell, that of the nearest
 *	  filled cell before it in its row or column), and per site its
 *	  smallest outgoing half-edge.  A walk (tin_locate.c) starts there.
 *
 * All three are built by parallel loops on a pool of the TIN's thread
 * count, like a job's phases: the numbering by ranges of half-edges (count,
 * prefix sum, assign), the site half-edges and cell sites by atomic minima,
 * so the result does not depend on the thread count.  Sites that are all
 * collinear make no triangle; they are sorted by (x, y) instead, which is
 * their order along their line.
 *
 * Operations.  Each operation (tin_interp.c, tin_contour.c, tin_drape.c)
 * runs through tin_op_start: like a job's emit phase it reuses the runner
 * (runner.c) of the TIN, on a thread of its own with every signal blocked,
 * or on the caller's thread when it is small, and runs parallel loops on a
 * pool of the TIN's thread count.  The host waits with tdc_tin_wait and may
 * cancel with tdc_tin_cancel; the operation's results live in the TIN until
 * the next operation starts or the TIN is freed.  tin.c only ever calls an
 * operation through the pointer it was handed, so the files stay layered.
 *
 * Memory.  tdc_tin_memory counts the TIN's own arrays: per input point 8
 * bytes of height, 24 of half-edge to triangle, 8 of triangle to half-edge
 * (two triangles per point at most), 4 of site to half-edge and 4 of cell
 * (a cell per two points), 48 in all, plus the collinear sort or a
 * constrained TIN's nearest-site tree (4 each, never both): 56.  What an
 * operation holds beyond it (contour lines, draped vertices, scratch) is
 * charged as it grows (tin_charge) against the rest of max_memory.
 */
#include <stdio.h>
#include <string.h>
#include <sys/types.h>

#include "tin_int.h"

#define HE_PER_TASK		65536	/* half-edges per numbering task, and per cancel poll */
#define SITES_PER_TASK	65536

/* ----------------------------------------------------------------
 *		numbering
 * ----------------------------------------------------------------
 */
typedef struct number_ctx
{
	tdc_tin    *tin;
	size_t	   *count;			/* per range: its triangles, then its first number */
} number_ctx;

/* Pass 1: every half-edge of the range NIL, its triangles counted. */
static void
count_task(void *arg, size_t r, int worker)
{
	number_ctx *c = arg;
	tdc_tin    *tin = c->tin;
	size_t		lo = r * HE_PER_TASK,
				hi = lo + HE_PER_TASK < tin->nhe ? lo + HE_PER_TASK : tin->nhe,
				n = 0;
	uint32_t	v[3];

	if (tin_cancelled(tin))
		return;
	for (size_t h = lo; h < hi; h++)
	{
		tin->he_tri[h] = TDC_NIL;
		if (tdc_mesh_tri_at(&tin->mesh, h, v))
			n++;
	}
	c->count[r] = n;
}

static inline void
atomic_min_u32(_Atomic(uint32_t) *p, uint32_t v)
{
	uint32_t	cur = atomic_load_explicit(p, memory_order_relaxed);

	while (v < cur &&
		   !atomic_compare_exchange_weak_explicit(p, &cur, v, memory_order_relaxed,
												  memory_order_relaxed))
		;
}

/*
 * Pass 2: the range's triangles numbered from its first number, each of its
 * three half-edges told its triangle (each half-edge has one left face, so
 * no two tasks write the same one), and every live half-edge offered to its
 * origin as its smallest.
 */
static void
assign_task(void *arg, size_t r, int worker)
{
	number_ctx *c = arg;
	tdc_tin    *tin = c->tin;
	const tdc_mesh_view *mesh = &tin->mesh;
	size_t		lo = r * HE_PER_TASK,
				hi = lo + HE_PER_TASK < tin->nhe ? lo + HE_PER_TASK : tin->nhe,
				t = c->count[r];
	uint32_t	v[3];

	if (tin_cancelled(tin))
		return;
	for (size_t h = lo; h < hi; h++)
	{
		uint32_t	o = mesh->he[h].org;

		if (o == TDC_NIL)
			continue;
		atomic_min_u32(&tin->site_he[o], (uint32_t) h);
		if (tdc_mesh_tri_at(mesh, h, v))
		{
			uint32_t	h1 = mesh->he[h ^ 1u].prev,
						h2 = mesh->he[h1 ^ 1u].prev;

			tin->tri_he[t] = (uint32_t) h;
			tin->he_tri[h] = tin->he_tri[h1] = tin->he_tri[h2] = (uint32_t) t;
			t++;
		}
	}
}

/* The heights of a range of site ids, and each site into its cell. */
static void
site_task(void *arg, size_t r, int worker)
{
	tdc_tin    *tin = arg;
	const tdc_mesh_view *mesh = &tin->mesh;
	size_t		lo = r * SITES_PER_TASK,
				hi = lo + SITES_PER_TASK < tin->nsite_ids ? lo + SITES_PER_TASK : tin->nsite_ids;

	if (tin_cancelled(tin))
		return;
	for (size_t s = lo; s < hi; s++)
	{
		const double *p;
		double		z;
		double		fx,
					fy;
		uint32_t	cx,
					cy;

		if (mesh->site_of[s] != s)
			continue;
		z = tin->zin[mesh->idx[s]];
		if (!isfinite(z))
		{
			char		msg[128];

			snprintf(msg, sizeof(msg), "the height of input point %u is not finite",
					 mesh->idx[s]);
			tin_fail(tin, TDC_EINVAL, msg);
			return;
		}
		tin->sz[s] = z;
		p = mesh->xy + 2 * s;
		fx = (p[0] - tin->lo[0]) * tin->gscale[0];
		fy = (p[1] - tin->lo[1]) * tin->gscale[1];
		cx = fx >= tin->gw ? tin->gw - 1 : fx > 0 ? (uint32_t) fx : 0;
		cy = fy >= tin->gh ? tin->gh - 1 : fy > 0 ? (uint32_t) fy : 0;
		atomic_min_u32(&tin->cell_site[(size_t) cy * tin->gw + cx], (uint32_t) s);
	}
}

static int
cmp_line(const void *x, const void *y, void *arg)
{
	const tdc_tin *tin = arg;
	const double *p = tin_pt(tin, *(const uint32_t *) x),
			   *q = tin_pt(tin, *(const uint32_t *) y);

	return tdc_lex_less(p, q) ? -1 : tdc_lex_less(q, p) ? 1 : 0;
}

/*
 * The locate grid's size: about two sites a cell, the cells as square as
 * the box allows.  A flat box (collinear sites along an axis) gets one row.
 */
static void
plan_grid(tdc_tin *tin)
{
	double		w = tin->hi[0] - tin->lo[0],
				h = tin->hi[1] - tin->lo[1],
				cells = (double) tin->nsites / 2 + 1,
				gw,
				gh;

	if (!(w > 0) && !(h > 0))
		gw = gh = 1;
	else if (!(w > 0))
		gw = 1, gh = cells;
	else if (!(h > 0))
		gw = cells, gh = 1;
	else
	{
		gw = ceil(sqrt(cells * w / h));
		gh = ceil(cells / gw);
	}
	if (gw > 65536)
		gw = 65536;
	if (gh > 65536)
		gh = 65536;
	if (gw < 1)
		gw = 1;
	if (gh < 1)
		gh = 1;
	tin->gw = (uint32_t) gw;
	tin->gh = (uint32_t) gh;
	tin->gscale[0] = w > 0 ? tin->gw / w : 0;
	tin->gscale[1] = h > 0 ? tin->gh / h : 0;
	/* a scale that overflows (a box of subnormal width) is as good as none */
	if (!isfinite(tin->gscale[0]))
		tin->gscale[0] = 0;
	if (!isfinite(tin->gscale[1]))
		tin->gscale[1] = 0;
}

/*
 * Empty cells take the site of the nearest filled cell before them in their
 * row, else after; a row with none takes the row before (or after) it.  A
 * site a few cells away is as good a start as any: the walk goes on from
 * there.
 */
static void
fill_cells(tdc_tin *tin)
{
	size_t		gw = tin->gw,
				gh = tin->gh;
	_Atomic(uint32_t) *c = tin->cell_site;
	ssize_t		last_row = -1;

	for (size_t y = 0; y < gh; y++)
	{
		_Atomic(uint32_t) *row = c + y * gw;
		uint32_t	prev = TDC_NIL;
		bool		any = false;

		for (size_t x = 0; x < gw; x++)
		{
			if (row[x] != TDC_NIL)
				prev = row[x], any = true;
			else
				row[x] = prev;
		}
		if (!any)
			continue;
		/* the row's leading empty cells from its first filled one */
		prev = TDC_NIL;
		for (size_t x = gw; x-- > 0;)
		{
			if (row[x] != TDC_NIL)
				prev = row[x];
			else
				row[x] = prev;
		}
		/* rows before with nothing: this one */
		for (size_t yy = (size_t) (last_row + 1); yy < y; yy++)
			for (size_t x = 0; x < gw; x++)
				c[yy * gw + x] = row[x];
		last_row = (ssize_t) y;
	}
	for (size_t yy = (size_t) (last_row + 1); last_row >= 0 && yy < gh; yy++)
		for (size_t x = 0; x < gw; x++)
			c[yy * gw + x] = c[(size_t) last_row * gw + x];
}

/* ----------------------------------------------------------------
 *		the nearest-site tree of a constrained TIN
 * ----------------------------------------------------------------
 *
 * The greedy walk of tin_locate.c finds the nearest site only on a Delaunay
 * mesh: on a constrained one a site may have a nearer Delaunay neighbour
 * that a constraint cut it off from.  So a TIN on a constrained job keeps
 * its sites as an implicit k-d tree (tin_int.h), 4 bytes a site.  Sites are
 * distinct, so the keys never tie and the tree is the same whatever
 * selection built it: the values it gives do not depend on the thread
 * count.  The median is found by quickselect (median of three); past 64
 * rounds on one range, which only an adversarial order reaches, the range
 * is sorted instead, so the build stays O(n log n).
 */
typedef struct kd_order
{
	const tdc_tin *tin;
	int			axis;
} kd_order;

static inline bool
kd_less(const tdc_tin *tin, int axis, uint32_t a, uint32_t b)
{
	const double *p = tin_pt(tin, a),
			   *q = tin_pt(tin, b);

	if (p[axis] != q[axis])
		return p[axis] < q[axis];
	return p[1 - axis] < q[1 - axis];
}

static int
cmp_kd(const void *x, const void *y, void *arg)
{
	const kd_order *o = arg;
	uint32_t	a = *(const uint32_t *) x,
				b = *(const uint32_t *) y;

	return kd_less(o->tin, o->axis, a, b) ? -1 : kd_less(o->tin, o->axis, b, a) ? 1 : 0;
}

static inline void
kd_swap(uint32_t *a, size_t i, size_t j)
{
	uint32_t	t = a[i];

	a[i] = a[j];
	a[j] = t;
}

/* Put the k-th of a[0 .. n) in the axis's order at k, smaller ones before it. */
static void
kd_select(const tdc_tin *tin, uint32_t *a, size_t n, size_t k, int axis)
{
	size_t		lo = 0,
				hi = n - 1;
	int			rounds = 0;

	while (hi > lo)
	{
		size_t		mid = lo + (hi - lo) / 2,
					store = lo;
		uint32_t	pivot;

		if (++rounds > 64)
		{
			kd_order	o = {tin, axis};

			qsort_r(a + lo, hi - lo + 1, sizeof(uint32_t), cmp_kd, &o);
			return;
		}
		/* the median of a[lo], a[mid], a[hi] to a[hi], the pivot */
		if (kd_less(tin, axis, a[mid], a[lo]))
			kd_swap(a, lo, mid);
		if (kd_less(tin, axis, a[hi], a[lo]))
			kd_swap(a, lo, hi);
		if (kd_less(tin, axis, a[mid], a[hi]))
			kd_swap(a, mid, hi);
		pivot = a[hi];
		for (size_t i = lo; i < hi; i++)
			if (kd_less(tin, axis, a[i], pivot))
				kd_swap(a, i, store++);
		kd_swap(a, store, hi);
		if (store == k)
			return;
		if (k < store)
			hi = store - 1;
		else
			lo = store + 1;
	}
}

static void
kd_build(tdc_tin *tin, uint32_t *a, size_t n, int depth)
{
	while (n > TIN_KD_LEAF)
	{
		size_t		m = n / 2;

		if (n > SITES_PER_TASK && tin_cancelled(tin))
			return;
		kd_select(tin, a, n, m, depth & 1);
		kd_build(tin, a, m, depth + 1);
		a += m + 1;
		n -= m + 1;
		depth++;
	}
}

/* The build, on the driver thread (or the caller's for small TINs). */
static int
tin_build_run(tdc_tin *tin)
{
	const tdc_mesh_view *mesh = &tin->mesh;
	size_t		nr,
				ns,
				t = 0;
	number_ctx	c = {tin, NULL};

	tin->nsite_ids = mesh->nin;
	tin->nsites = mesh->nsites;
	tin->nhe = mesh->nin * 6;
	tin->ntri = mesh->ntri;
	tin->zmin = NAN;
	tin->zmax = NAN;
	if (tin->nsites == 0)
		return TDC_OK;
	tdc_site_extent(tin->job, tin->lo, tin->hi);
	plan_grid(tin);

	tin->sz = tdc_big_alloc_uninit(tin->cache, tin->nsite_ids * sizeof(double) + 8);
	tin->site_he = tdc_big_alloc_uninit(tin->cache, tin->nsite_ids * sizeof(uint32_t) + 4);
	tin->cell_site = tdc_big_alloc_uninit(tin->cache,
										  (size_t) tin->gw * tin->gh * sizeof(uint32_t));
	if (!tin->sz || !tin->site_he || !tin->cell_site)
		goto oom;
	memset(tin->site_he, 0xff, tin->nsite_ids * sizeof(uint32_t));
	memset(tin->cell_site, 0xff, (size_t) tin->gw * tin->gh * sizeof(uint32_t));

	ns = (tin->nsite_ids + SITES_PER_TASK - 1) / SITES_PER_TASK;
	tdc_pool_for(tin->pool, ns, site_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;
	fill_cells(tin);

	/* the heights' range: a sequential pass, a few ms per million sites */
	tin->zmin = INFINITY;
	tin->zmax = -INFINITY;
	for (size_t s = 0; s < tin->nsite_ids; s++)
		if (mesh->site_of[s] == s)
		{
			tin->zmin = fmin(tin->zmin, tin->sz[s]);
			tin->zmax = fmax(tin->zmax, tin->sz[s]);
		}

	if (tin->ntri == 0)
	{
		/* collinear (or one site): the sites along their line */
		tin->line = malloc(tin->nsites * sizeof(uint32_t) + 4);
		if (tin->line == NULL)
			goto oom;
		for (size_t s = 0; s < tin->nsite_ids; s++)
			if (mesh->site_of[s] == s)
				tin->line[tin->nline++] = (uint32_t) s;
		qsort_r(tin->line, tin->nline, sizeof(uint32_t), cmp_line, tin);
		/* no face to number (and no outer-face marks to read) */
		return TDC_OK;
	}

	if (mesh->constrained)
	{
		tin->kd = tdc_big_alloc_uninit(tin->cache, tin->nsites * sizeof(uint32_t) + 4);
		if (tin->kd == NULL)
			goto oom;
		for (size_t s = 0; s < tin->nsite_ids; s++)
			if (mesh->site_of[s] == s)
				tin->kd[tin->nkd++] = (uint32_t) s;
		kd_build(tin, tin->kd, tin->nkd, 0);
		if (tin_cancelled(tin))
			return TDC_ECANCELED;
	}

	nr = (tin->nhe + HE_PER_TASK - 1) / HE_PER_TASK;
	c.count = calloc(nr + 1, sizeof(size_t));
	tin->he_tri = tdc_big_alloc_uninit(tin->cache, tin->nhe * sizeof(uint32_t) + 4);
	tin->tri_he = tdc_big_alloc_uninit(tin->cache, tin->ntri * sizeof(uint32_t) + 4);
	if (!c.count || !tin->he_tri || !tin->tri_he)
	{
		free(c.count);
		goto oom;
	}
	tdc_pool_for(tin->pool, nr, count_task, &c);
	if (tin_cancelled(tin))
	{
		free(c.count);
		return TDC_ECANCELED;
	}
	for (size_t r = 0; r < nr; r++)
	{
		size_t		k = c.count[r];

		c.count[r] = t;
		t += k;
	}
	if (t != tin->ntri)
	{
		free(c.count);
		tin_fail(tin, TDC_EINVAL, "the mesh does not hold the triangles counted");
		return TDC_EINVAL;
	}
	tdc_pool_for(tin->pool, nr, assign_task, &c);
	free(c.count);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;
	return TDC_OK;

oom:
	tin_fail(tin, TDC_ENOMEM, "out of memory for the TIN");
	return TDC_ENOMEM;
}

/* ----------------------------------------------------------------
 *		lifecycle
 * ----------------------------------------------------------------
 */
static int
tin_work(void *arg)
{
	tdc_tin    *tin = arg;
	int			rc;

	/* inline work runs on the host's thread: no pool threads from there */
	if (tdc_pool_create(&tin->pool, tin->inline_now ? 1 : tin->threads) != 0)
	{
		snprintf(tin->err, sizeof(tin->err), "could not create worker threads");
		return TDC_ETHREAD;
	}
	rc = tin->built ? tin->op(tin) : tin_build_run(tin);
	tdc_pool_destroy(tin->pool);
	tin->pool = NULL;
	if (atomic_load(&tin->failed))
	{
		snprintf(tin->err, sizeof(tin->err), "%s", tin->task_err);
		return atomic_load(&tin->failed);
	}
	if (rc == TDC_ECANCELED || (rc == TDC_OK && atomic_load(&tin->cancel)))
	{
		snprintf(tin->err, sizeof(tin->err), "%s cancelled",
				 tin->built ? "TIN operation" : "TIN build");
		return TDC_ECANCELED;
	}
	if (rc == TDC_OK)
	{
		tin->built = true;
		tin->err[0] = '\0';
	}
	return rc;
}

size_t
tdc_tin_memory(size_t n)
{
	/* see the top of the file */
	return n * (8 + 24 + 8 + 4 + 4 + 4 + 4) + 4096;
}

bool
tin_charge(tdc_tin *tin, size_t bytes, const char *what)
{
	size_t		now = atomic_fetch_add(&tin->used, bytes) + bytes;

	if (tin->max_memory > 0 && now > tin->max_memory)
	{
		char		msg[256];

		snprintf(msg, sizeof(msg), "%s needs more than the memory limit of %zu MB",
				 what, tin->max_memory >> 20);
		tin_fail(tin, TDC_EMEMLIMIT, msg);
		return false;
	}
	return true;
}

void
tin_uncharge(tdc_tin *tin, size_t bytes)
{
	atomic_fetch_sub(&tin->used, bytes);
}

int
tdc_tin_start(const tdc_job *job, const double *z, int threads, size_t max_memory,
			  tdc_tin **out, char *err, size_t errlen)
{
	tdc_tin    *tin;
	int			rc;

#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	*out = NULL;
	if (err && errlen)
		err[0] = '\0';
	if (tdc_job_wait((tdc_job *) job, 0) != TDC_OK)
		FAIL(TDC_EINVAL, "the triangulation has not finished successfully");
	if (tdc_num_input(job) > 0 && z == NULL)
		FAIL(TDC_EINVAL, "no heights given for %zu points", tdc_num_input(job));
	if (threads < 0 || threads > 1024)
		FAIL(TDC_EINVAL, "threads must be between 0 and 1024, not %d", threads);
	if (max_memory > 0 && tdc_tin_memory(tdc_num_input(job)) > max_memory)
		FAIL(TDC_EMEMLIMIT, "a TIN of %zu points needs about %zu MB, more than the limit of %zu MB",
			 tdc_num_input(job), tdc_tin_memory(tdc_num_input(job)) >> 20, max_memory >> 20);
	tin = calloc(1, sizeof(tdc_tin));
	if (tin == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	tin->job = job;
	tdc_job_view(job, &tin->mesh);
	tin->cache = tin->mesh.opt->cache;
	tin->zin = z;
	tin->max_memory = max_memory;
	tin->threads = threads > 0 ? threads : tdc_threads_used(job);
	if (tin->threads < 1)
		tin->threads = 1;
	atomic_init(&tin->failed, 0);
	atomic_init(&tin->used, tdc_tin_memory(tdc_num_input(job)));
	tdc_runner_init(&tin->run, &tin->cancel);
	tin->inline_now = tin->mesh.nin <= TDC_INLINE_MAX;
	rc = tdc_runner_start(&tin->run, tin->inline_now, tin_work, tin, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&tin->run);
		free(tin);
		return rc;
	}
	*out = tin;
	return TDC_OK;
#undef FAIL
}

/*
 * Start an operation on a built TIN: the previous one's results go, then
 * op runs like the build (on the caller's thread when inline_run).
 */
int
tin_op_start(tdc_tin *tin, tin_op_fn op, void *state, void (*op_free) (tdc_tin *),
			 bool inline_run, char *err, size_t errlen)
{
	int			rc;

	if (!tin->built || tdc_runner_wait(&tin->run, 0) == TDC_RUNNING)
	{
		if (op_free)
		{
			tin->op_state = state;
			op_free(tin);
			tin->op_state = NULL;
		}
		if (err && errlen)
			snprintf(err, errlen, "the TIN %s", !tin->built ? "has not been built successfully" :
					 "is still running an operation");
		return TDC_EINVAL;
	}
	tdc_runner_rearm(&tin->run);
	if (tin->op_free)
		tin->op_free(tin);
	tin->op = op;
	tin->op_state = state;
	tin->op_free = op_free;
	atomic_store(&tin->cancel, 0);
	atomic_store(&tin->failed, 0);
	tin->task_err[0] = '\0';
	tin->inline_now = inline_run;
	rc = tdc_runner_start(&tin->run, inline_run, tin_work, tin, err, errlen);
	if (rc != TDC_OK)
		tdc_runner_finish(&tin->run, rc);
	return rc;
}

int
tdc_tin_wait(tdc_tin *tin, int timeout_ms)
{
	return tdc_runner_wait(&tin->run, timeout_ms);
}

void
tdc_tin_cancel(tdc_tin *tin)
{
	if (tin)
		tdc_runner_cancel(&tin->run);
}

const char *
tdc_tin_error(const tdc_tin *tin)
{
	return tin->err;
}

void
tdc_tin_free(tdc_tin *tin)
{
	if (tin == NULL)
		return;
	tdc_runner_destroy(&tin->run);
	if (tin->op_free)
		tin->op_free(tin);
	tdc_big_free(tin->cache, tin->sz);
	tdc_big_free(tin->cache, (void *) tin->site_he);
	tdc_big_free(tin->cache, (void *) tin->cell_site);
	tdc_big_free(tin->cache, tin->he_tri);
	tdc_big_free(tin->cache, tin->tri_he);
	tdc_big_free(tin->cache, tin->kd);
	free(tin->line);
	free(tin);
}

int
tdc_tin_build(const tdc_job *job, const double *z, int threads, size_t max_memory,
			  tdc_tin **out, char *err, size_t errlen)
{
	int			rc = tdc_tin_start(job, z, threads, max_memory, out, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_tin_wait(*out, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", (*out)->err);
	return rc;
}

void
tdc_tin_z_range(const tdc_tin *tin, double *zmin, double *zmax)
{
	*zmin = tin->zmin;
	*zmax = tin->zmax;
}
