/*
 * input.c
 *		Reading ./tdc's INPUT: a .bin file of little-endian float64 x,y
 *		pairs, or any other file (or - for stdin) of text lines "x y" or
 *		"x y z"; and the --segments file of lines "i j".  Every error dies
 *		with the file's name or the line's number.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* INPUT is read as a .bin file when its name ends in .bin */
bool
is_bin_path(const char *path)
{
	size_t		a = strlen(path),
				b = strlen(".bin");

	return a >= b && strcmp(path + a - b, ".bin") == 0;
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

/* INPUT into memory: in->xy, in->n and, for text with z, in->z */
void
read_input(const char *path, cli_input *in)
{
	in->z = NULL;
	in->xy = is_bin_path(path) ? read_bin(path, &in->n) : read_text(path, &in->n, &in->z);
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
