/*
 * sites.c
 *		The optional tolerance filter.  (Exact duplicates are removed inside
 *		the subsets, see leaf.c.)
 *
 * Tolerance (options.tolerance > 0).  Rule: take the points in lexicographic
 * (x, y) order, ties by input index; keep a point unless some already kept
 * site q satisfies dx*dx + dy*dy < tolerance*tolerance, computed in double
 * precision; a dropped point maps to the nearest such q (the earliest kept
 * on ties).  This greedy pass is inherently sequential, so it runs before
 * the subdivision on a hash grid of cell size = tolerance, and its survivors
 * then go through the parallel pipeline like any input.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"

typedef struct rec
{
	double		x,
				y;
	uint32_t	i;
} rec;

static inline bool
rec_less(const rec *a, const rec *b)
{
	if (a->x != b->x)
		return a->x < b->x;
	if (a->y != b->y)
		return a->y < b->y;
	return a->i < b->i;
}

/*
 * Introsort-free quicksort with median-of-three and insertion sort below 16:
 * subsets are small and the recursion depth is bounded by recursing on the
 * smaller side.  Checks the cancel flag on large ranges.
 */
static void
sort_recs(rec *r, size_t n, const atomic_int *cancel)
{
	while (n > 16)
	{
		size_t		mid = n / 2,
					i,
					j;
		rec			p,
					t;

		if (n > (1 << 16) && atomic_load_explicit(cancel, memory_order_relaxed))
			return;
		if (rec_less(&r[mid], &r[0]))
			t = r[mid], r[mid] = r[0], r[0] = t;
		if (rec_less(&r[n - 1], &r[0]))
			t = r[n - 1], r[n - 1] = r[0], r[0] = t;
		if (rec_less(&r[n - 1], &r[mid]))
			t = r[n - 1], r[n - 1] = r[mid], r[mid] = t;
		p = r[mid];
		i = 0;
		j = n - 1;
		for (;;)
		{
			while (rec_less(&r[i], &p))
				i++;
			while (rec_less(&p, &r[j]))
				j--;
			if (i >= j)
				break;
			t = r[i], r[i] = r[j], r[j] = t;
			i++;
			j--;
		}
		/* [0, j] <= p <= [j + 1, n) */
		if (j + 1 < n - j - 1)
		{
			sort_recs(r, j + 1, cancel);
			r += j + 1;
			n -= j + 1;
		}
		else
		{
			sort_recs(r + j + 1, n - j - 1, cancel);
			n = j + 1;
		}
	}
	for (size_t i = 1; i < n; i++)
	{
		rec			t = r[i];
		size_t		j = i;

		while (j > 0 && rec_less(&t, &r[j - 1]))
		{
			r[j] = r[j - 1];
			j--;
		}
		r[j] = t;
	}
}

/* --- tolerance --- */

typedef struct cell_table
{
	int64_t    *kx,
			   *ky;
	uint32_t   *head;			/* first kept site of the cell, TDC_NIL if none */
	size_t		mask;
} cell_table;

static inline size_t
cell_hash(int64_t cx, int64_t cy, size_t mask)
{
	uint64_t	h = (uint64_t) cx * 0x9E3779B97F4A7C15ull ^ ((uint64_t) cy + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;

	return (size_t) (h ^ (h >> 29)) & mask;
}

static inline size_t
cell_find(const cell_table *t, int64_t cx, int64_t cy)
{
	size_t		h = cell_hash(cx, cy, t->mask);

	while (t->head[h] != TDC_NIL && (t->kx[h] != cx || t->ky[h] != cy))
		h = (h + 1) & t->mask;
	return h;
}

static inline int64_t
cell_of(double v, double origin, double tol)
{
	double		c = floor((v - origin) / tol);

	if (c > 4e18)
		return (int64_t) 4e18;
	if (c < -4e18)
		return (int64_t) -4e18;
	return (int64_t) c;
}

/*
 * Apply the tolerance rule to all input points, leaving the survivors in
 * xy/idx (nin of them) and tol_to[] for the dropped ones.
 */
int
tdc_tolerance_filter(tdc_job *job)
{
	size_t		n = job->nin,
				kept = 0,
				cap = 16;
	double		tol = job->opt.tolerance,
				tol2 = tol * tol;
	rec		   *r;
	uint32_t   *chain;
	cell_table	t;

	while (cap < 2 * n)
		cap <<= 1;
	/* mapped, not malloc'd: a backend's raised malloc thresholds would keep them */
	r = tdc_big_alloc(n * sizeof(rec));
	chain = tdc_big_alloc(n * sizeof(uint32_t));
	t.kx = tdc_big_alloc(cap * sizeof(int64_t));
	t.ky = tdc_big_alloc(cap * sizeof(int64_t));
	t.head = tdc_big_alloc(cap * sizeof(uint32_t));
	t.mask = cap - 1;
	if (!r || !chain || !t.kx || !t.ky || !t.head)
	{
		tdc_big_free(r), tdc_big_free(chain), tdc_big_free(t.kx), tdc_big_free(t.ky), tdc_big_free(t.head);
		return TDC_ENOMEM;
	}
	memset(t.head, 0xff, cap * sizeof(uint32_t));

	for (size_t k = 0; k < n; k++)
	{
		r[k].x = job->xy[2 * k];
		r[k].y = job->xy[2 * k + 1];
		r[k].i = job->idx[k];
	}
	sort_recs(r, n, &job->cancel);
	if (atomic_load(&job->cancel))
		goto done;

	for (size_t k = 0; k < n; k++)
	{
		int64_t		cx = cell_of(r[k].x, job->bmin[0], tol),
					cy = cell_of(r[k].y, job->bmin[1], tol);
		uint32_t	best = TDC_NIL;
		double		bestd = 0;
		size_t		h;

		if ((k & 0xffff) == 0 && atomic_load_explicit(&job->cancel, memory_order_relaxed))
			goto done;

		for (int64_t dx = -1; dx <= 1; dx++)
			for (int64_t dy = -1; dy <= 1; dy++)
			{
				h = cell_find(&t, cx + dx, cy + dy);
				for (uint32_t q = t.head[h]; q != TDC_NIL; q = chain[q])
				{
					double		ex = r[k].x - job->xy[2 * (size_t) q],
								ey = r[k].y - job->xy[2 * (size_t) q + 1],
								d2 = ex * ex + ey * ey;

					if (d2 < tol2 && (best == TDC_NIL || d2 < bestd ||
									  (d2 == bestd && q < best)))
						best = q, bestd = d2;
				}
			}
		if (best != TDC_NIL)
		{
			job->tol_to[r[k].i] = job->idx[best];
			continue;
		}
		/* keep: kept sites overwrite the front of xy/idx, already consumed */
		job->xy[2 * kept] = r[k].x;
		job->xy[2 * kept + 1] = r[k].y;
		job->idx[kept] = r[k].i;
		job->tol_to[r[k].i] = r[k].i;
		h = cell_find(&t, cx, cy);
		if (t.head[h] == TDC_NIL)
		{
			t.kx[h] = cx;
			t.ky[h] = cy;
		}
		chain[kept] = t.head[h];
		t.head[h] = (uint32_t) kept;
		kept++;
	}
	job->nin = kept;
done:
	tdc_big_free(r), tdc_big_free(chain), tdc_big_free(t.kx), tdc_big_free(t.ky), tdc_big_free(t.head);
	return 0;
}

/* Bytes tdc_tolerance_filter allocates for n points, at most. */
size_t
tdc_tolerance_memory(size_t n)
{
	size_t		cap = 16;

	while (cap < 2 * n)
		cap <<= 1;
	return n * (sizeof(rec) + sizeof(uint32_t)) + cap * (2 * sizeof(int64_t) + sizeof(uint32_t));
}
