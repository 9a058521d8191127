/*
 * voronoi.c
 *		The Voronoi diagram of a finished triangulation, clipped to a
 *		rectangle: one convex cell per site.  This file runs it and holds its
 *		lifecycle.
 *
 * The diagram is the dual of the Delaunay triangulation (Delaunay 1934; de
 * Berg et al., "Computational Geometry", 3rd ed., theorem 9.6): a vertex per
 * triangle, its circumcenter, and a cell per site read off the ring of
 * half-edges around it, so only the vertices are rounded.  The triangles
 * are numbered, cocircular ones joined and the cells built by parallel loops
 * on a driver thread with every signal blocked, polling cancel; a host that
 * wants one value gets the cells sized first, then written straight into it
 * in input order (tdc_voronoi_start_emit), the same bytes for any thread
 * count.  The mesh is read through mesh_view.h.
 *
 * The design note, with the reasons and the references, is
 * docs/design/voronoi.md; the other concerns have their own files, each
 * with its part of it: voronoi_geom.c (the error bound of the
 * circumcenters), voronoi_number.c (cocircular sites), voronoi_cell.c
 * (unbounded cells, clipping, collinear sites), voronoi_write.c (the
 * writer).
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "voronoi_int.h"

static int
cmp_site(const void *x, const void *y, void *arg)
{
	const tdc_voronoi *v = arg;
	const double *p = site_pt(v, *(const uint32_t *) x),
			   *q = site_pt(v, *(const uint32_t *) y);

	return tdc_lex_less(p, q) ? -1 : tdc_lex_less(q, p) ? 1 : 0;
}


/*
 * B: around E, the sites (base) and the vertices of the ranges' boxes,
 * widened on every side by its larger extent.
 */
static void
set_outer_box(tdc_voronoi *v, const double base[4], size_t nboxes)
{
	double		box[4] = {base[0], base[1], base[2], base[3]},
				w;

	for (size_t r = 0; r < nboxes; r++)
	{
		if (v->range_box[4 * r] <= v->range_box[4 * r + 2])
		{
			grow_box(box, v->range_box + 4 * r);
			grow_box(box, v->range_box + 4 * r + 2);
		}
	}
	w = fmax(box[2] - box[0], box[3] - box[1]);
	if (!(w > 0))
		w = fmax(fabs(box[2]), fabs(box[3])) + 1;
	v->box[0] = box[0] - w;
	v->box[1] = box[1] - w;
	v->box[2] = box[2] + w;
	v->box[3] = box[3] + w;
}

/*
 * The cells, into buffers or (emit) sized and recorded; every site's count
 * in cell_n.  Run again from scratch after the classes were joined.
 */
static int
build_cells(tdc_voronoi *v)
{
	size_t		nr = v->nranges;

	v->total_vertices = 0;
	v->emit_bytes = 0;
	v->emit_cells = 0;
	if (v->emit && v->ntri > 0)
	{
		for (size_t r = 0; r < nr; r++)
		{
			free(v->range_rec[r]);
			v->range_rec[r] = NULL;
			v->range_rec_len[r] = 0;
		}
		tdc_pool_for(v->pool, nr, tdc_vor_mesh_size_task, v);
		if (vor_cancelled(v))
			return TDC_ECANCELED;
		for (size_t r = 0; r < nr; r++)
		{
			v->emit_bytes += v->range_bytes[r];
			v->emit_cells += v->range_cells[r];
		}
		for (size_t s = 0; s < v->nsites; s++)
			v->total_vertices += v->cell_n[s];
		return TDC_OK;
	}
	for (size_t r = 0; r < nr; r++)
	{
		if (v->big_bufs)
			tdc_big_free(v->cache, v->range_buf[r]);
		else
			free(v->range_buf[r]);
		v->range_buf[r] = NULL;
	}
	tdc_pool_for(v->pool, nr, v->ntri > 0 ? tdc_vor_mesh_cell_task : tdc_vor_cell_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	for (size_t s = 0; s < v->nsites; s++)
	{
		v->total_vertices += v->cell_n[s];
		if (v->emit && v->cell_n[s] > 0)
		{
			v->emit_bytes += v->writer.size(v->writer.arg, v->cell_n[s]);
			v->emit_cells++;
		}
	}
	return TDC_OK;
}

/*
 * Join the triangles of every cocircular edge into classes, each with its
 * root's vertex, and B again from the roots' vertices.
 */
static int
join_cocircular(tdc_voronoi *v, const double base[4])
{
	size_t		nr = nranges_for(v->nhe, ITEMS_PER_TASK),
				ntr = nranges_for(v->ntri_cap, ITEMS_PER_TASK),
				nfr = nranges_for(v->nchunks, FLATTEN_CHUNKS);

	v->parent = tdc_big_alloc(v->cache, v->ntri_cap * sizeof(uint32_t));
	v->tri_he = tdc_big_alloc(v->cache, v->ntri_cap * sizeof(uint32_t));
	if (v->parent == NULL || v->tri_he == NULL)
		FAIL_OOM("out of memory joining cocircular triangles");
	tdc_pool_for(v->pool, ntr, tdc_vor_parent_task, v);
	tdc_pool_for(v->pool, nr, tdc_vor_tri_he_task, v);
	tdc_pool_for(v->pool, nr, tdc_vor_cocircular_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	tdc_pool_for(v->pool, nfr, tdc_vor_flatten_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	set_outer_box(v, base, nfr);
	return TDC_OK;
}

/* Everything, on the driver thread (or the caller's for small jobs). */
static int
vor_run(tdc_voronoi *v)
{
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		nr = 0,
				nboxes = 0;
	double		base[4] = {v->env[0], v->env[1], v->env[2], v->env[3]},
				lo[2],
				hi[2];
	int			rc;

	rc = tdc_pool_create(&v->pool, v->threads);
	if (rc != 0)
	{
		vor_fail(v, rc, rc == TDC_ETHREAD ? "could not create worker threads" : "out of memory");
		return rc;
	}
	v->nsites = mesh->nin;
	v->nhe = mesh->nin * 6;
	v->ntri = mesh->ntri;

	/* B: around E, the sites and (below) every vertex, then widened */
	if (mesh->nsites > 0)
	{
		tdc_site_extent(v->job, lo, hi);
		grow_box(base, lo);
		grow_box(base, hi);
	}

	if (v->ntri > 0)
	{
		size_t		ntri = 0;

		nr = nranges_for(v->nhe, ITEMS_PER_TASK);
		/* every range but one chunk per range fills its chunks */
		v->nchunks = v->ntri / TRI_CHUNK + nr;
		v->ntri_cap = v->nchunks * TRI_CHUNK;
		v->site_he = tdc_big_alloc(v->cache, mesh->nin * sizeof(uint32_t));
		v->range_ntri = calloc(nr + 1, sizeof(size_t));
		v->chunk_fill = calloc(v->nchunks + 1, sizeof(uint32_t));
		/* a half-edge outside every triangle keeps a number never read */
		v->tri_id = tdc_big_alloc(v->cache, v->nhe * sizeof(uint32_t));
		v->cc = tdc_big_alloc(v->cache, v->ntri_cap * 2 * sizeof(double));
		v->range_box = malloc((nr > v->nchunks ? nr : v->nchunks) * 4 * sizeof(double) + 1);
		if (!v->site_he || !v->range_ntri || !v->chunk_fill || !v->tri_id || !v->cc ||
			!v->range_box)
			FAIL_OOM("out of memory for the Voronoi vertices");
		atomic_init(&v->chunks_claimed, 0);
		for (size_t s = 0; s < mesh->nin; s++)
			atomic_init(&v->site_he[s], TDC_NIL);
		tdc_pool_for(v->pool, nr, tdc_vor_number_task, v);
		if (vor_cancelled(v))
			return TDC_ECANCELED;
		for (size_t r = 0; r < nr; r++)
			ntri += v->range_ntri[r];
		if (ntri != v->ntri)
		{
			vor_fail(v, TDC_EINVAL, "the mesh does not hold the triangles counted");
			return TDC_EINVAL;
		}
		nboxes = nr;
	}
	else if (mesh->nsites >= 2)
	{
		size_t		k = 0;

		v->line = malloc(mesh->nsites * sizeof(uint32_t));
		v->line_pos = malloc(mesh->nin * sizeof(uint32_t));
		if (v->line == NULL || v->line_pos == NULL)
			FAIL_OOM("out of memory sorting collinear sites");
		for (size_t s = 0; s < mesh->nin; s++)
			if (mesh->site_of[s] == s)
				v->line[k++] = (uint32_t) s;
		v->nline = k;
		qsort_r(v->line, k, sizeof(uint32_t), cmp_site, v);
		for (size_t i = 0; i < k; i++)
			v->line_pos[v->line[i]] = (uint32_t) i;
	}
	set_outer_box(v, base, nboxes);

	/*
	 * Cells of a mesh by half-edge ranges of at least 2^18 (a few MB of
	 * cells each: few buffers to map and grow), yet eight ranges per
	 * thread where there is enough, for balance.
	 */
	v->cell_range = v->nhe / ((size_t) v->threads * 8) + 1;
	if (v->cell_range < CELL_RANGE_MIN)
		v->cell_range = CELL_RANGE_MIN;
	v->big_bufs = v->ntri > 0;
	nr = v->ntri > 0 ? nranges_for(v->nhe, v->cell_range) : nranges_for(v->nsites, SITES_PER_TASK);
	v->nranges = nr;
	/* zeroed: a site without a cell (a duplicate) keeps 0 */
	v->cell_n = tdc_big_alloc(v->cache, v->nsites * sizeof(uint32_t) + 1);
	if (v->cell_n == NULL)
		FAIL_OOM("out of memory for the Voronoi cells");
	if (v->emit && v->ntri > 0)
	{
		v->range_bytes = calloc(nr + 1, sizeof(uint64_t));
		v->range_cells = calloc(nr + 1, sizeof(size_t));
		v->range_rec = calloc(nr + 1, sizeof(uint32_t *));
		v->range_rec_len = calloc(nr + 1, sizeof(size_t));
		if (v->range_bytes == NULL || v->range_cells == NULL || v->range_rec == NULL ||
			v->range_rec_len == NULL)
			FAIL_OOM("out of memory for the Voronoi cells");
	}
	else
	{
		v->cell_xy = tdc_big_alloc(v->cache, v->nsites * sizeof(double *) + 1);
		v->range_buf = calloc(nr + 1, sizeof(double *));
		if (v->cell_xy == NULL || v->range_buf == NULL)
			FAIL_OOM("out of memory for the Voronoi cells");
	}
	rc = build_cells(v);
	if (rc != TDC_OK)
		return rc;

	/*
	 * Two cocircular triangles whose vertices came out different (see
	 * voronoi_number.c): join the classes and build every cell again.
	 */
	if (atomic_load(&v->need_join))
	{
		rc = join_cocircular(v, base);
		if (rc == TDC_OK)
			rc = build_cells(v);
		if (rc != TDC_OK)
			return rc;
	}

	/* what only the build needed (emit: writing builds some cells again) */
	if (!(v->emit && v->ntri > 0))
	{
		tdc_big_free(v->cache, v->tri_id);
		v->tri_id = NULL;
	}
	return TDC_OK;
}

/* ----------------------------------------------------------------
 *		lifecycle (the same as a job's)
 * ----------------------------------------------------------------
 */
/*
 * The work, on the driver or the caller's thread: the status, its message in
 * v->err (a task's error wins, then a cancel).  The pool goes first.
 */
static int
vor_work(void *arg)
{
	tdc_voronoi *v = arg;
	int			rc = v->writing ? tdc_vor_emit_run(v) : vor_run(v);

	tdc_pool_destroy(v->pool);
	v->pool = NULL;
	if (atomic_load(&v->failed))
	{
		snprintf(v->err, sizeof(v->err), "%s", v->task_err);
		return atomic_load(&v->failed);
	}
	if (rc == TDC_ECANCELED || (rc == TDC_OK && atomic_load(&v->cancel)))
	{
		snprintf(v->err, sizeof(v->err), "Voronoi diagram cancelled");
		return TDC_ECANCELED;
	}
	return rc;
}

size_t
tdc_voronoi_memory(size_t n, int threads)
{
	/*
	 * Per input point: 6 half-edges' triangle numbers (24), at most 2
	 * triangles' parents, smallest half-edges (joining) and circumcenters
	 * (8 + 8 + 32, and a partly used chunk of numbers per 2^16 half-edges,
	 * under 2 bytes a point), the
	 * smallest half-edge, ring pointer and count of its site (4 + 8 + 4);
	 * ring storage: every triangle is in at most 3 rings (6 vertices per
	 * point), clipping adds at most 4 per cell, a hull cell 2 exit points
	 * and 4 corners of B: 16 vertices of 16 bytes per point, and a range's
	 * buffer grows by half its size at a time (x 1.5).  Plus the collinear
	 * sort (8) and per thread scratch rings.  A diagram written straight
	 * into the host's value (tdc_voronoi_start_emit) has no ring storage
	 * but, per point, its records (a site, a count and 6 classes on
	 * average; a clipped cell's coordinates instead, at most as many as
	 * the ring storage's; x 1.5 for growing), the input's sizes and
	 * offsets (8) and the sites' offsets (8), in the triangle numbers'
	 * pages when they fit, and with a tolerance the sites' first inputs
	 * (4): less.
	 */
	return n * (24 + 48 + 2 + 16 + 8 + 8 + 16 * 16 * 3 / 2) + (size_t) (threads + 1) * 65536 + 4096;
}

static int
voronoi_start(const tdc_job *job, const double env[4], int threads,
			  const tdc_cell_writer *writer, tdc_voronoi **out, char *err,
			  size_t errlen)
{
	tdc_mesh_view mesh;
	tdc_voronoi *v;
	int			rc;

	*out = NULL;
	if (err && errlen)
		err[0] = '\0';
#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (tdc_job_wait((tdc_job *) job, 0) != TDC_OK)
		FAIL(TDC_EINVAL, "the triangulation has not finished successfully");
	tdc_job_view(job, &mesh);
	if (!(env[0] <= env[2] && env[1] <= env[3]) || !isfinite(env[0]) ||
		!isfinite(env[1]) || !isfinite(env[2]) || !isfinite(env[3]))
		FAIL(TDC_EINVAL, "the clip envelope must be a finite rectangle");
	if (mesh.nsites > 0)
	{
		double		lo[2],
					hi[2];

		tdc_site_extent(job, lo, hi);
		if (lo[0] < env[0] || lo[1] < env[1] || hi[0] > env[2] || hi[1] > env[3])
			FAIL(TDC_EINVAL, "the clip envelope must contain every site");
	}
	if (threads < 0 || threads > 1024)
		FAIL(TDC_EINVAL, "threads must be between 0 and 1024, not %d", threads);
	v = calloc(1, sizeof(tdc_voronoi));
	if (v == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	v->job = job;
	v->mesh = mesh;
	v->cache = mesh.opt->cache;
	if (writer)
	{
		v->emit = true;
		v->writer = *writer;
	}
	memcpy(v->env, env, sizeof(v->env));
	v->threads = threads > 0 ? threads : mesh.threads;
	if (v->threads < 1)
		v->threads = 1;
	atomic_init(&v->failed, 0);
	tdc_runner_init(&v->run, &v->cancel);

	if (mesh.nin <= TDC_INLINE_MAX)
		v->threads = 1;
	rc = tdc_runner_start(&v->run, mesh.nin <= TDC_INLINE_MAX, vor_work, v, err, errlen);
	if (rc != TDC_OK)
	{
		tdc_runner_destroy(&v->run);
		free(v);
		return rc;
	}
	*out = v;
	return TDC_OK;
#undef FAIL
}

int
tdc_voronoi_start(const tdc_job *job, const double env[4], int threads,
				  tdc_voronoi **out, char *err, size_t errlen)
{
	return voronoi_start(job, env, threads, NULL, out, err, errlen);
}

int
tdc_voronoi_start_emit(const tdc_job *job, const double env[4], int threads,
					   const tdc_cell_writer *writer, tdc_voronoi **out,
					   char *err, size_t errlen)
{
	if (writer == NULL || writer->size == NULL || writer->write == NULL)
	{
		*out = NULL;
		if (err && errlen)
			snprintf(err, errlen, "a Voronoi cell writer needs its size and write functions");
		return TDC_EINVAL;
	}
	return voronoi_start(job, env, threads, writer, out, err, errlen);
}

uint64_t
tdc_voronoi_emit_size(const tdc_voronoi *v, size_t *cells)
{
	if (cells)
		*cells = v->emit_cells;
	return v->emit_bytes;
}

int
tdc_voronoi_emit(tdc_voronoi *v, char *dst, char *err, size_t errlen)
{
	int			rc;

	if (err && errlen)
		err[0] = '\0';
	if (!v->emit || v->writing || tdc_runner_wait(&v->run, 0) != TDC_OK)
	{
		if (err && errlen)
			snprintf(err, errlen, "the Voronoi cells cannot be written: %s",
					 !v->emit ? "not started for writing" : v->writing ? "already written" :
					 "their sizing has not finished successfully");
		return TDC_EINVAL;
	}
	tdc_runner_rearm(&v->run);
	v->dst = dst;
	v->writing = true;
	rc = tdc_runner_start(&v->run, v->mesh.nin <= TDC_INLINE_MAX, vor_work, v, err, errlen);
	if (rc != TDC_OK)
		tdc_runner_finish(&v->run, rc);
	return rc;
}

int
tdc_voronoi_wait(tdc_voronoi *v, int timeout_ms)
{
	return tdc_runner_wait(&v->run, timeout_ms);
}

void
tdc_voronoi_cancel(tdc_voronoi *v)
{
	if (v)
		tdc_runner_cancel(&v->run);
}

const char *
tdc_voronoi_error(const tdc_voronoi *v)
{
	return v->err;
}

void
tdc_voronoi_free(tdc_voronoi *v)
{
	if (v == NULL)
		return;
	tdc_runner_destroy(&v->run);
	tdc_big_free(v->cache, v->tri_id);
	tdc_big_free(v->cache, v->parent);
	tdc_big_free(v->cache, v->cc);
	tdc_big_free(v->cache, v->site_he);
	free(v->range_ntri);
	free(v->chunk_fill);
	tdc_big_free(v->cache, v->tri_he);
	free(v->range_box);
	free(v->line);
	free(v->line_pos);
	if (v->range_buf)
		for (size_t r = 0; r < v->nranges; r++)
		{
			if (v->big_bufs)
				tdc_big_free(v->cache, v->range_buf[r]);
			else
				free(v->range_buf[r]);
		}
	free(v->range_buf);
	tdc_big_free(v->cache, v->cell_xy);
	tdc_big_free(v->cache, v->cell_n);
	free(v->range_bytes);
	free(v->range_cells);
	free(v->first_in);
	if (!v->offsets_in_tri_id)
	{
		tdc_big_free(v->cache, v->inpos);
		tdc_big_free(v->cache, v->site_off);
	}
	free(v->block_start);
	if (v->range_rec)
		for (size_t r = 0; r < v->nranges; r++)
			free(v->range_rec[r]);
	free(v->range_rec);
	free(v->range_rec_len);
	free(v);
}

int
tdc_voronoi_build(const tdc_job *job, const double env[4], int threads,
				  tdc_voronoi **out, char *err, size_t errlen)
{
	int			rc = tdc_voronoi_start(job, env, threads, out, err, errlen);

	if (rc != TDC_OK)
		return rc;
	rc = tdc_voronoi_wait(*out, -1);
	if (rc != TDC_OK && err && errlen)
		snprintf(err, errlen, "%s", (*out)->err);
	return rc;
}

size_t
tdc_voronoi_cell(const tdc_voronoi *v, uint32_t site, const double **xy)
{
	if (site >= v->nsites || v->cell_xy == NULL || v->cell_n[site] == 0)
	{
		*xy = NULL;
		return 0;
	}
	*xy = v->cell_xy[site];
	return v->cell_n[site];
}

size_t
tdc_voronoi_num_vertices(const tdc_voronoi *v)
{
	return v->total_vertices;
}

void
tdc_voronoi_env(const tdc_voronoi *v, double env[4])
{
	memcpy(env, v->env, sizeof(v->env));
}

void
tdc_voronoi_default_env(const tdc_job *job, double env[4])
{
	tdc_mesh_view mesh;
	double		w;

	tdc_job_view(job, &mesh);
	if (mesh.nsites == 0)
	{
		env[0] = env[1] = env[2] = env[3] = 0;
		return;
	}

	/*
	 * The box of every input point, not only of the sites a tolerance kept:
	 * GEOS merges only exact duplicates before taking the envelope.
	 */
	w = fmax(mesh.bmax[0] - mesh.bmin[0], mesh.bmax[1] - mesh.bmin[1]);
	env[0] = mesh.bmin[0] - w;
	env[1] = mesh.bmin[1] - w;
	env[2] = mesh.bmax[0] + w;
	env[3] = mesh.bmax[1] + w;
}

