/*
 * contour_tiles.c
 *		Contour lines from the final triangles of a bounded run
 *		(tdc_contour_tiles_*, tdc.h): the whole TIN's lines
 *		(tin_contour.c), bit for bit and in the same order, in the memory of
 *		one tile plus what the lines' join needs.
 *
 * Why it can be done.  A contour line of the whole TIN is a path of
 * segments, one per (triangle, level) the level crosses, each from the
 * crossing on the triangle's down edge to that on its up edge; it goes on
 * across the up edge into the triangle beside it, where that edge is the
 * down edge, and stops at the hull or at a triangle max_edge drops.  Each
 * piece is local: which levels a triangle crosses, which of its edges are
 * down and up (heights equal to a level count as above it), and the
 * crossing on an edge, a function of the edge and the level alone
 * (tin_cut.c, the one-shot's very code).  The bounded run hands over every
 * global triangle exactly once, with its sites' coordinates and heights,
 * so the segments are the whole TIN's, to the bit.  What crosses tiles is
 * only the joining of segments into lines, and a crossing key (the level
 * and the crossed edge, named by its two ends' coordinates, the first in
 * (x, y) order first) names the join point whichever tile sees it.
 *
 * Per tile (here).  The tile's segments are joined into chains by the
 * local keys of their edges (vertex indices: a shared edge has the same
 * two), with a hash from down edge to segment: a chain starts at a segment
 * no segment of the tile leads into and runs until its up edge leads out
 * of the tile (or to the hull, or to a dropped triangle: the tile cannot
 * tell, and need not); what is left are rings within the tile.  Each
 * chain's points (its entry crossing, then one per segment, raw: a
 * crossing at a site repeats) go to a points file and its record (level,
 * entry and exit keys, where its points are) to a chains file, both in the
 * caller's temporary directory, through fixed write buffers.
 *
 * Memory per tile.  The segments are made in windows of levels holding at
 * most max(tile's triangles, CT_SEG_MIN) segments (a level crosses a
 * triangle once, so one level always fits), counted first by a histogram
 * of CT_HIST levels: about 30 bytes a segment with the hash, and 8 bytes a
 * point for its level index (below), beside the tile's points and
 * triangles; the bounded run frees the tile's engine (the bulk of its
 * model, tdc_tp_tile_bytes) before it emits, so the window fits in what
 * the tile was allowed.  What stays beside the tiles (this struct, the two
 * buffers and a histogram for each tile that may come at once: begin's
 * at_once) is the hold.
 *
 * Levels by vertex.  Which levels a triangle crosses, [klo, khi], is
 * asked of every triangle twice (the histogram, the windows), and most
 * triangles of dense samples cross none.  The least level above a height,
 * tin_k_above, is monotone in the height, so a triangle's klo and khi + 1
 * are the least and greatest of its corners' (kv, computed once a vertex),
 * and max_edge's exact test is only needed by a triangle that crosses one.
 *
 * Two tiles at once.  The bounded run's two workers may hand their tiles
 * over together (emit_concurrent): the segments and chains of each are
 * made on its own worker, and only the writing of a window's chains (so
 * that their points stay in one piece of the points file) and the counts
 * are taken under the struct's lock.  The files' order of chains then
 * depends on the workers, as it depends on the tiles' order already; the
 * join (contour_join.c) makes the lines canonical whatever it is.
 *
 * Levels.  A tile's heights are checked as the whole TIN's are
 * (tin_levels_check); a tile that fails marks the run, makes no segment,
 * and the run's check over all heights (contour_join.c, which must then
 * fail too, the tile's levels being among the run's) reports it with the
 * one-shot's message.
 */
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "contour_tiles.h"
#include "engine/predicates.h"
#include "tin/tin_cut.h"

#define NONE		UINT32_MAX

/* A segment of a window: triangle t crossed at level ka + kk, from edge d to edge u. */
typedef struct ct_seg
{
	uint32_t	t,
				kk;
	uint8_t		d,
				u;
} ct_seg;

/* One tile's window of levels [ka, kb). */
typedef struct ct_window
{
	const double *q,
			   *qz;
	const size_t *tri;
	const int64_t *kv;			/* per vertex: tin_k_above of its height */
	int64_t		ka;
	ct_seg	   *seg;
	size_t		nseg;
	uint32_t   *slot;			/* hash: down edge -> segment + 1, 0 empty */
	size_t		mask;
	uint32_t   *succ;			/* the segment its up edge leads to, or NONE */
	uint8_t    *state;			/* bit 0: something leads into it; bit 1: taken */
} ct_window;

static int
fail(char *err, size_t errlen, int code, const char *fmt, const char *arg)
{
	if (err && errlen)
		snprintf(err, errlen, fmt, arg);
	return code;
}

int
tdc_contour_tiles_begin(double interval, double base, const tdc_interp_spec *spec,
						const char *tmpdir, int at_once, tdc_contour_tiles **out, size_t *hold,
						char *err, size_t errlen)
{
	tdc_contour_tiles *c;
	char		path[4200];
	int			rc;

	*out = NULL;
	*hold = 0;
	if ((rc = tdc_tin_contours_spec_check(spec, err, errlen)) != TDC_OK)
		return rc;
	if (!(interval > 0) || !isfinite(interval))
	{
		if (err && errlen)
			snprintf(err, errlen, "the contour interval must be a finite number > 0, not %g", interval);
		return TDC_EINVAL;
	}
	if (!isfinite(base))
	{
		if (err && errlen)
			snprintf(err, errlen, "the contour base must be finite, not %g", base);
		return TDC_EINVAL;
	}
	if (strlen(tmpdir) >= sizeof(c->dir))
		return fail(err, errlen, TDC_EINVAL, "the temporary directory's name is too long: %s", tmpdir);
	if ((c = calloc(1, sizeof(*c))) == NULL)
		return fail(err, errlen, TDC_ENOMEM, "%s", "out of memory");
	c->interval = interval;
	c->base = base;
	c->max_edge = spec != NULL ? spec->max_edge : 0;
	c->zmin = INFINITY;
	c->zmax = -INFINITY;
	c->pts_fd = c->chain_fd = -1;
	strcpy(c->dir, tmpdir);
	pthread_mutex_init(&c->mu, NULL);
	c->pts_buf = malloc(CT_BUF);
	c->chain_buf = malloc(CT_BUF);
	if (c->pts_buf == NULL || c->chain_buf == NULL)
	{
		tdc_contour_tiles_free(c);
		return fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for the contours' buffers");
	}
	for (int f = 0; f < 2; f++)
	{
		int		   *fd = f ? &c->chain_fd : &c->pts_fd;
		FILE	  **fp = f ? &c->chains : &c->pts;

		snprintf(path, sizeof(path), "%s/%s", tmpdir, f ? "contour_chains" : "contour_points");
		*fd = open(path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
		if (*fd < 0)
		{
			tdc_contour_tiles_free(c);
			return fail(err, errlen, TDC_EIO, "cannot create %s", path);
		}
		/* the name goes at once: the descriptor keeps the file until it is closed */
		unlink(path);
		if ((*fp = fdopen(dup(*fd), "w")) == NULL ||
			setvbuf(*fp, f ? c->chain_buf : c->pts_buf, _IOFBF, CT_BUF) != 0)
		{
			tdc_contour_tiles_free(c);
			return fail(err, errlen, TDC_EIO, "cannot write %s", path);
		}
	}
	*out = c;
	*hold = sizeof(*c) + (at_once < 2 ? 1 : 2) * CT_HIST * sizeof(size_t) + 2 * CT_BUF;
	return TDC_OK;
}

/* Does max_edge drop the triangle (one of its edges longer, exactly: tin_interp.c's rule)? */
static bool
dropped(const tdc_contour_tiles *c, const double *const p[3])
{
	double		l[2] = {c->max_edge, 0},
				o[2] = {0, 0};

	if (!(c->max_edge > 0))
		return false;
	for (int k = 0; k < 3; k++)
		if (tdc_sqdist_cmp(p[k], p[(k + 1) % 3], l, o) > 0)
			return true;
	return false;
}

/*
 * The levels [*klo, *khi] triangle v crosses (none when dropped: *klo >
 * *khi): tin_k_above of its lowest and highest corner, from kv (the
 * essay's levels by vertex).
 */
static inline void
tri_levels(const tdc_contour_tiles *c, const double *q, const int64_t *kv, const size_t *v,
		   int64_t *klo, int64_t *khi)
{
	int64_t		a = kv[v[0]],
				b = kv[v[1]],
				d = kv[v[2]];

	*klo = a < b ? (a < d ? a : d) : (b < d ? b : d);
	*khi = (a > b ? (a > d ? a : d) : (b > d ? b : d)) - 1;
	if (*klo <= *khi)
	{
		const double *p[3] = {q + 2 * v[0], q + 2 * v[1], q + 2 * v[2]};

		if (dropped(c, p))
		{
			*klo = 1;
			*khi = 0;
		}
	}
}

/* Edge e of triangle t (from corner e to corner e + 1): its two vertices, the lesser index first. */
static inline void
edge_of(const ct_window *w, uint32_t t, int e, size_t *a, size_t *b)
{
	size_t		x = w->tri[3 * (size_t) t + e],
				y = w->tri[3 * (size_t) t + (e + 1) % 3];

	*a = x < y ? x : y;
	*b = x < y ? y : x;
}

static inline size_t
hash_of(size_t a, size_t b, uint32_t kk)
{
	uint64_t	h = (uint64_t) a * UINT64_C(0x9E3779B97F4A7C15) ^
		(uint64_t) b * UINT64_C(0xC2B2AE3D27D4EB4F) ^ (uint64_t) kk * UINT64_C(0x165667B19E3779F9);

	return (size_t) (h ^ (h >> 29));
}

/* The segment whose down edge is (a, b) at level ka + kk, or NONE. */
static uint32_t
find_down(const ct_window *w, size_t a, size_t b, uint32_t kk)
{
	for (size_t i = hash_of(a, b, kk) & w->mask;; i = (i + 1) & w->mask)
	{
		uint32_t	s = w->slot[i];
		size_t		x,
					y;

		if (s == 0)
			return NONE;
		s--;
		edge_of(w, w->seg[s].t, w->seg[s].d, &x, &y);
		if (x == a && y == b && w->seg[s].kk == kk)
			return s;
	}
}

/* The crossing key of edge e of triangle t: its ends' coordinates, the first in (x, y) order first. */
static void
key_of(const ct_window *w, uint32_t t, int e, double *key)
{
	const double *p0 = w->q + 2 * w->tri[3 * (size_t) t + e],
			   *p1 = w->q + 2 * w->tri[3 * (size_t) t + (e + 1) % 3];

	if (tdc_lex_less(p1, p0))
	{
		const double *s = p0;

		p0 = p1;
		p1 = s;
	}
	key[0] = p0[0];
	key[1] = p0[1];
	key[2] = p1[0];
	key[3] = p1[1];
}

/* The crossing of level L on edge e of triangle t (tin_cut.c, as the whole TIN's). */
static void
cut_of(const ct_window *w, uint32_t t, int e, double L, double *p)
{
	size_t		a = w->tri[3 * (size_t) t + e],
				b = w->tri[3 * (size_t) t + (e + 1) % 3];

	tin_cut_xy(w->q + 2 * a, w->qz[a], w->q + 2 * b, w->qz[b], L, p);
}

/* The chain from segment s0 (following succ until NONE or back to s0) to the files. */
static int
write_chain(tdc_contour_tiles *c, ct_window *w, uint32_t s0, char *err, size_t errlen)
{
	ct_chain	ch;
	double		L = tin_level(c->base, c->interval, w->ka + w->seg[s0].kk),
				p[2];
	uint32_t	s = s0,
				last = s0;

	memset(&ch, 0, sizeof(ch));
	ch.k = w->ka + w->seg[s0].kk;
	ch.off = c->npts;
	key_of(w, w->seg[s0].t, w->seg[s0].d, ch.s);
	cut_of(w, w->seg[s0].t, w->seg[s0].d, L, p);
	if (fwrite(p, sizeof(p), 1, c->pts) != 1)
		return fail(err, errlen, TDC_EIO, "cannot write the contours' points in %s", c->dir);
	ch.n = 1;
	do
	{
		w->state[s] |= 2;
		cut_of(w, w->seg[s].t, w->seg[s].u, L, p);
		if (fwrite(p, sizeof(p), 1, c->pts) != 1)
			return fail(err, errlen, TDC_EIO, "cannot write the contours' points in %s", c->dir);
		ch.n++;
		last = s;
		s = w->succ[s];
	} while (s != NONE && s != s0);
	key_of(w, w->seg[last].t, w->seg[last].u, ch.e);
	c->npts += ch.n;
	if (fwrite(&ch, sizeof(ch), 1, c->chains) != 1)
		return fail(err, errlen, TDC_EIO, "cannot write the contours' chains in %s", c->dir);
	c->nchains++;
	return TDC_OK;
}

/* The window's segments (nseg of them, levels [ka, kb)) made, joined and written. */
static int
do_window(tdc_contour_tiles *c, ct_window *w, size_t ntri, int64_t kb, size_t nseg,
		  char *err, size_t errlen)
{
	size_t		cap = 16;
	int			rc = TDC_OK;

	while (cap < 2 * nseg)
		cap *= 2;
	w->mask = cap - 1;
	w->nseg = 0;
	w->seg = malloc(nseg * sizeof(ct_seg) + 1);
	w->slot = calloc(cap, sizeof(uint32_t));
	w->succ = malloc(nseg * sizeof(uint32_t) + 1);
	w->state = calloc(nseg + 1, 1);
	if (!w->seg || !w->slot || !w->succ || !w->state)
	{
		rc = fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for a tile's contour segments");
		goto done;
	}
	for (size_t t = 0; t < ntri; t++)
	{
		const size_t *v = w->tri + 3 * t;
		int64_t		klo,
					khi;

		tri_levels(c, w->q, w->kv, v, &klo, &khi);
		if (klo < w->ka)
			klo = w->ka;
		if (khi > kb - 1)
			khi = kb - 1;
		for (int64_t k = klo; k <= khi; k++)
		{
			double		L = tin_level(c->base, c->interval, k);
			ct_seg		sg = {.t = (uint32_t) t, .kk = (uint32_t) (k - w->ka)};
			size_t		a,
						b;

			for (int e = 0; e < 3; e++)
			{
				bool		ao = w->qz[v[e]] >= L,
							ad = w->qz[v[(e + 1) % 3]] >= L;

				if (ao && !ad)
					sg.d = (uint8_t) e;
				else if (!ao && ad)
					sg.u = (uint8_t) e;
			}
			w->seg[w->nseg] = sg;
			edge_of(w, sg.t, sg.d, &a, &b);
			for (size_t i = hash_of(a, b, sg.kk) & w->mask;; i = (i + 1) & w->mask)
				if (w->slot[i] == 0)
				{
					w->slot[i] = (uint32_t) (w->nseg + 1);
					break;
				}
			w->nseg++;
		}
	}
	/* each segment's successor in the tile, across its up edge */
	for (size_t s = 0; s < w->nseg; s++)
	{
		size_t		a,
					b;

		edge_of(w, w->seg[s].t, w->seg[s].u, &a, &b);
		w->succ[s] = find_down(w, a, b, w->seg[s].kk);
		if (w->succ[s] != NONE)
			w->state[w->succ[s]] |= 1;
	}
	/* chains from their starts, then the rings within the tile */
	pthread_mutex_lock(&c->mu);
	for (int pass = 0; pass < 2 && rc == TDC_OK; pass++)
		for (size_t s = 0; s < w->nseg && rc == TDC_OK; s++)
			if (!(w->state[s] & 2) && (pass == 1 || !(w->state[s] & 1)))
				rc = write_chain(c, w, (uint32_t) s, err, errlen);
	pthread_mutex_unlock(&c->mu);
done:
	free(w->seg);
	free(w->slot);
	free(w->succ);
	free(w->state);
	w->seg = NULL;
	w->slot = NULL;
	w->succ = NULL;
	w->state = NULL;
	return rc;
}

int
tdc_contour_tiles_tile(tdc_contour_tiles *c, const double *q, const double *qz, const size_t *tri,
					   size_t ntri, char *err, size_t errlen)
{
	ct_window	w = {.q = q, .qz = qz, .tri = tri};
	double		zlo = INFINITY,
				zhi = -INFINITY;
	int64_t		kmin,
				kmax,
			   *kv;
	size_t		cap = ntri > CT_SEG_MIN ? ntri : CT_SEG_MIN,
				nv = 0,
			   *hist;
	bool		too_fine;
	int			rc = TDC_OK;

	if (ntri == 0)
		return TDC_OK;
	if (ntri >= UINT32_MAX)
		return fail(err, errlen, TDC_EINVAL, "%s", "a tile of 2^32 triangles or more");
	for (size_t i = 0; i < 3 * ntri; i++)
	{
		zlo = fmin(zlo, qz[tri[i]]);
		zhi = fmax(zhi, qz[tri[i]]);
		nv = tri[i] >= nv ? tri[i] + 1 : nv;
	}
	too_fine = tin_levels_check(c->interval, c->base, zlo, zhi, NULL, 0) != TDC_OK;
	pthread_mutex_lock(&c->mu);
	c->zmin = fmin(c->zmin, zlo);
	c->zmax = fmax(c->zmax, zhi);
	c->ntri += ntri;
	/* the run's check reports it (contour_join.c) */
	too_fine = c->too_fine = c->too_fine || too_fine;
	pthread_mutex_unlock(&c->mu);
	if (too_fine)
		return TDC_OK;
	kmin = tin_k_above(c->base, c->interval, zlo);
	kmax = tin_k_above(c->base, c->interval, zhi) - 1;
	hist = malloc(CT_HIST * sizeof(size_t));
	kv = malloc(nv * sizeof(int64_t));
	if (hist == NULL || kv == NULL)
	{
		free(hist);
		free(kv);
		return fail(err, errlen, TDC_ENOMEM, "%s", "out of memory for a tile's contour levels");
	}
	/* every vertex's level, once (indices no triangle names get one too: harmless) */
	for (size_t i = 0; i < nv; i++)
		kv[i] = tin_k_above(c->base, c->interval, qz[i]);
	w.kv = kv;
	for (int64_t ka = kmin; ka <= kmax && rc == TDC_OK; ka += CT_HIST)
	{
		size_t		nh = kmax - ka + 1 < CT_HIST ? (size_t) (kmax - ka + 1) : CT_HIST;

		memset(hist, 0, nh * sizeof(size_t));
		for (size_t t = 0; t < ntri; t++)
		{
			int64_t		klo,
						khi;

			tri_levels(c, q, kv, tri + 3 * t, &klo, &khi);
			for (int64_t k = klo > ka ? klo : ka; k <= khi && k < ka + (int64_t) nh; k++)
				hist[k - ka]++;
		}
		/* windows of consecutive levels, each within cap segments (or one level) */
		for (size_t h0 = 0; h0 < nh && rc == TDC_OK;)
		{
			size_t		h1 = h0 + 1,
						sum = hist[h0];

			while (h1 < nh && sum + hist[h1] <= cap)
				sum += hist[h1++];
			if (sum > 0)
			{
				w.ka = ka + (int64_t) h0;
				rc = do_window(c, &w, ntri, ka + (int64_t) h1, sum, err, errlen);
			}
			h0 = h1;
		}
	}
	free(hist);
	free(kv);
	return rc;
}

void
tdc_contour_tiles_free(tdc_contour_tiles *c)
{
	if (c == NULL)
		return;
	if (c->pts)
		fclose(c->pts);
	if (c->chains)
		fclose(c->chains);
	if (c->pts_fd >= 0)
		close(c->pts_fd);
	if (c->chain_fd >= 0)
		close(c->chain_fd);
	free(c->pts_buf);
	free(c->chain_buf);
	pthread_mutex_destroy(&c->mu);
	free(c);
}
