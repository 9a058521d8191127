/*
 * result.c
 *		Access to a finished job: counts, sites, the input->site map, the
 *		triangle and edge iterators, and the view its consumers read
 *		(mesh_view.h).
 *
 * Once a job has finished, its arrays are read-only and every accessor may
 * be called from any thread.  The one exception is the input->site map,
 * which costs 4 bytes per input point and so is built only on the first
 * request, under the job's lock (build_input_map).  The iterators walk the
 * half-edge array in order, so their output depends only on the mesh, not
 * on the thread count.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>

#include "job_int.h"


/*
 * Invert idx[] (position -> input) through site_of[], then send the points a
 * tolerance dropped to the site of the point that absorbed them.  Built once,
 * under the job's lock; the job is otherwise read-only after it finished.
 * Returns the map, or NULL when it cannot be allocated.
 *
 * Invariant: job->map is NULL or the complete map.  It is only stored under
 * the lock, with release order after the map's contents, so a thread that
 * loads it with acquire order outside the lock sees the whole map; threads
 * that race to build it queue on the lock and the later ones find it built.
 */
static uint32_t *
build_input_map(tdc_job *job)
{
	uint32_t   *map;

	pthread_mutex_lock(&job->run.lock);
	map = atomic_load_explicit(&job->map, memory_order_relaxed);
	if (map == NULL)
	{
		map = tdc_big_alloc(job->opt.cache, job->n * sizeof(uint32_t) + 4);
		if (map != NULL)
		{
			for (size_t p = 0; p < job->nin; p++)
				map[job->idx[p]] = job->site_of[p];
			if (job->tol_to)
				for (size_t i = 0; i < job->n; i++)
					if (job->tol_to[i] != i)
						map[i] = map[job->tol_to[i]];
			atomic_store_explicit(&job->map, map, memory_order_release);
		}
	}
	pthread_mutex_unlock(&job->run.lock);
	return map;
}


size_t
tdc_num_input(const tdc_job *job)
{
	return job->n;
}

size_t
tdc_num_sites(const tdc_job *job)
{
	return job->nsites;
}

size_t
tdc_num_triangles(const tdc_job *job)
{
	return job->ntri;
}

size_t
tdc_num_edges(const tdc_job *job)
{
	return job->nedges;
}

int
tdc_threads_used(const tdc_job *job)
{
	return job->threads;
}

int
tdc_levels_used(const tdc_job *job)
{
	return job->d;
}

int
tdc_grid_used(const tdc_job *job)
{
	return job->s;
}

void
tdc_job_times(const tdc_job *job, tdc_times *t)
{
	*t = job->times;
}

uint32_t
tdc_site_id_limit(const tdc_job *job)
{
	return (uint32_t) job->nin;
}

const double *
tdc_site_xy(const tdc_job *job, uint32_t site)
{
	return job->xy + 2 * (size_t) site;
}

void
tdc_site_extent(const tdc_job *job, double lo[2], double hi[2])
{
	/*
	 * check_input's box covers every input point, and without a tolerance
	 * each input point is a site or an exact duplicate of one.  The
	 * tolerance pass may drop extreme points, so then the survivors (the
	 * first nin entries of xy, in whatever order the sorts left them) are
	 * scanned instead.
	 */
	if (!(job->opt.tolerance > 0))
	{
		lo[0] = job->bmin[0], lo[1] = job->bmin[1];
		hi[0] = job->bmax[0], hi[1] = job->bmax[1];
		return;
	}
	lo[0] = lo[1] = INFINITY;
	hi[0] = hi[1] = -INFINITY;
	for (size_t p = 0; p < job->nin; p++)
	{
		lo[0] = fmin(lo[0], job->xy[2 * p]);
		hi[0] = fmax(hi[0], job->xy[2 * p]);
		lo[1] = fmin(lo[1], job->xy[2 * p + 1]);
		hi[1] = fmax(hi[1], job->xy[2 * p + 1]);
	}
}

size_t
tdc_site_input(const tdc_job *job, uint32_t site)
{
	return job->idx[site];
}
const uint32_t *
tdc_job_input_map(const tdc_job *job)
{
	tdc_job    *j = (tdc_job *) job;
	uint32_t   *map = atomic_load_explicit(&j->map, memory_order_acquire);

	return map != NULL ? map : build_input_map(j);
}

uint32_t
tdc_input_site(const tdc_job *job, size_t i)
{
	const uint32_t *map = tdc_job_input_map(job);

	return map == NULL ? UINT32_MAX : map[i];
}

/*
 * Each site's least label into the slot of its first point (tdc.h): one
 * pass over the positions, each a point that became a site (site_of names
 * the site, idx the points), so no input map is built.  The first point's
 * slot is read and written only for its own site, so the pass needs no
 * copy of the labels.
 */
void
tdc_least_labels(const tdc_job *job, int64_t *label)
{
	for (size_t p = 0; p < job->nin; p++)
	{
		size_t		first = job->idx[job->site_of[p]];
		int64_t		l = label[job->idx[p]];

		if (l < label[first])
			label[first] = l;
	}
}

void
tdc_job_view(const tdc_job *job, tdc_mesh_view *out)
{
	out->n = job->n;
	out->input = job->input;
	out->opt = &job->opt;
	out->bmin[0] = job->bmin[0];
	out->bmin[1] = job->bmin[1];
	out->bmax[0] = job->bmax[0];
	out->bmax[1] = job->bmax[1];
	out->threads = job->threads;
	out->nin = job->nin;
	out->nsites = job->nsites;
	out->xy = job->xy;
	out->site_of = job->site_of;
	out->idx = job->idx;
	out->he = job->he;
	out->ntri = job->ntri;
	out->outer = job->outer;
	out->constrained = job->constrained;
}

/*
 * The constrained insertion's flips (mesh_view.h): the one writer.  The job
 * remembers it, so that consumers which need the Delaunay property (a TIN's
 * nearest site walk, natural neighbours) know they cannot count on it.
 */
tdc_he *
tdc_job_edit_mesh(tdc_job *job)
{
	job->constrained = true;
	return job->he;
}

/*
 * Every face but the outer one is a triangle, reported from its smallest
 * half-edge.  Lnext(h) lies in h's own cache line, so most half-edges are
 * rejected without touching another part of the mesh; the outer face's
 * half-edges are marked in job->outer.
 */
int
tdc_next_triangle(const tdc_job *job, tdc_iter *it, uint32_t v[3])
{
	size_t		nhe = job->nin * 6;

	if (job->ntri == 0)
		return 0;
	for (size_t h = it->pos; h < nhe; h++)
	{
		if (tdc_tri_at(job, h, v))
		{
			it->pos = h + 1;
			return 1;
		}
	}
	it->pos = nhe;
	return 0;
}

int
tdc_next_edge(const tdc_job *job, tdc_iter *it, uint32_t v[2])
{
	size_t		nhe = job->nin * 6;

	for (size_t h = it->pos; h < nhe; h += 2)
	{
		uint32_t	a = job->he[h].org,
					b = job->he[h + 1].org;

		if (a == TDC_NIL)
			continue;
		if (tdc_key_less(job->xy + 2 * (size_t) b, job->xy + 2 * (size_t) a, 0))
			v[0] = b, v[1] = a;
		else
			v[0] = a, v[1] = b;
		it->pos = h + 2;
		return 1;
	}
	it->pos = nhe;
	return 0;
}
