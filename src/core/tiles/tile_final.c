/*
 * tile_final.c
 *		Exact tiled triangulation: the triangles of one tile of the global
 *		Delaunay triangulation, from the points of a box around the tile.
 *
 * A tile is triangulated with Q, every point of P (the global set) inside
 * a known box K (and optional extra boxes), and keeps the triangles it can
 * prove global: the finalization rule of streaming Delaunay (Isenburg, Liu,
 * Shewchuk, Snoeyink, SIGGRAPH 2006) applied to the stars of distributed
 * Delaunay (Caraffa, Memari, Yirci, Brédif, "Tile & merge", 2019).
 * Lemma 1: a triangle of T(Q) whose closed circumdisk is known (it meets
 * C, the convex polygon around P, only inside K and the extra boxes) is in
 * T(P), since the tie rule looks at four sites only.  Lemma 2: an outer
 * edge of T(Q) whose outer half-plane meets C only inside K is a hull edge
 * of P.  When the stars of all own sites pass them, the tile emits the
 * triangles whose smallest vertex it owns (the smallest label among a
 * site's copies): every triangle exactly once.  Otherwise it reports a
 * larger box, which grows every round up to C's bounding box B.  Lemma 2
 * is decided exactly; Lemma 1 from a disk's box with a forward error bound,
 * shrunk for slivers near the hull (both in tile_disk.c), and skipped for
 * "deep" sites, whose stars a block count certifies (mark_deep).  The
 * tile's mesh is read through mesh_view.h.
 *
 * The design note, with the notation, both proofs, the rounding and the
 * references, is docs/design/tiles.md.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/mesh_view.h"
#include "tile_cells.h"
#include "tile_disk.h"

#define EPS		0x1p-53

/* Exact "p on the closed left of a -> b". */
static inline bool
left_or_on(const double *a, const double *b, const double *p)
{
	return tdc_orient2d(a, b, p) >= 0;
}

typedef struct tile_ctx
{
	const tdc_tile_spec *spec;
	double		keff[4];		/* K with sides at infinity where K reaches B */
	double		B[4];			/* bounding box of C */
	double		need[4];		/* K united with the requests so far */
	bool		want_all;		/* a request we could not bound: ask for B */
	const double **known_list;	/* K, then the extra boxes */
	bool		skip_checks;	/* K covers B: only collect the triangles */
	const tdc_cells *cells;		/* the caller's grid, or NULL */
	tdc_cell_list cl;			/* the OTHER cells asked for (each thread its own) */
} tile_ctx;

static void
box_union(double *u, const double *b)
{
	u[0] = fmin(u[0], b[0]);
	u[1] = fmin(u[1], b[1]);
	u[2] = fmax(u[2], b[2]);
	u[3] = fmax(u[3], b[3]);
}

/*
 * Is the part of box r inside the closed box b covered by the union of the
 * closed boxes k[0..nk)?  Subtracts one box at a time; the up to four
 * pieces left around it are taken closed, which only asks for more.
 */
static bool
box_covered(const double *r0, const double *const *k, size_t nk, int depth)
{
	double		r[4];

	memcpy(r, r0, sizeof(r));
	if (r[0] > r[2] || r[1] > r[3])
		return true;
	for (size_t i = 0; i < nk; i++)
	{
		const double *x = k[i];
		double		pieces[4][4];
		int			np = 0;

		if (x[0] > r[2] || x[2] < r[0] || x[1] > r[3] || x[3] < r[1])
			continue;
		if (depth > 6)
			return false;
		if (r[0] < x[0])
			memcpy(pieces[np++], (double[4]) {r[0], r[1], x[0], r[3]}, sizeof(double[4]));
		if (r[2] > x[2])
			memcpy(pieces[np++], (double[4]) {x[2], r[1], r[2], r[3]}, sizeof(double[4]));
		if (r[1] < x[1])
			memcpy(pieces[np++], (double[4]) {fmax(r[0], x[0]), r[1], fmin(r[2], x[2]), x[1]}, sizeof(double[4]));
		if (r[3] > x[3])
			memcpy(pieces[np++], (double[4]) {fmax(r[0], x[0]), x[3], fmin(r[2], x[2]), r[3]}, sizeof(double[4]));
		for (int j = 0; j < np; j++)
			if (!box_covered(pieces[j], k + i + 1, nk - i - 1, depth + 1))
				return false;
		return true;
	}
	return false;
}

/*
 * Is region box (holding the region that matters) known: its part inside B
 * covered by K and the extra boxes?  No point lies outside B.
 */
static bool
box_known(const tile_ctx *cx, const double *box)
{
	double		r[4] = {fmax(box[0], cx->B[0]), fmax(box[1], cx->B[1]),
	fmin(box[2], cx->B[2]), fmin(box[3], cx->B[3])};

	/* the common case, without allocation */
	if (box[0] > cx->keff[0] && box[1] > cx->keff[1] &&
		box[2] < cx->keff[2] && box[3] < cx->keff[3])
		return true;
	if (cx->spec->nextra == 0)
		return false;
	return box_covered(r, cx->known_list, cx->spec->nextra + 1, 0);
}

bool
tdc_box_covered(const double *r, const double *const *k, size_t nk)
{
	return box_covered(r, k, nk, 0);
}

/* box_known for the cells' walks (tile_cells.c). */
static bool
cell_covered(const void *arg, const double box[4])
{
	return box_known((const tile_ctx *) arg, box);
}

/*
 * Add a request, grown by a tenth of its size and a millionth of K's (a
 * vertex of the failing disk may lie on K's side, and the box must then
 * pass it), and clipped to B (there are no points beyond it).
 */
static void
request(tile_ctx *cx, const double *box)
{
	const double *K = cx->spec->known;
	double		px = 0.1 * (box[2] - box[0]) + 1e-6 * (K[2] - K[0]) +
		1e-9 * (fabs(box[0]) + fabs(box[2])) + 0x1p-1000,
				py = 0.1 * (box[3] - box[1]) + 1e-6 * (K[3] - K[1]) +
		1e-9 * (fabs(box[1]) + fabs(box[3])) + 0x1p-1000;
	double		c[4] = {fmax(box[0] - px, cx->B[0]), fmax(box[1] - py, cx->B[1]),
	fmin(box[2] + px, cx->B[2]), fmin(box[3] + py, cx->B[3])};

	if (c[0] > c[2] || c[1] > c[3])
		return;
	box_union(cx->need, c);
}

/*
 * What to ask for when hull edge a -> b of T(Q) is not final: points of P
 * may lie beyond it, outside K.  Ask for the edge's box grown by its length
 * (Q's hull edges at own sites usually mean a halo thinner than the local
 * spacing), at most a twentieth of K's size to start with, doubling the
 * growth until the box leaves K so that K must grow;
 * and for the nearest vertex of C beyond the edge too when it is within a
 * few edge lengths (a global hull vertex, which the star needs).
 */
static void
hull_edge_request(tile_ctx *cx, const double *a, const double *b, const double *cvert,
				  double cdist2)
{
	const double *K = cx->spec->known;
	double		dx = b[0] - a[0],
				dy = b[1] - a[1],
				g = sqrt(dx * dx + dy * dy),
				box[4];

	/*
	 * A long edge of Q's hull (say between a halo strip and K's corner)
	 * must not blow K up by its length: start from a twentieth of K.
	 */
	g = fmin(g, fmax(K[2] - K[0], K[3] - K[1]) * 0.05);
	if (!(g > 0))
		g = fmax(K[2] - K[0], K[3] - K[1]) * 1e-3 + 0x1p-1000;
	for (int i = 0; i < 64; i++, g *= 2)
	{
		box[0] = fmin(a[0], b[0]) - g;
		box[1] = fmin(a[1], b[1]) - g;
		box[2] = fmax(a[0], b[0]) + g;
		box[3] = fmax(a[1], b[1]) + g;
		if (box[0] < K[0] || box[1] < K[1] || box[2] > K[2] || box[3] > K[3])
			break;
	}
	request(cx, box);
	if (cdist2 <= 16 * g * g)
		request(cx, cvert);
}

/*
 * Lemma 2 (docs/design/tiles.md) for the hull edge a -> b of T(Q)
 * (interior on its left): is the open half-plane right of it, intersected
 * with C, inside K?  Either every vertex of C is on the closed left (the
 * edge is on the global hull), or every strip of B outside K has its four
 * corners on the closed left.  When it fails, requests the vertices of C
 * strictly right of the edge.
 */
static bool
hull_edge_final(tile_ctx *cx, const double *a, const double *b)
{
	const tdc_tile_spec *sp = cx->spec;
	const double *K = sp->known;
	const double *B = cx->B;
	bool		all_left = true;
	double		strips[4][4];
	int			ns = 0;
	double		rq[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};

	double		best = INFINITY;

	/* the vertex of C beyond the edge nearest to it */
	for (size_t i = 0; i < sp->nhull; i++)
		if (!left_or_on(a, b, sp->hull + 2 * i))
		{
			const double *v = sp->hull + 2 * i;
			double		dx = v[0] - 0.5 * (a[0] + b[0]),
						dy = v[1] - 0.5 * (a[1] + b[1]),
						d2 = dx * dx + dy * dy;

			all_left = false;
			if (d2 < best || rq[0] > rq[2])
			{
				best = d2;
				rq[0] = rq[2] = v[0];
				rq[1] = rq[3] = v[1];
			}
		}
	if (all_left)
		return true;

	/* the closures of B \ K: left, right, bottom, top strips */
	if (K[0] > B[0])
		memcpy(strips[ns++], (double[4]) {B[0], B[1], K[0], B[3]}, sizeof(double[4]));
	if (K[2] < B[2])
		memcpy(strips[ns++], (double[4]) {K[2], B[1], B[2], B[3]}, sizeof(double[4]));
	if (K[1] > B[1])
		memcpy(strips[ns++], (double[4]) {B[0], B[1], B[2], K[1]}, sizeof(double[4]));
	if (K[3] < B[3])
		memcpy(strips[ns++], (double[4]) {B[0], K[3], B[2], B[3]}, sizeof(double[4]));
	for (int s = 0; s < ns; s++)
		for (int k = 0; k < 4; k++)
		{
			double		p[2] = {strips[s][(k & 1) ? 2 : 0], strips[s][(k & 2) ? 3 : 1]};

			if (!left_or_on(a, b, p))
			{
				/* with a grid: known if no cell beyond it may hold a point Q lacks */
				if (cx->cells && tdc_cells_beyond(cx->cells, a, b, cell_covered, cx, &cx->cl))
					return true;
				hull_edge_request(cx, a, b, rq, best);
				return false;
			}
		}
	return true;
}

/*
 * Lemma 1 (docs/design/tiles.md; the finalization rule of Isenburg, Liu,
 * Shewchuk, Snoeyink 2006) for triangle v[0..2] (counter-clockwise) of
 * T(Q); glob[k] says whether edge v[k] -> v[k+1] is a hull edge of T(Q)
 * certified global, own[k] whether v[k] is an own site (one is).
 * The disk's box is tried first; if it is not known, the box of the disk's
 * part inside C (clipped by C's edges and the certified hull edges, whose
 * lines support C) is tried.
 */
static bool
triangle_final(tile_ctx *cx, const double *p[3], const bool glob[3], const bool own[3])
{
	const tdc_tile_spec *sp = cx->spec;
	double		box[4],
				disk[3];

	if (sp->test_weaken == TDC_TILE_WEAKEN_DISKS)
		return true;
	if (!tdc_disk_box(p[0], p[1], p[2], box, disk))
	{
		cx->want_all = true;
		return false;
	}
	if (box_known(cx, box))
		return true;
	for (int k = 0; k < 3; k++)
		if (glob[k])
		{
			tdc_disk_clip_box(disk, p[k], p[(k + 1) % 3], box);
			tdc_disk_segment_box(p[k], p[(k + 1) % 3], p[(k + 2) % 3], box);
		}
	for (size_t i = 0; sp->nhull >= 2 && i < sp->nhull; i++)
		tdc_disk_clip_box(disk, sp->hull + 2 * i, sp->hull + 2 * ((i + 1) % sp->nhull), box);
	if (box_known(cx, box))
		return true;
	/* with a grid: known if every cell the disk meets is empty or passed whole */
	if (cx->cells)
	{
		/* its own vertices: their stars need the points near them first */
		double		near[6];
		int			nnear = 0;

		for (int k = 0; k < 3; k++)
			if (own[k])
			{
				near[2 * nnear] = p[k][0];
				near[2 * nnear++ + 1] = p[k][1];
			}
		if (tdc_cells_disk(cx->cells, disk, box, near, nnear, cell_covered, cx, &cx->cl))
			return true;
	}
	request(cx, box);
	return false;
}

static int
cmp_i64(int64_t a, int64_t b)
{
	return a < b ? -1 : a > b;
}

/* Per-site flags of tdc_tile_finish. */
#define SITE_OWN	1			/* the site belongs to this tile */
#define SITE_DEEP	2			/* every triangle at it is final (mark_deep) */

/*
 * Deep sites: Lemma 1 for every triangle at a site at once, from counts.
 * G, K clipped to the box of Q, is cut into a grid of blocks of about
 * BLOCK_POINTS points each (counting Q's points in G); take one block side
 * beta at least as large as every block's sides.  If every block within distance 2 rho of a site a is non-empty,
 * where rho = sqrt(2) beta, then every triangle of T(Q) at a has a
 * circumradius R < rho.  Proof: if R >= rho, the disk D' of radius rho
 * inside D, tangent to it at a, lies within 2 rho of a and holds the
 * axis-aligned square of side sqrt(2) rho = 2 beta around its centre,
 * which holds a whole block; that block has a point of Q, which lies in
 * the open disk D', hence in the open circumdisk of a triangle of T(Q): no
 * such triangle exists.  So the closed circumdisk lies within 2R < 2 rho
 * of a, and when the box of a grown by 2 rho is inside K the star of a
 * passes Lemma 1 without a disk being computed.
 *
 * Rounding.  The blocks are real boxes of width 1/sx (and 1/sy) from the
 * grid's corner, sx, sy being the doubles used; a point's computed block
 * index is within 1e-11 of a block of its true position for grids below
 * 1e4 blocks a side (two roundings of a value at most the block count), so
 * every block is taken 1e-6 of a width wider and beta is 4e-6 larger than
 * the computed widths.  The disk D' is taken of radius rho' = rho (1 +
 * 1e-5): the square of side 2 beta around its centre then lies in its
 * interior, so the block's point is not a (on D's circle) but inside D.
 * The distance used is 2 rho (1 + 2e-5) >= 2 rho', whose slack also
 * covers the rounding of the site's box grown by it (with a few ulps of
 * the site's coordinates).
 *
 * The uniform tiles of the CLI leave only their rim to the disk test;
 * where data has holes, the sites within 2 rho of an empty block are not
 * deep and go through the disk test as before.
 */
#define BLOCK_POINTS	10

static int
block_of(double v, double lo, double scale, int nb)
{
	double		t = (v - lo) * scale;
	int			b = (int) t;

	return b < 0 ? 0 : b >= nb ? nb - 1 : b;
}

/*
 * Set SITE_DEEP in flag[] for the deep sites (any owner), as above.
 * Returns false only when out of memory (then no site is deep).
 */
static bool
mark_deep(const tdc_mesh_view *mesh, const tile_ctx *cx, uint8_t *flag, bool weaken)
{
	const double *K = cx->spec->known;
	size_t		nin = mesh->nin,
				ng = 0;
	/* the grid covers G, K clipped to Q's box: the bands' points lie outside */
	double		lo[2] = {fmax(K[0], mesh->bmin[0]), fmax(K[1], mesh->bmin[1])},
				hi[2] = {fmin(K[2], mesh->bmax[0]), fmin(K[3], mesh->bmax[1])},
				W = hi[0] - lo[0],
				H = hi[1] - lo[1],
				side,
				sx,
				sy,
				beta,
				rho2;
	long		bx,
				by,
				kx,
				ky;
	uint32_t   *ps;
	uint8_t    *ok;

#define IN_G(a) ((a)[0] >= lo[0] && (a)[0] <= hi[0] && (a)[1] >= lo[1] && (a)[1] <= hi[1])
	if (!(W > 0) || !(H > 0) || !isfinite(W) || !isfinite(H))
		return true;
	for (size_t p = 0; p < nin; p++)
		ng += IN_G(mesh->xy + 2 * p);
	if (ng < 64 * BLOCK_POINTS)
		return true;
	side = sqrt(W / ng * H * BLOCK_POINTS);
	if (!(side > 0) || !isfinite(side))
		return true;
	bx = (long) fmin(fmax(W / side, 1), 8192);
	by = (long) fmin(fmax(H / side, 1), 8192);
	sx = bx / W;
	sy = by / H;
	if (!(sx > 0) || !(sy > 0) || !isfinite(sx) || !isfinite(sy))
		return true;
	beta = fmax(1 / sx, 1 / sy) * (1 + 4e-6);
	/* 2 rho', widened */
	rho2 = 2 * sqrt(2.0) * beta * (1 + 2e-5);
	kx = (long) ceil(rho2 * sx * (1 + 1e-9) + 1e-6);
	ky = (long) ceil(rho2 * sy * (1 + 1e-9) + 1e-6);
	if (2 * kx + 1 > bx || 2 * ky + 1 > by)
		return true;
	ps = calloc((size_t) (bx + 1) * (by + 1), sizeof(uint32_t));
	ok = malloc((size_t) bx * by);
	if (ps == NULL || ok == NULL)
	{
		free(ps);
		free(ok);
		return false;
	}
	/* non-empty blocks, then their 2-D prefix sums */
	for (size_t p = 0; p < nin; p++)
		if (IN_G(mesh->xy + 2 * p))
			ps[(size_t) (block_of(mesh->xy[2 * p + 1], lo[1], sy, by) + 1) * (bx + 1) +
			   block_of(mesh->xy[2 * p], lo[0], sx, bx) + 1] = 1;
	if (weaken)
		for (long j = 0; j < by; j++)
			for (long i = 0; i < bx; i++)
				ps[(size_t) (j + 1) * (bx + 1) + i + 1] = 1;
	for (long j = 1; j <= by; j++)
		for (long i = 1; i <= bx; i++)
			ps[(size_t) j * (bx + 1) + i] += ps[(size_t) (j - 1) * (bx + 1) + i] +
				ps[(size_t) j * (bx + 1) + i - 1] - ps[(size_t) (j - 1) * (bx + 1) + i - 1];
	/* a block is ok when its neighbourhood lies in the grid and has no empty block */
	for (long j = 0; j < by; j++)
		for (long i = 0; i < bx; i++)
		{
			long		i0 = i - kx,
						i1 = i + kx + 1,
						j0 = j - ky,
						j1 = j + ky + 1;

			ok[(size_t) j * bx + i] = i0 >= 0 && j0 >= 0 && i1 <= bx && j1 <= by &&
				ps[(size_t) j1 * (bx + 1) + i1] - ps[(size_t) j0 * (bx + 1) + i1] -
				ps[(size_t) j1 * (bx + 1) + i0] + ps[(size_t) j0 * (bx + 1) + i0] ==
				(uint32_t) ((i1 - i0) * (j1 - j0));
		}
	free(ps);
	for (size_t p = 0; p < nin; p++)
	{
		const double *a = mesh->xy + 2 * p;
		double		r = rho2 + 4 * EPS * (fabs(a[0]) + fabs(a[1])),
					box[4] = {a[0] - r, a[1] - r, a[0] + r, a[1] + r};

		if (IN_G(a) &&
			ok[(size_t) block_of(a[1], lo[1], sy, by) * bx + block_of(a[0], lo[0], sx, bx)] &&
			box[0] > cx->keff[0] && box[1] > cx->keff[1] &&
			box[2] < cx->keff[2] && box[3] < cx->keff[3])
			flag[p] |= SITE_DEEP;
	}
	free(ok);
	return true;
#undef IN_G
}

/*
 * The checks run on the job's thread count, each thread over a range of
 * half-edges, with its own copy of the context (its requests are merged
 * afterwards); on the way each keeps the triangles whose smallest vertex is
 * owned, handed over if the tile turns out final.  flag[] (SITE_OWN,
 * SITE_DEEP per site) is only read.
 */
typedef struct tile_work
{
	const tdc_mesh_view *mesh;
	tile_ctx	cx;
	const uint8_t *flag;
	size_t		lo,
				hi;
	size_t		unfinal;		/* failing triangles and hull edges at own sites */
	size_t		deep;			/* triangles at own sites final by a deep vertex */
	size_t		ntri,
				cap;
	size_t	   *tri;
	bool		failed;
	void		(*fn) (struct tile_work *w);
} tile_work;

#define PF		48				/* prefetch distance in half-edges */

static void
check_range(tile_work *w)
{
	const tdc_mesh_view *mesh = w->mesh;
	const tdc_he *he = mesh->he;
	const uint8_t *flag = w->flag;
	const tdc_tile_spec *spec = w->cx.spec;
#ifdef __GNUC__
	const size_t nhe = w->mesh->nin * 6;
#endif

	for (size_t h = w->lo; h < w->hi; h++)
	{
		uint32_t	a,
					b,
					v[3],
					hh[3];
		const double *p[3];
		bool		glob[3],
					own[3];
		uint8_t		fl;

#ifdef __GNUC__

		/*
		 * The walk is bound by one random load per half-edge: the record
		 * of lnext's twin, which holds both the third corner and the next
		 * link (lnext's own record is next to its twin's, and h's twin is
		 * next to h).  Fetch it ahead.
		 */
		if (h + PF < w->hi)
		{
			uint32_t	g1 = he[SYM(h + PF)].prev;

			/* a free edge's links may be anything: stay in the array */
			if (g1 < nhe)
				__builtin_prefetch(&he[SYM(g1)]);
		}
#endif
		if (he[h].org == TDC_NIL)
			continue;
		/* a hull edge: the outer face is on the left of h */
		if (mesh->outer == NULL || ((mesh->outer[h >> 6] >> (h & 63)) & 1))
		{
			if (w->cx.skip_checks)
				continue;
			b = he[h].org;
			a = he[SYM(h)].org;
			if (((flag[a] | flag[b]) & SITE_OWN) &&
				!hull_edge_final(&w->cx, mesh->xy + 2 * (size_t) a, mesh->xy + 2 * (size_t) b))
				w->unfinal++;
			continue;
		}
		if (mesh->ntri == 0)
			continue;
		/* the triangle on h's left, from its smallest half-edge (tdc_tri_at, one load less) */
		hh[1] = he[SYM(h)].prev;
		if (hh[1] < h)
			continue;
		hh[2] = he[SYM(hh[1])].prev;
		if (hh[2] < h)
			continue;
		v[0] = he[h].org;
		v[1] = he[hh[1]].org;
		v[2] = he[SYM(hh[1])].org;	/* org of lnext(lnext(h)) = dest of lnext(h) */
		fl = flag[v[0]] | flag[v[1]] | flag[v[2]];
		if (!(fl & SITE_OWN))
			continue;
		/* keep it if its smallest vertex is ours: used when the tile is final */
		if (w->unfinal == 0 && !w->failed)
		{
			int			lo = 0;

			/* all three ours (most): no need to know which is smallest */
			if (!(flag[v[0]] & flag[v[1]] & flag[v[2]] & SITE_OWN))
				for (int k = 1; k < 3; k++)
					if (tdc_key_less(mesh->xy + 2 * (size_t) v[k], mesh->xy + 2 * (size_t) v[lo], 0))
						lo = k;
			if (flag[v[lo]] & SITE_OWN)
			{
				if (w->ntri == w->cap)
				{
					/* a range of k half-edges holds about k / 3 triangles: sized once, never copied */
					size_t		nc = w->cap ? 2 * w->cap : (w->hi - w->lo) / 3 + 64;
					size_t	   *t = realloc(w->tri, sizeof(size_t) * 3 * nc);

					if (t == NULL)
						w->failed = true;
					else
					{
						w->tri = t;
						w->cap = nc;
					}
				}
				if (!w->failed)
				{
					for (int k = 0; k < 3; k++)
						w->tri[3 * w->ntri + k] = mesh->idx[v[k]];
					w->ntri++;
				}
			}
		}
		if (w->cx.skip_checks)
			continue;
		if (fl & SITE_DEEP)
		{
			w->deep++;
			continue;
		}
		hh[0] = (uint32_t) h;
		for (int k = 0; k < 3; k++)
		{
			uint32_t	o = SYM(hh[k]);

			p[k] = mesh->xy + 2 * (size_t) v[k];
			glob[k] = false;
			if ((mesh->outer[o >> 6] >> (o & 63)) & 1)
			{
				const double *q = mesh->xy + 2 * (size_t) v[(k + 1) % 3];

				glob[k] = true;
				for (size_t i = 0; i < spec->nhull && glob[k]; i++)
					glob[k] = left_or_on(p[k], q, spec->hull + 2 * i);
			}
		}
		own[0] = flag[v[0]] & SITE_OWN;
		own[1] = flag[v[1]] & SITE_OWN;
		own[2] = flag[v[2]] & SITE_OWN;
		if (!triangle_final(&w->cx, p, glob, own))
			w->unfinal++;
	}
}

static void *
work_main(void *arg)
{
	tile_work  *w = arg;

	w->fn(w);
	return NULL;
}

/* Run fn over the half-edges in nthreads ranges; threads that cannot start run inline. */
static void
run_parallel(const tdc_mesh_view *mesh, const tile_ctx *cx, const uint8_t *flag,
			 void (*fn) (tile_work *w), tile_work *tw, int nthreads)
{
	size_t		nhe = mesh->nin * 6;
	pthread_t  *th = malloc(sizeof(pthread_t) * nthreads);
	bool	   *started = calloc(nthreads, sizeof(bool));

	for (int i = 0; i < nthreads; i++)
	{
		tw[i].mesh = mesh;
		tw[i].cx = *cx;
		tw[i].flag = flag;
		tw[i].lo = nhe / nthreads * i;
		tw[i].hi = i == nthreads - 1 ? nhe : nhe / nthreads * (i + 1);
		tw[i].fn = fn;
	}
	for (int i = 1; i < nthreads && th && started; i++)
		started[i] = pthread_create(&th[i], NULL, work_main, &tw[i]) == 0;
	fn(&tw[0]);
	for (int i = 1; i < nthreads; i++)
	{
		if (th && started && started[i])
			pthread_join(th[i], NULL);
		else
			fn(&tw[i]);
	}
	free(th);
	free(started);
}

static int
tile_finish(const tdc_mesh_view *mesh, const tdc_tile_spec *spec, tdc_tile_result *res,
			char *err, size_t errlen)
{
	tile_ctx	cx;
	const double *K = spec->known;
	size_t		nin = mesh->nin,
				nhe = nin * 6;
	int64_t    *lab = NULL;
	uint8_t    *flag = NULL;		/* per site: SITE_OWN, SITE_DEEP */
	const double **known_list = NULL;
	tile_work  *tw = NULL;
	tdc_cells	cells = {0};
	int			nthreads;
	bool		covers;
	size_t		nsites_own = 0;

	memset(res, 0, sizeof(*res));
	if (err && errlen)
		err[0] = '\0';
#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); \
		free(lab); free(flag); free(known_list); free(tw); tdc_cells_free(&cells); \
		tdc_tile_result_free(res); return (code); } while (0)

	if (mesh->opt->tolerance > 0)
		FAIL(TDC_EINVAL, "a tiled triangulation cannot use a tolerance: which points it merges depends on all of them");
	if (!(K[0] <= K[2] && K[1] <= K[3]))
		FAIL(TDC_EINVAL, "the known box is empty or not a number");
	if (mesh->n > 0 && (spec->hull == NULL || spec->nhull == 0))
		FAIL(TDC_EINVAL, "no extent polygon given");
	if (mesh->n > 0 && spec->tile == NULL)
		FAIL(TDC_EINVAL, "no tile labels given");

	memset(&cx, 0, sizeof(cx));
	cx.spec = spec;
	cx.want_all = false;
	if (spec->grid)
	{
		if (spec->grid->nx < 1 || spec->grid->ny < 1 ||
			(size_t) spec->grid->nx * spec->grid->ny > UINT32_MAX)
			FAIL(TDC_EINVAL, "the tile grid has no cells or too many");
		if (!tdc_cells_init(&cells, spec->grid))
			FAIL(TDC_ENOMEM, "out of memory");
		cx.cells = &cells;
	}
	cx.B[0] = cx.B[1] = INFINITY;
	cx.B[2] = cx.B[3] = -INFINITY;
	for (size_t i = 0; i < spec->nhull; i++)
		box_union(cx.B, (double[4]) {spec->hull[2 * i], spec->hull[2 * i + 1],
									 spec->hull[2 * i], spec->hull[2 * i + 1]});
	cx.keff[0] = K[0] <= cx.B[0] ? -INFINITY : K[0];
	cx.keff[1] = K[1] <= cx.B[1] ? -INFINITY : K[1];
	cx.keff[2] = K[2] >= cx.B[2] ? INFINITY : K[2];
	cx.keff[3] = K[3] >= cx.B[3] ? INFINITY : K[3];
	memcpy(cx.need, K, sizeof(cx.need));
	cx.known_list = known_list = malloc(sizeof(double *) * (spec->nextra + 1));
	if (cx.known_list == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	cx.known_list[0] = K;
	for (size_t i = 0; i < spec->nextra; i++)
		cx.known_list[i + 1] = spec->extra + 4 * i;
	covers = K[0] <= cx.B[0] && K[1] <= cx.B[1] && K[2] >= cx.B[2] && K[3] >= cx.B[3];

	/*
	 * ownership: the smallest label among a site's copies (the stars of
	 * Caraffa et al. 2019, docs/design/tiles.md)
	 */
	lab = malloc(sizeof(int64_t) * (nin + 1));
	flag = calloc(nin + 1, 1);
	if (lab == NULL || flag == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	for (size_t s = 0; s < nin; s++)
		lab[s] = INT64_MAX;
	/*
	 * In position order: the coordinates, input index and site of a
	 * position are read in sequence, only the label is a random read (a
	 * loop over the input would look up the site of each point, and its
	 * label slot, at random).  Without a tolerance every input point has a
	 * position.
	 */
	for (size_t at = 0; at < nin; at++)
	{
		const double *p = mesh->xy + 2 * at;
		size_t		i = mesh->idx[at];
		uint32_t	s = mesh->site_of[at];

#ifdef __GNUC__
		/* the label is the one random read: fetch it ahead */
		if (at + 64 < nin)
			__builtin_prefetch(&spec->tile[mesh->idx[at + 64]]);
#endif

		if (!(p[0] >= K[0] && p[0] <= K[2] && p[1] >= K[1] && p[1] <= K[3]))
		{
			bool		in_extra = false;

			for (size_t e = 0; e < spec->nextra && !in_extra && spec->tile[i] != spec->self; e++)
			{
				const double *x = spec->extra + 4 * e;

				in_extra = p[0] >= x[0] && p[0] <= x[2] && p[1] >= x[1] && p[1] <= x[3];
			}
			if (!in_extra && cx.cells && spec->tile[i] != spec->self)
				in_extra = tdc_cells_point_known(cx.cells, p);
			if (!in_extra)
				FAIL(TDC_EINVAL, "point %zu (%.17g %.17g) lies outside the known box%s", i, p[0], p[1],
					 spec->tile[i] == spec->self ?  " (an own point must lie in K)" : " and the extra boxes and known cells");
		}
		if (!(p[0] >= cx.B[0] && p[0] <= cx.B[2] && p[1] >= cx.B[1] && p[1] <= cx.B[3]))
			FAIL(TDC_EINVAL, "point %zu (%.17g %.17g) lies outside the extent polygon", i, p[0], p[1]);
		if (cmp_i64(spec->tile[i], lab[s]) < 0)
			lab[s] = spec->tile[i];
	}
	for (size_t s = 0; s < nin; s++)
		if (lab[s] == spec->self)
		{
			flag[s] = SITE_OWN;
			nsites_own++;
		}
	free(lab);
	lab = NULL;
	res->own_sites = nsites_own;
	res->sites = mesh->nsites;
	nthreads = mesh->threads > 0 ? mesh->threads : 1;
	if (nhe < 65536)
		nthreads = 1;
	tw = calloc(nthreads, sizeof(tile_work));
	if (tw == NULL)
		FAIL(TDC_ENOMEM, "out of memory");

	cx.skip_checks = covers;	/* Q = P: every star is final */
	if (covers)
		run_parallel(mesh, &cx, flag, check_range, tw, nthreads);
	else if (mesh->nsites < 2)
	{
		/* a lone site is final only when it is alone in P */
		if (nsites_own > 0)
		{
			cx.want_all = true;
			res->unfinal = nsites_own;
		}
	}
	else
	{
		if (!mark_deep(mesh, &cx, flag, spec->test_weaken == TDC_TILE_WEAKEN_BLOCKS))
			FAIL(TDC_ENOMEM, "out of memory");
		run_parallel(mesh, &cx, flag, check_range, tw, nthreads);
	}

	for (int w = 0; w < nthreads; w++)
	{
		res->unfinal += tw[w].unfinal;
		res->deep += tw[w].deep;
		box_union(cx.need, tw[w].cx.need);
		cx.want_all |= tw[w].cx.want_all;
	}
	if (cx.cells)
	{
		tdc_cell_list *lists = malloc(sizeof(tdc_cell_list) * nthreads);
		bool		ok = lists != NULL;

		for (int w = 0; w < nthreads; w++)
		{
			if (lists)
				lists[w] = tw[w].cx.cl;
			else
				free(tw[w].cx.cl.v);
			memset(&tw[w].cx.cl, 0, sizeof(tw[w].cx.cl));
		}
		if (ok && res->unfinal > 0)
			ok = tdc_cells_merge(&cells, lists, nthreads, &res->need_cells, &res->nneed_cells);
		else
			for (int w = 0; lists && w < nthreads; w++)
				free(lists[w].v);
		free(lists);
		tdc_cells_free(&cells);
		if (!ok)
		{
			for (int w = 0; w < nthreads; w++)
				free(tw[w].tri);
			FAIL(TDC_ENOMEM, "out of memory");
		}
	}
	if (res->unfinal > 0)
	{
		if (cx.want_all || (cx.need[0] >= K[0] && cx.need[1] >= K[1] &&
							cx.need[2] <= K[2] && cx.need[3] <= K[3]))
			box_union(cx.need, cx.B);
		memcpy(res->need, cx.need, sizeof(res->need));
		res->final = 0;
		for (int w = 0; w < nthreads; w++)
			free(tw[w].tri);
		free(flag);
		free(known_list);
		free(tw);
		return TDC_OK;
	}

	/* every own star is final: the triangles whose smallest vertex we own */
	res->final = 1;
	for (int w = 0; w < nthreads; w++)
	{
		if (tw[w].failed)
		{
			for (int u = 0; u < nthreads; u++)
				free(tw[u].tri);
			FAIL(TDC_ENOMEM, "out of memory");
		}
		res->ntri += tw[w].ntri;
	}
	/* the first range's array, grown, takes the others: one copy less */
	res->tri = realloc(tw[0].tri, sizeof(size_t) * 3 * res->ntri + 1);
	if (res->tri == NULL)
	{
		for (int u = 0; u < nthreads; u++)
			free(tw[u].tri);
		FAIL(TDC_ENOMEM, "out of memory");
	}
	for (size_t w = 1, at = tw[0].ntri; w < (size_t) nthreads; w++)
	{
		if (tw[w].ntri > 0)
			memcpy(res->tri + 3 * at, tw[w].tri, sizeof(size_t) * 3 * tw[w].ntri);
		at += tw[w].ntri;
		free(tw[w].tri);
	}
	free(flag);
	free(known_list);
	free(tw);
	return TDC_OK;
#undef FAIL
}

int
tdc_tile_finish(const tdc_job *job, const tdc_tile_spec *spec, tdc_tile_result *res,
				char *err, size_t errlen)
{
	tdc_mesh_view mesh;

	tdc_job_view(job, &mesh);
	return tile_finish(&mesh, spec, res, err, errlen);
}

int
tdc_tile_triangulate(const double *xy, size_t n, const tdc_tile_spec *spec,
					 const tdc_options *opt, tdc_tile_result *res,
					 char *err, size_t errlen)
{
	tdc_job    *job;
	int			rc;

	memset(res, 0, sizeof(*res));
	rc = tdc_triangulate(xy, n, opt, &job, err, errlen);
	if (rc == TDC_OK)
		rc = tdc_tile_finish(job, spec, res, err, errlen);
	else if (job && err && errlen)
		snprintf(err, errlen, "%s", tdc_job_error(job));
	tdc_job_free(job);
	return rc;
}

void
tdc_tile_result_free(tdc_tile_result *res)
{
	if (res == NULL)
		return;
	free(res->tri);
	res->tri = NULL;
	res->ntri = 0;
	free(res->need_cells);
	res->need_cells = NULL;
	res->nneed_cells = 0;
}
