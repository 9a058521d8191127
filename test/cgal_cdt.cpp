// cgal_cdt.cpp
//	Reference for the constrained Delaunay tests (test/test_cdt.c): CGAL's
//	Constrained_Delaunay_triangulation_2 with exact predicates, on the same
//	points and segments.
//
//	cgal_cdt < INPUT > OUTPUT
//
//	INPUT (text): "n k", then n lines "x y" (%.17g), then k lines "i j"
//	(segments as point indices).  OUTPUT: one finite face per line,
//	"x0 y0 x1 y1 x2 y2" counter-clockwise, %.17g.  Only general-position
//	input is compared (no four cocircular points), where the constrained
//	Delaunay triangulation is unique.
//
//	Tests only; the library never links CGAL.  Built by `make check-core`
//	when the CGAL headers are installed (Debian: libcgal-dev).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>

#include <cstdio>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Triangulation_vertex_base_2<K> Vb;
typedef CGAL::Constrained_triangulation_face_base_2<K> Fb;
typedef CGAL::Triangulation_data_structure_2<Vb, Fb> Tds;
typedef CGAL::Constrained_Delaunay_triangulation_2<K, Tds,
		CGAL::No_constraint_intersection_requiring_constructions_tag> CDT;
typedef K::Point_2 Point;

int
main()
{
	size_t n, k;

	if (std::scanf("%zu %zu", &n, &k) != 2)
		return 2;
	std::vector<Point> pts;
	std::vector<CDT::Vertex_handle> vh;
	CDT cdt;

	for (size_t i = 0; i < n; i++)
	{
		double x, y;

		if (std::scanf("%lf %lf", &x, &y) != 2)
			return 2;
		pts.push_back(Point(x, y));
	}
	for (size_t i = 0; i < n; i++)
		vh.push_back(cdt.insert(pts[i]));
	for (size_t i = 0; i < k; i++)
	{
		size_t a, b;

		if (std::scanf("%zu %zu", &a, &b) != 2 || a >= n || b >= n)
			return 2;
		if (vh[a] != vh[b])
			cdt.insert_constraint(vh[a], vh[b]);
	}
	for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f)
	{
		for (int j = 0; j < 3; j++)
			std::printf("%s%.17g %.17g", j ? " " : "", f->vertex(j)->point().x(),
						f->vertex(j)->point().y());
		std::printf("\n");
	}
	return 0;
}
