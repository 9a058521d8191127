/*
 * voronoi_number.c
 *		The Voronoi vertices numbered: one per triangle, and one per class
 *		of cocircular triangles (a lock-free union-find).
 *
 * Cocircular sites.  When four or more sites lie on one empty circle the
 * triangulation splits that circle's polygon into triangles whose
 * circumcenters are the same point: the Voronoi edges dual to the inner
 * diagonals have length zero.  Such an edge is recognised exactly (the
 * incircle determinant of its two triangles is exactly zero), and the
 * triangles are merged into one class by a lock-free union-find whose root
 * is the smallest triangle number, so the class has one vertex, computed
 * once, and a cell never repeats it.  Testing every edge costs a tenth of
 * the diagram, and on data in general position finds nothing; so the edges
 * are tested where it is cheap and can matter: the walks that build the
 * cells compare the vertices of consecutive triangles around each site,
 * and only when the two are within rounding of each other (2^-48 of the
 * coordinate, far above the bound below) is the edge between them tested.
 * Every inner edge is between consecutive triangles around its end points,
 * so none is missed.  If one is cocircular, the classes are joined (every
 * edge tested, as above) and the cells are built again.
 *
 * One vertex, one value.  A Voronoi vertex is computed once per triangle,
 * with the vertices rotated to start at the lexicographically smallest, and
 * a class reads its root's: every cell that uses it reads the same double
 * pair, so neighbouring cells share their vertices bit for bit and the cells
 * form a coverage with no gap and no overlap beyond that rounding.  Points
 * made by clipping are computed from the segment's end points taken in
 * lexicographic order, so both cells of a clipped edge get the same point
 * too.
 *
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
 *		triangles: numbering, cocircular classes, circumcenters
 * ----------------------------------------------------------------
 */

/* The Voronoi vertex of a triangle: its circumcenter, from its canonical rotation. */
static inline void
triangle_vertex(const tdc_voronoi *v, const uint32_t s[3], double out[2])
{
	const double *p[3];
	int			k = 0;

	for (int i = 0; i < 3; i++)
		p[i] = site_pt(v, s[i]);
	if (tdc_lex_less(p[1], p[k]))
		k = 1;
	if (tdc_lex_less(p[2], p[k]))
		k = 2;
	tdc_circumcenter(p[k], p[(k + 1) % 3], p[(k + 2) % 3], out);
}

/*
 * One walk over half-edge range r: note each site's smallest half-edge,
 * number the range's triangles, record each triangle's number on its three
 * half-edges, compute its circumcenter and the range's bounding box of them.
 * The numbers come in chunks of TRI_CHUNK claimed with one atomic add, as
 * emit.c collects triangles, so no walk is needed first to count them; the
 * numbers then depend on the timing, so nothing may be ordered by them (see
 * uf_union).  Cocircular triangles are found later, by the cell walks
 * (note_pair).
 */
void
tdc_vor_number_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	const tdc_mesh_view *mesh = &v->mesh;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe,
				n = 0,
				chunk = 0,
				used = TRI_CHUNK;
	uint32_t	t[3];
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h < hi; h++)
	{
		uint32_t	o = mesh->he[h].org;

		if (((h - lo) & 4095) == 4095 && vor_cancelled(v))
			break;
		prefetch_face(v, h, hi);
		if (o == TDC_NIL)
			continue;
		/* smallest half-edge out of o: a CAS loop, contention is rare */
		{
			uint32_t	cur = atomic_load_explicit(&v->site_he[o], memory_order_relaxed);

			while ((uint32_t) h < cur &&
				   !atomic_compare_exchange_weak_explicit(&v->site_he[o], &cur, (uint32_t) h,
														  memory_order_relaxed,
														  memory_order_relaxed))
				;
		}
		if (tdc_mesh_tri_at(mesh, h, t))
		{
			uint32_t	h1 = mesh->he[SYM(h)].prev,
						h2 = mesh->he[SYM(h1)].prev,
						id;
			double	   *c;

			if (used == TRI_CHUNK)
			{
				if (n > 0)
					v->chunk_fill[chunk] = (uint32_t) used;
				chunk = atomic_fetch_add_explicit(&v->chunks_claimed, 1, memory_order_relaxed);
				if (chunk >= v->nchunks)
				{
					vor_fail(v, TDC_EINVAL, "the mesh holds more triangles than it counted");
					return;
				}
				used = 0;
			}
			id = (uint32_t) (chunk * TRI_CHUNK + used++);
			c = v->cc + 2 * (size_t) id;
			v->tri_id[h] = v->tri_id[h1] = v->tri_id[h2] = id;
			triangle_vertex(v, t, c);
			grow_box(box, c);
			n++;
		}
	}
	if (n > 0)
		v->chunk_fill[chunk] = (uint32_t) used;
	v->range_ntri[r] = n;
	memcpy(v->range_box + 4 * r, box, sizeof(box));
}

void
tdc_vor_parent_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->ntri_cap ? lo + ITEMS_PER_TASK : v->ntri_cap;

	for (size_t t = lo; t < hi; t++)
		atomic_init(&v->parent[t], (uint32_t) t);
}

/* The join's order of the triangles: by their smallest half-edges. */
void
tdc_vor_tri_he_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe;
	uint32_t	t[3];

	if (vor_cancelled(v))
		return;
	for (size_t h = lo; h < hi; h++)
		if (tdc_mesh_tri_at(&v->mesh, h, t))
			v->tri_he[v->tri_id[h]] = (uint32_t) h;
}

static uint32_t
uf_find(tdc_voronoi *v, uint32_t x)
{
	for (;;)
	{
		uint32_t	p = atomic_load_explicit(&v->parent[x], memory_order_relaxed);

		if (p == x)
			return x;
		x = p;
	}
}

/*
 * Lock-free union: the later root, in the order of the triangles' smallest
 * half-edges (not of their numbers, which depend on the timing), is linked
 * below the earlier with a CAS, so a root only ever moves earlier and every
 * class ends with its first triangle as root, whatever the order of the
 * unions: the same class vertex whatever the thread count.
 */
static void
uf_union(tdc_voronoi *v, uint32_t a, uint32_t b)
{
	for (;;)
	{
		uint32_t	big,
					small;

		a = uf_find(v, a);
		b = uf_find(v, b);
		if (a == b)
			return;
		big = v->tri_he[a] > v->tri_he[b] ? a : b;
		small = big == a ? b : a;
		if (atomic_compare_exchange_strong_explicit(&v->parent[big], &big, small,
													memory_order_relaxed,
													memory_order_relaxed))
			return;
	}
}

/* Join the two triangles of every cocircular edge of range r. */
void
tdc_vor_cocircular_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * ITEMS_PER_TASK,
				hi = lo + ITEMS_PER_TASK < v->nhe ? lo + ITEMS_PER_TASK : v->nhe;

	if (vor_cancelled(v))
		return;
	for (size_t h = lo & ~(size_t) 1; h < hi; h += 2)
		if (edge_cocircular(v, h))
			uf_union(v, v->tri_id[h], v->tri_id[h + 1]);
}

/*
 * Flatten the classes of the triangles of chunks [r * FLATTEN_CHUNKS, ...),
 * and the bounding box of its roots' circumcenters: a class's vertex is its
 * root's.
 */

void
tdc_vor_flatten_task(void *arg, size_t r, int worker)
{
	tdc_voronoi *v = arg;
	size_t		lo = r * FLATTEN_CHUNKS,
				hi = lo + FLATTEN_CHUNKS < v->nchunks ? lo + FLATTEN_CHUNKS : v->nchunks;
	double		box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	if (vor_cancelled(v))
		return;
	for (size_t c = lo; c < hi; c++)
		for (size_t t = c * TRI_CHUNK; t < c * TRI_CHUNK + v->chunk_fill[c]; t++)
		{
			uint32_t	root = uf_find(v, (uint32_t) t);

			/* safe: other tasks only read parents while flattening */
			atomic_store_explicit(&v->parent[t], root, memory_order_relaxed);
			if (root == t)
				grow_box(box, v->cc + 2 * t);
		}
	memcpy(v->range_box + 4 * r, box, sizeof(box));
}

