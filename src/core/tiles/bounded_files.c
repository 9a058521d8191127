/*
 * bounded_files.c
 *		The files of a bounded run and how it fails: the .bin source read
 *		in chunks, the tile and halo files written in buffered records and
 *		read back across their parts, all in the caller's temporary
 *		directory; and the first error of a run or of one of its threads.
 *
 * The caller owns the directory; the run creates its files there under
 * names of its own ("tile", "halo" and "cell", the tile and the part:
 * tile3.1) and removes every one of them before it returns, on success or
 * on error (tdc_bd_remove_all), so a caller may keep files of its own
 * there (./tdc keeps its staged text input).
 *
 * An error is kept once, the first, with its message (tdc_bd_fail), and
 * is sticky: a source read after it gives no points, a record file drops
 * its records and a reader reads nothing, so the loops of the passes end
 * by themselves and their callers look at the error once, after them.
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bounded_int.h"

/* Keep the first error: code and message.  Returns the first error's code. */
int
tdc_bd_fail(bd_err *e, int code, const char *fmt,...)
{
	va_list		ap;

	if (e->code != TDC_OK)
		return e->code;
	e->code = code;
	va_start(ap, fmt);
	vsnprintf(e->msg, sizeof(e->msg), fmt, ap);
	va_end(ap);
	return code;
}

int
tdc_bd_nomem(bd_err *e)
{
	return tdc_bd_fail(e, TDC_ENOMEM, "out of memory");
}

/*
 * Has the caller asked the run to stop?  Another thread sets the flag (a
 * host's, or tdc_bounded_cancel): read atomically.
 */
bool
tdc_bd_canceled(const volatile int *cancel)
{
	return cancel != NULL && __atomic_load_n(cancel, __ATOMIC_RELAXED) != 0;
}

/* s->xy (and s->z, s->l) of CHUNK points; reads from the start of the files. */
int
tdc_bd_source_open(source *s, const char *xypath, const char *zpath, const char *lpath, bd_err *e,
				   const volatile int *cancel)
{
	memset(s, 0, sizeof(*s));
	s->e = e;
	s->cancel = cancel;
	s->fxy = fopen(xypath, "rb");
	s->fz = zpath ? fopen(zpath, "rb") : NULL;
	s->fl = lpath ? fopen(lpath, "rb") : NULL;
	if (s->fxy == NULL || (zpath && s->fz == NULL) || (lpath && s->fl == NULL))
	{
		tdc_bd_source_close(s);
		return tdc_bd_fail(e, TDC_EIO, "cannot open %s",
						   s->fxy == NULL ? xypath : zpath && s->fz == NULL ? zpath : lpath);
	}
	s->xy = malloc(16 * (size_t) CHUNK);
	s->z = zpath ? malloc(8 * (size_t) CHUNK) : NULL;
	s->l = lpath ? malloc(8 * (size_t) CHUNK) : NULL;
	if (s->xy == NULL || (zpath && s->z == NULL) || (lpath && s->l == NULL))
	{
		tdc_bd_source_close(s);
		return tdc_bd_nomem(e);
	}
	s->left = SIZE_MAX;
	return TDC_OK;
}

/* Read only the points [from, from + count) from now on. */
int
tdc_bd_source_range(source *s, size_t from, size_t count)
{
	if (fseeko(s->fxy, (off_t) from * 16, SEEK_SET) != 0 ||
		(s->fz && fseeko(s->fz, (off_t) from * 8, SEEK_SET) != 0) ||
		(s->fl && fseeko(s->fl, (off_t) from * 8, SEEK_SET) != 0))
	{
		s->left = 0;
		return tdc_bd_fail(s->e, TDC_EIO, "cannot seek in the input");
	}
	s->left = count;
	return TDC_OK;
}

/*
 * The next chunk: its number of points, 0 at the end, after an error of
 * this source's (a failed read, or any earlier one) or once the caller
 * asks the run to stop.
 */
size_t
tdc_bd_source_read(source *s)
{
	size_t		k;

	if (s->e->code != TDC_OK)
		return 0;
	if (tdc_bd_canceled(s->cancel))
	{
		tdc_bd_fail(s->e, TDC_ECANCELED, "canceled");
		return 0;
	}
	k = fread(s->xy, 16, s->left < CHUNK ? s->left : CHUNK, s->fxy);
	s->left -= k;
	if (s->fz && fread(s->z, 8, k, s->fz) != k)
	{
		tdc_bd_fail(s->e, TDC_EIO, "short read on the temporary z file");
		return 0;
	}
	if (s->fl && fread(s->l, 8, k, s->fl) != k)
	{
		tdc_bd_fail(s->e, TDC_EIO, "short read on the temporary label file");
		return 0;
	}
	return k;
}

void
tdc_bd_source_close(source *s)
{
	if (s->fxy)
		fclose(s->fxy);
	if (s->fz)
		fclose(s->fz);
	if (s->fl)
		fclose(s->fl);
	free(s->xy);
	free(s->z);
	free(s->l);
	s->fxy = s->fz = s->fl = NULL;
	s->xy = s->z = NULL;
	s->l = NULL;
}

/*
 * Tile t's file of a kind ("tile": its own points, "halo": the others of
 * its first region) written by binning part `part`: the parts hold
 * consecutive ranges of the input, so read one after the other they keep
 * input order.  ("cell": its own points in cell order, one part,
 * bounded_cells.c.)  NULL, e set, when it cannot be opened.
 */
FILE *
tdc_bd_part_file(const char *dir, bd_err *e, const char *kind, int t, int part, const char *mode)
{
	char		p[4400];
	FILE	   *f;

	snprintf(p, sizeof(p), "%s/%s%d.%d", dir, kind, t, part);
	f = fopen(p, mode);
	if (f == NULL)
		tdc_bd_fail(e, TDC_EIO, "cannot open temporary file %s", p);
	return f;
}

/* That file removed: its space back as soon as it is not needed. */
int
tdc_bd_remove(const char *dir, bd_err *e, const char *kind, int t, int part)
{
	char		p[4400];

	snprintf(p, sizeof(p), "%s/%s%d.%d", dir, kind, t, part);
	if (unlink(p) != 0)
		return tdc_bd_fail(e, TDC_EIO, "cannot remove temporary file %s", p);
	return TDC_OK;
}

/*
 * Every file a run of nt tiles may have left, removed: the tile and halo
 * files of both binning parts, the cell files.  Those not there are no
 * error.
 */
void
tdc_bd_remove_all(const char *dir, int nt)
{
	static const char *const kinds[3] = {"tile", "halo", "cell"};
	char		p[4400];

	for (int t = 0; t < nt; t++)
		for (int k = 0; k < 3; k++)
			for (int part = 0; part < (k == 2 ? 1 : 2); part++)
			{
				snprintf(p, sizeof(p), "%s/%s%d.%d", dir, kinds[k], t, part);
				(void) unlink(p);
			}
}

int
tdc_bd_rec_open(recfile *r, const char *dir, bd_err *e, const char *kind, int t, int part,
				size_t cap)
{
	r->dir = dir;
	r->e = e;
	r->cap = cap;
	r->len = 0;
	r->count = 0;
	r->buf = NULL;
	r->f = tdc_bd_part_file(dir, e, kind, t, part, "wb");
	if (r->f == NULL)
		return e->code;
	r->buf = malloc(8 * cap);
	if (r->buf == NULL)
	{
		fclose(r->f);
		r->f = NULL;
		return tdc_bd_nomem(e);
	}
	return TDC_OK;
}

void
tdc_bd_rec_flush(recfile *r)
{
	if (r->len > 0 && r->e->code == TDC_OK && fwrite(r->buf, 8, r->len, r->f) != r->len)
		tdc_bd_fail(r->e, TDC_EIO, "cannot write temporary files in %s", r->dir);
	r->len = 0;
}

/* Flushed, closed and its buffer freed; a record file never opened is left alone. */
int
tdc_bd_rec_close(recfile *r)
{
	if (r->f == NULL)
		return r->e ? r->e->code : TDC_OK;
	tdc_bd_rec_flush(r);
	if (fclose(r->f) != 0)
		tdc_bd_fail(r->e, TDC_EIO, "cannot write temporary files in %s (disk full?)", r->dir);
	free(r->buf);
	r->f = NULL;
	r->buf = NULL;
	return r->e->code;
}

int
tdc_bd_mr_open(mreader *m, const char *dir, bd_err *e, const char *kind, int t, int nparts)
{
	m->kind = kind;
	m->t = t;
	m->part = 0;
	m->nparts = nparts;
	m->dir = dir;
	m->e = e;
	m->f = tdc_bd_part_file(dir, e, kind, t, 0, "rb");
	return m->f ? TDC_OK : e->code;
}

/* Up to count whole records of size bytes; 0 at the end of the last part, or on an error. */
size_t
tdc_bd_mr_read(mreader *m, void *buf, size_t size, size_t count)
{
	size_t		got;

	if (m->f == NULL)
		return 0;
	while ((got = fread(buf, size, count, m->f)) == 0 && m->part + 1 < m->nparts)
	{
		fclose(m->f);
		m->f = tdc_bd_part_file(m->dir, m->e, m->kind, m->t, ++m->part, "rb");
		if (m->f == NULL)
			return 0;
	}
	return got;
}

void
tdc_bd_mr_close(mreader *m)
{
	if (m->f)
		fclose(m->f);
	m->f = NULL;
}

/* Read exactly k records of w doubles of tile t's file of a kind into buf. */
int
tdc_bd_read_all(const char *dir, bd_err *e, const char *kind, int t, int nparts, double *buf,
				size_t k, int w)
{
	mreader		m;
	size_t		at = 0,
				got;

	if (tdc_bd_mr_open(&m, dir, e, kind, t, nparts) != TDC_OK)
		return e->code;
	while (at < k && (got = tdc_bd_mr_read(&m, buf + w * at, 8 * (size_t) w, k - at)) > 0)
		at += got;
	tdc_bd_mr_close(&m);
	if (e->code != TDC_OK)
		return e->code;
	if (at != k)
		return tdc_bd_fail(e, TDC_EIO, "short read on a temporary file in %s", dir);
	return TDC_OK;
}
