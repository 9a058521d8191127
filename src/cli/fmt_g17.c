/*
 * fmt_g17.c
 *		A double as the text of printf's "%.17g", without printf: ./tdc's
 *		triangles, contour lines and .asc grids are hundreds of millions of
 *		such numbers, and the C library's conversion, exact for any double,
 *		is built for every format and precision, not this one.
 *
 * The invariant: fmt_g17(buf, v) writes exactly the characters that
 * snprintf(buf, 32, "%.17g", v) writes in the C locale and the default
 * rounding mode (round to nearest), for every double v, so that a file
 * written with it is byte for byte the file printf would write.
 * test/fmt_g17.c checks it against the C library on tens of millions of
 * values.
 *
 * Why it is exact.  A finite nonzero v is m 2^e with m a 53-bit integer.
 * With d = floor(log10 |v|), "%.17g" prints the 17 significant digits
 * N = round(|v| 10^(16 - d)), rounded to nearest with exact ties going to
 * the even N (as the C library does in that rounding mode), and the
 * exponent X = d, or d + 1 with N = 10^16 when N rounds up to 10^17.
 * When 16 - d >= 0 and e <= 0, |v| 10^(16 - d) is the quotient of the
 * integers m 10^(16 - d) and 2^-e: the first is below 2^53 10^22 < 2^127
 * for 16 - d <= 22, so it fits an unsigned 128-bit integer, the quotient
 * is a shift and the remainder, compared with half the divisor, rounds it
 * exactly, ties included.  When e >= 0, |v| is the integer m 2^e: up to
 * 2^127 it fits, and N is it times 10^(16 - d), or its quotient by
 * 10^(d - 16), whose remainder again rounds it exactly.  No
 * floating-point operation takes part.  d is first estimated from the
 * binary exponent (floor(log10 |v|) or one less) and then corrected by the
 * result itself: N >= 10^17 means d was too small (or the rounding carried,
 * which the next d gets right: 10^16), N < 10^16 that it was too large.
 * Everything the integers cannot hold, |v| below 10^-6 or above 2^127,
 * subnormals, infinities and NaN, goes to snprintf itself; so do platforms
 * without a 128-bit integer type.
 *
 * The text is then C11's %g (7.21.6.1): with precision P = 17, fixed
 * notation with P - 1 - X decimals when P > X >= -4, else one digit, the
 * point, P - 1 digits and the exponent ("e+XX", "e-XX", at least two
 * digits); trailing zeros of the fraction removed, and the point when
 * nothing follows it; a minus sign for a negative value, "-0" included.
 *
 * The line writer below is what the CLI's writers use: the numbers of one
 * line separated by single spaces, gathered in a buffer and handed to the
 * stream in pieces, a line at a time.  The stream's error indicator is set
 * as printf would set it, so the callers' checks are unchanged.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"

#ifdef __SIZEOF_INT128__

__extension__ typedef unsigned __int128 u128;

#define POW10_16	UINT64_C(10000000000000000)
#define POW10_17	UINT64_C(100000000000000000)

static const uint64_t pow10_64[20] = {
	UINT64_C(1), UINT64_C(10), UINT64_C(100), UINT64_C(1000), UINT64_C(10000),
	UINT64_C(100000), UINT64_C(1000000), UINT64_C(10000000), UINT64_C(100000000),
	UINT64_C(1000000000), UINT64_C(10000000000), UINT64_C(100000000000),
	UINT64_C(1000000000000), UINT64_C(10000000000000), UINT64_C(100000000000000),
	UINT64_C(1000000000000000), UINT64_C(10000000000000000),
	UINT64_C(100000000000000000), UINT64_C(1000000000000000000),
	UINT64_C(10000000000000000000)
};

/* Two decimal digits of 0 .. 99, at 2 r. */
static const char digit_pairs[201] =
	"00010203040506070809101112131415161718192021222324252627282930313233343536373839"
	"40414243444546474849505152535455565758596061626364656667686970717273747576777879"
	"8081828384858687888990919293949596979899";

/* 10^k, 0 <= k <= 38 (10^38 < 2^128) */
static u128
pow10_128(int k)
{
	return k < 20 ? (u128) pow10_64[k] : (u128) pow10_64[k - 19] * pow10_64[19];
}

/*
 * round(m 2^e 10^s) to an integer, ties to even, into *n; false when the
 * 128-bit arithmetic cannot hold it exactly (m < 2^53).
 */
static bool
scaled_round(uint64_t m, int e, int s, u128 *n)
{
	u128		num,
				q,
				r;

	if (s >= 0)
	{
		if (s > 22)
			return false;
		/* m 10^s < 2^53 10^22 < 2^127 */
		num = (u128) m * pow10_128(s);
		if (e >= 0)
		{
			/* an integer times 10^s: exact, when it fits */
			if (e > 63 || (num >> (127 - e)) != 0)
				return false;
			*n = num << e;
			return true;
		}
		if (e < -127)
			return false;
		/* num / 2^-e: the remainder is the bits shifted out */
		q = num >> -e;
		r = num - (q << -e);
		{
			u128		half = (u128) 1 << (-e - 1);

			if (r > half || (r == half && (q & 1)))
				q++;
		}
		*n = q;
		return true;
	}
	/* s < 0: |v| >= 10^17 > 2^53, an integer, so e > 0 */
	if (e < 0 || e > 74 || -s > 38)
		return false;
	{
		u128		den = pow10_128(-s);

		num = (u128) m << e;
		q = num / den;
		r = num - q * den;
		/* r against den - r: half of den without halving an odd den */
		if (r > den - r || (r == den - r && (q & 1)))
			q++;
	}
	*n = q;
	return true;
}

/*
 * floor(k log10 2) for |k| <= 1100: 78913 / 2^18 is log10 2 to 8e-7, and
 * k log10 2 is never that close above an integer for such k (0 aside).
 */
static int
log10_pow2(int k)
{
	return k >= 0 ? (k * 78913) >> 18 : -((-k * 78913 + (1 << 18) - 1) >> 18);
}

/*
 * The 17 digits of N (10^16 <= N < 10^17) and the decimal exponent x as
 * "%.17g" writes them, after the sign.
 */
static size_t
g17_text(char *p, uint64_t n, int x)
{
	char		dig[17];
	char	   *start = p;
	int			last;

	/* two 32-bit halves, 9 and 8 digits: two short chains of divisions */
	uint32_t	hi = (uint32_t) (n / 100000000),
				lo = (uint32_t) (n % 100000000);

	for (int i = 15; i >= 9; i -= 2)
	{
		memcpy(dig + i, digit_pairs + 2 * (lo % 100), 2);
		lo /= 100;
		memcpy(dig + i - 8, digit_pairs + 2 * (hi % 100), 2);
		hi /= 100;
	}
	dig[0] = (char) ('0' + hi);
	/* the last significant digit: trailing zeros are not written */
	for (last = 16; last > 0 && dig[last] == '0'; last--)
		;
	if (x >= -4 && x < 17)
	{
		if (x >= 0)
		{
			memcpy(p, dig, x + 1);
			p += x + 1;
			if (last > x)
			{
				*p++ = '.';
				memcpy(p, dig + x + 1, last - x);
				p += last - x;
			}
		}
		else
		{
			*p++ = '0';
			*p++ = '.';
			for (int i = 0; i < -x - 1; i++)
				*p++ = '0';
			memcpy(p, dig, last + 1);
			p += last + 1;
		}
	}
	else
	{
		unsigned	ax = (unsigned) (x < 0 ? -x : x);

		*p++ = dig[0];
		if (last > 0)
		{
			*p++ = '.';
			memcpy(p, dig + 1, last);
			p += last;
		}
		*p++ = 'e';
		*p++ = x < 0 ? '-' : '+';
		if (ax >= 100)
		{
			*p++ = (char) ('0' + ax / 100);
			ax %= 100;
		}
		memcpy(p, digit_pairs + 2 * ax, 2);
		p += 2;
	}
	*p = '\0';
	return (size_t) (p - start);
}

#endif							/* __SIZEOF_INT128__ */

/* buf: at least 32 bytes (the longest text is 24 and its NUL) */
size_t
fmt_g17(char *buf, double v)
{
#ifdef __SIZEOF_INT128__
	uint64_t	bits,
				m;
	int			be,
				e,
				d;
	char	   *p = buf;

	memcpy(&bits, &v, sizeof(bits));
	be = (int) ((bits >> 52) & 0x7ff);
	m = bits & ((UINT64_C(1) << 52) - 1);
	if (bits >> 63)
		*p++ = '-';
	if (be == 0 && m == 0)
	{
		*p++ = '0';
		*p = '\0';
		return (size_t) (p - buf);
	}
	/* subnormals, infinities, NaN: the C library's text */
	if (be == 0 || be == 0x7ff)
		return (size_t) snprintf(buf, 32, "%.17g", v);
	m |= UINT64_C(1) << 52;
	e = be - 1075;
	d = log10_pow2(e + 52);
	/*
	 * d is floor(log10 |v|) or one less; the digits correct it: at most
	 * twice, a d too small and then a rounding up to 10^17.
	 */
	for (int tries = 0; tries < 3; tries++)
	{
		u128		n;

		if (!scaled_round(m, e, 16 - d, &n))
			break;
		if (n >= POW10_17)
			d++;
		else if (n < POW10_16)
			d--;
		else
			return (size_t) (p - buf) + g17_text(p, (uint64_t) n, d);
	}
#endif
	return (size_t) snprintf(buf, 32, "%.17g", v);
}

void
g17_line_start(g17_line *l, FILE *f)
{
	l->f = f;
	l->len = 0;
	l->first = true;
}

/* v after a space, or first on the line */
void
g17_line_num(g17_line *l, double v)
{
	/* room for a space, the longest number and its NUL */
	if (l->len > sizeof(l->buf) - 40)
	{
		fwrite(l->buf, 1, l->len, l->f);
		l->len = 0;
	}
	if (!l->first)
		l->buf[l->len++] = ' ';
	l->first = false;
	l->len += fmt_g17(l->buf + l->len, v);
}

/* The newline, and the line to the stream */
void
g17_line_end(g17_line *l)
{
	l->buf[l->len++] = '\n';
	fwrite(l->buf, 1, l->len, l->f);
	l->len = 0;
	l->first = true;
}
