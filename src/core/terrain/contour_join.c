/*
 * contour_join.c
 *		After the last tile: the chains of contour_tiles.c joined into the
 *		whole TIN's contour lines, each made canonical as tin_contour.c
 *		makes it, and handed out in its order (tdc_contour_tiles_lines).
 *
 * The join.  Every crossing key is the exit of at most one chain and the
 * entry of at most one (an edge has two triangles, and the level goes up
 * through one and down through the other), so the chains, sorted by their
 * entry keys, each find their successor by a binary search on their exit
 * key: the lines are the paths from the chains nothing leads into, and
 * the cycles left over, which are the rings (a ring within one tile is a
 * chain that leads into itself).  A line's raw points are its chains'
 * points in order; where two chains meet the crossing appears twice, the
 * same bits, and goes with the repeats at sites.
 *
 * Canonical as the one-shot's.  tin_contour.c walks a line from a
 * segment its numbering happens to reach first; its output does not
 * depend on that, and these rules are applied here to the same raw
 * points: consecutive repeats dropped; an open line as walked, from the
 * end with the higher ground on its left; fewer than two distinct points
 * (a peak at the level) is no line; a ring (its closing repeat kept) of
 * fewer than three points is none, else it starts at the rotation whose
 * points come first in (x, y) order.  A ring's repeats dropped from any
 * start leave the same cycle, so its rotation is the same.  Then a
 * level's lines are sorted by their points (the one-shot's comparison:
 * point by point in (x, y) order, then the shorter first), the levels
 * increasing.
 *
 * Memory.  The chain records (88 bytes each, plus 41 of indexes and line) and then
 * one level's points at a time must fit in max_bytes: else TDC_EMEMLIMIT
 * with the numbers.  The points are read back from the points file chain
 * by chain, level by level.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "contour_tiles.h"
#include "tin/tin_cut.h"

#define NONE		UINT32_MAX

/* A line: its first chain, whether it closes, and its points' place in the level's array. */
typedef struct ct_line
{
	int64_t		k;
	uint32_t	head;
	bool		closed;
	size_t		first,
				n;
} ct_line;

typedef struct ct_join
{
	ct_chain   *ch;
	size_t		nch;
	uint32_t   *by_entry;		/* chain indexes sorted by entry key */
	uint32_t   *succ;
	uint8_t    *state;			/* bit 0: led into; bit 1: taken */
	ct_line    *line;
	size_t		nline;
} ct_join;

static int
key_cmp(int64_t ka, const double *a, int64_t kb, const double *b)
{
	if (ka != kb)
		return ka < kb ? -1 : 1;
	for (int i = 0; i < 4; i++)
		if (a[i] != b[i])
			return a[i] < b[i] ? -1 : 1;
	return 0;
}

static int
cmp_entry(const void *x, const void *y, void *arg)
{
	const ct_chain *ch = arg,
			   *a = ch + *(const uint32_t *) x,
			   *b = ch + *(const uint32_t *) y;

	return key_cmp(a->k, a->s, b->k, b->s);
}

/* The chain entered at key (k, e), or NONE. */
static uint32_t
find_entry(const ct_join *j, int64_t k, const double *e)
{
	size_t		lo = 0,
				hi = j->nch;

	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo) / 2;
		const ct_chain *m = j->ch + j->by_entry[mid];
		int			c = key_cmp(m->k, m->s, k, e);

		if (c == 0)
			return j->by_entry[mid];
		if (c < 0)
			lo = mid + 1;
		else
			hi = mid;
	}
	return NONE;
}

static int
cmp_line_level(const void *x, const void *y)
{
	const ct_line *a = x,
			   *b = y;

	return a->k < b->k ? -1 : a->k > b->k ? 1 : a->head < b->head ? -1 : a->head > b->head;
}

/* Two lines of a level by their points (tin_contour.c's order, tin_cut.c's comparison). */
static int
cmp_line_pts(const void *x, const void *y, void *arg)
{
	const double *xy = arg;
	const ct_line *a = x,
			   *b = y;

	return tin_line_cmp(xy + 2 * a->first, a->n, xy + 2 * b->first, b->n);
}

static int
read_pts(const tdc_contour_tiles *c, const ct_chain *ch, double *to, char *err, size_t errlen)
{
	size_t		want = (size_t) ch->n * 16;
	off_t		at = (off_t) (ch->off * 16);

	for (size_t got = 0; got < want;)
	{
		ssize_t		k = pread(c->pts_fd, (char *) to + got, want - got, at + (off_t) got);

		if (k <= 0)
		{
			if (err && errlen)
				snprintf(err, errlen, "cannot read the contours' points in %s", c->dir);
			return TDC_EIO;
		}
		got += (size_t) k;
	}
	return TDC_OK;
}

/* The lines of one level (line[0 .. nl)): their points read, made canonical, sorted and handed out. */
static int
do_level(tdc_contour_tiles *c, ct_join *j, ct_line *line, size_t nl, size_t max_bytes,
		 tdc_contour_line_fn fn, void *arg, size_t *nlines, size_t *npoints, char *err, size_t errlen)
{
	size_t		raw = 0,
				at = 0,
				kept = 0;
	double	   *xy,
				L = tin_level(c->base, c->interval, line[0].k);
	int			rc = TDC_OK;

	for (size_t i = 0; i < nl; i++)
	{
		uint32_t	h = line[i].head;

		do
		{
			raw += j->ch[h].n;
			h = j->succ[h];
		} while (h != NONE && h != line[i].head);
	}
	if (raw > max_bytes / 16)
	{
		if (err && errlen)
			snprintf(err, errlen, "the contour lines at level %.17g hold %zu points (%zu MB), more than "
					 "the %zu MB the limit leaves for one level's lines; raise it",
					 L, raw, (raw * 16) >> 20, max_bytes >> 20);
		return TDC_EMEMLIMIT;
	}
	if ((xy = malloc(raw * 16 + 16)) == NULL)
	{
		if (err && errlen)
			snprintf(err, errlen, "out of memory for the contour lines at level %.17g", L);
		return TDC_ENOMEM;
	}
	for (size_t i = 0; i < nl && rc == TDC_OK; i++)
	{
		ct_line    *ln = &line[i];
		uint32_t	h = ln->head;
		size_t		w,
					start = at;

		do
		{
			if ((rc = read_pts(c, &j->ch[h], xy + 2 * at, err, errlen)) != TDC_OK)
				break;
			at += j->ch[h].n;
			h = j->succ[h];
		} while (h != NONE && h != ln->head);
		if (rc != TDC_OK)
			break;
		/* consecutive repeats (chain joins, crossings at a site at the level) go */
		w = start + 1;
		for (size_t i2 = start + 1; i2 < at; i2++)
		{
			if (xy[2 * i2] != xy[2 * (w - 1)] || xy[2 * i2 + 1] != xy[2 * (w - 1) + 1])
			{
				xy[2 * w] = xy[2 * i2];
				xy[2 * w + 1] = xy[2 * i2 + 1];
				w++;
			}
		}
		at = w;
		ln->first = start;
		ln->n = w - start;
		if (ln->n < 2 || (ln->closed && ln->n < 3))
		{
			at = start;			/* a peak at the level: no line */
			continue;
		}
		if (ln->closed)
			tin_ring_canon(xy + 2 * start, ln->n - 1);
		line[kept++] = *ln;
	}
	if (rc == TDC_OK && kept > 1)
		qsort_r(line, kept, sizeof(ct_line), cmp_line_pts, xy);
	for (size_t i = 0; i < kept && rc == TDC_OK; i++)
	{
		if ((rc = fn(arg, L, xy + 2 * line[i].first, line[i].n, line[i].closed)) != 0)
		{
			if (err && errlen)
				snprintf(err, errlen, "the contour lines were not taken (the caller's function returned %d)", rc);
			rc = rc < 0 ? rc : TDC_EINVAL;
			break;
		}
		(*nlines)++;
		*npoints += line[i].n;
	}
	free(xy);
	return rc;
}

static void
join_free(ct_join *j)
{
	free(j->ch);
	free(j->by_entry);
	free(j->succ);
	free(j->state);
	free(j->line);
}

int
tdc_contour_tiles_lines(tdc_contour_tiles *c, size_t max_bytes, tdc_contour_line_fn fn, void *arg,
						const volatile int *cancel, size_t *nlines, size_t *npoints,
						char *err, size_t errlen)
{
	ct_join		j = {0};
	size_t		per = sizeof(ct_chain) + 2 * sizeof(uint32_t) + 1 + sizeof(ct_line),
				need;
	int			rc = TDC_OK;

	*nlines = 0;
	*npoints = 0;
	if (c->ntri == 0)
		return TDC_OK;
	if ((rc = tin_levels_check(c->interval, c->base, c->zmin, c->zmax, err, errlen)) != TDC_OK)
		return rc;
	if (c->too_fine)
	{
		if (err && errlen)
			snprintf(err, errlen, "the contour interval %g is too small for a tile's heights", c->interval);
		return TDC_EINVAL;
	}
	if (fflush(c->pts) != 0 || fflush(c->chains) != 0)
	{
		if (err && errlen)
			snprintf(err, errlen, "cannot write the contours' files in %s", c->dir);
		return TDC_EIO;
	}
	j.nch = (size_t) c->nchains;
	if (j.nch >= NONE)
	{
		if (err && errlen)
			snprintf(err, errlen, "%zu contour chains: more than 2^32 - 1", j.nch);
		return TDC_EINVAL;
	}
	need = j.nch * per;
	if (need > max_bytes)
	{
		if (err && errlen)
			snprintf(err, errlen, "joining the tiles' %zu contour chains needs %zu MB, more than the "
					 "%zu MB the limit leaves after the tiles; raise it", j.nch, need >> 20,
					 max_bytes >> 20);
		return TDC_EMEMLIMIT;
	}
	j.ch = malloc(j.nch * sizeof(ct_chain) + 1);
	j.by_entry = malloc(j.nch * sizeof(uint32_t) + 1);
	j.succ = malloc(j.nch * sizeof(uint32_t) + 1);
	j.state = calloc(j.nch + 1, 1);
	j.line = malloc(j.nch * sizeof(ct_line) + 1);
	if (!j.ch || !j.by_entry || !j.succ || !j.state || !j.line)
	{
		join_free(&j);
		if (err && errlen)
			snprintf(err, errlen, "out of memory for the contours' %zu chains", j.nch);
		return TDC_ENOMEM;
	}
	for (size_t got = 0; got < j.nch * sizeof(ct_chain);)
	{
		ssize_t		k = pread(c->chain_fd, (char *) j.ch + got, j.nch * sizeof(ct_chain) - got,
							  (off_t) got);

		if (k <= 0)
		{
			join_free(&j);
			if (err && errlen)
				snprintf(err, errlen, "cannot read the contours' chains in %s", c->dir);
			return TDC_EIO;
		}
		got += (size_t) k;
	}
	for (size_t i = 0; i < j.nch; i++)
		j.by_entry[i] = (uint32_t) i;
	qsort_r(j.by_entry, j.nch, sizeof(uint32_t), cmp_entry, j.ch);
	for (size_t i = 0; i < j.nch; i++)
	{
		j.succ[i] = find_entry(&j, j.ch[i].k, j.ch[i].e);
		if (j.succ[i] != NONE)
			j.state[j.succ[i]] |= 1;
	}
	/* the open lines from their first chains, then the rings */
	for (int pass = 0; pass < 2; pass++)
		for (size_t i = 0; i < j.nch; i++)
			if (!(j.state[i] & 2) && (pass == 1 || !(j.state[i] & 1)))
			{
				uint32_t	h = (uint32_t) i;

				j.line[j.nline++] = (ct_line) {.k = j.ch[i].k, .head = h, .closed = pass == 1};
				do
				{
					j.state[h] |= 2;
					h = j.succ[h];
				} while (h != NONE && h != i);
			}
	qsort(j.line, j.nline, sizeof(ct_line), cmp_line_level);
	for (size_t a = 0, b; a < j.nline && rc == TDC_OK; a = b)
	{
		for (b = a + 1; b < j.nline && j.line[b].k == j.line[a].k; b++)
			;
		if (cancel && *cancel)
		{
			if (err && errlen)
				snprintf(err, errlen, "canceled");
			rc = TDC_ECANCELED;
			break;
		}
		rc = do_level(c, &j, j.line + a, b - a, max_bytes - need, fn, arg, nlines, npoints, err, errlen);
	}
	join_free(&j);
	return rc;
}
