/*
 * mesh_view.h
 *		A finished triangulation as its consumers read it: the Voronoi
 *		diagram (voronoi*.c), the constrained insertion (cdt*.c) and the
 *		tile finalization (tile_final.c).  Not installed.
 *
 * struct tdc_job (job_int.h) holds some forty fields: the plan, the grid and
 * the subdivision tree, the pool, the arena, the lifecycle.  A consumer
 * needs only the result: the input, the sites, the half-edges and the
 * outer face.  So the consumers do not include job_int.h (test/layering.sh
 * checks it); they take a tdc_mesh_view, filled once from a finished job by
 * tdc_job_view (result.c, in the layer that owns the job), and keep the job
 * itself only as the opaque handle of tdc.h, for the public accessors
 * (tdc_job_wait, tdc_input_site, the iterators).  Every field is fixed once
 * the job has finished: its arrays are allocated by the triangulation and
 * not moved or freed before tdc_job_free, so a view stays valid exactly as
 * long as the job.  A view is copied by value into its consumer's state, so
 * a read through it costs what job->field cost.
 *
 * One consumer writes: the constrained insertion flips edges of the mesh in
 * place (Sloan 1993, cdt_insert.c).  It gets the half-edges writable from
 * tdc_job_edit_mesh, which takes the non-const job that tdc_cdt_start takes;
 * nothing else may.  A flip turns the diagonal of a convex quadrilateral
 * inside the hull and keeps its edge slot, and hull edges are never
 * flipped, so the sites, the triangle count and the outer face (ntri and
 * outer here) stay right; only links and origins inside the hull change,
 * and readers of the same arrays see them.
 */
#ifndef TDC_MESH_VIEW_H
#define TDC_MESH_VIEW_H

#include "engine_int.h"

typedef struct tdc_mesh_view
{
	/* the input */
	size_t		n;				/* input points */
	const double *input;		/* the caller's coordinates, 2 per input point */
	const tdc_options *opt;		/* the job's options (cache, tolerance, memory bound) */
	double		bmin[2],
				bmax[2];		/* bounding box of the input */
	int			threads;		/* the job's thread count */

	/* the sites: site ids are positions [0, nin), some of them duplicates */
	size_t		nin;			/* site id limit; the mesh has 6 nin half-edge slots */
	size_t		nsites;			/* distinct sites */
	const double *xy;			/* coordinates, 2 per position */
	const uint32_t *site_of;	/* position -> its site (itself if a site) */
	const uint32_t *idx;		/* position -> its input index (a site's first) */

	/* the mesh (engine_int.h) */
	const tdc_he *he;			/* 6 nin half-edges; org TDC_NIL: a free slot */
	size_t		ntri;			/* triangles */
	const uint64_t *outer;		/* bitmap of the outer face's half-edges;
								 * NULL when there is no triangle */
	bool		constrained;	/* constraints were inserted (tdc_job_edit_mesh):
								 * the mesh need not be Delaunay */
} tdc_mesh_view;

/* result.c: the view of a finished job (the caller saw tdc_job_wait succeed). */
extern void tdc_job_view(const tdc_job *job, tdc_mesh_view *out);

/*
 * result.c: the input -> site map of a finished job, built on the first
 * request (4 bytes per input point, under the job's lock); NULL when it
 * cannot be allocated.
 */
extern const uint32_t *tdc_job_input_map(const tdc_job *job);

/*
 * result.c: the writable half-edges of a finished job, for the constrained
 * insertion alone (see above).
 */
extern tdc_he *tdc_job_edit_mesh(tdc_job *job);

/* Is half-edge h on the outer face? */
static inline bool
tdc_he_outer(const uint64_t *outer, size_t h)
{
	return (outer[h >> 6] >> (h & 63)) & 1;
}

/*
 * Does half-edge h start a triangle, i.e. is it the smallest half-edge of a
 * face other than the outer one?  Its corners in v, counter-clockwise.
 * Lnext(h) lies in h's own cache line, so most half-edges are rejected
 * without touching another part of the mesh.
 */
static inline bool
tdc_face_tri_at(const tdc_he *he, const uint64_t *outer, size_t h, uint32_t v[3])
{
	uint32_t	h1,
				h2;

	if (he[h].org == TDC_NIL || tdc_he_outer(outer, h))
		return false;
	h1 = he[SYM(h)].prev;		/* lnext */
	if (h1 < h)
		return false;
	h2 = he[SYM(h1)].prev;
	if (h2 < h)
		return false;
	v[0] = he[h].org;
	v[1] = he[h1].org;
	v[2] = he[h2].org;
	return true;
}

/* The same through a view. */
static inline bool
tdc_mesh_tri_at(const tdc_mesh_view *mesh, size_t h, uint32_t v[3])
{
	return tdc_face_tri_at(mesh->he, mesh->outer, h, v);
}

#endif							/* TDC_MESH_VIEW_H */
