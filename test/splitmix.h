/*
 * splitmix.h
 *		The splitmix64 generator (Steele, Lea and Flood 2014), shared by the
 *		core suite (test/), the core fuzz target and the benchmark tools
 *		(bench/gen_points.c, bench/gshhg_convert.c).
 *
 * Tests and benchmarks need random inputs that are the same on every run and
 * every machine, so that a failure or a timing can be reproduced from its
 * seed alone.  splitmix64 is a pure function of a 64-bit state, has no
 * global state of its own (each caller keeps its own), and passes BigCrush,
 * which is more than point sets need.  Header-only: bench tools are built
 * as single files with plain cc.
 */
#ifndef TDC_SPLITMIX_H
#define TDC_SPLITMIX_H

#include <stdint.h>

/* The next value of the sequence whose state is *s. */
static inline uint64_t
tdc_splitmix64(uint64_t *s)
{
	uint64_t	z = (*s += UINT64_C(0x9E3779B97F4A7C15));

	z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
	z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
	return z ^ (z >> 31);
}

/* A double uniform in [0, 1), from the top 53 bits of the next value. */
static inline double
tdc_splitmix_unit(uint64_t *s)
{
	return (double) (tdc_splitmix64(s) >> 11) * 0x1p-53;
}

/* An integer uniform in [0, bound) (bound > 0); rejection avoids the bias of %. */
static inline uint64_t
tdc_splitmix_below(uint64_t *s, uint64_t bound)
{
	uint64_t	limit = UINT64_MAX - UINT64_MAX % bound;
	uint64_t	r;

	do
		r = tdc_splitmix64(s);
	while (r >= limit);
	return r % bound;
}

#endif							/* TDC_SPLITMIX_H */
