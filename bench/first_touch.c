/*
 * first_touch.c
 *		How much a process pays for memory it has not used before, against
 *		memory it maps again right after unmapping it.
 *
 *	first_touch [MB] [ROUNDS] [huge]
 *
 * Maps MB megabytes (default 256) in 4 kB pages (with "huge": asking for
 * transparent huge pages instead), writes
 * one byte per 4 kB page, unmaps, and does it ROUNDS times (default 4),
 * printing each round's rate.  On a physical machine every round costs the
 * same: the kernel zeroes the pages.  On a virtual machine whose host backs
 * guest memory only once it is touched, and takes back what the guest has
 * left free for a while (free page reporting, in 2 MB blocks), memory the
 * guest has not used for a few seconds costs more, and most of all in huge
 * pages: on the 2-core benchmark machines, 0.4-0.7 GB/s for huge pages
 * against 3-5 GB/s in 4 kB pages, which is why the engine times its first
 * huge page before it asks for more (src/core/engine/mem.c).  The benchmarks print
 * these figures in their header so that a reader can tell such a machine.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
	int			huge = argc > 3 && strcmp(argv[3], "huge") == 0;
	size_t		size = mb << 20;

	if (mb == 0 || rounds <= 0)
	{
		fprintf(stderr, "usage: first_touch [MB] [ROUNDS] [huge]\n");
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
		if (huge)
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
