/*
 * tolerance.c
 *		The optional tolerance filter.  (Exact duplicates are removed inside
 *		the subsets, see leaf.c.)
 *
 * The rule (options.tolerance = t > 0): take the points in lexicographic
 * (x, y) order, ties by input index; keep a point unless some already kept
 * site q has (px - qx)^2 + (py - qy)^2 < t^2, evaluated exactly; a dropped
 * point maps to the nearest such q, the earliest kept on exact ties.  So no
 * two kept sites are closer than t and every dropped point lies closer than
 * t to its site, for every input: a rounded rule would depend on where the
 * data lies.  The rule is sequential, so it runs once before the
 * subdivision.  t is clamped to [2^-252, 2^202], which changes no decision
 * for the inputs the driver accepts; the distances are decided in doubles
 * with proven bounds, and exactly (tdc_sqdist_cmp_exact) in between.  The
 * candidates come from a sweep over x with the active kept sites in a bit
 * set by y rank, never missing a site within t and examining at most 7
 * candidates and one failing test per direction for a point: O(n log n)
 * for every input.  The order comes from an LSD radix sort, by y then x,
 * whose stable passes give the ties and the ranks for free; cancel is
 * polled by work done, not by points.
 *
 * The design note, with the clamp, the error bounds, the sweep's proof and
 * the sort, is docs/design/tolerance.md.
 */
#include <stdlib.h>
#include <string.h>

#include "job_int.h"

/*
 * Units of work between two polls of the cancel flag.  A unit is a record
 * moved or a bit-set step (nanoseconds) or a candidate examined (at worst an
 * exact comparison, well under a microsecond), so polls are at most a few
 * milliseconds apart and usually a small fraction of one.
 */
#define TOL_POLL_WORK	(1u << 14)

/* Records mapped in per tdc_prefault call: a few ms, between cancel polls. */
#define TOL_PREFAULT_RECS	((size_t) 1 << 18)

/* The tolerance clamp (docs/design/tolerance.md). */
#define TOL_CLAMP_MIN	0x1p-252
#define TOL_CLAMP_MAX	0x1p202

/* Relative slack of the filters: 2^-49 = 16u. */
#define TOL_FILTER_SLACK	0x1p-49

typedef struct rec
{
	double		x,
				y;
	uint32_t	i;				/* input index */
	uint32_t	yr;				/* rank in (y, i) order, set by sort_recs */
} rec;

typedef struct tol_poll
{
	unsigned	work;
	const atomic_int *cancel;
} tol_poll;

/* Count one unit of work; true when the job was cancelled. */
static inline bool
poll_cancelled(tol_poll *p)
{
	if (++p->work < TOL_POLL_WORK)
		return false;
	p->work = 0;
	return atomic_load_explicit(p->cancel, memory_order_relaxed) != 0;
}

/* --- sort --- */

#define RADIX_BITS		11
#define RADIX_SIZE		(1 << RADIX_BITS)
#define RADIX_DIGITS	6		/* ceil(64 / RADIX_BITS) */

/* Unsigned key in the order of the double's value; -0 and +0 get one key. */
static inline uint64_t
order_key(double v)
{
	uint64_t	b;

	if (v == 0)
		v = 0;
	memcpy(&b, &v, sizeof(b));
	return (b >> 63) ? ~b : b | ((uint64_t) 1 << 63);
}

static inline unsigned
digit_of(const rec *r, int coord, int d)
{
	return (unsigned) (order_key(coord ? r->y : r->x) >> (d * RADIX_BITS)) & (RADIX_SIZE - 1);
}

/*
 * Sort r[0..n) (in input-index order on entry) into (x, y, i) order, setting
 * every yr on the way; tmp has room for n records.  *out is whichever of r
 * and tmp holds the result.  Returns false if cancelled (or out of memory,
 * then *oom is set).
 */
static bool
sort_recs(rec *r, rec *tmp, size_t n, rec **out, tol_poll *pl, bool *oom)
{
	size_t	   *hist = calloc((size_t) 2 * RADIX_DIGITS * RADIX_SIZE, sizeof(size_t));
	rec		   *src = r,
			   *dst = tmp;

	*oom = hist == NULL;
	if (hist == NULL)
		return false;

	/* all histograms in one read of the data */
	for (size_t k = 0; k < n; k++)
	{
		uint64_t	kx = order_key(r[k].x),
					ky = order_key(r[k].y);

		for (int d = 0; d < RADIX_DIGITS; d++)
		{
			hist[d * RADIX_SIZE + ((kx >> (d * RADIX_BITS)) & (RADIX_SIZE - 1))]++;
			hist[(RADIX_DIGITS + d) * RADIX_SIZE + ((ky >> (d * RADIX_BITS)) & (RADIX_SIZE - 1))]++;
		}
		if (poll_cancelled(pl))
			goto cancelled;
	}

	/* y digits first (least significant first), then x */
	for (int c = 1; c >= 0; c--)
	{
		for (int d = 0; d < RADIX_DIGITS; d++)
		{
			size_t	   *pos = hist + (c * RADIX_DIGITS + d) * RADIX_SIZE,
						sum = 0;
			rec		   *t;

			if (pos[digit_of(&src[0], c, d)] == n)
				continue;		/* one digit value: the pass would copy */
			for (int b = 0; b < RADIX_SIZE; b++)
			{
				size_t		cnt = pos[b];

				pos[b] = sum;
				sum += cnt;
			}
			for (size_t k = 0; k < n; k++)
			{
				dst[pos[digit_of(&src[k], c, d)]++] = src[k];
				if (poll_cancelled(pl))
					goto cancelled;
			}
			t = src, src = dst, dst = t;
		}
		if (c == 1)
			for (size_t k = 0; k < n; k++)
			{
				src[k].yr = (uint32_t) k;
				if (poll_cancelled(pl))
					goto cancelled;
			}
	}
	free(hist);
	*out = src;
	return true;

cancelled:
	free(hist);
	return false;
}

/* --- the set of active kept sites, by rank --- */

/* 64^6 = 2^36 ranks: more than TDC_MAX_POINTS */
#define RS_LEVELS	6

/*
 * A bit per rank (w[0]), and above it a bit per nonzero word of the level
 * below, up to a single word (w[top]): successor and predecessor queries in
 * O(levels), a few machine words each.
 */
typedef struct rankset
{
	uint64_t   *w[RS_LEVELS];
	size_t		nw[RS_LEVELS];
	int			top;
	uint64_t   *mem;
} rankset;

static bool
rankset_init(rankset *s, size_t n, tdc_cache *cache)
{
	size_t		m = n,
				total = 0;
	int			l = 0;

	do
	{
		s->nw[l] = (m + 63) / 64;
		total += s->nw[l];
		m = s->nw[l];
		l++;
	} while (m > 1 && l < RS_LEVELS);
	s->top = l - 1;
	s->mem = tdc_big_alloc(cache, total * sizeof(uint64_t));	/* zeroed */
	if (s->mem == NULL)
		return false;
	total = 0;
	for (l = 0; l <= s->top; l++)
	{
		s->w[l] = s->mem + total;
		total += s->nw[l];
	}
	return true;
}

static inline void
rankset_add(rankset *s, uint64_t i)
{
	for (int l = 0; l <= s->top; l++)
	{
		uint64_t	old = s->w[l][i >> 6];

		s->w[l][i >> 6] = old | (uint64_t) 1 << (i & 63);
		if (old != 0)
			break;
		i >>= 6;
	}
}

static inline void
rankset_remove(rankset *s, uint64_t i)
{
	for (int l = 0; l <= s->top; l++)
	{
		if ((s->w[l][i >> 6] &= ~((uint64_t) 1 << (i & 63))) != 0)
			break;
		i >>= 6;
	}
}

/* Smallest member >= i, or -1. */
static inline int64_t
rankset_next(const rankset *s, int64_t i)
{
	int			l = 0;

	for (;;)
	{
		size_t		wi = (size_t) i >> 6;
		uint64_t	m;

		if (wi >= s->nw[l])
			return -1;
		m = s->w[l][wi] & (~(uint64_t) 0 << (i & 63));
		if (m != 0)
		{
			i = (int64_t) (wi << 6) + __builtin_ctzll(m);
			break;
		}
		if (l == s->top)
			return -1;
		i = (int64_t) wi + 1;
		l++;
	}
	while (l > 0)
	{
		l--;
		i = (i << 6) + __builtin_ctzll(s->w[l][i]);
	}
	return i;
}

/* Largest member <= i (i < n), or -1. */
static inline int64_t
rankset_prev(const rankset *s, int64_t i)
{
	int			l = 0;

	if (i < 0)
		return -1;
	for (;;)
	{
		size_t		wi = (size_t) i >> 6;
		uint64_t	m = s->w[l][wi] & (~(uint64_t) 0 >> (63 - (i & 63)));

		if (m != 0)
		{
			i = (int64_t) (wi << 6) + 63 - __builtin_clzll(m);
			break;
		}
		if (l == s->top || wi == 0)
			return -1;
		i = (int64_t) wi - 1;
		l++;
	}
	while (l > 0)
	{
		l--;
		i = (i << 6) + 63 - __builtin_clzll(s->w[l][i]);
	}
	return i;
}

/* --- exact distance decisions (the bounds: docs/design/tolerance.md) --- */

typedef struct tol_ctx
{
	double		t;				/* the clamped tolerance t' */
	double		lo,
				hi;				/* d < lo: D < t'^2; d > hi: D > t'^2 */
	double		tpt[2],
				origin[2];		/* |tpt - origin| = t' for the exact test */
} tol_ctx;

static inline double
sqdist(const double *p, const double *q)
{
	double		ex = p[0] - q[0],
				ey = p[1] - q[1];

	return ex * ex + ey * ey;
}

/* Is D(p, q) < t'^2 exactly?  d = sqdist(p, q). */
static inline bool
within(const tol_ctx *c, const double *p, const double *q, double d)
{
	if (d < c->lo)
		return true;
	if (d > c->hi)
		return false;
	return tdc_sqdist_cmp_exact(p, q, c->tpt, c->origin) < 0;
}

/* Exact sign of D(p, a) - D(p, b); da, db their sqdist. */
static inline int
closer(const double *p, const double *a, double da, const double *b, double db)
{
	if (da < db * (1 - TOL_FILTER_SLACK))
		return -1;
	if (db < da * (1 - TOL_FILTER_SLACK))
		return 1;
	return tdc_sqdist_cmp_exact(p, a, p, b);
}

/* --- the pass --- */

/*
 * Apply the tolerance rule to all input points, leaving the survivors in
 * xy/idx (nin of them, in (x, y) order) and tol_to[] for the dropped ones.
 * On entry xy/idx hold the input in input order (idx[k] == k; the sort's
 * tie rule relies on it).  Returns TDC_ENOMEM or 0; on cancel returns 0
 * with nin unchanged and xy/idx partly overwritten (the driver then stops).
 */
int
tdc_tolerance_filter(tdc_job *job)
{
	size_t		n = job->nin,
				kept = 0,
				head = 0;		/* oldest active kept site */
	rec		   *r,
			   *tmp,
			   *sorted = NULL;
	uint32_t   *krank = NULL,	/* kept site -> its rank */
			   *site_at = NULL; /* rank -> kept site (while active) */
	rankset		rs = {.mem = NULL};
	tol_poll	pl = {0, &job->cancel};
	tol_ctx		c;
	double		t2;
	bool		oom = false;

	if (n == 0)
		return 0;
	r = tdc_big_alloc(job->opt.cache, n * sizeof(rec));
	tmp = tdc_big_alloc(job->opt.cache, n * sizeof(rec));
	if (r == NULL || tmp == NULL)
		goto nomem;
	if (atomic_load_explicit(&job->cancel, memory_order_relaxed))
		goto stop;
	for (size_t k0 = 0; k0 < n; k0 += TOL_PREFAULT_RECS)
	{
		size_t		k1 = n - k0 < TOL_PREFAULT_RECS ? n : k0 + TOL_PREFAULT_RECS;

		/* both are written in full: map them in by the chunk, not a fault a page */
		tdc_prefault(r + k0, (k1 - k0) * sizeof(rec));
		tdc_prefault(tmp + k0, (k1 - k0) * sizeof(rec));
		for (size_t k = k0; k < k1; k++)
		{
			r[k].x = job->xy[2 * k];
			r[k].y = job->xy[2 * k + 1];
			r[k].i = job->idx[k];
			if (poll_cancelled(&pl))
				goto stop;
		}
	}
	if (!sort_recs(r, tmp, n, &sorted, &pl, &oom))
		goto stop;
	if (sorted == r)
		tdc_big_free(job->opt.cache, tmp);
	else
		tdc_big_free(job->opt.cache, r), r = tmp;
	tmp = NULL;

	krank = tdc_big_alloc(job->opt.cache, n * sizeof(uint32_t));
	site_at = tdc_big_alloc(job->opt.cache, n * sizeof(uint32_t));
	if (krank == NULL || site_at == NULL || !rankset_init(&rs, n, job->opt.cache))
		goto nomem;

	c.t = job->opt.tolerance;
	c.t = c.t < TOL_CLAMP_MIN ? TOL_CLAMP_MIN : (c.t > TOL_CLAMP_MAX ? TOL_CLAMP_MAX : c.t);
	t2 = c.t * c.t;
	c.lo = t2 * (1 - TOL_FILTER_SLACK);
	c.hi = t2 * (1 + TOL_FILTER_SLACK);
	c.tpt[0] = c.t;
	c.tpt[1] = c.origin[0] = c.origin[1] = 0;

	for (size_t k = 0; k < n; k++)
	{
		const rec  *p = &r[k];
		const double pt[2] = {p->x, p->y};
		uint32_t	best = TDC_NIL;
		double		bestd = 0;
		int64_t		q;

		/* expire: the kept sites are in x order, px only grows */
		while (head < kept && p->x - job->xy[2 * head] > c.t)
		{
			rankset_remove(&rs, krank[head++]);
			if (poll_cancelled(&pl))
				goto stop;
		}

		/* walk up, then down, from p's rank while |dy| may be below t' */
		for (int dir = 0; dir < 2; dir++)
		{
			q = dir == 0 ? rankset_next(&rs, (int64_t) p->yr + 1)
				: rankset_prev(&rs, (int64_t) p->yr - 1);
			while (q >= 0)
			{
				uint32_t	s = site_at[q];
				const double *sq = job->xy + 2 * (size_t) s;
				double		d;

				if (poll_cancelled(&pl))
					goto stop;
				if ((dir == 0 ? sq[1] - p->y : p->y - sq[1]) > c.t)
					break;
				d = sqdist(pt, sq);
				if (within(&c, pt, sq, d))
				{
					int			cmp = best == TDC_NIL ? -1 :
						closer(pt, sq, d, job->xy + 2 * (size_t) best, bestd);

					if (cmp < 0 || (cmp == 0 && s < best))
						best = s, bestd = d;
				}
				q = dir == 0 ? rankset_next(&rs, q + 1) : rankset_prev(&rs, q - 1);
			}
		}
		if (poll_cancelled(&pl))
			goto stop;

		if (best != TDC_NIL)
		{
			job->tol_to[p->i] = job->idx[best];
			continue;
		}
		/* keep: kept sites overwrite the front of xy/idx, already copied to r */
		job->xy[2 * kept] = p->x;
		job->xy[2 * kept + 1] = p->y;
		job->idx[kept] = p->i;
		job->tol_to[p->i] = p->i;
		krank[kept] = p->yr;
		site_at[p->yr] = (uint32_t) kept;
		rankset_add(&rs, p->yr);
		kept++;
	}
	job->nin = kept;

stop:
	tdc_big_free(job->opt.cache, r), tdc_big_free(job->opt.cache, tmp);
	tdc_big_free(job->opt.cache, krank), tdc_big_free(job->opt.cache, site_at);
	tdc_big_free(job->opt.cache, rs.mem);
	return oom ? TDC_ENOMEM : 0;

nomem:
	oom = true;
	goto stop;
}

/*
 * Bytes tdc_tolerance_filter allocates for n points, at most: the records
 * and the radix sort's second buffer, the rank arrays and the rank set
 * (counted as if all were alive at once), and the sort's histograms.
 */
size_t
tdc_tolerance_memory(size_t n)
{
	return 2 * n * sizeof(rec) + 2 * n * sizeof(uint32_t) +
		2 * (n / 64 + RS_LEVELS + 1) * sizeof(uint64_t) +
		(size_t) 2 * RADIX_DIGITS * RADIX_SIZE * sizeof(size_t);
}
