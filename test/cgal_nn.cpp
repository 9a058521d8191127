// cgal_nn.cpp
//	Reference for the natural neighbour tests (test/test_tin.c): CGAL's
//	natural_neighbor_coordinates_2 and linear_interpolation on a
//	Delaunay_triangulation_2 with exact predicates and exact constructions
//	(Epeck), on the same samples.
//
//	cgal_nn < INPUT > OUTPUT
//
//	INPUT (text): "n m", then n lines "x y z" (samples, %.17g; of samples
//	with equal x and y the first one's z counts), then m lines "x y"
//	(queries).  OUTPUT: one line per query, its value (%.17g) or "nan"
//	outside the convex hull.  On a hull edge CGAL interpolates linearly
//	along the edge, as we do.
//
//	Tests only; the library never links CGAL.  Built by `make check-core`
//	when the CGAL headers are installed (Debian: libcgal-dev).

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/natural_neighbor_coordinates_2.h>
#include <CGAL/interpolation_functions.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_exact_constructions_kernel K;
typedef K::FT FT;
typedef K::Point_2 Point;
typedef CGAL::Delaunay_triangulation_2<K> DT;
typedef std::map<Point, FT, K::Less_xy_2> ZMap;

int
main()
{
	size_t n, m;

	if (std::scanf("%zu %zu", &n, &m) != 2)
		return 2;
	DT dt;
	ZMap z;
	std::vector<Point> pts;

	for (size_t i = 0; i < n; i++)
	{
		double x, y, h;

		if (std::scanf("%lf %lf %lf", &x, &y, &h) != 3)
			return 2;
		Point p(x, y);

		pts.push_back(p);
		z.insert(std::make_pair(p, FT(h)));		// the first one stays
	}
	dt.insert(pts.begin(), pts.end());
	for (size_t i = 0; i < m; i++)
	{
		double x, y;

		if (std::scanf("%lf %lf", &x, &y) != 2)
			return 2;
		Point q(x, y);
		std::vector<std::pair<Point, FT> > coords;

		if (dt.dimension() < 2)
		{
			std::printf("nan\n");
			continue;
		}
		auto res = CGAL::natural_neighbor_coordinates_2(dt, q, std::back_inserter(coords));
		if (!res.third)
		{
			std::printf("nan\n");
			continue;
		}
		FT v = CGAL::linear_interpolation(coords.begin(), coords.end(), res.second,
										  CGAL::Data_access<ZMap>(z));

		std::printf("%.17g\n", CGAL::to_double(CGAL::exact(v)));
	}
	return 0;
}
