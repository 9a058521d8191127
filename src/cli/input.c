/*
 * input.c
 *		Reading ./tdc's INPUT: a LAS file (.las, read by las.c, its points
 *		of the --class values), a .xyz.bin file of little-endian float64
 *		x,y,z triples, a .bin file of float64 x,y pairs, or any other file
 *		(or - for stdin) of text lines "x y" or "x y z"; and the --segments
 *		file of lines "i j".  Every error dies with the file's name or the
 *		line's number.
 *
 * Into memory for the one-shot run (read_input), or, for --max-memory,
 * staged as the bounded run reads its input: x,y pairs in one file and z in
 * another (text_to_bin, las_to_bin, xyz_bin_to_bin), in batches, so that
 * the input is never held whole (LAS and .xyz.bin: read and written on
 * two threads, stage_run).  A .bin file of pairs is its own stage.
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* Points per batch when staging LAS or .xyz.bin input: 768 KB of doubles */
#define STAGE_BATCH 32768

/* INPUT is read as a .bin file when its name ends in .bin */
bool
is_bin_path(const char *path)
{
	size_t		a = strlen(path),
				b = strlen(".bin");

	return a >= b && strcmp(path + a - b, ".bin") == 0;
}

/* ... and as float64 x,y,z triples when it ends in .xyz.bin */
bool
is_xyz_bin_path(const char *path)
{
	size_t		a = strlen(path),
				b = strlen(".xyz.bin");

	return a >= b && strcmp(path + a - b, ".xyz.bin") == 0;
}

/* The size of a .xyz.bin file in triples; dies unless a whole number of them */
static size_t
xyz_bin_count(const char *path, FILE *f)
{
	long		size;

	if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0)
		die(1, "cannot read %s", path);
	if (size % 24 != 0)
		die(1, "%s: size is not a multiple of 24 bytes (x,y,z float64 triples)", path);
	return (size_t) size / 24;
}

/*
 * Up to max triples of f (a multiple of 1024) into xy (pairs) and z;
 * returns how many, 0 at the end.
 */
static size_t
xyz_bin_batch(const char *path, FILE *f, double *xy, double *z, size_t max)
{
	double		t[3 * 1024];
	size_t		m = 0,
				k;

	while (m < max && (k = fread(t, 24, 1024, f)) > 0)
	{
		for (size_t i = 0; i < k; i++, m++)
		{
			xy[2 * m] = t[3 * i];
			xy[2 * m + 1] = t[3 * i + 1];
			z[m] = t[3 * i + 2];
		}
	}
	if (ferror(f))
		die(1, "short read on %s", path);
	return m;
}

static void
read_xyz_bin(const char *path, cli_input *in)
{
	FILE	   *f = fopen(path, "rb");
	size_t		m,
				k = 0;

	if (f == NULL)
		die(1, "cannot open %s", path);
	in->n = xyz_bin_count(path, f);
	/* whole blocks of 1024: the last one may run past n */
	in->xy = malloc(16 * (in->n + 1024));
	in->z = malloc(8 * (in->n + 1024));
	if (in->xy == NULL || in->z == NULL)
		die(1, "out of memory reading %s", path);
	while (k < in->n && (m = xyz_bin_batch(path, f, in->xy + 2 * k, in->z + k, 1024)) > 0)
		k += m;
	if (k != in->n)
		die(1, "short read on %s", path);
	fclose(f);
}

/* A LAS file into memory: the points of the --class values, its CRS */
static void
read_las(const cli_args *a, cli_input *in)
{
	las_file	lf;
	size_t		k;
	const unsigned char *keep = a->has_class ? a->class_keep : NULL;

	las_open(a->input, &lf);
	if (lf.n > SIZE_MAX / 16 - 1)
		die(1, "%s: too many points for this machine", a->input);
	in->xy = malloc(16 * (size_t) lf.n + 16);
	in->z = malloc(8 * (size_t) lf.n + 8);
	if (in->xy == NULL || in->z == NULL)
		die(1, "out of memory reading %s", a->input);
	while (las_next(&lf, keep, in->xy + 2 * lf.kept, in->z + lf.kept, SIZE_MAX, &k))
		;
	in->n = (size_t) lf.kept;
	in->srs = lf.srs;
	if (a->stats)
		las_report(&lf);
	las_close(&lf);
}

double *
read_bin(const char *path, size_t *n)
{
	FILE	   *f = fopen(path, "rb");
	long		size;
	double	   *xy;

	if (f == NULL)
		die(1, "cannot open %s", path);
	if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0)
		die(1, "cannot read %s", path);
	if (size % 16 != 0)
		die(1, "%s: size is not a multiple of 16 bytes (x,y float64 pairs)", path);
	*n = (size_t) size / 16;
	xy = malloc((size_t) size + 16);
	if (xy == NULL)
		die(1, "out of memory reading %s", path);
	if (fread(xy, 16, *n, f) != *n)
		die(1, "short read on %s", path);
	fclose(f);
	return xy;
}

/*
 * Parse one text line into v: returns the number of values (0 for a blank
 * or comment line), dies on garbage.  *dims is the line width seen so far.
 */
int
parse_line(char *line, size_t lineno, double v[3], int *dims)
{
	int			k = 0;
	char	   *p = line,
			   *end;

	while (k < 4)
	{
		while (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r' || *p == '\n')
			p++;
		if (*p == '\0' || *p == '#')
			break;
		if (k == 3)
		{
			k = 4;
			break;
		}
		v[k] = strtod(p, &end);
		if (end == p)
		{
			char		msg[64];

			snprintf(msg, sizeof(msg), "%zu", lineno);
			die(1, "line %s: expected numbers 'x y' or 'x y z'", msg);
		}
		p = end;
		k++;
	}
	if (k == 0)
		return 0;
	if (k == 1 || k == 4 || (*dims && k != *dims))
	{
		char		msg[64];

		snprintf(msg, sizeof(msg), "%zu", lineno);
		die(1, "line %s: every line must hold 'x y' or every line 'x y z'", msg);
	}
	*dims = k;
	return k;
}

static double *
read_text(const char *path, size_t *n, double **zout)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
	char	   *line = NULL;
	size_t		cap = 0,
				alloc = 1024,
				lineno = 0;
	int			dims = 0;
	double	   *xy = malloc(alloc * 2 * sizeof(double)),
			   *z = NULL;

	if (f == NULL)
		die(1, "cannot open %s", path);
	*n = 0;
	while (getline(&line, &cap, f) >= 0)
	{
		double		v[3];

		if (parse_line(line, ++lineno, v, &dims) == 0)
			continue;
		if (*n == alloc)
		{
			alloc *= 2;
			xy = realloc(xy, alloc * 2 * sizeof(double));
			if (dims == 3)
				z = realloc(z, alloc * sizeof(double));
		}
		if (dims == 3 && z == NULL)
			z = malloc(alloc * sizeof(double));
		if (xy == NULL || (dims == 3 && z == NULL))
			die(1, "out of memory reading %s", path);
		xy[2 * *n] = v[0];
		xy[2 * *n + 1] = v[1];
		if (dims == 3)
			z[*n] = v[2];
		(*n)++;
	}
	free(line);
	if (f != stdin)
		fclose(f);
	*zout = z;
	return xy;
}

/* INPUT into memory: in->xy, in->n and, for input with z, in->z; for LAS in->srs */
void
read_input(const cli_args *a, cli_input *in)
{
	in->z = NULL;
	in->srs = NULL;
	if (is_las_path(a->input))
		read_las(a, in);
	else if (is_xyz_bin_path(a->input))
		read_xyz_bin(a->input, in);
	else
		in->xy = is_bin_path(a->input) ? read_bin(a->input, &in->n) : read_text(a->input, &in->n, &in->z);
}

/* Segment file: lines "i j"; every index must be below n. */
uint32_t *
read_segments(const char *path, size_t n, size_t *k)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
	size_t		cap = 1024;
	uint32_t   *seg = malloc(cap * 2 * sizeof(uint32_t));
	unsigned long long a,
				b;
	int			got;

	if (f == NULL)
		die(1, "cannot read %s", path);
	if (seg == NULL)
		die(1, "out of memory for %s", path);
	*k = 0;
	while ((got = fscanf(f, "%llu %llu", &a, &b)) == 2)
	{
		if (a >= n || b >= n)
			die(1, "segment index beyond the input's points in %s", path);
		if (*k == cap)
		{
			seg = realloc(seg, (cap *= 2) * 2 * sizeof(uint32_t));
			if (seg == NULL)
				die(1, "out of memory for %s", path);
		}
		seg[2 * *k] = (uint32_t) a;
		seg[2 * *k + 1] = (uint32_t) b;
		(*k)++;
	}
	if (got != EOF)
		die(1, "%s: lines must be two point indices 'i j'", path);
	if (f != stdin)
		fclose(f);
	return seg;
}

/* Text input to tmp_dir/input.xy (+ input.z): returns n, sets *has_z. */
size_t
text_to_bin(const char *path, int *has_z)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r"),
			   *fxy,
			   *fz = NULL;
	char	   *line = NULL;
	size_t		cap = 0,
				lineno = 0,
				n = 0;
	int			dims = 0;

	if (f == NULL)
		die(1, "cannot open %s", path);
	fxy = tmp_open("input.xy", "wb");
	while (getline(&line, &cap, f) >= 0)
	{
		double		v[3];

		if (parse_line(line, ++lineno, v, &dims) == 0)
			continue;
		if (dims == 3 && fz == NULL)
		{
			if (n > 0)
				die(1, "line %s: every line must hold 'x y' or every line 'x y z'", "1");
			fz = tmp_open("input.z", "wb");
		}
		if (fwrite(v, 8, 2, fxy) != 2 || (fz && fwrite(v + 2, 8, 1, fz) != 1))
			die(1, "cannot write temporary files in %s", tmp_dir);
		n++;
	}
	free(line);
	if (f != stdin)
		fclose(f);
	if (fclose(fxy) != 0 || (fz && fclose(fz) != 0))
		die(1, "cannot write temporary files in %s", tmp_dir);
	*has_z = fz != NULL;
	return n;
}

/*
 * The staging of LAS and .xyz.bin input, on two threads: this one reads
 * and decodes a batch while the writer writes the one before to
 * tmp_dir/input.xy and input.z.  Both sides are copies through the page
 * cache as much as work, so a billion-point file stages in about half the
 * time of one thread.  The batches keep their order, so the staged files
 * are those of one thread, byte for byte.
 */
typedef struct stage_pipe
{
	pthread_mutex_t mu;
	pthread_cond_t cv;
	double	   *xy[2],
			   *z[2];
	size_t		k[2];
	bool		full[2],		/* batch i read, not yet written */
				end,			/* no batch follows */
				failed;			/* a write failed: the reader stops */
	FILE	   *fxy,
			   *fz;
} stage_pipe;

static void *
stage_writer(void *arg)
{
	stage_pipe *sp = arg;

	for (int i = 0;; i ^= 1)
	{
		bool		ok;

		pthread_mutex_lock(&sp->mu);
		while (!sp->full[i] && !sp->end)
			pthread_cond_wait(&sp->cv, &sp->mu);
		if (!sp->full[i])
		{
			pthread_mutex_unlock(&sp->mu);
			return NULL;
		}
		pthread_mutex_unlock(&sp->mu);
		ok = fwrite(sp->xy[i], 16, sp->k[i], sp->fxy) == sp->k[i] &&
			fwrite(sp->z[i], 8, sp->k[i], sp->fz) == sp->k[i];
		pthread_mutex_lock(&sp->mu);
		sp->full[i] = false;
		sp->failed |= !ok;
		pthread_cond_broadcast(&sp->cv);
		pthread_mutex_unlock(&sp->mu);
		if (!ok)
			return NULL;
	}
}

/*
 * Stage the batches that next (arg) reads, at most STAGE_BATCH points each,
 * until it returns false; returns the points staged.  Dies on errors.
 */
static size_t
stage_run(bool (*next) (void *arg, double *xy, double *z, size_t max, size_t *k), void *arg)
{
	stage_pipe	sp = {.fxy = tmp_open("input.xy", "wb"), .fz = tmp_open("input.z", "wb")};
	pthread_t	th;
	size_t		total = 0;
	bool		more = true;

	pthread_mutex_init(&sp.mu, NULL);
	pthread_cond_init(&sp.cv, NULL);
	for (int i = 0; i < 2; i++)
	{
		sp.xy[i] = malloc(16 * STAGE_BATCH);
		sp.z[i] = malloc(8 * STAGE_BATCH);
		if (sp.xy[i] == NULL || sp.z[i] == NULL)
			die(1, "out of memory staging the input in %s", tmp_dir);
	}
	if (pthread_create(&th, NULL, stage_writer, &sp) != 0)
		die(1, "cannot start a thread to stage the input in %s", tmp_dir);
	for (int i = 0; more; i ^= 1)
	{
		size_t		k = 0;

		pthread_mutex_lock(&sp.mu);
		while (sp.full[i] && !sp.failed)
			pthread_cond_wait(&sp.cv, &sp.mu);
		pthread_mutex_unlock(&sp.mu);
		if (sp.failed)
			break;
		/* a bad file dies here, and the exit removes tmp_dir under the writer */
		more = next(arg, sp.xy[i], sp.z[i], STAGE_BATCH, &k);
		if (k == 0)
			continue;
		total += k;
		pthread_mutex_lock(&sp.mu);
		sp.k[i] = k;
		sp.full[i] = true;
		pthread_cond_broadcast(&sp.cv);
		pthread_mutex_unlock(&sp.mu);
	}
	pthread_mutex_lock(&sp.mu);
	sp.end = true;
	pthread_cond_broadcast(&sp.cv);
	pthread_mutex_unlock(&sp.mu);
	pthread_join(th, NULL);
	for (int i = 0; i < 2; i++)
	{
		free(sp.xy[i]);
		free(sp.z[i]);
	}
	if (sp.failed | (fclose(sp.fxy) != 0) | (fclose(sp.fz) != 0))
		die(1, "cannot write temporary files in %s", tmp_dir);
	return total;
}

/*
 * LAS input (a->input) to tmp_dir/input.xy + input.z, the points of the
 * --class values, in batches: returns their number, sets *srs.
 */
typedef struct las_stage
{
	las_file	lf;
	const unsigned char *keep;
} las_stage;

static bool
las_batch(void *arg, double *xy, double *z, size_t max, size_t *k)
{
	las_stage  *ls = arg;

	return las_next(&ls->lf, ls->keep, xy, z, max, k);
}

size_t
las_to_bin(const cli_args *a, char **srs)
{
	las_stage	ls = {.keep = a->has_class ? a->class_keep : NULL};
	las_file   *lf = &ls.lf;

	las_open(a->input, lf);
	stage_run(las_batch, &ls);
	*srs = lf->srs;
	if (a->stats)
		las_report(lf);
	las_close(lf);
	return (size_t) lf->kept;
}

typedef struct xyz_stage
{
	const char *path;
	FILE	   *f;
} xyz_stage;

static bool
xyz_batch(void *arg, double *xy, double *z, size_t max, size_t *k)
{
	xyz_stage  *xs = arg;

	*k = xyz_bin_batch(xs->path, xs->f, xy, z, max);
	return *k > 0;
}

/* A .xyz.bin file to tmp_dir/input.xy + input.z, in batches: returns n */
size_t
xyz_bin_to_bin(const char *path)
{
	xyz_stage	xs = {.path = path, .f = fopen(path, "rb")};
	size_t		n,
				total;

	if (xs.f == NULL)
		die(1, "cannot open %s", path);
	n = xyz_bin_count(path, xs.f);
	total = stage_run(xyz_batch, &xs);
	fclose(xs.f);
	if (total != n)
		die(1, "short read on %s", path);
	return n;
}
