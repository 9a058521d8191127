/*
 * test/fmt_g17.c: ./tdc's "%.17g" without printf (src/cli/fmt_g17.c)
 * against the C library's snprintf, for test/cli_fmt_g17.sh.
 *
 *	fmt_g17		prints a line per group and "N passed, N failed" last
 *
 * fmt_g17 must write exactly what snprintf(buf, 32, "%.17g", v) writes, for
 * every double; a group of values passes when every one of them does, and
 * the first that does not is printed with both texts.  The groups: zeros,
 * infinities, NaN, the extremes and the subnormals; powers of 10 and 2 and
 * their neighbours; exact ties of the 17th digit, constructed, with the C
 * library checked to round them to even (the rule fmt_g17 follows);
 * values around the switch between fixed and exponential notation and
 * around the edges of fmt_g17's integer arithmetic; coordinates, levels and
 * heights as ./tdc writes them; 20 million random doubles (random bit
 * patterns, and uniform in ranges), from fixed seeds; and the line writer
 * against fprintf, across its buffer's size.
 *
 *	fmt_g17 COUNT	COUNT random doubles instead of 20 million
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "splitmix.h"

static long passed,
			failed;
static long compared;			/* values in the current group */
static int	group_bad;			/* the current group's first mismatch printed */

static void
group_start(void)
{
	compared = 0;
	group_bad = 0;
}

static void
group_end(const char *name)
{
	if (group_bad)
		failed++;
	else
		passed++;
	printf("%s: %ld values, %s\n", name, compared, group_bad ? "FAILED" : "identical");
}

/* v through fmt_g17 and snprintf; the first mismatch of a group is printed */
static void
cmp(double v)
{
	char		want[32],
				got[32];
	int			nw = snprintf(want, sizeof(want), "%.17g", v);
	size_t		ng;

	memset(got, 'X', sizeof(got));
	ng = fmt_g17(got, v);
	compared++;
	if ((size_t) nw != ng || strcmp(want, got) != 0)
	{
		if (!group_bad)
		{
			uint64_t	bits;

			memcpy(&bits, &v, sizeof(bits));
			printf("MISMATCH for 0x%016llx (%a): snprintf \"%s\" (%d), fmt_g17 \"%.*s\" (%zu)\n",
				   (unsigned long long) bits, v, want, nw, (int) (ng < 32 ? ng : 31), got, ng);
		}
		group_bad = 1;
	}
}

/* v, -v and their k neighbours on each side */
static void
cmp_around(double v, int k)
{
	double		lo = v,
				hi = v;

	cmp(v);
	cmp(-v);
	for (int i = 0; i < k; i++)
	{
		lo = nextafter(lo, -INFINITY);
		hi = nextafter(hi, INFINITY);
		cmp(lo);
		cmp(-lo);
		cmp(hi);
		cmp(-hi);
	}
}

static double
from_bits(uint64_t b)
{
	double		v;

	memcpy(&v, &b, sizeof(v));
	return v;
}

static void
specials(void)
{
	group_start();
	cmp(0.0);
	cmp(-0.0);
	cmp(INFINITY);
	cmp(-INFINITY);
	cmp(NAN);
	cmp(-NAN);
	cmp(from_bits(UINT64_C(0x7ff0000000000001)));	/* a signalling NaN */
	cmp_around(DBL_MIN, 3);
	cmp_around(DBL_MAX, 3);
	cmp_around(DBL_TRUE_MIN, 3);
	cmp_around(DBL_EPSILON, 3);
	cmp_around(1.0, 3);
	cmp_around(0.1, 3);
	cmp_around(0x1p52, 3);
	cmp_around(0x1p53, 3);
	cmp_around(0x1p54, 3);
	/* the edges of fmt_g17's integers: 1e-6 below, 2^127 above */
	cmp_around(1e-6, 5);
	cmp_around(1e-7, 5);
	cmp_around(0x1p127, 5);
	cmp_around(0x1p128, 5);
	cmp_around(1e38, 5);
	cmp_around(1e22, 5);
	cmp_around(1e23, 5);
	for (int i = 1; i <= 1000; i++)
	{
		cmp(i);
		cmp(-i);
		cmp(i / 1000.0);
		cmp(i * 0.1);
	}
	group_end("zeros, infinities, NaN, extremes, subnormals, edges");
}

static void
powers(void)
{
	char		s[16];

	group_start();
	/* every power of 10 a double comes near, each as strtod rounds it */
	for (int k = -325; k <= 308; k++)
	{
		snprintf(s, sizeof(s), "1e%d", k);
		cmp_around(strtod(s, NULL), 4);
	}
	for (int k = -1074; k <= 1023; k++)
		cmp_around(ldexp(1.0, k), 2);
	group_end("powers of 10 and 2, and neighbours");
}

/*
 * Exact ties of the 17th significant digit: a = k / 2^(s+1) with k odd and
 * 10^(16-s) <= a < 10^(17-s) is (q + 1/2) 10^(s - 16) with q an integer,
 * since a 10^s = k 5^s / 2 and k 5^s is odd.  Such a is a double when
 * k < 2^53, which leaves room for s = 1 .. 22 (a from 1e-6 to 1e15).
 * Each one is also checked to be a tie by its exact decimal expansion, and
 * the C library to round it to even.
 */
static int
tie_check(double a, int *up)
{
	char		exact[400],
				e17[40],
				*p = exact,
				*d;
	char		digits[64];
	int			n = 0;
	uint64_t	lead = 0,
				got = 0;

	snprintf(exact, sizeof(exact), "%.360f", a);
	/* the significant digits of the exact expansion */
	while (*p == '0' || *p == '.')
		p++;
	for (; *p && n < (int) sizeof(digits) - 1; p++)
		if (*p != '.')
			digits[n++] = *p;
	while (n > 0 && digits[n - 1] == '0')
		n--;
	if (n != 18 || digits[17] != '5')
		return 0;				/* not a tie of the 17th digit */
	for (int i = 0; i < 17; i++)
		lead = lead * 10 + (uint64_t) (digits[i] - '0');
	/* the C library's 17 digits */
	snprintf(e17, sizeof(e17), "%.16e", a);
	for (d = e17; *d && *d != 'e'; d++)
		if (*d >= '0' && *d <= '9')
			got = got * 10 + (uint64_t) (*d - '0');
	*up = got != lead;
	/* to even: kept when even, one up when odd (a carry to 10^17 aside) */
	if (lead % 2 == 0)
		return got == lead ? 1 : -1;
	return got == lead + 1 || (lead + 1 == UINT64_C(100000000000000000) &&
							   got == UINT64_C(10000000000000000)) ? 1 : -1;
}

static void
ties(void)
{
	uint64_t	seed = 1717;
	long		made = 0,
				up = 0,
				kept = 0,
				not_even = 0,
				not_tie = 0;
	double		fixed[] = {1000000000000000.25, 1000000000000000.75, 123456789012345.125,
		123456789012345.375, 2251799813685247.75};

	group_start();
	for (size_t i = 0; i < sizeof(fixed) / sizeof(fixed[0]); i++)
		cmp_around(fixed[i], 0);
	for (int s = 1; s <= 22; s++)
	{
		double		lo = pow(10, 16 - s),
					hi = pow(10, 17 - s);
		/* k in [lo 2^(s+1), hi 2^(s+1)), below 2^53 */
		double		klo = ceil(ldexp(lo, s + 1)),
					khi = fmin(ldexp(hi, s + 1), 0x1p53);

		for (int i = 0; i < 5000; i++)
		{
			uint64_t	k = (uint64_t) klo + tdc_splitmix_below(&seed, (uint64_t) (khi - klo));
			double		a;
			int			r,
						u = 0;

			k |= 1;
			if ((double) k >= khi)
				k -= 2;
			a = ldexp((double) k, -(s + 1));
			if (!(a >= lo && a < hi))
				continue;
			r = tie_check(a, &u);
			if (r == 0)
				not_tie++;
			else if (r < 0)
				not_even++;
			else
				u ? up++ : kept++;
			made++;
			cmp(a);
			cmp(-a);
		}
	}
	group_end("exact ties of the 17th digit");
	/* the construction makes ties, and the C library rounds them to even both ways */
	if (made > 0 && not_tie == 0 && not_even == 0 && up > 0 && kept > 0)
		passed++;
	else
		failed++;
	printf("ties: %ld made, %ld not ties, %ld not to even; the C library kept %ld, rounded up %ld\n",
		   made, not_tie, not_even, kept, up);
}

/* Around the switch between fixed and exponential notation, both sides */
static void
switch_points(void)
{
	double		at[] = {1e-5, 1e-4, 1e-3, 1e15, 1e16, 1e17, 1e18, 9.9999999999999995e-5,
	99999999999999999.0, 9999999999999999.0};

	group_start();
	for (size_t i = 0; i < sizeof(at) / sizeof(at[0]); i++)
		cmp_around(at[i], 1000);
	group_end("fixed/exponential switch (1e-5, 1e-4, 1e16, 1e17 and neighbours)");
}

/* What ./tdc writes: projected and geographic coordinates, levels, heights */
static void
coordinates(void)
{
	uint64_t	seed = 4242;

	group_start();
	for (int i = 0; i < 300000; i++)
	{
		cmp(500000.123 + i * 1e-3);
		cmp(5210160.456 + i * 1e-3);
		cmp(-73.123456789 + i * 1e-9);
		cmp(45.987654321 - i * 1e-7);
		cmp(100.0 + i * 0.1);	/* contour levels base + k interval */
		cmp(-12.5 + i * 0.25);
		cmp(tdc_splitmix_unit(&seed) * 4000.0);	/* heights */
		cmp(i * 0.01);
	}
	group_end("coordinates, levels, heights");
}

static void
random_bits(long count)
{
	uint64_t	seed = 20250117;

	group_start();
	for (long i = 0; i < count; i++)
		cmp(from_bits(tdc_splitmix64(&seed)));
	group_end("random 64-bit patterns");
}

/*
 * Uniform in ranges, and random 53-bit mantissas with binary exponents
 * where fmt_g17's integer arithmetic works and just beyond.
 */
static void
random_ranges(long count)
{
	static const double ranges[][2] = {
		{0, 1}, {-1000, 1000}, {0, 1e7}, {166000, 834000}, {0, 1e7}, {-180, 180},
		{-90, 90}, {-500, 9000}, {1e15, 1e17}, {1e17, 1e25}, {1e-6, 1e-3}, {1e-9, 1e-5}
	};
	int			nr = (int) (sizeof(ranges) / sizeof(ranges[0]));
	uint64_t	seed = 977;

	group_start();
	for (long i = 0; i < count; i++)
	{
		int			r = (int) (i % (nr + 1));
		double		v;

		if (r < nr)
			v = ranges[r][0] + tdc_splitmix_unit(&seed) * (ranges[r][1] - ranges[r][0]);
		else
		{
			uint64_t	m = tdc_splitmix64(&seed) >> 11 | UINT64_C(1) << 52;

			v = ldexp((double) m, (int) tdc_splitmix_below(&seed, 220) - 150);
			if (tdc_splitmix64(&seed) & 1)
				v = -v;
		}
		cmp(v);
	}
	group_end("random, uniform in ranges and in binary exponents -150 .. 69");
}

/*
 * The line writer against fprintf: lines of 0 .. 700 numbers (past its
 * buffer), and the same file byte for byte.
 */
static void
line_writer(void)
{
	FILE	   *a = tmpfile(),
			   *b = tmpfile();
	uint64_t	seed = 31;
	long		na,
				nb;
	int			same = 0;
	g17_line	l;

	if (a && b)
	{
		for (int n = 0; n <= 700; n += 7)
		{
			g17_line_start(&l, a);
			for (int k = 0; k < n; k++)
			{
				double		v = (tdc_splitmix_unit(&seed) - 0.5) * 1e7;

				g17_line_num(&l, v);
				fprintf(b, k ? " %.17g" : "%.17g", v);
			}
			g17_line_end(&l);
			fputc('\n', b);
		}
		na = ftell(a);
		nb = ftell(b);
		rewind(a);
		rewind(b);
		same = na == nb && na > 0;
		for (long i = 0; same && i < na; i++)
			same = getc(a) == getc(b);
	}
	if (same)
		passed++;
	else
		failed++;
	printf("line writer: %s\n",
		   same ? "the same file as fprintf's" : "FAILED: the file differs from fprintf's");
	if (a)
		fclose(a);
	if (b)
		fclose(b);
}

int
main(int argc, char **argv)
{
	/*
	 * random doubles, 20 million by default: a fifth random bit patterns,
	 * most of which are far beyond fmt_g17's integers (and slow for the C
	 * library), the rest uniform in ranges
	 */
	long		count = argc > 1 ? atol(argv[1]) : 20000000;

	setvbuf(stdout, NULL, _IOLBF, 0);
	specials();
	powers();
	ties();
	switch_points();
	coordinates();
	random_bits(count / 5);
	random_ranges(count - count / 5);
	line_writer();
	printf("%ld passed, %ld failed\n", passed, failed);
	return failed ? 1 : 0;
}
