// cgal_dt.cpp
//	Reference timing for the tdc_delaunay benchmarks: CGAL's 2D Delaunay
//	triangulation (Epick kernel, range insert with spatial sorting) on the
//	same .bin input as ./tdc (raw little-endian float64 x,y pairs).
//
//	cgal_dt [-r REPS] INPUT.bin
//
//	Prints one line per repetition:
//	  n=<input points> vertices=<unique> faces=<finite faces> seconds=<s> ns_per_point=<ns> cpu_seconds=<s>
//	and finally peak_rss_mb=<MB>.  Only dt.insert(begin, end) is timed
//	(steady_clock; cpu_seconds = process CPU time of the insert); reading the
//	file and destroying the triangulation are not.
//
//	Used by bench/core_bench.sh only; the library never links CGAL.
//	Build: g++ -O2 -DNDEBUG -DCGAL_NDEBUG -o build/cgal_dt bench/cgal_dt.cpp -lgmp -lmpfr

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Delaunay_triangulation_2.h>

#include <sys/resource.h>
#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_2<K> DT;
typedef K::Point_2 Point;

int
main(int argc, char **argv)
{
	int reps = 1;
	const char *path = nullptr;

	for (int i = 1; i < argc; i++)
	{
		if (std::strcmp(argv[i], "-r") == 0 && i + 1 < argc)
			reps = std::atoi(argv[++i]);
		else
			path = argv[i];
	}
	if (!path || reps < 1)
	{
		std::fprintf(stderr, "usage: %s [-r REPS] INPUT.bin\n", argv[0]);
		return 2;
	}

	FILE *f = std::fopen(path, "rb");
	if (!f)
	{
		std::perror(path);
		return 1;
	}
	std::fseek(f, 0, SEEK_END);
	long bytes = std::ftell(f);
	std::fseek(f, 0, SEEK_SET);
	if (bytes < 0 || bytes % 16 != 0)
	{
		std::fprintf(stderr, "%s: size is not a multiple of 16 bytes\n", path);
		return 1;
	}
	size_t n = (size_t) bytes / 16;
	std::vector<double> xy(2 * n);
	if (std::fread(xy.data(), 16, n, f) != n)
	{
		std::fprintf(stderr, "%s: short read\n", path);
		return 1;
	}
	std::fclose(f);

	std::vector<Point> pts;
	pts.reserve(n);
	for (size_t i = 0; i < n; i++)
		pts.emplace_back(xy[2 * i], xy[2 * i + 1]);
	std::vector<double>().swap(xy);

	for (int r = 0; r < reps; r++)
	{
		// range insert spatially sorts the range it is given: give it a copy of
		// the input order, except on the last repetition (no extra memory then)
		std::vector<Point> work;
		if (r + 1 < reps)
			work = pts;
		else
			work.swap(pts);
		DT dt;
		struct timespec c0, c1;
		clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
		auto t0 = std::chrono::steady_clock::now();
		dt.insert(work.begin(), work.end());
		auto t1 = std::chrono::steady_clock::now();
		clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
		double s = std::chrono::duration<double>(t1 - t0).count();
		double cpu = (double) (c1.tv_sec - c0.tv_sec) + 1e-9 * (double) (c1.tv_nsec - c0.tv_nsec);
		std::printf("n=%zu vertices=%zu faces=%zu seconds=%.6f ns_per_point=%.1f cpu_seconds=%.6f\n",
					n, (size_t) dt.number_of_vertices(), (size_t) dt.number_of_faces(),
					s, n ? s * 1e9 / (double) n : 0.0, cpu);
		std::fflush(stdout);
	}

	struct rusage ru;
	getrusage(RUSAGE_SELF, &ru);
	std::printf("peak_rss_mb=%.1f\n", ru.ru_maxrss / 1024.0);
	return 0;
}
