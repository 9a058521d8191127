/*
 * tin_drape.c
 *		Draping lines on a TIN: every vertex gets a height, and with the
 *		linear method every segment is split where it crosses a triangle
 *		edge, so that the draped line follows the surface exactly.
 *
 * The walk along a segment p -> q (both ends inside the hull, so the whole
 * segment is: the hull is convex) is a straight-line walk through the
 * triangles it meets, with every decision an exact orientation:
 *
 *	- in a triangle (v0, v1, v2), counter-clockwise: if q is in it (closed),
 *	  the segment ends there.  Otherwise, with s_i the side of v_i from the
 *	  line p -> q, the segment leaves through edge v_i -> v_i+1 when
 *	  s_i < 0 < s_i+1 (v_i right of the line, v_i+1 left of it), or through
 *	  corner v_i when s_i = 0, s_i+1 > 0 and s_i-1 < 0.  The edge it came in
 *	  by, and a corner behind it, have the opposite signs, so the rule never
 *	  turns back.
 *	- at a site v (reached, or where p is): along an edge v -> w when w is
 *	  on the line ahead of v (the segment runs on the edge, and w is the next
 *	  crossing unless q comes first); otherwise into the triangle (v, w, x)
 *	  whose corner at v holds the direction of q strictly (v -> w right of
 *	  it, v -> x left), through its edge w -> x or to q inside it.
 *	- p strictly inside an edge a -> b goes into the triangle on q's side,
 *	  or along the edge when q is on its line.
 *
 * Every crossing is an output vertex: a site is itself, with its height; a
 * proper crossing of edge (a, b), a the end first in (x, y) order, is
 * a + u (b - a) with u = o_a / (o_a - o_b), o the signed areas of p, q and
 * each end in double, clamped to [0, 1], and its height is
 * z_a + u (z_b - z_a): linear along the edge, which is where the planes of
 * the two triangles beside it meet.  Computed from the edge and the line,
 * not from the walk, the crossing is the same from either side.  Its
 * parameter t along p -> q (for the host's M) is the same construction
 * with the roles of the two segments swapped.  A segment whose ends are not
 * both inside the hull gets no crossing; its ends get what the method gives
 * them outside (the host decides whether that is an error).
 *
 * max_edge.  Every vertex gets its value by the mask's rule (tin_interp.c):
 * an input vertex through tin_value_at, a crossing of an edge when the edge
 * is kept from one side, a site always.  The pieces between them matter
 * too, since the draped line is linear across the triangle it passes: a
 * piece through a dropped triangle, or along an edge no kept triangle
 * holds, has no value though both its ends may, and the vertex it starts
 * from is marked (gap).  Without the option the walk tests nothing.
 *
 * The input vertices are shared out among the pool's threads in ranges of
 * 4096, whatever chains they belong to (a long line is cut into several
 * ranges); each range writes its own list, charged against max_memory as
 * it grows, and the lists are joined in order at the end: the result does
 * not depend on the thread count.  Cancel is polled every 256 vertices and
 * every 4096 steps of a walk.
 */
#include <stdio.h>
#include <string.h>

#include "tin_int.h"

#define VERTICES_PER_TASK	4096

typedef struct drape_list
{
	tdc_drape_vertex *v;
	size_t		n,
				cap;
} drape_list;

typedef struct drape_op
{
	tdc_interp_spec spec;
	const double *xy;
	const size_t *chain_end;
	size_t		nchains;
	size_t		ntask;
	drape_list *lists;			/* per task */
	size_t	   *chain_off;		/* per chain: its first output vertex */
	tin_scratch *scratch;
	int			nscratch;
	size_t		charged;

	tdc_drape_vertex *v;		/* the result */
	size_t		nv;
} drape_op;

typedef struct walker
{
	tdc_tin    *tin;
	drape_list *out;
	const double *p,
			   *q;
	uint32_t	src;
	size_t		steps;
	double		max_edge;		/* > 0: mark pieces and crossings it drops */
} walker;

static inline size_t
chain_start(const drape_op *op, size_t c)
{
	return c == 0 ? 0 : op->chain_end[c - 1];
}

static bool
push(walker *w, double x, double y, double z, double t, int valid, bool inside)
{
	drape_list *o = w->out;

	if (o->n == o->cap)
	{
		size_t		cap = o->cap ? 2 * o->cap : 256;
		tdc_drape_vertex *v;

		if (!tin_charge(w->tin, (cap - o->cap) * sizeof(tdc_drape_vertex), "the draped vertices"))
			return false;
		v = realloc(o->v, cap * sizeof(tdc_drape_vertex));
		if (v == NULL)
		{
			tin_fail(w->tin, TDC_ENOMEM, "out of memory for the draped vertices");
			return false;
		}
		/* the new half in one call, not a page fault a page */
		tdc_prefault(v + o->cap, (cap - o->cap) * sizeof(tdc_drape_vertex));
		o->v = v;
		o->cap = cap;
	}
	o->v[o->n].x = x;
	o->v[o->n].y = y;
	o->v[o->n].z = z;
	o->v[o->n].t = t;
	o->v[o->n].src = w->src;
	o->v[o->n].valid = (uint8_t) valid;
	o->v[o->n].inside = inside;
	o->v[o->n].gap = 0;
	o->v[o->n].pad = 0;
	o->n++;
	return true;
}

/* The signed area of (a, b, c) in double: a value, not just a sign. */
static inline double
area(const double *a, const double *b, const double *c)
{
	return (a[0] - c[0]) * (b[1] - c[1]) - (a[1] - c[1]) * (b[0] - c[0]);
}

static inline double
clamp01(double u)
{
	return !(u > 0) ? 0 : u > 1 ? 1 : u;
}

/* max_edge: the piece from the last vertex pushed on has no value. */
static inline void
mark_gap(walker *w)
{
	w->out->v[w->out->n - 1].gap = 1;
}

/* max_edge: is a point strictly inside the edge h (of a triangle) kept? */
static bool
edge_kept(const walker *w, uint32_t h)
{
	tin_loc		l = {LOC_EDGE, h, tin_org(w->tin, h), tin_dest(w->tin, h)};

	return tin_loc_kept(w->tin, &l, w->max_edge);
}

/* Site v as a crossing of p -> q. */
static bool
push_site(walker *w, uint32_t v)
{
	const double *pv = tin_pt(w->tin, v),
			   *p = w->p,
			   *q = w->q;
	double		dx = q[0] - p[0],
				dy = q[1] - p[1],
				t = ((pv[0] - p[0]) * dx + (pv[1] - p[1]) * dy) / (dx * dx + dy * dy);

	return push(w, pv[0], pv[1], w->tin->sz[v], clamp01(t), 1, true);
}

/* The proper crossing of p -> q with edge h (x-y). */
static bool
push_crossing(walker *w, uint32_t h)
{
	const tdc_tin *tin = w->tin;
	const double *a,
			   *b;
	uint32_t	x = tin_org(tin, h),
				y = tin_dest(tin, h);
	double		oa,
				ob,
				u,
				sp,
				sq,
				t;
	int			valid = w->max_edge > 0 ? edge_kept(w, h) : 1;

	if (tdc_lex_less(tin_pt(tin, y), tin_pt(tin, x)))
	{
		uint32_t	s = x;

		x = y;
		y = s;
	}
	a = tin_pt(tin, x);
	b = tin_pt(tin, y);
	oa = area(w->p, w->q, a);
	ob = area(w->p, w->q, b);
	u = clamp01(oa / (oa - ob));
	sp = area(a, b, w->p);
	sq = area(a, b, w->q);
	t = clamp01(sp / (sp - sq));
	return push(w, a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1]),
				tin->sz[x] + u * (tin->sz[y] - tin->sz[x]), t, valid, true);
}

/* Is w ahead of v on the line p -> q (both on it)? */
static inline bool
ahead(const walker *wk, const double *v, const double *w)
{
	return tdc_lex_less(wk->p, wk->q) ? tdc_lex_less(v, w) : tdc_lex_less(w, v);
}

/* Is q in the closed triangle left of h? */
static bool
q_in_face(const tdc_tin *tin, uint32_t h, const double *q)
{
	for (int k = 0; k < 3; k++, h = tin_lnext(tin, h))
		if (tdc_orient2d(tin_pt(tin, tin_org(tin, h)), tin_pt(tin, tin_dest(tin, h)), q) < 0)
			return false;
	return true;
}

static bool walk_vertex(walker *w, uint32_t v);

/*
 * The walk found no way on, which the exact predicates rule out for a
 * segment inside the hull: a bug, reported as an error rather than a
 * line with crossings missing.
 */
static bool
lost(walker *w)
{
	char		msg[200];

	snprintf(msg, sizeof(msg), "the walk along (%.17g %.17g, %.17g %.17g) lost its way",
			 w->p[0], w->p[1], w->q[0], w->q[1]);
	tin_fail(w->tin, TDC_EINVAL, msg);
	return false;
}

/*
 * In the triangle left of h: to q, or out through an edge or a corner.
 * Returns false on failure or cancel.
 */
static bool
walk_face(walker *w, uint32_t h)
{
	tdc_tin    *tin = w->tin;

	for (;;)
	{
		uint32_t	e[3],
					v[3];
		double		s[3];
		bool		moved = false;

		/* the segment runs through this triangle's interior */
		if (w->max_edge > 0 && !tin_face_kept(tin, h, w->max_edge))
			mark_gap(w);
		if (q_in_face(tin, h, w->q))
			return true;
		e[0] = h;
		e[1] = tin_lnext(tin, e[0]);
		e[2] = tin_lnext(tin, e[1]);
		for (int k = 0; k < 3; k++)
		{
			v[k] = tin_org(tin, e[k]);
			s[k] = tdc_orient2d(w->p, w->q, tin_pt(tin, v[k]));
		}
		for (int k = 0; k < 3 && !moved; k++)
		{
			int			n = (k + 1) % 3,
						b = (k + 2) % 3;

			if (s[k] < 0 && s[n] > 0)
			{
				if (!push_crossing(w, e[k]))
					return false;
				h = e[k] ^ 1u;
				moved = true;
			}
			else if (s[k] == 0 && s[n] > 0 && s[b] < 0)
			{
				if (!push_site(w, v[k]))
					return false;
				return walk_vertex(w, v[k]);
			}
		}
		if (!moved || tin_outer(tin, h))
			return lost(w);
		if ((++w->steps & 4095) == 0 && tin_cancelled(tin))
			return false;
	}
}

/* From site v (on the segment, before q): onwards. */
static bool
walk_vertex(walker *w, uint32_t v)
{
	tdc_tin    *tin = w->tin;

	for (;;)
	{
		const double *pv = tin_pt(tin, v);
		uint32_t	h = atomic_load_explicit(&tin->site_he[v], memory_order_relaxed),
					start = h,
					next_v = TDC_NIL,
					face = TDC_NIL;

		if (pv[0] == w->q[0] && pv[1] == w->q[1])
			return true;
		do
		{
			uint32_t	wv = tin_dest(tin, h);
			const double *pw = tin_pt(tin, wv);
			double		ow = tdc_orient2d(pv, pw, w->q);

			if (ow == 0 && ahead(w, pv, pw))
			{
				next_v = wv;
				break;
			}
			if (!tin_outer(tin, h) && ow > 0)
			{
				uint32_t	x = tin_dest(tin, tin_onext(tin, h));

				if (tdc_orient2d(pv, tin_pt(tin, x), w->q) < 0)
				{
					face = h;
					break;
				}
			}
			h = tin_onext(tin, h);
		} while (h != start);

		if (next_v != TDC_NIL)
		{
			const double *pw = tin_pt(tin, next_v);

			/* along the edge h = v -> next_v */
			if (w->max_edge > 0 && !edge_kept(w, h))
				mark_gap(w);
			/* q on the edge, or at its end: the segment ends there */
			if (!ahead(w, pw, w->q))
				return true;
			if (!push_site(w, next_v))
				return false;
			v = next_v;
		}
		else if (face != TDC_NIL)
		{
			uint32_t	wx = tin_lnext(tin, face);	/* the edge w -> x facing v */

			if (w->max_edge > 0 && !tin_face_kept(tin, face, w->max_edge))
				mark_gap(w);
			if (tdc_orient2d(tin_pt(tin, tin_org(tin, wx)), tin_pt(tin, tin_dest(tin, wx)),
							 w->q) >= 0)
				return true;	/* q in the triangle */
			if (!push_crossing(w, wx))
				return false;
			return walk_face(w, wx ^ 1u);
		}
		else
			return lost(w);
		if ((++w->steps & 4095) == 0 && tin_cancelled(tin))
			return false;
	}
}

/*
 * Collinear sites, max_edge: is the piece a-b of the line (no site strictly
 * between) on a segment between neighbouring sites longer than it?  The
 * segment starts at the last site not after the piece's first end.
 */
static bool
line_piece_long(const walker *w, const double *a, const double *b)
{
	const tdc_tin *tin = w->tin;
	const double *m = tdc_lex_less(a, b) ? a : b;
	size_t		lo = 0,
				hi = tin->nline - 1;

	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo + 1) / 2;

		if (tdc_lex_less(m, tin_pt(tin, tin->line[mid])))
			hi = mid - 1;
		else
			lo = mid;
	}
	return lo + 1 < tin->nline && tin_edge_long(tin, tin->line[lo], tin->line[lo + 1], w->max_edge);
}

/* Collinear sites: the sites strictly between p and q. */
static bool
walk_line(walker *w)
{
	const tdc_tin *tin = w->tin;
	bool		fwd = tdc_lex_less(w->p, w->q);
	const double *from = w->p;

	for (size_t k = 0; k < tin->nline; k++)
	{
		size_t		i = fwd ? k : tin->nline - 1 - k;
		const double *s = tin_pt(tin, tin->line[i]);

		if (ahead(w, w->p, s) && ahead(w, s, w->q))
		{
			if (w->max_edge > 0 && line_piece_long(w, from, s))
				mark_gap(w);
			if (!push_site(w, tin->line[i]))
				return false;
			from = s;
		}
	}
	if (w->max_edge > 0 && line_piece_long(w, from, w->q))
		mark_gap(w);
	return true;
}

/* The crossings of segment p -> q, p located at lp. */
static bool
walk_segment(walker *w, const tin_loc *lp)
{
	const tdc_tin *tin = w->tin;

	if (w->p[0] == w->q[0] && w->p[1] == w->q[1])
		return true;
	if (tin->ntri == 0)
		return walk_line(w);
	switch (lp->kind)
	{
		case LOC_VERTEX:
			return walk_vertex(w, lp->a);
		case LOC_FACE:
			return walk_face(w, lp->h);
		case LOC_EDGE:
			{
				const double *a = tin_pt(tin, lp->a),
						   *b = tin_pt(tin, lp->b);
				double		o = tdc_orient2d(a, b, w->q);

				if (o == 0)
				{
					/* along the edge: to its end ahead, unless q comes first */
					uint32_t	e = ahead(w, a, b) ? lp->b : lp->a;

					if (w->max_edge > 0 && !tin_loc_kept(tin, lp, w->max_edge))
						mark_gap(w);
					if (!ahead(w, tin_pt(tin, e), w->q))
						return true;
					if (!push_site(w, e))
						return false;
					return walk_vertex(w, e);
				}
				return walk_face(w, o > 0 ? lp->h : lp->h ^ 1u);
			}
		default:
			return true;
	}
}

static bool
loc_inside(const tin_loc *l)
{
	return l->kind == LOC_FACE || l->kind == LOC_EDGE || l->kind == LOC_VERTEX;
}

/*
 * Task k: the input vertices [k V, (k + 1) V), V = VERTICES_PER_TASK, of
 * whatever chains they belong to, and the segments that start at them (a
 * segment's far end is valued again by the next task if it lies there:
 * the same value, which depends on the point alone).
 */
static void
drape_task(void *arg, size_t k, int worker)
{
	tdc_tin    *tin = arg;
	drape_op   *op = tin->op_state;
	tin_scratch *sc = &op->scratch[worker];
	walker		w = {tin, &op->lists[k], NULL, NULL, 0, 0, op->spec.max_edge};
	uint32_t	hint = TDC_NIL;
	size_t		nv = op->nchains > 0 ? op->chain_end[op->nchains - 1] : 0,
				lo = k * VERTICES_PER_TASK,
				hi = lo + VERTICES_PER_TASK < nv ? lo + VERTICES_PER_TASK : nv,
				c,
				a = 0,
				b = op->nchains;

	/* the chain of vertex lo: the first whose end is past it */
	while (a < b)
	{
		size_t		m = a + (b - a) / 2;

		if (op->chain_end[m] <= lo)
			a = m + 1;
		else
			b = m;
	}
	for (c = a; c < op->nchains && chain_start(op, c) < hi; c++)
	{
		size_t		cs = chain_start(op, c),
					ce = op->chain_end[c],
					from = cs > lo ? cs : lo,
					to = ce < hi ? ce : hi;
		tin_loc		here,
					there;
		double		z;
		int			rc;

		if (from >= to)
			continue;
		rc = tin_value_at(tin, &op->spec, sc, op->xy + 2 * from, &hint, &z, &here);
		for (size_t i = from; i < to; i++)
		{
			const double *p = op->xy + 2 * i;

			if (rc < 0)
			{
				tin_point_fail(tin, rc, p);
				return;
			}
			if ((i & 255) == 0 && tin_cancelled(tin))
				return;
			if (!tin_scratch_charge(tin, sc))
				return;
			w.src = (uint32_t) i;
			if (!push(&w, p[0], p[1], z, 0, rc, loc_inside(&here)))
				return;
			if (i + 1 == ce)
				break;
			/* the next vertex's value, and the crossings on the way there */
			{
				uint32_t	h2 = hint;
				double		z2;
				int			rc2 = tin_value_at(tin, &op->spec, sc, p + 2, &h2, &z2, &there);

				if (rc2 >= 0 && op->spec.method == TDC_INTERP_LINEAR &&
					loc_inside(&here) && loc_inside(&there))
				{
					w.p = p;
					w.q = p + 2;
					if (!walk_segment(&w, &here))
						return;
				}
				hint = h2;
				here = there;
				z = z2;
				rc = rc2;
			}
		}
	}
}

static int
drape_run(tdc_tin *tin)
{
	drape_op   *op = tin->op_state;
	size_t		total = 0,
				c = 0;

	tdc_pool_for(tin_pool(tin), op->ntask, drape_task, tin);
	if (tin_cancelled(tin))
		return TDC_ECANCELED;
	for (size_t k = 0; k < op->ntask; k++)
		total += op->lists[k].n;
	if (!tin_charge(tin, total * sizeof(tdc_drape_vertex), "the draped vertices"))
		return TDC_EMEMLIMIT;
	op->charged += total * sizeof(tdc_drape_vertex);
	op->v = tdc_big_alloc_uninit(tin->cache, total * sizeof(tdc_drape_vertex) + 8);
	if (op->v == NULL)
	{
		tin_fail(tin, TDC_ENOMEM, "out of memory for the draped vertices");
		return TDC_ENOMEM;
	}
	tdc_prefault(op->v, total * sizeof(tdc_drape_vertex));
	for (size_t k = 0; k < op->ntask; k++)
	{
		drape_list *o = &op->lists[k];

		if (o->n > 0)
			memcpy(op->v + op->nv, o->v, o->n * sizeof(tdc_drape_vertex));
		op->nv += o->n;
		tin_uncharge(tin, o->cap * sizeof(tdc_drape_vertex));
		free(o->v);
		memset(o, 0, sizeof(*o));
	}
	/* each chain starts at its first input vertex; an empty one where the next starts */
	for (size_t i = 0; i < op->nv; i++)
	{
		if (op->v[i].t != 0)
			continue;
		while (c < op->nchains && op->chain_end[c] <= op->v[i].src)
			c++;
		if (c < op->nchains && op->v[i].src == chain_start(op, c))
			op->chain_off[c] = i;
	}
	op->chain_off[op->nchains] = op->nv;
	for (size_t k = op->nchains; k-- > 0;)
		if (op->chain_end[k] == chain_start(op, k))
			op->chain_off[k] = op->chain_off[k + 1];
	return TDC_OK;
}

static void
drape_free(tdc_tin *tin)
{
	drape_op   *op = tin->op_state;

	if (op == NULL)
		return;
	if (op->lists)
		for (size_t k = 0; k < op->ntask; k++)
		{
			tin_uncharge(tin, op->lists[k].cap * sizeof(tdc_drape_vertex));
			free(op->lists[k].v);
		}
	for (int i = 0; i < op->nscratch; i++)
		tin_scratch_release(tin, &op->scratch[i]);
	free(op->scratch);
	free(op->lists);
	free(op->chain_off);
	tdc_big_free(tin->cache, op->v);
	tin_uncharge(tin, op->charged);
	free(op);
	tin->op_state = NULL;
	tin->op_free = NULL;
}

int
tdc_tin_drape_start(tdc_tin *tin, const tdc_interp_spec *spec, const double *xy,
					const size_t *chain_end, size_t nchains, char *err, size_t errlen)
{
	drape_op   *op;
	size_t		nv = nchains > 0 ? chain_end[nchains - 1] : 0;

#define FAIL(code, ...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return (code); } while (0)
	if (!tin_spec_ok(tin, spec, err, errlen))
		return TDC_EINVAL;
	if (nv > UINT32_MAX)
		FAIL(TDC_ETOOBIG, "%zu vertices to drape exceed the limit of %u", nv, UINT32_MAX);
	for (size_t c = 1; c < nchains; c++)
		if (chain_end[c] < chain_end[c - 1])
			FAIL(TDC_EINVAL, "chain %zu ends before it starts", c);
	if (nv > 0 && xy == NULL)
		FAIL(TDC_EINVAL, "no vertices given");
	op = calloc(1, sizeof(drape_op));
	if (op == NULL)
		FAIL(TDC_ENOMEM, "out of memory");
	op->spec = *spec;
	op->xy = xy;
	op->chain_end = chain_end;
	op->nchains = nchains;
	op->chain_off = malloc((nchains + 1) * sizeof(size_t));
	op->nscratch = tin->threads + 1;
	op->scratch = calloc(op->nscratch, sizeof(tin_scratch));
	if (!op->chain_off || !op->scratch)
	{
		free(op->chain_off);
		free(op->scratch);
		free(op);
		FAIL(TDC_ENOMEM, "out of memory");
	}
	/* ranges of VERTICES_PER_TASK input vertices, a long chain cut into several */
	op->ntask = (nv + VERTICES_PER_TASK - 1) / VERTICES_PER_TASK;
	op->lists = calloc(op->ntask + 1, sizeof(drape_list));
	if (op->lists == NULL)
	{
		free(op->chain_off);
		free(op->scratch);
		free(op);
		FAIL(TDC_ENOMEM, "out of memory");
	}
	op->chain_off[nchains] = 0;
#undef FAIL
	return tin_op_start(tin, drape_run, op, drape_free,
						tin->nsite_ids <= TDC_INLINE_MAX && nv <= VERTICES_PER_TASK, err, errlen);
}

size_t
tdc_tin_drape_result(const tdc_tin *tin, const tdc_drape_vertex **v, const size_t **chain_off)
{
	const drape_op *op = tin->op_state;

	if (op == NULL || tin->op != drape_run || tdc_runner_wait((tdc_runner *) &tin->run, 0) != TDC_OK)
	{
		*v = NULL;
		*chain_off = NULL;
		return 0;
	}
	*v = op->v;
	*chain_off = op->chain_off;
	return op->nv;
}
