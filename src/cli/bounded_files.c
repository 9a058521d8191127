/*
 * bounded_files.c
 *		The files of a bounded run: its temporary directory, the .bin
 *		source read in chunks, and the tile and halo files written in
 *		buffered records and read back across their parts.
 */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bounded.h"

char		tmp_dir[4096];

/* tmp_dir := a new directory under base; removed at exit */
void
tmp_create(const char *base)
{
	snprintf(tmp_dir, sizeof(tmp_dir), "%s/tdc.XXXXXX", base);
	if (mkdtemp(tmp_dir) == NULL)
	{
		tmp_dir[0] = '\0';
		die(1, "cannot create a temporary directory in %s", base);
	}
	atexit(tmp_cleanup);
}

void
tmp_cleanup(void)
{
	DIR		   *d;
	struct dirent *e;

	if (tmp_dir[0] == '\0')
		return;
	if ((d = opendir(tmp_dir)) != NULL)
	{
		while ((e = readdir(d)) != NULL)
		{
			char		p[4400];

			if (e->d_name[0] == '.')
				continue;
			snprintf(p, sizeof(p), "%s/%s", tmp_dir, e->d_name);
			unlink(p);
		}
		closedir(d);
	}
	rmdir(tmp_dir);
	tmp_dir[0] = '\0';
}

FILE *
tmp_open(const char *name, const char *mode)
{
	char		p[4400];
	FILE	   *f;

	snprintf(p, sizeof(p), "%s/%s", tmp_dir, name);
	f = fopen(p, mode);
	if (f == NULL)
		die(1, "cannot open temporary file %s", p);
	return f;
}

void
source_open(source *s, const char *xypath, const char *zpath)
{
	s->fxy = fopen(xypath, "rb");
	s->fz = zpath ? fopen(zpath, "rb") : NULL;
	if (s->fxy == NULL || (zpath && s->fz == NULL))
		die(1, "cannot open %s", xypath);
	s->xy = malloc(16 * (size_t) CHUNK);
	s->z = zpath ? malloc(8 * (size_t) CHUNK) : NULL;
	if (s->xy == NULL || (zpath && s->z == NULL))
		die(1, "out of memory%s", "");
	s->left = SIZE_MAX;
}

/* Read only the points [from, from + count) from now on. */
void
source_range(source *s, size_t from, size_t count)
{
	if (fseeko(s->fxy, (off_t) from * 16, SEEK_SET) != 0 ||
		(s->fz && fseeko(s->fz, (off_t) from * 8, SEEK_SET) != 0))
		die(1, "cannot seek in the input%s", "");
	s->left = count;
}

size_t
source_read(source *s)
{
	size_t		k = fread(s->xy, 16, s->left < CHUNK ? s->left : CHUNK, s->fxy);

	s->left -= k;
	if (s->fz && fread(s->z, 8, k, s->fz) != k)
		die(1, "short read on the temporary z file%s", "");
	return k;
}

void
source_close(source *s)
{
	fclose(s->fxy);
	if (s->fz)
		fclose(s->fz);
	free(s->xy);
	free(s->z);
}

/*
 * Tile t's file of a kind ("tile": its own points, "halo": the others of
 * its first region) written by binning part `part`: the parts hold
 * consecutive ranges of the input, so read one after the other they keep
 * input order.  ("cell": its own points in cell order, one part,
 * bounded_cells.c.)
 */
FILE *
part_file(const char *kind, int t, int part, const char *mode)
{
	char		name[48];

	snprintf(name, sizeof(name), "%s%d.%d", kind, t, part);
	return tmp_open(name, mode);
}

/* That file removed: its space back as soon as it is not needed. */
void
tmp_remove(const char *kind, int t, int part)
{
	char		p[4400];

	snprintf(p, sizeof(p), "%s/%s%d.%d", tmp_dir, kind, t, part);
	if (unlink(p) != 0)
		die(1, "cannot remove temporary file %s", p);
}

void
rec_open(recfile *r, const char *kind, int t, int part, size_t cap)
{
	r->f = part_file(kind, t, part, "wb");
	r->buf = malloc(8 * cap);
	r->cap = cap;
	r->len = 0;
	r->count = 0;
	if (r->buf == NULL)
		die(1, "out of memory%s", "");
}

void
rec_flush(recfile *r)
{
	if (r->len > 0 && fwrite(r->buf, 8, r->len, r->f) != r->len)
		die(1, "cannot write temporary files in %s", tmp_dir);
	r->len = 0;
}

void
rec_close(recfile *r)
{
	if (r->f == NULL)
		return;
	rec_flush(r);
	if (fclose(r->f) != 0)
		die(1, "cannot write temporary files in %s (disk full?)", tmp_dir);
	free(r->buf);
	r->f = NULL;
	r->buf = NULL;
}

void
mr_open(mreader *m, const char *kind, int t, int nparts)
{
	m->kind = kind;
	m->t = t;
	m->part = 0;
	m->nparts = nparts;
	m->f = part_file(kind, t, 0, "rb");
}

/* Up to count whole records of size bytes; 0 at the end of the last part. */
size_t
mr_read(mreader *m, void *buf, size_t size, size_t count)
{
	size_t		got;

	while ((got = fread(buf, size, count, m->f)) == 0 && m->part + 1 < m->nparts)
	{
		fclose(m->f);
		m->f = part_file(m->kind, m->t, ++m->part, "rb");
	}
	return got;
}

void
mr_close(mreader *m)
{
	fclose(m->f);
}

/* Read exactly k records of w doubles of tile t's file of a kind into buf. */
void
read_all(const char *kind, int t, int nparts, double *buf, size_t k, int w)
{
	mreader		m;
	size_t		at = 0,
				got;

	mr_open(&m, kind, t, nparts);
	while (at < k && (got = mr_read(&m, buf + w * at, 8 * (size_t) w, k - at)) > 0)
		at += got;
	mr_close(&m);
	if (at != k)
		die(1, "short read on a temporary file in %s", tmp_dir);
}
