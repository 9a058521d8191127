/*
 * subdivide.c
 *		Step 1 of Wu et al. 2014: parallel adaptive subdivision over an
 *		auxiliary s x s grid.
 *
 * As in the paper (section 2.1, after Wang et al. 2014), the points are
 * indexed once by the cell of an auxiliary grid laid over their bounding
 * box, and every split works on cell counts, not on points: a node of the
 * binary tree is a rectangle of cells, split alternately by a column line and
 * by a row line chosen so that both halves hold nearly half its points.  With
 * a 2-D prefix sum of the counts, a rectangle's count costs four loads, so a
 * split is a binary search over the rectangle's columns (rows).  The first d
 * levels form the tree whose 2^d leaves are the subsets; below them the
 * subsets go on splitting their rectangles the same way down to single cells
 * (leaf.c), which makes their triangulation Dwyer's cell-wise divide and
 * conquer.
 *
 * Once the tree is known, each non-empty cell gets its place in depth-first
 * order of the whole tree, and one parallel counting-sort pass copies every
 * point there.  So every node, down to a single cell, owns a contiguous range
 * of points, and of edge slots (three per point): merges of different nodes
 * never share memory.
 *
 * Separation.  A cell's column is a non-decreasing function of x, so points
 * in columns left of a column line have strictly smaller x than points right
 * of it, and the (x, y) keys of the merge along axis 0 are separated; rows
 * separate (y, -x) the same way.  Equal points share a cell.
 *
 * Splits: binary search by count in the top d levels (balanced subsets for
 * the threads); inside a subset the midpoint line of the longer-split axis,
 * which is cheaper and balanced enough, with empty rectangles pruned.  If a
 * rectangle is one cell wide in its axis, it splits along the other; a
 * single cell is not split.
 */
#include <stdlib.h>
#include <string.h>

#include "job_int.h"

/*
 * Points between two looks at the cancel flag in the counting passes: their
 * first writes to fresh memory fault pages in, so 65536 points could take
 * hundreds of milliseconds on a loaded machine.
 */
#define CANCEL_POLL_POINTS	4096

static inline uint32_t
grid_index(double v, double origin, double scale, int s)
{
	double		f = (v - origin) * scale;

	if (!(f > 0))
		return 0;
	if (f >= s)
		return s - 1;
	return (uint32_t) f;
}

static inline uint32_t
cell_of(const tdc_job *job, const double *p)
{
	return grid_index(p[1], job->bmin[1], job->gscale[1], job->s) * job->s +
		grid_index(p[0], job->bmin[0], job->gscale[0], job->s);
}

uint32_t
tdc_rect_count(const tdc_job *job, const tdc_rect *r)
{
	const uint32_t *P = job->prefix;
	size_t		w = job->s + 1;

	if (r->r0 >= r->r1 || r->c0 >= r->c1)
		return 0;
	return P[r->r1 * w + r->c1] - P[r->r0 * w + r->c1] - P[r->r1 * w + r->c0] +
		P[r->r0 * w + r->c0];
}

/*
 * Split r along axis (flipped if r is one cell wide there) into a and b,
 * a before b in the axis order; returns the axis used, or -1 for a single
 * cell.  by_count chooses the line that best halves the points.
 */
int
tdc_rect_split(const tdc_job *job, const tdc_rect *r, int axis, bool by_count,
			   tdc_rect *a, tdc_rect *b)
{
	uint32_t	lo,
				hi,
				cut;

	if (r->r1 - r->r0 <= 1 && r->c1 - r->c0 <= 1)
		return -1;
	if (axis == 0 && r->c1 - r->c0 <= 1)
		axis = 1;
	else if (axis == 1 && r->r1 - r->r0 <= 1)
		axis = 0;
	*a = *r;
	*b = *r;
	lo = axis == 0 ? r->c0 : r->r0;
	hi = axis == 0 ? r->c1 : r->r1;
	cut = lo + (hi - lo) / 2;
	if (by_count)
	{
		uint32_t	total = tdc_rect_count(job, r);
		uint32_t	l = lo + 1,
					h = hi - 1;

		/* smallest cut with at least half the points before it */
		while (l < h)
		{
			uint32_t	m = l + (h - l) / 2;

			if (axis == 0)
				a->c1 = m;
			else
				a->r1 = m;
			if (2 * (uint64_t) tdc_rect_count(job, a) >= total)
				h = m;
			else
				l = m + 1;
		}
		cut = l;
		/* the line just before may balance better */
		if (cut > lo + 1)
		{
			uint32_t	with,
						without;

			if (axis == 0)
				a->c1 = cut;
			else
				a->r1 = cut;
			with = tdc_rect_count(job, a);
			if (axis == 0)
				a->c1 = cut - 1;
			else
				a->r1 = cut - 1;
			without = tdc_rect_count(job, a);
			if ((uint64_t) total - 2 * (uint64_t) without < 2 * (uint64_t) with - total)
				cut--;
		}
	}
	if (axis == 0)
		a->c1 = b->c0 = cut;
	else
		a->r1 = b->r0 = cut;
	return axis;
}

/* Inner split of leaf.c and the numbering below: the same choice both times. */
int
tdc_rect_split_inner(const tdc_job *job, const tdc_rect *r, int axis,
					 tdc_rect *a, tdc_rect *b)
{
	return tdc_rect_split(job, r, axis, false, a, b);
}

typedef struct grid_arg
{
	tdc_job    *job;
	const double *src;			/* points to place: the input, or tolerance survivors */
	const uint32_t *src_idx;	/* their input indices; NULL: the identity */
	size_t		n;
	uint32_t   *cell;			/* cell of each input point */
	uint32_t   *hist;			/* per slice: counts, then write positions */
	uint32_t   *cell_start;		/* first position of each cell */
	size_t		ncells;
	int			nslices;
	int			level;			/* tree level being split */
} grid_arg;

static void
cell_task(void *arg, size_t t, int worker)
{
	grid_arg   *ga = arg;
	tdc_job    *job = ga->job;
	size_t		lo = ga->n * t / ga->nslices,
				hi = ga->n * (t + 1) / ga->nslices;
	uint32_t   *h = ga->hist + t * ga->ncells;

	memset(h, 0, ga->ncells * sizeof(uint32_t));
	for (size_t i = lo; i < hi; i++)
	{
		uint32_t	c = cell_of(job, ga->src + 2 * i);

		if ((i & (CANCEL_POLL_POINTS - 1)) == 0 && atomic_load_explicit(&job->cancel, memory_order_relaxed))
			return;

		ga->cell[i] = c;
		h[c]++;
	}
}

static void
scatter_task(void *arg, size_t t, int worker)
{
	grid_arg   *ga = arg;
	tdc_job    *job = ga->job;
	size_t		lo = ga->n * t / ga->nslices,
				hi = ga->n * (t + 1) / ga->nslices;
	uint32_t   *pos = ga->hist + t * ga->ncells;

	for (size_t i = lo; i < hi; i++)
	{
		uint32_t	p = pos[ga->cell[i]]++;

		if ((i & (CANCEL_POLL_POINTS - 1)) == 0 && atomic_load_explicit(&job->cancel, memory_order_relaxed))
			return;

		job->xy[2 * (size_t) p] = ga->src[2 * i];
		job->xy[2 * (size_t) p + 1] = ga->src[2 * i + 1];
		job->idx[p] = ga->src_idx ? ga->src_idx[i] : (uint32_t) i;
	}
}

/* Split node i of the current level by count; a single cell keeps all. */
static void
split_task(void *arg, size_t i, int worker)
{
	grid_arg   *ga = arg;
	tdc_job    *job = ga->job;
	int			level = ga->level;
	size_t		k = ((size_t) 1 << level) + i;
	tdc_rect   *r = &job->node_rect[k],
			   *a = &job->node_rect[2 * k],
			   *b = &job->node_rect[2 * k + 1];
	int			axis = tdc_rect_split(job, r, level & 1, true, a, b);

	if (axis < 0)
	{
		*a = *r;
		*b = *r;
		b->r0 = b->r1;			/* empty */
		axis = level & 1;
	}
	job->node_axis[k] = (uint8_t) axis;
	job->node_lo[2 * k] = job->node_lo[k];
	job->node_hi[2 * k] = job->node_lo[k] + tdc_rect_count(job, a);
	job->node_lo[2 * k + 1] = job->node_hi[2 * k];
	job->node_hi[2 * k + 1] = job->node_hi[k];
}

/* Number the cells of r in depth-first order of the inner splits. */
static uint32_t
number_cells(const tdc_job *job, const tdc_rect *r, int axis, uint32_t next,
			 uint32_t *cell_start)
{
	tdc_rect	a,
				b;
	uint32_t	count = tdc_rect_count(job, r);

	if (count == 0)
		return next;
	/* a single subset numbers the whole grid here: stay cancellable */
	if (count >= CANCEL_POLL_POINTS && atomic_load_explicit(&job->cancel, memory_order_relaxed))
		return next + count;
	if (tdc_rect_split_inner(job, r, axis, &a, &b) < 0)
	{
		cell_start[r->r0 * job->s + r->c0] = next;
		return next + count;
	}
	next = number_cells(job, &a, axis ^ 1, next, cell_start);
	return number_cells(job, &b, axis ^ 1, next, cell_start);
}

static void
number_task(void *arg, size_t i, int worker)
{
	grid_arg   *ga = arg;
	tdc_job    *job = ga->job;
	size_t		k = ((size_t) 1 << job->d) + i;

	number_cells(job, &job->node_rect[k], job->d & 1, job->node_lo[k], ga->cell_start);
}

/*
 * Build the grid and the tree, and place the points into job->xy / job->idx
 * in tree order: read straight from the caller's input, or, after a
 * tolerance pass, from the survivors it left in job->xy / job->idx.
 */
void
tdc_subdivide(tdc_job *job)
{
	grid_arg	ga;
	size_t		w;
	int			T = job->threads;
	double	   *copy = NULL;
	uint32_t   *copyidx = NULL;

	memset(&ga, 0, sizeof(ga));
	ga.job = job;
	ga.nslices = T < TDC_GRID_SLICES ? T : TDC_GRID_SLICES;
	ga.ncells = (size_t) job->s * job->s;
	ga.n = job->nin;
	ga.src = job->input;
	w = job->s + 1;

	/*
	 * One cell and no tree, the auto grid of small inputs: the counting sort
	 * would put every point into that cell in its order, so place them so
	 * directly (a tolerance pass left its survivors in place already).
	 */
	if (job->s == 1 && job->d == 0)
	{
		job->prefix = tdc_job_alloc(job, 4 * sizeof(uint32_t));
		if (job->prefix == NULL)
			goto oom;
		job->prefix[3] = (uint32_t) ga.n;
		if (!job->tol_to && ga.n > 0)
		{
			memcpy(job->xy, job->input, ga.n * 2 * sizeof(double));
			for (size_t i = 0; i < ga.n; i++)
				job->idx[i] = (uint32_t) i;
		}
		job->node_rect[1].r0 = job->node_rect[1].c0 = 0;
		job->node_rect[1].r1 = job->node_rect[1].c1 = 1;
		job->node_lo[1] = 0;
		job->node_hi[1] = (uint32_t) ga.n;
		return;
	}

	if (job->tol_to)
	{
		copy = job->xy;
		copyidx = job->idx;
		ga.src = copy;
		ga.src_idx = copyidx;
		job->xy = tdc_job_alloc(job, job->nin * 2 * sizeof(double) + 16);
		job->idx = tdc_job_alloc(job, job->nin * sizeof(uint32_t) + 4);
		if (!job->xy || !job->idx)
			goto oom;
	}

	ga.cell = tdc_job_alloc(job, ga.n * sizeof(uint32_t) + 4);
	ga.hist = tdc_job_alloc(job, (size_t) ga.nslices * ga.ncells * sizeof(uint32_t));
	ga.cell_start = tdc_job_alloc(job, ga.ncells * sizeof(uint32_t));
	job->prefix = tdc_job_alloc(job, w * w * sizeof(uint32_t));
	if (!ga.cell || !ga.hist || !ga.cell_start || !job->prefix)
		goto oom;

	tdc_pool_for(job->pool, ga.nslices, cell_task, &ga);
	if (atomic_load(&job->cancel))
		goto done;

	/* total counts into the 2-D prefix sum */
	for (size_t r = 0; r < (size_t) job->s; r++)
	{
		uint32_t	rowsum = 0;

		if (atomic_load_explicit(&job->cancel, memory_order_relaxed))
			goto done;

		for (size_t c = 0; c < (size_t) job->s; c++)
		{
			uint32_t	cnt = 0;

			for (int t = 0; t < ga.nslices; t++)
				cnt += ga.hist[t * ga.ncells + r * job->s + c];
			rowsum += cnt;
			job->prefix[(r + 1) * w + c + 1] = job->prefix[r * w + c + 1] + rowsum;
		}
	}

	/* the top d levels, split by count, level by level on the pool */
	job->node_rect[1].r0 = job->node_rect[1].c0 = 0;
	job->node_rect[1].r1 = job->node_rect[1].c1 = job->s;
	job->node_lo[1] = 0;
	job->node_hi[1] = (uint32_t) ga.n;
	for (int level = 0; level < job->d; level++)
	{
		ga.level = level;
		tdc_pool_for(job->pool, (size_t) 1 << level, split_task, &ga);
	}

	/* cell positions in tree order, then per-slice write positions */
	tdc_pool_for(job->pool, (size_t) 1 << job->d, number_task, &ga);
	if (atomic_load(&job->cancel))
		goto done;
	for (size_t c = 0; c < ga.ncells; c++)
	{
		uint32_t	p = ga.cell_start[c];

		for (int t = 0; t < ga.nslices; t++)
		{
			uint32_t	cnt = ga.hist[t * ga.ncells + c];

			ga.hist[t * ga.ncells + c] = p;
			p += cnt;
		}
	}
	tdc_pool_for(job->pool, ga.nslices, scatter_task, &ga);
	goto done;

oom:
	tdc_job_fail(job, TDC_ENOMEM, "out of memory for the subdivision grid (%d x %d cells)",
				 job->s, job->s);
done:
	tdc_job_release(job, copy);
	tdc_job_release(job, copyidx);
	tdc_job_release(job, ga.cell);
	tdc_job_release(job, ga.hist);
	tdc_job_release(job, ga.cell_start);
}
