/*
 * bounded_bin.c
 *		Pass 2 of a bounded run: every point of the .bin source appended
 *		to its tile's file, and to the halo file of every other tile whose
 *		first known region holds it.
 *
 * Each tile's first known region (K and its bands, first_region) is
 * fixed by the plan, so binning can also write every point that lies in
 * another tile's first region to that tile's halo file: a tile's first run
 * then reads its own file and its halo file once, without filtering,
 * instead of every neighbour's file twice (counting, then filling).  Two
 * files per tile: with too many tiles for the open files, there are no
 * halo files and every run gathers from the tile files.
 *
 * Duplicates share their cell, hence their tile, and the files keep input
 * order (the two halves of the input, binned on two threads, each into
 * files of their own, are read back one after the other), so the Z of a
 * vertex is that of its first input point, as in the one-shot run.  The
 * write buffers of the files take a sixteenth of the budget.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "bounded_int.h"

/*
 * The files the bin may hold open at once: 800 (two each for 400 tiles,
 * the halo index's bound), or more when the process's soft limit on open
 * files leaves more than that after HOST_FILES for the host's own (a
 * PostgreSQL backend keeps up to max_files_per_process, 1000 by default;
 * ./tdc raises its soft limit to the hard one).  The limit is only read.
 */
#define HOST_FILES	1224

static size_t
files_room(void)
{
	struct rlimit rl;
	rlim_t		cur;

	if (getrlimit(RLIMIT_NOFILE, &rl) != 0)
		return 800;
	cur = rl.rlim_cur == RLIM_INFINITY || rl.rlim_cur > (rlim_t) 1 << 20 ? (rlim_t) 1 << 20 : rl.rlim_cur;
	return cur > 800 + HOST_FILES ? (size_t) cur - HOST_FILES : 800;
}

/*
 * Each tile's first region: r->kfirst[t], its first K, and r->band_idx
 * from r->band_off[t], its hull bands; and in *pairs (*npairs of them,
 * *cap allocated) a (cell, tile) pair for every cell that a box of the
 * region meets, but the tile's own cells, and (cell, tile | WHOLE) for its
 * hull cells, whose points all belong to the region.
 */
#define WHOLE	0x8000

static int
add_pair(bounded_run *r, uint32_t **pairs, size_t *npairs, size_t *cap, uint32_t cell, uint32_t t)
{
	if (*npairs == *cap)
	{
		uint32_t   *a = realloc(*pairs, sizeof(uint32_t) * 2 * (*cap * 2));

		if (a == NULL)
			return tdc_bd_nomem(&r->e);
		*pairs = a;
		*cap *= 2;
	}
	(*pairs)[2 * *npairs] = cell;
	(*pairs)[2 * *npairs + 1] = t;
	(*npairs)++;
	return TDC_OK;
}

static int
first_regions(bounded_run *r, uint32_t **pairs, size_t *npairs, size_t *cap)
{
	const double *grid = r->grid.box,
			   *xcut = r->grid.xcut,
			   *ycut = r->grid.ycut,
			   *bb = r->bb;
	double		sx = r->grid.sx,
				sy = r->grid.sy;

	r->band_off[0] = 0;
	for (int t = 0; t < r->nt; t++)
	{
		double		h,
				   *K = r->kfirst + 4 * t;
		size_t		nb = 0;

		r->band_off[t + 1] = r->band_off[t];
		if (r->tiles[t].count == 0)
			continue;
		first_region(r, t, K, &h);
		for (size_t i = 0; r->nhull > 1 && i < r->nhull; i++)
			if (r->inband[i])
				r->xs[nb++] = r->bands + 4 * i;
		{
			size_t	   *a = realloc(r->band_idx, sizeof(size_t) * (r->band_off[t] + nb + 1));

			if (a == NULL)
				return tdc_bd_nomem(&r->e);
			r->band_idx = a;
		}
		for (size_t i = 0; r->nhull > 1 && i < r->nhull; i++)
			if (r->inband[i])
				r->band_idx[r->band_off[t + 1]++] = i;
		/* the cells each box of the region meets, but the tile's own */
		for (size_t e = 0; e <= nb; e++)
		{
			const double *b = e == 0 ? K : r->xs[e - 1];
			int			c0 = tdc_tp_cell_of(b[0], grid[0], sx, xcut),
						c1 = tdc_tp_cell_of(b[2], grid[0], sx, xcut),
						r0 = tdc_tp_cell_of(b[1], grid[1], sy, ycut),
						r1 = tdc_tp_cell_of(b[3], grid[1], sy, ycut);

			if (b[2] < bb[0] || b[0] > bb[2] || b[3] < bb[1] || b[1] > bb[3])
				continue;
			for (int row = r0; row <= r1; row++)
				for (int c = c0; c <= c1; c++)
				{
					if (r->cell_tile[row * TDC_TP_GRID + c] == t)
						continue;
					if (add_pair(r, pairs, npairs, cap, (uint32_t) (row * TDC_TP_GRID + c),
								 (uint32_t) t) != TDC_OK)
						return r->e.code;
				}
		}
		for (size_t k = 0; k < r->nhcells; k++)
			if (add_pair(r, pairs, npairs, cap, r->hcells[k], (uint32_t) t | WHOLE) != TDC_OK)
				return r->e.code;
	}
	return TDC_OK;
}

/*
 * Per cell, its tiles of the pairs, once each: r->cell_halo from
 * r->cell_off[cell] (zeroed by the caller), as a counting sort by cell; a
 * tile that has the cell whole as -1 - tile.
 */
static int
index_cells(bounded_run *r, const uint32_t *pairs, size_t npairs)
{
	uint32_t   *fill,
			   *cell_off = r->cell_off;
	uint8_t    *seen = calloc((size_t) r->nt + 1, 1);
	int16_t    *cell_halo;

	for (size_t i = 0; i < npairs; i++)
		cell_off[pairs[2 * i] + 1]++;
	for (size_t c = 0; c < (size_t) TDC_TP_GRID * TDC_TP_GRID; c++)
		cell_off[c + 1] += cell_off[c];
	fill = malloc(sizeof(uint32_t) * ((size_t) TDC_TP_GRID * TDC_TP_GRID + 1));
	r->cell_halo = cell_halo = malloc(sizeof(int16_t) * (npairs + 1));
	if (!fill || !cell_halo || !seen)
	{
		free(fill);
		free(seen);
		return tdc_bd_nomem(&r->e);
	}
	memcpy(fill, cell_off, sizeof(uint32_t) * ((size_t) TDC_TP_GRID * TDC_TP_GRID + 1));
	for (size_t i = 0; i < npairs; i++)
		cell_halo[fill[pairs[2 * i]]++] = (int16_t) pairs[2 * i + 1];
	/* drop repeats within a cell (a tile whose K and bands meet it), whole first */
	for (size_t c = 0, at = 0; c < (size_t) TDC_TP_GRID * TDC_TP_GRID; c++)
	{
		uint32_t	a = cell_off[c],
					b = cell_off[c + 1];

		cell_off[c] = (uint32_t) at;
		for (uint32_t j = a; j < b; j++)
			seen[(uint16_t) cell_halo[j] & ~WHOLE] |= ((uint16_t) cell_halo[j] & WHOLE) ? 2 : 1;
		for (uint32_t j = a; j < b; j++)
		{
			int			u = (uint16_t) cell_halo[j] & ~WHOLE;

			if (seen[u])
				cell_halo[at++] = (int16_t) ((seen[u] & 2) ? -1 - u : u);
			seen[u] = 0;
		}
		if (c + 1 == (size_t) TDC_TP_GRID * TDC_TP_GRID)
			cell_off[c + 1] = (uint32_t) at;
	}
	free(fill);
	free(seen);
	return TDC_OK;
}

/*
 * The halo index, when the tiles are few enough for two files each
 * (r->use_halo): each tile's first region (first_regions) and, per fine
 * cell, the other tiles whose first region meets the cell's box, each
 * once (index_cells): a point is tested only against those.
 */
int
tdc_bd_halo_index(bounded_run *r)
{
	size_t		npairs = 0,
				cap = 1024;
	uint32_t   *pairs;
	int			nt = r->nt;

	r->use_halo = nt <= 400;
	if (!r->use_halo)
		return TDC_OK;
	pairs = malloc(sizeof(uint32_t) * 2 * cap);
	r->kfirst = malloc(32 * (size_t) (nt > 0 ? nt : 1));
	r->band_off = malloc(sizeof(size_t) * (nt + 1));
	r->cell_off = calloc((size_t) TDC_TP_GRID * TDC_TP_GRID + 1, sizeof(uint32_t));
	if (!pairs || !r->kfirst || !r->band_off || !r->cell_off)
	{
		free(pairs);
		return tdc_bd_nomem(&r->e);
	}
	if (first_regions(r, &pairs, &npairs, &cap) == TDC_OK)
		index_cells(r, pairs, npairs);
	free(pairs);
	return r->e.code;
}

/*
 * Pass 2 over the input points [from, from + count): each point to its
 * tile's file, and to the halo file of every other tile whose first known
 * region holds it, with the label of its own tile; the exact box of each
 * tile's points in bb.
 */
typedef struct bin_work
{
	/* shared, read only */
	const bounded_run *r;
	/* this part's */
	size_t		from,
				count;
	recfile    *own,
			   *halo;
	double	   *bb;				/* nt boxes */
	bd_err		e;				/* this part's first error */
} bin_work;

static void *
bin_range(void *arg)
{
	bin_work   *b = arg;
	const bounded_run *r = b->r;
	source		src;
	size_t		k;
	int			w = r->w;
	const double *grid = r->grid.box,
			   *xcut = r->grid.xcut,
			   *ycut = r->grid.ycut,
			   *kfirst = r->kfirst,
			   *bands = r->bands;
	double		sx = r->grid.sx,
				sy = r->grid.sy;
	const int16_t *cell_tile = r->cell_tile,
			   *cell_halo = r->cell_halo;
	const uint32_t *cell_off = r->cell_off;
	const size_t *band_off = r->band_off,
			   *band_idx = r->band_idx;
	bool		use_halo = r->use_halo;

	if (tdc_bd_source_open(&src, r->xypath, r->zpath, r->lpath, &b->e, r->p->cancel) == TDC_OK)
		tdc_bd_source_range(&src, b->from, b->count);
	while ((k = tdc_bd_source_read(&src)) > 0)
		for (size_t i = 0; i < k; i++)
		{
			double		rec[5] = {src.xy[2 * i], src.xy[2 * i + 1], src.z ? src.z[i] : 0, 0, 0};
			int			cell = tdc_tp_cell_of(rec[1], grid[1], sy, ycut) * TDC_TP_GRID +
				tdc_tp_cell_of(rec[0], grid[0], sx, xcut),
						t = cell_tile[cell];
			double	   *bb = b->bb + 4 * t;

			if (src.l)
				rec_set_label(rec, REC_L(r), src.l[i]);
			if (rec[0] < bb[0])
				bb[0] = rec[0];
			if (rec[0] > bb[2])
				bb[2] = rec[0];
			if (rec[1] < bb[1])
				bb[1] = rec[1];
			if (rec[1] > bb[3])
				bb[3] = rec[1];
			rec_put(&b->own[t], rec, w);
			if (!use_halo)
				continue;
			for (uint32_t j = cell_off[cell]; j < cell_off[cell + 1]; j++)
			{
				int			u = cell_halo[j] < 0 ? -1 - cell_halo[j] : cell_halo[j];
				const double *K = kfirst + 4 * u;
				bool		in = cell_halo[j] < 0 ||
					(rec[0] >= K[0] && rec[0] <= K[2] && rec[1] >= K[1] && rec[1] <= K[3]);

				for (size_t e = band_off[u]; e < band_off[u + 1] && !in; e++)
				{
					const double *x = bands + 4 * band_idx[e];

					in = rec[0] >= x[0] && rec[0] <= x[2] && rec[1] >= x[1] && rec[1] <= x[3];
				}
				if (in)
				{
					rec[w] = t;
					rec_put(&b->halo[u], rec, w + 1);
				}
			}
		}
	tdc_bd_source_close(&src);
	for (int t = 0; t < r->nt; t++)
	{
		tdc_bd_rec_close(&b->own[t]);
		if (use_halo)
			tdc_bd_rec_close(&b->halo[t]);
	}
	return NULL;
}

/*
 * Pass 2: the tile files ("tile" t, and "halo" t with use_halo) in
 * r->nparts parts, r->tiles[t].bb the exact box of tile t's points and
 * r->halo_count[t] its halo file's points.  The two halves of the input
 * on two threads (each with its own files) when there are file handles
 * enough (files_room): a 1e9-point run's few hundred tiles need about
 * 1,400, which the old fixed bound of 800 refused, so that its bin, a
 * minute long, kept one core idle.  Frees the cell maps.
 */
int
tdc_bd_bin_points(bounded_run *r)
{
	int			nt = r->nt,
				w = r->w;
	bool		use_halo = r->use_halo;
	/* buffers: a sixteenth of the budget over the files, 4 kB to 256 kB each */
	size_t		per;
	bin_work	bw[2];
	pthread_t	th;
	bool		started = false;

	memset(bw, 0, sizeof(bw));
	r->nparts = r->n >= ((size_t) 1 << 18) &&
		(size_t) nt * (use_halo ? 2 : 1) * 2 <= files_room() ? 2 : 1;
	r->st->bin_threads = r->nparts;
	per = r->budget / 16 / (size_t) (2 * r->nparts * (nt > 0 ? nt : 1)) / 8;
	per = per < 512 ? 512 : per > 32768 ? 32768 : per;
	for (int p = 0; p < r->nparts && r->e.code == TDC_OK; p++)
	{
		bin_work   *b = &bw[p];

		b->r = r;
		b->from = r->n / r->nparts * p;
		b->count = p == r->nparts - 1 ? r->n - b->from : r->n / r->nparts;
		b->own = calloc((size_t) (nt > 0 ? nt : 1), sizeof(recfile));
		b->halo = use_halo ? calloc((size_t) (nt > 0 ? nt : 1), sizeof(recfile)) : NULL;
		b->bb = malloc(32 * (size_t) (nt > 0 ? nt : 1));
		if (b->own == NULL || (use_halo && b->halo == NULL) || b->bb == NULL)
		{
			tdc_bd_nomem(&r->e);
			break;
		}
		for (int t = 0; t < nt; t++)
		{
			b->bb[4 * t] = b->bb[4 * t + 1] = INFINITY;
			b->bb[4 * t + 2] = b->bb[4 * t + 3] = -INFINITY;
			if (tdc_bd_rec_open(&b->own[t], r->dir, &b->e, "tile", t, p, per - per % w) != TDC_OK ||
				(use_halo &&
				 tdc_bd_rec_open(&b->halo[t], r->dir, &b->e, "halo", t, p,
								 (per / 4) - (per / 4) % (w + 1)) != TDC_OK))
				break;
		}
		if (b->e.code != TDC_OK)
			tdc_bd_fail(&r->e, b->e.code, "%s", b->e.msg);
	}
	if (r->e.code == TDC_OK)
	{
		if (r->nparts == 2)
			started = pthread_create(&th, NULL, bin_range, &bw[1]) == 0;
		bin_range(&bw[0]);
		if (started)
			pthread_join(th, NULL);
		else if (r->nparts == 2)
			bin_range(&bw[1]);
		for (int p = 0; p < r->nparts; p++)
			if (bw[p].e.code != TDC_OK)
				tdc_bd_fail(&r->e, bw[p].e.code, "%s", bw[p].e.msg);
	}
	else
	{
		/* the files opened before the error, closed (removed with the rest) */
		for (int p = 0; p < r->nparts; p++)
			for (int t = 0; t < nt; t++)
			{
				if (bw[p].own)
					tdc_bd_rec_close(&bw[p].own[t]);
				if (bw[p].halo)
					tdc_bd_rec_close(&bw[p].halo[t]);
			}
	}
	r->halo_count = calloc((size_t) (nt > 0 ? nt : 1), sizeof(size_t));
	if (r->halo_count == NULL)
		tdc_bd_nomem(&r->e);
	for (int p = 0; p < r->nparts; p++)
	{
		for (int t = 0; t < nt && r->e.code == TDC_OK; t++)
		{
			tdc_tp_box_union(r->tiles[t].bb, bw[p].bb + 4 * t);
			if (use_halo)
				r->halo_count[t] += bw[p].halo[t].count;
		}
		free(bw[p].own);
		free(bw[p].halo);
		free(bw[p].bb);
	}
	free(r->cell_tile);
	free(r->cell_off);
	free(r->cell_halo);
	r->cell_tile = NULL;
	r->cell_off = NULL;
	r->cell_halo = NULL;
	return r->e.code;
}
