/*
 * gen_points.c
 *		Deterministic synthetic point sets for the tdc_delaunay benchmarks.
 *
 *	gen_points KIND N SEED OUT.bin
 *
 * Writes N points as raw little-endian float64 x,y pairs (16 bytes per
 * point, no header), or, when OUT ends in ".tsv", as "x<TAB>y" text lines
 * (%.17g, reads back exactly) for COPY.  KIND is one of
 *
 *	uniform		uniform in [0,1000)^2
 *	clustered	Gaussian clusters: ~sqrt(N)/4 centres uniform in [0,1000)^2,
 *				each with its own sigma in [0.5, 15]; points pick a centre
 *				with a skewed (quadratic) distribution, so cluster sizes vary
 *	clusters64	64 Gaussian clusters, centres uniform in [0,1000)^2, widths
 *				(sigma) log-uniform from 0.1 to 20, each point in a cluster
 *				picked uniformly: tight clusters beside wide ones, the case of
 *				the bounded-memory runs (./tdc --max-memory)
 *	grid		exact integer lattice 0..s-1 x 0..s-1 with s = ceil(sqrt(N)),
 *				the first N lattice points in row-major order, then shuffled
 *				(maximally degenerate: every lattice square is cocircular)
 *	gridjitter	the same lattice, each point moved by uniform noise of +-0.25
 *
 * The random generator is splitmix64 seeded with SEED, so the output is a
 * pure function of (KIND, N, SEED) on every little-endian IEEE machine.
 * Build: cc -O2 -o build/gen_points bench/gen_points.c -lm
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../test/splitmix.h"

static uint64_t rng_state;

/* uniform double in [0,1) with 53 random bits */
static double
rng_unit(void)
{
	return tdc_splitmix_unit(&rng_state);
}

/* uniform integer in [0, bound) (bound > 0), rejection to avoid bias */
static uint64_t
rng_below(uint64_t bound)
{
	return tdc_splitmix_below(&rng_state, bound);
}

/* standard normal pair by Box-Muller */
static void
rng_normal2(double *a, double *b)
{
	double		u,
				v,
				r;

	do
		u = rng_unit();
	while (u <= 0.0);
	v = rng_unit();
	r = sqrt(-2.0 * log(u));
	*a = r * cos(2.0 * M_PI * v);
	*b = r * sin(2.0 * M_PI * v);
}

static void
shuffle(double *xy, size_t n)
{
	for (size_t i = n; i > 1; i--)
	{
		size_t		j = (size_t) rng_below(i);
		double		tx = xy[2 * (i - 1)],
					ty = xy[2 * (i - 1) + 1];

		xy[2 * (i - 1)] = xy[2 * j];
		xy[2 * (i - 1) + 1] = xy[2 * j + 1];
		xy[2 * j] = tx;
		xy[2 * j + 1] = ty;
	}
}

static int
host_is_little_endian(void)
{
	uint16_t	one = 1;
	unsigned char c;

	memcpy(&c, &one, 1);
	return c == 1;
}

int
main(int argc, char **argv)
{
	const char *kind;
	char	   *end;
	size_t		n;
	uint64_t	seed;
	double	   *xy;
	FILE	   *f;

	if (argc != 5)
	{
		fprintf(stderr, "usage: %s uniform|clustered|clusters64|grid|gridjitter N SEED OUT.bin\n", argv[0]);
		return 2;
	}
	if (!host_is_little_endian())
	{
		fprintf(stderr, "gen_points: big-endian host not supported\n");
		return 2;
	}
	kind = argv[1];
	errno = 0;
	n = (size_t) strtod(argv[2], &end);	/* accepts 1e6 */
	if (errno || *end || n == 0)
	{
		fprintf(stderr, "gen_points: bad N '%s'\n", argv[2]);
		return 2;
	}
	seed = strtoull(argv[3], &end, 10);
	if (*end)
	{
		fprintf(stderr, "gen_points: bad SEED '%s'\n", argv[3]);
		return 2;
	}
	rng_state = seed ^ UINT64_C(0x5DEECE66D2B7E151);

	xy = malloc(n * 2 * sizeof(double));
	if (!xy)
	{
		fprintf(stderr, "gen_points: out of memory\n");
		return 1;
	}

	if (strcmp(kind, "uniform") == 0)
	{
		for (size_t i = 0; i < n; i++)
		{
			xy[2 * i] = 1000.0 * rng_unit();
			xy[2 * i + 1] = 1000.0 * rng_unit();
		}
	}
	else if (strcmp(kind, "clustered") == 0)
	{
		size_t		k = (size_t) (sqrt((double) n) / 4.0);
		double	   *c;

		if (k < 1)
			k = 1;
		c = malloc(k * 3 * sizeof(double));
		if (!c)
		{
			fprintf(stderr, "gen_points: out of memory\n");
			return 1;
		}
		for (size_t j = 0; j < k; j++)
		{
			c[3 * j] = 1000.0 * rng_unit();
			c[3 * j + 1] = 1000.0 * rng_unit();
			c[3 * j + 2] = 0.5 + 14.5 * rng_unit();
		}
		for (size_t i = 0; i < n; i += 2)
		{
			double		u = rng_unit();
			size_t		j = (size_t) (u * u * (double) k);
			double		a,
						b;

			if (j >= k)
				j = k - 1;
			rng_normal2(&a, &b);
			xy[2 * i] = c[3 * j] + c[3 * j + 2] * a;
			xy[2 * i + 1] = c[3 * j + 1] + c[3 * j + 2] * b;
			if (i + 1 < n)
			{
				rng_normal2(&a, &b);
				xy[2 * i + 2] = c[3 * j] + c[3 * j + 2] * a;
				xy[2 * i + 3] = c[3 * j + 1] + c[3 * j + 2] * b;
			}
		}
		free(c);
	}
	else if (strcmp(kind, "clusters64") == 0)
	{
		double		c[64][3];

		for (int j = 0; j < 64; j++)
		{
			c[j][0] = 1000.0 * rng_unit();
			c[j][1] = 1000.0 * rng_unit();
			c[j][2] = 0.1 * pow(200.0, rng_unit());
		}
		for (size_t i = 0; i < n; i++)
		{
			size_t		j = (size_t) rng_below(64);
			double		a,
						b;

			rng_normal2(&a, &b);
			xy[2 * i] = c[j][0] + c[j][2] * a;
			xy[2 * i + 1] = c[j][1] + c[j][2] * b;
		}
	}
	else if (strcmp(kind, "grid") == 0 || strcmp(kind, "gridjitter") == 0)
	{
		int			jitter = strcmp(kind, "gridjitter") == 0;
		size_t		s = (size_t) ceil(sqrt((double) n));

		while (s * s < n)
			s++;
		for (size_t i = 0; i < n; i++)
		{
			double		x = (double) (i % s),
						y = (double) (i / s);

			if (jitter)
			{
				x += 0.5 * rng_unit() - 0.25;
				y += 0.5 * rng_unit() - 0.25;
			}
			xy[2 * i] = x;
			xy[2 * i + 1] = y;
		}
		shuffle(xy, n);
	}
	else
	{
		fprintf(stderr, "gen_points: unknown kind '%s'\n", kind);
		return 2;
	}

	f = fopen(argv[4], "wb");
	if (!f)
	{
		fprintf(stderr, "gen_points: cannot open %s: %s\n", argv[4], strerror(errno));
		return 1;
	}
	if (strlen(argv[4]) > 4 && strcmp(argv[4] + strlen(argv[4]) - 4, ".tsv") == 0)
	{
		for (size_t i = 0; i < n; i++)
			fprintf(f, "%.17g\t%.17g\n", xy[2 * i], xy[2 * i + 1]);
		if (ferror(f) || fclose(f) != 0)
		{
			fprintf(stderr, "gen_points: write error on %s\n", argv[4]);
			return 1;
		}
	}
	else if (fwrite(xy, 2 * sizeof(double), n, f) != n || fclose(f) != 0)
	{
		fprintf(stderr, "gen_points: write error on %s\n", argv[4]);
		return 1;
	}
	free(xy);
	return 0;
}
