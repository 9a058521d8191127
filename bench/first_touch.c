/*
 * first_touch.c
 *		How much a process pays for memory it has not used before, against
 *		memory it maps again right after unmapping it.
 *
 *	first_touch [MB] [ROUNDS]
 *
 * Maps MB megabytes (default 256) with the same transparent huge-page advice
 * the engine gives its big arrays, writes one byte per 4 kB page, unmaps, and
 * does it ROUNDS times (default 4), printing each round's rate.  On a
 * physical machine every round costs the same: the kernel zeroes the pages.
 * On a virtual machine whose host backs guest memory only once it is
 * touched, and takes it back once the guest has left it free for a while
 * (free page reporting), the first round also pays the host's faults and is
 * many times slower: so are the first touches of a statement's mesh and
 * result, in both tdc_delaunay and PostGIS.  The benchmarks print this
 * figure in their header so that a reader can tell such a machine.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <time.h>

static double
now(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

int
main(int argc, char **argv)
{
	size_t		mb = argc > 1 ? (size_t) atol(argv[1]) : 256;
	int			rounds = argc > 2 ? atoi(argv[2]) : 4;
	size_t		size = mb << 20;

	if (mb == 0 || rounds <= 0)
	{
		fprintf(stderr, "usage: first_touch [MB] [ROUNDS]\n");
		return 2;
	}
	for (int r = 0; r < rounds; r++)
	{
		double		t0 = now(),
					t1;
		volatile char *p = mmap(NULL, size, PROT_READ | PROT_WRITE,
								MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);

		if (p == MAP_FAILED)
		{
			perror("mmap");
			return 1;
		}
#ifdef MADV_HUGEPAGE
		(void) madvise((void *) p, size, MADV_HUGEPAGE);
#endif
		for (size_t o = 0; o < size; o += 4096)
			p[o] = 1;
		t1 = now();
		munmap((void *) p, size);
		printf("round %d: %zu MB touched in %.1f ms (%.2f GB/s)\n",
			   r + 1, mb, (t1 - t0) * 1e3, size / (t1 - t0) / 1e9);
	}
	return 0;
}
