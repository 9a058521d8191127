/*
 * raster_natural.c
 *		Natural neighbour pixels of a bounded run's grid (tdc_raster_nn_tile,
 *		tdc_bounded.h): the whole TIN's values, to the bit, from each tile's
 *		own triangulation.
 *
 * Sibson's value at a pixel centre q (tin_natural.c) is made of the
 * cavity of q: the triangles of the Delaunay triangulation T(P) whose open
 * circumdisk holds q, and nothing else (tin_natural.c computes it from
 * their corners, heights and circumcentres alone, in an order the geometry
 * fixes).  A tile holds T(Q), the triangulation of the points Q of a box K
 * around it; raster.c hands over the pixels its final triangles hold
 * (closed; a centre on P's hull is linear along the hull edge, at a site
 * the site's height, as in one TIN), and for each here the tile's cavity
 * cav_Q is computed on a TIN of T(Q) and accepted only when it is proven
 * to be the global cavity cav_P:
 *
 *	(a) every triangle of cav_Q is a triangle of T(P), and
 *	(b) across every boundary edge e of cav_Q, the triangle of T(Q) is one
 *		of T(P) too, or e is an edge of T(Q)'s outer face and a hull edge
 *		of P.
 *
 * Then cav_P = cav_Q.  cav_P holds a triangle of cav_Q (q's own, which
 * T(P) shares by (a)), and it is edge-connected (the Bowyer-Watson cavity
 * is star-shaped from q), so if it held more it would hold a triangle t'
 * across a boundary edge e of cav_Q, from the side away from cav_Q; by
 * (b) that is the triangle of T(Q) across e, which is not in cav_Q, so q
 * is not in its open circumdisk; or there is none, e being on P's hull.
 * And cav_P holds every triangle of cav_Q, which are in T(P) by (a) with
 * q in their circumdisks.
 *
 * A triangle of T(Q) is proven in T(P) when one of its corners is an own
 * site of the tile (the tile is final: every own site's star passed, see
 * docs/design/tiles.md), or by Lemma 1 there, decided as tile_final.c
 * decides it: the box of its closed circumdisk (tile_disk.c, with its
 * forward error bound; a triangle too flat for the bound is not proven by
 * its disk) inside what the tile knows (K, a side of K past the box B of
 * P's hull open, the extra boxes), else the box of the disk's part inside
 * P's hull and on the inner side of the triangle's own edges on that hull,
 * else with the cells, every cell the disk meets empty or known
 * (tile_cells.c).  An outer edge a -> b of T(Q) is P's hull edge when
 * every vertex of P's hull lies on its closed left (exact orientations).
 *
 * A pixel that fails is left unwritten and the tile asks, as a tile that
 * is not final asks (final_run, tdc_bounded.h): the cells the failing
 * disks meet and the boxes of those disks (an outer edge of T(Q) that is
 * not P's: the cells beyond it and its box grown by its length; B when
 * nothing smaller can help), and the bounded run runs it again knowing
 * more.  Its known region grows every time; once it holds B, Q = P and
 * every cavity is proven, so the run completes unless the limit stops it
 * first: where wide empty triangles join dense clusters, the cavity of a
 * pixel between them has circumdisks whose rims cross the clusters, and
 * the run says that a tile needs more than the limit.  The pixels already
 * written are global values and are written again the same; a centre on
 * an edge between two tiles' triangles is written by both, the same.
 * What makes the bits equal to the whole TIN's: cav_Q is cav_P as a set
 * of triangles, and tin_natural.c's value depends on that geometry only
 * (its order of summation and its circumcentres start from the first
 * vertex in (x, y) order, not from how a mesh numbers its half-edges).
 *
 * Memory: the TIN of T(Q) (tdc_tin_memory), a label and a flag per point
 * and a state per triangle (at most two a point), within
 * TDC_RASTER_NN_PER_POINT bytes a point of the tile, counted in the tile's
 * model by the caller; the cavity scratch within RS_NN_HOLD.  Each
 * triangle asks once, so the cells asked for are at most the failing
 * triangles' few each.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/predicates.h"
#include "raster_int.h"
#include "tiles/tile_cells.h"
#include "tiles/tile_disk.h"
#include "tin/tin_int.h"

#define TRI_PROVEN	1			/* in T(P) */
#define TRI_ASKED	2			/* not proven: what it needs is asked for already */

/* what the fill of one tile needs */
typedef struct nn_tile
{
	tdc_raster *r;
	tdc_tin    *tin;
	tin_scratch sc;
	uint8_t    *own;			/* per site of T(Q): an own site of the tile */
	uint8_t    *state;			/* per triangle of T(Q): 0 not tried, TRI_PROVEN, TRI_ASKED */
	const tdc_tile_spec *spec;	/* what the tile knows: K, extra boxes, cells */
	const double **known_list;	/* K and the extra boxes */
	tdc_cells	cells;			/* the spec's cells (g NULL without) */
	tdc_cell_list cl;			/* OTHER cells a failing pixel needs */
	double		keff[4];		/* K, a side past B's open */
	double		need[4];		/* what failed, clipped to B */
	bool		more;			/* some pixel failed: need holds what it asks */
	bool		all;			/* K holds B: Q = P, everything is proven */
	uint32_t	hint;
} nn_tile;

/* need grown by box, clipped to the hull's box B */
static void
ask(nn_tile *t, const double *box)
{
	const double *B = t->r->fr.box;

	t->need[0] = fmin(t->need[0], fmax(box[0], B[0]));
	t->need[1] = fmin(t->need[1], fmax(box[1], B[1]));
	t->need[2] = fmax(t->need[2], fmin(box[2], B[2]));
	t->need[3] = fmax(t->need[3], fmin(box[3], B[3]));
	t->more = true;
}

/*
 * Is box known (docs/design/tiles.md, Lemma 1): inside K, or past it only
 * where K reaches past B, or its part inside B covered by K and the extra
 * boxes?  As tile_final.c's box_known.
 */
static bool
box_known(const nn_tile *t, const double *box)
{
	const double *B = t->r->fr.box;
	double		r[4] = {fmax(box[0], B[0]), fmax(box[1], B[1]), fmin(box[2], B[2]), fmin(box[3], B[3])};

	if (box[0] > t->keff[0] && box[1] > t->keff[1] && box[2] < t->keff[2] && box[3] < t->keff[3])
		return true;
	return t->spec->nextra > 0 && tdc_box_covered(r, t->known_list, t->spec->nextra + 1);
}

/* box_known for the cells' walks (tile_cells.c) */
static bool
cell_covered(const void *arg, const double box[4])
{
	return box_known((const nn_tile *) arg, box);
}

/* Is outer edge a -> b of T(Q) a hull edge of P (every vertex of P's hull on its closed left)? */
static bool
on_hull(const nn_tile *t, const double *a, const double *b)
{
	const fringe *fr = &t->r->fr;

	for (size_t i = 0; i < fr->nhull; i++)
		if (tdc_orient2d(a, b, fr->hull + 2 * i) < 0)
			return false;
	return true;
}

/*
 * Is the triangle left of h (not the outer face) in T(P)?  Lemma 1 as
 * tile_final.c decides it (tile_disk.c): the disk's box, else the box of
 * its part inside P's hull and on the inner side of its own edges on P's
 * hull, else the cells.  If not, ask for that box and those cells.  Each
 * triangle is decided once a tile (many pixels share it).
 */
static bool
tri_decide(nn_tile *t, uint32_t h)
{
	const tdc_tin *tin = t->tin;
	const fringe *fr = &t->r->fr;
	uint32_t	hh[3],
				v[3];
	const double *p[3];
	double		box[4],
				disk[3];

	hh[0] = h;
	hh[1] = tin_lnext(tin, h);
	hh[2] = tin_lnext(tin, hh[1]);
	for (int k = 0; k < 3; k++)
	{
		v[k] = tin_org(tin, hh[k]);
		p[k] = tin_pt(tin, v[k]);
	}
	if (t->all || t->own[v[0]] || t->own[v[1]] || t->own[v[2]])
		return true;
	if (!tdc_disk_box(p[0], p[1], p[2], box, disk))
	{
		ask(t, fr->box);
		return false;
	}
	if (box_known(t, box))
		return true;
	for (int k = 0; k < 3; k++)
		if (tin_outer(tin, hh[k] ^ 1u) && on_hull(t, p[k], p[(k + 1) % 3]))
		{
			tdc_disk_clip_box(disk, p[k], p[(k + 1) % 3], box);
			tdc_disk_segment_box(p[k], p[(k + 1) % 3], p[(k + 2) % 3], box);
		}
	for (size_t i = 0; i < fr->nhull; i++)
		tdc_disk_clip_box(disk, fr->hull + 2 * i, fr->hull + 2 * ((i + 1) % fr->nhull), box);
	if (box_known(t, box))
		return true;
	/* with cells: known when every cell the disk meets is empty or known */
	if (t->cells.g != NULL)
	{
		double		near[6] = {p[0][0], p[0][1], p[1][0], p[1][1], p[2][0], p[2][1]};

		if (tdc_cells_disk(&t->cells, disk, box, near, 3, cell_covered, t, &t->cl))
			return true;
	}
	ask(t, box);
	return false;
}

/* tri_decide, once a triangle */
static bool
tri_proven(nn_tile *t, uint32_t h)
{
	uint8_t    *st = &t->state[t->tin->he_tri[h]];

	if (*st == 0)
		*st = tri_decide(t, h) ? TRI_PROVEN : TRI_ASKED;
	return *st == TRI_PROVEN;
}

/* Is outer edge a -> b of T(Q) (outer face on its right) a hull edge of P?  If not, ask around it. */
static bool
hull_proven(nn_tile *t, uint32_t a, uint32_t b)
{
	const double *pa = tin_pt(t->tin, a),
			   *pb = tin_pt(t->tin, b);
	double		g,
				box[4];

	if (t->all || on_hull(t, pa, pb))
		return true;
	if (t->cells.g != NULL)
		(void) tdc_cells_beyond(&t->cells, pa, pb, cell_covered, t, &t->cl);
	g = fabs(pb[0] - pa[0]) + fabs(pb[1] - pa[1]);
	box[0] = fmin(pa[0], pb[0]) - g;
	box[1] = fmin(pa[1], pb[1]) - g;
	box[2] = fmax(pa[0], pb[0]) + g;
	box[3] = fmax(pa[1], pb[1]) + g;
	ask(t, box);
	return false;
}

/*
 * The value at q, a centre strictly inside a final triangle or an edge of
 * one not on P's hull: 1 with *z when its cavity is proven global, 0 when
 * not (t->need grown), or an error.
 */
static int
nn_value(nn_tile *t, const double *q, double *z)
{
	const tdc_tin *tin = t->tin;
	tin_scratch *sc = &t->sc;
	tin_loc		loc;
	bool		ok = true;
	int			rc;

	tin_locate(tin, q, t->hint, &loc);
	if (loc.h != TDC_NIL)
		t->hint = loc.h;
	if (loc.kind != LOC_FACE && loc.kind != LOC_EDGE)
		return TDC_EINVAL;		/* a final triangle holds q: T(Q) must too */
	if (loc.kind == LOC_EDGE && (loc.h == TDC_NIL || tin_outer(tin, loc.h ^ 1u)))
	{
		/* on T(Q)'s hull but inside P's: points beyond the edge are missing */
		if (loc.h == TDC_NIL || hull_proven(t, tin_org(tin, loc.h), tin_dest(tin, loc.h)))
			ask(t, t->r->fr.box);
		return 0;
	}
	rc = tin_natural(tin, sc, q, &loc, z);
	if (rc == TDC_ENOMEM)
		return rc;
	if (rc != TDC_OK)
	{
		/* T(Q)'s cavity is not a disk: only where T(Q) is not T(P) near q */
		ask(t, t->r->fr.box);
		return 0;
	}
	/* (a): the cavity's triangles; (b): across its boundary (sc->bnd[0 .. nbnd)) */
	for (size_t i = 0; i < sc->ntri; i++)
		ok &= tri_proven(t, sc->tri[i]);
	for (size_t i = 0; i < sc->nbnd; i++)
	{
		uint32_t	b = sc->bnd[i];

		/* b has the cavity on its left; the other side is outer or a triangle */
		ok &= tin_outer(tin, b ^ 1u) ? hull_proven(t, tin_org(tin, b), tin_dest(tin, b)) :
			tri_proven(t, b ^ 1u);
	}
	return ok ? 1 : 0;
}

/* rs_fill_fn: the window's natural neighbour pixels, each proven or left unwritten */
static int
nn_fill(void *arg, size_t w0, size_t w1, size_t c0, size_t wcols, uint64_t *win, char *err,
		size_t errlen)
{
	nn_tile    *t = arg;

	for (size_t row = w0; row < w1; row++)
		for (size_t col = c0; col < c0 + wcols; col++)
		{
			uint64_t   *w = win + (row - w0) * wcols + (col - c0);
			double		q[2],
						z;
			int			rc;

			if (*w != RS_NN_MARK)
				continue;
			rs_centre(t->r->g.gt, col, row, q);
			rc = nn_value(t, q, &z);
			if (rc < 0)
			{
				char		c[80];

				snprintf(c, sizeof(c), "(%.17g %.17g)", q[0], q[1]);
				return tdc_rs_fail(err, errlen, rc, rc == TDC_ENOMEM ?
								   "out of memory for the natural neighbour cavity at %s" :
								   "the natural neighbour cavity at %s: the tile's triangulation "
								   "does not hold the centre its final triangle holds", c);
			}
			if (rc == 1)
				memcpy(w, &z, 8);
			else
				*w = RS_SENT;
		}
	if (t->sc.bytes > RS_NN_HOLD)
		return tdc_rs_fail(err, errlen, TDC_EMEMLIMIT, "%s", "a natural neighbour cavity needs more "
						   "than the grid's scratch allows (a huge set of cocircular sites)");
	return TDC_OK;
}

/* The tile's state freed. */
static void
nn_free(nn_tile *t)
{
	tin_scratch_free(&t->sc);
	free(t->own);
	free(t->state);
	free(t->known_list);
	free(t->cl.v);
	tdc_cells_free(&t->cells);
	if (t->tin)
		tdc_tin_free(t->tin);
}

int
tdc_raster_nn_tile(tdc_raster *r, const tdc_job *job, const double *q, const double *qz, size_t m,
				   const size_t *tri, size_t ntri, const tdc_tile_spec *spec,
				   tdc_tile_result *more, char *err, size_t errlen)
{
	nn_tile		t;
	const double *B = r->fr.box,
			   *K = spec->known;
	int64_t    *lab;
	int			rc;

	memset(more, 0, sizeof(*more));
	if (r->spec.method != TDC_INTERP_NATURAL)
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "tdc_raster_nn_tile is for a natural "
						   "neighbour grid");
	if (ntri == 0)
		return TDC_OK;
	memset(&t, 0, sizeof(t));
	t.r = r;
	t.spec = spec;
	t.hint = TDC_NIL;
	memcpy(t.need, K, sizeof(t.need));
	t.keff[0] = K[0] <= B[0] ? -INFINITY : K[0];
	t.keff[1] = K[1] <= B[1] ? -INFINITY : K[1];
	t.keff[2] = K[2] >= B[2] ? INFINITY : K[2];
	t.keff[3] = K[3] >= B[3] ? INFINITY : K[3];
	t.all = isinf(t.keff[0]) && isinf(t.keff[1]) && isinf(t.keff[2]) && isinf(t.keff[3]);
	t.known_list = malloc(sizeof(double *) * (spec->nextra + 1));
	lab = malloc(sizeof(int64_t) * (m + 1));
	t.own = calloc(m + 1, 1);
	if (t.known_list == NULL || lab == NULL || t.own == NULL ||
		(spec->grid != NULL && !tdc_cells_init(&t.cells, spec->grid)))
	{
		free(lab);
		nn_free(&t);
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the tile's sites");
	}
	t.known_list[0] = K;
	for (size_t i = 0; i < spec->nextra; i++)
		t.known_list[i + 1] = spec->extra + 4 * i;
	if ((rc = tdc_tin_build(job, qz, 1, 0, &t.tin, err, errlen)) != TDC_OK)
	{
		free(lab);
		nn_free(&t);
		return rc;
	}
	if (t.tin->mesh.nin != m)
	{
		free(lab);
		nn_free(&t);
		return tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "the tile's job is not of its points");
	}
	if ((t.state = calloc(t.tin->ntri + 1, 1)) == NULL)
	{
		free(lab);
		nn_free(&t);
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the tile's triangles");
	}
	/* own sites: a site belongs to the least tile among its copies (tile_final.c) */
	for (size_t s = 0; s < m; s++)
		lab[s] = INT64_MAX;
	for (size_t at = 0; at < m; at++)
	{
		uint32_t	s = t.tin->mesh.site_of[at];
		int64_t		l = spec->tile[t.tin->mesh.idx[at]];

		if (l < lab[s])
			lab[s] = l;
	}
	for (size_t s = 0; s < m; s++)
		t.own[s] = lab[s] == spec->self;
	free(lab);

	rc = tdc_rs_tile(r, q, qz, tri, ntri, nn_fill, &t, err, errlen);
	if (rc == TDC_OK && t.more && t.all)
		rc = tdc_rs_fail(err, errlen, TDC_EINVAL, "%s", "a natural neighbour cavity of a tile "
						 "that holds every point is not proven: a bug");
	if (rc != TDC_OK || !t.more)
	{
		nn_free(&t);
		return rc;
	}
	/* a box containing K that K does not hold: else all of B */
	if (t.need[0] >= K[0] && t.need[1] >= K[1] && t.need[2] <= K[2] && t.need[3] <= K[3])
	{
		t.need[0] = fmin(K[0], B[0]);
		t.need[1] = fmin(K[1], B[1]);
		t.need[2] = fmax(K[2], B[2]);
		t.need[3] = fmax(K[3], B[3]);
	}
	memcpy(more->need, t.need, sizeof(t.need));
	if (t.cells.g != NULL && t.cl.n > 0 &&
		!tdc_cells_merge(&t.cells, &t.cl, 1, &more->need_cells, &more->nneed_cells))
	{
		memset(&t.cl, 0, sizeof(t.cl));
		nn_free(&t);
		return tdc_rs_fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the cells a tile needs");
	}
	memset(&t.cl, 0, sizeof(t.cl));		/* merged: the list is gone */
	nn_free(&t);
	return 1;
}
