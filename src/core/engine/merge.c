/*
 * merge.c
 *		Merging two Delaunay triangulations separated along an axis
 *		(Guibas & Stolfi 1985, section 9; step 3 of Wu et al. 2014).
 *
 * The twofold scheme of Wu et al. splits the sites alternately by x and by y,
 * so the sub-triangulations are merged left-right and bottom-top.  Both are
 * the same Guibas-Stolfi merge seen in another frame: a bottom-top merge is a
 * left-right merge after rotating the plane by -90 degrees, (x, y) ->
 * (y, -x).  A rotation keeps every orientation and in-circle sign, so the
 * merge only needs to know which hull edges to start from.  Every subset
 * therefore carries the counter-clockwise hull edge out of its extreme site
 * in all four directions (the paper's leftmost, rightmost, bottommost and
 * topmost edges); axis 0 orders sites by (x, y), axis 1 by (y, -x), both
 * lexicographically so that ties on one coordinate are still separated.
 *
 * After a merge the hull of the union is the left part's chain from the upper
 * tangent point l' down to the lower tangent point l, the lower tangent
 * l -> r, the right part's chain from r up to r', and the upper tangent
 * r' -> l'.  So the hull edge out of an extreme site is the one it had in
 * its part, except at l (now the lower tangent) and at r' (now the upper
 * tangent, the last base edge of the merge).
 *
 * Ties.  Four or more cocircular sites admit several Delaunay
 * triangulations.  incircle_sos() decides exact zeros (with the kernel's
 * tdc_incircle_tie, predicates.c) as if every site p were
 * lifted to the paraboloid at |p|^2 + eps_p, with eps infinitesimal and
 * larger for lexicographically smaller sites (simulation of simplicity,
 * Edelsbrunner & Muecke 1990, applied to the lifting coordinate only).  The
 * perturbed lift is in general position, so its lower hull, and hence the
 * triangulation, depends on the site set alone: not on the input order, the
 * thread count or the subdivision.
 */
#include <string.h>

#include "engine_int.h"

/*
 * Zip steps between two looks at the cancel flag.  A step is a few
 * predicate calls; the top merges of a big job take millions of them, and
 * a poll per 65536 keeps the flag's cache line out of the loop while still
 * looking many times per millisecond.  A power of two.
 */
#define MERGE_POLL_STEPS	65536

/* Is p strictly left of (counter-clockwise from) the directed line of h? */
static inline bool
left_of(const tdc_mesh *m, uint32_t p, uint32_t h)
{
	return tdc_orient2d(tdc_pt(m, p), tdc_pt(m, tdc_org(m, h)),
						tdc_pt(m, tdc_dest(m, h))) > 0;
}

static inline bool
right_of(const tdc_mesh *m, uint32_t p, uint32_t h)
{
	return tdc_orient2d(tdc_pt(m, p), tdc_pt(m, tdc_dest(m, h)),
						tdc_pt(m, tdc_org(m, h))) > 0;
}

/* Is site p strictly right of the base edge from bo to bd, i.e. above it? */
static inline bool
above(const tdc_mesh *m, uint32_t p, const double *bo, const double *bd)
{
	return tdc_orient2d(tdc_pt(m, p), bd, bo) > 0;
}

/*
 * Is d inside the circle through counter-clockwise a, b, c (ties broken by
 * the kernel's rule, tdc_incircle_tie)?  The four sites must be distinct;
 * the callers make sure of it.
 */
static inline __attribute__((always_inline)) bool
incircle_sos(const tdc_mesh *m, uint32_t a, uint32_t b, uint32_t c, uint32_t d)
{
	return tdc_incircle_sos(tdc_pt(m, a), tdc_pt(m, b), tdc_pt(m, c), tdc_pt(m, d));
}

/* Site of a subset that is extreme in direction k, and whether it beats q. */
static inline bool
beats(const tdc_mesh *m, uint32_t p, uint32_t q, int k)
{
	if (k & 1)
		return tdc_key_less(tdc_pt(m, q), tdc_pt(m, p), k >> 1);
	return tdc_key_less(tdc_pt(m, p), tdc_pt(m, q), k >> 1);
}

/*
 * Fill out->ext from n (2 or 3) sites with their counter-clockwise hull
 * edges.  Used by the base cases of the divide and conquer, which sort
 * their distinct sites by (x, y): the extremes along axis 0 are the first
 * and the last, and only those along axis 1 need comparing (the same
 * choice as beats() in all four directions, with half the unpredictable
 * branches on the hottest path of a call on a few points).
 */
void
tdc_sub_from_sites(tdc_mesh *m, const uint32_t *v, const uint32_t *ccw, int n,
				   tdc_sub *out)
{
	int			lo = 0,
				hi = 0;

	for (int i = 1; i < n; i++)
	{
		if (beats(m, v[i], v[lo], 2))
			lo = i;
		if (beats(m, v[i], v[hi], 3))
			hi = i;
	}
	out->ext[0] = ccw[0];
	out->ext[1] = ccw[n - 1];
	out->ext[2] = ccw[lo];
	out->ext[3] = ccw[hi];
	out->vert = TDC_NIL;
	out->nsites = n;
}

static inline uint32_t
sub_site(const tdc_mesh *m, const tdc_sub *s, int k)
{
	return s->ext[k] == TDC_NIL ? s->vert : tdc_org(m, s->ext[k]);
}

/*
 * Merge L and R, where every site of L precedes every site of R in the order
 * of the axis, into out.  Edges come from and go back to fl.  If the job is
 * cancelled mid-way the mesh is left inconsistent; callers must then stop.
 */
void
tdc_merge(tdc_mesh *mesh, tdc_freelist *fl, const tdc_sub *L, const tdc_sub *R,
		  int axis, tdc_sub *out)
{
	/* a private copy: its pointers stay in registers across the mesh stores */
	tdc_mesh	local = *mesh;
	tdc_mesh   *m = &local;
	uint32_t	ldi,
				rdi,
				basel,
				lt,
				lsite,
				rsite;
	uint32_t	lext[4],
				rext[4];
	unsigned	steps = 0;

	if (L->nsites == 0 || R->nsites == 0)
	{
		const tdc_sub *s = L->nsites ? L : R;

		memcpy(out->ext, s->ext, sizeof(out->ext));
		out->vert = s->vert;
		out->nsites = s->nsites;
		return;
	}

	/* The parts' extreme sites, read before the merge deletes their edges. */
	for (int k = 0; k < 4; k++)
	{
		lext[k] = sub_site(m, L, k);
		rext[k] = sub_site(m, R, k);
	}

	/*
	 * Lower common tangent, then its edge basel from R to L.  A part of one
	 * site has no hull edge; the tangent then only walks the other part.
	 */
	if (L->nsites == 1 && R->nsites == 1)
		basel = tdc_make_edge(m, fl, R->vert, L->vert);
	else if (L->nsites == 1)
	{
		uint32_t	v = L->vert;

		rdi = R->ext[2 * axis];
		while (right_of(m, v, rdi))
			rdi = tdc_rprev(m, rdi);
		basel = tdc_make_edge(m, fl, tdc_org(m, rdi), v);
		tdc_splice(m, basel, tdc_oprev(m, rdi));
	}
	else if (R->nsites == 1)
	{
		uint32_t	w = R->vert;

		ldi = tdc_oprev(m, L->ext[2 * axis + 1]);
		while (left_of(m, w, ldi))
			ldi = tdc_lnext(m, ldi);
		basel = tdc_make_edge(m, fl, w, tdc_org(m, ldi));
		tdc_splice(m, SYM(basel), ldi);
	}
	else
	{
		ldi = tdc_oprev(m, L->ext[2 * axis + 1]);
		rdi = R->ext[2 * axis];
		for (;;)
		{
			if (left_of(m, tdc_org(m, rdi), ldi))
				ldi = tdc_lnext(m, ldi);
			else if (right_of(m, tdc_org(m, ldi), rdi))
				rdi = tdc_rprev(m, rdi);
			else
				break;
		}
		basel = tdc_connect(m, fl, SYM(rdi), ldi);
	}
	lt = SYM(basel);

	/*
	 * Zip upwards.  A candidate is valid when it lies strictly right of basel
	 * (above it, basel running from R to L); candidates whose edge fails the
	 * in-circle test against the next one around are deleted.
	 */
	for (;;)
	{
		uint32_t	bo = tdc_org(m, basel),
					bd = tdc_dest(m, basel);
		const double *pbo = tdc_pt(m, bo),
				   *pbd = tdc_pt(m, bd);
		uint32_t	lcand = tdc_rprev(m, basel),
					rcand = tdc_oprev(m, basel);
		bool		lvalid,
					rvalid;

		if ((++steps & (MERGE_POLL_STEPS - 1)) == 0 && tdc_cancelled(m))
			return;

		lvalid = above(m, tdc_dest(m, lcand), pbo, pbd);
		if (lvalid)
		{
			bool		deleted = false;

			/*
			 * The next edge around bd ends at bo only when it is basel
			 * itself, and then no site can be inside.
			 */
			while (tdc_onext(m, lcand) != SYM(basel) &&
				   incircle_sos(m, bd, bo, tdc_dest(m, lcand),
								tdc_dest(m, tdc_onext(m, lcand))))
			{
				uint32_t	t = tdc_onext(m, lcand);

				tdc_delete_edge(m, fl, lcand);
				lcand = t;
				deleted = true;
			}
			if (deleted)
				lvalid = above(m, tdc_dest(m, lcand), pbo, pbd);
		}
		rvalid = above(m, tdc_dest(m, rcand), pbo, pbd);
		if (rvalid)
		{
			bool		deleted = false;

			while (tdc_oprev(m, rcand) != basel &&
				   incircle_sos(m, bd, bo, tdc_dest(m, rcand),
								tdc_dest(m, tdc_oprev(m, rcand))))
			{
				uint32_t	t = tdc_oprev(m, rcand);

				tdc_delete_edge(m, fl, rcand);
				rcand = t;
				deleted = true;
			}
			if (deleted)
				rvalid = above(m, tdc_dest(m, rcand), pbo, pbd);
		}
		if (!lvalid && !rvalid)
			break;
		if (!lvalid ||
			(rvalid && incircle_sos(m, tdc_dest(m, lcand), tdc_org(m, lcand),
									tdc_org(m, rcand), tdc_dest(m, rcand))))
			basel = tdc_connect(m, fl, rcand, SYM(basel));
		else
			basel = tdc_connect(m, fl, SYM(basel), SYM(lcand));
	}

	/* basel is now the upper tangent r' -> l'. */
	lsite = tdc_org(m, lt);
	rsite = tdc_org(m, basel);
	for (int k = 0; k < 4; k++)
	{
		uint32_t	a = lext[k],
					b = rext[k];
		uint32_t	v;
		const tdc_sub *from;

		/* along the merge axis every site of L precedes every site of R */
		if ((k >> 1) == axis ? (k & 1) : beats(m, b, a, k))
			v = b, from = R;
		else
			v = a, from = L;
		if (v == lsite)
			out->ext[k] = lt;
		else if (v == rsite)
			out->ext[k] = basel;
		else
			out->ext[k] = from->ext[k];
	}
	out->vert = TDC_NIL;
	out->nsites = L->nsites + R->nsites;
}
