/*
 * voronoi_write.c
 *		The cells sized, then written straight into the host's value
 *		(tdc_voronoi_start_emit, tdc_voronoi_emit).
 *
 * The two phases, sizing then writing, are described in
 * docs/design/voronoi.md ("Writing straight into the host's value").
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "voronoi_int.h"


/* ----------------------------------------------------------------
 *		writing the cells straight into the host's value
 * ----------------------------------------------------------------
 */
/*
 * Site s's final cell (cut to E) into scratch, as tdc_vor_mesh_cell_task builds it:
 * an inner site untagged into w, kept when inside E; otherwise tagged into
 * a and clipped (b scratch).  *res is w or a; false when out of memory.
 */
static bool
build_mesh_cell(const tdc_voronoi *v, uint32_t s, ring *w, ring *a, ring *b,
				const ring **res)
{
	uint32_t	ho;
	size_t		deg = tdc_vor_site_degree(v, s, &ho);

	if (ho == TDC_NIL)
	{
		bool		inside = true;

		if (!ring_reserve(w, deg + 8))
			return false;
		tdc_vor_cell_of_mesh(v, s, deg, ho, w);
		for (size_t i = 0; i < w->n && inside; i++)
			inside = w->p[2 * i] >= v->env[0] && w->p[2 * i] <= v->env[2] &&
				w->p[2 * i + 1] >= v->env[1] && w->p[2 * i + 1] <= v->env[3];
		if (inside)
		{
			*res = w;
			return true;
		}
	}
	if (!ring_reserve(a, deg + 8))
		return false;
	tdc_vor_cell_of_mesh(v, s, deg, ho, a);
	if (!tdc_vor_clip_to_env(v, s, a, b))
		return false;
	*res = a;
	return true;
}

/* Where site s's cell goes: the first input point that became s. */
static inline size_t
first_input(const tdc_voronoi *v, uint32_t s)
{
	return v->first_in ? v->first_in[s] : v->mesh.idx[s];
}

/* Room for n more words in a range's record. */
static bool
rec_reserve(uint32_t **rec, size_t *cap, size_t len, size_t n)
{
	if (len + n > *cap)
	{
		size_t		c = (len + n) + (len + n) / 2 + 1024;
		uint32_t   *p = realloc(*rec, c * sizeof(uint32_t));

		if (p == NULL)
			return false;
		*rec = p;
		*cap = c;
	}
	return true;
}

/*
 * An inner site's cell as its classes, from its ring of half-edges hs (from
 * its smallest, counter-clockwise) and their triangles' classes ts: the
 * vertices tdc_vor_cell_of_mesh would give an untagged ring (a class once, a vertex
 * equal to the one before dropped, then a closing repeat of the first), as
 * class numbers into ids (room for cap).  Returns the count, or 0 when a
 * vertex lies outside E (or there are more than cap): then the cell is
 * built and clipped as a ring.
 */
static size_t
inner_cell_ids(const tdc_voronoi *v, const uint32_t *hs, const uint32_t *ts, size_t deg,
			   uint32_t *ids, size_t cap)
{
	uint32_t	prev_t = TDC_NIL;
	size_t		n = 0;
	const double *last = NULL;

	for (size_t j = 0; j < deg; j++)
	{
		uint32_t	t = ts[j];
		const double *c;

		if (t == prev_t)
			continue;
		if (prev_t != TDC_NIL)
			note_pair(v, prev_t, t, hs[j]);
		prev_t = t;
		c = v->cc + 2 * (size_t) t;
		if (last && c[0] == last[0] && c[1] == last[1])
			continue;
		if (!(c[0] >= v->env[0] && c[0] <= v->env[2] && c[1] >= v->env[1] && c[1] <= v->env[3]) ||
			n == cap)
			return 0;
		ids[n++] = t;
		last = c;
	}
	if (ts[0] != prev_t)
		note_pair(v, prev_t, ts[0], hs[0]);
	while (n > 1)
	{
		const double *f = v->cc + 2 * (size_t) ids[0],
				   *l = v->cc + 2 * (size_t) ids[n - 1];

		if (f[0] != l[0] || f[1] != l[1])
			break;
		n--;
	}
	return n;
}


/*
 * Sizing: the sites whose smallest half-edge lies in half-edge range rg, in
 * mesh order (see tdc_vor_mesh_cell_task), each cell's vertex count and the range's
 * bytes, and a record of the range's cells for the writing phase: per site
 * its number, its count m and, for an inner cell inside E (almost all of
 * them), its m classes; for any other cell (on the hull, or crossing E),
 * built as a ring and clipped, m | REC_XY and its coordinates.  Writing then
 * reads the record in order and looks up the vertices, with no walk around
 * the sites and no mesh: keeping all cells' coordinates instead would cost
 * some 100 MB of fresh memory for a million points, which the kernel must
 * clear, and walking twice, the mesh's random loads twice.
 */
#define BATCH		16			/* sites walked together (tdc_vor_mesh_size_task) */
#define REC_XY		0x80000000u	/* record: the cell's coordinates follow */
#define RING_MAX	32			/* longer rings go the ring's way */

void
tdc_vor_mesh_size_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		lo = rg * v->cell_range,
				hi = lo + v->cell_range < v->nhe ? lo + v->cell_range : v->nhe,
				len = 0,
				cap = 0,
				nb = 0;
	ring		w = {0},
				a = {.tagged = true},
				b = {.tagged = true};
	uint64_t	bytes = 0;
	size_t		cells = 0;
	uint32_t   *rec = NULL;
	uint32_t	site[BATCH],
				hs[BATCH][RING_MAX],
				ts[BATCH][RING_MAX],
				deg[BATCH];
	bool		open[BATCH],
				inner[BATCH];

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h <= hi; h++)
	{
		uint32_t	s = h < hi ? mesh->he[h].org : TDC_NIL;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			goto done;
		if (h < hi && (s == TDC_NIL ||
					   atomic_load_explicit(&v->site_he[s], memory_order_relaxed) != (uint32_t) h))
			continue;
		if (h < hi)
		{
			site[nb] = s;
			hs[nb][0] = (uint32_t) h;
			deg[nb] = 1;
			open[nb] = true;
			inner[nb] = true;
			nb++;
			if (nb < BATCH)
				continue;
		}
		if (nb == 0)
			continue;

		/*
		 * The batch's rings, one step of every site at a time: the walks'
		 * random loads are independent across the sites, so they overlap
		 * instead of waiting for each other.  A ring with the outer face
		 * or longer than RING_MAX goes the ring's way.
		 */
		for (bool any = true; any;)
		{
			any = false;
			for (size_t i = 0; i < nb; i++)
			{
				uint32_t	hn;

				if (!open[i])
					continue;
				hn = mesh->he[hs[i][deg[i] - 1]].next;
				if (hn == hs[i][0])
					open[i] = false;
				else if (deg[i] == RING_MAX)
				{
					open[i] = false;
					inner[i] = false;
				}
				else
				{
					hs[i][deg[i]++] = hn;
					__builtin_prefetch(&v->tri_id[hn]);
					any = true;
				}
			}
		}
		for (size_t i = 0; i < nb; i++)
			for (size_t j = 0; j < deg[i] && inner[i]; j++)
			{
				if (is_outer(mesh, hs[i][j]))
					inner[i] = false;
				else
				{
					ts[i][j] = class_of(v, hs[i][j]);
					__builtin_prefetch(v->cc + 2 * (size_t) ts[i][j]);
				}
			}
		for (size_t i = 0; i < nb; i++)
		{
			size_t		m = 0;
			const ring *c;

			if (!rec_reserve(&rec, &cap, len, 2 + RING_MAX))
				goto oom;
			if (inner[i])
				m = inner_cell_ids(v, hs[i], ts[i], deg[i], rec + len + 2, RING_MAX);
			rec[len] = site[i];
			rec[len + 1] = (uint32_t) m;
			if (m == 0)
			{
				/* built as a ring and clipped: its coordinates, 4 words a vertex */
				if (!build_mesh_cell(v, site[i], &w, &a, &b, &c) ||
					!rec_reserve(&rec, &cap, len, 2 + 4 * c->n))
					goto oom;
				m = c->n;
				rec[len + 1] = (uint32_t) m | REC_XY;
				memcpy(rec + len + 2, c->p, 16 * m);
				len += 2 + 4 * m;
			}
			else
				len += 2 + m;
			v->cell_n[site[i]] = (uint32_t) m;
			bytes += v->writer.size(v->writer.arg, m);
			cells++;
		}
		nb = 0;
	}
	v->range_bytes[rg] = bytes;
	v->range_cells[rg] = cells;
	v->range_rec[rg] = rec;
	v->range_rec_len[rg] = len;
	rec = NULL;
	goto done;
oom:
	vor_fail(v, TDC_ENOMEM, "out of memory sizing the Voronoi cells");
done:
	free(rec);
	free(w.p);
	free(a.p);
	free(a.tag);
	free(b.p);
	free(b.tag);
}

/* Writing: range rg's cells, as its record lists them, to the writer. */
static void
mesh_write_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	const uint32_t *rec = v->range_rec[rg];
	size_t		len = v->range_rec_len[rg];
	ring		w = {0};
	double		xy[2 * RING_MAX];

	if (vor_cancelled(v))
		return;
	for (size_t i = 0, k = 0; i < len; k++)
	{
		uint32_t	s = rec[i];
		size_t		m = rec[i + 1] & ~REC_XY;
		char	   *dst = v->dst + v->site_off[s];

		if ((k & 4095) == 4095 && vor_cancelled(v))
			break;
		if (rec[i + 1] & REC_XY)
		{
			/* the record's words are not aligned for doubles */
			if (!ring_reserve(&w, m))
			{
				vor_fail(v, TDC_ENOMEM, "out of memory writing the Voronoi cells");
				break;
			}
			memcpy(w.p, rec + i + 2, 16 * m);
			v->writer.write(v->writer.arg, dst, w.p, m);
			i += 2 + 4 * m;
		}
		else
		{
			for (size_t j = 0; j < m; j++)
				memcpy(xy + 2 * j, v->cc + 2 * (size_t) rec[i + 2 + j], 2 * sizeof(double));
			v->writer.write(v->writer.arg, dst, xy, m);
			i += 2 + m;
		}
	}
	free(w.p);
}

/* Collinear input: the cells of site range rg, kept by tdc_vor_cell_task, to the writer. */
static void
line_emit_task(void *arg, size_t rg, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = rg * SITES_PER_TASK,
				hi = lo + SITES_PER_TASK < v->nsites ? lo + SITES_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->writer.write(v->writer.arg, v->dst + v->site_off[s], v->cell_xy[s], v->cell_n[s]);
}

/* Each cell's bytes at the place of its site's first input point. */
static void
scatter_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nsites ? lo + ITEMS_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->inpos[first_input(v, (uint32_t) s)] = v->writer.size(v->writer.arg, v->cell_n[s]);
}

/* The bytes of the cells of input block r. */
static void
block_sum_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ninput ? lo + ITEMS_PER_TASK : v->ninput;
	uint64_t	sum = 0;

	if (vor_cancelled(v))
		return;
	for (size_t i = lo; i < hi; i++)
		sum += v->inpos[i];
	v->block_start[r + 1] = sum;
}

/*
 * Sizes to offsets in input block r, and the block's part of the value
 * mapped in now, in parallel, rather than a page fault at a time by the
 * scattered writes that follow.
 */
static void
offset_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ninput ? lo + ITEMS_PER_TASK : v->ninput;
	uint64_t	off = v->block_start[r];

	if (vor_cancelled(v))
		return;
	for (size_t i = lo; i < hi; i++)
	{
		uint64_t	size = v->inpos[i];

		v->inpos[i] = off;
		off += size;
	}
	tdc_prefault(v->dst + v->block_start[r], (size_t) (off - v->block_start[r]));
}

/*
 * Each site's offset, from its first input point's: a loop of independent
 * random loads, which overlap, rather than one in the middle of every
 * cell's writing.
 */
static void
gather_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nsites ? lo + ITEMS_PER_TASK : v->nsites;

	if (vor_cancelled(v))
		return;
	for (size_t s = lo; s < hi; s++)
		if (v->cell_n[s] > 0)
			v->site_off[s] = v->inpos[first_input(v, (uint32_t) s)];
}

/*
 * The writing phase, on the driver thread: offsets in input order (the
 * sites' first input points, for a tolerance found through the input map),
 * then every cell to the writer.
 */
int
tdc_vor_emit_run(tdc_voronoi *v)
{
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		nb;
	int			rc;

	rc = tdc_pool_create(&v->pool, v->threads);
	if (rc != 0)
	{
		vor_fail(v, rc, rc == TDC_ETHREAD ? "could not create worker threads" : "out of memory");
		return rc;
	}
	v->ninput = mesh->n;
	if (mesh->opt->tolerance > 0)
	{
		const uint32_t *map = tdc_job_input_map(v->job);

		if (map == NULL)
			FAIL_OOM("out of memory mapping the input to its sites");
		v->first_in = malloc(v->nsites * sizeof(uint32_t) + 1);
		if (v->first_in == NULL)
			FAIL_OOM("out of memory ordering the Voronoi cells");
		memset(v->first_in, 0xff, v->nsites * sizeof(uint32_t));
		for (size_t i = 0; i < v->ninput; i++)
		{
			uint32_t	s = map[i];

			if (v->first_in[s] == TDC_NIL)
				v->first_in[s] = (uint32_t) i;
			if ((i & 65535) == 65535 && vor_cancelled(v))
				return TDC_ECANCELED;
		}
	}
	nb = nranges_for(v->ninput, ITEMS_PER_TASK);
	v->block_start = calloc(nb + 1, sizeof(uint64_t));
	if (v->block_start == NULL)
		FAIL_OOM("out of memory ordering the Voronoi cells");

	/*
	 * Writing a mesh's cells reads only the records and the vertices: the
	 * triangle numbers' pages, mapped and cleared already, hold the offsets
	 * (the input's, then the sites'), when they fit, rather than fresh pages
	 * the kernel must clear.
	 */
	if (v->tri_id && (v->ninput + v->nsites) * sizeof(uint64_t) <= v->nhe * sizeof(uint32_t))
	{
		v->inpos = (uint64_t *) (void *) v->tri_id;
		v->site_off = v->inpos + v->ninput;
		v->offsets_in_tri_id = true;
		memset(v->inpos, 0, v->ninput * sizeof(uint64_t));
	}
	else
	{
		v->inpos = tdc_big_alloc(v->cache, v->ninput * sizeof(uint64_t) + 1);
		v->site_off = tdc_big_alloc(v->cache, v->nsites * sizeof(uint64_t) + 1);
		if (v->inpos == NULL || v->site_off == NULL)
			FAIL_OOM("out of memory ordering the Voronoi cells");
	}
	tdc_pool_for(v->pool, nranges_for(v->nsites, ITEMS_PER_TASK), scatter_task, v);
	tdc_pool_for(v->pool, nb, block_sum_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	for (size_t r = 0; r < nb; r++)
		v->block_start[r + 1] += v->block_start[r];
	if (v->block_start[nb] != v->emit_bytes)
	{
		vor_fail(v, TDC_EINVAL, "the Voronoi cells' offsets do not add up to their size");
		return TDC_EINVAL;
	}
	tdc_pool_for(v->pool, nb, offset_task, v);
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	/* by site now; the input's offsets are no longer needed */
	tdc_pool_for(v->pool, nranges_for(v->nsites, ITEMS_PER_TASK), gather_task, v);
	if (!v->offsets_in_tri_id)
		tdc_big_free(v->cache, v->inpos);
	v->inpos = NULL;
	if (vor_cancelled(v))
		return TDC_ECANCELED;
	tdc_pool_for(v->pool, v->nranges, v->ntri > 0 ? mesh_write_task : line_emit_task, v);
	return vor_cancelled(v) ? TDC_ECANCELED : TDC_OK;
}

