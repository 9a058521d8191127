// cgal_linear.cpp
//	Reference for the breakline values (test/fixtures/tin-reference.txt):
//	the linear value at a point on CGAL's Constrained_Delaunay_triangulation_2
//	with exact predicates and exact constructions (Epeck), the barycentric
//	weights computed in CGAL's exact number type.  With no segments it is
//	the linear value on the Delaunay triangulation, the only one when no
//	four samples are cocircular.
//
//	cgal_linear < INPUT > OUTPUT
//
//	INPUT (text): "n k m", then n lines "x y z" (samples, %.17g; of samples
//	with equal x and y the first one's z counts), k lines "i j" (segments as
//	sample indices, from 0), m lines "x y" (queries).  OUTPUT: one line per
//	query, its value (%.17g, the exact value's to_double) or "nan"
//	outside the convex hull.  Only input whose segments cross nowhere but
//	at shared ends is meant (the tag below refuses the rest).
//
//	Tests only; the library never links CGAL.  Built by `make check-core`
//	when the CGAL headers are installed (Debian: libcgal-dev).

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Constrained_Delaunay_triangulation_2.h>

#include <cstdio>
#include <map>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_exact_constructions_kernel K;
typedef K::FT FT;
typedef K::Point_2 Point;
typedef CGAL::Triangulation_vertex_base_2<K> Vb;
typedef CGAL::Constrained_triangulation_face_base_2<K> Fb;
typedef CGAL::Triangulation_data_structure_2<Vb, Fb> Tds;
typedef CGAL::Constrained_Delaunay_triangulation_2<K, Tds,
		CGAL::No_constraint_intersection_requiring_constructions_tag> CDT;
typedef std::map<Point, FT, K::Less_xy_2> ZMap;

int
main()
{
	size_t		n, k, m;

	if (std::scanf("%zu %zu %zu", &n, &k, &m) != 3)
		return 2;
	std::vector<CDT::Vertex_handle> vh;
	CDT			cdt;
	ZMap		z;

	for (size_t i = 0; i < n; i++)
	{
		double		x, y, h;

		if (std::scanf("%lf %lf %lf", &x, &y, &h) != 3)
			return 2;
		Point		p(x, y);

		z.insert(std::make_pair(p, FT(h)));		// the first one stays
		vh.push_back(cdt.insert(p));
	}
	for (size_t i = 0; i < k; i++)
	{
		size_t		a, b;

		if (std::scanf("%zu %zu", &a, &b) != 2 || a >= n || b >= n)
			return 2;
		if (vh[a] != vh[b])
			cdt.insert_constraint(vh[a], vh[b]);
	}
	for (size_t i = 0; i < m; i++)
	{
		double		x, y;

		if (std::scanf("%lf %lf", &x, &y) != 2)
			return 2;
		Point		q(x, y);
		CDT::Locate_type lt;
		int			li;
		CDT::Face_handle f;

		if (cdt.dimension() < 2)
		{
			std::printf("nan\n");
			continue;
		}
		f = cdt.locate(q, lt, li);
		if (lt == CDT::OUTSIDE_CONVEX_HULL || lt == CDT::OUTSIDE_AFFINE_HULL)
		{
			std::printf("nan\n");
			continue;
		}
		if (cdt.is_infinite(f))
		{
			// on a hull edge or vertex: the finite face on its other side
			f = f->neighbor(f->index(cdt.infinite_vertex()));
		}
		const Point &a = f->vertex(0)->point();
		const Point &b = f->vertex(1)->point();
		const Point &c = f->vertex(2)->point();
		FT			area = CGAL::area(a, b, c);
		FT			v = (z[a] * CGAL::area(q, b, c) + z[b] * CGAL::area(a, q, c) +
						 z[c] * CGAL::area(a, b, q)) / area;

		std::printf("%.17g\n", CGAL::to_double(CGAL::exact(v)));
	}
	return 0;
}
